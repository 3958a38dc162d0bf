"""Rule orbit_tile: existence and stability of periodic impact motions on some 1/beta rows."""
from vibroimpact.pipeline import tasks

tasks.log_to(snakemake.log[0])
tasks.orbit_tile(snakemake.params.entry, int(snakemake.wildcards.tile), snakemake.output[0],
                 snakemake.params.provenance)
