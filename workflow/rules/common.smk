# Named helpers the rules use, each defined before its first use: config blocks, code
# digests, tile lists, the inputs of each rule, the targets of `rule all`. No numerics here.
#
# Rebuild scope (README, "What reruns"): each rule's params carry only the config block it
# reads and the digest of the code its script runs (`provenance.code_digest`: the import
# closure of the script, docstrings and comments left out; kept between runs by
# `digest_cache`), so Snakemake's params trigger reruns exactly the jobs an edit touches,
# committed or not. Provenance (version, commit, dirty flag, config digest, seed) is written
# by the jobs at run time, never passed through params (a commit alone must not rerun
# anything).
from pathlib import Path
import shlex
import sys
from types import SimpleNamespace

from snakemake_interface_executor_plugins.settings import DeploymentMethod

from vibroimpact.pipeline import figures, forked, layout, targets
from vibroimpact.pipeline.config import requests
from vibroimpact.pipeline.digest_cache import cached_code_digest
from vibroimpact.pipeline.study import (
    JOB_KEYS,
    ORBIT_JOB_KEYS,
    attractor_rows,
    orbit_rows,
    plane_attractor_rows,
    shooting,
)
from vibroimpact.reports import arguments


wildcard_constraints:
    study="[A-Za-z][A-Za-z0-9_]*",
    # not ending like the entry's derived datasets (results/orbits/<name>_basins.nc ...)
    orbits="[A-Za-z][A-Za-z0-9_]*(?<!_boundaries)(?<!_basins)(?<!_lyapunov)",
    noise="[A-Za-z][A-Za-z0-9_]*",
    sweep="[A-Za-z][A-Za-z0-9_]*",
    tile="[0-9]+",
    level="[0-9]+",
    # a study name, or orbits/<name> for an `orbits` entry (their figures never collide)
    owner="(orbits/)?[A-Za-z][A-Za-z0-9_]*",
    # figNN or fig15_vs_fig16 of the figure table, -k: k-th value of a listed parameter (not a
    # sweep.png, nor the validation figures)
    fig="(fig[0-9][0-9](_vs_fig[0-9][0-9])?|basins|lyapunov|residence|escape_vs_noise)(-[0-9]+)?",
    paper_fig="fig[0-9][0-9](_vs_fig[0-9][0-9])?|basins|lyapunov|residence|escape_vs_noise",


# With `--sdm conda` a job runs in the conda environment of envs/vibroimpact.yaml (the pins of
# requirements.lock, no path: it works from any folder) and imports vibroimpact from the copy
# this Snakemake runs, through PYTHONPATH, alone (not the other distributions beside it): the
# workflow and the package are one release.
if DeploymentMethod.CONDA in workflow.deployment_settings.deployment_method:
    layout.import_alone_in_jobs(".snakemake/vibroimpact-package")


# The figure jobs are drawn in forks of this process, warmed once, whatever the profile
# (`vibroimpact.pipeline.forked`): its server starts here, in the main process only, and idles
# until a figure job asks (nothing is imported before).
if workflow.is_main_process:
    forked.serve()


# every study resolved once, by `configuration.load` (the Snakefile's PLAN): its grids are
# those the config checks expanded
STUDIES = PLAN.studies


# the digests of the last runs, by the bytes of the package and the script (each Snakemake
# start would parse the whole package again: 2.3 CPU-s, three times a `make`), kept in the
# working directory's .snakemake folder, beside Snakemake's own records
CODE_DIGESTS = Path(".snakemake", "vibroimpact-code-digests.json")


# the workflow's own files, from the Snakefile's folder (WORKFLOW_DIR), wherever it runs
SCRIPTS = WORKFLOW_DIR / "scripts"


def script_code(rule):
    """The code digest of ``scripts/<rule>.py``: what its job runs."""
    return cached_code_digest(SCRIPTS / f"{rule}.py", CODE_DIGESTS)


def own_files(inputs):
    """``inputs`` with the workflow's own files among them (the report notebook, the stress
    campaign's table: `targets.WORKFLOW_INPUTS`, relative to the workflow's folder) made
    paths of this workflow's copy, so that a module reads its own notebooks: relative to the
    working directory when the workflow lies under it (a checkout: a copy of the project and
    its build stays up to date, its inputs' paths unchanged), else absolute."""
    return {
        key: layout.input_path(WORKFLOW_DIR / path) if key in targets.WORKFLOW_INPUTS else path
        for key, path in inputs.items()
    }


# --- Priorities ------------------------------------------------------------------------------
# Of the ready jobs Snakemake starts those of highest `priority:` first (its ILP scheduler
# maximizes the sum of the priorities of the jobs it starts together, then the cores they
# use). The heads of the build's longest chains carry one: the noise records (every
# simulation reads one) 3; the map's tiles, the attractor and orbit tiles and the orbits'
# join 2; the events tiles, the map's join, its predictors, the boundaries, and the spectra
# and escape jobs (heads of the chains that end in the reports: without a priority the
# escape levels could run last, and the map's report wait on their figure) 1; figures,
# reports and the rest 0. The work-precision run holds every core, and a job starts only
# when its cores are free at once: it has 7, more than any two other jobs together (3 + 3),
# so it starts first, while every core is free, not at the end, where the build would wait
# for it alone. Replayed on the job times of a default build, the priorities of the long
# chains ended it a few seconds earlier, and within a narrower range over random orders of
# the jobs of equal priority, than none.

# --- Threads of the tiles that run numba threads ---------------------------------------------
# The orbit, attractor and boundary jobs run their rows and starts on numba threads: half the
# cores each (one on 2 cores), so that they pack beside the one-core jobs. Asking for every
# core, such a job waited until the other jobs drained: on 2 cores the orbit and attractor
# tiles then ran one after the other, near the end of the build.
# That is this machine's rule; on a cluster the cores of Snakemake's process say nothing of
# a node's, and the SLURM profile sets each threaded rule's threads itself (`set-threads`,
# workflow/profiles/slurm), which replaces this default.
TILE_THREADS = max(1, workflow.cores // 2)


# --- config blocks --------------------------------------------------------------------------


def study_block(kind):
    """The part of ``studies[{study}]`` that a ``kind`` job reads."""

    def block(wildcards):
        entry = config["studies"][wildcards.study]
        # a plane study's job may read more (its fixed values): JOB_KEYS["plane_<kind>"]
        keys = (
            JOB_KEYS.get(f"plane_{kind}", JOB_KEYS[kind]) if entry.get("plane") else JOB_KEYS[kind]
        )
        return {key: entry[key] for key in keys if key in entry}

    return block


def noise_entry(wildcards):
    """The config entry ``noises[{noise}]``."""
    return config["noises"][wildcards.noise]


def orbits_block(kind):
    """The part of ``orbits[{orbits}]`` that a ``kind`` job reads (``ORBIT_JOB_KEYS``)."""

    def block(wildcards):
        entry = config["orbits"][wildcards.orbits]
        return {key: entry[key] for key in ORBIT_JOB_KEYS[kind] if key in entry}

    return block


# --- inputs of the simulations and aggregations ----------------------------------------------


def study_noise(wildcards):
    """The noise record that drives study ``{study}``."""
    return f"results/noise/{config['studies'][wildcards.study]['noise']}.nc"


def escape_noise(wildcards):
    """What an escape job reads of study ``{study}``'s noise entry: its spectrum, ``dt`` and
    seed (each level's rms is the study's; no record file, no ``n_samples``)."""
    entry = config["noises"][config["studies"][wildcards.study]["noise"]]
    return {k: entry[k] for k in ("kind", "dt", "beta_c", "zeta_f", "seed") if k in entry}


def escape_levels(wildcards):
    """The escape levels of study ``{study}``, one file each."""
    n = len(config["studies"][wildcards.study]["escape"]["rms"])
    return [f"results/cells/{wildcards.study}/escape/{k}.nc" for k in range(n)]


def tiles(kind):
    """The ``kind`` tiles of study ``{study}``."""

    def files(wildcards):
        n = STUDIES[wildcards.study].n_tiles(kind)
        return [f"results/cells/{wildcards.study}/{kind}/{t}.nc" for t in range(n)]

    return files


def orbit_tiles(wildcards):
    """The tiles of orbits entry ``{orbits}`` (the shooting solver's, two walls or an impact
    law: rule ``solve_clearance_orbit_tile``'s)."""
    entry = config["orbits"][wildcards.orbits]
    _, n = orbit_rows(entry)
    tiles = "clearance_tiles" if shooting(entry) else "tiles"
    return [f"results/orbits/{wildcards.orbits}/{tiles}/{t}.nc" for t in range(n)]


def attractor_tiles(wildcards):
    """The attractor-map tiles of orbits entry ``{orbits}``."""
    _, n = attractor_rows(config["orbits"][wildcards.orbits])
    return [f"results/orbits/{wildcards.orbits}/attractor_tiles/{t}.nc" for t in range(n)]


# --- figures ----------------------------------------------------------------------------------


def _owner(wildcards):
    """``("orbits", name, entry)`` or ``("study", name, entry)`` of a figure's owner."""
    if wildcards.owner.startswith("orbits/"):
        name = wildcards.owner.split("/", 1)[1]
        return "orbits", name, config["orbits"][name]
    return "study", wildcards.owner, config["studies"][wildcards.owner]


# Where each dataset a figure can read lives ({name}: the owner; {noise}: its noise record).
_DATASETS = targets.DATASETS


def figure_inputs(wildcards):
    """The datasets figure ``{fig}`` of ``{owner}`` draws, from the table FIGURES."""
    return targets.figure_inputs(config, wildcards.owner, wildcards.fig)


def figure_options(wildcards):
    """The drawing options of ``{fig}`` from its owner's config entry."""
    _, _, entry = _owner(wildcards)
    return figures.figure_options(entry, wildcards.fig)


def figure_captions():
    """``{png: caption}`` of every figure of every study and orbits entry: what it shows,
    with its parameters. The report's caption template (workflow/report/figure.rst) reads it
    from ``config["figure_captions"]``: a caption is no param, so rewording one redraws
    nothing."""
    captions = {}
    for kind, section, prefix in (("study", "studies", ""), ("orbits", "orbits", "orbits/")):
        for name, entry in config[section].items():
            for fig in figures.figure_targets(entry):
                png = f"results/figures/{prefix}{name}/{fig}.png"
                captions[png] = figures.caption(kind, name, entry, fig)
    return captions


def paper_figure_source(wildcards):
    """The PNG and PDF of the figure that ``paper_figures[{paper_fig}]`` names."""
    return targets.paper_figure_source(config, wildcards.paper_fig)


def _paper_figure_of(wildcards):
    """The paper figure (``fig07`` ...) that this config copies from ``{fig}`` of ``{owner}``,
    or None."""
    png = f"results/figures/{wildcards.owner}/{wildcards.fig}.png"
    for paper_fig in sorted(PLAN.drawn["paper_figures"]):
        if paper_figure_source(SimpleNamespace(paper_fig=paper_fig))["png"] == png:
            return paper_fig
    return None


def figure_report_category(wildcards):
    """``{fig}`` of ``{owner}`` in `snakemake --report`: under ``paper`` when it is a paper
    figure, else under its owner (each figure once: the paper's copies are not marked)."""
    return "paper" if _paper_figure_of(wildcards) else wildcards.owner


def figure_report_labels(wildcards):
    """The report's label of ``{fig}``: under ``paper`` the paper's name (``fig11``, not the
    study's ``fig11-0``; the caption names the study)."""
    return {"figure": _paper_figure_of(wildcards) or wildcards.fig}


# --- sweeps (sweeps.smk) ----------------------------------------------------------------------


def _sweep(wildcards):
    """The record ``config["sweeps"][{sweep}]``: its studies, keys and values."""
    if wildcards.sweep not in config["sweeps"]:
        raise ValueError(
            f"{wildcards.sweep} is not a sweep; sweeps: " f"{sorted(config['sweeps']) or 'none'}"
        )
    return config["sweeps"][wildcards.sweep]


def sweep_inputs(wildcards):
    """The events datasets of the studies of sweep ``{sweep}``, in its order."""
    return targets.sweep_inputs(config, wildcards.sweep)


def sweep_labels(wildcards):
    """The label of each combination of sweep ``{sweep}`` (the figure's legend)."""
    return configuration.sweep_labels(_sweep(wildcards))


# --- validation (validation.smk) ------------------------------------------------------------

# Each validation figure and the dataset it draws.
VALIDATION_FIGURES = targets.VALIDATION_FIGURES


# --- reports (reports.smk): one notebook per study, per orbits entry, two for validation -----

#: The interpreter running Snakemake (the .venv's): reports call its papermill and nbconvert;
#: with `--sdm conda` or `apptainer`, the environment's own `python`.
PYTHON = (
    "python" if workflow.deployment_settings.deployment_method else shlex.quote(sys.executable)
)


def predictors_inputs(wildcards):
    """The map of study ``{study}`` and, when it draws Fig. 15 over an orbits entry, that
    entry's orbit map, basins and Lyapunov datasets: what its predictors are computed from."""
    return targets.predictors_inputs(config, wildcards.study)


def map_orbits_inputs(wildcards):
    """The map of study ``{study}`` and the orbit map its ``fig15_vs_fig16`` names: the
    orbits rule ``solve_map_orbits`` solves at the map's own cells."""
    return targets.map_orbits_inputs(config, wildcards.study)


def study_report_inputs(wildcards):
    """The notebook, the datasets and the figures of a study and of its ``report_with``, and
    the study's noise record (its provenance row, whether or not a figure draws it); with a
    map over an orbits entry that has attractors, their basins and Lyapunov datasets."""
    return own_files(targets.study_report_inputs(config, wildcards.study, wildcards.report))


def orbits_report_inputs(wildcards):
    """The notebook, the dataset and the figures of orbits entry ``{orbits}``, and the map
    drawn over it (Fig. 15 against Fig. 16), if a built study draws one."""
    return own_files(targets.orbits_report_inputs(config, PLAN.drawn, wildcards.orbits))


def validation_report_inputs(wildcards):
    """The notebook, the dataset and the figure of validation report ``{vreport}``."""
    return own_files(targets.validation_report_inputs(wildcards.vreport))


def _report_notebook(wildcards):
    """The name of the notebook a report rule runs."""
    if "vreport" in wildcards.keys():
        return wildcards.vreport
    return wildcards.report if "report" in wildcards.keys() else "periodic_motions"


def report_code(wildcards):
    """The code digest of the report's notebook: what its import lines reach."""
    notebook = WORKFLOW_DIR / "notebooks" / f"{_report_notebook(wildcards)}.ipynb"
    return cached_code_digest(notebook, CODE_DIGESTS)


def report_arguments(wildcards, input):
    """``-p name value`` for every parameter of the report's notebook
    (`vibroimpact.reports.arguments`)."""
    study = wildcards.get("study")
    parameters = arguments.notebook_parameters(
        _report_notebook(wildcards),
        dict(input.items()),
        study=study,
        entry=config["studies"][study] if study else None,
        inv_beta=STUDIES[study].inv_beta if study else (),
        orbits=wildcards.get("orbits"),
    )
    return arguments.papermill_arguments(parameters)


def build_owners(wildcards):
    """The owners of every job of this build, for rule job_costs
    (`vibroimpact.reports.run.build_owners`)."""
    from vibroimpact.pipeline.config.plan import built_entries
    from vibroimpact.reports import run

    return run.build_owners(built_entries(config, PLAN.drawn)[1])


# --- targets of `rule all` ------------------------------------------------------------------
# The same lists the plan walks (vibroimpact.pipeline.targets.needed_files), so the plan counts
# the jobs this DAG schedules.


def all_targets():
    """The figures and reports of the entries the config builds (``PLAN.drawn``: with
    ``paper: false``, only the user's file's own entries)."""
    return targets.all_targets(config, PLAN.drawn)


# Resources: what a job asks of a scheduler, from its work (cells, steps, records, the
# map's cells) by the plan's cost model (vibroimpact.pipeline.config.requests; README, "On a
# SLURM cluster"), times the attempt: a job retried (the SLURM profile's `retries`) asks
# twice, then three times as much memory and time.


def job_mem_mb(name):
    """The memory (MB) a job of rule ``name`` asks at its attempt."""

    def mem_mb(wildcards, attempt):
        return requests.job_request(name, config, STUDIES, dict(wildcards.items()), attempt).mem_mb

    return mem_mb


def job_runtime(name):
    """The run time (minutes) a job of rule ``name`` asks at its attempt."""

    def runtime(wildcards, attempt):
        return requests.job_request(
            name, config, STUDIES, dict(wildcards.items()), attempt
        ).runtime

    return runtime


def plane_attractor_tiles(wildcards):
    """The attractor tiles of plane study ``{study}``."""
    _, n = plane_attractor_rows(config["studies"][wildcards.study])
    return [f"results/cells/{wildcards.study}/attractors/{t}.nc" for t in range(n)]
