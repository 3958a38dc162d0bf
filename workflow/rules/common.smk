# Named helpers: config blocks, code digests, tile lists, the figure table. No numerics here.
#
# Rebuild scope (README, "What reruns"): each rule's params carry only the config block it
# reads and a digest of the package sources its output depends on, so Snakemake's params
# trigger reruns exactly the jobs an edit touches, committed or not. Provenance (version,
# commit, dirty flag, config digest, seed) is written by the jobs at run time, never passed
# through params (a commit alone must not rerun anything).
import hashlib
from pathlib import Path
import shlex
import sys
from types import SimpleNamespace

from vibroimpact.pipeline import figures
from vibroimpact.pipeline.provenance import source_digest
from vibroimpact.pipeline.study import Study, orbit_rows
from vibroimpact.reports.notebook import markdown_table


wildcard_constraints:
    study="[A-Za-z][A-Za-z0-9_]*",
    orbits="[A-Za-z][A-Za-z0-9_]*",
    noise="[A-Za-z][A-Za-z0-9_]*",
    tile="[0-9]+",
    # a study name, or orbits/<name> for an `orbits` entry (their figures never collide)
    owner="(orbits/)?[A-Za-z][A-Za-z0-9_]*",
    # figNN or fig15_vs_fig16 of the figure table, -k: k-th value of a listed parameter (not a
    # sweep.png, nor the validation figures)
    fig="fig[0-9][0-9](_vs_fig[0-9][0-9])?(-[0-9]+)?",
    paper_fig="fig[0-9][0-9](_vs_fig[0-9][0-9])?",


STUDIES = {name: Study.from_config(name, entry) for name, entry in config["studies"].items()}

# Package sources each kind of output depends on (modules or subpackages of vibroimpact).
CODE = {
    "noise": source_digest("noise", "stats/spectra", "pipeline/io", "pipeline/tasks",
                           "_checks", "_files"),
    "simulate": source_digest("impact", "stats", "noise", "pipeline/cells", "pipeline/study",
                              "pipeline/datasets", "pipeline/io", "pipeline/tasks",
                              "_checks", "_files"),
    "aggregate": source_digest("pipeline/datasets", "pipeline/study", "pipeline/io",
                               "pipeline/tasks", "stats/spectra", "noise", "_files"),
    "orbits": source_digest("orbits", "pipeline/datasets", "pipeline/study",
                            "pipeline/io", "pipeline/tasks", "_checks", "_files"),
    "figure": source_digest("plotting", "pipeline/figures", "pipeline/tasks", "stats",
                            "_files"),
    # a report runs its notebook, which calls vibroimpact.reports (and plotting for Fig. 15
    # against Fig. 16); the notebooks themselves are inputs
    "report": source_digest("reports", "plotting", "stats"),
}

# Config keys each job reads from a study entry (nothing else of the entry reaches its params).
_PHYSICS = ("noise", "zeta", "eps", "amplitude", "inv_beta", "transient", "tile_size", "sweep")
_READS = {
    "events": _PHYSICS + ("delta", "t_end", "n_batches", "motion_window", "motions", "bins"),
    "map": _PHYSICS + ("delta", "n_batches", "motion_window", "motions", "map"),
    "spectra": _PHYSICS + ("spectra",),
    "trace": _PHYSICS + ("trace",),
}


def study_block(kind):
    """The part of ``studies[{study}]`` that a ``kind`` job reads."""
    def block(wildcards):
        entry = config["studies"][wildcards.study]
        return {key: entry[key] for key in _READS[kind] if key in entry}
    return block


def noise_entry(wildcards):
    return config["noises"][wildcards.noise]


def orbits_entry(wildcards):
    return config["orbits"][wildcards.orbits]


def study_noise(wildcards):
    return f"results/noise/{config['studies'][wildcards.study]['noise']}.nc"


def tiles(kind):
    def files(wildcards):
        n = STUDIES[wildcards.study].n_tiles(kind)
        return [f"results/cells/{wildcards.study}/{kind}/{t}.nc" for t in range(n)]
    return files


def orbit_tiles(wildcards):
    _, n = orbit_rows(config["orbits"][wildcards.orbits])
    return [f"results/orbits/{wildcards.orbits}/tiles/{t}.nc" for t in range(n)]


def _owner(wildcards):
    """``("orbits", name, entry)`` or ``("study", name, entry)`` of a figure's owner."""
    if wildcards.owner.startswith("orbits/"):
        name = wildcards.owner.split("/", 1)[1]
        return "orbits", name, config["orbits"][name]
    return "study", wildcards.owner, config["studies"][wildcards.owner]


# Where each dataset a figure can read lives ({name}: the owner; {noise}: its noise record).
_DATASETS = {
    "noise": "results/noise/{noise}.nc",
    "trace": "results/traces/{name}.nc",
    "spectra": "results/datasets/{name}_spectra.nc",
    "events": "results/datasets/{name}_events.nc",
    "map": "results/datasets/{name}_map.nc",
    "orbits": "results/orbits/{name}.nc",
}


def figure_inputs(wildcards):
    """The datasets figure ``{fig}`` of ``{owner}`` draws, from the table FIGURES."""
    kind, name, entry = _owner(wildcards)
    fig, _ = figures.figure_variant(wildcards.fig)
    if figures.FIGURES.get(fig, {}).get("owner") != kind:
        raise ValueError(f"{wildcards.owner}: no figure {fig!r} for a {kind} entry")
    names = dict(figures.figure_sources(entry, fig), name=name, noise=entry.get("noise"))
    return [_DATASETS[d].format(name=names.get(d, name), noise=names["noise"])
            for d in figures.FIGURES[fig]["reads"]]


def figure_options(wildcards):
    """The drawing options of ``{fig}`` from its owner's config entry."""
    _, _, entry = _owner(wildcards)
    return figures.figure_options(entry, wildcards.fig)


def figure_caption(wildcards):
    """What ``{fig}`` of ``{owner}`` shows, with its parameters (the report's caption)."""
    kind, name, entry = _owner(wildcards)
    return figures.caption(kind, name, entry, wildcards.fig)


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


def paper_figure_source(wildcards):
    if wildcards.paper_fig not in config.get("paper_figures", {}):
        raise ValueError(f"paper_figures: {wildcards.paper_fig} is not listed; listed: "
                         f"{sorted(config.get('paper_figures', {}))}")
    name = config["paper_figures"][wildcards.paper_fig]
    section = "orbits" if figures.FIGURES[wildcards.paper_fig]["owner"] == "orbits" else "studies"
    owner = f"orbits/{name}" if section == "orbits" else name
    target = figures.paper_target(config[section][name], wildcards.paper_fig)
    return {ext: f"results/figures/{owner}/{target}.{ext}" for ext in ("png", "pdf")}


def all_targets():
    """The figures of the entries the config builds (``PLAN.drawn``: with ``paper: false``,
    only the user's file's own entries)."""
    drawn = PLAN.drawn
    targets = [f"results/figures/{fig}.png" for fig in sorted(drawn["paper_figures"])]
    for name in sorted(drawn["studies"]):
        entry = config["studies"][name]
        targets += [f"results/figures/{name}/{f}.png" for f in figures.figure_targets(entry)]
    for name in sorted(drawn["orbits"]):
        entry = config["orbits"][name]
        targets += [f"results/figures/orbits/{name}/{f}.png" for f in figures.figure_targets(entry)]
    targets += sweep_targets()              # sweeps.smk: the side-by-side figure of each sweep
    if config["validation"]["build"]:
        targets += validation_targets()     # validation.smk: work_precision.png, stress.png
    return targets + report_targets()


# --- reports (reports.smk): one notebook per study, per orbits entry, two for validation -----

#: The interpreter running Snakemake (the .venv's): reports call its papermill and nbconvert.
PYTHON = shlex.quote(sys.executable)

#: The parameters of each notebook, in its `parameters` cell; each is passed with -p.
REPORT_PARAMETERS = {
    "random_force": ("study", "events", "spectra", "noise", "trace", "figures"),
    "harmonic_random": ("study", "events", "spectra", "noise", "trace", "map", "orbits",
                        "figures", "amplitude", "inv_beta", "density_delta"),
    "periodic_motions": ("name", "orbits", "map", "figures"),
    "performance": ("work_precision", "figures"),
    "stability": ("stress", "readme", "figures"),
}


def study_report_kind(entry):
    """The notebook of a study's report: random force alone, or harmonic plus random."""
    return "harmonic_random" if float(entry.get("amplitude", 0.0)) != 0.0 else "random_force"


def _study_datasets(name):
    """``{kind: path}`` of the datasets the figures of study ``name`` read."""
    entry = config["studies"][name]
    out = {}
    for fig in {f if isinstance(f, str) else f["name"] for f in entry["figures"]}:
        names = dict(figures.figure_sources(entry, fig), name=name, noise=entry.get("noise"))
        for kind in figures.FIGURES[fig]["reads"]:
            out.setdefault(kind, _DATASETS[kind].format(name=names.get(kind, name),
                                                        noise=names["noise"]))
    return out


def study_report_inputs(wildcards):
    """The notebook, the datasets and the figures of a study and of its ``report_with``, and
    the study's noise record (its provenance row, whether or not a figure draws it)."""
    entry = config["studies"][wildcards.study]
    kind = study_report_kind(entry)
    if wildcards.report != kind:
        raise ValueError(f"study {wildcards.study}: its report is {kind}, not {wildcards.report}")
    inputs = {"notebook": f"notebooks/{kind}.ipynb",
              "noise": _DATASETS["noise"].format(noise=entry["noise"])}
    shown = []
    for name in [wildcards.study, *entry.get("report_with", [])]:
        for dataset, path in _study_datasets(name).items():
            inputs.setdefault(dataset, path)
        shown += [f"results/figures/{name}/{f}.png"
                  for f in figures.figure_targets(config["studies"][name])]
    return {**inputs, "figures": shown}


def _maps_over(orbits_name):
    """Map datasets of the built studies that draw Fig. 15 over orbits entry ``orbits_name``."""
    for name in sorted(PLAN.drawn["studies"]):
        entry = config["studies"][name]
        for item in entry["figures"]:
            if isinstance(item, dict) and item.get("orbits") == orbits_name:
                return [_DATASETS["map"].format(name=name)]
    return []


def orbits_report_inputs(wildcards):
    entry = config["orbits"][wildcards.orbits]
    inputs = {"notebook": "notebooks/periodic_motions.ipynb",
              "orbits": _DATASETS["orbits"].format(name=wildcards.orbits),
              "figures": [f"results/figures/orbits/{wildcards.orbits}/{f}.png"
                          for f in figures.figure_targets(entry)]}
    inputs.update({"map": path for path in _maps_over(wildcards.orbits)})
    return inputs


def validation_report_inputs(wildcards):
    if wildcards.vreport == "performance":
        return {"notebook": "notebooks/performance.ipynb",
                "work_precision": "results/validation/work_precision.nc",
                "figures": ["results/figures/work_precision.png"]}
    return {"notebook": "notebooks/stability.ipynb",
            "stress": "results/validation/stress_sample.nc",
            "figures": ["results/figures/stress.png"]}


def quoted_campaign(wildcards):
    """The README's table of the full stress campaign, which the stability report quotes: a
    param, so that editing that table reruns the report and editing the rest of the README
    does not (the README is passed by path, not as an input)."""
    if wildcards.get("vreport") != "stability":
        return ""
    try:
        table = markdown_table(Path(workflow.basedir, "README.md"), "| family |")
    except ValueError:
        return ""       # no table to quote: the report says so when it runs
    return hashlib.sha256(table.to_csv().encode()).hexdigest()[:16]


def _report_name(wildcards):
    if "vreport" in wildcards.keys():
        return wildcards.vreport
    return wildcards.report if "report" in wildcards.keys() else "periodic_motions"


def _nearest(values, target):
    return min(values, key=lambda v: abs(v - target))


def report_arguments(wildcards, input):
    """``-p name value`` for every parameter of the report's notebook: input paths (``""``
    when the study has no such dataset), the figures as one space-separated string, and the
    study's name, forcing amplitude, the 1/beta_f its density findings read and the plays its
    density figures draw (space-separated; "" = every play)."""
    notebook = _report_name(wildcards)
    given = {name: " ".join(value) if name == "figures" else str(value)
             for name, value in input.items()}
    if "study" in wildcards.keys():
        entry = config["studies"][wildcards.study]
        grid = [float(v) for v in STUDIES[wildcards.study].inv_beta]
        given.update(study=wildcards.study, amplitude=float(entry.get("amplitude", 0.0)),
                     inv_beta=_nearest(grid, 1.1),      # Figs. 13, 14 of the paper: tau/1.1
                     density_delta=" ".join(str(float(d))
                                            for d in entry.get("density_delta") or ()))
    if "orbits" in wildcards.keys():
        given["name"] = wildcards.orbits
    given.setdefault("readme", "README.md")     # the stability report quotes its table
    values = {name: given.get(name, "") for name in REPORT_PARAMETERS[notebook]}
    return " ".join(f"-p {name} {shlex.quote(str(value))}" for name, value in values.items())


def report_targets():
    """The HTML report of every built study and orbits entry, and the validation reports."""
    drawn = PLAN.drawn
    targets = [f"results/reports/{name}/{study_report_kind(config['studies'][name])}.html"
               for name in sorted(drawn["studies"])]
    targets += [f"results/reports/orbits/{name}/periodic_motions.html"
                for name in sorted(drawn["orbits"])]
    if config["validation"]["build"]:
        targets += [f"results/reports/validation/{r}.html" for r in ("performance", "stability")]
    return targets


# Resources: the cost model of vibroimpact.pipeline.config.costs (README, "Job costs"), the one
# the plan uses too.
from vibroimpact.pipeline.config import costs

BASE_MEM_MB = costs.BASE_MEM_MB
NOISE_MEM_MB = costs.NOISE_MEM_MB


def _study_noise_entry(study):
    return config["noises"][config["studies"][study]["noise"]]


def simulate_mem_mb(wildcards):
    return costs.simulate_mem_mb(int(_study_noise_entry(wildcards.study)["n_samples"]))


def simulate_runtime(kind):
    """Minutes of a ``kind`` tile: its cells at the steps of one cell (a map cell: to the cap
    of the longest forcing period), plus start-up."""
    def runtime(wildcards):
        if kind == "trace":
            return costs.simulate_runtime_min(0, 0)
        entry = config["studies"][wildcards.study]
        steps = costs.study_steps(kind, entry, _study_noise_entry(wildcards.study))
        grid = "events" if kind == "map" else kind
        cells = len(STUDIES[wildcards.study].tile(int(wildcards.tile), grid))
        return costs.simulate_runtime_min(cells, steps)
    return runtime
