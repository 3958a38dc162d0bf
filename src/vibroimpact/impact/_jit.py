"""The simulator's numba decorator: ``njit(cache=True, error_model="numpy")``, with the cache of
every kernel invalidated by an edit of any module below (:mod:`vibroimpact._kernel_cache`)."""
from numba import njit

from vibroimpact._kernel_cache import kernel_decorator, package_modules

#: The modules the compiled kernels are made of (:data:`vibroimpact._kernel_cache.KERNEL_MODULES`).
KERNEL_MODULES = package_modules("impact")

kernel = kernel_decorator(njit, __file__, KERNEL_MODULES, error_model="numpy")
