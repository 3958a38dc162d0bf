"""Numba kernels for the periodic impact motions of section 4 (used by ``vibroimpact.orbits``).

Pure functions of numbers and preallocated arrays: no I/O, no Python objects. Notation follows
the paper and docs/model.md (section 8): forcing ``sin(beta*tau)``, wall at ``x = delta``,
``wd = sqrt(1 - zeta**2)``, steady harmonic response ``x_p = q sin(beta*tau - phi)``.

A free flight starting on the wall at ``tau_a`` with approach velocity ``u_a`` (so leaving with
``-eps*u_a``) is, with ``psi = beta*tau_a - phi`` and ``s = tau - tau_a``::

    x(s) = q sin(beta s + psi) + P11(s) A + P12(s) B,   A = delta - q sin psi,
    v(s) = q beta cos(beta s + psi) + P21(s) A + P22(s) B,   B = -eps u_a - q beta cos psi,

where ``P(s)`` is the damped free propagator of ``y'' + 2 zeta y' + y = 0``.
"""
import numpy as np
from math import acos, atan2, ceil, cos, cosh, exp, floor, hypot, pi, sin, sinh, sqrt
from numba import njit, prange

#: Reason codes of the map (``orbits.api.Reason``): why a point has no stable motion of a type.
REASON_STABLE, REASON_NO_SOLUTION, REASON_INADMISSIBLE, REASON_UNSTABLE = 0, 1, 2, 3

# Numerical thresholds (one place).
NEWTON_MAXIT = 30
NEWTON_GIVE_UP_IT = 10       # a start still this far off after this many steps is abandoned
NEWTON_GIVE_UP_RTOL = 1e-4
NEWTON_RTOL = 1e-12          # residual tolerance, relative to the problem's displacement scale
# Float64 evaluation noise of the residual at an exact solution, relative to the scale: measured
# <= 2.5e-15 (median 2.4e-16) at 150 mpmath-polished orbits of (1/1), (2/1), (2/2), (1/2); 4x
# that. Below it a Newton step is driven by round-off alone (near a fold or a period doubling,
# where |mu - 1| is tiny, such a step moves the orbit by noise/|mu - 1|), so Newton stops there.
RESIDUAL_NOISE_RTOL = 1e-14
# Once the residual is below NEWTON_RTOL, Newton goes on while a full step at least halves the
# residual (quadratic convergence does far better) and stops when it does not: the step is then
# dominated by round-off and would only move the solution along a near-null direction.
NEWTON_POLISH_DECREASE = 0.5
NEWTON_STEP_RTOL = 1e-14     # converged on the step: |dy_i| <= this * (1 + |y_i|) (a few ulps)
SAME_ORBIT_RTOL = 1e-7       # two solutions closer than this (phase/T_f, velocity/scale) are one
# Uncertainty of a solution (added to SAME_ORBIT_RTOL in the dedupe and repeated-orbit tests):
# UNCERTAINTY_SAFETY * |J^-1| (residual + noise), per component, in the units of
# SAME_ORBIT_RTOL. The factor covers the first-order bound's neglect of curvature (a Newton
# point stopped in the flat, noise-level region between close roots: then the bound is >= its
# distance to either root for any factor >= 1). At the doubled (1/1) motion 1e-10 in delta from
# a period doubling the bound is 6e-5 .. 3e-3 (it takes the noise at its ceiling), while Newton
# copies of that motion landed ~5e-7 off it (relative): the cap decides there. It is 100 x
# SAME_ORBIT_RTOL, above those copies' errors and 10 x below the 1e-4 at which the independent
# check pairs orbits, so a (near) singular J never merges orbits that are clearly apart.
UNCERTAINTY_SAFETY = 4.0
UNCERTAINTY_CAP = 1e-5
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
# m = 2 scan, near-tangencies: a local extremum of a circle factor (no sign change around it)
# is refined when the parabola through its three nodes comes within TANGENCY_MARGIN * a2 H^2
# of zero (a2: the parabola's curvature, H: the wider cell). The parabola predicts the
# extremum to ~H g'''/g'' (~2% at 0.02 rad nodes) of a2 H^2, so a pair of roots hidden in
# the cells (the two orbits next to a fold, ~sqrt(distance) apart) is never skipped.
TANGENCY_MARGIN = 1.0
# The refinement (Brent's minimization) stops at this fraction of the two cells: a hidden pair
# ~1e-7 apart (a fold ~1e-14 away in delta) still shows a negative value at that resolution.
TANGENCY_XTOL = 1e-9
ROOT_MAXIT = 100             # Brent root/minimum iterations (bisection bound ~60 for float64)
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
def _norm(v, n):
    acc = 0.0
    for i in range(n):
        acc += v[i] * v[i]
    return sqrt(acc)


@njit(cache=True)
def newton(y, m, z, beta, delta, zeta, eps, scale, res, jac, dy, ytry):
    """Damped Newton with the analytic Jacobian, in place on ``y``.

    Returns ``(converged, residual norm at y)``. Converged means a residual <= NEWTON_RTOL
    times ``scale`` *and* a settled position: Newton goes on below that tolerance while full
    steps keep cutting the residual (by NEWTON_POLISH_DECREASE at least) and stops on a step
    of a few ulps, at the round-off floor (RESIDUAL_NOISE_RTOL) or when a step no longer
    helps; a step that does not help is not taken (near a singular Jacobian it would only
    carry the solution along the near-null direction, by noise / |mu - 1|).
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    nn = 2 * m
    tol = NEWTON_RTOL * scale
    floor_ = RESIDUAL_NOISE_RTOL * scale
    _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
    nr = _norm(res, nn)
    for it in range(NEWTON_MAXIT):
        if not np.isfinite(nr) or (it >= NEWTON_GIVE_UP_IT and nr > NEWTON_GIVE_UP_RTOL * scale):
            return False, nr
        if nr <= floor_:
            return True, nr
        for i in range(nn):
            dy[i] = -res[i]
        if not _solve_inplace(jac, dy, nn):
            return nr <= tol, nr
        polishing = nr <= tol
        step = 1.0
        accepted = False
        nt = nr
        for _ in range(1 if polishing else 8):
            for i in range(nn):
                ytry[i] = y[i] + step * dy[i]
            _residual_jacobian(ytry, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
            nt = _norm(res, nn)
            if polishing:
                accepted = nt <= NEWTON_POLISH_DECREASE * nr
                break
            if nt < nr:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            return nr <= tol, nr               # y unchanged (res, jac: the rejected trial)
        small = True
        for i in range(nn):
            if abs(ytry[i] - y[i]) > NEWTON_STEP_RTOL * (1.0 + abs(y[i])):
                small = False
            y[i] = ytry[i]
        nr = nt
        if small and nr <= tol:
            return True, nr
    return nr <= tol, nr


@njit(cache=True)
def uncertainty(y, m, z, beta, delta, zeta, eps, scale, tf, uscale):
    """Error bound of the solution ``y`` in the units of SAME_ORBIT_RTOL (phase / T_f,
    velocity / uscale), from the conditioning of eqs. (10)-(11) there.

    ``UNCERTAINTY_SAFETY * max_i sum_j |J^-1_ij| (|res| + noise)`` over the phases (over
    ``tf``) and the velocities (over ``uscale``), capped at UNCERTAINTY_CAP. Next to a fold or
    a period doubling (|mu - 1| small) round-off alone leaves a Newton solution this far off.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    nn = 2 * m
    res = np.empty(nn)
    jac = np.empty((nn, nn))
    a = np.empty((nn, nn))
    col = np.empty(nn)
    rows = np.zeros(nn)
    _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
    err = _norm(res, nn) + RESIDUAL_NOISE_RTOL * scale
    for c in range(nn):
        for i in range(nn):
            for k in range(nn):
                a[i, k] = jac[i, k]
            col[i] = 0.0
        col[c] = 1.0
        if not _solve_inplace(a, col, nn):
            return UNCERTAINTY_CAP
        for i in range(nn):
            rows[i] += abs(col[i])
    worst = 0.0
    for i in range(m):
        worst = max(worst, rows[i] / tf, rows[m + i] / uscale)
    bound = UNCERTAINTY_SAFETY * worst * err
    if not bound < UNCERTAINTY_CAP:             # also NaN
        return UNCERTAINTY_CAP
    return bound


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
def _same_orbit(ya, yb, m, shift, tf, uscale, tol):
    """True when ``yb`` rotated by ``shift`` impacts is ``ya`` within ``tol`` (phases mod T_f
    over T_f, velocities over ``uscale``)."""
    for j in range(m):
        k = (j + shift) % m
        if _circ_dist(ya[j], yb[k], tf) > tol * tf:
            return False
        if abs(ya[m + j] - yb[m + k]) > tol * uscale:
            return False
    return True


@njit(cache=True)
def _valid(y, m, z):
    """Positive approach velocities and increasing impact instants within one period."""
    for j in range(m):
        if not (y[m + j] > 0.0):
            return False
    for j in range(1, m):
        if not (y[j] - y[j - 1] > 0.0):
            return False
    return y[0] + z - y[m - 1] > 0.0


@njit(cache=True)
def _accept(y, rho, rep_rho, m, z, tf, uscale, sols, count):
    """Append ``y`` (uncertainty ``rho``) to ``sols`` unless invalid, a duplicate, or a
    repeated shorter orbit; returns the new count.

    Rows of ``sols`` are ``(tau.., u.., rho)``. Two solutions are one orbit when they agree
    within ``SAME_ORBIT_RTOL + rho_a + rho_b`` (the uncertainty of a Newton solution grows like
    noise / |mu - 1| next to a fold or a period doubling); the better-conditioned copy is kept.
    ``y`` is a shorter orbit traversed repeatedly (e.g. the doubled (1/1) motion among the
    (2/2) solutions) when it is its own rotation within ``SAME_ORBIT_RTOL + 2 rep_rho``: pass
    ``rep_rho = rho`` for a Newton solution, 0 for one whose intervals are exact (the m = 2
    scan's, whose circle condition stays regular at the doubled motion).
    """
    if not _valid(y, m, z):
        return count
    nn = 2 * m
    for r in range(1, m):
        if _same_orbit(y, y, m, r, tf, uscale, SAME_ORBIT_RTOL + 2.0 * rep_rho):
            return count                       # a shorter orbit traversed m/r times
    for i in range(count):
        tol = SAME_ORBIT_RTOL + rho + sols[i, nn]
        for r in range(m):
            if _same_orbit(sols[i], y, m, r, tf, uscale, tol):
                if rho < sols[i, nn]:
                    for c in range(nn):
                        sols[i, c] = y[c]
                    sols[i, nn] = rho
                return count
    if count >= sols.shape[0]:
        return count
    for c in range(nn):
        sols[count, c] = y[c]
    sols[count, nn] = rho
    return count + 1


@njit(cache=True)
def _try_start(y, m, z, beta, delta, zeta, eps, scale, tf, uscale, sols, count, work, jac):
    """Newton from ``y``; a converged, valid solution goes to ``_accept``."""
    res = work[0]
    dy = work[1]
    ytry = work[2]
    conv, _ = newton(y, m, z, beta, delta, zeta, eps, scale, res, jac, dy, ytry)
    if conv and _valid(y, m, z):
        rho = uncertainty(y, m, z, beta, delta, zeta, eps, scale, tf, uscale)
        count = _accept(y, rho, rho, m, z, tf, uscale, sols, count)
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


# --- m = 2: the circle condition along z_1, exact roots ------------------------------------

@njit(cache=True)
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


@njit(cache=True)
def _fill_symmetric_system(o, h, beta, delta, zeta, eps, wd, kmat):
    """(2/n) system for even n at ``z_1 = h + o``, ``z_2 = h - o`` (``h = z/2``), regular at o = 0.

    For even n the flights' forcing phases differ by ``beta o`` only, and at o = 0 the four
    rows of ``_fill_interval_system`` have rank 3: the doubled (1/(n/2)) motion solves them for
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


@njit(cache=True)
def _m2_null(x, z, even, beta, delta, zeta, eps, wd, zs, kmat, sub, nvec):
    """Null vector ``(S0, C0, u_0, u_1, t)`` of the (2/n) equations at ``z_1 = x``, in ``nvec``."""
    if even:
        h = 0.5 * z
        o = x - h
        _fill_symmetric_system(o, h, beta, delta, zeta, eps, wd, kmat)
        _cofactors(kmat, 0, 5, sub, nvec)
        up = nvec[2]
        ub = nvec[3]
        nvec[2] = up + o * ub
        nvec[3] = up - o * ub
    else:
        zs[0] = x
        zs[1] = z - x
        _fill_interval_system(zs, 2, beta, delta, zeta, eps, wd, kmat)
        _cofactors(kmat, 0, 5, sub, nvec)


@njit(cache=True)
def _m2_factor(x, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat, sub, nvec):
    """Circle factor ``f`` (0 or 1, ``_circle_factors``) of the (2/n) equations at ``z_1 = x``."""
    _m2_null(x, z, even, beta, delta, zeta, eps, wd, zs, kmat, sub, nvec)
    g0, g1 = _circle_factors(nvec, 5, delta, q)
    return g0 if f == 0 else g1


@njit(cache=True)
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
        tol = 4.4e-16 * abs(b) + 1e-300
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


@njit(cache=True)
def _m2_dip(a, b, x, fx, sgn, f, z, even, beta, delta, zeta, eps, wd, q, zs, kmat, sub, nvec):
    """Minimum of ``sgn g`` (g: circle factor ``f``) on ``[a, b]`` from the node ``x`` (Brent).

    Returns ``(x, sgn g(x))``, at once when ``sgn g`` drops to <= 0 (then ``[a, x]`` and
    ``[x, b]`` each bracket a root: the pair of a near-double root, next to a fold).
    """
    golden = 0.3819660112501051
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
            d = golden * e
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


@njit(cache=True)
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
    res = work[0]
    _residual_jacobian(y, 2, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
    if _norm(res, 4) <= NEWTON_RTOL * scale:
        if _valid(y, 2, z):
            rho = uncertainty(y, 2, z, beta, delta, zeta, eps, scale, tf, scale)
            count = _accept(y, rho, 0.0, 2, z, tf, scale, sols, count)
        return count
    return _try_start(y, 2, z, beta, delta, zeta, eps, scale, tf, scale, sols, count, work, jac)


@njit(cache=True)
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
    npt = max(16, int(ceil(z * fast / scan_step)))
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
        return _scan_m2(n, beta, delta, zeta, eps, scan_step, sols, count, work, jac)
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
        conv, _ = newton(y, m, z, beta, delta, zeta, eps, scale, work[0], jac, work[1],
                         work[2])
        if not conv or not _valid(y, m, z):
            return
        rho = uncertainty(y, m, z, beta, delta, zeta, eps, scale, tf, scale)
        before = counts[dd]
        counts[dd] = _accept(y, rho, rho, m, z, tf, scale, sols[dd], before)
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
        sols = np.empty((nd, MAX_SOLUTIONS, nn + 1))   # rows (tau.., u.., uncertainty)
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
                reason[t, ib, d] = REASON_STABLE
            elif counts[d] == 0:
                reason[t, ib, d] = REASON_NO_SOLUTION
            elif n_adm == 0:
                reason[t, ib, d] = REASON_INADMISSIBLE
            else:
                reason[t, ib, d] = REASON_UNSTABLE


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
