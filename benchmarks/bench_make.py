"""`make`'s Snakemake part (``--make``: all of what `make` runs after installation) for the
default config, from a fresh results folder: this tree against a peer revision, in turn.

Each side builds in a folder of its own under a temporary directory: this tree's tracked and
new files (tests/helpers.py ``copy_tree``, as ``benchmarks/job_costs.py``), the peer a
``git worktree`` of ``--peer`` (default 3091f6a, the issue's baseline). Both run this
``.venv``'s ``snakemake`` with ``PYTHONPATH=<side>/src`` (the package is imported from the
side's sources, as ``benchmarks/ab_kernels.py``) and ``NUMBA_CACHE_DIR`` of their own (a
fresh clone compiles; ``--warm`` reuses each side's cache from its previous round: the cost of
a build after installation, whose first ``make`` compiled). The sides alternate, peer first
in odd rounds.

Printed per run: ``uptime`` before it (the machine may be shared), the wall time, the CPU
time of snakemake and all its jobs (``getrusage(RUSAGE_CHILDREN)``), the per-job benchmark
files' sums (``results/benchmarks/**/*.tsv``: columns ``s`` and ``cpu_time``) and the five
costliest rules by CPU time; at the end the ratios this/peer. Prefer the CPU-time sums on a
loaded machine. A whole default build is minutes of both cores: run it sparingly.

    python benchmarks/bench_make.py                     # both sides, 1 round, --cores 2
    python benchmarks/bench_make.py --side this --keep /tmp/bench_make
    python benchmarks/bench_make.py --make        # what `make` runs: run, then report
"""
import argparse
import csv
from collections import defaultdict
import os
from pathlib import Path
import resource
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the tests' copy of the working tree
from helpers import SNAKEMAKE, copy_tree  # noqa: E402


def _uptime():
    out = subprocess.run(["uptime"], capture_output=True, text=True)
    return out.stdout.strip()


def _benchmark_sums(workdir):
    """``(s, cpu_time, {rule: [n, s, cpu_time]})`` over every benchmark file of the build."""
    rules = defaultdict(lambda: [0, 0.0, 0.0])
    for path in sorted((workdir / "results" / "benchmarks").rglob("*.tsv")):
        parts = path.relative_to(workdir / "results" / "benchmarks").parts
        rule = parts[0] if len(parts) > 1 else path.stem   # benchmarks/<rule>.tsv: one job
        with path.open() as f:
            for row in csv.DictReader(f, delimiter="\t"):
                entry = rules[rule]
                entry[0] += 1
                entry[1] += float(row["s"])
                cpu = row.get("cpu_time", "NA")
                entry[2] += float(cpu) if cpu not in ("", "NA", "-") else 0.0
    return (sum(v[1] for v in rules.values()), sum(v[2] for v in rules.values()), dict(rules))


def _commands(cores, make):
    """What one build runs: Snakemake alone, or (``make``) what ``make`` runs after
    installation, ``python -m vibroimpact run`` (the config checked, the plan printed, the
    recovery, then Snakemake) and ``python -m vibroimpact report`` (Snakemake's report)."""
    if not make:
        return [[SNAKEMAKE, "--cores", str(cores), "-q"]]
    return [[sys.executable, "-m", "vibroimpact", "run", "--cores", str(cores)],
            [sys.executable, "-m", "vibroimpact", "report"]]


def build(workdir, cores, cache, fresh=True, make=False):
    """One default build in ``workdir``: ``{wall, cpu, bench_s, bench_cpu, rules}`` (with
    ``make``, ``steps``: the wall time of each of its two commands)."""
    if fresh:
        for name in ("results", ".snakemake"):
            shutil.rmtree(workdir / name, ignore_errors=True)
    env = dict(os.environ, PYTHONPATH=str(workdir / "src"), NUMBA_CACHE_DIR=str(cache))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    steps = []
    for cmd in _commands(cores, make):
        step = time.perf_counter()
        out = subprocess.run(cmd, cwd=workdir, env=env, capture_output=True, text=True)
        steps.append(time.perf_counter() - step)
        if out.returncode != 0:
            raise SystemExit(f"FAIL: {' '.join(cmd[-3:])} in {workdir} exited with "
                             f"{out.returncode}:\n{out.stdout[-2000:]}\n{out.stderr[-3000:]}")
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    bench_s, bench_cpu, rules = _benchmark_sums(workdir)
    return dict(wall=wall, cpu=cpu, bench_s=bench_s, bench_cpu=bench_cpu, rules=rules,
                steps=steps)


def _print(label, r):
    print(f"  {label}: wall {r['wall']:.1f} s, CPU {r['cpu']:.1f} s (snakemake and its jobs); "
          f"benchmark files: s {r['bench_s']:.1f}, cpu_time {r['bench_cpu']:.1f}", flush=True)
    if len(r["steps"]) > 1:
        print(f"      wall of `vibroimpact run` {r['steps'][0]:.1f} s, of `vibroimpact report` "
              f"{r['steps'][1]:.1f} s", flush=True)
    top = sorted(r["rules"].items(), key=lambda kv: -kv[1][2])[:5]
    for rule, (n, s, cpu) in top:
        print(f"      {rule:28s} {n:3d} jobs  s {s:7.1f}  cpu_time {cpu:7.1f}", flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--peer", default="3091f6a", help="git revision to compare against")
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=1)
    parser.add_argument("--side", choices=("both", "this", "peer"), default="both")
    parser.add_argument("--warm", action="store_true",
                        help="keep each side's numba cache between rounds (after installation)")
    parser.add_argument("--make", action="store_true",
                        help="run what `make` runs (python -m vibroimpact run, then report) "
                        "instead of Snakemake alone")
    parser.add_argument("--keep", metavar="DIR", help="build here and keep it (default: a "
                        "temporary directory, removed)")
    args = parser.parse_args(argv)
    tmp = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="bench_make-"))
    tmp.mkdir(parents=True, exist_ok=True)
    sides = {}
    if args.side in ("both", "peer"):
        sides["peer"] = tmp / "peer"
        if not sides["peer"].exists():
            subprocess.run(["git", "worktree", "add", "-f", "--detach", str(sides["peer"]),
                            args.peer], cwd=ROOT, check=True, capture_output=True)
    if args.side in ("both", "this"):
        sides["this"] = copy_tree(tmp / "this")
    print(f"bench_make: default config, {'make' if args.make else 'snakemake'}, "
          f"--cores {args.cores}, peer = {args.peer}, "
          f"this = {ROOT} (working tree); in {tmp}")
    runs = defaultdict(list)
    try:
        for i in range(args.rounds):
            order = list(sides) if i % 2 == 0 else list(reversed(sides))
            for side in order:
                cache = tmp / f"numba-{side}" / ("warm" if args.warm else f"round{i}")
                print(f"round {i + 1} {side}: {_uptime()}", flush=True)
                r = build(sides[side], args.cores, cache, make=args.make)
                runs[side].append(r)
                _print(side, r)
    finally:
        if not args.keep and "peer" in sides:
            subprocess.run(["git", "worktree", "remove", "--force", str(sides["peer"])],
                           cwd=ROOT, capture_output=True)
        if not args.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    if len(runs) == 2:
        print("\nthis/peer (best of the rounds):")
        for key in ("wall", "cpu", "bench_s", "bench_cpu"):
            this, peer = min(r[key] for r in runs["this"]), min(r[key] for r in runs["peer"])
            print(f"  {key:10s} this {this:8.1f}  peer {peer:8.1f}  ratio {this / peer:.2f}")


if __name__ == "__main__":
    main()
