"""Wall time of `attractor_map` on the default Fig. 15 grid (57 x 91 cells, 64 starts).

Targets: the whole map (basins) in 60 s and the Lyapunov part in 30 s on 2 threads. The
exponents come from the same trajectories (the tangent product runs along them), so the two are
not separable; the kernel's time is split into the solver orbits and the starts.

    PYTHONPATH=src python benchmarks/bench_attractors.py [--threads 2] [--starts 64] [--peer 200]

The peer: one public ``vibroimpact.simulate`` call per start, to the cap, on a sample of
starts, extrapolated (what a user would write without this function).
"""
import argparse
import time

import numba
import numpy as np

from vibroimpact.attractors import api as attractors
from vibroimpact.attractors import kernels as ak


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--starts", type=int, default=64)
    parser.add_argument("--max-time", type=float, default=attractors.DEFAULT_MAX_TIME)
    parser.add_argument("--peer", type=int, default=200,
                        help="starts run through vibroimpact.simulate as the peer (0: none)")
    args = parser.parse_args()
    numba.set_num_threads(args.threads)
    inv_beta = np.round(np.arange(0.2, 3.0 + 1e-9, 0.05), 10)
    delta = np.round(np.arange(-1.5, 3.0 + 1e-9, 0.05), 10)
    # compile (or load from the cache) outside the timing
    attractors.attractor_map(inv_beta[:1], delta[:1], 0.05, 0.5, n_starts=2,
                             max_time=args.max_time)
    checked = attractors._validate(inv_beta, delta, 0.05, 0.5, attractors.DEFAULT_TYPES,
                                   args.starts, (0.0, 4.0), (-4.0, 4.0), args.max_time,
                                   attractors.DEFAULT_MATCH_TOL, 0)
    t0 = time.perf_counter()
    raw = attractors._simulate_starts(*checked)
    wall = time.perf_counter() - t0
    cls = raw["outi"][:, ak.I_CLASS]
    n = cls.size
    print(f"grid {inv_beta.size} x {delta.size} cells, {args.starts} starts, "
          f"{args.threads} threads, max_time {args.max_time:g}")
    print(f"wall time {wall:.1f} s against the 60 s target "
          f"(solver orbits {raw['seconds_orbits']:.1f} s, starts with their exponents "
          f"{raw['seconds_starts']:.1f} s: {1e6 * raw['seconds_starts'] * args.threads / n:.0f}"
          f" us per start per thread)")
    print("Lyapunov part: computed along the same trajectories (tangent products at the "
          "impacts), not separable; its share is inside the starts' time")
    for c, name in enumerate(attractors.CLASSES):
        print(f"  {name:15s} {np.count_nonzero(cls == c) / n:7.3%}")
    listed = np.count_nonzero(raw["outi"][:, ak.I_MOTION] >= 0) / n
    settled = np.count_nonzero(np.isfinite(raw["outf"][:, ak.F_SETTLE])) / n
    failed = np.count_nonzero(raw["outi"][:, ak.I_STATUS]) / n
    print(f"settled {settled:.3%} (on a listed solver orbit {listed:.3%}), "
          f"other {1 - listed:.3%}, failed {failed:.3%}")
    if args.peer:
        peer(args, raw, n, wall)


def peer(args, raw, n, wall):
    """What a user of the public API would write: one `vibroimpact.simulate` call per start
    (each to the cap, noise=None, no settling test, no tangent dynamics), on ``--peer``
    starts drawn over the plane, extrapolated to every start on ``--threads`` processes."""
    from vibroimpact import simulate

    rng = np.random.default_rng(0)
    pick = rng.choice(n, size=args.peer, replace=False)
    inv_beta = np.round(np.arange(0.2, 3.0 + 1e-9, 0.05), 10)
    delta = np.round(np.arange(-1.5, 3.0 + 1e-9, 0.05), 10)
    nd = delta.size
    _, _, g, v0 = attractors.sobol_starts(args.starts, (0.0, 4.0), (-4.0, 4.0), 0)
    simulate(0.05, 0.5, 0.0, amplitude=1.0, beta=1.0, t_end=10.0)      # compiled
    t0 = time.perf_counter()
    for i in pick:
        cell, s = divmod(int(i), args.starts)
        ib, d = divmod(cell, nd)
        beta = 1.0 / inv_beta[ib]
        # simulate() starts at forcing phase 0 (the start's theta is not reproduced): what is
        # compared is the cost of running a start to the cap
        simulate(0.05, 0.5, delta[d], amplitude=1.0, beta=beta, x0=delta[d] - g[s],
                 v0=v0[s], t_end=args.max_time, dt=min(0.2, 2 * np.pi / beta / 16))
    per = (time.perf_counter() - t0) / args.peer
    total = per * n / args.threads
    print(f"peer: vibroimpact.simulate per start to the cap, {args.peer} starts: "
          f"{1e3 * per:.2f} ms each, {total:.0f} s extrapolated to {n} starts on "
          f"{args.threads} processes; attractor_map {wall:.1f} s: {total / wall:.0f} x faster")


if __name__ == "__main__":
    main()
