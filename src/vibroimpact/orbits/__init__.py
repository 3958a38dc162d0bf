"""Periodic (m/n) impact motions under the harmonic force alone, their stability, domain maps.

`api` is the public face (`periodic_orbits`, `PeriodicOrbit`, `orbit_map`, `Reason`); `kernels`
holds the numba kernels: flights and admissibility, the (1/n) closed form, the (m/n) scan and
Newton solver, the impact-map Jacobian and the row-parallel map (docs/model.md, section 8).
"""
from vibroimpact.orbits.api import REASON_CODES, PeriodicOrbit, Reason, orbit_map, periodic_orbits

__all__ = ["periodic_orbits", "PeriodicOrbit", "orbit_map", "Reason", "REASON_CODES"]
