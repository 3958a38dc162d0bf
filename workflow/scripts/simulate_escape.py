"""Rule simulate_escape: residence times of the escape cells at one noise level."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.escape_level(snakemake.wildcards.study, snakemake.params.block, snakemake.params.noise,
                       int(snakemake.wildcards.level), snakemake.output[0])
