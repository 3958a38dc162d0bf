"""The files a build makes: the targets of ``rule all`` and the inputs of each rule above the
simulations, in plain functions of the config.

One place for both readers: the workflow's input functions (``workflow/rules/common.smk``)
call these, and the plan (`vibroimpact.pipeline.config.plan`) walks :func:`needed_files`, the
closure of ``rule all``'s targets through the same functions, so it counts the jobs a dry run
schedules (a study drawn only in another's report, ``report_with``, included), not a second
estimate of them. ``drawn`` is :attr:`~vibroimpact.pipeline.config.Plan.drawn`: ``{section:
names}`` of the entries whose figures ``rule all`` draws. Paths are relative to the project
directory, but for the workflow's own files among the report rules' inputs
(:data:`WORKFLOW_INPUTS`), relative to its folder; no Snakemake, no numerics.
"""
import functools
import re

from vibroimpact.pipeline import figures
from vibroimpact.pipeline.config.sweeps import drawn_sweeps
from vibroimpact.reports.arguments import study_report_kind

__all__ = ["PRODUCTS", "TWINS", "product", "product_of", "DATASETS", "WORKFLOW_INPUTS",
           "VALIDATION_FIGURES", "figure_names", "figure_inputs",
           "paper_figure_source", "study_datasets", "attractor_datasets",
           "predictors_inputs", "map_orbits_inputs",
           "study_report_inputs", "maps_over", "orbits_report_inputs",
           "validation_report_inputs", "sweep_inputs", "sweep_targets", "validation_targets",
           "report_targets", "all_targets", "needed_files", "rule_inputs"]

#: Every kind of product a build makes and where it lives: the one table the rules' outputs
#: (workflow/rules/*.smk), the plan's files (`needed_files`), `make stale`
#: (`vibroimpact.pipeline.stale`) and the reports' inputs are formatted from. ``{name}``: the
#: owner (a study, an orbits entry, a sweep, a validation dataset); ``{owner}``: a study's
#: name or ``orbits/<name>`` (their figures and reports); ``{noise}``: a noise record;
#: ``{figure}``, ``{report}``: a figure target (``fig13-1``) or a report's notebook. A new kind
#: is one row here (and the rule that makes it).
PRODUCTS = {
    "noise": "results/noise/{noise}.nc",
    "trace": "results/traces/{name}.nc",
    "spectra": "results/datasets/{name}_spectra.nc",
    "events": "results/datasets/{name}_events.nc",
    "map": "results/datasets/{name}_map.nc",
    "escape": "results/datasets/{name}_escape.nc",
    # the rank correlations of the predictors with a map's P (the reports that show the map)
    "predictors": "results/datasets/{name}_predictors.nc",
    # the orbits of the fig15_vs_fig16 entry solved at the map's own cells (finding 8)
    "map_orbits": "results/datasets/{name}_map_orbits.nc",
    "orbits": "results/orbits/{name}.nc",
    "boundaries": "results/orbits/{name}_boundaries.nc",
    "basins": "results/orbits/{name}_basins.nc",
    "lyapunov": "results/orbits/{name}_lyapunov.nc",
    # a plane study's (attractors block): the harmonic force alone over its plane
    "plane_basins": "results/datasets/{name}_basins.nc",
    "plane_lyapunov": "results/datasets/{name}_lyapunov.nc",
    # the validation targets' datasets (work-precision run, stress sample)
    "validation": "results/validation/{name}.nc",
    "figure": "results/figures/{owner}/{figure}.png",
    # a paper figure's copy, and a validation figure: at the top of results/figures/
    "top_figure": "results/figures/{figure}.png",
    "sweep_figure": "results/figures/{name}/sweep.png",
    "report": "results/reports/{owner}/{report}.html",
}

#: The kinds of `PRODUCTS` that are datasets a figure can read.
DATASETS = {kind: pattern for kind, pattern in PRODUCTS.items()
            if kind not in ("validation", "figure", "top_figure", "sweep_figure", "report")}


#: Files made beside a product, current when it is: ``{twin's suffix: product's suffix}`` (a
#: figure's PDF beside its PNG, a report's notebook and its rendering without images beside
#: its HTML).
TWINS = {".pdf": ".png", ".ipynb": ".html", ".summary.html": ".html"}


def product(kind, *, twin=None, **fields):
    """The path of a product of ``kind`` (`PRODUCTS`) with its fields filled, or of its
    ``twin`` (a suffix of `TWINS`: ``".pdf"`` beside a figure); a rule passes its wildcards
    (``product("events", name="{study}")``) to get its output's pattern."""
    path = PRODUCTS[kind].format(**fields)
    return path if twin is None else path[:-len(TWINS[twin])] + twin


@functools.cache
def _matchers():
    """``[(kind, regex)]`` of `PRODUCTS`, the most specific pattern (most fixed characters)
    first: ``{name}.nc`` also matches ``{name}_boundaries.nc``, ``{owner}/{figure}.png`` also
    ``{name}/sweep.png``. A field is one path segment but ``{owner}`` (``orbits/<name>``)."""
    def regex(pattern):
        parts = re.split(r"\{(\w+)\}", pattern)
        return re.compile("".join(
            re.escape(p) if i % 2 == 0 else
            f"(?P<{p}>(?:orbits/)?[^/]+)" if p == "owner" else f"(?P<{p}>[^/]+)"
            for i, p in enumerate(parts)) + r"\Z")

    fixed = lambda kind: len(re.sub(r"\{\w+\}", "", PRODUCTS[kind]))
    return [(kind, regex(PRODUCTS[kind])) for kind in sorted(PRODUCTS, key=fixed, reverse=True)]


def product_of(path):
    """``(kind, fields)`` of a product's ``path`` (`PRODUCTS` read backwards), or
    ``(None, {})`` for a path of no kind (a tile, a log)."""
    for kind, regex in _matchers():
        match = regex.match(path)
        if match:
            return kind, match.groupdict()
    return None, {}

#: The inputs of the report rules that are the workflow's own files, not results: their paths
#: are relative to the workflow's folder (``workflow/`` of a checkout), which the rules prefix.
WORKFLOW_INPUTS = ("notebook", "campaign")

#: Each validation figure and the dataset it draws.
VALIDATION_FIGURES = {
    "work_precision": product("validation", name="work_precision"),
    "stress": product("validation", name="stress_sample"),
}


def figure_names(entry):
    """The names of the figures an entry lists (a figure given with options: its name)."""
    return [f if isinstance(f, str) else f["name"] for f in entry.get("figures", [])]


def _owner(config, owner):
    """``(kind, name, entry)`` of ``owner``: a study name, or ``orbits/<name>``."""
    if owner.startswith("orbits/"):
        name = owner.split("/", 1)[1]
        return "orbits", name, config["orbits"][name]
    return "study", owner, config["studies"][owner]


def figure_inputs(config, owner, fig):
    """The datasets figure ``fig`` (``figNN``, ``figNN-k``) of ``owner`` draws, from the
    table `~vibroimpact.pipeline.figures.FIGURES`."""
    kind, name, entry = _owner(config, owner)
    base, _ = figures.figure_variant(fig)
    spec = figures.figure_spec(base, kind) if base in figures.FIGURES else None
    if spec is None:
        raise ValueError(f"{owner}: no figure {base!r} for a {kind} entry")
    names = dict(figures.figure_sources(entry, base), name=name, noise=entry.get("noise"))
    return [DATASETS[d].format(name=names.get(d, name), noise=names["noise"])
            for d in spec["reads"]]


def paper_figure_source(config, paper_fig):
    """``{"png", "pdf"}`` of the figure that ``paper_figures[paper_fig]`` names."""
    if paper_fig not in config.get("paper_figures", {}):
        raise ValueError(f"paper_figures: {paper_fig} is not listed; listed: "
                         f"{sorted(config.get('paper_figures', {}))}")
    name = config["paper_figures"][paper_fig]
    section = "orbits" if figures.FIGURES[paper_fig]["owner"] == "orbits" else "studies"
    owner = f"orbits/{name}" if section == "orbits" else name
    target = figures.paper_target(config[section][name], paper_fig)
    png = product("figure", owner=owner, figure=target)
    return {"png": png, "pdf": png[:-len(".png")] + ".pdf"}


def study_datasets(config, name):
    """``{kind: path}`` of the datasets the figures of study ``name`` read."""
    entry = config["studies"][name]
    out = {}
    for fig in sorted(set(figure_names(entry))):
        names = dict(figures.figure_sources(entry, fig), name=name, noise=entry.get("noise"))
        for kind in figures.figure_spec(fig, "study")["reads"]:
            out.setdefault(kind, DATASETS[kind].format(name=names.get(kind, name),
                                                       noise=names["noise"]))
    return out


def attractor_datasets(config, name):
    """``{basins, lyapunov: path}`` of the orbits entry study ``name`` draws Fig. 15 over
    (``fig15_vs_fig16``), when that entry has an ``attractors`` block: the harmonic report's
    noise-free predictors of the probabilities; {} otherwise."""
    entry = config["studies"][name]
    if "fig15_vs_fig16" not in figure_names(entry):
        return {}
    orbits = figures.figure_sources(entry, "fig15_vs_fig16")["orbits"]
    if not config["orbits"][orbits].get("attractors"):
        return {}
    return {kind: DATASETS[kind].format(name=orbits) for kind in ("basins", "lyapunov")}


def map_orbits_inputs(config, name):
    """``{map, orbits: path}`` of rule ``solve_map_orbits``: study ``name``'s map and the
    orbit map of the entry its ``fig15_vs_fig16`` names, whose orbits it solves at the map's
    own cells."""
    entry = config["studies"][name]
    orbits = figures.figure_sources(entry, "fig15_vs_fig16")["orbits"]
    return {"map": DATASETS["map"].format(name=name),
            "orbits": DATASETS["orbits"].format(name=orbits)}


def predictors_inputs(config, name):
    """``{map, orbits, basins, lyapunov: path}`` the predictors of study ``name``'s map are
    computed from (rule ``map_predictors``): its map and, when it draws Fig. 15 over an
    orbits entry (``fig15_vs_fig16``), that entry's orbits solved at the map's own cells
    (``map_orbits``, rule ``solve_map_orbits``); the basins and Lyapunov exponents of the
    study's own ``attractors`` block (simulated over its map's cells), else the orbits
    entry's (:func:`attractor_datasets`); the datasets it has not are left out."""
    entry = config["studies"][name]
    inputs = {"map": DATASETS["map"].format(name=name)}
    if "fig15_vs_fig16" in figure_names(entry):
        inputs["orbits"] = DATASETS["map_orbits"].format(name=name)
    if entry.get("attractors"):
        return {**inputs, **{kind: DATASETS[f"plane_{kind}"].format(name=name)
                             for kind in ("basins", "lyapunov")}}
    return {**inputs, **attractor_datasets(config, name)}


def _predictors_of(map_path):
    """The predictors dataset of the study whose map is ``map_path``."""
    return product("predictors", name=product_of(map_path)[1]["name"])


def study_report_inputs(config, study, report=None):
    """The notebook, the datasets and the figures of study ``study`` and of its
    ``report_with``, and its noise record (its provenance row, whether or not a figure draws
    it); with a map over an orbits entry that has attractors, their basins and Lyapunov
    datasets. ``report``: the notebook asked for, checked against the study's."""
    entry = config["studies"][study]
    kind = study_report_kind(entry)
    if report is not None and report != kind:
        raise ValueError(f"study {study}: its report is {kind}, not {report}")
    inputs = {"notebook": f"notebooks/{kind}.ipynb",
              "noise": DATASETS["noise"].format(noise=entry["noise"])}
    shown = []
    for name in [study, *entry.get("report_with", [])]:
        for dataset, path in {**study_datasets(config, name),
                              **attractor_datasets(config, name)}.items():
            inputs.setdefault(dataset, path)
        shown += [product("figure", owner=name, figure=f)
                  for f in figures.figure_targets(config["studies"][name])]
    # the predictors of the map's P, computed once for every report that shows the map (the
    # harmonic report reads them; the random-force report has no such table)
    if "map" in inputs and kind == "harmonic_random":
        inputs["predictors"] = _predictors_of(inputs["map"])
    return {**inputs, "figures": shown}


def maps_over(config, drawn, orbits_name):
    """Map datasets of the drawn studies that draw Fig. 15 over orbits entry ``orbits_name``
    (the first, by name)."""
    for name in sorted(drawn["studies"]):
        for item in config["studies"][name]["figures"]:
            if isinstance(item, dict) and item.get("orbits") == orbits_name:
                return [DATASETS["map"].format(name=name)]
    return []


def orbits_report_inputs(config, drawn, name):
    """The notebook, the dataset and the figures of orbits entry ``name``, and the map drawn
    over it (Fig. 15 against Fig. 16), if a drawn study draws one."""
    entry = config["orbits"][name]
    inputs = {"notebook": "notebooks/periodic_motions.ipynb",
              "orbits": DATASETS["orbits"].format(name=name),
              "figures": [product("figure", owner=f"orbits/{name}", figure=f)
                          for f in figures.figure_targets(entry)]}
    for path in maps_over(config, drawn, name):
        inputs["map"] = path
        inputs["predictors"] = _predictors_of(path)
        inputs["map_orbits"] = _predictors_of(path).replace("_predictors.nc", "_map_orbits.nc")
    if "fig16" in figures.figure_targets(entry):
        inputs["boundaries"] = DATASETS["boundaries"].format(name=name)
    if entry.get("attractors"):
        inputs.update({kind: DATASETS[kind].format(name=name) for kind in ("basins", "lyapunov")})
    return inputs


def validation_report_inputs(vreport):
    """The notebook, the dataset and the figure of validation report ``vreport``; the
    stability report also quotes the full stress campaign
    (workflow/notebooks/stress_campaign.csv)."""
    if vreport == "performance":
        return {"notebook": "notebooks/performance.ipynb",
                "work_precision": VALIDATION_FIGURES["work_precision"],
                "figures": [product("top_figure", figure="work_precision")]}
    return {"notebook": "notebooks/stability.ipynb",
            "stress": VALIDATION_FIGURES["stress"],
            "campaign": "notebooks/stress_campaign.csv",
            "figures": [product("top_figure", figure="stress")]}


def sweep_inputs(config, sweep):
    """The events datasets of the studies of sweep ``sweep``, in its order; of a sweep over
    a plane's third parameter (its studies have a ``plane``), their map datasets (a stack
    of maps, drawn side by side)."""
    if sweep not in config.get("sweeps", {}):
        raise ValueError(f"{sweep} is not a sweep; sweeps: "
                         f"{sorted(config.get('sweeps', {})) or 'none'}")
    studies = config["sweeps"][sweep]["studies"]
    kind = "map" if config["studies"][studies[0]].get("plane") is not None else "events"
    return [DATASETS[kind].format(name=study) for study in studies]


def sweep_targets(config, drawn):
    """The side-by-side figure of every sweep whose studies are all drawn."""
    return [product("sweep_figure", name=name) for name in drawn_sweeps(config, drawn)]


def validation_targets():
    """``results/figures/work_precision.png`` and ``stress.png``."""
    return [product("top_figure", figure=name) for name in VALIDATION_FIGURES]


def report_targets(config, drawn):
    """The HTML report of every drawn study and orbits entry, and the validation reports."""
    targets = [product("report", owner=name, report=study_report_kind(config["studies"][name]))
               for name in sorted(drawn["studies"])]
    targets += [product("report", owner=f"orbits/{name}", report="periodic_motions")
                for name in sorted(drawn["orbits"])]
    if config["validation"]["build"]:
        targets += [product("report", owner="validation", report=r)
                    for r in ("performance", "stability")]
    return targets


def all_targets(config, drawn):
    """The figures and reports of ``rule all``: of the drawn entries (with ``paper: false``,
    only the user's file's own), the paper figures' copies, the sweeps' figures and the
    validation targets when ``validation.build``."""
    targets = [product("top_figure", figure=fig) for fig in sorted(drawn["paper_figures"])]
    for name in sorted(drawn["studies"]):
        entry = config["studies"][name]
        targets += [product("figure", owner=name, figure=f) for f in figures.figure_targets(entry)]
    for name in sorted(drawn["orbits"]):
        entry = config["orbits"][name]
        targets += [product("figure", owner=f"orbits/{name}", figure=f)
                    for f in figures.figure_targets(entry)]
    targets += sweep_targets(config, drawn)
    if config["validation"]["build"]:
        targets += validation_targets()
    return targets + report_targets(config, drawn)


def _flat(inputs):
    out = []
    for value in inputs.values():
        out += value if isinstance(value, list) else [value]
    return [p for p in out if p.startswith("results/")]


def rule_inputs(config, drawn, path):
    """The files under results/ that the rule making ``path`` reads, for the rules above the
    datasets (figures, copies, sweeps, reports) and the boundary curves; [] for a dataset
    made from tiles or a record (the plan costs those per entry)."""
    kind, fields = product_of(path)
    if kind == "top_figure":            # a validation figure, or a paper figure's copy
        fig = fields["figure"]
        if fig in VALIDATION_FIGURES:
            return [VALIDATION_FIGURES[fig]]
        return [paper_figure_source(config, fig)["png"]]
    if kind == "sweep_figure":
        return sweep_inputs(config, fields["name"])
    if kind == "figure":
        return figure_inputs(config, fields["owner"], fields["figure"])
    if kind == "report":
        owner = fields["owner"]
        if owner == "validation":
            return _flat(validation_report_inputs(fields["report"]))
        if owner.startswith("orbits/"):
            return _flat(orbits_report_inputs(config, drawn, owner[len("orbits/"):]))
        return _flat(study_report_inputs(config, owner, fields["report"]))
    if kind == "predictors":
        return _flat(predictors_inputs(config, fields["name"]))
    if kind == "boundaries":
        return [product("orbits", name=fields["name"])]
    return []


def needed_files(config, drawn):
    """Every file under results/ that ``rule all`` needs, whether or not already built: its
    targets and, through :func:`rule_inputs`, the figures and datasets they read (a
    ``report_with`` study's figures and datasets too), down to the datasets."""
    needed, todo = set(), list(all_targets(config, drawn))
    while todo:
        path = todo.pop()
        if path not in needed:
            needed.add(path)
            todo += rule_inputs(config, drawn, path)
    return needed
