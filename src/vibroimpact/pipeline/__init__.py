"""The workflow-facing layer: studies and their cells, datasets, files, the units of work.

Knows about files and config entries, never about Snakemake: the scripts under
``workflow/scripts`` unpack ``snakemake.*`` into calls of `tasks`.
"""
