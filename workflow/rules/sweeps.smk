# Sweeps (README, "Sweeps"): a study listing values of zeta, eps, amplitude, rms or seed is
# expanded by `configuration.load` into the studies <sweep>_0 ... <sweep>_<N-1>, which the
# other stages build like any study; config["sweeps"] records each sweep's studies and values.
# One figure per sweep sets their means side by side; drawing is cheap, so it runs locally.
#
# One rule per sweep, its paths written out: Snakemake prefers a rule without wildcards, so
# results/figures/<sweep>/sweep.png is drawn here, never by draw_figure's {owner}/{fig}.png
# (a sweep's name is no study's once it is expanded).
import functools

# `rule all` (all_targets) draws the figure of every sweep whose studies it builds.
sweep_targets = functools.partial(configuration.sweep_figures, config, PLAN.drawn)

for _name, _sweep in config["sweeps"].items():

    rule:
        name:
            f"draw_sweep_{_name}"
        localrule: True
        input:
            [_DATASETS["events"].format(name=study) for study in _sweep["studies"]],
        output:
            png=report(f"results/figures/{_name}/sweep.png", caption="../report/sweep.rst",
                       category=_name, labels={"figure": "sweep"}),
            pdf=f"results/figures/{_name}/sweep.pdf",
        conda:
            "../envs/vibroimpact.yaml"
        log:
            f"results/logs/draw_sweep/{_name}.log",
        benchmark:
            f"results/benchmarks/draw_sweep/{_name}.tsv"
        threads: 1
        resources:
            mem_mb=BASE_MEM_MB,
            runtime=5,
        params:
            labels=configuration.sweep_labels(_sweep),
            code=CODE["figure"],
        script:
            "../scripts/draw_sweep.py"
