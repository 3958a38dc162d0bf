"""The orbit solver's numba decorator: ``njit(cache=True)``, with the cache of every kernel
invalidated by an edit of any module below (:mod:`vibroimpact._kernel_cache`)."""
from numba import njit

from vibroimpact._kernel_cache import kernel_decorator
from vibroimpact._law import LAW_MODULES

#: The modules the compiled kernels are made of (constants included; the impact law too).
KERNEL_MODULES = ("tolerances.py", "flight.py", "linalg.py", "newton.py", "solutions.py",
                  "m1.py", "intervals.py", "scan_m2.py", "scan_m3.py", "solve.py",
                  "domain_map.py", "boundaries_kernels.py") + tuple(f"../{m}" for m in LAW_MODULES)

kernel = kernel_decorator(njit, __file__, KERNEL_MODULES)
