# Named helpers: studies, target lists, tile lists, provenance. No numerics here.
import subprocess

from vibroimpact.pipeline.io import config_digest, provenance
from vibroimpact.pipeline.study import Study
from vibroimpact.pipeline.tasks import orbit_rows


wildcard_constraints:
    study="[A-Za-z][A-Za-z0-9_]*",
    noise="[A-Za-z][A-Za-z0-9_]*",
    tile="[0-9]+",
    fig="fig[0-9][0-9]",


def _check_references():
    """Cross-references the JSON Schema cannot express, checked before any job."""
    for name, entry in config["studies"].items():
        if entry["noise"] not in config["noises"]:
            raise ValueError(f"studies.{name}.noise: unknown noise {entry['noise']!r}; "
                             f"allowed: {sorted(config['noises'])}")
    owners = {**config["studies"], **config["orbits"]}
    for fig, name in config.get("paper_figures", {}).items():
        if name not in owners:
            raise ValueError(f"paper_figures.{fig}: unknown study or orbits entry {name!r}; "
                             f"allowed: {sorted(owners)}")
        if fig not in owners[name]["figures"]:
            raise ValueError(f"paper_figures.{fig}: {name!r} does not list {fig} in its figures")


_check_references()
STUDIES = {name: Study.from_config(name, entry) for name, entry in config["studies"].items()}


def _git_commit():
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=workflow.basedir,
                             capture_output=True, text=True, timeout=10)
        return out.stdout.strip() or "unknown"
    except OSError:
        return "unknown"


GIT_COMMIT = _git_commit()


def noise_entry(wildcards):
    return config["noises"][wildcards.noise]


def noise_provenance(wildcards):
    entry = config["noises"][wildcards.noise]
    return provenance(config_digest(entry), GIT_COMMIT, entry["seed"])


def study_entry(wildcards):
    return config["studies"][wildcards.study]


def study_provenance(wildcards):
    entry = config["studies"][wildcards.study]
    return provenance(config_digest([entry, config["noises"][entry["noise"]]]), GIT_COMMIT)


def study_noise(wildcards):
    return f"results/noise/{config['studies'][wildcards.study]['noise']}.nc"


def tiles(kind):
    def files(wildcards):
        n = STUDIES[wildcards.study].n_tiles(kind)
        return [f"results/cells/{wildcards.study}/{kind}/{t}.nc" for t in range(n)]
    return files


def paper_figure_sources(wildcards):
    study = config["paper_figures"][wildcards.fig]
    return {ext: f"results/figures/{study}/{wildcards.fig}.{ext}" for ext in ("png", "pdf")}


def orbits_entry(wildcards):
    return config["orbits"][wildcards.study]


def orbits_provenance(wildcards):
    return provenance(config_digest(config["orbits"][wildcards.study]), GIT_COMMIT)


def orbit_tiles(wildcards):
    _, n = orbit_rows(config["orbits"][wildcards.study])
    return [f"results/orbits/{wildcards.study}/tiles/{t}.nc" for t in range(n)]


def all_targets():
    targets = [f"results/figures/{fig}.png" for fig in config.get("paper_figures", {})]
    for name, entry in {**config["studies"], **config["orbits"]}.items():
        targets += [f"results/figures/{name}/{fig}.png" for fig in entry["figures"]]
    return targets
