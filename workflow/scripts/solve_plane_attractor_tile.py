"""Rule solve_plane_attractor_tile: basins and Lyapunov exponents on some rows of a plane."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.attractor_tile(snakemake.params.entry, int(snakemake.wildcards.tile),
                         snakemake.output[0], threads=snakemake.threads,
                         study=snakemake.wildcards.study)
