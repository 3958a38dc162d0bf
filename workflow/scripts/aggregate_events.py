"""Rule aggregate_events: the events dataset of a study from its tiles."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.aggregate(snakemake.wildcards.study, snakemake.params.entry, "events", snakemake.input,
                snakemake.output[0], snakemake.params.provenance)
