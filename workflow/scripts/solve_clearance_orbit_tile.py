"""Rule solve_clearance_orbit_tile: the stable motions of a two-wall orbits entry's rows."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.clearance_orbit_tile(snakemake.params.entry, int(snakemake.wildcards.tile),
                               snakemake.output[0])
