"""Residence in a periodic motion of the default map's escape cells: splitting against brute
force with the same A and B (vibroimpact.rare.motions), value, interval and cost in sample steps.

    python benchmarks/rare_motions.py ams RMS [--motion 1/1|2/1|1/2]
                                           [--coordinate predicted|distance|forecast|margin]
                                           [--clones N] [--runs R] [--seed S]
    python benchmarks/rare_motions.py brute RMS [--motion M] [--periods P] [--seed S]

One process, one core; prints one line. The cells and the force are config/config.yaml's
studies.motion_map.escape (zeta 0.05, eps 0.5, amplitude 1, band_limited beta_c 4, dt 0.1):
(1/1) at 1/beta_f 1.1, delta 1; (2/1) at 1.1, 0.1; (1/2) at 1.2, 2.5. A: d < 0.25; B: d >= 0.9
at the strobes (energy metric), 1.2 for the (1/2) motion, whose deviations under noise are
larger.
"""
import argparse
import math
import time

from vibroimpact import noise
from vibroimpact.rare.motions import (MotionDynamics, PeriodicMotion, brute_force_residence,
                                      residence_time)

ZETA, EPS, AMP = 0.05, 0.5, 1.0
RADIUS_A = 0.25
#: motion -> (1/beta_f, delta, radius_b)
CELLS = {"1/1": (1.1, 1.0, 0.9), "2/1": (1.1, 0.1, 0.9), "1/2": (1.2, 2.5, 1.2)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mode", choices=["ams", "brute"])
    ap.add_argument("rms", type=float)
    ap.add_argument("--motion", choices=sorted(CELLS), default="1/1")
    ap.add_argument("--coordinate", choices=["predicted", "distance", "forecast", "margin"],
                    default="predicted")
    ap.add_argument("--clones", type=int, default=100)
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--periods", type=float, default=40000.0)
    ap.add_argument("--seed", type=int, default=7)
    a = ap.parse_args()
    inv_beta, delta, radius_b = CELLS[a.motion]
    m, n = (int(v) for v in a.motion.split("/"))
    orbit = PeriodicMotion(ZETA, EPS, delta, 1.0 / inv_beta, AMP, (m, n))
    spec = noise.NoiseSpec("band_limited", a.rms, 0.1, 4.0)
    dyn = MotionDynamics(ZETA, EPS, delta, 1.0 / inv_beta, AMP, spec, orbit, radius_a=RADIUS_A,
                         radius_b=radius_b,
                         coordinate=None if a.coordinate == "distance" else a.coordinate)
    t = time.perf_counter()
    if a.mode == "ams":
        r = residence_time(dyn, n_clones=a.clones, n_runs=a.runs, seed=a.seed)
        print(f"ams ({a.motion}) rms={a.rms} coordinate={a.coordinate} n={a.clones} R={a.runs} "
              f"seed={a.seed}: T = {r.time:.4g} +- {r.time_se:.2g} periods, p = "
              f"{r.probability:.3g} +- {r.probability_se:.2g}, extinct runs "
              f"{sum(x.extinct for x in r.runs)}, steps {r.n_steps}, "
              f"{time.perf_counter() - t:.1f} s")
    else:
        times, steps = brute_force_residence(dyn, n_periods=a.periods, seed=a.seed)
        se = times.std(ddof=1) / math.sqrt(times.size)
        print(f"brute ({a.motion}) rms={a.rms} periods={a.periods:g} seed={a.seed}: "
              f"T = {times.mean():.4g} +- {se:.2g} periods over {times.size} residences, "
              f"steps {steps}, {time.perf_counter() - t:.1f} s")


if __name__ == "__main__":
    main()
