"""Rule simulate_trace: a short sampled record from rest (Figs. 3, 10)."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.trace(snakemake.wildcards.study, snakemake.params.entry, snakemake.input.noise,
            snakemake.output[0], snakemake.params.provenance)
