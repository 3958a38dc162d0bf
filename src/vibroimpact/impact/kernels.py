"""Numba kernels: exact event-driven motion of the impact oscillator (the package's kernel API).

Pure functions of numpy arrays and scalars: no I/O, no random numbers, no allocation per
step. The Python driver (:mod:`vibroimpact.impact.simulate`) validates input, allocates the
output buffers and wraps the results.

Model (docs/model.md, sections 2-6; paper eqs. 2-7)::

    x'' + 2 zeta x' + x = f(tau) = A sin(beta tau) + r(tau),   x <= delta,
    impact at x = delta with u = x'(tau-) > 0:  x'(tau+) = -eps u,

with r linear between the samples r_k = r(k h). The kernels live in one module per concept;
this module gathers what the driver and the tests use:

- :mod:`~vibroimpact.impact.tolerances`: every numerical threshold, each with its reason;
- :mod:`~vibroimpact.impact.layout`: the named slots of the parameter vector ``P``, the
  segment tuple ``c``, the state, the counters and the float record; modes and status codes;
- :mod:`~vibroimpact.impact.motion`: the closed-form motion between impacts (and the
  double-double phase, ``sincos``, ``expm1`` it rests on);
- :mod:`~vibroimpact.impact.events`: event location: first contact, release, chatter tails;
- :mod:`~vibroimpact.impact.stepping`: the loop over force samples (``run_steps``) and one
  step through its events (``slow_step``; ``slow_step_one`` the one-wall step compiled
  apart).

Every kernel is compiled with ``njit(cache=True, error_model="numpy")``; the cache is
stamped with all of those modules (:mod:`vibroimpact.impact._jit`), so an edit of any one of
them recompiles the kernels.
"""
# every name below is a re-export: the kernel API, gathered for the driver (F401)
from vibroimpact.impact.events import (  # noqa: F401
    chatter_tail, first_contact, force_tol, leave_wall, push_recovery, release_time, safe_step,
    stays_on_wall, tolg_wall)
from vibroimpact.impact.layout import *  # noqa: F403  (the named slots and codes)
from vibroimpact.impact.motion import (  # noqa: F401
    expm1, phase, push_eval, seg_eval, segment, sincos, two_prod)
from vibroimpact.impact.stepping import run_steps, slow_step, slow_step_one  # noqa: F401
from vibroimpact.impact.tolerances import *  # noqa: F403  (every threshold)

