"""Rule aggregate_spectra: the spectra dataset of a study from its tiles."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.aggregate(snakemake.wildcards.study, snakemake.params.block, "spectra",
                    list(snakemake.input.tiles), snakemake.output[0],
                    noise_path=snakemake.input.noise)
