"""Cost of the events cells' self-audit: the compiled kernel against the numpy reference.

For one seeded band-limited record (rms 0.5, beta_c 4, dt = 0.1; zeta = 0.05, eps = 0.5, the
random study's force), at four delta and once with A sin(tau / 1.1) added, prints CPU ns per
sample step of

1. the simulation alone: `simulate_chunks` with the state recorded at every sample, as an
   events cell runs it (the peer);
2. the numpy audit, `stats.flight_moments`, on those chunks, as `pipeline.cells` fed it;
3. the kernel audit, `impact.audit.audit_moments`, on the same chunks, as the cells feed it;

with the ratios audit / simulation and numpy / kernel, and the largest difference of the two
audits' integrals relative to each row's largest magnitude. Best of `--repeats` CPU times
(time.process_time: on a shared machine the neighbours' load stays out). The kernel's first
call in a fresh process (compilation, or loading numba's cache) is printed first.

Usage::

    python benchmarks/bench_audit.py                # 1e6 steps, a minute or two
    python benchmarks/bench_audit.py --steps 200000 --repeats 2
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread for everybody

import argparse
import math
import time

import numpy as np

from vibroimpact import Model, noise, stats
from vibroimpact.impact import audit, simulate_chunks
from vibroimpact.pipeline import cells

SPEC = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)
ZETA, EPS, TRANSIENT, BATCHES = 0.05, 0.5, 200.0, 20
#: (delta, amplitude of sin(beta_f tau)): the random study's cells, then one with the harmonic
#: force of the harmonic study (its sine costs the kernel a sin and a cos a step)
CELLS = ((3.0, 0.0), (0.5, 0.0), (0.0, 0.0), (-0.5, 0.0), (0.0, 1.0))
BETA_F = 1 / 1.1
SEED = 19740072


def cpu_best(fn, repeats):
    """Best CPU time (time.process_time) of ``repeats`` calls of fn(), and its last result."""
    best = math.inf
    for _ in range(repeats):
        c0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - c0)
    return best, out


def run_audit(record, chunks, moments):
    """The audit of ``pipeline.cells`` over stored chunks, integrating with ``moments``."""
    dt = SPEC.dt
    p = chunks["params"]
    model = Model.paper(p["zeta"], p["eps"], p["delta"], p["amplitude"], p["beta_f"])
    rec = cells._IdentityRecord(record, dt, TRANSIENT, (record.size - 1) * dt, BATCHES, model)
    compiled, cells.audit_moments = cells.audit_moments, moments    # what `add` calls
    try:
        for chunk in chunks["chunks"]:
            rec.add(chunk)
    finally:
        cells.audit_moments = compiled
    return rec.moments


def numpy_moments(k_first, a, v, r, dt, *, delta, batch_bounds, **kw):
    """``stats.flight_moments`` fed as the cells fed it before the kernel: ``x = delta - a``
    and the batch of every step."""
    batch = np.searchsorted(batch_bounds, k_first + np.arange(a.size), side="right") - 1
    return stats.flight_moments(k_first, delta - a, v, r, dt, delta=delta, batch=batch,
                                n_batches=len(batch_bounds) - 1, **kw)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10**6)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    record = noise.generate_array(SPEC, args.steps + 1, SEED)
    n = args.steps

    c0 = time.perf_counter()
    audit.audit_moments(0, np.zeros(4), np.zeros(4), np.zeros(5), SPEC.dt, zeta=ZETA, eps=EPS,
                        delta=0.0)
    print(f"kernel first call (compile, or load numba's cache): "
          f"{time.perf_counter() - c0:.2f} s")
    print(f"\n== Self-audit of an events cell: {n:.3g} steps, zeta = {ZETA}, eps = {EPS}, "
          f"band-limited rms {SPEC.rms} dt {SPEC.dt}; CPU ns per step, best of "
          f"{args.repeats} ==")
    print(f"{'delta':>6} {'A':>4} {'impacts':>8} {'simulate':>9} {'numpy':>8} {'kernel':>8} "
          f"{'numpy/sim':>10} {'kernel/sim':>11} {'numpy/kernel':>13} {'max rel diff':>13}")
    for delta, amplitude in CELLS:
        params = dict(zeta=ZETA, eps=EPS, delta=delta, amplitude=amplitude, beta_f=BETA_F)
        simulation = lambda delta=delta, amplitude=amplitude: list(simulate_chunks(
            ZETA, EPS, delta, noise=record, dt=SPEC.dt, amplitude=amplitude, beta=BETA_F,
            record_every=1))
        sim_s, chunk_list = cpu_best(simulation, args.repeats)
        chunks = dict(params=params, chunks=chunk_list)
        np_s, ref = cpu_best(lambda c=chunks: run_audit(record, c, numpy_moments), args.repeats)
        k_s, got = cpu_best(lambda c=chunks: run_audit(record, c, audit.audit_moments),
                            args.repeats)
        scale = np.abs(ref).max(axis=1)
        diff = np.max(np.abs(got - ref).max(axis=1) / np.where(scale > 0, scale, 1.0))
        impacts = sum(c.impact_time.size for c in chunk_list)
        ns = lambda s: s / n * 1e9
        print(f"{delta:>6g} {amplitude:>4g} {impacts:>8d} {ns(sim_s):>9.1f} {ns(np_s):>8.1f} "
              f"{ns(k_s):>8.1f} {np_s / sim_s:>10.2f} {k_s / sim_s:>11.2f} "
              f"{np_s / k_s:>13.1f} {diff:>13.1e}")
    print("simulate: simulate_chunks with record_every=1 (the events cell's simulation, "
          "statistics aside); numpy / kernel: the audit on its chunks; max rel diff: "
          "max |kernel - numpy| / max |numpy| over each row of the integrals")


if __name__ == "__main__":
    main()
