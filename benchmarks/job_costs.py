"""Wall time of each kind of workflow job, at this revision and at a peer revision, same run.

A job's cost is the time of ``snakemake --force <target>`` (that one job) minus that of the
same dry run (DAG building), on the test config after a full build: Snakemake's per-job overhead,
the interpreter's imports and the job's own work. The peer is another git revision, built in
its own copy and imported from there (PYTHONPATH), so both run on the same machine at once.

    python benchmarks/job_costs.py --peer 33a035a --rounds 3
"""
import argparse
import os
from pathlib import Path
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
# the tests' copy of the working tree (one function for both); a script, so not on the path
sys.path.insert(0, str(ROOT / "tests"))
from helpers import SNAKEMAKE, copy_tree  # noqa: E402

# kind -> target (fig16's path depends on the revision)
JOBS = {
    "figure (fig07)": "results/figures/random/fig07.png",
    "figure (fig16)": "{fig16}",
    "aggregate events": "results/datasets/random_events.nc",
    "simulate events tile": "results/cells/random/events/0.nc",
}


def _checkout(rev, where):
    subprocess.run(["git", "worktree", "add", "-f", "--detach", str(where), rev], cwd=ROOT,
                   check=True, capture_output=True)


def _run(workdir, *args):
    env = {**os.environ, "PYTHONPATH": str(workdir / "src")}
    start = time.perf_counter()
    out = subprocess.run([SNAKEMAKE, "--cores", "1", "--configfile", "config/test.yaml", "-q",
                          "--rerun-triggers", "mtime", *args], cwd=workdir, env=env,
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stdout[-2000:] + out.stderr[-2000:])
    return time.perf_counter() - start


def job_cost(workdir, target):
    full = _run(workdir, "--force", target)
    dry = _run(workdir, "-n", target)
    return full - dry


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--peer", default="33a035a", help="git revision to compare against")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        sides = {"this tree": Path(tmp) / "now", f"peer {args.peer}": Path(tmp) / "peer"}
        copy_tree(sides["this tree"])     # results never land in the repository
        _checkout(args.peer, sides[f"peer {args.peer}"])
        try:
            for workdir in sides.values():
                _run(workdir)                       # full build of the test config
            fig16 = {"this tree": "results/figures/orbits/harmonic/fig16.png",
                     f"peer {args.peer}": "results/figures/harmonic/fig16.png"}
            print(f"{'job':24s} {'this tree [s]':>14s} {'peer [s]':>10s} {'ratio':>7s}")
            for kind, target in JOBS.items():
                cost = {}
                for side, workdir in sides.items():
                    t = target.format(fig16=fig16[side])
                    cost[side] = statistics.median(job_cost(workdir, t)
                                                   for _ in range(args.rounds))
                now, peer = cost.values()
                print(f"{kind:24s} {now:14.2f} {peer:10.2f} {now / peer:7.2f}")
        finally:
            subprocess.run(["git", "worktree", "remove", "--force",
                            str(sides[f"peer {args.peer}"])], cwd=ROOT, capture_output=True)


if __name__ == "__main__":
    main()
