# The validation targets (docs/figures.md, "Beyond the paper"): the work-precision run of the
# simulator against its peers, and a seeded quick sample of the stress families; drawing is
# cheap and runs locally. The work-precision job compares wall times, so it holds every core
# of the run (threads = --cores): no other job of the build runs beside it. On SLURM its
# profile asks for a node to itself (workflow/profiles/slurm).
localrules:
    draw_validation_figure,


# Package sources each validation output depends on.
VALIDATION_CODE = {
    "work_precision": source_digest("validation/work_precision", "validation/peers",
                                    "validation/reference", "impact", "_checks", "_files",
                                    "pipeline/io", "pipeline/tasks"),
    "stress": source_digest("validation/campaign", "validation/families",
                            "validation/orbit_families", "validation/streaming",
                            "validation/reference", "validation/compare", "validation/report",
                            "impact", "orbits", "noise", "stats", "_checks", "_files",
                            "pipeline/io", "pipeline/tasks"),
    "figure": source_digest("plotting", "stats", "_files", "pipeline/io", "pipeline/tasks"),
}

# Each validation figure and the dataset it draws.
VALIDATION_FIGURES = {
    "work_precision": "results/validation/work_precision.nc",
    "stress": "results/validation/stress_sample.nc",
}

# What `rule all` builds when validation.build is true (all_targets calls it: a fresh list each
# call; a bound method rather than a function, so that this file holds rules only).
validation_targets = [f"results/figures/{name}.png" for name in VALIDATION_FIGURES].copy


rule measure_work_precision:
    output:
        "results/validation/work_precision.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/measure_work_precision.log",
    benchmark:
        "results/benchmarks/measure_work_precision.tsv"
    threads: workflow.cores
    resources:
        mem_mb=BASE_MEM_MB + 200,
        runtime=10,
    params:
        block=config["validation"]["work_precision"],
        code=VALIDATION_CODE["work_precision"],
    script:
        "../scripts/measure_work_precision.py"


rule sample_stress_families:
    output:
        "results/validation/stress_sample.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/sample_stress_families.log",
    benchmark:
        "results/benchmarks/sample_stress_families.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB + 200,
        runtime=10,
    params:
        block=config["validation"]["stress"],
        code=VALIDATION_CODE["stress"],
    script:
        "../scripts/sample_stress_families.py"


rule draw_validation_figure:
    input:
        lookup(dpath="{validation_fig}", within=VALIDATION_FIGURES),
    output:
        png=report("results/figures/{validation_fig}.png",
                   caption="../report/validation_figure.rst", category="validation",
                   labels={"figure": "{validation_fig}"}),
        pdf="results/figures/{validation_fig}.pdf",
    wildcard_constraints:
        validation_fig="|".join(VALIDATION_FIGURES),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/draw_validation_figure/{validation_fig}.log",
    benchmark:
        "results/benchmarks/draw_validation_figure/{validation_fig}.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB,
        runtime=5,
    params:
        code=VALIDATION_CODE["figure"],
    script:
        "../scripts/draw_validation_figure.py"
