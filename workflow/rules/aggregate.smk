# Aggregation reads small tiles and writes one dataset: cheap, run where Snakemake runs.
localrules:
    aggregate_events,
    aggregate_spectra,
    aggregate_map,


rule aggregate_events:
    input:
        tiles("events"),
    output:
        "results/datasets/{study}_events.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_events/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_events/{study}.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB,
        runtime=5,
    params:
        block=study_block("events"),
        code=CODE["aggregate"],
    script:
        "../scripts/aggregate_events.py"


rule aggregate_spectra:
    input:
        tiles=tiles("spectra"),
        noise=study_noise,
    output:
        "results/datasets/{study}_spectra.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_spectra/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_spectra/{study}.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB,
        runtime=5,
    params:
        block=study_block("spectra"),
        code=CODE["aggregate"],
    script:
        "../scripts/aggregate_spectra.py"


rule aggregate_map:
    input:
        tiles("map"),
    output:
        "results/datasets/{study}_map.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_map/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_map/{study}.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB,
        runtime=5,
    params:
        block=study_block("map"),
        code=CODE["aggregate"],
    script:
        "../scripts/aggregate_map.py"
