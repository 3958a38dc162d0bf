"""The Fig. 15 map job at its floor (issue 37): this tree against named revisions, in one run.

Two measurements, nothing asserted:

1. The map job: every cell of a built map (``--dataset``, default
   ``results/datasets/motion_map_map.nc``) over its noise record (``--noise``), split over
   ``--procs`` processes (default 2, as the workflow runs the map's tiles), each process running
   ``benchmarks/map_cells_cpu.py`` (fresh interpreter, NUMBA_NUM_THREADS = 1, the build's own
   NUMBA_CACHE_DIR, one warm-up cell, then its share of the cells). Builds: this tree's ``src``,
   the merge base with ``--main`` (default ``origin/main``) and the peer ``--peer`` (default
   3091f6a, the revision the issue measured at 36 s), each ``git archive REV src/vibroimpact``
   as ``benchmarks/ab_kernels.py`` does. Printed per build: the wall time of the whole job
   (start-up, compile or cache load, warm-up, cells), the summed CPU time of the cells
   (time.process_time, less disturbed by the neighbours on a shared machine), the ratios to
   this tree, and the largest difference of the stored probabilities to this tree's.
2. The step without impact: ``vibroimpact.simulate`` at delta = 100 (no impact) over a seeded
   N(0,1) record against a closed-form prototype, a minimal numba loop (the 2x2 propagator plus
   the two force terms of a linearly interpolated force per step, nothing else), in turn in one
   process (``--rounds`` alternations, best of each): ns per step and their ratio.

Measured 2026-11-27 01:42-01:48 UTC (load average 5 on 2 cores, shared machine), all 5187
cells of the default build's map, this tree = the merge base f02e60b (no kernel change yet):
this tree 133.6 s wall / 71.0 s cell CPU; merge base 136.6 / 72.8; peer 3091f6a 75.1 / 49.4
(0.69 x the CPU: the issue-33 hop check and two extra grouping rules per cell cost +44 %);
max |dP| to the peer 0.037 (the physical collision rule of issue 33, expected). Step without
impact: simulator 3.97 ns, prototype 4.33 ns (0.92 x; an earlier 2e6-step run gave 1.23 x:
noisy at this load).

Usage::

    python benchmarks/bench_map_floor.py --noise results/noise/harmonic_input.nc
    python benchmarks/bench_map_floor.py --stride 4 --no-main     # a quarter of the cells
    python benchmarks/bench_map_floor.py --only-step
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread, as the jobs

import argparse
import json
from pathlib import Path
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
from ab_no_impact import extract  # noqa: E402  (git archive REV src/vibroimpact)

ZETA, EPS, DT, SEED = 0.05, 0.5, 0.1, 19740072  # as benchmarks/ab_kernels.py


# ---------------------------------------------------------------------------- 1. the map job
def map_job(dataset, noise_path, stride):
    """The cells and the motion_map_cell keywords of a built map (as bench_map.py reads them)."""
    from bench_map import load_map
    ds, kw, _ = load_map(dataset)
    cells = [(float(b), float(d)) for b in ds.inv_beta.values for d in ds.delta.values]
    kw = {k: (list(map(list, v)) if k == "motions" else v) for k, v in kw.items()}
    return cells[::stride], kw


def run_build(label, src, cells, kw, noise_path, procs, tmp):
    """All cells on ``procs`` concurrent processes; returns wall, CPU and probabilities."""
    cache = Path(tmp) / f"cache-{label}"
    cache.mkdir(exist_ok=True)
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS="1",
               NUMBA_CACHE_DIR=str(cache))
    script = str(REPO / "benchmarks" / "map_cells_cpu.py")
    shares = [list(range(i, len(cells), procs)) for i in range(procs)]
    start = time.perf_counter()
    running = []
    for share in shares:
        job = json.dumps(dict(noise=str(noise_path), kwargs=kw, cells=[cells[i] for i in share]))
        p = subprocess.Popen([sys.executable, script], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                             cwd=tmp)
        running.append((share, p, job))
    outs = [(share, p.communicate(job)) + (p.returncode,) for share, p, job in running]
    wall = time.perf_counter() - start
    cpu = np.zeros(len(cells))
    prob = [None] * len(cells)
    for share, (out, err), code in outs:
        if code != 0:
            sys.stderr.write(err)
            raise SystemExit(f"FAIL: build {label} exited with {code}")
        res = json.loads(out)
        for k, i in enumerate(share):
            cpu[i] = res["cpu"][k]
            prob[i] = res["probability"][k]
    return dict(wall=wall, cpu=cpu, prob=np.array(prob, dtype=float))


def merge_base(main):
    return subprocess.run(["git", "-C", str(REPO), "merge-base", "HEAD", main], check=True,
                          capture_output=True, text=True).stdout.strip()


# ---------------------------------------------------------------------------- 2. the step
def prototype_kernel():
    """A minimal numba loop: x_{k+1} = A x_k + g0 f_k + g1 f_{k+1}, nothing else."""
    import numba

    @numba.njit(cache=False)
    def run(a, g0, g1, f):
        x, v = 0.0, 0.0
        acc = 0.0
        for k in range(f.size - 1):
            x, v = (a[0, 0] * x + a[0, 1] * v + g0[0] * f[k] + g1[0] * f[k + 1],
                    a[1, 0] * x + a[1, 1] * v + g0[1] * f[k] + g1[1] * f[k + 1])
            acc += x
        return acc
    return run


def propagator(zeta, dt):
    """A and the force vectors of x'' + 2 zeta x' + x = f(t), f linear over a step: the
    exponential of the augmented matrix (state, f, f')."""
    from scipy.linalg import expm
    m = np.zeros((4, 4))
    m[0, 1], m[1, 0], m[1, 1], m[1, 2], m[2, 3] = 1.0, -1.0, -2.0 * zeta, 1.0, 1.0 / dt
    e = expm(m * dt)
    a = e[:2, :2].copy()
    g1 = e[:2, 3].copy()                  # response to the ramp f_{k+1} - f_k
    g0 = e[:2, 2].copy() - g1             # response to f_k (constant minus ramp)
    return a, g0, g1


def step_ratio(n_steps, rounds):
    from vibroimpact import simulate
    noise = np.random.default_rng(SEED).standard_normal(n_steps + 1)
    a, g0, g1 = propagator(ZETA, DT)
    proto = prototype_kernel()
    proto(a, g0, g1, noise[:100])
    simulate(ZETA, EPS, 100.0, noise[:1001], DT)
    best = dict(simulator=np.inf, prototype=np.inf)
    for _ in range(rounds):
        for name, fn in (("simulator", lambda: simulate(ZETA, EPS, 100.0, noise, DT)),
                         ("prototype", lambda: proto(a, g0, g1, noise))):
            c0 = time.process_time()
            fn()
            best[name] = min(best[name], time.process_time() - c0)
    ns = {k: v / n_steps * 1e9 for k, v in best.items()}
    print(f"\n== 2. Step without impact, delta = 100, {n_steps:.0e} steps, best of {rounds} "
          f"alternations (CPU) ==")
    for k, v in ns.items():
        print(f"{k:<10} {v:6.2f} ns/step")
    print(f"ratio simulator / prototype: {ns['simulator'] / ns['prototype']:.2f}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dataset", default=str(REPO / "results/datasets/motion_map_map.nc"))
    p.add_argument("--noise", default=str(REPO / "results/noise/harmonic_input.nc"))
    p.add_argument("--peer", default="3091f6a")
    p.add_argument("--main", default="origin/main")
    p.add_argument("--no-main", action="store_true", help="skip the merge base")
    p.add_argument("--procs", type=int, default=2)
    p.add_argument("--stride", type=int, default=1, help="every this-many-th cell (default all)")
    p.add_argument("--steps", type=float, default=2e7)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--only-step", action="store_true")
    args = p.parse_args(argv)
    print(f"load average {os.getloadavg()} on {os.cpu_count()} CPUs")
    if not args.only_step:
        cells, kw = map_job(args.dataset, args.noise, args.stride)
        print(f"\n== 1. The map job: {len(cells)} cells of {args.dataset} on {args.procs} "
              f"processes ==")
        with tempfile.TemporaryDirectory() as tmp:
            builds = [("this tree", REPO / "src")]
            if not args.no_main:
                base = merge_base(args.main)
                builds.append((f"merge base {base[:7]}",
                               extract(base, Path(tmp) / "base")))
            builds.append((f"peer {args.peer}", extract(args.peer, Path(tmp) / "peer")))
            res = {label: run_build(f"b{i}", src, cells, kw, args.noise, args.procs, tmp)
                   for i, (label, src) in enumerate(builds)}
        ref = res["this tree"]
        print(f"{'build':<22} {'wall s':>8} {'cell CPU s':>11} {'wall/this':>10} "
              f"{'CPU/this':>9} {'max |dP| vs this':>17}")
        for label, r in res.items():
            dp = np.nanmax(np.abs(r["prob"] - ref["prob"]))
            print(f"{label:<22} {r['wall']:8.2f} {r['cpu'].sum():11.2f} "
                  f"{r['wall'] / ref['wall']:10.2f} {r['cpu'].sum() / ref['cpu'].sum():9.2f} "
                  f"{dp:17.3g}")
    step_ratio(int(args.steps), args.rounds)


if __name__ == "__main__":
    main()
