"""Rule solve_clearance_orbit_tile: the periodic motions of an orbits entry's rows by the
shooting solver (`vibroimpact.attractors.plane.orbit_plane`: a second wall, or an impact law)."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    # here, not at the top: the job loads the simulator (numba) when it runs, and its code
    # digest still follows the solver
    from vibroimpact.attractors.plane import orbit_plane

    tasks.orbit_tile(snakemake.params.entry, int(snakemake.wildcards.tile), snakemake.output[0],
                     solver=orbit_plane)
