"""Periodic (m/n) impact motions under the harmonic force alone, their stability, domain maps.

`api` is the public face (`periodic_orbits`, `PeriodicOrbit`, `orbit_map`, `Reason`); `kernels`
gathers the numba kernels, one module per concept: flights, the impact-map Jacobian and
admissibility (`flight`), linear algebra (`linalg`), Newton (`newton`), one orbit once
(`solutions`), the (1/n) closed form (`m1`), the (m/n) scans (`intervals`, `scan_m2`,
`scan_m3`, `solve`), the row-parallel map (`domain_map`) and the exact boundaries of the
stable domains (`boundaries`, kernels in `boundaries_kernels`); thresholds in `tolerances`
(docs/model.md, section 8).
"""
from vibroimpact.orbits.api import REASON_CODES, PeriodicOrbit, Reason, orbit_map, periodic_orbits
from vibroimpact.orbits.boundaries import (BoundaryCurve, CodimTwoPoint, DomainBoundaries,
                                           PlaneCurve, PlanePoint, domain_boundaries,
                                           plane_boundaries)

__all__ = ["periodic_orbits", "PeriodicOrbit", "orbit_map", "Reason", "REASON_CODES",
           "domain_boundaries", "BoundaryCurve", "CodimTwoPoint", "DomainBoundaries",
           "plane_boundaries", "PlaneCurve", "PlanePoint"]
