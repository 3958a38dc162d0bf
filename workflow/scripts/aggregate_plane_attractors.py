"""Rule aggregate_plane_attractors: the basins and Lyapunov datasets of a plane study."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.aggregate_plane_attractors(snakemake.params.entry, list(snakemake.input),
                                     snakemake.output.basins, snakemake.output.lyapunov)
