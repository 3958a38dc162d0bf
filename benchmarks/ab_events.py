"""The events jobs (rule ``simulate_events``) of this tree against a named peer revision, in
turn in one run: the CPU of each job and whether the two write the same tiles.

Each side runs ``pipeline.tasks.events_tile`` of the default config's events studies, tile
by tile, in a fresh process (this ``.venv``, ``PYTHONPATH=<side>/src``, the side's own
config; the peer in a ``git worktree``), the sides alternated and their order swapped every
repeat, from the noise records of a build (``--noise``, default ``results/noise``: build
them with ``snakemake results/noise/random_input.nc results/noise/harmonic_input.nc``).
Printed per job: the process CPU (what a job's benchmark file records as ``cpu_time``:
start-up, simulation, statistics, writing) and the CPU of the call itself; then the sums
and their ratio, and whether every tile of this tree equals the peer's
(``xarray.testing.assert_identical`` without attributes and run measurements, as
``same_build.py``). Exit status 1 when a tile differs.

A side's first job compiles or loads its kernels: one warm-up job a side, untimed, first.
On a shared machine the CPU sums are the steadier figures; the load average is printed.

    python benchmarks/ab_events.py --peer 2ec7353
    python benchmarks/ab_events.py --peer 2ec7353 --studies random --tiles 0,1 --repeats 3
"""
import argparse
import os
from pathlib import Path
import resource
import subprocess
import sys
import tempfile

import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from same_build import _data  # noqa: E402

#: The child: one events job, its own CPU printed last.
JOB = """
import sys, time
from vibroimpact.pipeline import config, tasks
cfg, _ = config.load(root=sys.argv[1])
study, tile, noise, out = sys.argv[2], int(sys.argv[3]), sys.argv[4], sys.argv[5]
start = time.process_time()
tasks.events_tile(study, cfg["studies"][study], tile, noise, out)
print("call_cpu", time.process_time() - start)
"""


def _uptime():
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def run_job(side, study, tile, noise, out):
    """CPU seconds (process, call) of one events job of ``side`` (a source tree)."""
    env = dict(os.environ, PYTHONPATH=str(side / "src"), NUMBA_NUM_THREADS="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run([sys.executable, "-c", JOB, str(side), study, str(tile), str(noise),
                           str(out)], env=env, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        raise SystemExit(f"{side.name}: events job {study} {tile} failed:\n{done.stderr[-3000:]}")
    call = float(done.stdout.split("call_cpu")[-1])
    process = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return process, call


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--peer", required=True, help="git revision to compare against")
    parser.add_argument("--noise", default=str(ROOT / "results" / "noise"),
                        help="folder of the studies' noise records (<noise entry>.nc)")
    parser.add_argument("--studies", default="random,harmonic")
    parser.add_argument("--tiles", default=None,
                        help="tiles to run, e.g. 0,1 (default: every tile of each study)")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--keep", metavar="DIR", help="work here and keep it")
    args = parser.parse_args(argv)
    from vibroimpact.pipeline import config
    from vibroimpact.pipeline.study import Study

    cfg, _ = config.load(root=ROOT)
    jobs = []
    for name in args.studies.split(","):
        entry = cfg["studies"][name]
        noise = Path(args.noise) / f"{entry['noise']}.nc"
        if not noise.exists():
            raise SystemExit(f"--noise: no {noise} (build it: snakemake {noise})")
        n_tiles = Study.from_config(name, entry).n_tiles("events")
        tiles = (range(n_tiles) if args.tiles is None
                 else [int(t) for t in args.tiles.split(",")])
        jobs += [(name, t, noise) for t in tiles]
    tmp = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="ab_events-"))
    tmp.mkdir(parents=True, exist_ok=True)
    peer = tmp / "peer"
    if not peer.exists():
        subprocess.run(["git", "worktree", "add", "-f", "--detach", str(peer), args.peer],
                       cwd=ROOT, check=True, capture_output=True)
    sides = {"this": ROOT, "peer": peer}
    print(f"ab_events: this = {ROOT} (working tree), peer = {args.peer}; in {tmp}")
    study, tile, noise = jobs[0]
    for label, side in sides.items():          # compile or load each side's kernels
        run_job(side, study, tile, noise, tmp / f"warm_{label}.nc")
    print(_uptime(), flush=True)
    total = {label: [0.0, 0.0] for label in sides}
    for rep in range(args.repeats):
        order = list(sides) if rep % 2 == 0 else list(sides)[::-1]
        for study, tile, noise in jobs:
            for label in order:
                process, call = run_job(sides[label], study, tile, noise,
                                        tmp / f"{label}_{study}_{tile}.nc")
                total[label][0] += process
                total[label][1] += call
                print(f"repeat {rep} {study} tile {tile} {label:>4}: process {process:6.2f} "
                      f"CPU-s, call {call:6.2f}", flush=True)
    print(_uptime())
    differ = []
    for study, tile, _ in jobs:
        try:
            xr.testing.assert_identical(_data(tmp / f"this_{study}_{tile}.nc"),
                                        _data(tmp / f"peer_{study}_{tile}.nc"))
        except AssertionError as err:
            differ.append(f"{study} tile {tile}: {str(err)[:400]}")
    for label, (process, call) in total.items():
        print(f"{label:>4}: process {process / args.repeats:7.2f} CPU-s a repeat, "
              f"call {call / args.repeats:7.2f}")
    print(f"ratio this / peer: process {total['this'][0] / total['peer'][0]:.3f}, "
          f"call {total['this'][1] / total['peer'][1]:.3f}")
    print("tiles: " + ("identical to the peer's" if not differ
                       else "DIFFER\n" + "\n".join(differ)))
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
