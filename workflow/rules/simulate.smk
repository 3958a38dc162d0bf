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
    params:
        entry=study_entry,
        provenance=study_provenance,
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
    params:
        entry=study_entry,
        provenance=study_provenance,
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
    params:
        entry=study_entry,
        provenance=study_provenance,
    script:
        "../scripts/simulate_trace.py"
