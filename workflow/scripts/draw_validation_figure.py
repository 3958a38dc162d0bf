"""Rule draw_validation_figure: the work-precision or stress figure, saved as PNG and PDF."""
from vibroimpact import plotting
from vibroimpact.pipeline import io, tasks

with tasks.logged(snakemake.log[0]):
    draw = getattr(plotting, snakemake.wildcards.validation_fig)
    plotting.save(draw(io.load_dataset(snakemake.input[0])), snakemake.output.png)
