"""Rule draw_figure: one figure from its datasets, saved as PNG and PDF."""
from vibroimpact.pipeline import tasks

with tasks.logged(snakemake.log[0]):
    tasks.figure(snakemake.wildcards.fig, list(snakemake.input), snakemake.output.png,
                 snakemake.params.options)
