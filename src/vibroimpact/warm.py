"""Compile every numba kernel the workflow's jobs call, once, at installation.

numba compiles a kernel on its first call and keeps the machine code in its cache
(``cache=True``; the package's ``__pycache__`` folders, or ``NUMBA_CACHE_DIR``). On a fresh
machine the first jobs of a build would each compile the kernels they call, and two jobs
running at once compile the same kernel twice. ``make`` instead runs ``python -m vibroimpact
warm`` when it installs: the same calls the jobs make (the cell functions of
:mod:`vibroimpact.pipeline.cells`, the orbit, boundary and attractor solvers, the validation's
peers), on inputs a few steps long, so that each kernel is compiled for the argument types the
jobs pass it. A job then loads the machine code from the cache.

The calls are grouped in independent families run in worker processes at once (``jobs``). A
kernel whose source changes later is recompiled on its next call, as always: warming is an
optimization, never a condition of correctness. ``benchmarks/warm_coverage.py`` lists what a
build still had to compile after the warm-up.
"""
from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
import time

import numpy as np

ZETA, EPS, DT = 0.05, 0.5, 0.1


def _noise(n=4000, seed=1):
    return 0.3 * np.random.default_rng(seed).standard_normal(n)


def _simulator():
    """The cell functions of every simulating job: events, map, escape, spectra, trace; one
    wall and two, with and without the harmonic force."""
    from vibroimpact import stats
    from vibroimpact.pipeline import cells

    noise = _noise()
    edges = {name: np.linspace(0.0, top, 7)
             for name, top in (("v_after", 3.0), ("interval", 20.0), ("ratio", 1.0))}
    for walls in ({}, {"gap": 1.5, "eps_lower": 0.6}):
        for amplitude, delta in ((0.0, 0.3), (1.0, -0.2)):
            model = cells.cell_model(dict(zeta=ZETA, eps=EPS, delta=delta, amplitude=amplitude,
                                          inv_beta=1.1, **walls))
            cells.event_statistics(noise, DT, model, transient=10.0, bins=edges, n_batches=4)
            cells.spectra_statistics(noise, DT, model, nperseg=256)
            cells.trace(noise, DT, model, t_end=50.0)
        model = cells.cell_model(dict(zeta=ZETA, eps=EPS, delta=0.2, inv_beta=1.1,
                                      amplitude=1.0, **walls))
        cells.motion_map_cell(noise, DT, model, transient=20.0, n_batches=4, target_stderr=0.5,
                              min_time=50.0, max_periods=30, min_switches=1,
                              motions=stats.DEFAULT_MOTIONS if not walls
                              else ((1, 1, 1), (1, 0, 1)))
        cells.escape_cell(noise, DT, model, transient=20.0, record_length=100.0,
                          motions=stats.DEFAULT_MOTIONS if not walls else ((1, 1, 1),))


def _orbits():
    """Fig. 16 (the closed-form solver over a grid) and its exact domain boundaries."""
    from vibroimpact.orbits import domain_boundaries, orbit_map, plane_boundaries

    seeds = orbit_map(np.linspace(0.8, 1.4, 4), np.linspace(-0.5, 1.5, 5),
                      types=((1, 1), (2, 1), (1, 2), (1, 3), (3, 1)), zeta=ZETA, eps=EPS)
    domain_boundaries(1, 1, ZETA, EPS, inv_beta=(0.8, 1.4), delta=(-0.5, 1.5),
                      resolution=(4, 5), seed_map=seeds, tol=1e-8)
    # over another plane: the same kernels, and the plane point read from Python
    plane_boundaries(1, 1, "eps", (0.4, 0.6), "delta", (-0.5, 1.5),
                     {"zeta": ZETA, "inv_beta": 1.1}, resolution=(3, 5), tol=1e-8)


def _attractors():
    """Basins and Lyapunov exponents (the attractor kernels over the simulator)."""
    from vibroimpact.attractors import attractor_map

    attractor_map(np.array([1.1]), np.array([0.5]), ZETA, EPS, types=((1, 1), (2, 1)),
                  n_starts=2, max_time=300.0, seed=1)


def _validation():
    """The work-precision peers and the stress families' references (one case each)."""
    from vibroimpact.validation.work_precision import work_precision

    work_precision(delta=(0.0,), impacts=2, stretch=10.0, long_samples=2000,
                   rtol=(1e-3,), solvers=("RK45",), rk4_steps=(1,), repeats=1)


FAMILIES = {"simulator": _simulator, "orbits": _orbits, "attractors": _attractors,
            "validation": _validation}


def _run(name):
    start = time.perf_counter()
    FAMILIES[name]()
    return name, time.perf_counter() - start


def warm(jobs=2, log=print):
    """Compile the kernels of every job into numba's cache, ``jobs`` families at once."""
    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=max(1, int(jobs))) as pool:
        for name, seconds in pool.map(_run, FAMILIES):
            log(f"warm: {name} kernels ready ({seconds:.1f} s)")
    log(f"warm: every kernel compiled or loaded in {time.perf_counter() - start:.1f} s")


def main(argv=None):
    import argparse

    parser = argparse.ArgumentParser(prog="vibroimpact warm",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2,
                        help="kernel families compiled at once (default 2)")
    warm(parser.parse_args(argv).jobs)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
