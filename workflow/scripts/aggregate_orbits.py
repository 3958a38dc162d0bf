"""Rule aggregate_orbits: the orbit map of one `orbits` entry from its tiles."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.aggregate_orbits(snakemake.params.entry, list(snakemake.input), snakemake.output[0])
