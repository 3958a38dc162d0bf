"""Rule simulate_spectra: Welch spectra of a(tau) for the cells of one tile."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.spectra_tile(snakemake.wildcards.study, snakemake.params.block,
                       int(snakemake.wildcards.tile), snakemake.input.noise, snakemake.output[0])
