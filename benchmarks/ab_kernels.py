"""A/B of the kernels: an old build of `vibroimpact` against this tree, in the same run.

Cases, each through the public entry points only (so any internal layout of the kernels works):

- ``simulate`` on one seeded record of N(0,1) force samples (default 1e6 steps), dt = 0.1,
  zeta = 0.05, eps = 0.5, at delta = 0.5 (free flights, a few impacts) and at delta = -0.5
  (chatter and sticking: the event location and the slow step);
- ``periodic_orbits`` over a grid: (1/1), (2/1), (1/2), (3/1) at 1/beta in {0.8, 1.4, 2.2}
  and delta in {-0.5, 0.3, 1.2} (the m = 1 closed form, the m = 2 and m = 3 scans, Newton).

- old = ``--old-src DIR`` (a ``src`` directory holding ``vibroimpact``, e.g. a clone of the
  revision before the change) or ``--base REV`` (``git archive REV src/vibroimpact`` of this
  repository, default HEAD);
- new = this tree's ``src``.

Every measurement runs in a fresh subprocess with PYTHONPATH = the build's ``src`` (checked:
every ``vibroimpact`` module must come from there), NUMBA_NUM_THREADS = 1 and a NUMBA_CACHE_DIR
of its own per build. A child warms every case up with one call (compiling on the build's
first child), then times ``--repeats`` calls of each (time.perf_counter, and
time.process_time: on a shared machine the CPU time shows what the wall time would be without
the neighbours). Children alternate old new, new old, ... (``--rounds``) to cancel drift.
Printed per case: the best and the median wall and CPU time of each build over all its timed
calls, and the ratios new/old; nothing is asserted.

Usage::

    python benchmarks/ab_kernels.py --old-src /tmp/old-clone/src
    python benchmarks/ab_kernels.py --base HEAD~3 --rounds 6
    python benchmarks/ab_kernels.py --quick               # 2e5 steps, 2 rounds
"""
import argparse
import json
import os
from pathlib import Path
import statistics
import subprocess
import sys
import tempfile
import time

from ab_no_impact import extract  # git archive REV src/vibroimpact (this folder is on sys.path)

ZETA, EPS, DT = 0.05, 0.5, 0.1
SEED = 19740072  # as benchmarks/bench_simulate.py
SIM_DELTAS = (0.5, -0.5)
ORBIT_TYPES = ((1, 1), (2, 1), (1, 2), (3, 1))
ORBIT_INV_BETA = (0.8, 1.4, 2.2)
ORBIT_DELTAS = (-0.5, 0.3, 1.2)
REPO = Path(__file__).resolve().parent.parent


# ---------------------------------------------------------------------------- child
def child(src, n_steps, repeats):
    """Runs in the subprocess: check the build, time every case, print one JSON line."""
    pkg_dir = Path(src).resolve() / "vibroimpact"
    import numpy as np
    import vibroimpact
    from vibroimpact import periodic_orbits, simulate

    noise = np.random.default_rng(SEED).standard_normal(n_steps + 1)

    def orbit_grid():
        return sum(len(periodic_orbits(m, n, 1.0 / ib, d, ZETA, EPS))
                   for m, n in ORBIT_TYPES for ib in ORBIT_INV_BETA for d in ORBIT_DELTAS)

    cases = {f"simulate delta = {d:+.1f}":
             (lambda d=d: simulate(ZETA, EPS, d, noise, DT).n_impacts) for d in SIM_DELTAS}
    cases["periodic_orbits grid"] = orbit_grid
    out = dict(file=vibroimpact.__file__, cases={})
    for name, fn in cases.items():
        t0 = time.perf_counter()
        count = fn()
        warm = time.perf_counter() - t0
        wall, cpu = [], []
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            fn()
            wall.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        out["cases"][name] = dict(count=count, warmup_s=warm, wall=wall, cpu=cpu)
    stray = [f"{n}: {m.__file__}" for n, m in sorted(sys.modules.items())
             if n.split(".")[0] == "vibroimpact" and getattr(m, "__file__", None)
             and pkg_dir not in Path(m.__file__).resolve().parents]
    if stray:
        raise SystemExit("FAIL: vibroimpact modules from elsewhere: " + "; ".join(stray))
    print(json.dumps(out))


# ---------------------------------------------------------------------------- parent
def run_child(build, n_steps, repeats):
    env = dict(os.environ, PYTHONPATH=str(build["src"]), NUMBA_NUM_THREADS="1",
               NUMBA_CACHE_DIR=str(build["cache"]))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", str(build["src"]),
           "--steps", str(n_steps), "--repeats", str(repeats)]
    proc = subprocess.run(cmd, env=env, cwd=build["cache"], capture_output=True, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        raise SystemExit(f"FAIL: child of build {build['label']} exited with {proc.returncode}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--old-src", help="the old build's src directory")
    parser.add_argument("--base", default="HEAD",
                        help="without --old-src: git revision of the old build (default HEAD)")
    parser.add_argument("--rounds", type=int, help="old/new child pairs (default 6, quick 2)")
    parser.add_argument("--steps", type=float, help="force steps (default 1e6, quick 2e5)")
    parser.add_argument("--repeats", type=int, default=5, help="timed calls per case and child")
    parser.add_argument("--quick", action="store_true", help="2e5 steps, 2 rounds")
    parser.add_argument("--child", metavar="SRC", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    n_steps = int(args.steps or (2e5 if args.quick else 1e6))
    if args.child:
        child(args.child, n_steps, args.repeats)
        return
    rounds = args.rounds or (2 if args.quick else 6)
    start = time.perf_counter()
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="ab_kernels-") as tmp:
        tmp = Path(tmp)
        old_src = Path(args.old_src).resolve() if args.old_src else extract(args.base,
                                                                            tmp / "old")
        builds = {key: dict(label=key, src=src, cache=tmp / f"cache-{key}")
                  for key, src in (("old", old_src), ("new", REPO / "src"))}
        for build in builds.values():
            build["cache"].mkdir()
        print(f"A/B of the kernels: old = {old_src}"
              + ("" if args.old_src else f" (git {args.base})") + f", new = {REPO / 'src'}")
        print(f"simulate: {n_steps:.3g} N(0,1) steps (seed {SEED}), dt = {DT}, zeta = {ZETA}, "
              f"eps = {EPS}; periodic_orbits: {len(ORBIT_TYPES)} types x "
              f"{len(ORBIT_INV_BETA) * len(ORBIT_DELTAS)} points; {rounds} rounds x "
              f"{args.repeats} timed calls per build and case after a warm-up call; "
              f"NUMBA_NUM_THREADS = 1; load average {load:.1f} on {os.cpu_count()} CPUs")
        runs = {"old": [], "new": []}
        for i in range(rounds):
            for key in (("old", "new") if i % 2 == 0 else ("new", "old")):
                out = run_child(builds[key], n_steps, args.repeats)
                runs[key].append(out)
                best = ", ".join(f"{min(c['wall']):.3f}" for c in out["cases"].values())
                print(f"  round {i + 1} {key}: best s per case {best}", flush=True)
    for clock in ("wall", "cpu"):
        print(f"\n== {clock} seconds per call (best and median over {rounds} x {args.repeats} "
              "calls) ==")
        print(f"{'case':<24} {'old best':>9} {'new best':>9} {'new/old':>8} {'old med':>9} "
              f"{'new med':>9} {'new/old':>8}  result (old, new)")
        for name in runs["old"][0]["cases"]:
            times = {k: [t for r in runs[k] for t in r["cases"][name][clock]] for k in runs}
            counts = {k: {r["cases"][name]["count"] for r in runs[k]} for k in runs}
            b_old, b_new = min(times["old"]), min(times["new"])
            m_old, m_new = statistics.median(times["old"]), statistics.median(times["new"])
            print(f"{name:<24} {b_old:>9.4f} {b_new:>9.4f} {b_new / b_old:>8.3f} "
                  f"{m_old:>9.4f} {m_new:>9.4f} {m_new / m_old:>8.3f}  "
                  f"{sorted(counts['old'])}, {sorted(counts['new'])}")
    print("(result: impacts of simulate, orbits found by the grid: equal when the builds agree)")
    print(f"total {time.perf_counter() - start:.0f} s; load average {load:.1f} at start, "
          f"{os.getloadavg()[0]:.1f} at end")


if __name__ == "__main__":
    main()
