"""Benchmark of the periodic-orbit solver: cold calls per type and the full default map.

Usage: ``python benchmarks/bench_orbits.py [--quick]`` (``--quick``: every 4th 1/beta row).

Prints, per (m/n) type, the median wall time of one cold ``periodic_orbits`` call (no branch
to follow; numba already compiled) over a spread of parameter points, against a peer measured
in the same run: scipy's ``brentq`` on a 2000-point scan of the (1/n) residual in the impact
phase (the textbook approach, for m = 1 only), and the ratio. Then the time of the full
default ``orbit_map`` (1/beta 0.2..3.0 and delta -1.5..3.0 in steps of 0.02, types (1/1),
(2/1), (1/2), (1/3), (3/1)) with the numba threads available (``NUMBA_NUM_THREADS``).
No assertions.
"""
import math
import sys
import time

import numba
import numpy as np
from scipy.optimize import brentq

from vibroimpact.orbits import orbit_map, periodic_orbits

ZETA, EPS = 0.05, 0.5
TYPES = [(1, 1), (2, 1), (1, 2), (1, 3), (3, 1)]
POINTS = [(ib, d) for ib in (0.3, 0.8, 1.2, 2.0, 2.8) for d in (-1.0, -0.3, 0.0, 0.5, 1.5)]


def peer_m1(n, beta, delta, zeta=ZETA, eps=EPS, nscan=2000):
    """(1/n) impact phases by a dense phase scan + scipy brentq on the velocity mismatch."""
    w = math.sqrt(1 - zeta ** 2)
    den = (1 - beta ** 2) ** 2 + (2 * zeta * beta) ** 2
    p, q = (1 - beta ** 2) / den, -2 * zeta * beta / den
    z = 2 * math.pi * n / beta

    def xv(ta, u, s):
        t = ta + s
        y0 = delta - (p * np.sin(beta * ta) + q * np.cos(beta * ta))
        v0 = -eps * u - beta * (p * np.cos(beta * ta) - q * np.sin(beta * ta))
        c2 = (v0 + zeta * y0) / w
        e, cs, sn = np.exp(-zeta * s), np.cos(w * s), np.sin(w * s)
        x = p * np.sin(beta * t) + q * np.cos(beta * t) + e * (y0 * cs + c2 * sn)
        v = (beta * (p * np.cos(beta * t) - q * np.sin(beta * t))
             + e * ((-zeta * y0 + w * c2) * cs + (-zeta * c2 - w * y0) * sn))
        return x, v

    def resid(ta):
        x0 = xv(ta, 0.0, z)[0]
        u = (delta - x0) / (xv(ta, 1.0, z)[0] - x0)
        return xv(ta, u, z)[1] - u

    taus = np.linspace(0, 2 * math.pi / beta, nscan + 1)
    r = resid(taus)
    return [brentq(resid, taus[i], taus[i + 1], xtol=1e-14)
            for i in np.nonzero(r[:-1] * r[1:] < 0)[0]]


def median_time(fn, repeat=3):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def main():
    quick = "--quick" in sys.argv
    t = time.perf_counter()
    for m, n in TYPES:
        periodic_orbits(m, n, 1.0, 0.0, ZETA, EPS)
    orbit_map([1.0], [0.0], TYPES, ZETA, EPS)
    print(f"first calls (numba cache load or compile): {time.perf_counter() - t:.2f} s")
    print(f"{'type':>6} {'median cold call':>17} {'max':>9} {'peer (brentq scan)':>19} "
          f"{'ratio':>7}")
    for m, n in TYPES:
        own = [median_time(lambda: periodic_orbits(m, n, 1 / ib, d, ZETA, EPS))
               for ib, d in POINTS]
        line = f"({m}/{n}) {np.median(own) * 1e3:14.3f} ms {max(own) * 1e3:6.2f} ms"
        if m == 1:
            peer = [median_time(lambda: peer_m1(n, 1 / ib, d), 1) for ib, d in POINTS]
            line += f" {np.median(peer) * 1e3:16.3f} ms {np.median(peer) / np.median(own):7.1f}"
        else:
            line += f" {'(no peer)':>19}"
        print(line)
    inv_beta = np.round(np.arange(0.2, 3.0 + 1e-9, 0.02), 10)
    delta = np.round(np.arange(-1.5, 3.0 + 1e-9, 0.02), 10)
    if quick:
        inv_beta = inv_beta[::4]
    t = time.perf_counter()
    r = orbit_map(inv_beta, delta, TYPES, ZETA, EPS)
    elapsed = time.perf_counter() - t
    print(f"orbit_map {inv_beta.size} x {delta.size} points x {len(TYPES)} types: "
          f"{elapsed:.2f} s on {numba.get_num_threads()} thread(s)")
    for k, (m, n) in enumerate(TYPES):
        counts = np.bincount(r["reason"][k].ravel(), minlength=4)
        print(f"  ({m}/{n}) cells: stable {counts[0]}, no solution {counts[1]}, "
              f"inadmissible only {counts[2]}, unstable only {counts[3]}")


if __name__ == "__main__":
    main()
