"""Rule simulate_trace: a short record from rest (Figs. 3, 10)."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.trace(snakemake.wildcards.study, snakemake.params.block, snakemake.input.noise,
                snakemake.output[0])
