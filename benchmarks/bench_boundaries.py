"""Benchmark of the exact stable-domain boundaries of Fig. 16 (``domain_boundaries``).

Usage: ``python benchmarks/bench_boundaries.py [map.npz]``.

Computes the default Fig. 16 map once (zeta 0.05, eps 0.5, 1/beta 0.2..3.0 x delta -1.5..3.0
on 141 x 226, types (1/1), (2/1), (1/2), (1/3), (3/1); or loads it from an ``.npz`` written
by a previous run), warms the kernels up on (1/1), then traces every type's boundary curves
with ``seed_map`` = that map and prints, per type, the number of curves, of points and of
codimension-two points, the wall time, and the total against the 10 s target (the seed map
not counted). Threads: ``NUMBA_NUM_THREADS`` (the map only; the tracing is serial).
No assertions.
"""
import os
import sys
import time

import numpy as np

from vibroimpact.orbits import domain_boundaries, orbit_map

ZETA, EPS = 0.05, 0.5
TYPES = [(1, 1), (2, 1), (1, 2), (1, 3), (3, 1)]
TARGET = 10.0


def seed_map(path=None):
    if path and os.path.exists(path):
        return dict(np.load(path))
    t0 = time.perf_counter()
    mp = orbit_map(np.linspace(0.2, 3.0, 141), np.linspace(-1.5, 3.0, 226), types=TYPES,
                   zeta=ZETA, eps=EPS)
    print(f"seed map (not counted): {time.perf_counter() - t0:.1f} s")
    if path:
        np.savez(path, **mp)
    return mp


def main():
    mp = seed_map(sys.argv[1] if len(sys.argv) > 1 else None)
    domain_boundaries(1, 1, ZETA, EPS, seed_map=mp)          # compile / load the kernels
    total = 0.0
    print(f"{'type':>6} {'curves':>6} {'points':>7} {'codim2':>6} {'time (s)':>9}  kinds")
    for m, n in TYPES:
        t0 = time.perf_counter()
        res = domain_boundaries(m, n, ZETA, EPS, seed_map=mp)
        dt = time.perf_counter() - t0
        total += dt
        kinds = {}
        for c in res:
            kinds[c.kind] = kinds.get(c.kind, 0) + 1
        npts = sum(len(c) for c in res)
        print(f"{f'({m}/{n})':>6} {len(res):>6} {npts:>7} {len(res.codimension_two):>6} "
              f"{dt:>9.2f}  {kinds}")
    verdict = "within" if total < TARGET else "ABOVE"
    print(f"total {total:.2f} s: {verdict} the {TARGET:.0f} s target")


if __name__ == "__main__":
    main()
