"""Rule solve_clearance_orbit_tile: the periodic motions of a two-wall orbits entry's rows, by
the shooting solver (`vibroimpact.attractors.plane.orbit_plane`)."""
from vibroimpact.attractors.plane import orbit_plane
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.orbit_tile(snakemake.params.entry, int(snakemake.wildcards.tile), snakemake.output[0],
                     solver=orbit_plane)
