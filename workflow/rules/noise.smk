rule noise:
    output:
        "results/noise/{noise}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/noise/{noise}.log",
    benchmark:
        "results/benchmarks/noise/{noise}.tsv"
    params:
        entry=noise_entry,
        provenance=noise_provenance,
    script:
        "../scripts/noise.py"
