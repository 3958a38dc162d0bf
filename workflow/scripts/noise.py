"""Rule noise: generate one random force record (results/noise/{noise}.nc)."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.make_noise(snakemake.params.entry, snakemake.output[0], snakemake.params.provenance)
