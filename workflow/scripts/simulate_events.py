"""Rule simulate_events: impact statistics of the cells of one tile."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.events_tile(snakemake.wildcards.study, snakemake.params.block,
                      int(snakemake.wildcards.tile), snakemake.input.noise, snakemake.output[0])
