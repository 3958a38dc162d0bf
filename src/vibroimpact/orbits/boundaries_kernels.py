"""Kernels of the stable-domain boundaries (Fig. 16): the test functions of an orbit and Newton
on the augmented system in ``X = (tau_0..tau_{m-1}, u_0..u_{m-1}, p, q)``, ``(p, q)`` the
plane's two parameters (Fig. 16's: ``(1/beta, delta)``).

The plane: ``prm`` holds every parameter ``(zeta, eps, 1/beta, delta, A)`` (`PRM_*` slots) and
``ax`` the slots of ``p`` and ``q``; `plane_point` reads ``(beta, delta / A, zeta, eps)`` of the
unit-force problem at ``X`` (the amplitude scales out: docs in `vibroimpact.orbits.plane`).
Over ``(1/beta, delta)`` with ``A = 1`` that is ``(1 / X[2m], X[2m+1], zeta, eps)``, the
arithmetic the kernels did before they knew of planes, bit for bit.

The stable admissible (m/n) orbits are those where every test function is positive:

- ``1 - tr T + det T`` (a multiplier at +1: fold) and ``1 + tr T + det T`` (at -1: period
  doubling); with ``det T < 1`` both positive is ``|mu| < 1``; both are taken times
  ``prod u_j > 0`` (``scaled_trace``), which keeps them smooth where an impact velocity -> 0;
- every approach velocity ``u_j`` (an impact velocity reaching 0: grazing impact);
- every flight's margin ``delta - max x`` (an interior maximum reaching the wall: grazing);
- every interval ``z_j`` (two impacts merging: the orbit stops existing).

A boundary point solves the 2m orbit equations plus one test function = 0 (2m + 1 equations,
2m + 2 unknowns: a curve); the last equation is the pseudo-arclength condition, a fixed
parameter, or a second test function (a codimension-two point).

Why numba: one Newton iteration costs ~2m + 3 evaluations of the orbit equations and of a
test function (central differences), each a few microseconds of scalar arithmetic; from
Python the call overhead alone (~1 us per scalar operation) would be larger than the work.

The impact law enters as in :mod:`vibroimpact.orbits.flight` (``rebound_velocity``,
``rebound_derivative``, ``rebound_ratio``); only ``det T = eps^(2m) exp(-2 zeta z)`` of the
fold and period-doubling conditions is Newton's law written out (docs/architecture.md, "Adding
physics").
"""
from math import ceil, cos, exp, pi, sin

import numpy as np

from vibroimpact._law import rebound_derivative, rebound_ratio, rebound_velocity
from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import _flight_xv, flight, flight_max, harmonic_constants
from vibroimpact.orbits.linalg import _solve_inplace
from vibroimpact.orbits.newton import _residual_jacobian
from vibroimpact.orbits.tolerances import (BOUNDARY_FD_REL, BOUNDARY_NEWTON_MAXIT,
                                           BOUNDARY_PEAK_STEP, BOUNDARY_STEP_RTOL)

#: Test-function codes (``cond_value``); the index ``j`` picks the impact / flight.
#: COND_OTHER_PEAK (flight j): the highest maximum of the flight other than the one followed.
COND_FOLD, COND_PD, COND_U, COND_MARGIN, COND_Z, COND_OTHER_PEAK = 0, 1, 2, 3, 4, 5
#: Slots of the parameter vector ``prm`` (`plane_point`).
PRM_ZETA, PRM_EPS, PRM_INV_BETA, PRM_DELTA, PRM_AMPLITUDE = 0, 1, 2, 3, 4


@kernel
def plane_point(x, nn, prm, ax):
    """``(beta, delta, zeta, eps)`` of the unit-force problem at ``x``: ``prm`` with its slots
    ``ax[0]``, ``ax[1]`` taken from ``x[nn]``, ``x[nn + 1]``; delta is the play over the
    amplitude. ``beta`` is 0 and the rest NaN-free but meaningless when the point is not a
    problem (`plane_valid`)."""
    zeta = prm[PRM_ZETA]
    eps = prm[PRM_EPS]
    inv_beta = prm[PRM_INV_BETA]
    delta = prm[PRM_DELTA]
    amp = prm[PRM_AMPLITUDE]
    for k in range(2):
        v = x[nn + k]
        slot = ax[k]
        if slot == PRM_ZETA:
            zeta = v
        elif slot == PRM_EPS:
            eps = v
        elif slot == PRM_INV_BETA:
            inv_beta = v
        elif slot == PRM_DELTA:
            delta = v
        else:
            amp = v
    return 1.0 / inv_beta, delta / amp, zeta, eps


@kernel
def plane_valid(x, nn, prm, ax):
    """Whether ``x``'s parameters are a problem: 1/beta > 0, A > 0, 0 < zeta < 1, eps >= 0."""
    for k in range(2):
        v = x[nn + k]
        slot = ax[k]
        if slot == PRM_ZETA:
            if not (0.0 < v < 1.0):
                return False
        elif slot == PRM_EPS:
            if not (v >= 0.0):
                return False
        elif slot == PRM_INV_BETA or slot == PRM_AMPLITUDE:
            if not (v > 0.0):
                return False
    return True


@kernel
def scaled_trace(y, m, z, beta, delta, zeta, eps):
    """``(tr M, U)`` with ``U = prod u_j`` and ``M = prod (u_j T_j) = U T`` (no division).

    Each ``u_j T_j`` is smooth where ``u_j -> 0`` (``T_j`` itself has ``1/u_j``), so the fold
    and period-doubling conditions ``U (1 + det T) -+ tr M = 0`` (``U`` times ``1 -+ tr T + det
    T``, ``det T = eps^(2m) exp(-2 zeta z)`` exactly) stay regular through a grazing impact,
    where a fold and a period-doubling curve meet the grazing curve ``u_j = 0``.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    r11, r12, r21, r22 = 1.0, 0.0, 0.0, 1.0
    prod_u = 1.0
    for jj in range(1, m + 1):
        a = jj - 1
        b = jj % m
        ta = y[a]
        ua = y[m + a]
        tb = y[b] + (z if jj == m else 0.0)
        ub = y[m + b]
        x, v, acc, p11, p12, p21, p22 = flight(ta, ua, tb - ta, beta, delta, zeta, eps, wd, q,
                                               phi)
        e_a = -rebound_ratio(eps, ua)                 # -v_+ = e_a ua
        g_a = delta - sin(beta * ta) - 2.0 * zeta * e_a * ua
        dx_dta = p11 * e_a * ua + p12 * g_a
        dv_dta = p21 * e_a * ua + p22 * g_a
        a_b = sin(beta * tb) - 2.0 * zeta * ub - delta
        s11 = -dx_dta
        s12 = -rebound_derivative(eps, ua) * p12
        s21 = ub * dv_dta + a_b * s11
        s22 = rebound_derivative(eps, ua) * p22 * ub + a_b * s12
        r11, r12, r21, r22 = (s11 * r11 + s12 * r21, s11 * r12 + s12 * r22,
                              s21 * r11 + s22 * r21, s21 * r12 + s22 * r22)
        prod_u *= ub
    return r11 + r22, prod_u


@kernel
def cond_value(code, j, y, m, n, beta, delta, zeta, eps, stack, tmat, smooth, hint):
    """Value of test function ``code`` (index ``j``) of the orbit ``y`` at ``(beta, delta)``.

    ``smooth``: the margin from ``flight_peak`` (a smooth function, for the curves'
    equations; the maximum nearest to the time ``hint`` after the impact, or the highest if
    ``hint < 0``) rather than ``flight_max`` (the global, certified maximum, for the signs).
    """
    z = 2.0 * pi * n / beta
    if code == COND_FOLD or code == COND_PD:
        tr_m, prod_u = scaled_trace(y, m, z, beta, delta, zeta, eps)
        det = eps ** (2 * m) * exp(-2.0 * zeta * z)
        if code == COND_FOLD:
            return prod_u * (1.0 + det) - tr_m
        return prod_u * (1.0 + det) + tr_m
    if code == COND_U:
        return y[m + j]
    b = (j + 1) % m
    tb = y[b] + (z if j == m - 1 else 0.0)
    if code == COND_Z:
        return tb - y[j]
    if smooth or code == COND_OTHER_PEAK:
        # the maximum nearest to hint (hint < 0: the highest); COND_OTHER_PEAK: the highest
        # of the others
        if code == COND_MARGIN:
            top, place = flight_peak(y[j], y[m + j], tb - y[j], beta, delta, zeta, eps, hint,
                                     -1.0)
        else:
            top, place = flight_peak(y[j], y[m + j], tb - y[j], beta, delta, zeta, eps, -1.0,
                                     hint)
        if place < 0.0:
            return np.inf
        return delta - top
    top = flight_max(y[j], y[m + j], tb - y[j], beta, delta, zeta, eps, stack)
    if top == -np.inf:
        return np.inf
    return delta - top


@kernel
def flight_peak(tau_a, u_a, s_end, beta, delta, zeta, eps, hint, skip):
    """``(height, place)`` of one interior local maximum of a flight, as a smooth function.

    The grazing condition of a curve needs a test function free of the bracketing noise of
    ``flight_max`` near a flat maximum, and it must follow one maximum: where two maxima of a
    flight (a long flight has one per forcing cycle) are equally high the highest one jumps,
    and the edge of the domain has a corner (two grazing conditions: a codimension-two point).
    The local maxima are located on a grid of BOUNDARY_PEAK_STEP radians (when following one,
    one step past the flight's end too, so a maximum that merges with the impact as u -> 0 is
    followed through);
    the one nearest to the time ``hint`` (``hint < 0``: the highest, but not the one nearest
    to ``skip`` if ``skip >= 0``) is converged by Newton on the velocity, unclamped.
    Returns ``(-inf, -1)`` when there is no such maximum.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    psi = beta * tau_a - phi
    a_coef = delta - q * sin(psi)
    b_coef = rebound_velocity(eps, u_a) - q * beta * cos(psi)
    c_coef = (b_coef + zeta * a_coef) / wd
    d_coef = -(zeta * c_coef + wd * a_coef)
    fast = max(beta, wd)
    npts = max(64, int(ceil(s_end * fast / BOUNDARY_PEAK_STEP)))
    step = s_end / npts
    # the maximum nearest to skip, to be left out
    s_skip = -1.0
    if hint < 0.0 and skip >= 0.0:
        far = np.inf
        x0, v0, a0, j0 = _flight_xv(0.0, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q)
        for k in range(1, npts + 1):
            s1 = step * k
            x1, v1, a1, j1 = _flight_xv(s1, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta,
                                        wd, q)
            if v0 > 0.0 and v1 <= 0.0 and abs(s1 - skip) < far:
                far = abs(s1 - skip)
                s_skip = s1
            v0 = v1
    best = -np.inf
    s_best = -1.0
    # one step past the flight's end only to follow a maximum (not to find the highest)
    last = npts + 2 if hint >= 0.0 else npts + 1
    x0, v0, a0, j0 = _flight_xv(0.0, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q)
    for k in range(1, last):
        s1 = step * k
        x1, v1, a1, j1 = _flight_xv(s1, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q)
        if v0 > 0.0 and v1 <= 0.0 and s1 != s_skip:
            top = max(x0, x1)
            place = s1 if x1 > x0 else s1 - step
            if hint >= 0.0:
                take = s_best < 0.0 or abs(place - hint) < abs(s_best - hint)
            else:
                take = top > best
            if take:
                best = top
                s_best = place
        x0, v0 = x1, v1
    if s_best < 0.0:
        return -np.inf, -1.0
    s = s_best
    for _ in range(BOUNDARY_NEWTON_MAXIT):
        xs, vs, as_, js = _flight_xv(s, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q)
        if as_ == 0.0:
            break
        ds = vs / as_
        s -= ds
        if abs(ds) <= 1e-15 * (1.0 + abs(s)):
            break
    xs, vs, as_, js = _flight_xv(s, psi, a_coef, c_coef, b_coef, d_coef, beta, zeta, wd, q)
    return xs, s


@kernel
def peak_of(code, j, hint, x, m, n, prm, ax):
    """``(margin, place)`` of the maximum that test ``code`` (COND_MARGIN or COND_OTHER_PEAK)
    picks on flight ``j`` with ``hint``, at ``x = (y, p, q)``."""
    nn = 2 * m
    beta, delta, zeta, eps = plane_point(x, nn, prm, ax)
    z = 2.0 * pi * n / beta
    b = (j + 1) % m
    tb = x[b] + (z if j == m - 1 else 0.0)
    if code == COND_MARGIN:
        top, place = flight_peak(x[j], x[m + j], tb - x[j], beta, delta, zeta, eps, hint, -1.0)
    else:
        top, place = flight_peak(x[j], x[m + j], tb - x[j], beta, delta, zeta, eps, -1.0, hint)
    if place < 0.0:
        return np.inf, place
    return delta - top, place


@kernel
def all_tests(y, m, n, beta, delta, zeta, eps, stack, tmat, out):
    """Every test function into ``out`` (length 2 + 3m): fold, pd, u_j, margin_j, z_j."""
    out[0] = cond_value(COND_FOLD, 0, y, m, n, beta, delta, zeta, eps, stack, tmat, False, -1.0)
    out[1] = cond_value(COND_PD, 0, y, m, n, beta, delta, zeta, eps, stack, tmat, False, -1.0)
    for j in range(m):
        out[2 + j] = y[m + j]
        out[2 + m + j] = cond_value(COND_MARGIN, j, y, m, n, beta, delta, zeta, eps, stack,
                                    tmat, False, -1.0)
        out[2 + 2 * m + j] = cond_value(COND_Z, j, y, m, n, beta, delta, zeta, eps, stack,
                                        tmat, False, -1.0)


@kernel
def _cond_x(code, j, hint, x, m, n, prm, ax, stack, tmat):
    nn = 2 * m
    beta, delta, zeta, eps = plane_point(x, nn, prm, ax)
    return cond_value(code, j, x[:nn], m, n, beta, delta, zeta, eps, stack, tmat, True, hint)


@kernel
def _orbit_rows(x, m, n, prm, ax, res, jy):
    nn = 2 * m
    beta, delta, zeta, eps = plane_point(x, nn, prm, ax)
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    _residual_jacobian(x[:nn], m, z, beta, delta, zeta, eps, wd, q, phi, res, jy)


@kernel
def _cond_row(code, j, hint, x, m, n, prm, ax, stack, tmat, xs, row):
    """Central-difference gradient of a test function in X into ``row``; returns its value."""
    na = 2 * m + 2
    for c in range(na):
        xs[c] = x[c]
    for c in range(na):
        h = BOUNDARY_FD_REL * (1.0 + abs(x[c]))
        xs[c] = x[c] + h
        fp = _cond_x(code, j, hint, xs, m, n, prm, ax, stack, tmat)
        xs[c] = x[c] - h
        fm = _cond_x(code, j, hint, xs, m, n, prm, ax, stack, tmat)
        xs[c] = x[c]
        row[c] = (fp - fm) / (2.0 * h)
    return _cond_x(code, j, hint, x, m, n, prm, ax, stack, tmat)


@kernel
def aug_system(x, m, n, prm, ax, code, j, hint, fvec, jac):
    """The 2m orbit equations and test function ``code`` (rows of ``fvec``) at ``x``, with the
    (2m + 1) x (2m + 2) Jacobian ``jac`` (analytic in y, central differences elsewhere)."""
    nn = 2 * m
    na = nn + 2
    res = np.empty(nn)
    jy = np.empty((nn, nn))
    res_p = np.empty(nn)
    res_m = np.empty(nn)
    jtmp = np.empty((nn, nn))
    xs = np.empty(na)
    stack = np.empty((64, 2))
    tmat = np.empty((2, 2))
    _orbit_rows(x, m, n, prm, ax, res, jy)
    for i in range(nn):
        fvec[i] = res[i]
        for c in range(nn):
            jac[i, c] = jy[i, c]
    for c in range(nn, na):
        for k in range(na):
            xs[k] = x[k]
        h = BOUNDARY_FD_REL * (1.0 + abs(x[c]))
        xs[c] = x[c] + h
        _orbit_rows(xs, m, n, prm, ax, res_p, jtmp)
        xs[c] = x[c] - h
        _orbit_rows(xs, m, n, prm, ax, res_m, jtmp)
        for i in range(nn):
            jac[i, c] = (res_p[i] - res_m[i]) / (2.0 * h)
    fvec[nn] = _cond_row(code, j, hint, x, m, n, prm, ax, stack, tmat, xs, jac[nn])


@kernel
def newton_aug(x, m, n, prm, ax, code, j, hint, mode, code2, j2, hint2, tvec, xref, idx,
               val):
    """Newton in place on ``x`` for the orbit equations, test ``code`` = 0, and a last equation:

    - ``mode 0``: ``tvec . (x - xref) = 0`` (pseudo-arclength);
    - ``mode 1``: ``x[idx] = val`` (a fixed parameter);
    - ``mode 2``: test ``code2`` (index ``j2``) = 0 (a codimension-two point).

    Returns ``(iterations, residual)``; iterations = -1 when it did not converge (the residual
    is the max-norm of the equations, each relative to the problem's scale). Converged: the
    residual is at the round-off floor (no further decrease by a full step) and the last step
    below BOUNDARY_STEP_RTOL.
    """
    nn = 2 * m
    na = nn + 2
    fvec = np.empty(nn + 1)
    jac = np.empty((nn + 1, na))
    a = np.empty((na, na))
    rhs = np.empty(na)
    row2 = np.empty(na)
    xs = np.empty(na)
    stack = np.empty((64, 2))
    tmat = np.empty((2, 2))
    prev = np.inf
    for it in range(BOUNDARY_NEWTON_MAXIT):
        if not plane_valid(x, nn, prm, ax):
            return -1, np.inf
        aug_system(x, m, n, prm, ax, code, j, hint, fvec, jac)
        for i in range(nn + 1):
            for c in range(na):
                a[i, c] = jac[i, c]
            rhs[i] = -fvec[i]
        if mode == 0:
            g = 0.0
            for c in range(na):
                a[nn + 1, c] = tvec[c]
                g += tvec[c] * (x[c] - xref[c])
            rhs[nn + 1] = -g
        elif mode == 1:
            for c in range(na):
                a[nn + 1, c] = 0.0
            a[nn + 1, idx] = 1.0
            rhs[nn + 1] = -(x[idx] - val)
        else:
            g = _cond_row(code2, j2, hint2, x, m, n, prm, ax, stack, tmat, xs, row2)
            for c in range(na):
                a[nn + 1, c] = row2[c]
            rhs[nn + 1] = -g
        nr = 0.0
        for i in range(na):
            if not np.isfinite(rhs[i]):
                return -1, np.inf
            nr = max(nr, abs(rhs[i]))
        if not _solve_inplace(a, rhs, na):
            return -1, nr
        small = True
        for c in range(na):
            if abs(rhs[c]) > BOUNDARY_STEP_RTOL * (1.0 + abs(x[c])):
                small = False
            x[c] += rhs[c]
        if small:
            return it + 1, nr
        if it >= 4 and nr > 0.5 * prev:
            # no longer converging quadratically: at the round-off floor if tiny
            if nr < 1e-11:
                return it + 1, nr
        prev = nr
    return -1, prev


@kernel
def follow_orbit(y, m, n, beta, delta, zeta, eps):
    """Newton on the orbit equations alone at fixed ``(beta, delta)``, in place; converged?"""
    nn = 2 * m
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    res = np.empty(nn)
    jac = np.empty((nn, nn))
    scale = 1.0 + abs(delta) + q * (1.0 + beta)
    for it in range(BOUNDARY_NEWTON_MAXIT):
        _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
        nr = 0.0
        for i in range(nn):
            nr = max(nr, abs(res[i]))
            res[i] = -res[i]
        if not np.isfinite(nr) or (it > 8 and nr > 1e-6 * scale):
            return False
        if nr <= 1e-14 * scale:
            return True
        if not _solve_inplace(jac, res, nn):
            return False
        small = True
        for i in range(nn):
            if abs(res[i]) > 1e-13 * (1.0 + abs(y[i])):
                small = False
            y[i] += res[i]
        if small:
            return True
    return False
