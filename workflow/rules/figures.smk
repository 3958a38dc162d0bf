# One rule draws every figure: its inputs and options come from the figure table
# (vibroimpact.pipeline.figures) through common.smk. Drawing is cheap: run locally (each
# rule's `localrule: True`: a `localrules:` list would name rules by the names a host that
# pulls this workflow in as a module renames).


# What each figure shows, with its parameters, for the report's caption (figure.rst reads it
# from the config, which the report hands to a caption template; not a param: rewording a
# caption redraws nothing).
config["figure_captions"] = figure_captions()


rule draw_figure:
    """Figure {fig} of study or orbits entry {owner}, as PNG and PDF."""
    localrule: True
    input:
        figure_inputs,
    output:
        # in `snakemake --report`, once: under `paper` when it is a paper figure (its copy
        # results/figures/figNN.png is not marked), else in its study's or orbits entry's
        png=report(
            targets.product("figure", owner="{owner}", figure="{fig}"),
            caption="../report/figure.rst",
            category=figure_report_category,
            labels=figure_report_labels,
        ),
        pdf=targets.product("figure", owner="{owner}", figure="{fig}", twin=".pdf"),
    log:
        "results/logs/draw_figure/{owner}/{fig}.log",
    threads: 1
    resources:
        mem_mb=job_mem_mb("draw_figure"),
        runtime=job_runtime("draw_figure"),
    conda:
        "../envs/vibroimpact.yaml"
    params:
        options=figure_options,
        code=script_code("draw_figure"),
        # written by the fork that draws, from its own resource use (`pipeline.forked`)
        benchmark="results/benchmarks/draw_figure/{owner}/{fig}.tsv",
    # drawn in a fork of Snakemake's process, its imports and matplotlib's first drawing
    # done once (`pipeline.forked`: 1.1 CPU-s a figure less), with any profile
    script:
        "../scripts/draw_figure.py"


rule copy_paper_figure:
    """The paper figure {paper_fig}: a copy of the study figure it names."""
    localrule: True
    input:
        unpack(paper_figure_source),
    output:
        # in the report as its source (draw_figure)
        png=targets.product("top_figure", figure="{paper_fig}"),
        pdf=targets.product("top_figure", figure="{paper_fig}", twin=".pdf"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/copy_paper_figure/{paper_fig}.log",
    threads: 1
    resources:
        mem_mb=job_mem_mb("copy_paper_figure"),
        runtime=job_runtime("copy_paper_figure"),
    shell:
        "(cp {input.png} {output.png}.tmp && cp {input.pdf} {output.pdf}.tmp"
        " && mv {output.png}.tmp {output.png} && mv {output.pdf}.tmp {output.pdf}) > {log} 2>&1"
