"""Rule aggregate_attractors: the basins and Lyapunov datasets of one `orbits` entry."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.aggregate_attractors(snakemake.params.entry, list(snakemake.input),
                               snakemake.output.basins, snakemake.output.lyapunov)
