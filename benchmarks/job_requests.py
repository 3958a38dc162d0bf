"""Job requests against measured use: every job's memory and run time request (the rules'
``resources:``, `vibroimpact.pipeline.config.requests.job_request`) beside the peak memory
and wall time its benchmark file measured in a finished build.

Run after a build of a config (``make``, or ``python -m vibroimpact run --configfile ...``);
the two sizes of tests/data/job_requests.json, from a fresh ``results``::

    python -m vibroimpact run --cores 2
    python benchmarks/job_requests.py --size default --write tests/data/job_requests.json
    python -m vibroimpact run --cores 2 --configfile benchmarks/configs/fine_map.yaml
    python benchmarks/job_requests.py --size fine_map --study fine_map \\
        --configfile benchmarks/configs/fine_map.yaml --write tests/data/job_requests.json

(the second build adds the finer map's jobs to the first; ``--study`` records those alone).

Each benchmark file under ``--results`` (default ``results``) of a rule the config builds
gives one row: the rule, its wildcards, ``max_rss`` (MB) and ``s`` (wall seconds), and the
request at the first attempt. Printed: per rule the largest measured peak against its request
and the smallest headroom; ``--write`` records the rows under ``--size`` in a JSON file (the
other sizes kept), which ``tests/test_job_requests.py`` reads: it recomputes every request from
the current cost model and checks it against what was measured, timing nothing itself. Exit
status 1 when a measured peak or wall time exceeds its request.
"""
import argparse
import csv
import json
from pathlib import Path
import sys

from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline.config import requests

ROOT = Path(__file__).resolve().parents[1]


#: The wildcards of each rule's benchmark file, ``results/benchmarks/<rule>/<w1>/<w2>.tsv``
#: (workflow/rules/*.smk); the reports share ``report/`` and are told apart below.
WILDCARDS = {
    "generate_noise": ("noise",),
    "simulate_events": ("study", "tile"), "simulate_spectra": ("study", "tile"),
    "simulate_map": ("study", "tile"), "simulate_trace": ("study",),
    "simulate_escape": ("study", "level"),
    "solve_orbit_tile": ("orbits", "tile"), "solve_clearance_orbit_tile": ("orbits", "tile"),
    "solve_attractor_tile": ("orbits", "tile"), "solve_plane_attractor_tile": ("study", "tile"),
    "trace_boundaries": ("orbits",), "solve_map_orbits": ("study",), "map_predictors": ("study",),
    "aggregate_events": ("study",), "aggregate_spectra": ("study",), "aggregate_map": ("study",),
    "aggregate_escape": ("study",), "aggregate_plane_attractors": ("study",),
    "aggregate_orbits": ("orbits",), "aggregate_attractors": ("orbits",),
    "measure_work_precision": (), "sample_stress_families": (),
    "draw_validation_figure": ("validation_fig",), "draw_sweep": ("sweep",),
}


def job_of(relpath):
    """``(rule, wildcards)`` of a benchmark file's path under ``results/benchmarks``, None
    for a file of no rule of `requests.RULES`."""
    folder, *rest = Path(relpath).with_suffix("").parts
    if folder == "report":
        if rest[0] == "validation":
            return "validation_report", {"vreport": rest[1]}
        if rest[0] == "orbits":
            return "orbits_report", {"orbits": rest[1]}
        return "study_report", {"study": rest[0], "report": rest[1]}
    if folder == "draw_figure":
        return folder, {"owner": "/".join(rest[:-1]), "fig": rest[-1]}
    if folder not in WILDCARDS:
        return None
    return folder, dict(zip(WILDCARDS[folder], rest))


def of_studies(wildcards, names):
    """Whether a job's wildcards name one of the studies ``names`` (all jobs if none)."""
    return not names or wildcards.get("study", wildcards.get("owner")) in names


def measured(path):
    """``(max_rss MB, s)`` of a benchmark file (its last row: the last run)."""
    with open(path) as handle:
        row = list(csv.DictReader(handle, delimiter="\t"))[-1]
    rss = row["max_rss"]
    return (float(rss) if rss not in ("", "NA", "-") else 0.0), float(row["s"])


def rows(results, configfiles, studies=()):
    """One dict per benchmark file of a rule of the config (module docstring), of the jobs
    of ``studies`` alone if any are given."""
    config, plan = configuration.load(root=ROOT, user_files=configfiles)
    out = []
    for path in sorted(Path(results, "benchmarks").rglob("*.tsv")):
        job = job_of(path.relative_to(Path(results, "benchmarks")))
        if job is None:
            continue
        rule, wildcards = job
        if not of_studies(wildcards, studies):
            continue
        try:
            request = requests.job_request(rule, config, plan.studies, wildcards)
        except KeyError:                    # an entry of another config's build
            continue
        rss, wall = measured(path)
        out.append({"rule": rule, "wildcards": wildcards, "max_rss_mb": rss, "s": wall,
                    "mem_mb": request.mem_mb, "runtime_min": request.runtime})
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--results", default="results")
    parser.add_argument("--configfile", action="append", default=[],
                        help="config files layered on config/config.yaml (as the build's)")
    parser.add_argument("--study", action="append", default=[],
                        help="record the jobs of this study alone (its map, its figures, its "
                             "report); repeatable")
    parser.add_argument("--size", required=True, help="the name the rows are recorded under")
    parser.add_argument("--write", metavar="JSON", help="record the rows in this file")
    args = parser.parse_args(argv)
    found = rows(args.results, args.configfile, args.study)
    worst = {}
    for r in found:
        head = (r["mem_mb"] / max(r["max_rss_mb"], 1e-9), r["runtime_min"] * 60 / r["s"])
        w = worst.setdefault(r["rule"], [0, 0.0, 0, 0.0, head[0], head[1]])
        w[0] += 1
        if r["max_rss_mb"] > w[1]:
            w[1], w[2] = r["max_rss_mb"], r["mem_mb"]
        w[3] = max(w[3], r["s"])
        w[4], w[5] = min(w[4], head[0]), min(w[5], head[1])
    print(f"{len(found)} jobs of {args.results} (size {args.size}):")
    print(f"  {'rule':<28} {'jobs':>4} {'peak MB':>8} {'asks MB':>8} {'min x':>6} "
          f"{'max s':>7} {'min x':>6}")
    for rule, (n, rss, mem, wall, mem_x, time_x) in sorted(worst.items()):
        print(f"  {rule:<28} {n:>4} {rss:>8.0f} {mem:>8} {mem_x:>6.2f} {wall:>7.1f} "
              f"{time_x:>6.1f}")
    over = [r for r in found if r["max_rss_mb"] > r["mem_mb"] or r["s"] > 60 * r["runtime_min"]]
    for r in over:
        print(f"  OVER: {r['rule']} {r['wildcards']}: {r['max_rss_mb']:.0f} MB of "
              f"{r['mem_mb']}, {r['s']:.1f} s of {r['runtime_min']} min")
    if args.write:
        path = Path(args.write)
        data = json.loads(path.read_text()) if path.exists() else {}
        data[args.size] = {"configfiles": args.configfile, "studies": args.study,
                           "jobs": [{k: r[k] for k in ("rule", "wildcards", "max_rss_mb", "s")}
                                    for r in found]}
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(data, indent=1, sort_keys=True) + "\n")
        print(f"recorded under {args.size!r} in {path}")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
