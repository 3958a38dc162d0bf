"""vibroimpact: exact simulation and statistics of a vibro-impact oscillator.

Reproduces Irie, Yamada & Matsuzaki (1974), "On the dynamic response of a vibro-impact
system to random force", Bull. Fac. Eng. Hokkaido Univ. 72, 13-24.
"""
from importlib.metadata import PackageNotFoundError, version

from vibroimpact.simulate import SimulationResult, simulate, simulate_chunks
from vibroimpact.orbits import PeriodicOrbit, orbit_map, periodic_orbits

try:
    __version__ = version("vibroimpact")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0+unknown"

PAPER_REFERENCE = (
    "T. Irie, G. Yamada, H. Matsuzaki (1974), On the Dynamic Response of a Vibro-Impact "
    "System to Random Force, Bull. Fac. Eng. Hokkaido Univ. 72, 13-24, hdl:2115/41224"
)

__all__ = [
    "simulate", "simulate_chunks", "SimulationResult",
    "periodic_orbits", "PeriodicOrbit", "orbit_map", "PAPER_REFERENCE", "__version__",
]
