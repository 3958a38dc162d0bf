"""Rule draw_validation_figure: the work-precision or stress figure, saved as PNG and PDF."""
from vibroimpact import plotting
from vibroimpact.pipeline import io, tasks
from vibroimpact.pipeline.figures import drawing_function

with tasks.logged(snakemake.log[0]):
    draw = drawing_function(snakemake.wildcards.validation_fig)
    plotting.save(draw(io.load_dataset(snakemake.input[0])), snakemake.output.png)
