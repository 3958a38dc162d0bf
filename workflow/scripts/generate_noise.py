"""Rule generate_noise: the random force record of a `noises` entry."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.make_noise(snakemake.params.entry, snakemake.output[0])
