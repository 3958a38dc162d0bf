"""Run time and accuracy of `vibroimpact.simulate` against peers measured in the same run.

Prints, for one seeded record of Gaussian force samples (unit variance, dt = 0.1, linear in
between; zeta = 0.05, eps = 0.5, start at rest at min(0, delta)):

1. throughput on the long record: ns per sample step with no impact reachable, ns per impact
   (delta = 0), cost per unit of simulated time for each delta, and the floor: the bare
   dependent 2x2 recurrence with forcing terms and no wall;
2. a work-precision table (`vibroimpact.validation.work_precision`, the same measurement as the
   workflow's results/figures/work_precision.png) for delta in {1, 0, -0.5}: the simulator,
   scipy's solve_ivp (RK45, DOP853, LSODA; restarted at every force sample and after every
   impact, atol = rtol) at rtol 1e-3 ... 1e-12, numba RK4 with event location at 1 ... 64
   steps per sample, and numba RK4 that clamps x to the wall (peers in
   `vibroimpact.validation.peers`). Error = max over the first N comparable impacts (chatter
   tails excluded) of |impact time error| and |relative velocity error|, against the mpmath
   reference of vibroimpact.validation.reference (34 digits); N is cut where a float64-precision
   run of the reference stops agreeing with it to 1e-10;
3. the targets of the benchmark issue as ratios (printed, not asserted).

Usage::

    python benchmarks/bench_simulate.py                 # full size, a few minutes
    python benchmarks/bench_simulate.py --quick         # small, under a minute
    python benchmarks/bench_simulate.py --plot results/benchmarks/work_precision.png
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread for everybody

import argparse
import math
import time
from pathlib import Path

import numpy as np

from vibroimpact import simulate
from vibroimpact.validation import peers
from vibroimpact.validation.work_precision import SIMULATOR, work_precision

ZETA, EPS, DT = 0.05, 0.5, 0.1
DELTAS = (1.0, 0.0, -0.5)
DELTA_FREE = 1e6  # far beyond any excursion of the response (rms ~0.7): no impact reachable
SEED = 19740072  # the paper's year and bulletin number
METHODS = ("RK45", "DOP853", "LSODA")
T_MIN = 100.0  # shortest stretch for the work-precision runs (time units), for stable timings
WP_SAMPLES = 10**6  # at most this long a record for the compiled methods of the work-precision

TARGET_NS_PER_STEP = 4.5
TARGET_NS_PER_IMPACT = 300.0
TARGET_SPEEDUP = {1.0: 1e5, 0.0: 5e4}  # vs solve_ivp(DOP853, rtol = atol = 1e-10)
TARGET_ERROR_GAIN = 100.0
TARGET_RTOL = 1e-10


def best_times(fn, repeats):
    """Best wall time (time.perf_counter) and best CPU time (time.process_time) of `repeats`
    calls of fn(), and the last result. On a shared machine the CPU time shows what the wall
    time would be without the neighbours."""
    wall = cpu = math.inf
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall = min(wall, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu, out


def run_simulate(delta, noise):
    return simulate(ZETA, EPS, delta, noise, DT)


def fmt(value, spec=".2e"):
    return "inf" if not math.isfinite(value) else format(value, spec)


def throughput(noise, repeats):
    """Long-record timings of the simulator and of the recurrence floor; prints a table."""
    n_steps = noise.size - 1
    t_sim = n_steps * DT
    rows = {}
    for delta in (DELTA_FREE,) + DELTAS:
        seconds, cpu, res = best_times(lambda delta=delta: run_simulate(delta, noise), repeats)
        rows[delta] = dict(seconds=seconds, cpu=cpu, n_impacts=res.n_impacts,
                           n_chatter=res.n_chatter, contact=res.contact_time,
                           cost=seconds / t_sim, result=res)
    propagator = peers.linear_propagator(ZETA, DT)
    floor_seconds, floor_cpu, _ = best_times(lambda: peers.linear_recurrence(noise, propagator),
                                             repeats)
    free = rows[DELTA_FREE]["seconds"]

    print(f"\n== Throughput: simulate() on {n_steps:.3g} sample steps "
          f"(tau = 0 .. {t_sim:g}), best of {repeats} ==")
    print(f"{'delta':>8} {'seconds':>9} {'ns/step':>8} {'cpu ns/step':>11} {'impacts':>9} "
          f"{'chatter':>8} {'contact':>8} {'ns/impact':>10} {'marginal ns/impact':>19} "
          f"{'cpu marginal':>12} {'s per unit time':>16}")
    for delta, row in rows.items():
        n = row["n_impacts"]
        per_impact = row["seconds"] / n * 1e9 if n else math.nan
        marginal = (row["seconds"] - free) / n * 1e9 if n else math.nan
        cpu_marginal = (row["cpu"] - rows[DELTA_FREE]["cpu"]) / n * 1e9 if n else math.nan
        print(f"{delta:>8g} {row['seconds']:>9.4f} {row['seconds'] / n_steps * 1e9:>8.2f} "
              f"{row['cpu'] / n_steps * 1e9:>11.2f} {n:>9d} {row['n_chatter']:>8d} "
              f"{row['contact'] / t_sim:>8.3f} {per_impact:>10.1f} {marginal:>19.1f} "
              f"{cpu_marginal:>12.1f} {row['cost']:>16.3e}")
    print(f"{'floor':>8} {floor_seconds:>9.4f} {floor_seconds / n_steps * 1e9:>8.2f} "
          f"{floor_cpu / n_steps * 1e9:>11.2f}   "
          f"(bare 2x2 recurrence with forcing terms, no wall)")
    print("contact = fraction of time resting on the wall; marginal ns/impact = (time at delta "
          "- time with no impact) / impacts; cpu = time.process_time, for a shared machine")
    return rows, floor_seconds, floor_cpu


def print_work_precision(ds):
    """The work-precision table of each delta, with the ratio to the simulator's cost."""
    for delta in ds["delta"].values:
        row = ds.sel(delta=delta)
        print(f"\n== Work-precision, delta = {delta:g}: tau = 0 .. {float(row['t_stretch']):g}, "
              f"{int(row['n_reference'])} reference impacts (reference run "
              f"{float(row['reference_seconds']):.1f} s), errors over the first "
              f"{int(row['n_compared'])} comparable ones; the round-off level of float64 on this "
              f"stretch (a 53-bit run of the reference): {float(row['roundoff']):.2e} ==")
        print(f"{'method':<22} {'setting':<10} {'impacts':>7} {'err time':>9} {'err vel':>9} "
              f"{'error':>9} {'s/unit time':>11} {'timed on':>9} {'x simulate':>10}")
        for j in ds["run"].values:
            r = row.sel(run=j)
            print(f"{str(r['method'].values):<22} {str(r['setting'].values):<10} "
                  f"{int(r['n_found']):>7d} {fmt(float(r['err_time'])):>9} "
                  f"{fmt(float(r['err_velocity'])):>9} {fmt(float(r['error'])):>9} "
                  f"{float(r['cost']):>11.3e} {float(r['timed_span']):>9g} "
                  f"{float(r['cost_ratio']):>10.3g}")


def print_targets(through, floor_seconds, floor_cpu, n_steps, ds):
    print("\n== Targets (ratio = measured / target; <= 1 meets the target for costs, "
          ">= 1 for gains) ==")
    free, zero = through[DELTA_FREE], through[0.0]
    for clock, key, floor in (("wall", "seconds", floor_seconds), ("cpu", "cpu", floor_cpu)):
        ns_step = free[key] / n_steps * 1e9
        ns_impact = (zero[key] - free[key]) / zero["n_impacts"] * 1e9
        print(f"[{clock}] ns per sample step, no impact reachable: {ns_step:.2f} ns vs target "
              f"{TARGET_NS_PER_STEP} ns: ratio {ns_step / TARGET_NS_PER_STEP:.2f}; vs the floor "
              f"{floor / n_steps * 1e9:.2f} ns: x{free[key] / floor:.2f}")
        print(f"[{clock}] ns per impact (delta = 0, marginal over the no-impact run): "
              f"{ns_impact:.1f} ns vs target {TARGET_NS_PER_IMPACT:g} ns: "
              f"ratio {ns_impact / TARGET_NS_PER_IMPACT:.2f}")
    for delta, target in TARGET_SPEEDUP.items():
        if delta not in ds["delta"].values:
            continue
        row = ds.sel(delta=delta)
        peer = np.flatnonzero((row["method"].values == "solve_ivp DOP853")
                              & (row["setting"].values == f"rtol={TARGET_RTOL:.0e}"))
        if peer.size == 0:
            print(f"delta = {delta:g}: no solve_ivp DOP853 run at rtol={TARGET_RTOL:.0e}")
            continue
        peer = row.isel(run=peer[0])
        sim = row.isel(run=int(np.flatnonzero(row["method"].values == SIMULATOR)[0]))
        speedup = float(peer["cost_ratio"])
        gain = float(peer["error_ratio"])
        print(f"delta = {delta:g}: run time per unit time, solve_ivp DOP853 rtol=atol="
              f"{TARGET_RTOL:.0e} / simulate = {speedup:.3g} vs target {target:.0e}: ratio "
              f"{speedup / target:.2f}; error {fmt(float(peer['error']))} / "
              f"{fmt(float(sim['error']))} = {fmt(gain, '.3g')} vs target {TARGET_ERROR_GAIN:g}: "
              f"ratio {gain / TARGET_ERROR_GAIN:.3g}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=float, default=1e7,
                        help="force samples in the long record (default 1e7)")
    parser.add_argument("--quick", action="store_true",
                        help="small run: 1e5 samples, fewer tolerances and impacts")
    parser.add_argument("--impacts", type=int, default=None,
                        help="impacts compared in the work-precision runs (default 40, quick 20)")
    parser.add_argument("--repeats", type=int, default=3, help="best of this many timings")
    parser.add_argument("--plot", type=Path, default=None,
                        help="save the work-precision figure to this PNG")
    parser.add_argument("--seed", type=int, default=SEED, help="seed of the force record")
    args = parser.parse_args(argv)

    n_samples = int(1e5 if args.quick and args.samples == 1e7 else args.samples)
    n_target = args.impacts or (20 if args.quick else 40)
    rtols = (1e-3, 1e-6, TARGET_RTOL) if args.quick else tuple(10.0 ** -np.arange(3, 13))
    rk4_steps = (1, 8, 64) if args.quick else (1, 2, 4, 8, 16, 32, 64)

    t0 = time.perf_counter()
    noise = np.random.default_rng(args.seed).standard_normal(n_samples + 1)
    print(f"force record: {noise.size} N(0,1) samples, seed {args.seed}, dt = {DT}, "
          f"drawn in {time.perf_counter() - t0:.2f} s (once, reused by every run); "
          f"zeta = {ZETA}, eps = {EPS}; NUMBA_NUM_THREADS = {os.environ['NUMBA_NUM_THREADS']}; "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs (timings are wall "
          "clock: a busy machine inflates them)")

    for delta in (DELTA_FREE,) + DELTAS:  # compile and warm up before any timing
        run_simulate(delta, noise[:2001])
    peers.linear_recurrence(noise[:101], peers.linear_propagator(ZETA, DT))

    through, floor_seconds, floor_cpu = throughput(noise, args.repeats)
    ds = work_precision(DELTAS, impacts=n_target, stretch=T_MIN,
                        long_samples=min(n_samples, WP_SAMPLES), seed=args.seed, rtol=rtols,
                        rk4_steps=rk4_steps, clamp_steps=rk4_steps, repeats=args.repeats)
    print_work_precision(ds)
    print(f"(compiled methods timed on {min(n_samples, WP_SAMPLES)} samples, solve_ivp on the "
          f"stretch; whole work-precision run {float(ds['build_seconds']):.1f} s)")
    print_targets(through, floor_seconds, floor_cpu, noise.size - 1, ds)
    if args.plot is not None:
        from vibroimpact import plotting

        plotting.save(plotting.work_precision(ds), args.plot)
        print(f"\nwork-precision figure: {args.plot} (and .pdf)")


if __name__ == "__main__":
    main()
