"""Rule aggregate_orbits: one orbit map from its tiles."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.aggregate_orbits(list(snakemake.input), snakemake.output[0], snakemake.params.provenance)
