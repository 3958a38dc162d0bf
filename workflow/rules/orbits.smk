# Orbit tiles are solved as jobs (SLURM: grouped, workflow/profiles/slurm); joining
# them into one dataset is cheap: run where Snakemake runs.


rule solve_orbit_tile:
    """The periodic (m/n) motions of one tile of orbits entry {orbits}."""
    output:
        "results/orbits/{orbits}/tiles/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/solve_orbit_tile/{orbits}/{tile}.log",
    benchmark:
        "results/benchmarks/solve_orbit_tile/{orbits}/{tile}.tsv"
    # rows run in parallel numba threads: exactly the rule's threads (tasks.orbit_tile)
    threads: TILE_THREADS  # common.smk, "Threads of the tiles"
    priority: 2  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("solve_orbit_tile"),
        runtime=job_runtime("solve_orbit_tile"),
    params:
        entry=orbits_block("orbits"),
        code=script_code("solve_orbit_tile"),
    script:
        "../scripts/solve_orbit_tile.py"


rule solve_clearance_orbit_tile:
    """The stable periodic motions of one tile of two-wall orbits entry {orbits}."""
    output:
        "results/orbits/{orbits}/clearance_tiles/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/solve_clearance_orbit_tile/{orbits}/{tile}.log",
    benchmark:
        "results/benchmarks/solve_clearance_orbit_tile/{orbits}/{tile}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("solve_clearance_orbit_tile"),
        runtime=job_runtime("solve_clearance_orbit_tile"),
    params:
        entry=orbits_block("orbits"),
        code=script_code("solve_clearance_orbit_tile"),
    script:
        "../scripts/solve_clearance_orbit_tile.py"


rule aggregate_orbits:
    """The orbits dataset of entry {orbits}, from its tiles."""
    localrule: True
    input:
        orbit_tiles,
    output:
        targets.product("orbits", name="{orbits}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_orbits/{orbits}.log",
    benchmark:
        "results/benchmarks/aggregate_orbits/{orbits}.tsv"
    threads: 1
    priority: 2  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("aggregate_orbits"),
        runtime=job_runtime("aggregate_orbits"),
    params:
        entry=orbits_block("orbits"),
        code=script_code("aggregate_orbits"),
    script:
        "../scripts/aggregate_orbits.py"


rule solve_map_orbits:
    """The orbits of the entry study {study}'s fig15_vs_fig16 names, at its map's cells."""
    input:
        unpack(map_orbits_inputs),
    output:
        targets.product("map_orbits", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/solve_map_orbits/{study}.log",
    benchmark:
        "results/benchmarks/solve_map_orbits/{study}.tsv"
    threads: 1
    priority: 1  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("solve_map_orbits"),
        runtime=job_runtime("solve_map_orbits"),
    params:
        code=script_code("solve_map_orbits"),
    script:
        "../scripts/solve_map_orbits.py"


rule trace_boundaries:
    """The exact edges of the stable domains of orbits entry {orbits}, seeded from its map."""
    input:
        targets.product("orbits", name="{orbits}"),
    output:
        targets.product("boundaries", name="{orbits}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/trace_boundaries/{orbits}.log",
    benchmark:
        "results/benchmarks/trace_boundaries/{orbits}.tsv"
    threads: TILE_THREADS  # common.smk, "Threads of the tiles"
    priority: 1  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("trace_boundaries"),
        runtime=job_runtime("trace_boundaries"),
    params:
        entry=orbits_block("boundaries"),
        code=script_code("trace_boundaries"),
    script:
        "../scripts/trace_boundaries.py"


rule solve_attractor_tile:
    """Basins of attraction and Lyapunov exponents on one tile of orbits entry {orbits}."""
    output:
        "results/orbits/{orbits}/attractor_tiles/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/solve_attractor_tile/{orbits}/{tile}.log",
    benchmark:
        "results/benchmarks/solve_attractor_tile/{orbits}/{tile}.tsv"
    # starts run in parallel numba threads: exactly the rule's threads (tasks.attractor_tile)
    threads: TILE_THREADS  # common.smk, "Threads of the tiles"
    priority: 2  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("solve_attractor_tile"),
        runtime=job_runtime("solve_attractor_tile"),
    params:
        entry=orbits_block("attractors"),
        code=script_code("solve_attractor_tile"),
    script:
        "../scripts/solve_attractor_tile.py"


rule aggregate_attractors:
    """The basins and Lyapunov datasets of orbits entry {orbits}, from its tiles."""
    localrule: True
    input:
        attractor_tiles,
    output:
        basins=targets.product("basins", name="{orbits}"),
        lyapunov=targets.product("lyapunov", name="{orbits}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_attractors/{orbits}.log",
    benchmark:
        "results/benchmarks/aggregate_attractors/{orbits}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("aggregate_attractors"),
        runtime=job_runtime("aggregate_attractors"),
    params:
        entry=orbits_block("attractors"),
        code=script_code("aggregate_attractors"),
    script:
        "../scripts/aggregate_attractors.py"
