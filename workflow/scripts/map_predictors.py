"""Rule map_predictors: the rank correlations of the predictors with P over one study's map."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    inputs = snakemake.input
    tasks.map_predictors(inputs.map, snakemake.output[0], inputs.get("orbits"),
                         inputs.get("basins"), inputs.get("lyapunov"))
