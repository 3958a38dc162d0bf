"""The README's numbers of the default build, generated: the plan, and a finished build's own.

    python benchmarks/readme_numbers.py                       # print them
    python benchmarks/readme_numbers.py --write README.md     # rewrite the README's blocks
    python benchmarks/readme_numbers.py --results /path/to/results --write README.md

The README holds each generated number between ``<!-- readme_numbers:NAME -->`` and
``<!-- /readme_numbers:NAME -->``; ``--write`` replaces the text between each pair, and
nothing else:

- ``plan``: ``make plan`` on the default config (`vibroimpact.pipeline.config.load`: the
  cells, jobs, outputs and CPU the build will run, from the same target lists Snakemake's
  DAG uses), at the commit of this tree; no build needed.
- ``build``: one finished default build (``--results``, default ``results/``): the commit
  its datasets record (``git_commit``), its jobs (one ``results/benchmarks/**.tsv`` each),
  the jobs' CPU and wall time (Snakemake's ``benchmark:`` files), the span from the first
  job's start to the last job's end, the heaviest jobs, the outputs on disk.
- ``report``: the size of that build's ``results/report.html``.
- ``figures``: which entry lists each figure, the config blocks it needs and its options,
  from the figure table `vibroimpact.pipeline.figures.FIGURES` that the checks read.
- ``plan_clearance``, ``plan_planes``: ``make plan`` on the shipped examples;
  ``plan_finer``: on the README's own ``finer.yaml``.

``--docs docs/figures.md`` rewrites that file's blocks the same way, from the finished
build's datasets: ``fig08_tail`` (the quantiles of the interval at the lowest play) and
``fig09_rice`` (the measured mean interval against Rice's, `results/datasets/
random_events.nc`).

``--datasets docs/datasets.md`` rewrites that file's block ``variables``: a table of every
variable and coordinate of each dataset of the finished build (not the per-job tiles), with
its dimensions, ``units`` and ``long_name`` as the file holds them. The test config builds
the same files with the same variables, and a workflow test holds the block to its build.

Re-run it after a build that changes what the README quotes (a new job, a new cost): the
README's numbers then come from one build, named by its commit.
"""
import argparse
import csv
from pathlib import Path
import re
import subprocess
import sys

import numpy as np
import xarray as xr

from vibroimpact.pipeline import config as configuration, figures

ROOT = Path(__file__).resolve().parents[1]


def _commit(root):
    out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True,
                         text=True)
    # what the plan reads (not the README this script rewrites)
    dirty = subprocess.run(["git", "status", "--porcelain", "--", "src", "config", "workflow",
                            "Snakefile"], cwd=root, capture_output=True, text=True).stdout.strip()
    return out.stdout.strip() + (" with uncommitted changes" if dirty else "")


def plan_text(root=ROOT):
    """The ``plan`` block: the default config's plan, at this tree's commit."""
    _, plan = configuration.load(root=root)
    return (f"`make plan` on the default config (generated at {_commit(root)} by "
            f"`benchmarks/readme_numbers.py`): {plan.summary(2)}")


#: The shipped examples whose plan the README quotes: block name, config file.
EXAMPLES = {"plan_clearance": "config/examples/clearance.yaml",
            "plan_planes": "config/examples/planes.yaml",
            "plan_impact_law": "config/examples/impact_law.yaml"}


def example_plan_text(name, root=ROOT):
    """A ``plan_*`` block: the plan of a shipped example (:data:`EXAMPLES`)."""
    _, plan = configuration.load(root=root, user_files=[Path(root) / EXAMPLES[name]])
    return f"`make plan CONFIG={EXAMPLES[name]}` (generated): {plan.summary(2)}"


def finer_plan_text(root=ROOT):
    """The ``plan_finer`` block: the plan of the README's own example file ``finer.yaml``
    (its first ``yaml`` block after "A new study, and a sweep"), written to a temporary file
    and planned as `make plan CONFIG=finer.yaml` would."""
    import tempfile

    readme = (Path(root) / "README.md").read_text()
    start = readme.index("```yaml\n", readme.index("### A new study, and a sweep")) + 8
    text = readme[start:readme.index("```", start)]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "finer.yaml"
        path.write_text(text)
        _, plan = configuration.load(root=root, user_files=[path])
    maps = [r for r in plan.rows if r.key == "studies.finer_map"]
    cells = f"{maps[0].cells:,} cells; " if maps and getattr(maps[0], "cells", None) else ""
    return f"{cells}`make plan CONFIG=finer.yaml` (generated): {plan.summary(2)}"


def _fmt(x, digits=2):
    return f"{x:.{digits}f}".rstrip("0").rstrip(".") if abs(x) < 100 else f"{x:,.0f}"


def docs_blocks(results):
    """The blocks of docs/figures.md, from the finished build's random-force events."""
    from vibroimpact import stats

    ds = xr.open_dataset(Path(results) / "datasets" / "random_events.nc").isel(inv_beta=0)
    low = ds.isel(delta=0)
    x = low.interval.values
    width = x[1] - x[0]
    mass = low.interval_density.values * width
    edges = np.r_[x - width / 2, x[-1] + width / 2]
    cdf = np.r_[0.0, np.cumsum(mass)]
    q50, q99 = (np.interp(q * cdf[-1], cdf, edges) for q in (0.5, 0.99))
    longest = edges[np.nonzero(mass)[0][-1] + 1]
    tail = (f"at δ = {float(low.delta):g} the median interval is {q50:.1f}, the 99 % quantile "
            f"{q99:.0f} and the longest below {longest:.0f} (bin edges; generated)")
    d = ds.delta.values
    n = ds.n_collisions.values
    tn = ds.simulated_time.values / np.where(n > 0, n, np.nan)
    lo, hi = ds.interval_mean_lo.values, ds.interval_mean_hi.values
    rice = 1.0 / stats.upcrossing_rate(d, ds.attrs["linear_sigma_x"],
                                       ds.attrs["linear_sigma_v"])
    ratio = tn / rice
    many = n >= 20                     # the figure's filled points
    r = np.where(many, ratio, np.nan)
    i_min = int(np.nanargmin(r))        # the run of plays around the least ratio, below 1
    a = b = i_min
    while a > 0 and r[a - 1] < 1.0:
        a -= 1
    while b + 1 < r.size and r[b + 1] < 1.0:
        b += 1
    c = b + 1                           # the run after it, at or above 1
    while c + 1 < r.size and r[c + 1] >= 1.0:
        c += 1
    short, longer = slice(a, b + 1), slice(b + 1, c + 1)
    i_max = b + 1 + int(np.nanargmax(r[longer]))
    i_b = b + 1 + int(np.nonzero(rice[longer] < lo[longer])[0][-1])
    after = many & (np.arange(d.size) > i_b)
    inside = after & (rice >= lo) & (rice <= hi)
    far = after & (d >= d[i_b] + 0.4)
    return {"fig08_tail": tail, "fig09_rice": (
        f"On the default build (generated from `results/datasets/random_events.nc`, plays with "
        f"at least 20 collisions) the measured T/N is shorter than $1/\\nu^+$ for "
        f"{d[a]:g} ≤ δ ≤ {d[b]:g} ({_fmt(ratio[short].min())}-{_fmt(ratio[short].max())} of "
        f"it, least at δ = {d[i_min]:g}) and longer for {d[b + 1]:g} ≤ δ ≤ {d[c]:g}, by "
        f"{100 * (ratio[longer].min() - 1):.0f}-{100 * (ratio[i_max] - 1):.0f} % (most near "
        f"δ = {d[i_max]:g}); Rice's value is below "
        f"the 95 % interval up to δ = {d[i_b]:g} ({rice[i_b]:,.0f} against {tn[i_b]:,.0f} "
        f"[{lo[i_b]:,.0f}, {hi[i_b]:,.0f}]). Beyond, Rice lies inside the interval at "
        f"{int(inside.sum())} of the {int(after.sum())} plays; T/N·ν⁺ is "
        f"{_fmt(ratio[far].min())}-{_fmt(ratio[far].max())} at δ = {d[far].min():g}-"
        f"{d[far].max():g}")}


def dataset_files(results):
    """The datasets of a build that docs/datasets.md tabulates: every ``results/<folder>/
    <name>.nc``, the per-job tiles (further down) left out."""
    results = Path(results)
    return sorted(p for p in results.glob("*/*.nc") if not p.name.startswith("."))


def datasets_text(results):
    """The ``variables`` block of docs/datasets.md: per dataset of the build in ``results``,
    each variable and coordinate with its dimensions, units and long_name, from the file."""
    import netCDF4

    def cell(text):
        return " ".join(str(text).split()).replace("|", "\\|")

    rows = [""]
    for path in dataset_files(results):
        rows += [f"### `results/{path.relative_to(results).as_posix()}`", "",
                 "| variable | dimensions | units | long_name |", "|---|---|---|---|"]
        with netCDF4.Dataset(path) as nc:
            for name, var in nc.variables.items():
                kind = " (coordinate)" if var.dimensions == (name,) else ""
                attrs = {k: var.getncattr(k) for k in var.ncattrs()}
                rows.append(f"| `{name}`{kind} | {', '.join(var.dimensions) or '-'} | "
                            f"`{cell(attrs.get('units', ''))}` | "
                            f"{cell(attrs.get('long_name', ''))} |")
        rows.append("")
    return "\n".join(rows)


def _minsec(s):
    m, s = divmod(round(s), 60)
    return f"{m} min {s} s" if m else f"{s} s"


def build_numbers(results):
    """``{commit, jobs, measured, cpu_s, job_s, span_s, heavy: [(job, s, cpu_s)], disk,
    report}`` of
    the finished build in ``results``."""
    results = Path(results)
    commits = set()
    for path in sorted((results / "datasets").glob("*.nc"))[:50]:
        with xr.open_dataset(path) as ds:
            commits.add(str(ds.attrs.get("git_commit", "?"))[:7]
                        + (" (dirty)" if int(ds.attrs.get("git_dirty", 0)) else ""))
    rows = []
    for tsv in sorted((results / "benchmarks").rglob("*.tsv")):
        with tsv.open() as f:
            row = next(csv.DictReader(f, delimiter="\t"))
        name = tsv.relative_to(results / "benchmarks").with_suffix("").as_posix()
        rows.append((name, float(row["s"]), float(row["cpu_time"]), tsv.stat().st_mtime))
    if not rows:
        raise SystemExit(f"{results}: no results/benchmarks/*.tsv: not a finished build")
    span = max(r[3] for r in rows) - min(r[3] - r[1] for r in rows)
    heavy = sorted(rows, key=lambda r: -r[1])[:4]
    disk = sum(p.stat().st_size for p in results.rglob("*") if p.is_file()
               and not {"logs", "benchmarks"} & set(p.relative_to(results).parts))
    report = results / "report.html"
    # the paper figures' copies (copy_paper_figure) are the jobs without a benchmark file
    copies = [p for p in (results / "figures").glob("*.png")
              if p.stem not in ("work_precision", "stress")]
    return {"commit": ", ".join(sorted(commits)), "jobs": len(rows) + len(copies),
            "measured": len(rows),
            "cpu_s": sum(r[2] for r in rows), "job_s": sum(r[1] for r in rows), "span_s": span,
            "heavy": [(r[0], r[1], r[2]) for r in heavy], "disk": disk,
            "report": report.stat().st_size if report.exists() else None}


def build_text(numbers):
    """The ``build`` block: one build's own numbers, named by its commit."""
    heavy = "; ".join(f"{name} {s:.0f} s ({cpu:.0f} s CPU)" for name, s, cpu in numbers["heavy"])
    return (f"The default build at {numbers['commit']} (`benchmarks/readme_numbers.py` on its "
            f"`results/`): {numbers['jobs']} jobs besides `all`; of the {numbers['measured']} "
            f"with a benchmark file (all but the paper figures' copies) "
            f"{_minsec(numbers['cpu_s'])} of CPU, {_minsec(numbers['job_s'])} of wall time "
            f"added up, "
            f"{_minsec(numbers['span_s'])} from the first job's start to the last job's end; "
            f"its outputs take {numbers['disk'] / 1e6:.0f} MB (logs and benchmarks aside). "
            f"The longest jobs: {heavy}")


def report_text(numbers):
    """The ``report`` block: the size of that build's Snakemake report."""
    size = numbers["report"]
    size = "not written" if size is None else f"{size / 1e6:.1f} MB"
    return f"{size} for the default config at {numbers['commit']}"


def figures_text():
    """The ``figures`` block: a table of the figures an entry may list and what each needs
    (the rules `vibroimpact.pipeline.config.checks` applies to the table FIGURES)."""
    rows = ["", "| figure | listed by | needs in that entry | options of its item |",
            "|---|---|---|---|"]
    from vibroimpact.pipeline.config.checks import PLANE_FIGURES

    for fig, spec in figures.FIGURES.items():
        owner = "a study" if spec["owner"] == "study" else "an `orbits` entry"
        if spec["owner"] != "study" and fig in PLANE_FIGURES:
            owner += ", or a study with a `plane` (over it)"
        needs = [f"`{b}:`" for b in ("trace", "spectra", "escape") if b in spec["reads"]]
        if "map" in spec["reads"]:
            needs.append("the map grid (`inv_beta`, `delta`; `map:` defaults)")
        if "events" in spec["reads"]:
            needs.append("the `delta` grid")
        if spec.get("needs"):
            needs.append(f"`{spec['needs']}:`")
        if spec.get("harmonic"):
            needs.append("`amplitude` != 0")
        needs += [f"an `{src}` entry of the same zeta, eps and walls (over a plane: the same "
                  f"plane and every fixed value), named in its item"
                  for src in spec.get("sources", ())]
        options = [f"`{o}`" for o in spec.get("options", ())]
        if spec.get("per"):
            options.insert(0, f"`{spec['per']}` (one figure per value: `{fig}-0` ...)")
        if "spectra" in spec["reads"]:
            options.append("`beta_max`")
        options += [f"`{src}`" for src in spec.get("sources", ())]
        rows.append(f"| `{fig}` | {owner} | {', '.join(needs) or '-'} | "
                    f"{', '.join(options) or '-'} |")
    return "\n".join(rows) + "\n"


def requests_text(root=ROOT):
    """The README's job requests against measured use: per size recorded in
    tests/data/job_requests.json (``benchmarks/job_requests.py``), each job's peak memory and
    wall time against what `vibroimpact.pipeline.config.requests` asks at its first attempt."""
    import json

    from vibroimpact.pipeline.config import costs, requests

    record = json.loads((root / "tests" / "data" / "job_requests.json").read_text())
    parts = []
    for size, label in (("default", "Default config"), ("fine_map", "The 4x finer map")):
        config, plan = configuration.load(root=root, user_files=record[size]["configfiles"])
        rows = []
        for job in record[size]["jobs"]:
            asked = requests.job_request(job["rule"], config, plan.studies, job["wildcards"])
            rows.append((job["max_rss_mb"], asked.mem_mb, job["s"], asked.runtime, job["rule"]))
        ratio = sorted(rows, key=lambda r: r[1] / r[0])
        low, high = ratio[0], ratio[-1]
        pred = [r for r in rows if r[4] == "map_predictors"]
        parts.append(
            f"{label}, {len(rows)} jobs: peaks {min(r[0] for r in rows):,.0f}-"
            f"{max(r[0] for r in rows):,.0f} MB against requests of "
            f"{min(r[1] for r in rows):,}-{max(r[1] for r in rows):,} MB, "
            f"{low[1] / low[0]:.2f} x ({low[4]}, {low[0]:,.0f} of {low[1]:,}) to "
            f"{high[1] / high[0]:.1f} x ({high[4]}); wall times {min(r[2] for r in rows):.1f}-"
            f"{max(r[2] for r in rows):.0f} s against {min(r[3] for r in rows)}-"
            f"{max(r[3] for r in rows)} min"
            + (f"; `map_predictors` {pred[0][0]:,.0f} of {pred[0][1]:,} MB" if pred else ""))
    fine = 81_225          # the 16x map, step 0.0125 on both axes
    return (" " + ". ".join(parts) + f". The predictors of an {fine:,}-cell map (the 16x "
            f"map, step 0.0125) ask {costs.BASE_MEM_MB + costs.predictors_mem_mb(fine):,.0f} MB. ")


def rewrite(readme, blocks):
    """``readme`` with the text of each ``<!-- readme_numbers:NAME -->`` block replaced."""
    text = Path(readme).read_text()
    for name, value in blocks.items():
        pattern = re.compile(rf"(<!-- readme_numbers:{name} -->)(.*?)(<!-- /readme_numbers:"
                             rf"{name} -->)", re.S)
        if not pattern.search(text):
            raise SystemExit(f"{readme}: no <!-- readme_numbers:{name} --> block")
        text = pattern.sub(lambda m, v=value: m[1] + v + m[3], text)
    Path(readme).write_text(text)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", default=str(ROOT / "results"),
                        help="a finished default build's results/ (default: this tree's)")
    parser.add_argument("--write", metavar="README", help="rewrite the blocks of this file")
    parser.add_argument("--plan-only", action="store_true",
                        help="only the plans (no finished build needed)")
    parser.add_argument("--docs", metavar="FIGURES_MD",
                        help="rewrite the blocks of this file (docs/figures.md)")
    parser.add_argument("--datasets", metavar="DATASETS_MD",
                        help="rewrite the variables block of this file (docs/datasets.md)")
    args = parser.parse_args(argv)
    blocks = {"plan": plan_text(), "figures": figures_text()}
    blocks.update({name: example_plan_text(name) for name in EXAMPLES},
                  plan_finer=finer_plan_text(), requests=requests_text())
    docs = {}
    if not args.plan_only:
        numbers = build_numbers(args.results)
        blocks.update(build=build_text(numbers), report=report_text(numbers))
        docs = docs_blocks(args.results)
    for name, value in {**blocks, **docs}.items():
        print(f"{name}: {value}")
    if args.write:
        rewrite(args.write, blocks)
    if args.docs and docs:
        rewrite(args.docs, docs)
    if args.datasets:
        rewrite(args.datasets, {"variables": datasets_text(Path(args.results))})
    return 0


if __name__ == "__main__":
    sys.exit(main())
