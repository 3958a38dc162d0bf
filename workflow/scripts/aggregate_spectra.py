"""Rule aggregate_spectra: the spectra dataset of a study from its tiles."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.aggregate(snakemake.wildcards.study, snakemake.params.entry, "spectra", snakemake.input.tiles,
                snakemake.output[0], snakemake.params.provenance, noise_path=snakemake.input.noise)
