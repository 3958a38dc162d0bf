# A plane study's basins and Lyapunov exponents (its `attractors` block): tiles over the
# plane's first axis, solved as jobs; joining them is cheap: run where Snakemake runs.
# (Their input and runtime functions are in common.smk.)


rule solve_plane_attractor_tile:
    """Basins and Lyapunov exponents on one tile of plane study {study}."""
    output:
        "results/cells/{study}/attractors/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/solve_plane_attractor_tile/{study}/{tile}.log",
    benchmark:
        "results/benchmarks/solve_plane_attractor_tile/{study}/{tile}.tsv"
    # starts run in parallel numba threads: exactly the rule's threads
    threads: TILE_THREADS  # common.smk, "Threads of the tiles"
    resources:
        mem_mb=job_mem_mb("solve_plane_attractor_tile"),
        runtime=job_runtime("solve_plane_attractor_tile"),
    params:
        entry=study_block("attractors"),
        code=script_code("solve_plane_attractor_tile"),
    script:
        "../scripts/solve_plane_attractor_tile.py"


rule aggregate_plane_attractors:
    """The basins and Lyapunov datasets of plane study {study}, from its tiles."""
    localrule: True
    input:
        plane_attractor_tiles,
    output:
        basins=targets.product("plane_basins", name="{study}"),
        lyapunov=targets.product("plane_lyapunov", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_plane_attractors/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_plane_attractors/{study}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("aggregate_plane_attractors"),
        runtime=job_runtime("aggregate_plane_attractors"),
    params:
        entry=study_block("attractor_basins"),
        code=script_code("aggregate_plane_attractors"),
    script:
        "../scripts/aggregate_plane_attractors.py"
