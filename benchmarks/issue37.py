"""Every issue-37 target, this tree against a named peer revision, in one run; a table at
the end.

What it runs (each side in a folder of its own under ``--keep`` or a temporary directory:
this tree's tracked and new files, the peer a ``git worktree``; both on this ``.venv`` with
``PYTHONPATH=<side>/src``, as ``benchmarks/bench_make.py``):

1. ``make``'s Snakemake part of the default config from a fresh results folder, what `make`
   runs after installation (`bench_make.build(make=True)`: ``python -m vibroimpact run``,
   then ``python -m vibroimpact report``; fresh numba cache, the sides in turn, peer first):
   the wall time (target <= 120 s on 2 cores) and the CPU of Snakemake and its jobs. A side
   whose `make` compiles the kernels when it installs (``vibroimpact.warm``) does so first,
   untimed by the build and printed apart, as `make` does after installation.
2. From each build's benchmark files: the dearest report and figure job (target: none above
   5 s wall), the work-precision and stress jobs (the issue asks a fraction of today's
   cost), and the plan of this tree against this side's files per kind of job
   (`job_costs.plan_comparison`: target within 25 %).
3. The Fig. 15 map job from its noise record (`bench_map_floor.py`: every cell of the built
   map on 2 processes, each build's kernels; target <= 10 s wall) and the step without impact
   against the closed-form prototype (target <= 1.0x).
4. With ``--tests``: ``make test`` in each side (target <= 15 min wall), peer first. Half an
   hour of both cores a side: off by default.

    python benchmarks/issue37.py --peer a13f0b3
    python benchmarks/issue37.py --peer a13f0b3 --tests --keep /tmp/issue37

Timings on a shared machine measure the machine: the load average is printed before each
part, and the CPU sums are the steadier figures.
"""
import argparse
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_make  # noqa: E402
import job_costs  # noqa: E402
from bench_make import copy_tree  # noqa: E402

SHORT = ("report", "draw_figure", "draw_validation_figure")


def _uptime():
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def _sides(tmp, peer):
    sides = {"peer": tmp / "peer", "this": tmp / "this"}
    if not sides["peer"].exists():
        subprocess.run(["git", "worktree", "add", "-f", "--detach", str(sides["peer"]), peer],
                       cwd=ROOT, check=True, capture_output=True)
    if not sides["this"].exists():
        copy_tree(sides["this"])
    return sides


def job_summary(results):
    """The dearest report/figure job (path, wall s), how many exceed 5 s, and the
    validation runs' wall s, from a build's benchmark files."""
    rows = job_costs.benchmark_rows(results)
    short = {k: v for k, v in rows.items() if job_costs.rule_of(k) in SHORT}
    worst = max(short.items(), key=lambda kv: kv[1][0])
    validation = {k: rows[k][0] for k in ("measure_work_precision.tsv",
                                          "sample_stress_families.tsv") if k in rows}
    return dict(worst=worst[0], worst_s=worst[1][0],
                above=sum(v[0] > 5.0 for v in short.values()), n_short=len(short),
                validation=validation)


def map_floor(side_results, peer):
    """``bench_map_floor.py`` on this side's built map: the wall s of each build's map job
    and the step ratio simulator / prototype."""
    out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_map_floor.py"),
                          "--no-main", "--peer", peer,
                          "--dataset", str(side_results / "datasets/motion_map_map.nc"),
                          "--noise", str(side_results / "noise/harmonic_input.nc")],
                         cwd=ROOT, capture_output=True, text=True)
    print(out.stdout, out.stderr[-2000:], flush=True)
    if out.returncode:
        return {}
    found = {}
    for line in out.stdout.splitlines():
        m = re.match(r"^(this tree|peer \S+)\s+([\d.]+)\s+([\d.]+)", line)
        if m:
            found["this" if m.group(1) == "this tree" else "peer"] = float(m.group(2))
        m = re.match(r"^ratio simulator / prototype: ([\d.]+)", line)
        if m:
            found["step"] = float(m.group(1))
    return found


def make_test(workdir):
    env = dict(os.environ, PYTHONPATH=str(workdir / "src"))
    start = time.perf_counter()
    venv = ROOT / ".venv"
    # this .venv, never reinstalled (-o: its stamp taken as up to date; a peer's newer
    # pyproject.toml would otherwise reinstall the package from the peer into it)
    out = subprocess.run(["make", "-o", str(venv / ".installed"), "test", f"VENV={venv}"],
                         cwd=workdir, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    tail = out.stdout.strip().splitlines()[-1:] or [""]
    print(f"  make test in {workdir.name}: exit {out.returncode}, {wall:.0f} s; {tail[0]}",
          flush=True)
    return wall if out.returncode == 0 else float("nan")


def warm(workdir, cache):
    """What `make` compiles when it installs (``python -m vibroimpact.warm``, since 15572b0)
    into the side's numba cache, and the code digests it keeps (``python -m
    vibroimpact.pipeline.digest_cache``, since w38), before its build is timed: its wall
    seconds, or 0.0 for a revision without it, whose jobs compile the kernels in the timed
    build."""
    if not (workdir / "src" / "vibroimpact" / "warm.py").exists():
        return 0.0
    env = dict(os.environ, PYTHONPATH=str(workdir / "src"), NUMBA_CACHE_DIR=str(cache))
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "vibroimpact.warm", "--jobs", "2"], cwd=workdir,
                   env=env, check=True, capture_output=True)
    if (workdir / "src" / "vibroimpact" / "pipeline" / "digest_cache.py").exists():
        # and the workflow's code digests, kept for the build's Snakemake starts (since w38)
        subprocess.run([sys.executable, "-m", "vibroimpact.pipeline.digest_cache"],
                       cwd=workdir, env=env, check=True, capture_output=True)
    return time.perf_counter() - start


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--peer", required=True, help="git revision to compare against")
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--tests", action="store_true", help="also `make test` on each side")
    parser.add_argument("--no-map", action="store_true", help="skip the map-floor part")
    parser.add_argument("--keep", metavar="DIR", help="work here and keep it")
    args = parser.parse_args(argv)
    tmp = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="issue37-"))
    tmp.mkdir(parents=True, exist_ok=True)
    sides = _sides(tmp, args.peer)
    print(f"issue37: this = {ROOT} (working tree), peer = {args.peer}; in {tmp}", flush=True)
    rows = []
    try:
        builds = {}
        installs = {}
        for side, workdir in sides.items():
            installs[side] = warm(workdir, tmp / f"numba-{side}")
            print(f"1. make ({side}): {_uptime()}", flush=True)
            builds[side] = bench_make.build(workdir, args.cores, tmp / f"numba-{side}",
                                            make=True)
            bench_make._print(side, builds[side])
        jobs = {side: job_summary(workdir / "results") for side, workdir in sides.items()}
        rows.append(("make, wall s (2 cores)", builds["this"]["wall"], builds["peer"]["wall"],
                     "<= 120"))
        rows.append(("make, CPU s (Snakemake and jobs)", builds["this"]["cpu"],
                     builds["peer"]["cpu"], ""))
        rows.append(("installation's kernel compilation, wall s (not in make's)",
                     installs["this"], installs["peer"], ""))
        rows.append(("dearest report/figure job, wall s", jobs["this"]["worst_s"],
                     jobs["peer"]["worst_s"], "<= 5"))
        rows.append(("report/figure jobs above 5 s", jobs["this"]["above"],
                     jobs["peer"]["above"], "0"))
        for name in ("measure_work_precision.tsv", "sample_stress_families.tsv"):
            rows.append((f"{name[:-4]}, wall s", jobs["this"]["validation"].get(name, 0.0),
                         jobs["peer"]["validation"].get(name, 0.0), "a fraction"))
        comparison = job_costs.plan_comparison(sides["this"] / "results")
        measured = [r for r in comparison if r[2]]
        within = sum(abs(r[3] / r[4] - 1.0) <= 0.25 for r in measured if r[4])
        print("2. the plan against this side's benchmark files:")
        for rule, pj, mj, pc, mc in measured:
            print(f"  {rule:26s} jobs {pj:3d}/{mj:3d}  CPU-s plan {pc:7.1f}  measured "
                  f"{mc:7.1f}  ratio {pc / mc if mc else float('inf'):5.2f}")
        rows.append(("plan: kinds of job within 25 %", f"{within}/{len(measured)}", "n/a",
                     "all"))
        if not args.no_map:
            print(f"3. map floor: {_uptime()}", flush=True)
            floor = map_floor(sides["this"] / "results", args.peer)
            rows.append(("Fig. 15 map job, wall s", floor.get("this", float("nan")),
                         floor.get("peer", float("nan")), "<= 10"))
            rows.append(("step without impact / prototype", floor.get("step", float("nan")),
                         "n/a", "<= 1.0"))
        if args.tests:
            walls = {}
            for side, workdir in sides.items():
                print(f"4. make test ({side}): {_uptime()}", flush=True)
                walls[side] = make_test(workdir)
            rows.append(("make test, wall s", walls["this"], walls["peer"], "<= 900"))
    finally:
        print(f"\nissue 37 targets, this tree against {args.peer} ({_uptime()}):")
        print(f"| target | this tree | peer {args.peer} | goal |")
        print("|---|---|---|---|")
        for name, this, peer, goal in rows:
            fmt = (lambda v: f"{v:.1f}" if isinstance(v, float) else str(v))
            print(f"| {name} | {fmt(this)} | {fmt(peer)} | {goal} |")
        if not args.keep:
            subprocess.run(["git", "worktree", "remove", "--force", str(sides["peer"])],
                           cwd=ROOT, capture_output=True)
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
