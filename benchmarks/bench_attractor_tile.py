"""Where the attractor tile's time goes (rule ``solve_attractor_tile``, issue 37).

Runs the default harmonic entry's attractor map (config/config.yaml, ``orbits.harmonic``)
through the phases of `vibroimpact.attractors.attractor_map` and times each: the solver
orbits (``cell_orbits``), the starts (``run_starts``) and the reduction to the result; with
``--rows`` on every k-th 1/beta row only. The starts' CPU is split by what each start did:
the simulated time until it settled (or the cap), from the per-start records.

``--threads 1`` gives the serial cost; compare ``2 x wall(2 threads)`` with it for the
imbalance between the threads (under load the other agents' processes take a share too:
quote the load average).

    PYTHONPATH=src python benchmarks/bench_attractor_tile.py [--threads 2] [--rows 1] [--repeat 1]
"""
import argparse
import os
import resource
import time

import numba
import numpy as np
import yaml

from vibroimpact.attractors import api
from vibroimpact.attractors import kernels as ak
from vibroimpact.pipeline.study import grid_values


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--rows", type=int, default=1, help="every k-th 1/beta row only")
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args()
    numba.set_num_threads(args.threads)
    root = os.path.join(os.path.dirname(__file__), "..")
    with open(os.path.join(root, "config", "config.yaml")) as f:
        entry = yaml.safe_load(f)["orbits"]["harmonic"]
    block = entry["attractors"]
    inv_beta = grid_values(block["inv_beta"])[::args.rows]
    delta = grid_values(block["delta"])
    zeta, eps = float(entry["zeta"]), float(entry["eps"])
    types = [tuple(int(k) for k in t) for t in entry["types"]]
    opts = dict(n_starts=int(block["n_starts"]), gap=tuple(block["gap"]),
                velocity=tuple(block["velocity"]), max_time=float(block["max_time"]),
                seed=int(block["seed"]))
    api.attractor_map(inv_beta[:1], delta[:1], zeta, eps, types, **dict(opts, n_starts=2))
    inner = api._simulate_starts
    got = {}

    def timed(*a, **k):
        got["raw"] = inner(*a, **k)
        got["t"], got["cpu"] = time.perf_counter(), cpu()
        return got["raw"]

    api._simulate_starts = timed
    for _ in range(args.repeat):
        c0, t0 = cpu(), time.perf_counter()
        api.attractor_map(inv_beta, delta, zeta, eps, types, **opts)
        c1, t1 = cpu(), time.perf_counter()
        raw = got["raw"]
        n = raw["outi"].shape[0]
        print(f"{inv_beta.size} x {delta.size} cells x {opts['n_starts']} starts = {n}; "
              f"{args.threads} threads; load {os.getloadavg()[0]:.2f}")
        print(f"  wall {t1 - t0:.2f} s: orbits {raw['seconds_orbits']:.2f}, starts "
              f"{raw['seconds_starts']:.2f}, reduction {t1 - got['t']:.2f}; cpu {c1 - c0:.2f}"
              f" s (reduction {c1 - got['cpu']:.2f}); cpu / (threads x wall) "
              f"{(c1 - c0) / (args.threads * (t1 - t0)):.2f}")
    outf, outi = raw["outf"], raw["outi"]
    settled = np.isfinite(outf[:, ak.F_SETTLE])
    ran = np.where(settled, outf[:, ak.F_SETTLE], opts["max_time"])
    tf = 2 * np.pi * np.repeat(inv_beta, delta.size * opts["n_starts"])
    print(f"  settled {settled.mean():.3%}; simulated time: settled starts "
          f"{ran[settled].sum() / ran.sum():.1%} of it, unsettled (to the cap) "
          f"{ran[~settled].sum() / ran.sum():.1%}; forcing periods run "
          f"{(ran / tf).sum():.3g}")
    for c, name in enumerate(api.CLASSES):
        sel = outi[:, ak.I_CLASS] == c
        print(f"    {name:15s} starts {sel.mean():7.2%}  simulated time "
              f"{ran[sel].sum() / ran.sum():7.2%}")
    # the cost across the 1/beta rows (strided blocks share it; contiguous ones would not)
    per_row = (ran / tf).reshape(inv_beta.size, -1).sum(axis=1)
    print(f"  forcing periods per 1/beta row: min {per_row.min():.3g}, max "
          f"{per_row.max():.3g} (rows {inv_beta[np.argmin(per_row)]:g}, "
          f"{inv_beta[np.argmax(per_row)]:g})")


if __name__ == "__main__":
    main()
