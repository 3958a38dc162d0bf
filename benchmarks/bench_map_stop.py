"""The Fig. 15 map cell's check schedule: where its records stop against the precision asked,
and what they cost, for two schedules in one run.

Every ``--stride``-th cell of a built map (``--dataset``, over its noise record ``--noise``)
runs ``vibroimpact.pipeline.cells.motion_map_cell`` with the map's arguments under each
schedule (``approach, approach_unswitched, min_growth``: the default one, and the peer
``--peer``, by default ``1.1,1.1,1.1``: each check at 1.1 times the predicted length, at least
1.1 times the last, the schedule before switching records approached from below). The
schedules run in turn, ``--rounds`` times, interleaved; the best CPU round of each is
printed. Per schedule: CPU (process time, one numba thread, kernels compiled and warmed
first), simulated time, checks per cell, cells at the cap, and the worst standard error at
the stop (median and 90th percentile over the cells that reached the target; the target is
the map's). Then the ratios, and the largest differences between the schedules'
probabilities in units of their standard errors (``|p_a - p_b| / max(se_a, se_b)``: the
records overlap, one a prefix of the other, so this is not a test of independent estimates;
it shows how far a change of schedule moves each probability). Nothing is asserted.

Usage::

    python benchmarks/bench_map_stop.py --dataset results/datasets/motion_map_map.nc \\
        --noise results/noise/harmonic_input.nc --stride 8
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread, as the jobs

import argparse
import inspect
import time

import numpy as np

from bench_map import load_map
from vibroimpact.pipeline.cells import motion_map_cell
from vibroimpact.pipeline.io import read_noise

from cell_calls import call


KEYS = ("approach", "approach_unswitched", "min_growth")


def default_schedule():
    params = inspect.signature(motion_map_cell).parameters
    return tuple(params[k].default for k in KEYS)


def run(noise, dt, kwargs, cells, schedule):
    out = dict(cpu=0.0, simulated=0.0, checks=0, capped=0, worst=[], p=[], se=[])
    for inv_beta, delta in cells:
        start = time.process_time()
        cell = call(motion_map_cell, noise, dt, inv_beta, delta, **dict(zip(KEYS, schedule)),
                    **kwargs)
        out["cpu"] += time.process_time() - start
        out["simulated"] += cell["simulated_time"]
        out["checks"] += cell["n_checks"]
        worst = max(cell["stderr"].max(), cell["stick_stderr"].max())
        if cell["reached"]:
            out["worst"].append(worst)
        else:
            out["capped"] += 1
        out["p"].append(np.concatenate([cell["probability"], cell["stick_probability"]]))
        out["se"].append(np.concatenate([cell["stderr"], cell["stick_stderr"]]))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--dataset", default="results/datasets/motion_map_map.nc")
    ap.add_argument("--noise", default="results/noise/harmonic_input.nc")
    ap.add_argument("--stride", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--peer", default="1.1,1.1,1.1",
                    help="approach,approach_unswitched,min_growth of the peer")
    args = ap.parse_args()

    ds, kwargs, _ = load_map(args.dataset)
    noise, dt, _ = read_noise(args.noise)
    noise = np.asarray(noise[:], dtype=float)
    cells = [(float(a), float(b)) for a in ds["inv_beta"].values
             for b in ds["delta"].values][::args.stride]
    target = kwargs["target_stderr"]
    schedules = {"default": default_schedule(),
                 "peer": tuple(float(v) for v in args.peer.split(","))}
    # compile and warm the kernels on a busy cell before any timing
    call(motion_map_cell, noise, dt, 2.5, -1.0, **dict(kwargs, max_periods=50))
    best = {}
    for _ in range(args.rounds):
        for name, schedule in schedules.items():
            res = run(noise, dt, kwargs, cells, schedule)
            if name not in best or res["cpu"] < best[name]["cpu"]:
                best[name] = res
    print(f"{len(cells)} cells (every {args.stride}th of {args.dataset}), target {target:g}, "
          f"best CPU of {args.rounds} interleaved rounds")
    print(f"{'schedule':24s} {'CPU s':>7s} {'simulated':>10s} {'checks':>7s} {'capped':>6s} "
          f"{'worst/target median':>20s} {'p90':>6s}")
    for name, schedule in schedules.items():
        r = best[name]
        w = np.array(r["worst"]) / target
        label = f"{name} ({', '.join(f'{v:g}' for v in schedule)})"
        print(f"{label:24s} {r['cpu']:7.2f} {r['simulated']:10.4g} "
              f"{r['checks'] / len(cells):7.2f} {r['capped']:6d} {np.median(w):20.3f} "
              f"{np.percentile(w, 90):6.3f}")
    a, b = best["default"], best["peer"]
    print(f"default / peer: CPU {a['cpu'] / b['cpu']:.3f}, simulated time "
          f"{a['simulated'] / b['simulated']:.3f}")
    pa, pb = np.array(a["p"]), np.array(b["p"])
    se = np.maximum(np.array(a["se"]), np.array(b["se"]))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(se > 0, np.abs(pa - pb) / se, np.where(pa == pb, 0.0, np.inf))
    print("largest |p_default - p_peer| / max(se) over cells and probabilities "
          "(3 motions, then their impact-stick variants):")
    for i in np.argsort(z, axis=None)[::-1][:5]:
        c, j = np.unravel_index(i, z.shape)
        print(f"  cell 1/beta={cells[c][0]:.2f} delta={cells[c][1]:+.2f} probability {j}: "
              f"{pa[c, j]:.4f} vs {pb[c, j]:.4f}, se {se[c, j]:.4f}: {z[c, j]:.2f}")
    print(f"share of probabilities within 1 se: {np.mean(z <= 1):.3f}, within 2: "
          f"{np.mean(z <= 2):.3f}, within 3: {np.mean(z <= 3):.3f}")


if __name__ == "__main__":
    main()
