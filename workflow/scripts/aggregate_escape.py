"""Rule aggregate_escape: the escape dataset of a study from its noise levels."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.aggregate_escape(snakemake.wildcards.study, snakemake.params.block,
                           snakemake.params.noise, list(snakemake.input), snakemake.output[0])
