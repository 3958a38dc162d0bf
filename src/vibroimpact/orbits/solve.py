"""All (m/n) solutions at one parameter point: the (1/n) closed form, or the interval
scans plus Newton from seeds (m = 2, 3).
"""
from math import pi

import numpy as np

from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import harmonic_constants
from vibroimpact.orbits.m1 import solve_m1
from vibroimpact.orbits.newton import N_WORK
from vibroimpact.orbits.scan_m2 import _scan_m2
from vibroimpact.orbits.scan_m3 import _scan_m3
from vibroimpact.orbits.solutions import _try_start


@kernel
def solve_general(m, n, beta, delta, zeta, eps, seeds, nseed, scan_step, sols):
    """All (m/n) solutions for m = 2, 3: interval scan (global) plus Newton from ``seeds``.

    Rows of ``sols``/``seeds``: ``(tau_0..tau_{m-1}, u_0..u_{m-1})``. ``scan_step`` is the
    scan's grid step in radians of the fastest of ``beta`` and ``wd`` (0: no scan, seeds only).
    Returns the count.

    Notes
    -----
    For fixed intervals the 2m equations are linear in ``(S0, C0, u_0..u_{m-1}, t=delta)``
    (``fill_interval_system``). For m = 2 the 4x5 matrix has a cofactor null vector ``w(z_1)``
    and the solutions are the roots of the two factors of the circle condition
    ``delta^2 (w_S^2 + w_C^2) = q^2 w_t^2`` (``_circle_factors``), smooth functions of ``z_1``
    scanned over ``0 < z_1 < z`` (``_scan_m2``): every sign change is solved to a few ulps
    (Brent), and every dip of a factor toward zero between nodes is minimized first, so that
    both roots of a near-double root (the two orbits next to a fold) are bracketed. A root
    gives the solution directly (the equations are linear at fixed intervals); Newton only
    polishes one whose residual is above NEWTON_RTOL. For even n the matrix is taken in the
    symmetric form of ``_fill_symmetric_system``, regular at ``z_1 = z/2`` where the doubled
    (1/(n/2)) motion makes the plain one singular. For m = 3 the matrix is 6x6: the roots are
    the common zeros of ``det K`` and the same circle function (null vector of rows 1-5) on the
    triangle ``z_1 + z_2 < z``; every cell where both change sign (or the circle function comes
    near zero while ``det K`` changes sign) seeds Newton on the full system. Each orbit appears
    m times in the scan (one per choice of first impact). Solutions are kept once each
    (``_accept``: within SAME_ORBIT_RTOL plus their uncertainty from the conditioning,
    ``uncertainty``), and a repeated shorter orbit is dropped.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    tf = 2.0 * pi / beta
    nn = 2 * m
    scale = 1.0 + abs(delta) + q * (1.0 + beta)
    count = 0
    work = np.empty((N_WORK, nn))
    jac = np.empty((nn, nn))
    y = np.empty(nn)
    for i in range(nseed):
        for c in range(nn):
            y[c] = seeds[i, c]
        count = _try_start(y, m, z, beta, delta, zeta, eps, scale, tf, scale, sols, count,
                           work, jac)
    if scan_step <= 0.0:
        return count
    if m == 2:
        return _scan_m2(n, beta, delta, zeta, eps, scan_step, sols, count, work, jac)
    return _scan_m3(n, beta, delta, zeta, eps, scan_step, sols, count, work, jac, y)


@kernel
def solve_type(m, n, beta, delta, zeta, eps, seeds, nseed, scan_step, sols):
    """All (m/n) solutions (rows ``(tau.., u..)``) at one parameter point; returns the count."""
    if m == 1:
        return solve_m1(n, beta, delta, zeta, eps, sols)
    return solve_general(m, n, beta, delta, zeta, eps, seeds, nseed, scan_step, sols)
