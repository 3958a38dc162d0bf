rule simulate_events:
    """Impact statistics of the cells of one tile of study {study}."""
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
    priority: 1  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("simulate_events"),
        runtime=job_runtime("simulate_events"),
    params:
        block=study_block("events"),
        code=script_code("simulate_events"),
    script:
        "../scripts/simulate_events.py"


rule simulate_spectra:
    """Response spectra of the cells of one tile of study {study}."""
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
    priority: 1  # a report chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("simulate_spectra"),
        runtime=job_runtime("simulate_spectra"),
    params:
        block=study_block("spectra"),
        code=script_code("simulate_spectra"),
    script:
        "../scripts/simulate_spectra.py"


rule simulate_trace:
    """A stretch of the motion of study {study} (Figs. 3, 10)."""
    input:
        noise=study_noise,
    output:
        targets.product("trace", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/simulate_trace/{study}.log",
    benchmark:
        "results/benchmarks/simulate_trace/{study}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("simulate_trace"),
        runtime=job_runtime("simulate_trace"),
    params:
        block=study_block("trace"),
        code=script_code("simulate_trace"),
    script:
        "../scripts/simulate_trace.py"


rule simulate_map:
    """The motion map of one tile of study {study} (Fig. 15)."""
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
    priority: 2  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("simulate_map"),
        runtime=job_runtime("simulate_map"),
    params:
        block=study_block("map"),
        code=script_code("simulate_map"),
    script:
        "../scripts/simulate_map.py"


rule simulate_escape:
    """Residence times of the escape cells of study {study} at noise level {level}."""
    output:
        "results/cells/{study}/escape/{level}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/simulate_escape/{study}/{level}.log",
    benchmark:
        "results/benchmarks/simulate_escape/{study}/{level}.tsv"
    threads: 1
    priority: 1  # a report chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("simulate_escape"),
        runtime=job_runtime("simulate_escape"),
    params:
        block=study_block("escape"),
        noise=escape_noise,
        code=script_code("simulate_escape"),
    script:
        "../scripts/simulate_escape.py"
