"""The simulator's numba decorator: ``njit(cache=True, error_model="numpy")``, with the cache of
every kernel invalidated by an edit of any module below (:mod:`vibroimpact._kernel_cache`)."""
from numba import njit

from vibroimpact._kernel_cache import kernel_decorator
from vibroimpact._law import LAW_MODULES

#: The modules the compiled kernels are made of (constants included; the impact law of
#: :mod:`vibroimpact._law`, which a kernel calls as ``rebound_velocity(eps, u)``, too).
KERNEL_MODULES = ("tolerances.py", "layout.py", "motion.py", "events.py", "stepping.py",
                  "parameters.py") + tuple(f"../{m}" for m in LAW_MODULES)

kernel = kernel_decorator(njit, __file__, KERNEL_MODULES, error_model="numpy")
