"""m = 3: every (3/n) motion from a 2-D scan of the interval triangle: the cells where
``det K`` and the circle function both change sign seed Newton on the full system.
"""
from math import ceil, pi, sqrt

import numpy as np

from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import harmonic_constants
from vibroimpact.orbits.intervals import (_circle_factors, fill_interval_system,
                                          start_from_intervals)
from vibroimpact.orbits.linalg import cofactors
from vibroimpact.orbits.tolerances import (BILINEAR_ACCEPT, BILINEAR_DIVERGED, BILINEAR_MAXIT,
                                           BILINEAR_XTOL, M3_CIRCLE_NEAR, M3_MIN_NODES,
                                           M3_NODE_OFFSET)


@kernel
def bilinear_root(a00, a10, a01, a11, b00, b10, b01, b11):
    """Common zero ``(s, t)`` of the bilinear interpolants of two functions on a unit cell.

    Returns ``(found, s, t)``; ``found`` when Newton converges within the cell widened by a
    quarter on each side. Screens scan cells whose zero curves pass near each other without
    crossing (frequent along the edges of the interval triangle).
    """
    s = 0.5
    t = 0.5
    for _ in range(BILINEAR_MAXIT):
        fa = a00 + (a10 - a00) * s + (a01 - a00) * t + (a11 - a10 - a01 + a00) * s * t
        fb = b00 + (b10 - b00) * s + (b01 - b00) * t + (b11 - b10 - b01 + b00) * s * t
        ja_s = (a10 - a00) + (a11 - a10 - a01 + a00) * t
        ja_t = (a01 - a00) + (a11 - a10 - a01 + a00) * s
        jb_s = (b10 - b00) + (b11 - b10 - b01 + b00) * t
        jb_t = (b01 - b00) + (b11 - b10 - b01 + b00) * s
        det = ja_s * jb_t - ja_t * jb_s
        if det == 0.0:
            return False, s, t
        ds = (fa * jb_t - fb * ja_t) / det
        dt = (ja_s * fb - jb_s * fa) / det
        s -= ds
        t -= dt
        if abs(s - 0.5) > BILINEAR_DIVERGED or abs(t - 0.5) > BILINEAR_DIVERGED:
            return False, s, t
        if abs(ds) + abs(dt) < BILINEAR_XTOL:
            break
    return abs(s - 0.5) <= BILINEAR_ACCEPT and abs(t - 0.5) <= BILINEAR_ACCEPT, s, t


@kernel
def _scan_m3(n, beta, delta, zeta, eps, scan_step, sols, count, work, jac, y):
    """Every (3/n) solution from the 2-D scan of the interval triangle (see solve_general);
    ``y``, ``work`` and ``jac`` are scratch of the solver."""
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    m = 3
    nn = 2 * m
    fast = max(beta, wd)
    ncol = m + 3
    kmat = np.empty((nn, ncol))
    sub = np.empty((nn, ncol))
    nvec = np.empty(ncol)
    zs = np.empty(m)
    # m == 3: 2-D scan over (z_1, z_2), z_3 = z - z_1 - z_2. The nodes are offset by a third
    # of a step from the edges of the triangle, where a zero-length flight makes K singular.
    npt = max(M3_MIN_NODES, int(ceil(z * fast / scan_step)))
    hz = z / npt
    f1 = np.empty((npt + 1, npt + 1))
    f2 = np.empty((2, npt + 1, npt + 1))
    for i in range(npt + 1):
        for k in range(npt + 1 - i):
            zs[0] = (i + M3_NODE_OFFSET) * hz
            zs[1] = (k + M3_NODE_OFFSET) * hz
            zs[2] = z - zs[0] - zs[1]            # slightly negative on the outer row: fine
            fill_interval_system(zs, m, beta, delta, zeta, eps, wd, kmat)
            cofactors(kmat, 1, ncol, sub, nvec)
            det = 0.0
            cn = 0.0
            rn = 0.0
            for c in range(ncol):
                det += kmat[0, c] * nvec[c]
                cn += nvec[c] * nvec[c]
                rn += kmat[0, c] * kmat[0, c]
            norm = sqrt(cn * rn)
            f1[i, k] = det / norm if norm > 0.0 else 0.0
            f2[0, i, k], f2[1, i, k] = _circle_factors(nvec, ncol, delta, q)
    for i in range(npt):
        for k in range(npt - i):
            a00, a10, a01 = f1[i, k], f1[i + 1, k], f1[i, k + 1]
            a11 = f1[i + 1, k + 1] if i + k + 2 <= npt else a10 + a01 - a00
            if min(min(a00, a10), min(a01, a11)) > 0.0 or max(max(a00, a10), max(a01, a11)) < 0.0:
                continue
            for f in range(2):
                b00, b10, b01 = f2[f, i, k], f2[f, i + 1, k], f2[f, i, k + 1]
                b11 = f2[f, i + 1, k + 1] if i + k + 2 <= npt else b10 + b01 - b00
                lo2 = min(min(b00, b10), min(b01, b11))
                hi2 = max(max(b00, b10), max(b01, b11))
                if (lo2 > 0.0 or hi2 < 0.0) and min(abs(lo2), abs(hi2)) > M3_CIRCLE_NEAR:
                    continue
                ok_, si, ti = bilinear_root(a00, a10, a01, a11, b00, b10, b01, b11)
                if not ok_:
                    continue
                zs[0] = (i + M3_NODE_OFFSET + si) * hz
                zs[1] = (k + M3_NODE_OFFSET + ti) * hz
                zs[2] = z - zs[0] - zs[1]
                if zs[0] <= 0.0 or zs[1] <= 0.0 or zs[2] <= 0.0:
                    continue
                count = start_from_intervals(zs, m, n, beta, delta, zeta, eps,
                                              1.0 if f == 0 else -1.0, kmat, sub, nvec, y,
                                              sols, count, work, jac)
    return count
