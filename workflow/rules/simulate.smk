rule simulate_events:
    input:
        noise=study_noise,
    output:
        "results/cells/{study}/events/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/simulate_events/{study}/{tile}.log",
    benchmark:
        "results/benchmarks/simulate_events/{study}/{tile}.tsv"
    threads: 1
    resources:
        mem_mb=simulate_mem_mb,
        runtime=simulate_runtime("events"),
    params:
        block=study_block("events"),
        code=CODE["simulate"],
    script:
        "../scripts/simulate_events.py"


rule simulate_spectra:
    input:
        noise=study_noise,
    output:
        "results/cells/{study}/spectra/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/simulate_spectra/{study}/{tile}.log",
    benchmark:
        "results/benchmarks/simulate_spectra/{study}/{tile}.tsv"
    threads: 1
    resources:
        mem_mb=simulate_mem_mb,
        runtime=simulate_runtime("spectra"),
    params:
        block=study_block("spectra"),
        code=CODE["simulate"],
    script:
        "../scripts/simulate_spectra.py"


rule simulate_trace:
    input:
        noise=study_noise,
    output:
        "results/traces/{study}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/simulate_trace/{study}.log",
    benchmark:
        "results/benchmarks/simulate_trace/{study}.tsv"
    threads: 1
    resources:
        mem_mb=simulate_mem_mb,
        runtime=simulate_runtime("trace"),
    params:
        block=study_block("trace"),
        code=CODE["simulate"],
    script:
        "../scripts/simulate_trace.py"


rule simulate_map:
    input:
        noise=study_noise,
    output:
        "results/cells/{study}/map/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/simulate_map/{study}/{tile}.log",
    benchmark:
        "results/benchmarks/simulate_map/{study}/{tile}.tsv"
    threads: 1
    resources:
        mem_mb=simulate_mem_mb,
        runtime=simulate_runtime("map"),
    params:
        block=study_block("map"),
        code=CODE["simulate"],
    script:
        "../scripts/simulate_map.py"
