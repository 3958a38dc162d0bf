"""A report's "Run" section: what computed its numbers, on what, and at what cost.

- :func:`versions`: the tool's version and commit and the versions that can change a number
  (`vibroimpact._release.SOFTWARE`, Python, the CPU), as each dataset recorded them when its
  job wrote it (attribute ``software``), beside the environment executing the report: a
  dataset built by another environment shows in its own column.
- :func:`job_costs`: the CPU time, wall time and peak memory of the jobs behind the report's
  datasets and figures, read from the benchmark files Snakemake writes beside them
  (``results/benchmarks/<rule>/<owner>[/<part>].tsv``).
- :func:`rule_costs`: the same, summed by rule over every job of a build (:func:`build_owners`),
  beside the plan's estimate: the table of Snakemake's report (``results/reports/job_costs.html``,
  rule ``job_costs``).
"""
import json
from pathlib import Path

__all__ = ["versions", "job_costs", "owner_jobs", "build_owners", "rule_costs"]

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


def owner_jobs(owners, benchmarks, skip=_SKIPPED_RULES):
    """The benchmark files of the jobs of ``owners`` under the folder ``benchmarks``, the
    rules ``skip`` left out (a report's own: the report rules), sorted by rule and job. An
    owner is

    - ``orbits/<name>``, ``noise/<name>`` or ``map/<study>``: the jobs of that kind's rules
      (`KINDS`) for that entry, ``<rule>/<name>.tsv`` and ``<rule>/<name>/*.tsv``, and an
      orbits entry's figures and report;
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
                found.update(root.glob(f"report/orbits/{name}.tsv"))
            continue
        found.update(root.glob(f"{owner}.tsv"))            # a rule of one job
        found.update(p for p in [*root.glob(f"*/{owner}.tsv"), *root.glob(f"*/{owner}/*.tsv")]
                     if p.relative_to(root).parts[0] not in others)
    return sorted(p for p in found if p.relative_to(root).parts[0] not in skip)


def job_costs(owners, benchmarks, skip=_SKIPPED_RULES):
    """A pandas DataFrame of the jobs behind ``owners`` (:func:`owner_jobs`): ``rule``,
    ``job`` (its owner and part), ``CPU s``, ``wall s`` and ``peak memory MB`` (the maximum
    resident set size), as Snakemake's benchmark measured them; empty when the build wrote
    none (a build without benchmarks, or datasets copied from elsewhere)."""
    import pandas as pd

    root = Path(benchmarks)
    rows = []
    for path in owner_jobs(owners, root, skip):
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


#: The rules of the validation build (``validation.build``), each of one job, its figures'
#: and reports' names: the owners of :func:`build_owners`.
_VALIDATION_OWNERS = ("measure_work_precision", "sample_stress_families", "stress",
                      "work_precision", "validation")


def build_owners(build):
    """The owners (:func:`owner_jobs`) of every job of a build: ``build`` as
    `vibroimpact.pipeline.config.plan.built_entries` returns it (its second item): the
    studies, ``orbits/<name>``, ``noise/<name>``, the sweeps and, when the build has them,
    the validation jobs."""
    return sorted([*build["studies"], *(f"orbits/{n}" for n in build["orbits"]),
                   *(f"noise/{n}" for n in build["noises"]), *build["sweeps"],
                   *(_VALIDATION_OWNERS if build["validation"] else ())])


def rule_costs(owners, benchmarks, planned=None):
    """A pandas DataFrame, one row per kind of job (its benchmark files' folder, as
    `vibroimpact.pipeline.config.plan.Plan.rule_costs` names it: the three report rules are
    ``report``) of the jobs of ``owners`` under ``benchmarks``, reports included: ``jobs``,
    ``CPU s`` and ``wall s`` summed over them, ``longest job s`` (wall), ``peak memory MB``
    (the largest of its jobs), and with ``planned`` (``{kind: (jobs, CPU s)}``, the plan's)
    ``planned jobs`` and ``planned CPU s``; a last row ``all`` sums the columns (the largest
    for the longest job and the peak memory)."""
    costs = job_costs(owners, benchmarks, skip=())
    table = costs.groupby("rule").agg(**{
        "jobs": ("job", "size"), "CPU s": ("CPU s", "sum"), "wall s": ("wall s", "sum"),
        "longest job s": ("wall s", "max"), "peak memory MB": ("peak memory MB", "max")})
    if planned is not None:
        table["planned jobs"] = [planned.get(r, (0, 0.0))[0] for r in table.index]
        table["planned CPU s"] = [float(planned.get(r, (0, 0.0))[1]) for r in table.index]
    if not table.empty:
        total = table.sum(numeric_only=True)
        for column in ("longest job s", "peak memory MB"):
            total[column] = table[column].max()
        table.loc["all"] = total
    table.index.name = "rule"
    return table


def write_rule_costs(table, html, tsv):
    """Write :func:`rule_costs`' ``table`` as a tab-separated file ``tsv`` and as a page
    ``html`` (a sentence on the build, then the table), each in one rename
    (`vibroimpact._files.atomic_path`)."""
    from vibroimpact import _files

    with _files.atomic_path(tsv) as tmp:
        table.to_csv(tmp, sep="\t", float_format="%.3f")
    if table.empty:
        summary = "No benchmark file of this build's jobs was found."
    else:
        total = table.loc["all"]
        summary = (
            f"{int(total['jobs'])} jobs of {len(table) - 1} kinds, as Snakemake's benchmarks "
            f"measured them: {total['CPU s']:.1f} CPU-s and {total['wall s']:.1f} s of wall "
            f"time in all (jobs run side by side, so the build took less), the longest job "
            f"{total['longest job s']:.1f} s, the largest peak memory "
            f"{total['peak memory MB']:.0f} MB.")
        if "planned CPU s" in table:
            summary += (" The plan's estimate (<code>vibroimpact plan</code>) of each kind "
                        "stands beside it; the validation runs hold every core, and the plan "
                        "counts their wall time.")
    body = table.to_html(float_format=lambda v: f"{v:.2f}", na_rep="-", border=0)
    page = ("<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Job costs</title>"
            "<style>body{font-family:sans-serif} td,th{padding:2px 10px;text-align:right}"
            "</style></head>\n<body><p>" + summary + "</p>\n" + body + "\n</body></html>\n")
    with _files.atomic_path(html) as tmp:
        Path(tmp).write_text(page)
