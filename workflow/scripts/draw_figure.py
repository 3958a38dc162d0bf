"""Rule draw_figure: one figure from its datasets, saved as PNG and PDF, drawn in a fork of the
workflow's warm process (`vibroimpact.pipeline.forked`)."""
from vibroimpact.pipeline import forked


def draw(job):
    from vibroimpact.pipeline import tasks

    with tasks.logged(job.log[0]):
        tasks.figure(job.wildcards.fig, list(job.input), job.output.png, job.params.options)


forked.run(draw, snakemake, benchmark=snakemake.params.benchmark)
