# One rule per figure of the paper: each reads only what it draws.


rule fig03:
    input:
        "results/traces/{study}.nc",
    output:
        png="results/figures/{study}/fig03.png",
        pdf="results/figures/{study}/fig03.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig03.log",
    params:
        figure="fig03",
        options={},
    script:
        "../scripts/figure.py"


rule fig04:
    input:
        study_noise,
    output:
        png="results/figures/{study}/fig04.png",
        pdf="results/figures/{study}/fig04.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig04.log",
    params:
        figure="fig04",
        options={},
    script:
        "../scripts/figure.py"


rule fig05:
    input:
        study_noise,
    output:
        png="results/figures/{study}/fig05.png",
        pdf="results/figures/{study}/fig05.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig05.log",
    params:
        figure="fig05",
        options={},
    script:
        "../scripts/figure.py"


rule fig06:
    input:
        "results/datasets/{study}_spectra.nc",
    output:
        png="results/figures/{study}/fig06.png",
        pdf="results/figures/{study}/fig06.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig06.log",
    params:
        figure="fig06",
        options={},
    script:
        "../scripts/figure.py"


rule fig07:
    input:
        "results/datasets/{study}_events.nc",
    output:
        png="results/figures/{study}/fig07.png",
        pdf="results/figures/{study}/fig07.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig07.log",
    params:
        figure="fig07",
        options={},
    script:
        "../scripts/figure.py"


rule fig08:
    input:
        "results/datasets/{study}_events.nc",
    output:
        png="results/figures/{study}/fig08.png",
        pdf="results/figures/{study}/fig08.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig08.log",
    params:
        figure="fig08",
        options={},
    script:
        "../scripts/figure.py"


rule fig09:
    input:
        "results/datasets/{study}_events.nc",
    output:
        png="results/figures/{study}/fig09.png",
        pdf="results/figures/{study}/fig09.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig09.log",
    params:
        figure="fig09",
        options={},
    script:
        "../scripts/figure.py"


rule paper_figure:
    input:
        unpack(paper_figure_sources),
    output:
        png="results/figures/{fig}.png",
        pdf="results/figures/{fig}.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/paper_{fig}.log",
    localrule: True
    shell:
        "(cp {input.png} {output.png}.tmp && cp {input.pdf} {output.pdf}.tmp"
        " && mv {output.png}.tmp {output.png} && mv {output.pdf}.tmp {output.pdf}) > {log} 2>&1"


rule fig16:
    input:
        "results/orbits/{study}.nc",
    output:
        png="results/figures/{study}/fig16.png",
        pdf="results/figures/{study}/fig16.pdf",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/figures/{study}/fig16.log",
    params:
        figure="fig16",
        options={},
    script:
        "../scripts/figure.py"
