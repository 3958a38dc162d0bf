"""Event location: the first contact with the wall in a segment, the release from it, and
where a chatter sequence accumulates.

Impact detection is rigorous: ``|x''| <= A q beta^2 + R`` over a segment, with ``R`` the
amplitude of ``y`` at the segment's start (``p_lin'' = 0`` and every derivative of ``y`` has
amplitude ``<= R exp(-zeta s)``); near the wall the sharper ``|x''| <= max(|x''| at the
ends) + |x'''| h / 2`` is tried too. The first root is approached from the left by steps
that a Taylor bound proves contact-free (:func:`safe_step`), and polished by a bracketed
Halley iteration once the root is proved unique (:func:`first_contact`). Grazing double
crossings inside one step are therefore found, never jumped over. The release is the first
sign change of the push ``f - delta``, found the same way (:func:`release_time`); a chatter
sequence's tail is summed in closed form once its accumulation point is proved
(:func:`chatter_tail`). The thresholds are those of :mod:`vibroimpact.impact.tolerances`.
"""
import math

import numpy as np

from vibroimpact._law import restitution_range
from vibroimpact.impact._jit import kernel
from vibroimpact.impact.layout import (C_B, C_DF0, C_F0, C_F_LIN, C_G2, C_G3, C_R,
                                       C_V0, C_XD, NO_ROOT, P_A, P_AQ, P_BETA, P_DELTA, P_DT,
                                       P_EPS, P_LAW_A, P_ZETA, PRESSED, ROOT, TOUCH)
from vibroimpact.impact.motion import bounds, push_eval, seg_eval
from vibroimpact.impact.tolerances import (BOUND_SAFETY, BRACKET_END_REL, CHATTER_MAXIT,
                                           CHATTER_TIME_TOL, CHATTER_WINDOW,
                                           CHATTER_WINDOW_GROWTH, EPS64, FORCE_ULPS,
                                           GAP_ULPS, HALLEY_LAST_STEP, HERMITE_MAXIT,
                                           JERK_REMAINDER_REL, MAX_SEARCH, POLISH_MAXIT,
                                           RESOLVED_REBOUND, SAFE_STEP_CONVERGED,
                                           SAFE_STEP_MAXIT, STALL_REL, TANGENCY_STEP_REL,
                                           TINY, TOUCH_ULPS, WALL_ULPS)


@kernel
def _hermite_guess(w, glo, vlo, ghi, vhi):
    """Root in ``(0, w)`` of the cubic Hermite interpolant of ``g`` (a start for Newton)."""
    t = glo / (glo - ghi)
    for _ in range(HERMITE_MAXIT):
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


@kernel(inline="always")
def _polish(lo, hi, s, g, v, acc, tolg, M3, c, P):
    """Root of ``g`` in ``[lo, hi]``, where it is proved unique with ``g' > 0``, to round-off.

    Inlined into its two callers by numba (``inline="always"``): as a call it received the
    17-slot segment tuple and nine floats by value once per impact.

    Halley's iteration (``x''`` comes free with every evaluation: cubic convergence) from
    ``s``, where ``(g, v, acc)`` are known, kept inside the bracket by bisection. Stops when
    the step is below round-off in ``s`` or ``|g|`` below its evaluation round-off ``tolg``.
    A last Halley step ``d`` so small (HALLEY_LAST_STEP) that the next error (~ d^3) is below
    1e-18 and the velocity's Taylor remainder ``M3 d^2 / 2`` (``M3`` bounds the jerk) below
    one ulp of ``v`` is taken without evaluating there: the root and ``v + acc d`` are exact
    to round-off.
    """
    for _ in range(POLISH_MAXIT):
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
            if abs(d) <= HALLEY_LAST_STEP and M3 * d * d <= JERK_REMAINDER_REL * v:
                return s_new, v + acc * d
        if abs(s_new - s) <= STALL_REL * abs(s) or hi - lo <= STALL_REL * abs(hi):
            break
        s = s_new
        g, v, acc = seg_eval(s, c, P)
    if g < 0.0 and hi - s <= BRACKET_END_REL * abs(hi) + TINY:
        s = hi          # g changes sign between s and the next float
        g, v, acc = seg_eval(s, c, P)
    return s, v


@kernel
def _newton_bracket(lo, hi, glo, vlo, ghi, vhi, tolg, M3, c, P):
    """Unique root of the increasing ``g`` in ``[lo, hi]`` (``g(lo) < 0 <= g(hi)``) to round-off,
    polished from the root of the cubic Hermite interpolant of the end values."""
    s = lo + _hermite_guess(hi - lo, glo, vlo, ghi, vhi)
    if not (lo < s < hi):
        s = 0.5 * (lo + hi)
    g, v, acc = seg_eval(s, c, P)
    return _polish(lo, hi, s, g, v, acc, tolg, M3, c, P)


@kernel
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


@kernel
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
    for _ in range(SAFE_STEP_MAXIT):
        K = (acc + W * M3) * BOUND_SAFETY + EPS64 * abs(acc)
        s = _quad_root(ga, va, K)
        if s >= W:
            return max(best, W)
        best = max(best, s)
        if s >= SAFE_STEP_CONVERGED * W:
            return best
        W = s
    return best


@kernel
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


@kernel
def tolg_wall(c, P):
    """Round-off of ``x - delta`` near the wall: separations below it are not resolvable."""
    return WALL_ULPS * EPS64 * (abs(P[P_DELTA]) + abs(c[C_F_LIN]) + abs(P[P_AQ]) + c[C_R])


@kernel
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


def _first_contact(c, P, H, at_wall):
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
    M2, M3, M4, vscale = bounds(c, P)
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
        if step <= STALL_REL * a:
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


#: :func:`_first_contact` compiled as a kernel of its own, called by the generic step.
first_contact = kernel(_first_contact)
#: The same, inlined into its caller by numba (``inline="always"``): the one-wall step
#: (:func:`vibroimpact.impact.stepping.slow_step_one`), where a call that passes the
#: 17-slot segment tuple by value once per event cost ~5 % of the map's kernel (LLVM's own
#: inliner keeps it a call). Only there: every inlined copy adds to the compile time.
first_contact_inline = kernel(inline="always")(_first_contact)


@kernel
def force_tol(c, P):
    """Round-off of ``F = f - delta`` at a segment's start: ``|F|`` below it has no sign.

    The one tolerance of every decision between staying on the wall and leaving it
    (:func:`release_time`, :func:`first_contact`, :func:`push_recovery`), so that they always
    agree: a mass they disagreed on would be released and stuck again forever. It depends
    on the force's size and the step length ``h``, never on the time left in the step.
    """
    return FORCE_ULPS * EPS64 * (abs(c[C_F_LIN]) + abs(P[P_DELTA]) + abs(P[P_A])
                                 + abs(c[C_B]) * P[P_DT] + TINY)


@kernel
def stays_on_wall(F, dF, tolF):
    """True when a mass at rest on the wall is held there: ``f - delta > 0``, or zero within
    round-off and not falling (a force that touches ``delta`` without crossing holds it)."""
    return F > tolF or (F >= -tolF and dF >= 0.0)


@kernel
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


@kernel
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
            for _ in range(POLISH_MAXIT):
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
                if abs(s_new - s) <= STALL_REL * abs(s) or hi - lo <= STALL_REL * abs(hi):
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
        if step <= STALL_REL * max(a, TINY) + TINY:
            a = a + max(step, TANGENCY_STEP_REL * H)  # f touches delta: no sign change
        else:
            a = a + step
        Fa, dFa = push_eval(a, c, P)
        if Fa < 0.0:
            return a
        if not stays_on_wall(Fa, dFa, tolF):
            return a
    return a


@kernel
def chatter_tail(w, F0, dF0, prev, Hs, P):
    """Where a chatter sequence accumulates, proved, or -1 when it cannot be proved yet.

    The mass leaves the wall at speed ``w`` with the push ``F0 = f - delta > 0`` (slope
    ``dF0``). Over a window ``[0, W]`` inside the step (``W <= Hs``: ``r`` is linear there)
    ``F`` lies in ``F0 +- (|dF0| W + A beta^2 W^2 / 2)``; while the speed stays below ``2 w``
    and the gap ``a = delta - x`` below ``a_max``, the acceleration towards the wall,
    ``x'' = F - 2 zeta x' + a``, lies in ``[g_lo, g_hi]``, ``rho = g_hi / g_lo``. A flight
    from speed ``w_k`` then lasts ``[2 w_k / g_hi, 2 w_k / g_lo]`` and returns at
    ``w_k [rho^-1/2, rho^1/2]``; the impact law's restitution lies in ``[eps_lo, eps]`` at
    these speeds (:func:`vibroimpact.model.restitution_range`; ``eps_lo = eps`` under
    Newton's law), so with ``q = eps rho^1/2 < 1`` the rebounds accumulate at ``T`` in
    ``[T_lo, T_hi] = [2 w / (g_hi (1 - eps_lo / rho^1/2)), 2 w / (g_lo (1 - q))]``,
    where the push is still positive (``g_lo > 0``): the mass sticks there. Returns the
    midpoint when ``w < RESOLVED_REBOUND``, ``T_hi - T_lo <= CHATTER_TIME_TOL`` (the stated
    bound on the sticking onset), ``T_hi <= W``, and the unresolved rebounds are proved to
    shrink in velocity and in flight time (``eps rho^3/2 < 1``) starting below the flight
    that brought the mass here (``prev > 2 w / g_lo``), so that grouping the resolved
    impacts into collisions (:mod:`vibroimpact.stats.collisions`) is the same as with every
    rebound resolved.
    """
    zeta = P[P_ZETA]
    if w >= RESOLVED_REBOUND:
        return -1.0
    # the law's restitution over the speeds below 2 w: eps_lo its lowest (at 2 w), eps its
    # highest (at rest); both P[P_EPS] under Newton's law
    eps_lo, eps = restitution_range(P[P_EPS], P[P_LAW_A], 2.0 * w)
    MF = abs(P[P_A]) * P[P_BETA] * P[P_BETA] * BOUND_SAFETY
    W = 2.0 * CHATTER_WINDOW * w / (F0 * (1.0 - eps))   # the constant-push estimate, widened
    for _ in range(CHATTER_MAXIT):
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
            T_lo = 2.0 * w / (g_hi * (1.0 - eps_lo / root)) / BOUND_SAFETY
            if T_hi - T_lo > CHATTER_TIME_TOL:
                return -1.0
            return 0.5 * (T_lo + T_hi)
        W = CHATTER_WINDOW_GROWTH * T_hi
    return -1.0
