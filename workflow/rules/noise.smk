rule generate_noise:
    """The seeded noise record of `noises[{noise}]`: force samples and their spectrum."""
    output:
        targets.product("noise", noise="{noise}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/generate_noise/{noise}.log",
    benchmark:
        "results/benchmarks/generate_noise/{noise}.tsv"
    threads: 1
    priority: 3  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("generate_noise"),
        runtime=job_runtime("generate_noise"),
    params:
        entry=noise_entry,
        code=script_code("generate_noise"),
    script:
        "../scripts/generate_noise.py"
