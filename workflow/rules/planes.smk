# A plane study's basins and Lyapunov exponents (its `attractors` block): tiles over the
# plane's first axis, solved as jobs; joining them is cheap: run where Snakemake runs.
from vibroimpact.pipeline.study import plane_attractor_rows


localrules:
    aggregate_plane_attractors,


def plane_attractor_tiles(wildcards):
    """The attractor tiles of plane study ``{study}``."""
    _, n = plane_attractor_rows(config["studies"][wildcards.study])
    return [f"results/cells/{wildcards.study}/attractors/{t}.nc" for t in range(n)]


def plane_attractor_runtime_min(wildcards):
    """Minutes of a plane study's attractor tile: its cells' starts at the cost model's CPU
    time each, with the simulate jobs' margin and floor."""
    entry = config["studies"][wildcards.study]
    rows, n_tiles = plane_attractor_rows(entry)
    cells = len(rows[int(wildcards.tile) :: n_tiles]) * len(grid_values(entry[entry["plane"][1]]))
    cpu = costs.attractor_cpu_s(cells, int(entry["attractors"]["n_starts"]))
    return costs.RUNTIME_FLOOR_MIN + math.ceil(costs.RUNTIME_MARGIN * cpu / 60)


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
    threads: 2
    resources:
        mem_mb=BASE_MEM_MB + 300,
        runtime=plane_attractor_runtime_min,
    params:
        entry=study_block("attractors"),
        code=script_code("solve_plane_attractor_tile"),
    script:
        "../scripts/solve_plane_attractor_tile.py"


rule aggregate_plane_attractors:
    """The basins and Lyapunov datasets of plane study {study}, from its tiles."""
    input:
        plane_attractor_tiles,
    output:
        basins="results/datasets/{study}_basins.nc",
        lyapunov="results/datasets/{study}_lyapunov.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_plane_attractors/{study}.log",
    benchmark:
        "results/benchmarks/aggregate_plane_attractors/{study}.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB,
        runtime=5,
    params:
        entry=study_block("attractors"),
        code=script_code("aggregate_plane_attractors"),
    script:
        "../scripts/aggregate_plane_attractors.py"
