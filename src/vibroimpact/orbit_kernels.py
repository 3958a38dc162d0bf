"""Numba kernels for the periodic impact motions of section 4 (used by ``vibroimpact.orbits``).

Pure functions of numbers and preallocated arrays: no I/O, no Python objects. Notation follows
the paper and ``shared/spec/MODEL.md``: forcing ``sin(beta*tau)``, wall at ``x = delta``,
``wd = sqrt(1 - zeta**2)``, steady harmonic response ``x_p = q sin(beta*tau - phi)``.

A free flight starting on the wall at ``tau_a`` with approach velocity ``u_a`` (so leaving with
``-eps*u_a``) is, with ``psi = beta*tau_a - phi`` and ``s = tau - tau_a``::

    x(s) = q sin(beta s + psi) + P11(s) A + P12(s) B,   A = delta - q sin psi,
    v(s) = q beta cos(beta s + psi) + P21(s) A + P22(s) B,   B = -eps u_a - q beta cos psi,

where ``P(s)`` is the damped free propagator of ``y'' + 2 zeta y' + y = 0``.
"""
import numpy as np
from math import acos, atan2, ceil, cos, exp, floor, hypot, pi, sin, sqrt
from numba import njit, prange

# Numerical thresholds (one place).
NEWTON_MAXIT = 30
NEWTON_GIVE_UP_IT = 10       # a start still this far off after this many steps is abandoned
NEWTON_GIVE_UP_RTOL = 1e-4
NEWTON_RTOL = 1e-12          # residual tolerance, relative to the problem's displacement scale
SAME_ORBIT_RTOL = 1e-7       # two solutions closer than this (phase/T_f, velocity/scale) are one
ADMISSIBLE_TOL = 1e-12       # margin >= -tol counts as admissible (grazing is the edge, included)
MAX_SOLUTIONS = 64           # capacity per (m/n) type and parameter point
# Interval-scan steps, in radians of the fastest of beta and wd (m = 2: 1-D scan, m = 3: per
# axis of a 2-D scan); the map also follows branches, so it affords a coarser scan.
SCAN_STEP_M2 = 0.02
SCAN_STEP_M3 = 0.12
EDGE_LEVELS = 6              # m = 2 scan: extra nodes at 10^-6 .. 10^-1 steps from both ends
MAP_SCAN_STEP_M2 = SCAN_STEP_M2   # m = 2 scans are cheap: the map scans every point
MAP_SCAN_STEP_M3 = 0.25
MAP_SCAN_EVERY = 4           # map: global scan at every 4th delta; branches followed in between
FLIGHT_PHASE_STEP = 0.5      # admissibility: initial bracketing step (radians), refined by bounds
FLIGHT_MIN_STEP = 1e-9       # admissibility: smallest bracket before giving up refinement


@njit(cache=True)
def harmonic_constants(beta, zeta):
    """Return ``(wd, q, phi)``: damped frequency, steady amplitude and phase lag of sin(beta tau)."""
    wd = sqrt(1.0 - zeta * zeta)
    q = 1.0 / sqrt((1.0 - beta * beta) ** 2 + (2.0 * zeta * beta) ** 2)
    phi = atan2(2.0 * zeta * beta, 1.0 - beta * beta)
    return wd, q, phi


@njit(cache=True)
def propagator(s, zeta, wd):
    """Entries of the free propagator ``P(s)`` mapping ``(y, y')(0)`` to ``(y, y')(s)``."""
    e = exp(-zeta * s)
    c = cos(wd * s)
    sn = sin(wd * s) / wd
    return e * (c + zeta * sn), e * sn, -e * sn, e * (c - zeta * sn)


@njit(cache=True)
def flight(tau_a, u_a, s, beta, delta, zeta, eps, wd, q, phi):
    """State ``x, v, acc`` at ``tau_a + s`` of the flight leaving the wall at ``tau_a``.

    Also returns the propagator entries at ``s`` (needed by the Jacobians).
    """
    psi = beta * tau_a - phi
    a_coef = delta - q * sin(psi)
    b_coef = -eps * u_a - q * beta * cos(psi)
    p11, p12, p21, p22 = propagator(s, zeta, wd)
    th = beta * s + psi
    x = q * sin(th) + p11 * a_coef + p12 * b_coef
    v = q * beta * cos(th) + p21 * a_coef + p22 * b_coef
    acc = sin(beta * (tau_a + s)) - 2.0 * zeta * v - x
    return x, v, acc, p11, p12, p21, p22


@njit(cache=True)
def impact_map_jacobian(tau_a, u_a, tau_b, u_b, beta, delta, zeta, eps, wd, q, phi):
    """2x2 Jacobian ``T_j`` of ``(tau_{j-1}, u_{j-1}) -> (tau_j, u_j)`` (paper eqs. 14-15).

    Notes
    -----
    Implicit differentiation of ``x(tau_j; tau_{j-1}, u_{j-1}) = delta``. Moving the start by
    ``d tau`` perturbs the state by ``(eps u_a, delta - f(tau_a) - 2 zeta eps u_a) d tau``, which
    the propagator carries to the impact; ``det T_j = eps^2 (u_{j-1}/u_j) exp(-2 zeta z_j)``.
    """
    x, v, acc, p11, p12, p21, p22 = flight(tau_a, u_a, tau_b - tau_a, beta, delta, zeta, eps,
                                           wd, q, phi)
    g_a = delta - sin(beta * tau_a) - 2.0 * zeta * eps * u_a
    dx_dta = p11 * eps * u_a + p12 * g_a
    dv_dta = p21 * eps * u_a + p22 * g_a
    a_b = sin(beta * tau_b) - 2.0 * zeta * u_b - delta   # x'' just before the impact
    t11 = -dx_dta / u_b
    t12 = eps * p12 / u_b
    t21 = dv_dta + a_b * t11
    t22 = -eps * p22 + a_b * t12
    return t11, t12, t21, t22


@njit(cache=True)
def monodromy(y, m, z, beta, delta, zeta, eps, out):
    """One-period Jacobian ``T = T_m ... T_1`` (eq. 18) of the solution ``y`` into ``out`` (2x2).

    ``y = (tau_0..tau_{m-1}, u_0..u_{m-1})`` with ``u_j`` the approach velocity at ``tau_j``.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    r11, r12, r21, r22 = 1.0, 0.0, 0.0, 1.0
    for j in range(1, m + 1):
        a = j - 1
        b = j % m
        tb = y[b] + (z if j == m else 0.0)
        t11, t12, t21, t22 = impact_map_jacobian(y[a], y[m + a], tb, y[m + b], beta, delta,
                                                 zeta, eps, wd, q, phi)
        r11, r12, r21, r22 = (t11 * r11 + t12 * r21, t11 * r12 + t12 * r22,
                              t21 * r11 + t22 * r21, t21 * r12 + t22 * r22)
    out[0, 0] = r11
    out[0, 1] = r12
    out[1, 0] = r21
    out[1, 1] = r22


# --------------------------------------------------------------------------------------------
# small dense linear algebra on preallocated scratch (no allocation in the scans)

@njit(cache=True)
def _solve_inplace(a, b, n):
    """Solve ``a[:n,:n] x = b[:n]`` in place (x in b); returns False if singular."""
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        if big == 0.0 or not np.isfinite(big):
            return False
        if p != k:
            for c in range(k, n):
                tmp = a[k, c]
                a[k, c] = a[p, c]
                a[p, c] = tmp
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
        piv = a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] / piv
            if f != 0.0:
                for c in range(k + 1, n):
                    a[i, c] -= f * a[k, c]
                b[i] -= f * b[k]
    for k in range(n - 1, -1, -1):
        s = b[k]
        for c in range(k + 1, n):
            s -= a[k, c] * b[c]
        b[k] = s / a[k, k]
    return True


@njit(cache=True)
def _cofactors(kmat, row0, ncol, sub, out):
    """Signed cofactors of the ``(ncol-1) x ncol`` block ``kmat[row0:row0+ncol-1]``.

    ``out[k] = (-1)^k det(block without column k)``: the generalized cross product, a null
    vector of the block and a polynomial (smooth) function of its entries. One elimination with
    partial pivoting; ``out`` is all zero when the first ``ncol-1`` columns are singular.
    """
    r = ncol - 1
    for i in range(r):
        for c in range(ncol):
            sub[i, c] = kmat[row0 + i, c]
    sgn = 1.0
    prod = 1.0
    for k in range(r):
        p = k
        big = abs(sub[k, k])
        for i in range(k + 1, r):
            if abs(sub[i, k]) > big:
                big = abs(sub[i, k])
                p = i
        if big == 0.0:
            for c in range(ncol):
                out[c] = 0.0
            return
        if p != k:
            sgn = -sgn
            for c in range(k, ncol):
                tmp = sub[k, c]
                sub[k, c] = sub[p, c]
                sub[p, c] = tmp
        piv = sub[k, k]
        prod *= piv
        for i in range(k + 1, r):
            f = sub[i, k] / piv
            if f != 0.0:
                for c in range(k + 1, ncol):
                    sub[i, c] -= f * sub[k, c]
    # null vector with last component 1, then scaled to the cofactor normalization
    out[r] = 1.0
    for k in range(r - 1, -1, -1):
        acc = sub[k, r]
        for c in range(k + 1, r):
            acc += sub[k, c] * out[c]
        out[k] = -acc / sub[k, k]
    c_last = sgn * prod * (1.0 if r % 2 == 0 else -1.0)
    for c in range(ncol):
        out[c] *= c_last


@njit(cache=True)
def _fill_interval_system(zs, m, beta, delta, zeta, eps, wd, kmat):
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


@njit(cache=True)
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


# --------------------------------------------------------------------------------------------
# Newton on the full 2m-equation system

@njit(cache=True)
def _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac):
    """Residual of eqs. (10)-(11) for ``y = (tau_0..tau_{m-1}, u_0..u_{m-1})`` and its Jacobian."""
    nn = 2 * m
    for i in range(nn):
        for c in range(nn):
            jac[i, c] = 0.0
    for j in range(1, m + 1):
        a = j - 1
        b = j % m
        ta = y[a]
        ua = y[m + a]
        tb = y[b] + (z if j == m else 0.0)
        x, v, acc, p11, p12, p21, p22 = flight(ta, ua, tb - ta, beta, delta, zeta, eps,
                                               wd, q, phi)
        r1 = 2 * (j - 1)
        r2 = r1 + 1
        res[r1] = x - delta
        res[r2] = v - y[m + b]
        g_a = delta - sin(beta * ta) - 2.0 * zeta * eps * ua
        jac[r1, a] += p11 * eps * ua + p12 * g_a
        jac[r2, a] += p21 * eps * ua + p22 * g_a
        jac[r1, m + a] += -eps * p12
        jac[r2, m + a] += -eps * p22
        jac[r1, b] += v
        jac[r2, b] += acc
        jac[r2, m + b] += -1.0


@njit(cache=True)
def newton(y, m, z, beta, delta, zeta, eps, scale, res, jac, dy, ytry):
    """Damped Newton with the analytic Jacobian, in place on ``y``; True when converged."""
    wd, q, phi = harmonic_constants(beta, zeta)
    nn = 2 * m
    tol = NEWTON_RTOL * scale
    _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
    nr = 0.0
    for i in range(nn):
        nr += res[i] * res[i]
    nr = sqrt(nr)
    polished = 0
    for it in range(NEWTON_MAXIT):
        if not np.isfinite(nr) or (it >= NEWTON_GIVE_UP_IT and nr > NEWTON_GIVE_UP_RTOL * scale):
            return False
        if nr <= tol:
            polished += 1
            if polished > 1:
                return True
        for i in range(nn):
            dy[i] = -res[i]
        if not _solve_inplace(jac, dy, nn):
            return nr <= tol
        step = 1.0
        accepted = False
        for _ in range(8):
            for i in range(nn):
                ytry[i] = y[i] + step * dy[i]
            _residual_jacobian(ytry, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
            nt = 0.0
            for i in range(nn):
                nt += res[i] * res[i]
            nt = sqrt(nt)
            if nt < nr or nt <= tol:
                accepted = True
                break
            step *= 0.5
        for i in range(nn):
            y[i] = ytry[i]
        if not accepted:
            return nt <= tol
        nr = nt
    return nr <= tol


# --------------------------------------------------------------------------------------------
# admissibility: the exact maximum of x over a flight

@njit(cache=True)
def _flight_xv(s, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q):
    e = exp(-zeta * s)
    cw = cos(wd * s)
    sw = sin(wd * s)
    th = beta * s + psi
    x = q * sin(th) + e * (a_coef * cw + c_coef * sw)
    v = q * beta * cos(th) + e * (b_coef * cw + d_coef * sw)
    # free-part derivative coefficients rotate with unit gain (zeta^2 + wd^2 = 1)
    b2 = -zeta * b_coef + wd * d_coef
    d2 = -zeta * d_coef - wd * b_coef
    acc = -q * beta * beta * sin(th) + e * (b2 * cw + d2 * sw)
    b3 = -zeta * b2 + wd * d2
    d3 = -zeta * d2 - wd * b2
    jerk = -q * beta ** 3 * cos(th) + e * (b3 * cw + d3 * sw)
    return x, v, acc, jerk


@njit(cache=True)
def flight_max(tau_a, u_a, s_end, beta, delta, zeta, eps, stack):
    """Largest interior local maximum of ``x`` on the flight ``(0, s_end)`` from ``tau_a``.

    Returns ``-inf`` when ``x`` has no interior local maximum. The maxima are the zeros of the
    velocity where it turns from + to -, found exactly (safeguarded Newton), and no zero is
    skipped: a bracket is accepted only when a bound on the next derivative proves that the
    velocity is monotone in it (at most one zero) or keeps its sign; otherwise it is bisected.
    ``stack`` is scratch of shape (k, 2).
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    psi = beta * tau_a - phi
    a_coef = delta - q * sin(psi)
    b_coef = -eps * u_a - q * beta * cos(psi)
    c_coef = (b_coef + zeta * a_coef) / wd
    d_coef = -(zeta * c_coef + wd * a_coef)
    amp = hypot(a_coef, c_coef)          # amplitude of every derivative of the free part
    fast = max(beta, wd)
    n0 = max(4, int(ceil(s_end * fast / FLIGHT_PHASE_STEP)))
    best = -np.inf
    cap = stack.shape[0]
    for k in range(n0):
        stack[0, 0] = s_end * k / n0
        stack[0, 1] = s_end * (k + 1) / n0
        top = 1
        while top > 0:
            top -= 1
            lo = stack[top, 0]
            hi = stack[top, 1]
            h = hi - lo
            xl, vl, al, jl = _flight_xv(lo, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q)
            xh, vh, ah, jh = _flight_xv(hi, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q)
            e_lo = exp(-zeta * lo)
            m2 = q * beta * beta + e_lo * amp    # bound of |acc| on [lo, hi]
            m3 = q * beta ** 3 + e_lo * amp      # bound of |jerk| on [lo, hi]
            if vl * vh > 0.0 and abs(vl) + abs(vh) > m2 * h:
                continue                          # velocity keeps its sign
            monotone = al * ah > 0.0 and abs(al) + abs(ah) > m3 * h
            if monotone:
                if vl > 0.0 and vh <= 0.0:
                    # one zero, a local maximum of x: safeguarded Newton on v
                    a_, b_ = lo, hi
                    s = 0.5 * (lo + hi)
                    for _ in range(60):
                        xs, vs, as_, js = _flight_xv(s, psi, a_coef, c_coef, b_coef, d_coef,
                                                     beta, zeta, wd, q)
                        if vs > 0.0:
                            a_ = s
                        else:
                            b_ = s
                        sn = s - vs / as_ if as_ != 0.0 else 0.5 * (a_ + b_)
                        if not (a_ < sn < b_):
                            sn = 0.5 * (a_ + b_)
                        if abs(sn - s) <= 1e-15 * (1.0 + abs(s)) or b_ - a_ <= 1e-15 * s_end:
                            s = sn
                            break
                        s = sn
                    xs, vs, as_, js = _flight_xv(s, psi, a_coef, c_coef, b_coef, d_coef,
                                                 beta, zeta, wd, q)
                    best = max(best, xs)
                continue
            if h <= FLIGHT_MIN_STEP * max(1.0, s_end) or top + 2 > cap:
                # unresolvable sliver around a (near) double zero of v: x is flat there
                if 0.0 < lo and hi < s_end:
                    best = max(best, max(xl, xh))
                continue
            mid = 0.5 * (lo + hi)
            stack[top, 0] = mid
            stack[top, 1] = hi
            stack[top + 1, 0] = lo
            stack[top + 1, 1] = mid
            top += 2
    return best


@njit(cache=True)
def orbit_margin(y, m, z, beta, delta, zeta, eps, stack):
    """Admissibility margin ``delta - max x`` over all flights (``inf`` if no interior maximum)."""
    worst = -np.inf
    for j in range(1, m + 1):
        a = j - 1
        b = j % m
        tb = y[b] + (z if j == m else 0.0)
        worst = max(worst, flight_max(y[a], y[m + a], tb - y[a], beta, delta, zeta, eps, stack))
    return delta - worst


# --------------------------------------------------------------------------------------------
# the (1/n) closed form

@njit(cache=True)
def solve_m1(n, beta, delta, zeta, eps, sols):
    """All (1/n) solutions in closed form; writes ``(tau_0, u_0)`` rows into ``sols``, returns count.

    Notes
    -----
    With ``z = 2 pi n / beta`` the particular solution returns to itself, so eqs. (10)-(11) are
    linear in ``(S0, C0, u) = (q sin psi_0, q cos psi_0, u)``. Eliminating ``u`` leaves one
    equation in the impact phase,
    ``a_S sin psi_0 + a_C cos psi_0 = delta a_S / q`` with
    ``a_S = 1 - P11 + eps (P22 - exp(-2 zeta z))`` and ``a_C = -beta (1 + eps) P12``,
    i.e. ``cos(psi_0 - chi) = kappa``: two roots when ``|kappa| < 1``, none when ``|kappa| > 1``.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    p11, p12, p21, p22 = propagator(z, zeta, wd)
    e2 = exp(-2.0 * zeta * z)
    a_s = 1.0 - p11 + eps * (p22 - e2)
    a_c = -beta * (1.0 + eps) * p12
    r = hypot(a_s, a_c)
    count = 0
    if r == 0.0:
        return 0
    kappa = delta * a_s / (q * r)
    if abs(kappa) > 1.0:
        return 0
    chi = atan2(a_s, a_c)
    dpsi = acos(kappa)
    nroot = 1 if dpsi == 0.0 else 2
    tf = 2.0 * pi / beta
    for k in range(nroot):
        psi = chi + dpsi if k == 0 else chi - dpsi
        s0 = q * sin(psi)
        c0 = q * cos(psi)
        # u from whichever of the two equations depends on it more strongly
        den2 = 1.0 + eps * p22
        den1 = -eps * p12
        if abs(den2) >= abs(den1):
            u = (-p21 * s0 + beta * (1.0 - p22) * c0 + delta * p21) / den2
        else:
            u = ((1.0 - p11) * (delta - s0) + beta * p12 * c0) / den1
        if not (u > 0.0):
            continue
        tau = (psi + phi) / beta
        tau -= tf * floor(tau / tf)
        if tau >= tf:
            tau -= tf
        sols[count, 0] = tau
        sols[count, 1] = u
        count += 1
    return count


# --------------------------------------------------------------------------------------------
# global search for m = 2, 3 (interval scans) and bookkeeping

@njit(cache=True)
def _circ_dist(a, b, period):
    d = abs(a - b) % period
    return min(d, period - d)


@njit(cache=True)
def _same_orbit(ya, yb, m, shift, tf, uscale):
    """True when ``yb`` rotated by ``shift`` impacts is ``ya`` (phases mod T_f, velocities)."""
    for j in range(m):
        k = (j + shift) % m
        if _circ_dist(ya[j], yb[k], tf) > SAME_ORBIT_RTOL * tf:
            return False
        if abs(ya[m + j] - yb[m + k]) > SAME_ORBIT_RTOL * uscale:
            return False
    return True


@njit(cache=True)
def _accept(y, m, z, tf, uscale, sols, count):
    """Append ``y`` to ``sols`` unless invalid, a duplicate, or a repeated shorter orbit."""
    for j in range(m):
        if not (y[m + j] > 0.0):
            return count
    for j in range(1, m):
        if not (y[j] - y[j - 1] > 0.0):
            return count
    if not (y[0] + z - y[m - 1] > 0.0):
        return count
    for r in range(1, m):
        if _same_orbit(y, y, m, r, tf, uscale):
            return count                       # a shorter orbit traversed m/r times
    for i in range(count):
        for r in range(m):
            if _same_orbit(sols[i], y, m, r, tf, uscale):
                return count
    if count >= sols.shape[0]:
        return count
    for i in range(2 * m):
        sols[count, i] = y[i]
    return count + 1


@njit(cache=True)
def _try_start(y, m, z, beta, delta, zeta, eps, scale, tf, uscale, sols, count, work, jac):
    res = work[0]
    dy = work[1]
    ytry = work[2]
    if newton(y, m, z, beta, delta, zeta, eps, scale, res, jac, dy, ytry):
        count = _accept(y, m, z, tf, uscale, sols, count)
    return count


@njit(cache=True)
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


@njit(cache=True)
def _start_from_intervals(zs, m, n, beta, delta, zeta, eps, sign, kmat, sub, nvec, y, sols,
                          count, work, jac):
    """Newton from the linear solution at fixed intervals ``zs``, scaled by ``sign q/|w_SC|``."""
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    tf = 2.0 * pi / beta
    scale = 1.0 + abs(delta) + q * (1.0 + beta)
    ncol = m + 3
    _fill_interval_system(zs, m, beta, delta, zeta, eps, wd, kmat)
    _cofactors(kmat, 2 * m - ncol + 1, ncol, sub, nvec)
    if _guess_from_null(nvec, m, zs, q, phi, beta, sign, y):
        count = _try_start(y, m, z, beta, delta, zeta, eps, scale, tf, scale, sols, count,
                           work, jac)
    return count


@njit(cache=True)
def _bilinear_root(a00, a10, a01, a11, b00, b10, b01, b11):
    """Common zero ``(s, t)`` of the bilinear interpolants of two functions on a unit cell.

    Returns ``(found, s, t)``; ``found`` when Newton converges within the cell widened by a
    quarter on each side. Screens scan cells whose zero curves pass near each other without
    crossing (frequent along the edges of the interval triangle).
    """
    s = 0.5
    t = 0.5
    for _ in range(12):
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
        if abs(s - 0.5) > 2.0 or abs(t - 0.5) > 2.0:
            return False, s, t
        if abs(ds) + abs(dt) < 1e-6:
            break
    return abs(s - 0.5) <= 0.75 and abs(t - 0.5) <= 0.75, s, t


@njit(cache=True)
def solve_general(m, n, beta, delta, zeta, eps, seeds, nseed, scan_step, sols):
    """All (m/n) solutions for m = 2, 3: interval scan (global) plus Newton from ``seeds``.

    Rows of ``sols``/``seeds``: ``(tau_0..tau_{m-1}, u_0..u_{m-1})``. ``scan_step`` is the
    scan's grid step in radians of the fastest of ``beta`` and ``wd`` (0: no scan, seeds only).
    Returns the count.

    Notes
    -----
    For fixed intervals the 2m equations are linear in ``(S0, C0, u_0..u_{m-1}, t=delta)``
    (``_fill_interval_system``). For m = 2 the 4x5 matrix has a cofactor null vector ``w(z_1)``
    and the solutions are the roots of ``h(z_1) = delta^2 (w_S^2 + w_C^2) - q^2 w_t^2`` (the
    circle condition), a smooth scalar function scanned over ``0 < z_1 < z``. For m = 3 the
    matrix is 6x6: the roots are the common zeros of ``det K`` and the same circle function
    (null vector of rows 1-5) on the triangle ``z_1 + z_2 < z``. Every bracket (a sign change
    of ``h``; a cell where both change sign) and every shallow local minimum of ``|h|`` (of the
    circle function in a cell where ``det K`` changes sign) seeds Newton on the full system.
    Each orbit appears m times in the scan (one per choice of first impact), so a bracket lost
    to a near-tangency is usually recovered from a rotation.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    tf = 2.0 * pi / beta
    nn = 2 * m
    scale = 1.0 + abs(delta) + q * (1.0 + beta)
    count = 0
    work = np.empty((3, nn))
    jac = np.empty((nn, nn))
    y = np.empty(nn)
    for i in range(nseed):
        for c in range(nn):
            y[c] = seeds[i, c]
        count = _try_start(y, m, z, beta, delta, zeta, eps, scale, tf, scale, sols, count,
                           work, jac)
    if scan_step <= 0.0:
        return count
    fast = max(beta, wd)
    ncol = m + 3
    kmat = np.empty((nn, ncol))
    sub = np.empty((nn, ncol))
    nvec = np.empty(ncol)
    zs = np.empty(m)
    if m == 2:
        # nodes: uniform inside, geometric towards both ends (z_1 -> 0 and z_2 -> 0), where a
        # solution with a very short flight lives and a zero-length flight makes K singular
        npt = max(16, int(ceil(z * fast / scan_step)))
        nodes = np.empty(npt + 2 * EDGE_LEVELS)
        for k in range(EDGE_LEVELS):
            nodes[k] = z / npt * 10.0 ** (k - EDGE_LEVELS)
            nodes[npt + 2 * EDGE_LEVELS - 1 - k] = z - nodes[k]
        for k in range(npt):
            nodes[EDGE_LEVELS + k] = z * (k + 0.5) / npt
        nnode = nodes.shape[0]
        gval = np.empty((2, nnode))
        for k in range(nnode):
            zs[0] = nodes[k]
            zs[1] = z - zs[0]
            _fill_interval_system(zs, m, beta, delta, zeta, eps, wd, kmat)
            _cofactors(kmat, 0, ncol, sub, nvec)
            gval[0, k], gval[1, k] = _circle_factors(nvec, ncol, delta, q)
        for f in range(2):
            sign = 1.0 if f == 0 else -1.0
            for k in range(nnode - 1):
                h0 = gval[f, k]
                h1 = gval[f, k + 1]
                cand = -1.0
                if h0 * h1 <= 0.0 and h0 != h1:
                    cand = nodes[k] + (nodes[k + 1] - nodes[k]) * h0 / (h0 - h1)
                elif (0 < k and abs(h0) < 0.3 and abs(h0) <= abs(gval[f, k - 1])
                      and abs(h0) <= abs(h1)):
                    cand = nodes[k]
                if cand <= 0.0 or cand >= z:
                    continue
                zs[0] = cand
                zs[1] = z - zs[0]
                count = _start_from_intervals(zs, m, n, beta, delta, zeta, eps, sign, kmat, sub,
                                              nvec, y, sols, count, work, jac)
        return count
    # m == 3: 2-D scan over (z_1, z_2), z_3 = z - z_1 - z_2. The nodes are offset by a third
    # of a step from the edges of the triangle, where a zero-length flight makes K singular.
    npt = max(12, int(ceil(z * fast / scan_step)))
    hz = z / npt
    f1 = np.empty((npt + 1, npt + 1))
    f2 = np.empty((2, npt + 1, npt + 1))
    for i in range(npt + 1):
        for k in range(npt + 1 - i):
            zs[0] = (i + 1.0 / 3.0) * hz
            zs[1] = (k + 1.0 / 3.0) * hz
            zs[2] = z - zs[0] - zs[1]            # slightly negative on the outer row: fine
            _fill_interval_system(zs, m, beta, delta, zeta, eps, wd, kmat)
            _cofactors(kmat, 1, ncol, sub, nvec)
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
                if (lo2 > 0.0 or hi2 < 0.0) and min(abs(lo2), abs(hi2)) > 0.1:
                    continue
                ok_, si, ti = _bilinear_root(a00, a10, a01, a11, b00, b10, b01, b11)
                if not ok_:
                    continue
                zs[0] = (i + 1.0 / 3.0 + si) * hz
                zs[1] = (k + 1.0 / 3.0 + ti) * hz
                zs[2] = z - zs[0] - zs[1]
                if zs[0] <= 0.0 or zs[1] <= 0.0 or zs[2] <= 0.0:
                    continue
                count = _start_from_intervals(zs, m, n, beta, delta, zeta, eps,
                                              1.0 if f == 0 else -1.0, kmat, sub, nvec, y,
                                              sols, count, work, jac)
    return count


# --------------------------------------------------------------------------------------------
# per-point classification and the tiled domain map

@njit(cache=True)
def solve_type(m, n, beta, delta, zeta, eps, seeds, nseed, scan_step, sols):
    """All (m/n) solutions (rows ``(tau.., u..)``) at one parameter point; returns the count."""
    if m == 1:
        return solve_m1(n, beta, delta, zeta, eps, sols)
    return solve_general(m, n, beta, delta, zeta, eps, seeds, nseed, scan_step, sols)


@njit(cache=True)
def lam_of(tmat, m):
    """``max|mu|^(1/m)`` from the trace and determinant of the one-period Jacobian."""
    tr = tmat[0, 0] + tmat[1, 1]
    det = tmat[0, 0] * tmat[1, 1] - tmat[0, 1] * tmat[1, 0]
    disc = tr * tr - 4.0 * det
    if disc >= 0.0:
        big = 0.5 * (abs(tr) + sqrt(disc))
    else:
        big = sqrt(max(det, 0.0))
    return big ** (1.0 / m)


@njit(cache=True)
def _follow_back(y0, m, n, beta, deltas, d_from, d_stop, zeta, eps, sols, counts, work, jac):
    """Continue the solution ``y0`` (at ``deltas[d_from]``) down to ``d_stop``, adding it where
    it is missing; stops when Newton fails or the branch is already known there."""
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    tf = 2.0 * pi / beta
    nn = 2 * m
    y = np.empty(nn)
    for c in range(nn):
        y[c] = y0[c]
    for dd in range(d_from - 1, d_stop - 1, -1):
        delta = deltas[dd]
        scale = 1.0 + abs(delta) + q * (1.0 + beta)
        if not newton(y, m, z, beta, delta, zeta, eps, scale, work[0], jac, work[1], work[2]):
            return
        before = counts[dd]
        counts[dd] = _accept(y, m, z, tf, scale, sols[dd], before)
        if counts[dd] == before:
            return


@njit(cache=True)
def _map_row(ib, beta, deltas, types, zeta, eps, exists, n_sol, n_stab, lam_best, reason):
    """One row of the map: all types at ``beta`` for every delta.

    For m = 2 the global interval scan runs at every point, as in ``periodic_orbits``. For
    m = 3 it runs every ``MAP_SCAN_EVERY`` points of delta (and at the last, and wherever a
    branch ends); in between, the solutions of the previous point seed Newton (branch following
    upward in delta), and every solution found by a scan is followed back down to the previous
    scan, so a branch born between two scans is filled in as well.
    """
    nd = deltas.shape[0]
    stack = np.empty((64, 2))
    tmat = np.empty((2, 2))
    for t in range(types.shape[0]):
        m = types[t, 0]
        n = types[t, 1]
        nn = 2 * m
        z = 2.0 * pi * n / beta
        sols = np.empty((nd, MAX_SOLUTIONS, nn))
        counts = np.zeros(nd, dtype=np.int64)
        work = np.empty((3, nn))
        jac = np.empty((nn, nn))
        scan_step = MAP_SCAN_STEP_M2 if m == 2 else MAP_SCAN_STEP_M3
        last_scan = 0
        for d in range(nd):
            prev = d - 1 if d > 0 else 0
            nseed = counts[prev] if d > 0 else 0
            scan = m == 2 or d % MAP_SCAN_EVERY == 0 or d == nd - 1
            counts[d] = solve_type(m, n, beta, deltas[d], zeta, eps, sols[prev], nseed,
                                   scan_step if scan else 0.0, sols[d])
            if m > 1 and not scan and counts[d] < nseed:
                # a branch ended (fold or an impact velocity reaching zero): others may start
                scan = True
                counts[d] = solve_type(m, n, beta, deltas[d], zeta, eps, sols[prev], nseed,
                                       scan_step, sols[d])
            if scan and m > 1 and d > 0:
                d_stop = max(0, last_scan)
                last_scan = d
                for s in range(counts[d]):
                    _follow_back(sols[d, s], m, n, beta, deltas, d, d_stop, zeta, eps, sols,
                                 counts, work, jac)
        for d in range(nd):
            delta = deltas[d]
            n_adm = 0
            n_st = 0
            best = np.inf
            for s in range(counts[d]):
                y = sols[d, s]
                if orbit_margin(y, m, z, beta, delta, zeta, eps, stack) < -ADMISSIBLE_TOL:
                    continue
                n_adm += 1
                monodromy(y, m, z, beta, delta, zeta, eps, tmat)
                lam = lam_of(tmat, m)
                if lam < 1.0:
                    n_st += 1
                best = min(best, lam)
            exists[t, ib, d] = n_adm > 0
            n_sol[t, ib, d] = n_adm
            n_stab[t, ib, d] = n_st
            lam_best[t, ib, d] = best if n_adm > 0 else np.nan
            if n_st > 0:
                reason[t, ib, d] = 0
            elif counts[d] == 0:
                reason[t, ib, d] = 1
            elif n_adm == 0:
                reason[t, ib, d] = 2
            else:
                reason[t, ib, d] = 3


@njit(cache=True, parallel=True)
def map_kernel(inv_beta, deltas, types, zeta, eps, row_order, exists, n_sol, n_stab, lam_best,
               reason):
    """Fill the domain-map arrays, one row of ``inv_beta`` per task, continuing along delta.

    ``row_order`` is a permutation of the rows: the cost of a row grows with 1/beta, so
    interleaving the rows balances the threads' contiguous chunks.
    """
    for k in prange(row_order.shape[0]):
        ib = row_order[k]
        _map_row(ib, 1.0 / inv_beta[ib], deltas, types, zeta, eps, exists, n_sol, n_stab,
                 lam_best, reason)
