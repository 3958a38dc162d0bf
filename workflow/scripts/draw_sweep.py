"""Rule draw_sweep: the means of a sweep's studies side by side, saved as PNG and PDF."""
from vibroimpact import plotting
from vibroimpact.pipeline import io, tasks
from vibroimpact.plotting.sweep import sweep_means

with tasks.logged(snakemake.log[0]), plotting.style():
    datasets = [io.load_dataset(path) for path in snakemake.input]
    plotting.save(sweep_means(datasets, snakemake.params.labels), snakemake.output.png)
