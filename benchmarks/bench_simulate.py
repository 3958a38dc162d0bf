"""Run time and accuracy of `vibroimpact.simulate` against peers measured in the same run.

Prints, for one seeded record of Gaussian force samples (unit variance, dt = 0.1, linear in
between; zeta = 0.05, eps = 0.5, start at rest at min(0, delta)):

1. throughput on the long record: ns per sample step with no impact reachable, ns per impact
   (delta = 0), cost per unit of simulated time for each delta, and the floor: the bare
   dependent 2x2 recurrence with forcing terms and no wall;
2. a work-precision table on a short stretch of the same record, for delta in {1, 0, -0.5}:
   the simulator, scipy's solve_ivp (RK45, DOP853, LSODA; restarted at every force sample and
   after every impact, atol = rtol) at rtol 1e-3 ... 1e-12, and a numba fixed-step RK4 that
   clamps x to the wall, at 1 ... 64 steps per sample. Error = max over the first N comparable
   impacts (chatter tails excluded) of |impact time error| and |relative velocity error|,
   against the mpmath reference of vibroimpact.validation.reference (34 digits); N is cut where a
   float64-precision run of the reference stops agreeing with it to 1e-10;
3. the targets of the benchmark issue as ratios (printed, not asserted).

Usage::

    python benchmarks/bench_simulate.py                 # full size, a few minutes
    python benchmarks/bench_simulate.py --quick         # small, under a minute
    python benchmarks/bench_simulate.py --plot results/benchmarks/work_precision.png
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread for everybody

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import peers  # noqa: E402

from vibroimpact import simulate  # noqa: E402

ZETA, EPS, DT = 0.05, 0.5, 0.1
DELTAS = (1.0, 0.0, -0.5)
DELTA_FREE = 1e6  # far beyond any excursion of the response (rms ~0.7): no impact reachable
SEED = 19740072  # the paper's year and bulletin number
METHODS = ("RK45", "DOP853", "LSODA")
TRUST_TOL = 1e-10  # a float64 run of the reference must agree with 34 digits this closely
U_TAIL = 1e-4  # chatter-tail impacts slower than this are not compared one by one
T_MIN = 100.0  # shortest stretch for the work-precision runs (time units), for stable timings

TARGET_NS_PER_STEP = 4.5
TARGET_NS_PER_IMPACT = 300.0
TARGET_SPEEDUP = {1.0: 1e5, 0.0: 5e4}  # vs solve_ivp(DOP853, rtol = atol = 1e-10)
TARGET_ERROR_GAIN = 100.0
TARGET_RTOL = 1e-10


def load_reference():
    """The mpmath reference simulator (vibroimpact.validation.reference)."""
    from vibroimpact.validation import reference
    return reference


def best_time(fn, repeats):
    """Best wall time of `repeats` calls of fn() (time.perf_counter), and the last result."""
    wall, _, out = best_times(fn, repeats)
    return wall, out


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


def split_time(time_, dt):
    """Impact times as (sample index, offset in the sample), float64."""
    time_ = np.asarray(time_, dtype=np.float64)
    step = np.floor(time_ / dt).astype(np.int64)
    return step, time_ - step * dt


def reference_impacts(reference, delta, noise, t_end, **kwargs):
    """Comparable reference impacts: (step, offset, velocity) arrays; the offset is taken in
    multiprecision so that the simulator's step + offset form is compared at full precision."""
    from mpmath import mp, mpf

    run = reference.reference_impacts(ZETA, EPS, delta, noise, DT, t_end=t_end, **kwargs)
    tail = reference.chatter_tail_mask(run["time"], run["velocity"], run["stick_start"],
                                       run["stick_end"], U_TAIL)
    keep = [j for j, drop in enumerate(tail) if not drop]
    with mp.workdps(40):
        h = mpf(DT)
        step = [int(mp.floor(run["time"][j] / h)) for j in keep]
        offset = [float(run["time"][j] - s * h) for j, s in zip(keep, step)]
    velocity = [float(run["velocity"][j]) for j in keep]
    return run, (np.array(step, dtype=np.int64), np.array(offset), np.array(velocity))


def impact_errors(ref, step, offset, velocity, n_impacts):
    """(err_time, err_velocity) over the first n_impacts reference impacts.

    Each reference impact is paired with the peer impact nearest in time (a missed or
    spurious impact then shows as a large error, not as a shift of every later pair); the time
    difference is taken as (step difference) * dt + (offset difference), exact for equal steps.
    """
    ref_step, ref_offset, ref_velocity = (a[:n_impacts] for a in ref)
    if step.size == 0:
        return math.inf, math.inf
    ref_t = ref_step * DT + ref_offset
    t = step * DT + offset
    j = np.clip(np.searchsorted(t, ref_t), 1, max(t.size - 1, 1))
    j = np.minimum(j, t.size - 1)
    left = np.maximum(j - 1, 0)
    j = np.where(np.abs(t[left] - ref_t) <= np.abs(t[j] - ref_t), left, j)
    d_time = (step[j] - ref_step) * DT + (offset[j] - ref_offset)
    d_velocity = (velocity[j] - ref_velocity) / ref_velocity
    return float(np.max(np.abs(d_time))), float(np.max(np.abs(d_velocity)))


def fmt(value, spec=".2e"):
    return "inf" if not math.isfinite(value) else format(value, spec)


def throughput(noise, repeats):
    """Long-record timings of the simulator and of the recurrence floor; prints a table."""
    n_steps = noise.size - 1
    t_sim = n_steps * DT
    rows = {}
    for delta in (DELTA_FREE,) + DELTAS:
        seconds, cpu, res = best_times(lambda: run_simulate(delta, noise), repeats)
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
          f"{floor_cpu / n_steps * 1e9:>11.2f}   (bare 2x2 recurrence with forcing terms, no wall)")
    print("contact = fraction of time resting on the wall; marginal ns/impact = (time at delta "
          "- time with no impact) / impacts; cpu = time.process_time, for a shared machine")
    return rows, floor_seconds, floor_cpu


def stretch_end(delta, noise, n_impacts, res_long):
    """End of the short stretch: just past the simulator's n_impacts-th impact faster than
    U_TAIL (a proxy for the reference's comparable impacts), at least T_MIN, on the grid."""
    fast = res_long.impact_time[res_long.impact_velocity >= U_TAIL]
    t_n = fast[min(n_impacts, fast.size) - 1] if fast.size else T_MIN
    steps = int(math.ceil(max(1.05 * t_n + 2.0, T_MIN) / DT))
    return min(steps, noise.size - 1) * DT


def work_precision(delta, noise, reference, n_target, rtols, rk4_steps, repeats, long_run):
    """Rows of the work-precision table for one delta; long_run: its throughput row."""
    res_long = long_run["result"]
    t_end = stretch_end(delta, noise, n_target, res_long)
    n_short = int(round(t_end / DT))
    short = noise[:n_short + 1]

    t0 = time.perf_counter()
    run34, ref = reference_impacts(reference, delta, short, t_end)
    ref_seconds = time.perf_counter() - t0
    run53, ref53 = reference_impacts(reference, delta, short, t_end, prec=53)
    n_trust = reference.agreeing_prefix(run34, run53, tol=TRUST_TOL, u_tail=U_TAIL)
    n_cmp = min(n_target, n_trust, ref[0].size)
    roundoff = max(impact_errors(ref, *ref53, n_cmp))
    print(f"\n== Work-precision, delta = {delta:g}: tau = 0 .. {t_end:g} ({n_short} samples), "
          f"{len(run34['time'])} reference impacts ({ref[0].size} outside chatter tails, "
          f"reference run {ref_seconds:.1f} s) ==")
    print(f"A 53-bit run of the reference agrees with the 34-digit one to {TRUST_TOL:.0e} on "
          f"{n_trust} impacts: errors are over the first {n_cmp}. Its error there, the round-off "
          f"level of float64 arithmetic on this stretch: {roundoff:.2e}")

    rows = []

    def add(method, setting, step, offset, velocity, cost):
        err_t, err_u = impact_errors(ref, step, offset, velocity, n_cmp)
        rows.append(dict(delta=delta, method=method, setting=setting,
                         n_found=int(np.sum(step * DT + offset <= t_end)),
                         err_time=err_t, err_velocity=err_u, error=max(err_t, err_u), cost=cost))

    add("simulate (long record)", "exact", res_long.impact_step, res_long.impact_offset,
        res_long.impact_velocity, long_run["cost"])
    seconds, res = best_time(lambda: run_simulate(delta, short), repeats)
    add("simulate (short stretch)", "exact", res.impact_step, res.impact_offset, res.impact_velocity,
        seconds / t_end)
    for method in METHODS:
        for rtol in rtols:
            t0 = time.perf_counter()
            t_imp, u_imp = peers.solve_ivp_impacts(ZETA, EPS, delta, short, DT, method, rtol)
            seconds = time.perf_counter() - t0
            add(f"solve_ivp {method}", f"rtol={rtol:.0e}", *split_time(t_imp, DT), u_imp,
                seconds / t_end)
    for m in rk4_steps:
        seconds, (t_imp, u_imp) = best_time(
            lambda: peers.rk4_clamp_impacts(ZETA, EPS, delta, short, DT, m), repeats)
        add("RK4 clamp", f"dt/{m}", *split_time(t_imp, DT), u_imp, seconds / t_end)

    sim = rows[0]["cost"]
    print(f"{'method':<26} {'setting':<10} {'impacts':>7} {'err time':>9} {'err vel':>9} "
          f"{'error':>9} {'s/unit time':>11} {'x simulate (long record)':>24}")
    for row in rows:
        print(f"{row['method']:<26} {row['setting']:<10} {row['n_found']:>7d} "
              f"{fmt(row['err_time'])} {fmt(row['err_velocity']):>9} {fmt(row['error']):>9} "
              f"{row['cost']:>11.3e} {row['cost'] / sim:>24.3g}")
    return rows


def print_targets(through, floor_seconds, floor_cpu, n_steps, table):
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
        rows = [r for r in table if r["delta"] == delta]
        sim = next(r for r in rows if r["method"] == "simulate (long record)")
        peer = next((r for r in rows if r["method"] == "solve_ivp DOP853"
                     and r["setting"] == f"rtol={TARGET_RTOL:.0e}"), None)
        if peer is None:
            print(f"delta = {delta:g}: no solve_ivp DOP853 run at rtol={TARGET_RTOL:.0e}")
            continue
        speedup = peer["cost"] / sim["cost"]
        gain = peer["error"] / sim["error"] if sim["error"] > 0 else math.inf
        print(f"delta = {delta:g}: run time per unit time, solve_ivp DOP853 rtol=atol="
              f"{TARGET_RTOL:.0e} / simulate (long record) = {speedup:.3g} vs target "
              f"{target:.0e}: ratio {speedup / target:.2f}; error {fmt(peer['error'])} / "
              f"{fmt(sim['error'])} = {fmt(gain, '.3g')} vs target {TARGET_ERROR_GAIN:g}: "
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
        peers.rk4_clamp_impacts(ZETA, EPS, delta, noise[:101], DT, 2)
    peers.linear_recurrence(noise[:101], peers.linear_propagator(ZETA, DT))

    through, floor_seconds, floor_cpu = throughput(noise, args.repeats)
    reference = load_reference()
    table = []
    for delta in DELTAS:
        table += work_precision(delta, noise, reference, n_target, rtols, rk4_steps,
                                args.repeats, through[delta])
    print_targets(through, floor_seconds, floor_cpu, noise.size - 1, table)
    if args.plot is not None:
        args.plot.parent.mkdir(parents=True, exist_ok=True)
        peers.plot_work_precision(table).savefig(args.plot, dpi=150)
        print(f"\nwork-precision figure: {args.plot}")


if __name__ == "__main__":
    main()
