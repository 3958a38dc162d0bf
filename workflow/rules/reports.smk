# Report notebooks (notebooks/*.ipynb), executed by papermill from `shell:` rules: every input
# path and parameter is passed with -p, the notebook is a declared input, the executed notebook
# and its HTML rendering (nbconvert) are declared outputs under results/reports/<study>/, and
# the notebook's output goes to the rule's log. (Snakemake's `notebook:` directive would keep
# the executed notebook only as a log.) Both files are written in a temporary directory and
# moved into place when both exist, so a failed run leaves no report a later run would trust.
# The HTML reads offline: `vibroimpact.reports.notebook` renders it with nbconvert's template
# minus what it loads from the network, the maths turned into MathML at build time. Snakemake's
# report shows a rendering without the images (`.summary.html`): it holds every figure once.
# One process a report (`python -m vibroimpact.reports.notebook --execute`): papermill's
# Python API executes the notebook (its kernel a child process), then nbconvert renders both
# HTML forms (`--summary`); papermill, nbformat and nbconvert start once.
wildcard_constraints:
    report="random_force|harmonic_random",
    vreport="performance|stability",


# The predictors of a map's P (the bootstrap of rank correlations, the costly part of a map's
# report) are computed once, by rule map_predictors, for every report that shows the map.


rule map_predictors:
    """The rank correlations of the predictors with P over study {study}'s map."""
    input:
        unpack(predictors_inputs),
    output:
        targets.product("predictors", name="{study}"),
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/map_predictors/{study}.log",
    benchmark:
        "results/benchmarks/map_predictors/{study}.tsv"
    threads: 1
    priority: 1  # a long chain's head (common.smk, "Priorities")
    resources:
        mem_mb=job_mem_mb("map_predictors"),
        runtime=job_runtime("map_predictors"),
    params:
        code=script_code("map_predictors"),
    script:
        "../scripts/map_predictors.py"


REPORT_SHELL = (
    'tmp=$(mktemp -d "$(dirname {output.ipynb})/.report.XXXXXX"); '
    "trap 'rm -rf \"$tmp\"' EXIT; "
    "{params.python} -m vibroimpact.reports.notebook --execute {input.notebook} "
    "{params.arguments} --summary $tmp/summary.html $tmp/report.ipynb $tmp/report.html "
    "> {log} 2>&1; "
    "mv $tmp/summary.html {output.summary}; mv $tmp/report.html {output.html}; "
    "mv $tmp/report.ipynb {output.ipynb}"
)


rule study_report:
    """The executed report notebook {report} of study {study}, and its HTML."""
    localrule: True
    input:
        unpack(study_report_inputs),
    output:
        ipynb=targets.product("report", owner="{study}", report="{report}", twin=".ipynb"),
        html=targets.product("report", owner="{study}", report="{report}"),
        # in `snakemake --report` without its images: the report holds each figure once
        summary=report(
            targets.product("report", owner="{study}", report="{report}", twin=".summary.html"),
            caption="../report/report.rst",
            category="{study}",
            labels={"figure": "report: {report}"},
        ),
    log:
        "results/logs/report/{study}/{report}.log",
    benchmark:
        "results/benchmarks/report/{study}/{report}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("study_report"),
        runtime=job_runtime("study_report"),
    conda:
        "../envs/vibroimpact.yaml"
    params:
        arguments=report_arguments,
        python=PYTHON,  # the .venv's papermill and nbconvert, whether or not on PATH
        code=report_code,
    shell:
        REPORT_SHELL


rule orbits_report:
    """The executed periodic-motions report of orbits entry {orbits}, and its HTML."""
    localrule: True
    input:
        unpack(orbits_report_inputs),
    output:
        ipynb=targets.product(
            "report", owner="orbits/{orbits}", report="periodic_motions", twin=".ipynb"
        ),
        html=targets.product("report", owner="orbits/{orbits}", report="periodic_motions"),
        summary=report(
            targets.product(
                "report",
                owner="orbits/{orbits}",
                report="periodic_motions",
                twin=".summary.html",
            ),
            caption="../report/report.rst",
            category="orbits/{orbits}",
            labels={"figure": "report: periodic motions"},
        ),
    log:
        "results/logs/report/orbits/{orbits}.log",
    benchmark:
        "results/benchmarks/report/orbits/{orbits}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("orbits_report"),
        runtime=job_runtime("orbits_report"),
    conda:
        "../envs/vibroimpact.yaml"
    params:
        arguments=report_arguments,
        python=PYTHON,  # the .venv's papermill and nbconvert, whether or not on PATH
        code=report_code,
    shell:
        REPORT_SHELL


rule validation_report:
    """The executed validation report {vreport}, and its HTML."""
    localrule: True
    input:
        unpack(validation_report_inputs),
    output:
        ipynb=targets.product("report", owner="validation", report="{vreport}", twin=".ipynb"),
        html=targets.product("report", owner="validation", report="{vreport}"),
        summary=report(
            targets.product(
                "report", owner="validation", report="{vreport}", twin=".summary.html"
            ),
            caption="../report/report.rst",
            category="validation",
            labels={"figure": "report: {vreport}"},
        ),
    log:
        "results/logs/report/validation/{vreport}.log",
    benchmark:
        "results/benchmarks/report/validation/{vreport}.tsv"
    threads: 1
    resources:
        mem_mb=job_mem_mb("validation_report"),
        runtime=job_runtime("validation_report"),
    conda:
        "../envs/vibroimpact.yaml"
    params:
        arguments=report_arguments,
        python=PYTHON,  # the .venv's papermill and nbconvert, whether or not on PATH
        code=report_code,
    shell:
        REPORT_SHELL


# The costs of the build's jobs by rule, for Snakemake's report: not a target of `rule all`
# (it reads every job's benchmark file, so it would rerun after every change and sit in
# every figure's DAG); `vibroimpact report` (and `make`) builds it, forced, just before
# `snakemake --report`, and asks the report for it beside `all`.
rule job_costs:
    """The CPU time, wall time and peak memory of this build's jobs, by rule, beside the plan."""
    localrule: True
    output:
        html=report(
            "results/reports/job_costs.html",
            caption="../report/job_costs.rst",
            category="run",
            labels={"figure": "job costs by rule"},
        ),
        tsv="results/reports/job_costs.tsv",
    log:
        "results/logs/job_costs.log",
    threads: 1
    resources:
        mem_mb=job_mem_mb("job_costs"),
        runtime=job_runtime("job_costs"),
    conda:
        "../envs/vibroimpact.yaml"
    params:
        owners=build_owners,
        benchmarks="results/benchmarks",
        planned=lambda wildcards: PLAN.rule_costs(),
    script:
        "../scripts/job_costs.py"
