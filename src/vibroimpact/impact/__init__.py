"""The exact simulator: numba kernels (`kernels`) and the driver (`simulate`).

Between samples the flight is closed form; impacts are roots, found and polished in the
kernels; chatter and sticking are handled there too (docs/model.md). Importing this package
compiles nothing until a simulation runs (numba caches the kernels on disk).
"""
from vibroimpact.impact.simulate import (SimulationResult, concatenate_results, simulate,
                                         simulate_chunks)

__all__ = ["simulate", "simulate_chunks", "SimulationResult", "concatenate_results"]
