"""The hops of a record compiled: :func:`vibroimpact.stats.pressed_flights` in one pass.

Which flights between consecutive impacts the push ``f(tau) - delta`` presses throughout
(docs/figures.md, "Collisions"), walked flight by flight and step by step in numba, stopping
at the first step where the push is not positive, instead of evaluated on every step of
every candidate flight in arrays: the numpy function stays the reference and the statement of
the rule (tests/test_collisions.py holds this one to it); this is the one the simulator's
results and the streaming cells run.

With two walls a flight between two impacts at the lower wall is examined in the mirrored
frame ``x -> -x`` (force samples and amplitude negated, the wall at ``-(delta - gap)``), and a
flight between the walls never is (``stats.pressed_flights``).

Its kernel uses no simulator kernel and no constant of another module, so its numba cache is
stamped with this file alone.
"""
import math

import numpy as np
from numba import njit

from vibroimpact._kernel_cache import kernel_decorator

kernel = kernel_decorator(njit, __file__, ("hops.py",), error_model="numpy")


@kernel
def _push(r, i, k, s, dt, delta, amplitude, beta, mirror):
    """The push at ``k dt + s`` (``i = k - k_lo`` its index in ``r``); ``mirror = -1.0``:
    in the lower wall's mirrored frame (``delta``, ``amplitude`` given in it), else 1.0
    (the product is then exact: the one-wall push to the bit)."""
    r0, r1 = mirror * r[i], mirror * r[i + 1]
    value = r0 + (r1 - r0) / dt * s - delta
    if amplitude != 0.0:
        value += amplitude * math.sin(beta * (k * dt + s))
    return value


#: Relative round-off allowance of `_curved_above`: a few hundred times the worst error of a
#: computed push (the sine's argument beta (k dt + s) loses ~ulp(tau) ~ 1e-16 tau; the linear
#: force a few ulps of its samples), so that a step it clears is one where every push the
#: exact walk would evaluate is > 0 as well.
PUSH_ROUNDOFF = 1e-13


@kernel
def _push_above(r, i, k, s, dt, delta, amplitude, beta, mirror, anchor):
    """The push at ``k dt + s`` as `_push` computes it, or a lower bound of it when that
    bound already shows the computed push > 0.

    ``anchor`` holds ``(k, s, sin(beta (k dt + s)), known)`` of the last push computed in
    full: the sine moves by at most ``beta |tau - tau_anchor|``, so ``linear + amplitude
    sin_anchor - |amplitude| beta |tau - tau_anchor|`` bounds the push from below (less
    `PUSH_ROUNDOFF` times its scale for the round-off of both); above that same margin the
    push `_push` would compute is > 0, and the bound is returned instead (no sine).
    Otherwise the push is computed as `_push` computes it, to the bit, and becomes the
    anchor."""
    r0, r1 = mirror * r[i], mirror * r[i + 1]
    linear = r0 + (r1 - r0) / dt * s - delta
    if amplitude == 0.0:
        return linear
    if anchor[3] > 0.0:
        reach = abs((k - anchor[0]) * dt + (s - anchor[1]))
        slack = PUSH_ROUNDOFF * (1.0 + abs(r0) + abs(r1) + abs(delta)
                                 + abs(amplitude) * (1.0 + beta * (abs(k * dt) + dt)))
        low = (linear + amplitude * anchor[2]
               - abs(amplitude) * beta * reach * (1.0 + LIPSCHITZ_SLACK) - slack)
        if low > slack:
            return low
    sine = math.sin(beta * (k * dt + s))
    anchor[0], anchor[1], anchor[2], anchor[3] = k, s, sine, 1.0
    return linear + amplitude * sine


#: Relative allowance on the reach ``|tau - tau_anchor|`` of `_push_above` (its rounding).
LIPSCHITZ_SLACK = 1e-12


@kernel
def _curved_above(p_lo, p_hi, h, r0, r1, delta, amplitude, beta, tau):
    """True when the push is certainly > 0 on a stretch of one step of length ``h`` whose
    ends' pushes are ``p_lo, p_hi`` (computed, both > 0): the linear force adds no
    curvature and ``|d2/ds2 amplitude sin(beta s)| <= |amplitude| beta^2``, so the push stays
    above ``min(p_lo, p_hi) - |amplitude| beta^2 h^2 / 8``. The bound carries a margin of
    `PUSH_ROUNDOFF` times the push's scale over the round-off of every computed value, so a
    stretch it clears has every push the exact walk evaluates on it > 0: the walk may skip
    its interior minimum (an arccos and a sine) without changing the answer."""
    scale = (1.0 + abs(r0) + abs(r1) + abs(delta)
             + abs(amplitude) * (1.0 + beta * (abs(tau) + h)))
    curve = abs(amplitude) * beta * beta * h * h * 0.125
    return min(p_lo, p_hi) - curve > PUSH_ROUNDOFF * scale


@kernel
def _pressed(step, offset, r, k_lo, dt, delta_upper, delta_lower, amplitude_upper, beta,
             examine, lower, out):
    """``out[j]`` for every flight (see `pressed_flights`), walking the examined ones.

    The values are those of the plain walk (every step's end, and with a harmonic part its
    interior minimum when it lies inside), with four shortcuts that skip only evaluations
    the walk would find > 0: the push at an impact is taken once for the flight it ends and
    the one it starts (same wall: the same arguments), the last step's end is the flight's
    end already tested, a push whose lower bound from the last sine computed is clearly > 0
    is not computed (`_push_above`: the bound stands for it), and a step whose ends are
    pressed and whose curvature cannot bring the push to 0 (`_curved_above`, on the ends'
    pushes or their bounds) skips its interior minimum. Every push it does compute is
    `_push`'s, to the bit: the answer is the plain walk's.
    """
    two_pi = 2.0 * math.pi
    held_j, held = -1, 0.0      # the push at impact held_j in its flight's frame, if computed
    anchor = np.zeros(4)        # the last sine computed (`_push_above`)
    for j in range(step.size - 1):
        out[j] = False
        if not examine[j]:
            continue
        # the wall's frame: the lower wall's mirrored (x -> -x)
        if lower[j]:
            mirror, delta, amplitude = -1.0, delta_lower, -amplitude_upper
        else:
            mirror, delta, amplitude = 1.0, delta_upper, amplitude_upper
        sign = 1.0 if amplitude > 0.0 else -1.0
        ka, kb = step[j], step[j + 1]
        if held_j == j and lower[j - 1] == lower[j]:
            p_a = held
        else:
            p_a = _push_above(r, ka - k_lo, ka, offset[j], dt, delta, amplitude, beta,
                              mirror, anchor)
        if p_a <= 0.0:
            continue
        p_b = _push_above(r, kb - k_lo, kb, offset[j + 1], dt, delta, amplitude, beta,
                          mirror, anchor)
        held_j, held = j + 1, p_b
        if p_b <= 0.0:
            continue
        ok = True
        p_lo = p_a
        for k in range(ka, kb + 1):
            i = k - k_lo
            s_lo = offset[j] if k == ka else 0.0
            s_hi = offset[j + 1] if k == kb else dt
            if k == kb:
                p_hi = p_b
            else:
                p_hi = _push_above(r, i, k, s_hi, dt, delta, amplitude, beta, mirror, anchor)
                if p_hi <= 0.0:
                    ok = False
                    break
            if amplitude != 0.0 and not _curved_above(
                    p_lo, p_hi, s_hi - s_lo, r[i], r[i + 1], delta, amplitude, beta, k * dt):
                # interior minima: cos(beta tau) = c where amplitude sin(beta tau) < 0
                c = -(mirror * r[i + 1] - mirror * r[i]) / dt / (amplitude * beta)
                if abs(c) <= 1.0:
                    theta0 = -sign * math.acos(c)
                    th_lo = beta * (k * dt + s_lo)
                    th_hi = beta * (k * dt + s_hi)
                    for n_turn in (math.ceil((th_lo - theta0) / two_pi),
                                   math.floor((th_hi - theta0) / two_pi)):
                        theta = theta0 + two_pi * n_turn
                        if th_lo <= theta <= th_hi:
                            s = min(max(s_lo + (theta - th_lo) / beta, s_lo), s_hi)
                            if _push(r, i, k, s, dt, delta, amplitude, beta, mirror) <= 0.0:
                                ok = False
                if not ok:
                    break
            p_lo = p_hi
        out[j] = ok


def pressed_flights(impact_step, impact_offset, noise, dt, *, delta, amplitude=0.0, beta=1.0,
                    flights=None, wall=None, gap=None):
    """:func:`vibroimpact.stats.pressed_flights` compiled (same arguments and result)."""
    from vibroimpact.stats.collisions import flight_sides

    sides = flight_sides(impact_step, wall, gap, flights)
    step = np.ascontiguousarray(impact_step, dtype=np.int64)
    offset = np.ascontiguousarray(impact_offset, dtype=np.float64)
    n = step.size
    if n < 2:
        return np.zeros(0, bool)
    k_lo, k_hi = int(step[0]), int(step[-1]) + 2
    if noise is None:
        r = np.zeros(k_hi - k_lo)
    else:
        r = np.ascontiguousarray(noise[k_lo : min(k_hi, len(noise))], dtype=np.float64)
        if r.size < k_hi - k_lo:     # an impact on the record's last sample: no slope needed
            r = np.append(r, np.full(k_hi - k_lo - r.size, r[-1]))
    if sides is None:
        examine = (np.ones(n - 1, np.bool_) if flights is None
                   else np.ascontiguousarray(flights, dtype=np.bool_))
        lower, delta_lower = np.zeros(n - 1, np.bool_), 0.0
    else:
        examine = np.ascontiguousarray(sides[0] | sides[1])
        lower, delta_lower = np.ascontiguousarray(sides[1]), -(float(delta) - float(gap))
    out = np.empty(n - 1, np.bool_)
    _pressed(step, offset, r, k_lo, float(dt), float(delta), delta_lower, float(amplitude),
             float(beta), examine, lower, out)
    return out
