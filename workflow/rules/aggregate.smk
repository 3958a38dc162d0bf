# Aggregation reads small tiles and writes one dataset: cheap, run where Snakemake runs.


rule aggregate_events:
    """The events dataset of study {study}, from its tiles."""
    localrule: True
    input:
        tiles("events"),
    output:
        targets.product("events", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_events/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_events/{study}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("aggregate_events"),
        runtime=job_runtime("aggregate_events"),
    params:
        block=study_block("events"),
        code=script_code("aggregate_events"),
    script:
        "../scripts/aggregate_events.py"


rule aggregate_spectra:
    """The spectra dataset of study {study}, from its tiles and noise record."""
    localrule: True
    input:
        tiles=tiles("spectra"),
        noise=study_noise,
    output:
        targets.product("spectra", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_spectra/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_spectra/{study}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("aggregate_spectra"),
        runtime=job_runtime("aggregate_spectra"),
    params:
        block=study_block("spectra"),
        code=script_code("aggregate_spectra"),
    script:
        "../scripts/aggregate_spectra.py"


rule aggregate_map:
    """The motion-map dataset of study {study}, from its tiles."""
    localrule: True
    input:
        tiles("map"),
    output:
        targets.product("map", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_map/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_map/{study}.tsv"
    threads: 1
    priority: 1  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("aggregate_map"),
        runtime=job_runtime("aggregate_map"),
    params:
        block=study_block("map"),
        code=script_code("aggregate_map"),
    script:
        "../scripts/aggregate_map.py"


rule aggregate_escape:
    """The escape dataset of study {study}, from its noise levels, with the escape fits."""
    localrule: True
    input:
        escape_levels,
    output:
        targets.product("escape", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_escape/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_escape/{study}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("aggregate_escape"),
        runtime=job_runtime("aggregate_escape"),
    params:
        block=study_block("escape"),
        noise=escape_noise,
        code=script_code("aggregate_escape"),
    script:
        "../scripts/aggregate_escape.py"
