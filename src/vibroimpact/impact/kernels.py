"""Numba kernels: exact event-driven motion of the impact oscillator.

Pure functions of numpy arrays and scalars: no I/O, no random numbers, no allocation per
step. The Python driver (:mod:`vibroimpact.simulate`) validates input, allocates the
output buffers and wraps the results.

Model (docs/model.md, sections 2-6; paper eqs. 2-7)::

    x'' + 2 zeta x' + x = f(tau) = A sin(beta tau) + r(tau),   x <= delta,
    impact at x = delta with u = x'(tau-) > 0:  x'(tau+) = -eps u,

with r linear between the samples r_k = r(k h). Between samples and impacts the motion is
the closed form ``x = p_lin + p_h + y``: ``p_lin(s) = r0 + b s - 2 zeta b`` for the linear
force, ``p_h = A q sin(beta tau - phi)`` for the harmonic force and the damped free response
``y = exp(-zeta s) (c1 cos(omega s) + c2 sin(omega s))``, ``omega = sqrt(1 - zeta^2)``.

Impact detection is rigorous: ``|x''| <= A q beta^2 + R`` over a segment, with ``R`` the
amplitude of ``y`` at the segment's start (``p_lin'' = 0`` and every derivative of ``y`` has
amplitude ``<= R exp(-zeta s)``); near the wall the sharper ``|x''| <= max(|x''| at the
ends) + |x'''| h / 2`` is tried too. A step is free of impacts when the bound on ``max x``
from its end values (``max(x0, x1) + M h^2 / 8``) stays below the wall; otherwise the first
root is approached from the left by steps that a Taylor bound proves contact-free
(:func:`safe_step`), and polished by a bracketed Halley iteration once the root is proved
unique. Grazing double crossings inside one step are therefore found, never jumped over.

Time is kept as a sample index ``k`` plus an offset ``s`` in ``[0, h]``; the harmonic phase
``beta (k h + s) mod 2 pi`` is computed in double-double arithmetic so that it stays exact
on records of 1e9 samples.
"""
import math

import numpy as np
from numba import njit

# --- numerical thresholds (the only ones in the package's simulator) -------------------
#: Relative inflation of every derivative bound, covering round-off in the bound itself.
BOUND_SAFETY = 1.0 + 1e-12
#: Resynchronise the rotated harmonic phase used by the fast exclusion test every so many steps.
RESYNC_EVERY = 1024
#: Maximum number of root-search iterations in one segment (never reached in practice: the
#: search converges quadratically; a near-grazing approach takes ~30).
MAX_SEARCH = 400
#: Bound (in time) on the error of a chatter sequence's accumulation point, summed in closed
#: form (:func:`chatter_tail`, a proved bracket): the sticking onset, and so the time on the
#: wall, is exact to it; nothing else depends on it (the release is the push's own root, and
#: the rebounds left unresolved, slower than RESOLVED_REBOUND, never change the collisions).
CHATTER_TIME_TOL = 1e-7
#: Where chatter_tail cannot bracket the tail inside the step (a tail across a sample point,
#: eps near 1), it is summed once the first-order estimate of its neglected terms,
#: ``T (2 zeta w + |F'| T) / F`` with ``T = 2 w / (F (1 - eps))``, is below this.
CHATTER_ESTIMATE_TOL = 1e-12
#: A chatter tail is summed only once its rebounds leave the wall slower than this (so that
#: every later approach, at most twice as fast, is below 1e-4): every faster rebound is
#: resolved, so counts of rebounds above a floor >= 1e-4 (the statistics' ``rebound_floor``)
#: are exact whatever CHATTER_TIME_TOL, and every impact faster than 1e-4 is in the record.
RESOLVED_REBOUND = 5e-5
#: Elastic (eps = 1) micro-bounces shorter than this are taken as resting contact: with eps = 1
#: a pressed mass loses bounce energy only to damping, so bounces shrink like 1/k and never
#: accumulate; a flight of 1e-6 rises ~1e-13 F above the wall.
ELASTIC_MICRO_FLIGHT = 1e-6
#: After this many events in one step (eps very close to 1: chatter of ~1e5 impacts spread over
#: many steps; eps = 1 pressed on the wall with long steps), rebounds lower than
#: MICRO_HEIGHT * (1 + |delta|), or with flights too short for the rest of the step to hold
#: fewer than STEP_HEADROOM / 16 more of them, are taken as resting contact.
MANY_EVENTS = 4096
MICRO_HEIGHT = 1e-12
#: Event tolerances in units of the round-off EPS64 of the quantity's scale: an arrival slower
#: than TOUCH_ULPS is a touch, not an impact; a gap below WALL_ULPS (GAP_ULPS in the contact
#: search) is on the wall; a push f - delta below FORCE_ULPS has no sign. With
#: CHATTER_TIME_TOL, CHATTER_ESTIMATE_TOL, ELASTIC_MICRO_FLIGHT and MICRO_HEIGHT above they
#: are every tolerance that decides an event; no collision statistic depends on them
#: (tests/test_collisions.py changes them all by three orders of magnitude).
TOUCH_ULPS = 64.0
WALL_ULPS = 16.0
GAP_ULPS = 8.0
FORCE_ULPS = 8.0
#: Relative margin of the stay-on-the-wall test of a whole step in run_steps' fast path (on
#: the scale of the force), far above the round-off of the rotated harmonic phase (~1e-13
#: after RESYNC_EVERY steps); a step closer to a release goes through release_time.
STICK_MARGIN = 1e-9
#: Impacts and sticking events one step may write; the driver flushes buffers before a step
#: when less room than this is left.
STEP_HEADROOM = 1 << 16

# --- named indices ----------------------------------------------------------------------
# The parameter vector P (built by vibroimpact.impact.simulate.kernel_parameters); numba
# reads module-level ints as compile-time constants, so P[P_DELTA] costs what P[3] did.
P_ZETA, P_OMEGA, P_EPS, P_DELTA, P_DT = 0, 1, 2, 3, 4       # zeta, sqrt(1 - zeta^2), eps, delta, h
P_A, P_BETA, P_AQ, P_PHI = 5, 6, 7, 8                       # harmonic A, beta, A q, phase lag phi
P_COS_PHI, P_SIN_PHI = 9, 10
P_BH_HI, P_BH_LO = 11, 12                                   # beta h in double-double
P_M11, P_M12, P_M21, P_M22 = 13, 14, 15, 16                 # free-response propagator over h
P_INV_DT, P_INV_OMEGA, P_COS_BH, P_SIN_BH = 17, 18, 19, 20
N_PARAMS = 21
# The segment tuple c returned by `segment`: the state, the force and the free response at
# the segment's start.
C_XD, C_V0, C_B, C_SP, C_CP = 0, 1, 2, 3, 4        # x0 - delta, x0 velocity, slope b, sin/cos psi0
C_Y0, C_YV0, C_C2, C_D2, C_R = 5, 6, 7, 8, 9       # free response, its velocity, coefficients, amplitude
C_G2, C_G3, C_F0, C_DF0 = 10, 11, 12, 13           # 2nd, 3rd derivative of x; f - delta and its slope
C_SIN_T, C_COS_T, C_F_LIN = 14, 15, 16             # sin/cos of the forcing phase; r0 + b s

TWO_PI_HI = 6.283185307179586
TWO_PI_LO = 2.4492935982947064e-16
EPS64 = 2.220446049250313e-16

# status codes returned by run_steps
OK = 0
BUFFER_FULL = 1
TOO_MANY_EVENTS = 2
BAD_NOISE = 3

# modes
FREE = 0
STUCK = 1
#: Free, and exactly on the wall (x = delta, x' <= 0) at the step's start: an impact, a touch
#: or a release fell on the end of the previous step. Kept apart from FREE so that the state
#: is handed on exactly, not through the round-off of ``w = x - p_h``.
WALL = 2

# search results
NO_ROOT = 0
ROOT = 1
TOUCH = 2   # reaches the wall with zero velocity (grazing within round-off)
PRESSED = 3  # at the wall, at rest, pushed into it: sticks


@njit(cache=True, error_model="numpy")
def _split(a):
    c = 134217729.0 * a
    hi = c - (c - a)
    return hi, a - hi


@njit(cache=True, error_model="numpy")
def two_prod(a, b):
    """Error-free product: ``a * b = p + e`` exactly (Dekker)."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    return p, e


@njit(cache=True, error_model="numpy")
def phase(k, s, bh_hi, bh_lo, beta):
    """``beta * (k h + s)`` reduced to about ``[-pi, pi]``, exact to round-off for any ``k``.

    ``bh_hi + bh_lo`` is the exact product ``beta * h`` (double-double).
    """
    kf = float(k)
    p, e = two_prod(kf, bh_hi)
    e += kf * bh_lo
    n = math.floor(p / TWO_PI_HI + 0.5)
    q, qe = two_prod(n, TWO_PI_HI)
    return ((p - q) - qe) + (e - n * TWO_PI_LO) + beta * s


@njit(cache=True, error_model="numpy")
def sincos(x):
    """``(sin x, cos x)``: Taylor polynomials for ``|x| <= 0.25`` (error < 1e-19 relative,
    below round-off), libm beyond. Flights between samples have small arguments, and one
    polynomial pair costs a fraction of two libm calls in the hot root search."""
    if abs(x) > 0.25:
        return math.sin(x), math.cos(x)
    x2 = x * x
    s = x * (1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (
        1.0 / 362880 + x2 * (-1.0 / 39916800 + x2 * (1.0 / 6227020800)))))))
    c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320 + x2 * (
        -1.0 / 3628800 + x2 * (1.0 / 479001600 + x2 * (-1.0 / 87178291200)))))))
    return s, c


@njit(cache=True, error_model="numpy")
def expm1(x):
    """``exp(x) - 1``: Taylor polynomial for ``|x| <= 0.0625`` (error < 1e-19), libm beyond."""
    if abs(x) > 0.0625:
        return math.expm1(x)
    return x * (1.0 + x * (0.5 + x * (1.0 / 6 + x * (1.0 / 24 + x * (1.0 / 120 + x * (
        1.0 / 720 + x * (1.0 / 5040 + x * (1.0 / 40320 + x * (1.0 / 362880)))))))))


@njit(cache=True, error_model="numpy")
def segment(x0, v0, s, r0, b, theta_k, P):
    """Coefficients of the closed-form motion from state ``(x0, v0)`` at offset ``s`` of a step.

    ``P`` is the parameter vector built by :func:`vibroimpact.simulate.kernel_parameters`.
    Returns a tuple used by :func:`seg_eval` and the bounds of the search.
    """
    zeta, omega, delta = P[P_ZETA], P[P_OMEGA], P[P_DELTA]
    A, beta, Aq, phi = P[P_A], P[P_BETA], P[P_AQ], P[P_PHI]
    P0 = r0 + b * s - 2.0 * zeta * b
    if Aq != 0.0:
        psi0 = theta_k + beta * s - phi
        sp = math.sin(psi0)
        cp = math.cos(psi0)
    else:
        sp = 0.0
        cp = 1.0
    y0 = x0 - P0 - Aq * sp
    yv0 = v0 - b - Aq * beta * cp
    c2 = (yv0 + zeta * y0) / omega
    d2 = (y0 + zeta * yv0) / omega
    R = math.sqrt(y0 * y0 + c2 * c2) * BOUND_SAFETY
    # force at the segment start: sin(theta) = sin(psi0 + phi)
    sin_t = sp * P[P_COS_PHI] + cp * P[P_SIN_PHI]
    cos_t = cp * P[P_COS_PHI] - sp * P[P_SIN_PHI]
    F0 = r0 + b * s + A * sin_t - delta       # f - delta: the push into the wall at x = delta
    dF0 = b + A * beta * cos_t
    g2 = F0 + delta - 2.0 * zeta * v0 - x0      # x'' at the start
    g3 = dF0 - 2.0 * zeta * g2 - v0            # x''' at the start
    return (x0 - delta, v0, b, sp, cp, y0, yv0, c2, d2, R, g2, g3, F0, dF0, sin_t, cos_t,
            r0 + b * s)


@njit(cache=True, error_model="numpy")
def seg_eval(sig, c, P):
    """``(x - delta, x', x'')`` at ``sig`` after the segment start, in difference form.

    Written as ``x(sig) - x0`` plus ``x0 - delta`` with ``expm1`` and half-angle sines so that
    short flights (chatter) keep full relative accuracy; ``x''`` follows from eq. (2).
    """
    zeta, omega, delta = P[P_ZETA], P[P_OMEGA], P[P_DELTA]
    A, beta, Aq = P[P_A], P[P_BETA], P[P_AQ]
    g0, b, sp, cp, y0, yv0, c2, d2 = c[C_XD], c[C_B], c[C_SP], c[C_CP], c[C_Y0], c[C_YV0], c[C_C2], c[C_D2]
    em1 = expm1(-zeta * sig)
    E = em1 + 1.0
    sh, ch = sincos(0.5 * omega * sig)
    S = 2.0 * sh * ch
    C = 1.0 - 2.0 * sh * sh
    dx = b * sig + y0 * (em1 * C - 2.0 * sh * sh) + c2 * E * S
    v = b + E * (yv0 * C - d2 * S)
    f = c[C_F_LIN] + b * sig
    if Aq != 0.0:
        sb, cb = sincos(0.5 * beta * sig)
        cos_b = 1.0 - 2.0 * sb * sb
        sin_b = 2.0 * sb * cb
        dx += 2.0 * Aq * (cp * cb - sp * sb) * sb
        v += Aq * beta * (cp * cos_b - sp * sin_b)
        f += A * (c[C_SIN_T] * cos_b + c[C_COS_T] * sin_b)
    g = g0 + dx
    return g, v, f - 2.0 * zeta * v - (g + delta)


@njit(cache=True, error_model="numpy")
def _bounds(c, P):
    """Bounds on ``|x''|, |x'''|, |x''''|`` over a segment, and scales for tolerances."""
    Aq, beta = abs(P[P_AQ]), P[P_BETA]
    R = c[C_R]
    M2 = Aq * beta * beta * BOUND_SAFETY + R
    M3 = Aq * beta * beta * beta * BOUND_SAFETY + R
    M4 = Aq * beta * beta * beta * beta * BOUND_SAFETY + R
    vscale = abs(c[C_B]) + Aq * beta + R + abs(c[C_V0]) + 1e-300
    return M2, M3, M4, vscale


@njit(cache=True, error_model="numpy")
def _hermite_guess(w, glo, vlo, ghi, vhi):
    """Root in ``(0, w)`` of the cubic Hermite interpolant of ``g`` (a start for Newton)."""
    t = glo / (glo - ghi)
    for _ in range(4):
        t2 = t * t
        t3 = t2 * t
        p = ((2.0 * t3 - 3.0 * t2 + 1.0) * glo + (t3 - 2.0 * t2 + t) * w * vlo
             + (-2.0 * t3 + 3.0 * t2) * ghi + (t3 - t2) * w * vhi)
        dp = ((6.0 * t2 - 6.0 * t) * (glo - ghi) + (3.0 * t2 - 4.0 * t + 1.0) * w * vlo
              + (3.0 * t2 - 2.0 * t) * w * vhi)
        if dp <= 0.0:
            break
        t_new = t - p / dp
        if not (0.0 < t_new < 1.0):
            break
        t = t_new
    return t * w


@njit(cache=True, error_model="numpy")
def _polish(lo, hi, s, g, v, acc, tolg, M3, c, P):
    """Root of ``g`` in ``[lo, hi]``, where it is proved unique with ``g' > 0``, to round-off.

    Halley's iteration (``x''`` comes free with every evaluation: cubic convergence) from
    ``s``, where ``(g, v, acc)`` are known, kept inside the bracket by bisection. Stops when
    the step is below round-off in ``s`` or ``|g|`` below its evaluation round-off ``tolg``.
    A last Halley step ``d`` so small that the next error (~ d^3) is below 1e-18 and the
    velocity's Taylor remainder ``M3 d^2 / 2`` (``M3`` bounds the jerk) below one ulp of ``v``
    is taken without evaluating there: the root and ``v + acc d`` are exact to round-off.
    """
    for _ in range(100):
        if abs(g) <= tolg:
            break
        if g < 0.0:
            lo = s
        else:
            hi = s
        den = 2.0 * v * v - g * acc
        s_new = s - 2.0 * g * v / den if (v > 0.0 and den > 0.0) else 0.5 * (lo + hi)
        if not (lo <= s_new <= hi):
            s_new = 0.5 * (lo + hi)
        elif v > 0.0 and den > 0.0:
            d = s_new - s
            if abs(d) <= 1e-6 and M3 * d * d <= 2.0 * EPS64 * v:
                return s_new, v + acc * d
        if abs(s_new - s) <= 2.0 * EPS64 * abs(s) or hi - lo <= 2.0 * EPS64 * abs(hi):
            break
        s = s_new
        g, v, acc = seg_eval(s, c, P)
    if g < 0.0 and hi - s <= 4.0 * EPS64 * abs(hi) + 1e-300:
        s = hi          # g changes sign between s and the next float
        g, v, acc = seg_eval(s, c, P)
    return s, v


@njit(cache=True, error_model="numpy")
def _newton_bracket(lo, hi, glo, vlo, ghi, vhi, tolg, M3, c, P):
    """Unique root of the increasing ``g`` in ``[lo, hi]`` (``g(lo) < 0 <= g(hi)``) to round-off,
    polished from the root of the cubic Hermite interpolant of the end values."""
    s = lo + _hermite_guess(hi - lo, glo, vlo, ghi, vhi)
    if not (lo < s < hi):
        s = 0.5 * (lo + hi)
    g, v, acc = seg_eval(s, c, P)
    return _polish(lo, hi, s, g, v, acc, tolg, M3, c, P)


@njit(cache=True, error_model="numpy")
def _quad_root(ga, va, K):
    """First positive root of ``ga + va s + K s^2 / 2`` with ``ga <= 0`` (``inf`` if none)."""
    if ga == 0.0:
        if va < 0.0:
            return -2.0 * va / K if K > 0.0 else np.inf
        return np.inf if (va == 0.0 and K < 0.0) else 0.0
    disc = va * va - 2.0 * K * ga
    if disc < 0.0:
        return np.inf
    den = va + math.sqrt(disc)
    return -2.0 * ga / den if den > 0.0 else np.inf


@njit(cache=True, error_model="numpy")
def safe_step(ga, va, acc, M3, wmax):
    """Longest ``s <= wmax`` proved free of contact from a point where ``g = ga <= 0``.

    On ``[0, W]`` the acceleration is at most ``acc + W M3`` (``M3`` bounds the jerk), so
    ``g(s) <= ga + va s + (acc + W M3) s^2 / 2``; the best ``W`` is the fixed point of
    ``W = first root of that quadratic``, approached in a few cheap iterations.
    """
    best = 0.0
    if ga == 0.0 and va <= 0.0 and acc < 0.0:
        # on the wall, not moving into it, pulled off it: g <= acc s^2/2 + M3 s^3/6 < 0 up to
        # s = -3 acc / M3 (v s <= 0 only helps); half of it keeps a margin for round-off in acc
        best = min(wmax, -1.5 * acc / M3)
        if best >= wmax:
            return wmax
    W = wmax
    for _ in range(6):
        K = (acc + W * M3) * BOUND_SAFETY + EPS64 * abs(acc)
        s = _quad_root(ga, va, K)
        if s >= W:
            return max(best, W)
        best = max(best, s)
        if s >= 0.99 * W:      # converged to 1 %: more iterations gain nothing worth a sqrt
            return best
        W = s
    return best


@njit(cache=True, error_model="numpy")
def _newton_from(a, ga, va, acc, M3, H):
    """Length ``d`` of an interval ``[a, a + d]`` proved to hold exactly one root, or 0.

    From ``g(a) = ga < 0`` and ``g'(a) = va > 0``: on ``[a, a + d]`` the acceleration is at
    least ``-(max(-acc, 0) + d M3)``, which with ``d = -2 ga / va`` keeps ``g'`` positive and
    forces ``g(a + d) > 0``.
    """
    if va <= 0.0:
        return 0.0
    d = -2.0 * ga / va
    if a + d > H:
        return 0.0
    K = (max(-acc, 0.0) + d * M3) * BOUND_SAFETY
    if va - K * d > 0.0 and -ga - 0.5 * K * d * d > 0.0:
        return d
    return 0.0


@njit(cache=True, error_model="numpy")
def tolg_wall(c, P):
    """Round-off of ``x - delta`` near the wall: separations below it are not resolvable."""
    return WALL_ULPS * EPS64 * (abs(P[P_DELTA]) + abs(c[C_F_LIN]) + abs(P[P_AQ]) + c[C_R])


@njit(cache=True, error_model="numpy")
def leave_wall(c, P, H, tolF, M3, M4):
    """Length of a first stretch, from rest on the wall, that is proved free of contact.

    The mass is at ``g = 0`` with ``g' = 0`` within round-off and ``f - delta`` negative, or
    zero within ``tolF`` and falling (a release point). Returns the largest length (at most
    ``H``) proved by ``g <= g2 s^2/2 + M3 s^3/6`` (pulled off, ``g2 = x'' < 0``) or, at a
    release point where ``g2`` is only round-off, by ``g <= g3 s^3/6 + M4 s^4/24``
    (``g3 = x'''``). When the separation so proved stays below round-off and ``f - delta``
    turns back in the step, returns ``-sF`` (``sF`` the instant it is back to zero): the mass
    stays on the wall.
    """
    F0, g2, g3 = c[C_F0], c[C_G2], c[C_G3]
    best = 0.0
    if F0 < -tolF:
        best = safe_step(0.0, 0.0, min(g2, F0), M3, H)
    if g3 < 0.0:
        best = max(best, min(-2.0 * g3 / M4, H))
    if best < H:
        # the separation reached over the proved stretch: below round-off it is not resolvable
        gap = -(min(g2, F0, 0.0) * best * best / 2.0 + min(g3, 0.0) * best * best * best / 6.0)
        if gap <= tolg_wall(c, P):
            sF = push_recovery(c, P, H)
            if sF >= 0.0:
                return -sF
    if best <= 0.0:
        # no bound applies (f - delta zero within round-off and x''' >= 0): the force falls
        # by less than round-off and the mass leaves by less than round-off over the step
        best = H
    return best


@njit(cache=True, error_model="numpy")
def first_contact(c, P, H, at_wall):
    """Smallest ``sig`` in ``(0, H]`` where the segment's motion reaches the wall.

    Parameters
    ----------
    c : tuple
        Segment coefficients from :func:`segment`.
    P : ndarray
        Kernel parameters.
    H : float
        Length of the segment (to the end of the force sample step).
    at_wall : bool
        The segment starts on the wall (``x0 == delta``, ``x'0 <= 0``).

    Returns
    -------
    code : int
        ``NO_ROOT``, ``ROOT`` (impact with ``u > 0``), ``TOUCH`` (reaches the wall with zero
        velocity within round-off) or ``PRESSED`` (at rest on the wall and pushed into it from
        ``sig`` on: it sticks).
    sig, u : float
        Instant (from the segment start) and velocity there; with ``NO_ROOT``, ``H`` and
        the state ``(x - delta, x')`` at ``H`` in ``u, gH``.
    gH : float
        ``x - delta`` at ``H`` for ``NO_ROOT``.

    Notes
    -----
    Every point skipped is proved free of contact by a Taylor bound (:func:`safe_step`, or
    the quartic bound on leaving the wall at a release), and Newton runs only on an interval
    where the root is proved unique, so the root found is the first one, including a double
    crossing inside one step with no sign change at its ends.
    """
    M2, M3, M4, vscale = _bounds(c, P)
    a = 0.0
    ga = c[C_XD]
    va = c[C_V0]
    acc = c[C_G2]
    if at_wall:
        tolv = TOUCH_ULPS * EPS64 * vscale
        if va > tolv:
            return ROOT, 0.0, va, 0.0           # starts on the wall moving into it
        if va >= -tolv:
            # at rest on the wall: held or leaving by the same rule as release_time
            tolF = force_tol(c, P)
            if stays_on_wall(c[C_F0], c[C_DF0], tolF):
                return PRESSED, 0.0, 0.0, 0.0
            sa = leave_wall(c, P, H, tolF, M3, M4)
            if sa < 0.0:
                # pulled off so weakly that f - delta turns back before the mass gets a
                # resolvable distance away: it simply stays on the wall (no creeping by
                # microscopic steps)
                return PRESSED, -sa, 0.0, 0.0
        else:
            sa = safe_step(0.0, va, acc, M3, H)
        a = sa
        ga, va, acc = seg_eval(a, c, P)
        if a >= H:
            if ga < 0.0:
                return NO_ROOT, H, va, ga
            return (ROOT if va > 0.0 else TOUCH), H, va, 0.0
        if ga >= 0.0:       # only by round-off: the bound says ga < 0
            ga = -EPS64 * abs(P[P_DELTA])
    have_end = False
    gH = 0.0
    vH = 0.0
    accH = 0.0
    for _ in range(MAX_SEARCH):
        w = H - a
        d = _newton_from(a, ga, va, acc, M3, H)
        if d > 0.0:
            tolg = EPS64 * (abs(c[C_XD]) + (a + d) * vscale)
            s, u = _polish(a, a + d, a, ga, va, acc, tolg, M3, c, P)
            return ROOT, s, u, 0.0
        if not have_end:
            gH, vH, accH = seg_eval(H, c, P)
            have_end = True
        # |x''| on [a, H]: its larger end value plus |x'''| w / 2 (sharper than M2 for short w)
        Mloc = min(M2, (max(abs(acc), abs(accH)) + 0.5 * M3 * w) * BOUND_SAFETY)
        if max(ga, gH) + 0.125 * Mloc * w * w < 0.0:
            return NO_ROOT, H, vH, gH
        if gH >= 0.0 and 0.5 * (va + vH) - 0.5 * Mloc * w > 0.0:
            tolg = EPS64 * (abs(c[C_XD]) + H * vscale)
            s, u = _newton_bracket(a, H, ga, va, gH, vH, tolg, M3, c, P)
            return ROOT, s, u, 0.0
        step = safe_step(ga, va, acc, M3, w)
        if step >= w:
            if gH >= 0.0:
                return (ROOT if vH > 0.0 else TOUCH), H, vH, 0.0
            return NO_ROOT, H, vH, gH
        if step <= 2.0 * EPS64 * a:
            # no progress is possible in floating point: we are at the root
            return (ROOT if va > 0.0 else TOUCH), a, va, 0.0
        a = a + step
        ga, va, acc = seg_eval(a, c, P)
        if ga >= -GAP_ULPS * EPS64 * (abs(c[C_XD]) + a * vscale):
            if va <= TOUCH_ULPS * EPS64 * vscale:
                return TOUCH, a, va, 0.0
            if ga >= 0.0:
                return ROOT, a, va, 0.0
    return TOUCH, a, va, 0.0


@njit(cache=True, error_model="numpy")
def force_tol(c, P):
    """Round-off of ``F = f - delta`` at a segment's start: ``|F|`` below it has no sign.

    The one tolerance of every decision between staying on the wall and leaving it
    (:func:`release_time`, :func:`first_contact`, :func:`push_recovery`), so that they always
    agree: a mass they disagreed on would be released and stuck again forever. It depends
    on the force's size and the step length ``h``, never on the time left in the step.
    """
    return FORCE_ULPS * EPS64 * (abs(c[C_F_LIN]) + abs(P[P_DELTA]) + abs(P[P_A]) + abs(c[C_B]) * P[P_DT] + 1e-300)


@njit(cache=True, error_model="numpy")
def stays_on_wall(F, dF, tolF):
    """True when a mass at rest on the wall is held there: ``f - delta > 0``, or zero within
    round-off and not falling (a force that touches ``delta`` without crossing holds it)."""
    return F > tolF or (F >= -tolF and dF >= 0.0)


@njit(cache=True, error_model="numpy")
def push_eval(sig, c, P):
    """``F = f - delta`` and ``dF/dtau`` at ``sig`` after the segment start, in difference form."""
    A, beta = P[P_A], P[P_BETA]
    F = c[C_F0] + c[C_B] * sig
    dF = c[C_B]
    if A != 0.0:
        sb = math.sin(beta * sig)
        cb = math.cos(beta * sig)
        F += A * (c[C_COS_T] * sb - c[C_SIN_T] * (1.0 - cb))
        dF += A * beta * (c[C_COS_T] * cb - c[C_SIN_T] * sb)
    return F, dF


@njit(cache=True, error_model="numpy")
def push_recovery(c, P, H):
    """First ``sig`` in ``(0, H]`` where ``F = f - delta`` (negative at the start) is back to
    ``>= 0``, approached from the left by steps proved safe by ``|F''| <= A beta^2``; ``-1``
    if it stays negative through ``H``."""
    MF = abs(P[P_A]) * P[P_BETA] * P[P_BETA] * BOUND_SAFETY
    tolF = force_tol(c, P)
    a = 0.0
    Fa, dFa = c[C_F0], c[C_DF0]
    for _ in range(MAX_SEARCH):
        if Fa >= -tolF:
            return a
        step = _quad_root(Fa, dFa, MF)
        if a + step >= H:
            FH, _ = push_eval(H, c, P)
            return H if FH >= -tolF else -1.0
        a = a + step
        Fa, dFa = push_eval(a, c, P)
    return a


@njit(cache=True, error_model="numpy")
def release_time(c, P, H):
    """First ``sig`` in ``[0, H]`` after which ``f - delta`` turns negative (the mass leaves).

    Returns ``-1.0`` when the mass stays on the wall through ``H``. ``f`` is linear plus a
    sinusoid, so ``|F''| <= A beta^2`` bounds the safe steps as in :func:`first_contact`.
    """
    A, beta = P[P_A], P[P_BETA]
    MF = abs(A) * beta * beta * BOUND_SAFETY
    a = 0.0
    Fa, dFa = c[C_F0], c[C_DF0]
    tolF = force_tol(c, P)
    if not stays_on_wall(Fa, dFa, tolF):
        return 0.0
    Fa = max(Fa, 0.0)       # within round-off of zero and rising: still pressed
    FH, dFH = push_eval(H, c, P)
    for _ in range(MAX_SEARCH):
        w = H - a
        if min(Fa, FH) - 0.125 * MF * w * w > 0.0 or (MF == 0.0 and FH >= 0.0):
            return -1.0
        if FH < 0.0 and 0.5 * (dFa + dFH) + 0.5 * MF * w < 0.0:
            lo, hi = a, H
            # F is strictly decreasing on [lo, hi]: bisection-safeguarded Newton on F
            s = lo + Fa * (hi - lo) / (Fa - FH)
            for _ in range(100):
                F, dF = push_eval(s, c, P)
                if F > 0.0:
                    lo = s
                elif F < 0.0:
                    hi = s
                else:
                    break
                s_new = s - F / dF if dF < 0.0 else 0.5 * (lo + hi)
                if not (lo < s_new < hi):
                    s_new = 0.5 * (lo + hi)
                if abs(s_new - s) <= 2.0 * EPS64 * abs(s) or hi - lo <= 2.0 * EPS64 * abs(hi):
                    break
                s = s_new
            return s
        if MF == 0.0:
            step = Fa / -dFa if dFa < 0.0 else w
        else:
            disc = math.sqrt(dFa * dFa + 2.0 * MF * Fa)
            step = 2.0 * Fa / (disc - dFa) if dFa < 0.0 else (dFa + disc) / MF
        if a + step >= H:
            return -1.0 if FH >= 0.0 else H
        if step <= 2.0 * EPS64 * max(a, 1e-300) + 1e-300:
            a = a + max(step, 1e-12 * H)   # tangency of f with delta: no sign change here
        else:
            a = a + step
        Fa, dFa = push_eval(a, c, P)
        if Fa < 0.0:
            return a
        if not stays_on_wall(Fa, dFa, tolF):
            return a
    return a


@njit(cache=True, error_model="numpy")
def chatter_tail(w, F0, dF0, prev, Hs, P):
    """Where a chatter sequence accumulates, proved, or -1 when it cannot be proved yet.

    The mass leaves the wall at speed ``w`` with the push ``F0 = f - delta > 0`` (slope
    ``dF0``). Over a window ``[0, W]`` inside the step (``W <= Hs``: ``r`` is linear there)
    ``F`` lies in ``F0 +- (|dF0| W + A beta^2 W^2 / 2)``; while the speed stays below ``2 w``
    and the gap ``a = delta - x`` below ``a_max``, the acceleration towards the wall,
    ``x'' = F - 2 zeta x' + a``, lies in ``[g_lo, g_hi]``, ``rho = g_hi / g_lo``. A flight
    from speed ``w_k`` then lasts ``[2 w_k / g_hi, 2 w_k / g_lo]`` and returns at
    ``w_k [rho^-1/2, rho^1/2]``, so with ``q = eps rho^1/2 < 1`` the rebounds accumulate at
    ``T`` in ``[T_lo, T_hi] = [2 w / (g_hi (1 - eps / rho^1/2)), 2 w / (g_lo (1 - q))]``,
    where the push is still positive (``g_lo > 0``): the mass sticks there. Returns the
    midpoint when ``w < RESOLVED_REBOUND``, ``T_hi - T_lo <= CHATTER_TIME_TOL`` (the stated
    bound on the sticking onset), ``T_hi <= W``, and the unresolved rebounds are proved to
    shrink in velocity and in flight time (``eps rho^3/2 < 1``) starting below the flight
    that brought the mass here (``prev > 2 w / g_lo``), so that grouping the resolved
    impacts into collisions (:mod:`vibroimpact.stats.collisions`) is the same as with every
    rebound resolved.
    """
    zeta, eps = P[P_ZETA], P[P_EPS]
    if w >= RESOLVED_REBOUND:
        return -1.0
    MF = abs(P[P_A]) * P[P_BETA] * P[P_BETA] * BOUND_SAFETY
    W = 3.0 * w / (F0 * (1.0 - eps))       # 1.5 x the constant-push estimate
    for _ in range(4):
        if W > Hs:
            return -1.0
        spread = (abs(dF0) * W + 0.5 * MF * W * W) * BOUND_SAFETY
        g_lo = F0 - spread - 4.0 * zeta * w
        if g_lo <= 0.0:
            return -1.0
        g_hi = F0 + spread + 4.0 * zeta * w + 2.0 * w * w / g_lo
        rho = g_hi / g_lo
        if rho >= 4.0:                      # the speed bound 2 w needs rho^1/2 <= 2
            return -1.0
        root = math.sqrt(rho)
        q = eps * root
        if q >= 1.0:
            return -1.0
        T_hi = 2.0 * w / (g_lo * (1.0 - q)) * BOUND_SAFETY
        if T_hi <= W:
            if eps * rho * root >= 1.0 or prev <= 2.0 * w / g_lo:
                return -1.0
            T_lo = 2.0 * w / (g_hi * (1.0 - eps / root)) / BOUND_SAFETY
            if T_hi - T_lo > CHATTER_TIME_TOL:
                return -1.0
            return 0.5 * (T_lo + T_hi)
        W = 1.01 * T_hi
    return -1.0


@njit(cache=True, error_model="numpy")
def _record_event(buf_step, buf_off, buf_val, n, k, s, val):
    buf_step[n] = k
    buf_off[n] = s
    buf_val[n] = val


@njit(cache=True, error_model="numpy")
def slow_step(k, H, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step, stk_off,
              stk_kind, cnt, ftot):
    """Advance one force sample step ``[k h, k h + H]`` through every event in it.

    ``x, v, mode`` is the state at the step's start (in mode ``WALL``, ``v`` is
    ``w' = x' - p_h'``, as :func:`run_steps` keeps it). Impacts are appended to
    ``imp_*``, sticking starts (kind 1) and ends (kind 0) to ``stk_*``; ``cnt`` holds
    ``[n_impacts, n_stick_events, n_chatter]`` and ``ftot[0]`` the time in contact.
    Returns the state at the step's end and a status. An event that falls on the step's end
    (``s = H`` after rounding) leaves the rest to the next step, which starts in mode
    ``WALL``: a release, sticking onset, impact or touch at a sample point goes through the
    same logic as anywhere else. With ``TOO_MANY_EVENTS``, ``ftot[1:7]`` receives what the
    step saw: ``[offset reached, x - delta, x', mode, impacts in the step, sticking events]``
    (kept in ``ftot`` rather than an argument of its own: every argument and branch added to
    :func:`run_steps` slows its hot loop, measured by benchmarks/ab_no_impact.py).
    """
    zeta, eps, delta = P[P_ZETA], P[P_EPS], P[P_DELTA]
    theta_k = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], P[P_BETA]) if P[P_A] != 0.0 else 0.0
    s = 0.0
    n_events = 0
    if mode == WALL:
        # x' arrives as w' = x' - p_h' (run_steps keeps the harmonic part out of its loop)
        if P[P_A] != 0.0:
            v += P[P_AQ] * P[P_BETA] * math.cos(theta_k - P[P_PHI])
        mode = FREE
    at_wall = x >= delta
    if at_wall:
        x = delta
    just_hit = False
    imp0, stk0 = cnt[0], cnt[1]
    while True:
        if s >= H:
            # nothing of the step is left: every path here has set x = delta
            return delta, v, (STUCK if mode == STUCK else WALL), OK
        n_events += 1
        if n_events > STEP_HEADROOM - 2:
            ftot[1] = s
            ftot[2] = x - delta
            ftot[3] = v
            ftot[4] = mode
            ftot[5] = cnt[0] - imp0
            ftot[6] = cnt[1] - stk0
            return x, v, mode, TOO_MANY_EVENTS
        c = segment(x, v, s, r0, b, theta_k, P)
        Hs = H - s
        if just_hit and v < 0.0 and c[C_F0] > 0.0:
            # chatter: rebounds shrink geometrically while f pushes the mass into the wall;
            # the tail is summed in closed form as soon as chatter_tail proves where it ends
            wv, F, dF = -v, c[C_F0], c[C_DF0]
            if eps < 1.0:
                n = cnt[0] - 1              # the impact just recorded, and the one before it
                prev = ((imp_step[n] - imp_step[n - 1]) * P[P_DT] + (imp_off[n] - imp_off[n - 1])
                        if n >= 1 else 0.0)
                tail = chatter_tail(wv, F, dF, prev, Hs, P)
                ok = tail >= 0.0
                F_end = 1.0
                if not ok:
                    # no bracket inside the step (a tail across a sample point, eps near 1):
                    # the first-order estimate once its neglected terms are below round-off
                    tail = 2.0 * wv / (F * (1.0 - eps))
                    ok = tail * (2.0 * zeta * wv + abs(dF) * tail) / F <= CHATTER_ESTIMATE_TOL
                    F_end = (F + dF * tail
                             - 0.5 * abs(P[P_A]) * P[P_BETA] * P[P_BETA] * tail * tail)
            else:
                tail = 2.0 * wv / F
                ok = tail <= ELASTIC_MICRO_FLIGHT
                F_end = F + dF * tail - 0.5 * abs(P[P_A]) * P[P_BETA] * P[P_BETA] * tail * tail
            micro = n_events >= MANY_EVENTS and (
                wv * wv <= 2.0 * F * MICRO_HEIGHT * (1.0 + abs(delta))
                or 2.0 * wv / F <= 16.0 * H / STEP_HEADROOM)
            if (ok and tail <= Hs and F_end > 0.0) or micro:
                if not micro:
                    s = s + tail
                cnt[2] += 1
                mode = STUCK
                _record_event(stk_step, stk_off, stk_kind, cnt[1], k, s, 1.0)
                cnt[1] += 1
                v = 0.0
                just_hit = False
                continue
        just_hit = False
        if mode == STUCK:
            sig = release_time(c, P, Hs)
            if sig < 0.0:
                ftot[0] += Hs
                return delta, 0.0, STUCK, OK
            ftot[0] += sig
            s = min(s + sig, H)
            _record_event(stk_step, stk_off, stk_kind, cnt[1], k, s, 0.0)
            cnt[1] += 1
            mode = FREE
            x = delta
            v = 0.0
            at_wall = True
            continue
        code, sig, u, gH = first_contact(c, P, Hs, at_wall)
        if code == NO_ROOT:
            return gH + delta, u, FREE, OK
        if code == PRESSED:
            mode = STUCK
            s = min(s + sig, H)
            _record_event(stk_step, stk_off, stk_kind, cnt[1], k, s, 1.0)
            cnt[1] += 1
            x = delta
            v = 0.0
            continue
        s = min(s + sig, H)
        x = delta
        at_wall = True
        if code == ROOT and u <= TOUCH_ULPS * EPS64 * (abs(b) + abs(P[P_AQ]) * P[P_BETA] + c[C_R] + abs(v)):
            code = TOUCH          # arrives with zero velocity within round-off: grazing touch
        if code == TOUCH:
            v = min(u, 0.0)
            continue
        _record_event(imp_step, imp_off, imp_u, cnt[0], k, s, u)
        cnt[0] += 1
        v = -eps * u
        just_hit = True


@njit(cache=True, error_model="numpy")
def run_steps(r, k_begin, k_end, state, P, imp_step, imp_off, imp_u, stk_step, stk_off,
              stk_kind, cnt, ftot, grid, grid_v, stride, grid_n):
    """Advance the oscillator over the force samples ``r`` (``r[0]`` is sample ``k_begin``).

    ``state = [w, w', mode, sin(psi), cos(psi)]`` at sample ``k_begin``, with ``w = x - p_h``
    the displacement less the harmonic particular solution (so the fast recurrence never
    touches the harmonic part) and ``psi = beta k h - phi``; with mode ``WALL``, ``x = delta``
    exactly and ``w`` is not read. Steps ``k_begin .. k_end - 1``
    are taken unless an output buffer runs short, in which case the function returns early.
    ``grid`` and ``grid_v`` receive ``a = delta - x`` and ``x'`` at every sample with
    ``k % stride == 0`` (``stride`` 0: none), counted in ``grid_n[0]``.

    Returns ``(status, k)``: the sample reached.
    """
    zeta, delta, h = P[P_ZETA], P[P_DELTA], P[P_DT]
    Aq, beta = P[P_AQ], P[P_BETA]
    a11, a12, a21, a22 = P[P_M11], P[P_M12], P[P_M21], P[P_M22]
    inv_h, inv_omega = P[P_INV_DT], P[P_INV_OMEGA]
    cbh, sbh = P[P_COS_BH], P[P_SIN_BH]
    h2_8 = 0.125 * h * h
    M0 = abs(Aq) * beta * beta * BOUND_SAFETY
    margin = 1e-11 * abs(Aq) + 1e-300
    A = P[P_A]
    cos_phi, sin_phi = P[P_COS_PHI], P[P_SIN_PHI]
    MF_h2_8 = abs(A) * beta * beta * BOUND_SAFETY * h2_8
    abs_A_delta = abs(A) + abs(delta) + 1e-300
    has_h = Aq != 0.0
    w = state[0]
    wv = state[1]
    mode = int(state[2])
    sp = state[3]
    cp = state[4]
    cap_imp = imp_step.shape[0]
    cap_stk = stk_step.shape[0]
    status, k_stop = OK, k_end
    for k in range(k_begin, k_end):
        if has_h and k % RESYNC_EVERY == 0:
            psi = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], beta) - P[P_PHI]
            sp = math.sin(psi)
            cp = math.cos(psi)
        if stride > 0 and k % stride == 0:
            if mode != FREE:
                # on the wall; STUCK keeps w' = -p_h' exactly, so x' = 0 there
                grid[grid_n[0]] = 0.0
                grid_v[grid_n[0]] = wv + Aq * beta * cp
            elif has_h:
                psi = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], beta) - P[P_PHI]
                grid[grid_n[0]] = delta - (w + Aq * math.sin(psi))
                grid_v[grid_n[0]] = wv + Aq * beta * math.cos(psi)
            else:
                grid[grid_n[0]] = delta - w
                grid_v[grid_n[0]] = wv
            grid_n[0] += 1
        r0 = r[k - k_begin]
        r1 = r[k - k_begin + 1]
        b = (r1 - r0) * inv_h
        if has_h:
            sp1 = sp * cbh + cp * sbh
            cp1 = cp * cbh - sp * sbh
        else:
            sp1 = 0.0
            cp1 = 1.0
        if mode == FREE:
            y0 = w - (r0 - 2.0 * zeta * b)
            yv = wv - b
            w1 = r1 - 2.0 * zeta * b + a11 * y0 + a12 * yv
            wv1 = b + a21 * y0 + a22 * yv
            xmax = max(w + Aq * sp, w1 + Aq * sp1)
            R = abs(y0) + abs(yv + zeta * y0) * inv_omega
            # two tiers: |x''| <= A q beta^2 + R (R: amplitude of the free response) is cheap;
            # near the wall, |w''| exceeds its larger end value by at most |w'''| h/2 <= R h/2
            # is sharper when the force samples are steep (R large)
            clear = xmax + (M0 + R) * h2_8 + margin < delta
            if not clear and xmax + margin < delta:
                acc = max(abs(r0 - 2.0 * zeta * wv - w), abs(r1 - 2.0 * zeta * wv1 - w1))
                clear = xmax + (M0 + acc + 0.5 * h * R) * BOUND_SAFETY * h2_8 + margin < delta
            if clear:
                w = w1
                wv = wv1
                sp = sp1
                cp = cp1
                continue
            x = w
            v = wv
            if has_h:
                psi = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], beta) - P[P_PHI]
                x = w + Aq * math.sin(psi)
                v = wv + Aq * beta * math.cos(psi)
        else:
            if mode == STUCK:
                # resting on the wall: it stays through the step when the push f - delta is
                # positive all along, >= its smaller end value less |f''| h^2 / 8 (r is linear
                # over the step, |f''| <= A beta^2), with a margin far above the round-off of
                # the rotated phase; what release_time would conclude, without its sines
                F0 = r0 + A * (sp * cos_phi + cp * sin_phi) - delta
                F1 = r1 + A * (sp1 * cos_phi + cp1 * sin_phi) - delta
                if min(F0, F1) - MF_h2_8 > STICK_MARGIN * (abs(r0) + abs(r1) + abs_A_delta):
                    ftot[0] += h
                    w = delta - Aq * sp1
                    wv = -Aq * beta * cp1
                    sp = sp1
                    cp = cp1
                    continue
            x = delta
            v = wv          # w': slow_step adds p_h' in mode WALL, ignores it when STUCK
        # a non-finite sample always fails the exclusion test, so it is caught here at no cost
        if not (math.isfinite(r0) and math.isfinite(r1)):
            return BAD_NOISE, k
        # events are written only here: make sure the buffers have room for a whole step
        if cnt[0] + STEP_HEADROOM > cap_imp or cnt[1] + STEP_HEADROOM > cap_stk:
            if stride > 0 and k % stride == 0:
                grid_n[0] -= 1      # sample k is recorded again when the step is resumed
            status, k_stop = BUFFER_FULL, k
            break
        x, v, mode, status = slow_step(k, h, x, v, mode, r0, b, P, imp_step, imp_off, imp_u,
                                       stk_step, stk_off, stk_kind, cnt, ftot)
        if status != OK:
            return status, k
        if has_h:
            psi = phase(k + 1, 0.0, P[P_BH_HI], P[P_BH_LO], beta) - P[P_PHI]
            sp1 = math.sin(psi)
            cp1 = math.cos(psi)
        w = x - Aq * sp1
        wv = v - Aq * beta * cp1
        sp = sp1
        cp = cp1
    state[0] = w
    state[1] = wv
    state[2] = mode
    state[3] = sp
    state[4] = cp
    return status, k_stop
