"""Cost of a clearance: the two-wall simulator against the one-wall simulator, in one run.

Cases (each through the public ``vibroimpact.simulate``; one seeded record of N(0, rms^2)
samples, dt = 0.1, zeta = 0.05, eps = 0.5):

- ``free``: no wall reachable (one wall at delta = 1e6; two walls at 1e6 and -1e6): the
  cost of a sample step, where the second wall adds one bound to the exclusion test;
- ``impacts``: a wall at delta = 0.3 (one wall) against stops at +-0.3 (two walls, gap 0.6):
  the cost per impact, ``(t - n_steps t_free) / n_impacts`` with the matching ``free`` cost
  per step taken out.

Cases alternate one wall, two walls, ... (``--rounds``) in this process, each timed by
``time.process_time`` (CPU: on a shared machine it shows what the wall time would be without
the neighbours) after a warm-up call that compiles. Printed: the median per step and per
impact of each, and the ratios two/one. Nothing is asserted.

Usage::

    python benchmarks/bench_two_walls.py                 # 2e6 samples, 5 rounds
    python benchmarks/bench_two_walls.py --samples 1e7 --rounds 7
"""
import argparse
import os
import statistics
import time

import numpy as np

from vibroimpact import simulate

CASES = {
    ("free", 1): dict(delta=1e6),
    ("free", 2): dict(delta=1e6, gap=2e6),
    ("impacts", 1): dict(delta=0.3),
    ("impacts", 2): dict(delta=0.3, gap=0.6),
}


def _time(r, kw):
    t0 = time.process_time()
    res = simulate(0.05, 0.5, noise=r, dt=0.1, **kw)
    return time.process_time() - t0, res.n_steps, res.n_impacts


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=float, default=2e6)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--rms", type=float, default=0.5)
    args = parser.parse_args(argv)
    r = args.rms * np.random.default_rng(20261127).standard_normal(int(args.samples) + 1)
    for kw in CASES.values():
        simulate(0.05, 0.5, noise=r[:1001], dt=0.1, **kw)     # compile
    runs = {key: [] for key in CASES}
    for _ in range(args.rounds):
        for key, kw in CASES.items():
            runs[key].append(_time(r, kw))
    med = {key: statistics.median(t for t, _, _ in v) for key, v in runs.items()}
    steps = {key: v[0][1] for key, v in runs.items()}
    imps = {key: v[0][2] for key, v in runs.items()}
    print(f"{int(args.samples):.3g} samples of N(0, {args.rms}^2), dt = 0.1, zeta = 0.05, "
          f"eps = 0.5; {args.rounds} rounds; load average {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} CPUs")
    print(f"{'case':<10} {'walls':>5} {'impacts':>9} {'ns/step':>9} {'ns/impact':>10}")
    per_step = {}
    per_impact = {}
    for (case, walls), t in med.items():
        per_step[case, walls] = 1e9 * t / steps[case, walls]
        line = f"{case:<10} {walls:>5} {imps[case, walls]:>9} {per_step[case, walls]:>9.2f}"
        if case == "impacts":
            free = med["free", walls] / steps["free", walls]
            per_impact[walls] = 1e9 * (t - free * steps[case, walls]) / imps[case, walls]
            line += f" {per_impact[walls]:>10.0f}"
        print(line)
    print(f"two/one: per free step {per_step['free', 2] / per_step['free', 1]:.3f}, "
          f"per impact {per_impact[2] / per_impact[1]:.3f}")


if __name__ == "__main__":
    main()
