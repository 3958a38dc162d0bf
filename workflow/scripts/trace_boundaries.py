"""Rule trace_boundaries: the exact edges of the stable domains of one `orbits` entry."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.boundaries(snakemake.params.entry, snakemake.input[0], snakemake.output[0],
                     threads=snakemake.threads)
