"""Rule draw_validation_figure: the work-precision or stress figure, saved as PNG and PDF, drawn
in a fork of the workflow's warm process (`vibroimpact.pipeline.forked`)."""
from vibroimpact.pipeline import forked


def draw(job):
    from vibroimpact import plotting
    from vibroimpact.pipeline import io, tasks
    from vibroimpact.pipeline.figures import drawing_function

    with tasks.logged(job.log[0]):
        figure = drawing_function(job.wildcards.validation_fig)
        plotting.save(figure(io.load_dataset(job.input[0])), job.output.png)


forked.run(draw, snakemake, benchmark=snakemake.params.benchmark)
