"""Rule draw_sweep: the means of a sweep's studies side by side, saved as PNG and PDF; a
sweep over a plane's third parameter: its maps side by side (`plotting.map_stack`)."""
from vibroimpact import plotting
from vibroimpact.pipeline import io, tasks
from vibroimpact.plotting.sweep import sweep_means

with tasks.logged(snakemake.log[0]), plotting.style():
    datasets = [io.load_dataset(path) for path in snakemake.input]
    if "axes" in datasets[0].attrs:     # maps over a plane (docs/datasets.md)
        figure = plotting.map_stack(*datasets)
    else:
        figure = sweep_means(datasets, snakemake.params.labels)
    plotting.save(figure, snakemake.output.png)
