# Orbit tiles are solved as jobs (SLURM: grouped, workflow/profiles/slurm); joining
# them into one dataset is cheap: run where Snakemake runs.
localrules:
    aggregate_orbits,


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
    threads: 2
    resources:
        mem_mb=BASE_MEM_MB + 200,
        runtime=30,
    params:
        entry=orbits_entry,
        code=script_code("solve_orbit_tile"),
    script:
        "../scripts/solve_orbit_tile.py"


rule aggregate_orbits:
    """The orbits dataset of entry {orbits}, from its tiles."""
    input:
        orbit_tiles,
    output:
        "results/orbits/{orbits}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_orbits/{orbits}.log",
    benchmark:
        "results/benchmarks/aggregate_orbits/{orbits}.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB,
        runtime=5,
    params:
        entry=orbits_entry,
        code=script_code("aggregate_orbits"),
    script:
        "../scripts/aggregate_orbits.py"
