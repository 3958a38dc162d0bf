"""The simulator's numba decorator: ``njit(cache=True, error_model="numpy")``, with the cache of
every kernel invalidated by an edit of any module below (:mod:`vibroimpact._kernel_cache`)."""
from numba import njit

from vibroimpact._kernel_cache import kernel_decorator

#: The modules the compiled kernels are made of (constants included).
#: ``../model.py`` holds the impact law the stepping compiles in.
KERNEL_MODULES = ("tolerances.py", "layout.py", "motion.py", "events.py", "stepping.py",
                  "../model.py")

kernel = kernel_decorator(njit, __file__, KERNEL_MODULES, error_model="numpy")
