"""The exact simulator: numba kernels (gathered in `kernels`) and the driver (`simulate`).

Between samples the flight is closed form (`motion`); impacts are roots, found and polished
in `events`, which also handles chatter and sticking; `stepping` walks the force samples
(docs/model.md). Thresholds live in `tolerances`, the named slots of the arrays the kernels
share in `layout`. Importing this package
compiles nothing until a simulation runs (numba caches the kernels on disk).
"""
from vibroimpact.impact.simulate import (SimulationResult, concatenate_results, simulate,
                                         simulate_chunks)

__all__ = ["simulate", "simulate_chunks", "SimulationResult", "concatenate_results"]
