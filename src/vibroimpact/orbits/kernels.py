"""Numba kernels for the periodic impact motions of section 4 (the kernel API of
``vibroimpact.orbits``).

Pure functions of numbers and preallocated arrays: no I/O, no Python objects. One module per
concept; this module gathers what :mod:`vibroimpact.orbits.api` and the tests use:

- :mod:`~vibroimpact.orbits.tolerances`: every numerical threshold, each with its reason;
- :mod:`~vibroimpact.orbits.flight`: flights in closed form, the impact map's Jacobians,
  admissibility (the exact maximum of a flight);
- :mod:`~vibroimpact.orbits.linalg`: small dense linear algebra on scratch arrays;
- :mod:`~vibroimpact.orbits.newton`: Newton on the full system, a solution's uncertainty;
- :mod:`~vibroimpact.orbits.solutions`: one orbit once (duplicates, repeated orbits);
- :mod:`~vibroimpact.orbits.m1`: the (1/n) closed form;
- :mod:`~vibroimpact.orbits.intervals`: the equations at fixed intervals, the circle
  condition;
- :mod:`~vibroimpact.orbits.scan_m2`, :mod:`~vibroimpact.orbits.scan_m3`: the global scans
  for m = 2 and m = 3;
- :mod:`~vibroimpact.orbits.solve`: all (m/n) solutions at a point;
- :mod:`~vibroimpact.orbits.domain_map`: the parallel domain map (Fig. 16).

Every kernel is compiled with ``njit(cache=True)``; the cache is stamped with all of those
modules (:mod:`vibroimpact.orbits._jit`), so an edit of any one of them recompiles the kernels.
"""
# every name below is a re-export: the kernel API, gathered for its callers (F401)
from vibroimpact.orbits.domain_map import map_kernel  # noqa: F401
from vibroimpact.orbits.flight import (  # noqa: F401
    flight, flight_max, harmonic_constants, impact_map_jacobian, lam_of, monodromy, orbit_margin,
    propagator)
from vibroimpact.orbits.m1 import solve_m1  # noqa: F401
from vibroimpact.orbits.newton import newton, uncertainty  # noqa: F401
from vibroimpact.orbits.solve import solve_general, solve_type  # noqa: F401
from vibroimpact.orbits.tolerances import *  # noqa: F403  (every threshold)
