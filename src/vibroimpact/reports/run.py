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
_SKIPPED_RULES = ("report", "orbits_report", "validation_report")


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
    """The benchmark files of the jobs of ``owners`` (studies, orbits entries, noise
    records; ``orbits/<name>`` for an orbits entry's figures; a rule of one job by its name)
    under the folder ``benchmarks``: ``<owner>.tsv``, ``<rule>/<owner>.tsv`` and
    ``<rule>/<owner>/*.tsv``, the report rules left out; sorted by rule and job."""
    root = Path(benchmarks)
    found = set()
    for owner in owners:
        if not owner:
            continue
        found.update(root.glob(f"{owner}.tsv"))            # a rule of one job
        found.update(root.glob(f"*/{owner}.tsv"))
        found.update(root.glob(f"*/{owner}/*.tsv"))
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
        last = bench.iloc[-1]
        rel = path.relative_to(root)
        rows.append({"rule": rel.parts[0], "job": "/".join(rel.parts[1:])[:-len(".tsv")],
                     "CPU s": float(last["cpu_time"]), "wall s": float(last["s"]),
                     "peak memory MB": float(last["max_rss"])})
    return pd.DataFrame(rows, columns=["rule", "job", "CPU s", "wall s", "peak memory MB"])
