"""Rule aggregate_map: the probability-map dataset of a study from its tiles."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.aggregate(snakemake.wildcards.study, snakemake.params.block, "map",
                    list(snakemake.input), snakemake.output[0])
