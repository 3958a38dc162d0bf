"""The (m/n) equations at fixed intervals: linear in the impact phase's ``(sin, cos)`` and
the velocities; their null vector, the circle condition on it, and a Newton start from it.

Linear *because* Newton's law is (``v_+ = -eps u``): the ``-eps`` entries of ``kmat`` are that
law's coefficient, not a call of :mod:`vibroimpact._law`. A velocity-dependent law makes the
system nonlinear in the velocities; these starts then only seed the general Newton
(docs/architecture.md, "Adding physics").
"""
from math import atan2, cos, hypot, pi, sin

import numpy as np

from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import harmonic_constants, propagator
from vibroimpact.orbits.linalg import cofactors
from vibroimpact.orbits.solutions import _try_start


@kernel
def fill_interval_system(zs, m, beta, delta, zeta, eps, wd, kmat):
    """Linear system of the (m/n) equations for fixed intervals ``zs`` (eqs. 10-11).

    Unknowns ``w = (S0, C0, u_0..u_{m-1}, t)`` with ``S0 = q sin psi_0``, ``C0 = q cos psi_0``
    and ``t`` the multiplier of the delta terms (``t = delta`` for a solution): ``K w = 0``.
    Rows ``2(j-1)``, ``2(j-1)+1``: position and velocity at the end of flight j.
    """
    ncol = m + 3
    th_a = 0.0
    for j in range(1, m + 1):
        a = j - 1
        b = j % m
        th_b = th_a + beta * zs[j - 1]
        p11, p12, p21, p22 = propagator(zs[j - 1], zeta, wd)
        ca, sa, cb, sb = cos(th_a), sin(th_a), cos(th_b), sin(th_b)
        r1 = 2 * (j - 1)
        r2 = r1 + 1
        for c in range(ncol):
            kmat[r1, c] = 0.0
            kmat[r2, c] = 0.0
        # S_k = S0 cos th_k + C0 sin th_k,  C_k = -S0 sin th_k + C0 cos th_k
        kmat[r1, 0] = -p11 * ca + beta * p12 * sa + cb
        kmat[r1, 1] = -p11 * sa - beta * p12 * ca + sb
        kmat[r1, 2 + a] += -eps * p12
        kmat[r1, ncol - 1] = p11 - 1.0
        kmat[r2, 0] = -p21 * ca + beta * p22 * sa - beta * sb
        kmat[r2, 1] = -p21 * sa - beta * p22 * ca + beta * cb
        kmat[r2, 2 + a] += -eps * p22
        kmat[r2, 2 + b] += -1.0
        kmat[r2, ncol - 1] = p21
        th_a = th_b


@kernel
def _guess_from_null(nvec, m, zs, q, phi, beta, sign, y):
    """Initial Newton guess ``y`` from a null vector scaled onto the circle ``S0^2+C0^2 = q^2``."""
    r = hypot(nvec[0], nvec[1])
    if r == 0.0 or not np.isfinite(r):
        return False
    lam = sign * q / r
    s0 = lam * nvec[0]
    c0 = lam * nvec[1]
    tau = (atan2(s0, c0) + phi) / beta
    for j in range(m):
        y[j] = tau
        y[m + j] = lam * nvec[2 + j]
        tau += zs[j]
    return True


@kernel
def _circle_factors(nvec, ncol, delta, q):
    """The two factors ``(q w_t -+ delta |w_SC|) / norm`` of the circle condition.

    A null vector ``w`` of K is a solution when ``w`` scaled to ``t = delta`` puts
    ``(S0, C0)`` on the circle of radius q: ``q w_t = +delta |w_SC|`` (scale ``+q/|w_SC|``) or
    ``q w_t = -delta |w_SC|`` (scale ``-q/|w_SC|``). Each factor has simple zeros, also at
    ``delta = 0`` where the product degenerates into the square ``-q^2 w_t^2``.
    """
    r = abs(delta) * hypot(nvec[0], nvec[1])
    t = q * nvec[ncol - 1]
    if delta < 0.0:
        r = -r
    norm = hypot(r, t)
    if norm == 0.0:
        return 0.0, 0.0
    return (t - r) / norm, (t + r) / norm


@kernel
def start_from_intervals(zs, m, n, beta, delta, zeta, eps, sign, kmat, sub, nvec, y, sols,
                          count, work, jac):
    """Newton from the linear solution at fixed intervals ``zs``, scaled by ``sign q/|w_SC|``."""
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    tf = 2.0 * pi / beta
    scale = 1.0 + abs(delta) + q * (1.0 + beta)
    ncol = m + 3
    fill_interval_system(zs, m, beta, delta, zeta, eps, wd, kmat)
    cofactors(kmat, 2 * m - ncol + 1, ncol, sub, nvec)
    if _guess_from_null(nvec, m, zs, q, phi, beta, sign, y):
        count = _try_start(y, m, z, beta, delta, zeta, eps, scale, tf, scale, sols, count,
                           work, jac)
    return count
