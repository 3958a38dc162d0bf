# Sweeps (README, "Sweeps"): a study listing values of zeta, eps, amplitude, rms or seed is
# expanded by `configuration.load` into the studies <sweep>_0 ... <sweep>_<N-1>, which the
# other stages build like any study; config["sweeps"] records each sweep's studies and values.
# One figure per sweep sets their means side by side; drawing is cheap, so it runs locally.
# results/figures/<sweep>/sweep.png is never draw_figure's {owner}/{fig}.png: `fig` excludes
# `sweep`, and a name that is not a sweep fails in sweep_inputs, naming the sweeps.


rule draw_sweep:
    """The means of the studies of sweep {sweep} side by side, as PNG and PDF."""
    localrule: True
    input:
        sweep_inputs,
    output:
        png=report(
            targets.product("sweep_figure", name="{sweep}"),
            caption="../report/sweep.rst",
            category="{sweep}",
            labels={"figure": "sweep"},
        ),
        pdf=targets.product("sweep_figure", name="{sweep}", twin=".pdf"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/draw_sweep/{sweep}.log",
    benchmark:
        "results/benchmarks/draw_sweep/{sweep}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("draw_sweep"),
        runtime=job_runtime("draw_sweep"),
    params:
        labels=sweep_labels,
        code=script_code("draw_sweep"),
    script:
        "../scripts/draw_sweep.py"
