"""Figure rules: draw one figure from its datasets and save the PNG and its PDF twin."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.figure(snakemake.params.figure, list(snakemake.input), snakemake.output.png,
             **snakemake.params.options)
