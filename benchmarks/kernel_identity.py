"""Bit-identity of the kernels across a refactoring: save what they compute, compare two saves.

Runs a fixed set of cases through the public entry points and saves every array of the result
with ``np.save`` (one ``.npy`` per field and case):

- ``simulate``: a seeded N(0,1) force record (2e5 steps, dt = 0.1, zeta = 0.05) at
  delta = 0.5 (free flights), 0 (grazing) and -0.5 (chatter and sticking), each with
  eps = 0.5, 0 (plastic: every impact sticks) and 1 (elastic micro-bounces); the harmonic force
  alone ((2/1) motion at 1/beta = 1.1) and harmonic plus random force (rms 0.29) at
  delta = 0 and -1 (the impact-chatter-stick cycle), eps 0.5 and 0; a record ending inside a
  sample step (the driver's partial last step); three with a second wall below the mass
  (random force; harmonic plus random; plastic with a partial last step); ``a(tau)`` and
  ``x'`` recorded every 7 samples;
- ``periodic_orbits``: (1/1), (2/1), (1/2), (2/2), (3/1) on a 4 x 4 grid of (1/beta, delta),
  inadmissible solutions included, eps = 0.5 and 0;
- ``orbit_map``: the default types on a 5 x 6 grid (the parallel map kernel);
- ``attractor_map``: a 2 x 2 grid of (1/beta, delta), 8 starts a cell, one wall and two
  (the attractor kernels over the simulator, every array of the result);
- ``periodic_motions``: the shooting solver from its default starts, n = 1 and 2, one wall and
  two, each under Newton's law and under a restitution falling with the speed
  (``speed_scale``); every field of every motion found, and the skipped seeds.

The attractor and shooting cases, and one simulate case, are at 1/beta = 1.148, where
CPython's ``math.hypot`` and numba's (the C library's) give the harmonic gain q two values:
each caller of :func:`vibroimpact.impact.parameters.parameters` keeps the one it always used.

Usage::

    PYTHONPATH=OLD/src python benchmarks/kernel_identity.py save /tmp/ident-old
    PYTHONPATH=NEW/src python benchmarks/kernel_identity.py save /tmp/ident-new
    python benchmarks/kernel_identity.py compare /tmp/ident-old /tmp/ident-new

``compare`` checks every saved array with ``np.array_equal(..., equal_nan=True)`` (same dtype
and shape too) and prints the cases, the number of arrays and every difference; it exits with
status 1 on any difference or missing file.
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "2")  # the map's rows: same threads both sides

import sys
from pathlib import Path

import numpy as np

SEED = 19740072
N_STEPS = 200_000
DT = 0.1
ZETA = 0.05
SIM_FIELDS = ("impact_step", "impact_offset", "impact_velocity", "stick_start", "stick_end",
              "grid_time", "a", "v")
SIM_SCALARS = ("n_steps", "n_impacts", "n_chatter", "contact_time", "t_end", "x_end", "v_end",
               "stuck_end", "stuck_since", "n_collisions")
#: A 1/beta where CPython's and the C library's hypot give two values of q (simulate_cases).
Q_ROUNDING_INV_BETA = 1.148
ORBIT_FIELDS = ("tau0", "intervals", "velocities", "multipliers", "jacobian", "lam", "margin",
                "admissible")


def simulate_cases():
    """{name: keyword arguments of simulate}."""
    rng = np.random.default_rng(SEED)
    noise = rng.standard_normal(N_STEPS + 2)
    cases = {}
    for delta in (0.5, 0.0, -0.5):
        for eps in (0.5, 0.0, 1.0):
            cases[f"random_d{delta:+.1f}_e{eps:.1f}"] = dict(
                eps=eps, delta=delta, noise=noise)
    cases["harmonic_2_1"] = dict(eps=0.5, delta=0.0, noise=None, amplitude=1.0,
                                 beta=1.0 / 1.1, t_end=3000.0)
    for delta in (0.0, -1.0):
        for eps in (0.5, 0.0):
            cases[f"mixed_d{delta:+.1f}_e{eps:.1f}"] = dict(
                eps=eps, delta=delta, noise=0.29 * noise, amplitude=1.0, beta=1.0 / 2.5)
    # 1/beta = 1.148 (zeta = 0.05): CPython's math.hypot and the C library's round the
    # harmonic gain q = 1 / |1 - beta^2 + 2 i zeta beta| apart there (by an ulp), so these
    # cases fail if a caller of the parameter builder changes the hypot it uses
    cases["harmonic_q_rounding"] = dict(eps=0.5, delta=0.0, noise=None, amplitude=1.0,
                                        beta=1.0 / Q_ROUNDING_INV_BETA, t_end=3000.0)
    cases["partial_last_step"] = dict(eps=0.5, delta=-0.5, noise=noise[:50_002],
                                      t_end=(50_000 + 0.37) * DT)
    # a second wall below the mass (the generic step, both walls' frames)
    cases["two_walls_random"] = dict(eps=0.5, delta=0.3, noise=noise, gap=1.0, eps_lower=0.8)
    cases["two_walls_mixed"] = dict(eps=0.5, delta=-0.2, noise=0.29 * noise, amplitude=1.0,
                                    beta=1.0 / 2.5, gap=0.6, eps_lower=0.5)
    cases["two_walls_partial"] = dict(eps=0.0, delta=0.2, noise=0.29 * noise[:50_002],
                                      amplitude=1.0, beta=1.0 / 1.1, gap=1.0, eps_lower=0.5,
                                      t_end=(50_000 + 0.37) * DT)
    return cases


def orbit_points():
    return [(ib, d) for ib in (0.7, 1.1, 1.9, 2.8) for d in (-1.0, 0.0, 0.6, 1.5)]


ORBIT_TYPES = ((1, 1), (2, 1), (1, 2), (2, 2), (3, 1))

ATTRACTOR_CASES = {"one_wall": {}, "two_walls": dict(clearance=3.0, eps_lower=0.7)}
MOTION_FIELDS = ("state", "phase0_states", "impact_time", "impact_wall", "impact_velocity",
                 "monodromy", "multipliers", "lam", "S", "stable", "margin", "admissible",
                 "grazing", "residual")


def motion_cases():
    """{name: the Model of a periodic_motions case}."""
    from vibroimpact.model import Model

    beta = 1.0 / Q_ROUNDING_INV_BETA
    return {
        "one_wall": Model.paper(ZETA, 0.5, 0.5, 1.0, beta),
        "one_wall_speed_scale": Model.paper(ZETA, 0.5, 0.5, 1.0, beta, speed_scale=2.0),
        "two_walls": Model.paper(ZETA, 0.5, 1.0, 1.0, beta, gap=2.0, eps_lower=0.7),
        "two_walls_speed_scale": Model.paper(ZETA, 0.5, 1.0, 1.0, beta, gap=2.0, eps_lower=0.7,
                                             speed_scale=3.0, speed_scale_lower=1.5),
    }


def save(out):
    from vibroimpact import periodic_orbits, simulate
    from vibroimpact.orbits import orbit_map

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for name, kw in simulate_cases().items():
        res = simulate(ZETA, dt=DT, record_every=7, **kw)
        for field in SIM_FIELDS:
            np.save(out / f"sim.{name}.{field}.npy", np.asarray(getattr(res, field)))
        np.save(out / f"sim.{name}.scalars.npy",
                np.array([float(getattr(res, f)) for f in SIM_SCALARS]))
        print(f"simulate {name}: {res.n_impacts} impacts, {res.n_chatter} chatter tails, "
              f"{res.stick_start.size} sticking phases", flush=True)
    for eps in (0.5, 0.0):
        for m, n in ORBIT_TYPES:
            for ib, delta in orbit_points():
                orbits = periodic_orbits(m, n, 1.0 / ib, delta, ZETA, eps,
                                         include_inadmissible=True)
                tag = f"orb.e{eps:.1f}.{m}_{n}.ib{ib}.d{delta:+.1f}"
                np.save(out / f"{tag}.count.npy", np.array(len(orbits)))
                for field in ORBIT_FIELDS:
                    np.save(out / f"{tag}.{field}.npy",
                            np.array([np.asarray(getattr(o, field)) for o in orbits]))
        print(f"periodic_orbits eps = {eps}: {len(ORBIT_TYPES)} types x "
              f"{len(orbit_points())} points", flush=True)
    grid = orbit_map(np.linspace(0.6, 3.0, 5), np.linspace(-1.0, 2.0, 6))
    for key, value in grid.items():
        np.save(out / f"map.{key}.npy", np.asarray(value))
    print("orbit_map: 5 x 6 grid, default types", flush=True)
    from vibroimpact import attractor_map, periodic_motions

    for name, walls in ATTRACTOR_CASES.items():
        res = attractor_map(np.array([Q_ROUNDING_INV_BETA, 2.0]), np.array([0.0, 0.5]), ZETA,
                            0.5, types=((1, 1), (2, 1)), n_starts=8, max_time=300.0, seed=1,
                            gap=(0.0, 3.0), **walls)
        for key, value in res.items():
            np.save(out / f"att.{name}.{key}.npy", np.asarray(value))
        print(f"attractor_map {name}: 2 x 2 grid, 8 starts a cell", flush=True)
    for name, model in motion_cases().items():
        found = periodic_motions(model, (1, 2))
        np.save(out / f"mot.{name}.count.npy", np.array(len(found)))
        for i, motion in enumerate(found):
            for field in MOTION_FIELDS:
                np.save(out / f"mot.{name}.m{i}_{field}.npy", np.asarray(getattr(motion, field)))
        np.save(out / f"mot.{name}.skipped_seed.npy",
                np.array([s.seed for s in found.skipped], dtype=float).reshape(-1, 2))
        np.save(out / f"mot.{name}.skipped_kind.npy",
                np.array([f"{s.n}:{s.kind}:{s.reason}" for s in found.skipped], dtype=str))
        print(f"periodic_motions {name}: {len(found)} motions, {len(found.skipped)} skipped "
              f"seeds", flush=True)


def compare(dir_a, dir_b):
    dir_a, dir_b = Path(dir_a), Path(dir_b)
    names_a = {p.name for p in dir_a.glob("*.npy")}
    names_b = {p.name for p in dir_b.glob("*.npy")}
    bad = [f"only in {dir_a}: {n}" for n in sorted(names_a - names_b)]
    bad += [f"only in {dir_b}: {n}" for n in sorted(names_b - names_a)]
    for name in sorted(names_a & names_b):
        a, b = np.load(dir_a / name), np.load(dir_b / name)
        same = a.dtype == b.dtype and a.shape == b.shape and np.array_equal(
            a, b, equal_nan=a.dtype.kind in "fc")
        if not same:
            bad.append(f"differs: {name} ({a.dtype}{a.shape} vs {b.dtype}{b.shape})")
    cases = {n.rsplit(".", 2)[0] for n in names_a}
    kinds = {k: sum(c.split(".")[0] == k for c in cases)
             for k in ("sim", "orb", "map", "att", "mot")}
    print(f"{len(names_a & names_b)} arrays compared (np.array_equal, NaNs equal, same dtype and "
          f"shape): {kinds['sim']} simulate cases, {kinds['orb']} periodic_orbits calls, "
          f"{kinds['map']} orbit_map grid, {kinds['att']} attractor_map grids, "
          f"{kinds['mot']} periodic_motions calls")
    for line in bad:
        print("  " + line)
    print("IDENTICAL" if not bad else f"{len(bad)} DIFFERENCES")
    return not bad


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "save":
        save(sys.argv[2])
    elif len(sys.argv) == 4 and sys.argv[1] == "compare":
        sys.exit(0 if compare(sys.argv[2], sys.argv[3]) else 1)
    else:
        sys.exit(__doc__)
