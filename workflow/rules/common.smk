# Named helpers: config blocks, code digests, tile lists, the figure table. No numerics here.
#
# Rebuild scope (README, "What reruns"): each rule's params carry only the config block it
# reads and a digest of the package sources its output depends on, so Snakemake's params
# trigger reruns exactly the jobs an edit touches, committed or not. Provenance (version,
# commit, dirty flag, config digest, seed) is written by the jobs at run time, never passed
# through params (a commit alone must not rerun anything).
from vibroimpact.pipeline import figures
from vibroimpact.pipeline.provenance import source_digest
from vibroimpact.pipeline.study import Study, orbit_rows


wildcard_constraints:
    study="[A-Za-z][A-Za-z0-9_]*",
    orbits="[A-Za-z][A-Za-z0-9_]*",
    noise="[A-Za-z][A-Za-z0-9_]*",
    tile="[0-9]+",
    # a study name, or orbits/<name> for an `orbits` entry (their figures never collide)
    owner="(orbits/)?[A-Za-z][A-Za-z0-9_]*",
    # figNN, our own names (fig15_vs_fig16, work_precision), -k: k-th value of a listed parameter
    fig="[a-z][a-z0-9_]*(-[0-9]+)?",
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
}

# Config keys each job reads from a study entry (nothing else of the entry reaches its params).
_PHYSICS = ("noise", "zeta", "eps", "amplitude", "inv_beta", "transient", "tile_size")
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
    return targets


# Resources, from measured needs (README, "Job costs"): a job's resident memory is ~550 MB of
# interpreter, numba and scipy, plus the noise record held in memory (8 bytes a sample) and
# the simulator's chunk buffers (~100 MB at the default chunk of 2**20 samples).
BASE_MEM_MB = 600


def _noise_samples(name):
    return int(config["noises"][name]["n_samples"])


# chunked generation: one chunk (8 MB) plus the 2**22-sample head kept for the estimates
NOISE_MEM_MB = BASE_MEM_MB + 200


def simulate_mem_mb(wildcards):
    n = _noise_samples(config["studies"][wildcards.study]["noise"])
    return BASE_MEM_MB + 150 + -(-8 * n // 2**20)


def simulate_runtime(kind):
    """Minutes: cells of a tile x steps x ~60 ns a step (the measured cost with many impacts
    is ~20 ns a step on one core; x3 for a slower or shared node), plus start-up."""
    def runtime(wildcards):
        study = STUDIES[wildcards.study]
        entry = config["studies"][wildcards.study]
        noise = config["noises"][entry["noise"]]
        steps = _noise_samples(entry["noise"])
        if kind == "spectra" and entry["spectra"].get("t_end"):
            steps = min(steps, entry["spectra"]["t_end"] / noise["dt"])
        if kind == "map":   # a cell runs at most to its cap, the longest forcing period's
            steps = min(steps, (entry["transient"] + entry["map"]["max_periods"] * 2 * 3.141592653589793
                                * float(study.inv_beta.max())) / noise["dt"])
        grid = "events" if kind == "map" else kind
        cells = len(study.tile(int(wildcards.tile), grid)) if kind != "trace" else 0
        return 5 + int(cells * steps * 60e-9 / 60)
    return runtime
