"""Rule solve_map_orbits: the orbits of an orbits entry solved at one study's map cells."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.map_orbits(snakemake.input.map, snakemake.input.orbits, snakemake.output[0])
