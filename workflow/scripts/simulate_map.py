"""Rule simulate_map: probabilities of the (m/n) motions on the cells of one tile (Fig. 15)."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.map_tile(snakemake.wildcards.study, snakemake.params.block,
                   int(snakemake.wildcards.tile), snakemake.input.noise, snakemake.output[0])
