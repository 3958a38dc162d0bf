"""The impact law of :mod:`vibroimpact.model`, compiled once for every numba kernel.

``rebound_velocity``, ``rebound_derivative``, ``rebound_ratio`` and ``restitution_range``
here are numba's
compilations of the plain functions of :mod:`vibroimpact.model` (the one place the law is
written); a kernel calls them and numba inlines them, so ``rebound_velocity(eps, u, 0.0)``
(Newton's law) rounds exactly as ``-eps * u`` written in place. Every kernel package that
calls them stamps its numba cache with ``model.py`` and this file (:data:`LAW_MODULES`), so
that an edit of the law recompiles its callers.
"""
from numba import njit

from vibroimpact import model
from vibroimpact._kernel_cache import LAW_MODULES, kernel_decorator

_kernel = kernel_decorator(njit, __file__, LAW_MODULES, error_model="numpy")

rebound_velocity = _kernel(model.rebound_velocity)
rebound_derivative = _kernel(model.rebound_derivative)
rebound_ratio = _kernel(model.rebound_ratio)
restitution_range = _kernel(model.restitution_range)
