"""The parameter vector ``P`` the simulator's kernels read, built in one place for every caller.

:func:`parameters` fills the slots of :mod:`vibroimpact.impact.layout` from plain numbers, so
that a Python caller (:func:`vibroimpact.impact.simulate.model_parameters`, the shooting
solver of :mod:`vibroimpact.attractors.shooting`) and a compiled one (the attractor kernels,
which build a vector per cell) get the same vector from the same statements.
"""
import math

import numpy as np

from vibroimpact.impact._jit import kernel
from vibroimpact.impact.layout import (N_PARAMS, P_A, P_AQ, P_BETA, P_BH_HI, P_BH_LO, P_COS_BH,
                                       P_COS_PHI, P_DELTA, P_DT, P_EPS, P_INV_DT,
                                       P_INV_OMEGA, P_LAW_A, P_M11, P_M12, P_M21, P_M22,
                                       P_OMEGA, P_PHI, P_SIN_BH, P_SIN_PHI, P_ZETA)
from vibroimpact.impact.motion import two_prod


@kernel
def parameters(zeta, h, amplitude, beta, norm, eps, delta, law_a, walls, eps_lower, lower,
               law_a_lower):
    """The parameter vector for the sample step ``h``: ``N_PARAMS`` slots per wall.

    ``zeta`` is the damping ratio, ``amplitude sin(beta tau)`` the harmonic force, ``eps``,
    ``delta`` and ``law_a`` the restitution, position and impact law (``1 / speed_scale``,
    0 for Newton's law) of the wall above the mass. With ``walls = 2`` the second half is the
    wall below the mass at ``x = lower`` (restitution ``eps_lower``, law ``law_a_lower``) in
    the mirrored frame ``x -> -x``: wall at ``-lower`` hit from below, harmonic amplitude
    negated, so that every search of :mod:`vibroimpact.impact.events` serves both walls.

    ``norm`` is ``|1 - beta^2 + 2 i zeta beta|`` (the harmonic gain is ``q = 1 / norm``),
    computed by the caller as ``math.hypot(1 - beta^2, 2 zeta beta)``. CPython's
    ``math.hypot`` is a compensated algorithm of its own and numba's calls the C library's:
    the two differ by an ulp for about one random ``(zeta, beta)`` in 200, and ``q`` then by
    one or two ulps (at ``zeta = 0.05``, ``1/beta = 1.148`` for one). The Python callers
    have always used CPython's and the attractor kernels the C library's; each keeps its own,
    so that no result moves by a bit, and no single expression can round as both. Every other
    slot rounds here as it did in each of them (``math.sqrt`` is exact in both; ``exp``,
    ``cos``, ``sin`` and ``atan2`` are the C library's in both).
    """
    P = np.empty(walls * N_PARAMS)
    omega = math.sqrt(1.0 - zeta * zeta)
    q = 1.0 / norm
    phi = math.atan2(2.0 * zeta * beta, 1.0 - beta * beta)
    E = math.exp(-zeta * h)
    C = math.cos(omega * h)
    S = math.sin(omega * h)
    bh_hi, bh_lo = two_prod(beta, h)
    P[P_ZETA] = zeta
    P[P_OMEGA] = omega
    P[P_EPS] = eps
    P[P_DELTA] = delta
    P[P_DT] = h
    P[P_A] = amplitude
    P[P_BETA] = beta
    P[P_AQ] = amplitude * q
    P[P_PHI] = phi
    P[P_COS_PHI] = math.cos(phi)
    P[P_SIN_PHI] = math.sin(phi)
    P[P_BH_HI] = bh_hi
    P[P_BH_LO] = bh_lo
    P[P_M11] = E * (C + zeta * S / omega)
    P[P_M12] = E * S / omega
    P[P_M21] = -E * S / omega
    P[P_M22] = E * (C - zeta * S / omega)
    P[P_INV_DT] = 1.0 / h
    P[P_INV_OMEGA] = 1.0 / omega
    P[P_COS_BH] = math.cos(beta * h)
    P[P_SIN_BH] = math.sin(beta * h)
    P[P_LAW_A] = law_a
    if walls == 2:
        P[N_PARAMS:] = P[:N_PARAMS]
        P[N_PARAMS + P_EPS] = eps_lower
        P[N_PARAMS + P_LAW_A] = law_a_lower
        P[N_PARAMS + P_DELTA] = -lower
        P[N_PARAMS + P_A] = -amplitude
        P[N_PARAMS + P_AQ] = -P[P_AQ]
    return P
