# The validation targets (docs/figures.md, "Beyond the paper"): the work-precision run of the
# simulator against its peers, and a seeded sample of the stress families; drawing is
# cheap and runs locally. The work-precision job compares wall times, so it holds every core
# of the run (threads = --cores): no other job of the build runs beside it. On SLURM it is
# one CPU of a node, or the whole node when the profile's --exclusive is uncommented
# (workflow/profiles/slurm).


rule measure_work_precision:
    """The work-precision run: the simulator against its peers."""
    output:
        targets.VALIDATION_FIGURES["work_precision"],
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/measure_work_precision.log",
    benchmark:
        "results/benchmarks/measure_work_precision.tsv"
    threads: workflow.cores
    priority: 7  # first, while every core is free (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("measure_work_precision"),
        runtime=job_runtime("measure_work_precision"),
    params:
        block=config["validation"]["work_precision"],
        code=script_code("measure_work_precision"),
    script:
        "../scripts/measure_work_precision.py"


rule sample_stress_families:
    """A seeded sample of the stress families (config validation.stress.size)."""
    output:
        targets.VALIDATION_FIGURES["stress"],
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/sample_stress_families.log",
    benchmark:
        "results/benchmarks/sample_stress_families.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("sample_stress_families"),
        runtime=job_runtime("sample_stress_families"),
    params:
        block=config["validation"]["stress"],
        code=script_code("sample_stress_families"),
    script:
        "../scripts/sample_stress_families.py"


rule draw_validation_figure:
    """Validation figure {validation_fig}, as PNG and PDF."""
    localrule: True
    input:
        lookup(dpath="{validation_fig}", within=VALIDATION_FIGURES),
    output:
        png=report(
            targets.product("top_figure", figure="{validation_fig}"),
            caption="../report/validation_figure.rst",
            category="validation",
            labels={"figure": "{validation_fig}"},
        ),
        pdf=targets.product("top_figure", figure="{validation_fig}", twin=".pdf"),
    wildcard_constraints:
        validation_fig="|".join(VALIDATION_FIGURES),
    log:
        "results/logs/draw_validation_figure/{validation_fig}.log",
    threads: 1
    resources:
        mem_mb=job_mem_mb("draw_validation_figure"),
        runtime=job_runtime("draw_validation_figure"),
    conda:
        "../envs/vibroimpact.yaml"
    params:
        code=script_code("draw_validation_figure"),
        benchmark="results/benchmarks/draw_validation_figure/{validation_fig}.tsv",
    # drawn in a fork of Snakemake's process, as draw_figure (figures.smk)
    script:
        "../scripts/draw_validation_figure.py"
