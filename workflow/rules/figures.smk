# One rule draws every figure: its inputs and options come from the figure table
# (vibroimpact.pipeline.figures) through common.smk. Drawing is cheap: run locally.
localrules:
    draw_figure,
    copy_paper_figure,


rule draw_figure:
    input:
        figure_inputs,
    output:
        # in `snakemake --report`: one category per study or orbits entry
        png=report("results/figures/{owner}/{fig}.png", caption="../report/figure.rst",
                   category="{owner}", labels={"figure": "{fig}"}),
        pdf="results/figures/{owner}/{fig}.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/draw_figure/{owner}/{fig}.log",
    benchmark:
        "results/benchmarks/draw_figure/{owner}/{fig}.tsv"
    threads: 1
    resources:
        mem_mb=BASE_MEM_MB,
        runtime=5,
    params:
        options=figure_options,
        caption=figure_caption,     # what it shows, with which parameters (report caption)
        code=CODE["figure"],
    script:
        "../scripts/draw_figure.py"


rule copy_paper_figure:
    input:
        unpack(paper_figure_source),
    output:
        png=report("results/figures/{paper_fig}.png", caption="../report/paper_figure.rst",
                   category="paper", labels={"figure": "{paper_fig}"}),
        pdf="results/figures/{paper_fig}.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/copy_paper_figure/{paper_fig}.log",
    threads: 1
    resources:
        mem_mb=100,
        runtime=1,
    shell:
        "(cp {input.png} {output.png}.tmp && cp {input.pdf} {output.pdf}.tmp"
        " && mv {output.png}.tmp {output.png} && mv {output.pdf}.tmp {output.pdf}) > {log} 2>&1"
