"""Stepping: the simulator's loop over force samples, and one sample step through its events.

:func:`run_steps` takes the force samples one by one: a step that a bound proves free of
impacts (or, on the wall, free of a release) is one 2x2 recurrence and a few force terms;
any other goes to :func:`slow_step`, which walks it event by event with the searches of
:mod:`vibroimpact.impact.events` and writes the impacts and sticking events into the
driver's buffers. The arrays they share are laid out in :mod:`vibroimpact.impact.layout`.
"""
import math

from vibroimpact.impact._jit import kernel
from vibroimpact.impact.events import (chatter_tail, first_contact, first_contact_inline,
                                       release_time)
from vibroimpact.impact.layout import (BAD_NOISE, BUFFER_FULL, C_DF0, C_F0, C_R,
                                       CNT_CHATTER, CNT_IMPACTS, CNT_STICK_EVENTS,
                                       FREE, FT_CONTACT_TIME, FT_GAP, FT_IMPACTS, FT_MODE,
                                       FT_OFFSET, FT_STICK_EVENTS, FT_V, N_PARAMS, NO_ROOT,
                                       OK, P_A,
                                       P_AQ, P_BETA, P_BH_HI, P_BH_LO, P_COS_BH, P_COS_PHI,
                                       P_DELTA, P_DT, P_EPS, P_INV_DT, P_INV_OMEGA,
                                       P_LAW_A, P_M11,
                                       P_M12, P_M21, P_M22, P_PHI, P_SIN_BH, P_SIN_PHI,
                                       P_ZETA, PRESSED, ROOT, S_COS_PSI, S_MODE, S_SIN_PSI,
                                       S_W, S_WV, STICK_LO, STICK_OFF, STICK_ON, STUCK,
                                       STUCK_LO, TOO_MANY_EVENTS, TOUCH, WALL, WALL_LO)
from vibroimpact.impact.motion import phase, segment, segment_at
from vibroimpact._law import rebound_velocity, restitution_range
from vibroimpact.impact.tolerances import (BOUND_SAFETY, CHATTER_ESTIMATE_TOL,
                                           ELASTIC_MICRO_FLIGHT, EPS64,
                                           EXCLUSION_MARGIN_REL, MANY_EVENTS,
                                           MICRO_FLIGHTS_PER_HEADROOM, MICRO_HEIGHT,
                                           RESYNC_EVERY, STEP_HEADROOM, STICK_MARGIN, TINY,
                                           TOUCH_ULPS)


@kernel
def _record_event(buf_step, buf_off, buf_val, n, k, s, val):
    buf_step[n] = k
    buf_off[n] = s
    buf_val[n] = val


@kernel
def _wall_position(P, side):
    """Lab-frame position of wall ``side`` (0: the wall at delta; 1: the wall below the mass,
    whose half of ``P`` holds minus its position)."""
    return P[P_DELTA] if side == 0 else -P[N_PARAMS + P_DELTA]


@kernel
def slow_step(k, H, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step, stk_off,
              stk_kind, cnt, ftot):
    """Advance one force sample step ``[k h, k h + H]`` through every event in it.

    ``x, v, mode`` is the state at the step's start (in mode ``WALL`` or ``WALL_LO``, ``v`` is
    ``w' = x' - p_h'``, as :func:`run_steps` keeps it). Impacts are appended to ``imp_*``,
    sticking starts and ends to ``stk_*`` (kinds :data:`~vibroimpact.impact.layout.STICK_ON`,
    ``STICK_OFF``, plus ``STICK_LO`` at the lower wall); ``cnt`` holds the counters
    (``CNT_*``) and ``ftot[FT_CONTACT_TIME]`` the time in contact.
    Returns the state at the step's end and a status. An event that falls on the step's end
    (``s = H`` after rounding) leaves the rest to the next step, which starts in mode
    ``WALL``: a release, sticking onset, impact or touch at a sample point goes through the
    same logic as anywhere else. With ``TOO_MANY_EVENTS``, ``ftot[FT_DIAGNOSTICS]`` receives
    what the step saw (:data:`vibroimpact.impact.layout.FT_FIELDS`: the offset reached,
    ``x - delta``, ``x'``, the mode, impacts and sticking events written in the step).

    With a second wall (``P`` of ``2 N_PARAMS`` slots) the step is walked in the frame of the
    wall the mass is at or last met (``sg = +1``: the wall at delta; ``sg = -1``: the lower
    wall, seen from above in the mirrored frame ``x -> -x``, where it is a wall hit from
    below like the first): the chatter, sticking and release logic is the one-wall logic
    in that frame, and every free flight also searches the other wall's first contact (in
    its own frame, from a point off it), the earlier of the two ending the flight.
    """
    return _slow_step(k, H, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step,
                      stk_off, stk_kind, cnt, ftot, 0.0, 0.0, 1.0, False)


@kernel
def _slow_step(k, H, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step, stk_off,
               stk_kind, cnt, ftot, theta0, sp0, cp0, exact):
    """:func:`slow_step`, handed what :func:`run_steps` already computed at sample ``k``
    (``theta0, sp0, cp0, exact`` as in :func:`_slow_step_one`). Both walls' frames share the
    harmonic phase (the lower half of ``P`` differs in ``A``, ``A q``, ``eps`` and ``delta``
    only), so an event's sin and cos serve the segment in both frames."""
    delta = P[P_DELTA]
    two = P.shape[0] > N_PARAMS
    if exact:
        theta_k = theta0
    else:
        theta_k = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], P[P_BETA]) if P[P_A] != 0.0 else 0.0
    s = 0.0
    n_events = 0
    side = 1 if (mode == WALL_LO or mode == STUCK_LO) else 0
    if mode == WALL or mode == WALL_LO:
        # x' arrives as w' = x' - p_h' (run_steps keeps the harmonic part out of its loop)
        if P[P_A] != 0.0:
            v += P[P_AQ] * P[P_BETA] * (cp0 if exact else math.cos(theta_k - P[P_PHI]))
        mode = FREE
    elif mode == STUCK_LO:
        mode = STUCK
    at_wall = x >= delta
    if at_wall:
        x = delta
        side = 0
    elif two:
        lower = _wall_position(P, 1)
        if x <= lower:
            x = lower
            side = 1
            at_wall = True
        elif mode == FREE and x - lower < delta - x:
            # a flight is followed in the frame of the nearer wall: its end state is
            # x - wall in difference form there, accurate to the distance from that wall
            side = 1
    just_hit = False
    imp0, stk0 = cnt[CNT_IMPACTS], cnt[CNT_STICK_EVENTS]
    while True:
        if s >= H:
            # nothing of the step is left: every path here has set x on the wall
            if side == 0:
                return delta, v, (STUCK if mode == STUCK else WALL), OK
            return _wall_position(P, 1), v, (STUCK_LO if mode == STUCK else WALL_LO), OK
        n_events += 1
        if n_events > STEP_HEADROOM - 2:
            ftot[FT_OFFSET] = s
            ftot[FT_GAP] = x - delta
            ftot[FT_V] = v
            ftot[FT_MODE] = mode if side == 0 else mode + STUCK_LO - STUCK
            ftot[FT_IMPACTS] = cnt[CNT_IMPACTS] - imp0
            ftot[FT_STICK_EVENTS] = cnt[CNT_STICK_EVENTS] - stk0
            return x, v, mode, TOO_MANY_EVENTS
        # the frame of the wall the mass is at (or last met): the one-wall logic runs in it
        Pw = P[N_PARAMS:] if side == 1 else P
        sg = -1.0 if side == 1 else 1.0
        eps = Pw[P_EPS]
        # sin, cos of the harmonic phase at s, as segment computes them (the same in both
        # frames): at the step's start with ``exact`` the ones run_steps holds
        if P[P_AQ] != 0.0:
            if exact and n_events == 1:
                sps, cps = sp0, cp0
            else:
                psi0 = theta_k + P[P_BETA] * s - P[P_PHI]
                sps = math.sin(psi0)
                cps = math.cos(psi0)
        else:
            sps, cps = 0.0, 1.0
        c = segment_at(sg * x, sg * v, s, sg * r0, sg * b, sps, cps, Pw)
        vf = sg * v
        Hs = H - s
        if just_hit and vf < 0.0 and c[C_F0] > 0.0:
            # chatter: rebounds shrink (geometrically under Newton's law) while f pushes the
            # mass into the wall; the tail is summed in closed form as soon as chatter_tail
            # proves where it ends
            wv, F, dF = -vf, c[C_F0], c[C_DF0]
            if eps < 1.0:
                n = cnt[CNT_IMPACTS] - 1    # the impact just recorded, and the one before it
                prev = ((imp_step[n] - imp_step[n - 1]) * P[P_DT]
                        + (imp_off[n] - imp_off[n - 1]) if n >= 1 else 0.0)
                tail = chatter_tail(wv, F, dF, prev, Hs, Pw)
                ok = tail >= 0.0
                F_end = 1.0
                if not ok:
                    # no bracket inside the step (a tail across a sample point, eps near 1):
                    # the first-order estimate once its neglected terms are below round-off
                    # (and the law's fall of eps(u) over the rebounds' speeds, below wv)
                    tail = 2.0 * wv / (F * (1.0 - eps))
                    eps_lo = restitution_range(eps, Pw[P_LAW_A], wv)[0]
                    ok = (tail * (2.0 * Pw[P_ZETA] * wv + abs(dF) * tail) / F
                          + (eps - eps_lo) / (1.0 - eps) <= CHATTER_ESTIMATE_TOL)
                    F_end = (F + dF * tail
                             - 0.5 * abs(Pw[P_A]) * Pw[P_BETA] * Pw[P_BETA] * tail * tail)
            else:
                tail = 2.0 * wv / F
                ok = tail <= ELASTIC_MICRO_FLIGHT
                F_end = F + dF * tail - 0.5 * abs(Pw[P_A]) * Pw[P_BETA] * Pw[P_BETA] * tail * tail
            if two:
                # the summed rebounds (speeds below 2 wv over the tail, chatter_tail's bound)
                # must stay clear of the other wall
                ok = ok and 2.0 * wv * tail * BOUND_SAFETY < (
                    P[P_DELTA] + P[N_PARAMS + P_DELTA])
            micro = n_events >= MANY_EVENTS and (
                wv * wv <= 2.0 * F * MICRO_HEIGHT * (1.0 + abs(Pw[P_DELTA]))
                or 2.0 * wv / F <= MICRO_FLIGHTS_PER_HEADROOM * H / STEP_HEADROOM)
            if (ok and tail <= Hs and F_end > 0.0) or micro:
                if not micro:
                    s = s + tail
                cnt[CNT_CHATTER] += 1
                mode = STUCK
                _record_event(stk_step, stk_off, stk_kind, cnt[CNT_STICK_EVENTS], k, s,
                              STICK_ON + STICK_LO * side)
                cnt[CNT_STICK_EVENTS] += 1
                v = 0.0
                just_hit = False
                continue
        just_hit = False
        if mode == STUCK:
            sig = release_time(c, Pw, Hs)
            if sig < 0.0:
                ftot[FT_CONTACT_TIME] += Hs
                if side == 0:
                    return delta, 0.0, STUCK, OK
                return _wall_position(P, 1), 0.0, STUCK_LO, OK
            ftot[FT_CONTACT_TIME] += sig
            s = min(s + sig, H)
            _record_event(stk_step, stk_off, stk_kind, cnt[CNT_STICK_EVENTS], k, s,
                          STICK_OFF + STICK_LO * side)
            cnt[CNT_STICK_EVENTS] += 1
            mode = FREE
            x = _wall_position(P, side)
            v = 0.0
            at_wall = True
            continue
        code, sig, u, gH = first_contact(c, Pw, Hs, at_wall)
        if two and code != PRESSED:
            # the other wall, seen from off it: the earlier contact ends the flight
            o = 1 - side
            Po = P[N_PARAMS:] if o == 1 else P
            co = segment_at(-sg * x, -sg * v, s, -sg * r0, -sg * b, sps, cps, Po)
            code2, sig2, u2, gH2 = first_contact(co, Po, Hs, False)
            if code2 != NO_ROOT and (code == NO_ROOT or sig2 < sig):
                side, sg, Pw, c = o, -sg, Po, co
                code, sig, u, gH = code2, sig2, u2, gH2
                at_wall = False
        if code == NO_ROOT:
            return sg * (gH + Pw[P_DELTA]), sg * u, FREE, OK
        if code == PRESSED:
            mode = STUCK
            s = min(s + sig, H)
            _record_event(stk_step, stk_off, stk_kind, cnt[CNT_STICK_EVENTS], k, s,
                          STICK_ON + STICK_LO * side)
            cnt[CNT_STICK_EVENTS] += 1
            x = _wall_position(P, side)
            v = 0.0
            continue
        s = min(s + sig, H)
        x = _wall_position(P, side)
        at_wall = True
        if code == ROOT and u <= TOUCH_ULPS * EPS64 * (abs(b) + abs(P[P_AQ]) * P[P_BETA]
                                                       + c[C_R] + abs(v)):
            code = TOUCH          # arrives with zero velocity within round-off: grazing touch
        if code == TOUCH:
            v = sg * min(u, 0.0)
            continue
        _record_event(imp_step, imp_off, imp_u, cnt[CNT_IMPACTS], k, s, sg * u)
        cnt[CNT_IMPACTS] += 1
        v = sg * rebound_velocity(Pw[P_EPS], u, Pw[P_LAW_A])   # the law of the wall met
        just_hit = True


@kernel
def slow_step_one(k, H, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step, stk_off,
              stk_kind, cnt, ftot):
    """:func:`slow_step` for one wall (``P`` of ``N_PARAMS`` slots), compiled apart.

    The same arguments, results and events as :func:`slow_step` with one wall, in the
    arithmetic of a simulator that knows one wall only, operation for operation: no view of
    ``P`` per event, no sign multiplications, no test for a second wall. :func:`run_steps`
    calls it when ``lower`` is None (measured by benchmarks/ab_kernels.py: the generic step
    cost 7-13 % per run with impacts). An edit of the one-wall logic in :func:`slow_step` is
    made here too; tests/test_two_walls.py holds the two bit for bit (the far wall, the
    mirror) and tests/test_simulate*.py hold this one to the stress families' references.
    """
    return _slow_step_one(k, H, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step,
                          stk_off, stk_kind, cnt, ftot, 0.0, 0.0, 1.0, False)


@kernel
def _slow_step_one(k, H, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step, stk_off,
                   stk_kind, cnt, ftot, theta0, sp0, cp0, exact):
    """:func:`slow_step_one`, handed what :func:`run_steps` already computed at sample ``k``.

    With ``exact`` (only with a harmonic force), ``theta0`` is ``phase(k, 0, ...)`` and
    ``sp0, cp0`` are ``sin, cos`` of ``theta0 - phi`` from libm, the very values the step
    would compute itself for its first segment (at offset 0: ``theta0 + beta 0 - phi`` is
    ``theta0 - phi`` exactly, ``phase`` never returning -0) and for ``x'`` in mode ``WALL``:
    the step skips one ``phase`` and one ``sin``/``cos`` pair, bit for bit the same.
    """
    zeta, eps, delta = P[P_ZETA], P[P_EPS], P[P_DELTA]
    if exact:
        theta_k = theta0
    else:
        theta_k = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], P[P_BETA]) if P[P_A] != 0.0 else 0.0
    s = 0.0
    n_events = 0
    if mode == WALL:
        # x' arrives as w' = x' - p_h' (run_steps keeps the harmonic part out of its loop)
        if P[P_A] != 0.0:
            v += P[P_AQ] * P[P_BETA] * (cp0 if exact else math.cos(theta_k - P[P_PHI]))
        mode = FREE
    at_wall = x >= delta
    if at_wall:
        x = delta
    just_hit = False
    imp0, stk0 = cnt[CNT_IMPACTS], cnt[CNT_STICK_EVENTS]
    while True:
        if s >= H:
            # nothing of the step is left: every path here has set x = delta
            return delta, v, (STUCK if mode == STUCK else WALL), OK
        n_events += 1
        if n_events > STEP_HEADROOM - 2:
            ftot[FT_OFFSET] = s
            ftot[FT_GAP] = x - delta
            ftot[FT_V] = v
            ftot[FT_MODE] = mode
            ftot[FT_IMPACTS] = cnt[CNT_IMPACTS] - imp0
            ftot[FT_STICK_EVENTS] = cnt[CNT_STICK_EVENTS] - stk0
            return x, v, mode, TOO_MANY_EVENTS
        if exact and n_events == 1:
            c = segment_at(x, v, s, r0, b, sp0, cp0, P)     # s = 0: the step's own start
        else:
            c = segment(x, v, s, r0, b, theta_k, P)
        Hs = H - s
        if just_hit and v < 0.0 and c[C_F0] > 0.0:
            # chatter: rebounds shrink (geometrically under Newton's law) while f pushes the
            # mass into the wall; the tail is summed in closed form as soon as chatter_tail
            # proves where it ends
            wv, F, dF = -v, c[C_F0], c[C_DF0]
            if eps < 1.0:
                n = cnt[CNT_IMPACTS] - 1    # the impact just recorded, and the one before it
                prev = ((imp_step[n] - imp_step[n - 1]) * P[P_DT]
                        + (imp_off[n] - imp_off[n - 1]) if n >= 1 else 0.0)
                tail = chatter_tail(wv, F, dF, prev, Hs, P)
                ok = tail >= 0.0
                F_end = 1.0
                if not ok:
                    # no bracket inside the step (a tail across a sample point, eps near 1):
                    # the first-order estimate once its neglected terms are below round-off
                    # (and the law's fall of eps(u) over the rebounds' speeds, below wv)
                    tail = 2.0 * wv / (F * (1.0 - eps))
                    eps_lo = restitution_range(eps, P[P_LAW_A], wv)[0]
                    ok = (tail * (2.0 * zeta * wv + abs(dF) * tail) / F
                          + (eps - eps_lo) / (1.0 - eps) <= CHATTER_ESTIMATE_TOL)
                    F_end = (F + dF * tail
                             - 0.5 * abs(P[P_A]) * P[P_BETA] * P[P_BETA] * tail * tail)
            else:
                tail = 2.0 * wv / F
                ok = tail <= ELASTIC_MICRO_FLIGHT
                F_end = F + dF * tail - 0.5 * abs(P[P_A]) * P[P_BETA] * P[P_BETA] * tail * tail
            micro = n_events >= MANY_EVENTS and (
                wv * wv <= 2.0 * F * MICRO_HEIGHT * (1.0 + abs(delta))
                or 2.0 * wv / F <= MICRO_FLIGHTS_PER_HEADROOM * H / STEP_HEADROOM)
            if (ok and tail <= Hs and F_end > 0.0) or micro:
                if not micro:
                    s = s + tail
                cnt[CNT_CHATTER] += 1
                mode = STUCK
                _record_event(stk_step, stk_off, stk_kind, cnt[CNT_STICK_EVENTS], k, s, STICK_ON)
                cnt[CNT_STICK_EVENTS] += 1
                v = 0.0
                just_hit = False
                continue
        just_hit = False
        if mode == STUCK:
            sig = release_time(c, P, Hs)
            if sig < 0.0:
                ftot[FT_CONTACT_TIME] += Hs
                return delta, 0.0, STUCK, OK
            ftot[FT_CONTACT_TIME] += sig
            s = min(s + sig, H)
            _record_event(stk_step, stk_off, stk_kind, cnt[CNT_STICK_EVENTS], k, s, STICK_OFF)
            cnt[CNT_STICK_EVENTS] += 1
            mode = FREE
            x = delta
            v = 0.0
            at_wall = True
            continue
        code, sig, u, gH = first_contact_inline(c, P, Hs, at_wall)
        if code == NO_ROOT:
            return gH + delta, u, FREE, OK
        if code == PRESSED:
            mode = STUCK
            s = min(s + sig, H)
            _record_event(stk_step, stk_off, stk_kind, cnt[CNT_STICK_EVENTS], k, s, STICK_ON)
            cnt[CNT_STICK_EVENTS] += 1
            x = delta
            v = 0.0
            continue
        s = min(s + sig, H)
        x = delta
        at_wall = True
        if code == ROOT and u <= TOUCH_ULPS * EPS64 * (abs(b) + abs(P[P_AQ]) * P[P_BETA]
                                                       + c[C_R] + abs(v)):
            code = TOUCH          # arrives with zero velocity within round-off: grazing touch
        if code == TOUCH:
            v = min(u, 0.0)
            continue
        _record_event(imp_step, imp_off, imp_u, cnt[CNT_IMPACTS], k, s, u)
        cnt[CNT_IMPACTS] += 1
        v = rebound_velocity(eps, u, P[P_LAW_A])   # inlined; Newton's: rounds as -eps * u
        just_hit = True


@kernel
def run_steps(r, k_begin, k_end, state, P, imp_step, imp_off, imp_u, stk_step, stk_off,
              stk_kind, cnt, ftot, grid, grid_v, stride, grid_n, lower=None):
    """Advance the oscillator over the force samples ``r`` from sample ``k_begin`` to ``k_end``.

    Steps ``k_begin .. k_end - 1`` are taken unless an output buffer runs short, in which case
    the function returns early (the driver drains the buffers and calls again). The arguments
    stay separate arrays: every argument and branch added to this loop slows it (measured by
    benchmarks/ab_no_impact.py), and a record type of them would be one more indirection.

    Parameters
    ----------
    r : ndarray of float64, shape (>= k_end - k_begin + 1,)
        Force samples; ``r[0]`` is sample ``k_begin``.
    k_begin, k_end : int
        The samples to step from and to.
    state : ndarray of float64, shape (N_STATE,)
        In and out: the state at sample ``k_begin``, slots ``S_*`` of
        :mod:`vibroimpact.impact.layout`: ``w = x - p_h`` the displacement less the harmonic
        particular solution (so the fast recurrence never touches the harmonic part), ``w'``,
        the mode, and ``sin psi, cos psi`` with ``psi = beta k h - phi``; with mode ``WALL``,
        ``x = delta`` exactly and ``w`` is not read.
    P : ndarray of float64, shape (N_PARAMS,)
        The parameters, slots ``P_*``.
    imp_step, imp_off, imp_u : ndarray, shape (capacity,)
        Out: each impact's sample index (int64), offset in the step and approach velocity.
    stk_step, stk_off, stk_kind : ndarray, shape (capacity,)
        Out: each sticking event's sample index (int64), offset, and kind (1.0 onset,
        0.0 release).
    cnt : ndarray of int64, shape (N_COUNTERS,)
        In and out: the counters, slots ``CNT_*`` (the events written so far).
    ftot : ndarray of float64, shape (N_FTOT,)
        In and out: the float record, slots ``FT_*``: the time in contact, and what a step
        that gave up saw.
    grid, grid_v : ndarray of float64
        Out: ``a = delta - x`` and ``x'`` at every sample with ``k % stride == 0``.
    stride : int
        Record every ``stride`` samples (0: none).
    grid_n : ndarray of int64, shape (1,)
        In and out: the number of grid values written.
    lower : float or None
        The position of the second wall (``P`` then holds both walls' halves), or None for
        one wall: numba compiles the two cases apart, so the one-wall loop carries none of
        the second wall's tests (measured: +4 % per impact-free step when it tested at run
        time whether there was one).

    Returns
    -------
    status, k : int
        ``OK``, ``BUFFER_FULL``, ``TOO_MANY_EVENTS`` or ``BAD_NOISE``, and the sample reached.
    """
    zeta, delta, h = P[P_ZETA], P[P_DELTA], P[P_DT]
    Aq, beta = P[P_AQ], P[P_BETA]
    a11, a12, a21, a22 = P[P_M11], P[P_M12], P[P_M21], P[P_M22]
    inv_h, inv_omega = P[P_INV_DT], P[P_INV_OMEGA]
    cbh, sbh = P[P_COS_BH], P[P_SIN_BH]
    h2_8 = 0.125 * h * h
    M0 = abs(Aq) * beta * beta * BOUND_SAFETY
    margin = EXCLUSION_MARGIN_REL * abs(Aq) + TINY
    A = P[P_A]
    cos_phi, sin_phi = P[P_COS_PHI], P[P_SIN_PHI]
    MF_h2_8 = abs(A) * beta * beta * BOUND_SAFETY * h2_8
    abs_A_delta = abs(A) + abs(delta) + TINY
    has_h = Aq != 0.0
    # a second wall below the mass (P holds its mirrored half): the exclusion test of a free
    # step also bounds x from below, and a step resting on it has its own stay test
    if lower is None:
        # one wall: numba compiles this call without the lower wall's tests (the argument's
        # type is None), so the loop is the one-wall loop, instruction for instruction
        two = False
        low = -math.inf
        abs_A_lower = 0.0
    else:
        two = True
        low = lower
        abs_A_lower = abs(A) + abs(low) + TINY
    w = state[S_W]
    wv = state[S_WV]
    mode = int(state[S_MODE])
    sp = state[S_SIN_PSI]
    cp = state[S_COS_PSI]
    cap_imp = imp_step.shape[0]
    cap_stk = stk_step.shape[0]
    status, k_stop = OK, k_end
    # sp, cp are sin, cos of theta_x - phi from libm (not rotated) at sample k_exact (the
    # step after a slow step, or a resynchronisation): a slow step there reuses them and
    # theta_x = phase(k_exact, 0, ...) instead of computing them again (slow_step_one's
    # ``exact``); written only off the impact-free path
    k_exact = -1
    theta_x = 0.0
    for k in range(k_begin, k_end):
        if has_h and k % RESYNC_EVERY == 0:
            theta_x = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], beta)
            psi = theta_x - P[P_PHI]
            sp = math.sin(psi)
            cp = math.cos(psi)
            k_exact = k
        if stride > 0 and k % stride == 0:
            if mode != FREE:
                # on the wall; STUCK keeps w' = -p_h' exactly, so x' = 0 there
                grid[grid_n[0]] = 0.0 if (mode == STUCK or mode == WALL) else delta - low
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
            if clear and two:
                # the same two tiers, mirrored, against the wall below
                xmin = min(w + Aq * sp, w1 + Aq * sp1)
                clear = xmin - (M0 + R) * h2_8 - margin > low
                if not clear and xmin - margin > low:
                    acc = max(abs(r0 - 2.0 * zeta * wv - w), abs(r1 - 2.0 * zeta * wv1 - w1))
                    clear = (xmin - (M0 + acc + 0.5 * h * R) * BOUND_SAFETY * h2_8 - margin
                             > low)
            if clear:
                w = w1
                wv = wv1
                sp = sp1
                cp = cp1
                continue
            x = w
            v = wv
            sx = 0.0
            cx = 1.0
            if has_h:
                if k != k_exact:
                    theta_x = phase(k, 0.0, P[P_BH_HI], P[P_BH_LO], beta)
                    psi = theta_x - P[P_PHI]
                    sx = math.sin(psi)
                    cx = math.cos(psi)
                else:
                    sx = sp
                    cx = cp
                x = w + Aq * sx
                v = wv + Aq * beta * cx
        else:
            if mode == STUCK:
                # resting on the wall: it stays through the step when the push f - delta is
                # positive all along, >= its smaller end value less |f''| h^2 / 8 (r is linear
                # over the step, |f''| <= A beta^2), with a margin far above the round-off of
                # the rotated phase; what release_time would conclude, without its sines
                F0 = r0 + A * (sp * cos_phi + cp * sin_phi) - delta
                F1 = r1 + A * (sp1 * cos_phi + cp1 * sin_phi) - delta
                if min(F0, F1) - MF_h2_8 > STICK_MARGIN * (abs(r0) + abs(r1) + abs_A_delta):
                    ftot[FT_CONTACT_TIME] += h
                    w = delta - Aq * sp1
                    wv = -Aq * beta * cp1
                    sp = sp1
                    cp = cp1
                    continue
            elif two and mode == STUCK_LO:
                # resting on the wall below: the same test on the push into it, lower - f
                F0 = low - (r0 + A * (sp * cos_phi + cp * sin_phi))
                F1 = low - (r1 + A * (sp1 * cos_phi + cp1 * sin_phi))
                if min(F0, F1) - MF_h2_8 > STICK_MARGIN * (abs(r0) + abs(r1) + abs_A_lower):
                    ftot[FT_CONTACT_TIME] += h
                    w = low - Aq * sp1
                    wv = -Aq * beta * cp1
                    sp = sp1
                    cp = cp1
                    continue
            x = delta if (mode == STUCK or mode == WALL) else low
            v = wv          # w': slow_step adds p_h' in mode WALL, ignores it when STUCK
            sx = sp
            cx = cp
        # a non-finite sample always fails the exclusion test, so it is caught here at no cost
        if not (math.isfinite(r0) and math.isfinite(r1)):
            return BAD_NOISE, k
        # events are written only here: make sure the buffers have room for a whole step
        if (cnt[CNT_IMPACTS] + STEP_HEADROOM > cap_imp
                or cnt[CNT_STICK_EVENTS] + STEP_HEADROOM > cap_stk):
            if stride > 0 and k % stride == 0:
                grid_n[0] -= 1      # sample k is recorded again when the step is resumed
            status, k_stop = BUFFER_FULL, k
            break
        if lower is None:
            # one wall: its own step, compiled without any of the second wall's logic
            # with a harmonic force, sx, cx are sin, cos of theta_x - phi from libm at sample
            # k in mode FREE (just computed) and at k_exact
            exact = has_h and (mode == FREE or k == k_exact)
            x, v, mode, status = _slow_step_one(
                k, h, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step, stk_off,
                stk_kind, cnt, ftot, theta_x, sx, cx, exact)
        else:
            exact = has_h and (mode == FREE or k == k_exact)
            x, v, mode, status = _slow_step(
                k, h, x, v, mode, r0, b, P, imp_step, imp_off, imp_u, stk_step, stk_off,
                stk_kind, cnt, ftot, theta_x, sx, cx, exact)
        if status != OK:
            return status, k
        if has_h:
            theta_x = phase(k + 1, 0.0, P[P_BH_HI], P[P_BH_LO], beta)
            psi = theta_x - P[P_PHI]
            sp1 = math.sin(psi)
            cp1 = math.cos(psi)
            k_exact = k + 1
        w = x - Aq * sp1
        wv = v - Aq * beta * cp1
        sp = sp1
        cp = cp1
    state[S_W] = w
    state[S_WV] = wv
    state[S_MODE] = mode
    state[S_SIN_PSI] = sp
    state[S_COS_PSI] = cp
    return status, k_stop
