"""Rule simulate_spectra: Welch spectra of a(tau) for the cells of one tile."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.spectra_tile(snakemake.wildcards.study, snakemake.params.entry, int(snakemake.wildcards.tile),
                   snakemake.input.noise, snakemake.output[0], snakemake.params.provenance)
