"""The impact map's pieces: a flight between impacts in closed form, the Jacobian of one
impact to the next and over a period, and admissibility (the exact largest height of a flight).

Notation follows the paper and docs/model.md (section 8): forcing ``sin(beta*tau)``, wall at
``x = delta``, ``wd = sqrt(1 - zeta**2)``, steady harmonic response ``x_p = q sin(beta*tau -
phi)``. A free flight starting on the wall at ``tau_a`` with approach velocity ``u_a`` (so
leaving with ``-eps*u_a``) is, with ``psi = beta*tau_a - phi`` and ``s = tau - tau_a``::

    x(s) = q sin(beta s + psi) + P11(s) A + P12(s) B,   A = delta - q sin psi,
    v(s) = q beta cos(beta s + psi) + P21(s) A + P22(s) B,   B = -eps u_a - q beta cos psi,

where ``P(s)`` is the damped free propagator of ``y'' + 2 zeta y' + y = 0``.

The impact law enters through :mod:`vibroimpact._law` only: the velocity leaving the wall is
``rebound_velocity(eps, u_a)``, the Jacobians' ``d/du_a`` entries carry
``rebound_derivative(eps, u_a)``, and their ``d/dtau_a`` entries, the shift ``-(v_+, a_+)`` of
the start state when the impact instant moves, write ``-v_+`` as
``-rebound_ratio(eps, u_a) * u_a`` (for Newton's law ``eps * u_a``, rounded as it always was).
So the flight, its Jacobian and the monodromy hold for any law of :mod:`vibroimpact.model`.
"""
from math import atan2, ceil, cos, exp, hypot, sin, sqrt

import numpy as np

from vibroimpact._law import rebound_derivative, rebound_ratio, rebound_velocity
from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.tolerances import (FLIGHT_MAX_MAXIT, FLIGHT_MAX_XTOL, FLIGHT_MIN_BRACKETS,
                                           FLIGHT_MIN_STEP, FLIGHT_PHASE_STEP)


@kernel
def harmonic_constants(beta, zeta):
    """``(wd, q, phi)``: damped frequency, steady amplitude and phase lag of sin(beta tau)."""
    wd = sqrt(1.0 - zeta * zeta)
    q = 1.0 / sqrt((1.0 - beta * beta) ** 2 + (2.0 * zeta * beta) ** 2)
    phi = atan2(2.0 * zeta * beta, 1.0 - beta * beta)
    return wd, q, phi


@kernel
def propagator(s, zeta, wd):
    """Entries of the free propagator ``P(s)`` mapping ``(y, y')(0)`` to ``(y, y')(s)``."""
    e = exp(-zeta * s)
    c = cos(wd * s)
    sn = sin(wd * s) / wd
    return e * (c + zeta * sn), e * sn, -e * sn, e * (c - zeta * sn)


@kernel
def flight(tau_a, u_a, s, beta, delta, zeta, eps, wd, q, phi):
    """State ``x, v, acc`` at ``tau_a + s`` of the flight leaving the wall at ``tau_a``.

    Also returns the propagator entries at ``s`` (needed by the Jacobians).
    """
    psi = beta * tau_a - phi
    a_coef = delta - q * sin(psi)
    b_coef = rebound_velocity(eps, u_a) - q * beta * cos(psi)
    p11, p12, p21, p22 = propagator(s, zeta, wd)
    th = beta * s + psi
    x = q * sin(th) + p11 * a_coef + p12 * b_coef
    v = q * beta * cos(th) + p21 * a_coef + p22 * b_coef
    acc = sin(beta * (tau_a + s)) - 2.0 * zeta * v - x
    return x, v, acc, p11, p12, p21, p22


@kernel
def impact_map_jacobian(tau_a, u_a, tau_b, u_b, beta, delta, zeta, eps, wd, q, phi):
    """2x2 Jacobian ``T_j`` of ``(tau_{j-1}, u_{j-1}) -> (tau_j, u_j)`` (paper eqs. 14-15).

    Notes
    -----
    Implicit differentiation of ``x(tau_j; tau_{j-1}, u_{j-1}) = delta``. Moving the start by
    ``d tau`` perturbs the state by ``-(v_+, a_+) d tau = (e u_a, delta - f(tau_a) - 2 zeta e
    u_a) d tau`` with ``e = -rebound_ratio(eps, u_a)`` (``eps`` for Newton's law), which the
    propagator carries to the impact; for Newton's law
    ``det T_j = eps^2 (u_{j-1}/u_j) exp(-2 zeta z_j)``.
    """
    x, v, acc, p11, p12, p21, p22 = flight(tau_a, u_a, tau_b - tau_a, beta, delta, zeta, eps,
                                           wd, q, phi)
    e_a = -rebound_ratio(eps, u_a)                        # -v_+ = e_a u_a
    g_a = delta - sin(beta * tau_a) - 2.0 * zeta * e_a * u_a
    dx_dta = p11 * e_a * u_a + p12 * g_a
    dv_dta = p21 * e_a * u_a + p22 * g_a
    a_b = sin(beta * tau_b) - 2.0 * zeta * u_b - delta   # x'' just before the impact
    t11 = -dx_dta / u_b
    t12 = -rebound_derivative(eps, u_a) * p12 / u_b
    t21 = dv_dta + a_b * t11
    t22 = rebound_derivative(eps, u_a) * p22 + a_b * t12
    return t11, t12, t21, t22


@kernel
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


@kernel
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


@kernel
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


@kernel
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
    b_coef = rebound_velocity(eps, u_a) - q * beta * cos(psi)
    c_coef = (b_coef + zeta * a_coef) / wd
    d_coef = -(zeta * c_coef + wd * a_coef)
    amp = hypot(a_coef, c_coef)          # amplitude of every derivative of the free part
    fast = max(beta, wd)
    n0 = max(FLIGHT_MIN_BRACKETS, int(ceil(s_end * fast / FLIGHT_PHASE_STEP)))
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
                    for _ in range(FLIGHT_MAX_MAXIT):
                        xs, vs, as_, js = _flight_xv(s, psi, a_coef, c_coef, b_coef, d_coef,
                                                     beta, zeta, wd, q)
                        if vs > 0.0:
                            a_ = s
                        else:
                            b_ = s
                        sn = s - vs / as_ if as_ != 0.0 else 0.5 * (a_ + b_)
                        if not (a_ < sn < b_):
                            sn = 0.5 * (a_ + b_)
                        if (abs(sn - s) <= FLIGHT_MAX_XTOL * (1.0 + abs(s))
                                or b_ - a_ <= FLIGHT_MAX_XTOL * s_end):
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


@kernel
def orbit_margin(y, m, z, beta, delta, zeta, eps, stack):
    """Admissibility margin ``delta - max x`` over all flights (``inf`` if no interior maximum)."""
    worst = -np.inf
    for j in range(1, m + 1):
        a = j - 1
        b = j % m
        tb = y[b] + (z if j == m else 0.0)
        worst = max(worst, flight_max(y[a], y[m + a], tb - y[a], beta, delta, zeta, eps, stack))
    return delta - worst
