"""Basins of attraction and Lyapunov exponents under the harmonic force alone.

`api` is the public face (`attractor_map`); `kernels` runs the starts through the
simulator's kernel (:mod:`vibroimpact.impact.stepping`) and matches them to the orbit
solver's periodic motions (:mod:`vibroimpact.orbits`): this room sits above both.
"""
from vibroimpact.attractors.api import CLASSES, DEFAULT_TYPES, attractor_map

__all__ = ["attractor_map", "CLASSES", "DEFAULT_TYPES"]
