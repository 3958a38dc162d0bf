"""A report's "Run" section: what computed its numbers, on what, and at what cost.

- :func:`versions`: the tool's version and commit and the versions that can change a number
  (`vibroimpact._release.SOFTWARE`, Python, the CPU), as each dataset recorded them when its
  job wrote it (attribute ``software``), beside the environment executing the report: a
  dataset built by another environment shows in its own column.
- :func:`job_costs`: the CPU time, wall time and peak memory of the jobs behind the report's
  datasets and figures, read from the benchmark files Snakemake writes beside them
  (``results/benchmarks/<rule>/<owner>[/<part>].tsv``).
"""
import json
from pathlib import Path

__all__ = ["versions", "job_costs", "owner_jobs"]

#: Rows of :func:`versions` before the software's: the tool itself.
_TOOL = ("package_version", "git_commit", "git_dirty")
#: The report's own job is still running while the report is executed: it has no benchmark
#: yet, and an older one would describe an earlier run.
_SKIPPED_RULES = ("report",)
#: The rules of an owner written ``<kind>/<name>`` (:func:`owner_jobs`): an orbits entry's
#: (its figures too, ``draw_figure/orbits/<name>/``), a noise record's, and a map study's map
#: alone (its tiles and their aggregation, not the study's other jobs). A study, an orbits
#: entry and a noise record may share a name: the kind says whose jobs are meant.
KINDS = {
    "orbits": ("solve_orbit_tile", "solve_clearance_orbit_tile", "aggregate_orbits",
               "trace_boundaries", "solve_attractor_tile", "aggregate_attractors"),
    "noise": ("generate_noise",),
    "map": ("simulate_map", "aggregate_map"),
}


def versions(**datasets):
    """A pandas DataFrame: one row per tool attribute and software name, one column per
    distinct record among ``datasets`` (named after the datasets that share it), and the
    column ``this report`` (the environment executing it)."""
    import pandas as pd

    from vibroimpact._release import software, version

    here = {"package_version": version(), "git_commit": "-", "git_dirty": "-",
            **software()}
    records = {}            # record (as a tuple) -> the dataset names that carry it
    for name, ds in datasets.items():
        if ds is None:
            continue
        recorded = {k: str(ds.attrs.get(k, "")) for k in _TOOL}
        try:
            recorded.update(json.loads(ds.attrs.get("software", "{}")))
        except (TypeError, ValueError):
            pass
        records.setdefault(tuple(sorted(recorded.items())), []).append(name)
    rows = list(_TOOL) + list(software())
    columns = {", ".join(names): [dict(record).get(r, "not recorded") for r in rows]
               for record, names in records.items()}
    columns["this report"] = [str(here.get(r, "")) for r in rows]
    return pd.DataFrame(columns, index=rows)


def owner_jobs(owners, benchmarks):
    """The benchmark files of the jobs of ``owners`` under the folder ``benchmarks``, the
    report rules left out, sorted by rule and job. An owner is

    - ``orbits/<name>``, ``noise/<name>`` or ``map/<study>``: the jobs of that kind's rules
      (`KINDS`) for that entry, ``<rule>/<name>.tsv`` and ``<rule>/<name>/*.tsv``, and an
      orbits entry's figures;
    - ``<study>``: every other rule's jobs of that name, its figures among them;
    - a rule of one job (``measure_work_precision``), or a figure of one
      (``draw_validation_figure/<name>.tsv``), by its name.
    """
    root = Path(benchmarks)
    others = {rule for kind in ("orbits", "noise") for rule in KINDS[kind]}
    found = set()
    for owner in filter(None, owners):
        kind, _, name = owner.partition("/")
        if kind in KINDS and name:
            for rule in KINDS[kind]:
                found.update(root.glob(f"{rule}/{name}.tsv"))
                found.update(root.glob(f"{rule}/{name}/*.tsv"))
            if kind == "orbits":
                found.update(root.glob(f"draw_figure/orbits/{name}/*.tsv"))
            continue
        found.update(root.glob(f"{owner}.tsv"))            # a rule of one job
        found.update(p for p in [*root.glob(f"*/{owner}.tsv"), *root.glob(f"*/{owner}/*.tsv")]
                     if p.relative_to(root).parts[0] not in others)
    return sorted(p for p in found if p.relative_to(root).parts[0] not in _SKIPPED_RULES)


def job_costs(owners, benchmarks):
    """A pandas DataFrame of the jobs behind ``owners`` (:func:`owner_jobs`): ``rule``,
    ``job`` (its owner and part), ``CPU s``, ``wall s`` and ``peak memory MB`` (the maximum
    resident set size), as Snakemake's benchmark measured them; empty when the build wrote
    none (a build without benchmarks, or datasets copied from elsewhere)."""
    import pandas as pd

    root = Path(benchmarks)
    rows = []
    for path in owner_jobs(owners, root):
        try:
            bench = pd.read_csv(path, sep="\t")
        except (OSError, ValueError):
            continue
        if bench.empty:
            continue
        last = pd.to_numeric(bench.iloc[-1], errors="coerce")  # Snakemake writes "-" or NA
        rel = path.relative_to(root).with_suffix("")     # <rule>[/<owner>[/<part>]]
        rows.append({"rule": rel.parts[0], "job": "/".join(rel.parts[1:]),
                     "CPU s": float(last["cpu_time"]), "wall s": float(last["s"]),
                     "peak memory MB": float(last["max_rss"])})
    return pd.DataFrame(rows, columns=["rule", "job", "CPU s", "wall s", "peak memory MB"])
