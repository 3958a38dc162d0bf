"""m = 2: every (2/n) motion from the circle condition along ``0 < z_1 < z``, its roots
solved exactly (Brent) and its dips toward zero minimized, so that both orbits next to a fold
are found; for even n in a symmetric form regular at the doubled (1/(n/2)) motion.

The scan is the linear algebra of :mod:`vibroimpact.orbits.intervals` (the ``-eps`` entries of
its ``kmat`` are Newton's law's coefficient, linear in the velocities); a velocity-dependent law
does not have it (docs/architecture.md, "Adding physics").
"""
from math import ceil, cos, cosh, exp, pi, sin, sinh

import numpy as np

from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import harmonic_constants
from vibroimpact.orbits.intervals import _circle_factors, fill_interval_system, _guess_from_null
from vibroimpact.orbits.linalg import cofactors, _norm
from vibroimpact.orbits.newton import WORK_RES, _residual_jacobian, uncertainty
from vibroimpact.orbits.solutions import _accept, _try_start, _valid
from vibroimpact.orbits.tolerances import (BRENT_ROOT_REL, EDGE_LEVELS, GOLDEN_SECTION,
                                           M2_MIN_NODES, NEWTON_RTOL, ROOT_MAXIT, TANGENCY_MARGIN,
                                           TANGENCY_XTOL, TINY)


@kernel
def _even_parts(alpha, gamma, e_h, c_h, s_h, e_p, e_m, c_o, s_o, ch_z, sh_z_o, s_o_o):
    """``f(h +- o)``, their mean and ``(f(h+o) - f(h-o)) / (2 o)`` for
    ``f(s) = exp(-zeta s) (alpha cos wd s + gamma sin wd s)``, the difference in product form
    (no cancellation as o -> 0): ``f(h +- o) = e_h exp(-+zeta o) (X cos wd o +- Y sin wd o)``."""
    x_ = alpha * c_h + gamma * s_h
    y_ = gamma * c_h - alpha * s_h
    plus = e_h * e_p * (x_ * c_o + y_ * s_o)
    minus = e_h * e_m * (x_ * c_o - y_ * s_o)
    mean = 0.5 * (plus + minus)
    diff = e_h * (-x_ * c_o * sh_z_o + y_ * ch_z * s_o_o)
    return plus, minus, mean, diff


@kernel
def _fill_symmetric_system(o, h, beta, delta, zeta, eps, wd, kmat):
    """(2/n) system for even n at ``z_1 = h + o``, ``z_2 = h - o`` (``h = z/2``), regular at o = 0.

    For even n the flights' forcing phases differ by ``beta o`` only, and at o = 0 the four
    rows of ``fill_interval_system`` have rank 3: the doubled (1/(n/2)) motion solves them for
    every delta, and their null vector, a 0/0 there, is computed with an error ~ 1e-16 / o.
    This is that matrix with its rows recombined into the sums ``(r_1 + r_3)/2``,
    ``(r_2 + r_4)/2`` and the differences ``(r_1 - r_3)/(2 o)``, ``(r_2 - r_4)/(2 o)`` of the two
    flights' rows, and its velocity columns into ``u+ = (u_0 + u_1)/2``, ``ub = (u_0 - u_1)/(2 o)``
    (columns ``S0, C0, u+, ub, t``), every difference in closed product form. Same null space
    (``u_0, u_1 = u+ +- o ub``), a regular matrix at o = 0: the (2/n) motions born there from the
    doubled motion (a period doubling, intervals ``h +- O(sqrt(distance))``) are simple roots of
    its circle condition, found to round-off instead of to ~1e-16 / distance.
    """
    c = cos(beta * o)
    s = sin(beta * o)
    if o != 0.0:
        sb2 = sin(0.5 * beta * o)
        s2o = s / (2.0 * o)                   # sin(beta o) / (2 o)
        omc2o = sb2 * sb2 / o                 # (1 - cos beta o) / (2 o)
        sh_z_o = sinh(zeta * o) / o
        s_o_o = sin(wd * o) / o
    else:
        s2o = 0.5 * beta
        omc2o = 0.0
        sh_z_o = zeta
        s_o_o = wd
    e_h = exp(-zeta * h)
    c_h = cos(wd * h)
    s_h = sin(wd * h)
    e_p = exp(-zeta * o)
    e_m = exp(zeta * o)
    c_o = cos(wd * o)
    s_o = sin(wd * o)
    ch_z = cosh(zeta * o)
    p11p, p11m, m11, d11 = _even_parts(1.0, zeta / wd, e_h, c_h, s_h, e_p, e_m, c_o, s_o, ch_z,
                                       sh_z_o, s_o_o)
    p12p, p12m, m12, d12 = _even_parts(0.0, 1.0 / wd, e_h, c_h, s_h, e_p, e_m, c_o, s_o, ch_z,
                                       sh_z_o, s_o_o)
    p21p, p21m, m21, d21 = _even_parts(0.0, -1.0 / wd, e_h, c_h, s_h, e_p, e_m, c_o, s_o, ch_z,
                                       sh_z_o, s_o_o)
    p22p, p22m, m22, d22 = _even_parts(1.0, -zeta / wd, e_h, c_h, s_h, e_p, e_m, c_o, s_o, ch_z,
                                       sh_z_o, s_o_o)
    # sums of the position and velocity rows of the two flights
    kmat[0, 0] = 0.5 * (c - p11p - p11m * c + beta * p12m * s + 1.0)
    kmat[0, 1] = 0.5 * (s - beta * p12p - p11m * s - beta * p12m * c)
    kmat[0, 2] = -eps * m12
    kmat[0, 3] = -eps * o * o * d12
    kmat[0, 4] = m11 - 1.0
    kmat[1, 0] = 0.5 * (-p21p - beta * s - p21m * c + beta * p22m * s)
    kmat[1, 1] = 0.5 * (-beta * p22p + beta * c - p21m * s - beta * p22m * c + beta)
    kmat[1, 2] = -1.0 - eps * m22
    kmat[1, 3] = -eps * o * o * d22
    kmat[1, 4] = m21
    # differences over 2 o
    kmat[2, 0] = -omc2o * (1.0 + p11m) - d11 - beta * p12m * s2o
    kmat[2, 1] = s2o * (1.0 + p11m) - beta * d12 - beta * p12m * omc2o
    kmat[2, 2] = -eps * d12
    kmat[2, 3] = -eps * m12
    kmat[2, 4] = d11
    kmat[3, 0] = -d21 - p21m * omc2o - beta * s2o * (1.0 + p22m)
    kmat[3, 1] = -beta * d22 - beta * (1.0 + p22m) * omc2o + p21m * s2o
    kmat[3, 2] = -eps * d22
    kmat[3, 3] = 1.0 - eps * m22
    kmat[3, 4] = d21


@kernel
def _m2_null(x, z, even, beta, delta, zeta, eps, wd, zs, kmat, sub, nvec):
    """Null vector ``(S0, C0, u_0, u_1, t)`` of the (2/n) equations at ``z_1 = x``, in ``nvec``."""
    if even:
        h = 0.5 * z
        o = x - h
        _fill_symmetric_system(o, h, beta, delta, zeta, eps, wd, kmat)
        cofactors(kmat, 0, 5, sub, nvec)
        up = nvec[2]
        ub = nvec[3]
        nvec[2] = up + o * ub
        nvec[3] = up - o * ub
    else:
        zs[0] = x
        zs[1] = z - x
        fill_interval_system(zs, 2, beta, delta, zeta, eps, wd, kmat)
        cofactors(kmat, 0, 5, sub, nvec)


@kernel
def _m2_factor(x, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat, sub, nvec):
    """Circle factor ``f`` (0 or 1, ``_circle_factors``) of the (2/n) equations at ``z_1 = x``."""
    _m2_null(x, z, even, beta, delta, zeta, eps, wd, zs, kmat, sub, nvec)
    g0, g1 = _circle_factors(nvec, 5, delta, q)
    return g0 if f == 0 else g1


@kernel
def _m2_zero(a, b, fa, fb, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat, sub, nvec):
    """Root of circle factor ``f`` in ``[a, b]`` (``fa fb <= 0``): Brent's method, a few ulps."""
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    c = a
    fc = fa
    d = b - a
    e = d
    for _ in range(ROOT_MAXIT):
        if (fb > 0.0) == (fc > 0.0):
            c = a
            fc = fa
            d = b - a
            e = d
        if abs(fc) < abs(fb):
            a = b
            b = c
            c = a
            fa = fb
            fb = fc
            fc = fa
        tol = BRENT_ROOT_REL * abs(b) + TINY
        xm = 0.5 * (c - b)
        if abs(xm) <= tol or fb == 0.0:
            return b
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:
                p = 2.0 * xm * s
                qq = 1.0 - s
            else:
                qq = fa / fc
                r = fb / fc
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0))
                qq = (qq - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                qq = -qq
            else:
                p = -p
            if 2.0 * p < min(3.0 * xm * qq - abs(tol * qq), abs(e * qq)):
                e = d
                d = p / qq
            else:
                d = xm
                e = d
        else:
            d = xm
            e = d
        a = b
        fa = fb
        if abs(d) > tol:
            b += d
        else:
            b += tol if xm > 0.0 else -tol
        fb = _m2_factor(b, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat, sub, nvec)
    return b


@kernel
def _m2_dip(a, b, x, fx, sgn, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat, sub, nvec):
    """Minimum of ``sgn g`` (g: circle factor ``f``) on ``[a, b]`` from the node ``x`` (Brent).

    Returns ``(x, sgn g(x))``, at once when ``sgn g`` drops to <= 0 (then ``[a, x]`` and
    ``[x, b]`` each bracket a root: the pair of a near-double root, next to a fold).
    """
    tol1 = TANGENCY_XTOL * (b - a)
    v = x
    w = x
    fv = fx
    fw = fx
    d = 0.0
    e = 0.0
    for _ in range(ROOT_MAXIT):
        xm = 0.5 * (a + b)
        tol2 = 2.0 * tol1
        if abs(x - xm) <= tol2 - 0.5 * (b - a):
            break
        parabolic = False
        if abs(e) > tol1:
            r = (x - w) * (fx - fv)
            qq = (x - v) * (fx - fw)
            p = (x - v) * qq - (x - w) * r
            qq = 2.0 * (qq - r)
            if qq > 0.0:
                p = -p
            else:
                qq = -qq
            if abs(p) < abs(0.5 * qq * e) and p > qq * (a - x) and p < qq * (b - x):
                e = d
                d = p / qq
                u = x + d
                if u - a < tol2 or b - u < tol2:
                    d = tol1 if xm >= x else -tol1
                parabolic = True
        if not parabolic:
            e = (a - x) if x >= xm else (b - x)
            d = GOLDEN_SECTION * e
        u = x + d if abs(d) >= tol1 else x + (tol1 if d > 0.0 else -tol1)
        fu = sgn * _m2_factor(u, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat, sub, nvec)
        if fu <= 0.0:
            return u, fu
        if fu <= fx:
            if u >= x:
                a = x
            else:
                b = x
            v = w
            fv = fw
            w = x
            fw = fx
            x = u
            fx = fu
        else:
            if u < x:
                a = u
            else:
                b = u
            if fu <= fw or w == x:
                v = w
                fv = fw
                w = u
                fw = fu
            elif fu <= fv or v == x or v == w:
                v = u
                fv = fu
    return x, fx


@kernel
def _m2_solution(x, f, n, beta, delta, zeta, eps, scale, zs, kmat, sub, nvec, y, sols, count,
                 work, jac):
    """The (2/n) solution at the root ``z_1 = x`` of circle factor ``f``, into ``sols``.

    At fixed intervals eqs. (10)-(11) are linear, so the root gives the solution directly; it
    is kept as it is when its residual is below NEWTON_RTOL (no Newton: its intervals are exact
    even where the full system is near singular), and polished by Newton otherwise.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    tf = 2.0 * pi / beta
    even = n % 2 == 0
    _m2_null(x, z, even, beta, delta, zeta, eps, wd, zs, kmat, sub, nvec)
    zs[0] = x
    zs[1] = z - x
    if not _guess_from_null(nvec, 2, zs, q, phi, beta, 1.0 if f == 0 else -1.0, y):
        return count
    res = work[WORK_RES]
    _residual_jacobian(y, 2, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
    if _norm(res, 4) <= NEWTON_RTOL * scale:
        if _valid(y, 2, z):
            rho = uncertainty(y, 2, z, beta, delta, zeta, eps, scale, tf, scale)
            count = _accept(y, rho, 0.0, 2, z, tf, scale, sols, count)
        return count
    return _try_start(y, 2, z, beta, delta, zeta, eps, scale, tf, scale, sols, count, work, jac)


@kernel
def _scan_m2(n, beta, delta, zeta, eps, scan_step, sols, count, work, jac):
    """Every (2/n) solution from the circle condition along ``0 < z_1 < z`` (see solve_general)."""
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    scale = 1.0 + abs(delta) + q * (1.0 + beta)
    even = n % 2 == 0
    fast = max(beta, wd)
    kmat = np.empty((4, 5))
    sub = np.empty((4, 5))
    nvec = np.empty(5)
    zs = np.empty(2)
    y = np.empty(4)
    # nodes: uniform inside, geometric towards both ends (z_1 -> 0 and z_2 -> 0), where a
    # solution with a very short flight lives and a zero-length flight makes K singular; for
    # even n an odd count puts a node at z/2, which the (2/n) pair born from the doubled
    # (1/(n/2)) motion straddles
    npt = max(M2_MIN_NODES, int(ceil(z * fast / scan_step)))
    if even and npt % 2 == 0:
        npt += 1
    nodes = np.empty(npt + 2 * EDGE_LEVELS)
    for k in range(EDGE_LEVELS):
        nodes[k] = z / npt * 10.0 ** (k - EDGE_LEVELS)
        nodes[npt + 2 * EDGE_LEVELS - 1 - k] = z - nodes[k]
    for k in range(npt):
        nodes[EDGE_LEVELS + k] = z * (k + 0.5) / npt
    nnode = nodes.shape[0]
    gval = np.empty((2, nnode))
    for k in range(nnode):
        _m2_null(nodes[k], z, even, beta, delta, zeta, eps, wd, zs, kmat, sub, nvec)
        gval[0, k], gval[1, k] = _circle_factors(nvec, 5, delta, q)
    for f in range(2):
        for k in range(nnode - 1):
            h0 = gval[f, k]
            h1 = gval[f, k + 1]
            if not (h0 * h1 <= 0.0 and h0 != h1):
                continue
            x = _m2_zero(nodes[k], nodes[k + 1], h0, h1, f, z, even, beta, delta, zeta, eps, wd,
                         q, zs, kmat, sub, nvec)
            count = _m2_solution(x, f, n, beta, delta, zeta, eps, scale, zs, kmat, sub, nvec, y,
                                 sols, count, work, jac)
        # near-tangencies: both roots of a near-double root in the cells next to a node
        for k in range(1, nnode - 1):
            gk = gval[f, k]
            if gk == 0.0:
                continue
            sgn = 1.0 if gk > 0.0 else -1.0
            pl = sgn * gval[f, k - 1]
            pk = sgn * gk
            pr = sgn * gval[f, k + 1]
            if not (pl > 0.0 and pr > 0.0 and pk < pl and pk <= pr):
                continue                     # no dip toward zero here (or already bracketed)
            xl = nodes[k - 1]
            xk = nodes[k]
            xr = nodes[k + 1]
            d1 = (pk - pl) / (xk - xl)
            a2 = ((pr - pk) / (xr - xk) - d1) / (xr - xl)
            slope = d1 + a2 * (xk - xl)
            wide = max(xk - xl, xr - xk)
            if pk - slope * slope / (4.0 * a2) > TANGENCY_MARGIN * a2 * wide * wide:
                continue
            xm, pm = _m2_dip(xl, xr, xk, pk, sgn, f, z, even, beta, delta, zeta, eps, wd, q, zs,
                             kmat, sub, nvec)
            if pm > 0.0:
                continue
            for side in range(2):
                a = xl if side == 0 else xm
                b = xm if side == 0 else xr
                fa = sgn * (pl if side == 0 else pm)
                fb = sgn * (pm if side == 0 else pr)
                x = _m2_zero(a, b, fa, fb, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat,
                             sub, nvec)
                count = _m2_solution(x, f, n, beta, delta, zeta, eps, scale, zs, kmat, sub,
                                     nvec, y, sols, count, work, jac)
    return count
