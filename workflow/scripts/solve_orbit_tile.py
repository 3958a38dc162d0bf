"""Rule solve_orbit_tile: existence and stability of (m/n) motions on some 1/beta rows."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.orbit_tile(snakemake.params.entry, int(snakemake.wildcards.tile), snakemake.output[0],
                     threads=snakemake.threads)
