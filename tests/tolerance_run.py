"""Collision statistics of a few cells with the kernel's event tolerances scaled (a subprocess
of tests/test_collisions.py).

Usage: ``python tolerance_run.py '{"CHATTER_TIME_TOL": 1000.0, ...}' out.npz``. numba reads
a module's constants when it compiles, so the scaled values take effect only in a fresh
compilation: with factors, every kernel of ``vibroimpact.impact`` has its cache turned off
(numba's ``NullCache``: compiled in memory, nothing read from or written to disk), while the
kernels of other modules, which read none of the thresholds (the collision tally's), load from
the package's cache as in any run.
"""
import json
import sys

import numpy as np

from vibroimpact.impact import kernels, tolerances

FACTORS = json.loads(sys.argv[1])
# every kernel module binds the thresholds it reads (``from ...tolerances import``): numba
# reads each function's own module globals, so the scaled value goes into each of them
MODULES = [m for n, m in sorted(sys.modules.items()) if n.startswith("vibroimpact.impact.")]
for name, factor in FACTORS.items():
    value = type(getattr(tolerances, name))(getattr(tolerances, name) * factor)
    for module in MODULES:
        if hasattr(module, name):
            setattr(module, name, value)
if FACTORS:
    from numba.core.caching import NullCache
    from numba.core.dispatcher import Dispatcher

    for module in MODULES:
        for kernel in vars(module).values():
            if isinstance(kernel, Dispatcher):
                kernel._cache = NullCache()

from vibroimpact import Model, simulate                # noqa: E402  (after the patch)
from vibroimpact.noise import NoiseSpec, generate_array  # noqa: E402
from vibroimpact.pipeline import cells                 # noqa: E402

# a kernel module imported only now kept its thresholds: none may read one that is scaled
LATE = [n for n, m in sorted(sys.modules.items()) if n.startswith("vibroimpact.impact.")
        and m not in MODULES and any(hasattr(m, name) for name in FACTORS)]
if LATE:
    raise SystemExit(f"kernel modules imported after the thresholds were scaled read them: "
                     f"{LATE}")

BINS = {"v_after": np.linspace(0.0, 2.5, 101), "interval": np.linspace(0.0, 20.0, 201),
        "ratio": np.linspace(0.0, 4.0, 161)}
#: (name, noise rms, amplitude, 1/beta_f, delta): chatter under random force (delta <= 0),
#: free impacts (delta = 0.5), the impact-chatter-stick cycle and the (2/1) motion under
#: harmonic plus random force (Fig. 15's cells)
CASES = [("random_m05", 0.5, 0.0, 1.0, -0.5), ("random_0", 0.5, 0.0, 1.0, 0.0),
         ("random_05", 0.5, 0.0, 1.0, 0.5), ("harmonic_2_m05", 0.29, 1.0, 2.0, -0.5),
         ("harmonic_25_m1", 0.29, 1.0, 2.5, -1.0), ("harmonic_11_0", 0.29, 1.0, 1.1, 0.0)]
N_SAMPLES = 200_001


def main(out):
    noises = {rms: generate_array(NoiseSpec("band_limited", rms, 0.1, beta_c=4.0), N_SAMPLES,
                                  19741001) for rms in (0.5, 0.29)}
    result = {"applied": np.array([getattr(kernels, n) for n in sorted(FACTORS)], dtype=float)}
    for name, rms, amplitude, inv_beta, delta in CASES:
        model = Model.paper(0.05, 0.5, delta, amplitude, 1.0 / inv_beta)
        stats = cells.event_statistics(noises[rms], 0.1, model, transient=200.0, bins=BINS)
        for key, value in stats.items():
            result[f"{name}/{key}"] = np.asarray(value, dtype=float)
        res = simulate(0.05, 0.5, delta, noise=noises[rms], dt=0.1, amplitude=amplitude,
                       beta=1.0 / inv_beta)
        result[f"{name}/n_impacts_resolved"] = np.asarray(float(res.n_impacts))
        if amplitude:
            cell = cells.motion_map_cell(noises[rms], 0.1,
                                         Model.paper(0.05, 0.5, delta, 1.0, 1.0 / inv_beta),
                                         transient=200.0, max_periods=1000,
                                         target_stderr=0.02)
            for key in ("probability", "stderr", "n_collisions", "record_end",
                        "rule_probability", "rule_stick_probability"):
                result[f"{name}/map_{key}"] = np.asarray(cell[key], dtype=float)
    np.savez(out, **result)


if __name__ == "__main__":
    main(sys.argv[2])
