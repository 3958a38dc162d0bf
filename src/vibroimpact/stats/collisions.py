"""Collisions: impacts grouped with the chatter and sticking they start (docs/figures.md).

With ``eps < 1`` a mass pressed into the wall rebounds ever lower: a chatter sequence has
infinitely many impacts in finite time and ends in sticking. The simulator resolves its
rebounds one by one until the remaining tail is below a numerical tolerance and sums the
rest, so any count of individual rebounds is set by that tolerance. The unit of every impact
statistic is therefore the **collision**: an impact that follows a free flight, together with
the chatter sequence it starts and the sticking that follows, up to the release.

Definition (the physical rule, exact, independent of where resolving stops): with impacts at
``t_0 < t_1 < ...``, the flight from impact ``j`` to impact ``j + 1`` is a *hop* when no
sticking phase begins in ``[t_j, t_{j+1})`` and the push ``f(tau) - delta`` (the force the
wall would feel holding the mass, the sticking criterion of docs/model.md) is ``> 0`` at every
instant of ``[t_j, t_{j+1}]``: the net force presses the mass toward the wall for the whole
flight (away from the wall the spring adds to it). Any other flight, one in which the mass
was pulled away at some moment (or released from the wall), is a *free flight*.

- impact ``j`` *ends in sticking* when a sticking phase begins in ``[t_j, t_{j+1})`` (the
  accumulation point of a chatter sequence, or a plastic impact with ``eps = 0``);
- the *chatter sequence* ending at such an impact ``j`` is the longest run of impacts
  ``i, ..., j`` joined by hops: it starts at the first impact after the last free flight;
- a *collision* is an impact after a free flight with the chatter sequence it starts and the
  sticking phases that follow (before the next collision), or any other impact on its own.

:func:`pressed_flights` computes the hops exactly from the force record: the random force is
the straight line between samples, so its minimum over a step is at the step's ends; the
harmonic part ``A sin(beta tau)`` adds a closed-form interior minimum per step.

A cycle of one impact, a chatter sequence and sticking is therefore one collision, and so is
a long first rebound under a push that never lets go, whatever the rebound velocities do; a
run that the force interrupts (it pulls, at some moment, and the mass flies off) is split
where it pulled. A run of hops that never sticks is no chatter sequence: its impacts are
collisions of their own (the stable (2/1) motion of Fig. 16 at ``1/beta = 1.1, delta = 0``
has a pressed flight of 1.49 between its two impacts per period, and stays (2/1)). The
interval between collisions runs from one collision's first impact to the next's. The tail
rebounds that a tolerance decides to resolve or to sum all lie where the push is > 0 (the
kernel sticks only there), inside hops that end in the same sticking phase: they never
change the grouping, and every collision field below is independent of the simulator's
tolerances (tests/test_collisions.py changes them by three orders of magnitude).

Two other rules are kept for comparison (the reports' sensitivity table,
docs/figures.md): ``rule="impacts"``, the earlier rule that reads the impacts only (the
longest run of shrinking rebounds, ``u_i > u_{i+1} > ...`` and shrinking flights, that ends
in sticking joins the impact that starts it), which folds some free flights into chatter;
and ``rule="rebounds"``, every rebound leaving the wall at speed ``>= floor`` an event of its
own (the per-rebound view; the slower ones join the event before them).

With a second wall (a clearance, docs/model.md) every impact has a wall (0: the wall at
``x = delta``, hit moving up; 1: the wall at ``delta - gap``, hit moving down). The rule is
the same at each wall with its own sign: the push towards the wall a hop is at is
``f - delta`` at the upper wall and ``(delta - gap) - f`` at the lower one, and a flight
from one wall to the other is never a hop (the mass crossed the clearance: it was pulled
away from the first wall). A collision never spans the two walls: under every rule an
impact at the other wall than the impact before it starts a new collision. With one wall
(``wall`` None, or all zeros) every result is the one-wall result, bit for bit.

Pure numpy on the simulator's event arrays and the force record: :func:`group_collisions`,
:func:`pressed_flights`.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from vibroimpact import _checks

__all__ = ["DEFAULT_REBOUND_FLOOR", "MIN_REBOUND_FLOOR", "RULES", "Collisions",
           "group_collisions", "pressed_flights", "close_open_phase"]

#: The grouping rules of :func:`group_collisions`: the physical rule (chatter hops are the
#: flights pressed throughout), today's default; the earlier impacts-only rule; every rebound
#: above the floor on its own.
RULES = ("physical", "impacts", "rebounds")

#: Default velocity floor of the rebound counts: rebounds leaving the wall slower than this are
#: not counted. A rebound at speed ``v`` rises ``v**2 / (2 F)`` above the wall under a push
#: ``F = f - delta``; at ``v = 0.01`` and ``F ~ 0.5`` that is 1e-4 static deflections, below the
#: contact deformation the rigid-wall model neglects (the paper's velocities after impact are
#: of order 0.1-1, the linear response's rms velocity about 1). The simulator resolves every
#: rebound faster than `MIN_REBOUND_FLOOR` individually, whatever its tolerances, so the count
#: above any floor >= that is exact.
DEFAULT_REBOUND_FLOOR = 0.01
#: Smallest floor allowed: twice ``vibroimpact.impact.kernels.RESOLVED_REBOUND``.
MIN_REBOUND_FLOOR = 1e-4


class Collisions(NamedTuple):
    """Collisions of one record, in time order (see the module docstring)."""

    first: np.ndarray       #: (n_c,) index of each collision's first impact
    impact_collision: np.ndarray   #: (n,) index of the collision of each impact
    step: np.ndarray        #: (n_c,) sample step of the first impact (``impact_step``)
    offset: np.ndarray      #: (n_c,) its offset (``impact_offset``)
    time: np.ndarray        #: (n_c,) its instant, ``step * dt + offset``
    velocity: np.ndarray    #: (n_c,) approach velocity ``u > 0`` of the first impact
    rebounds: np.ndarray    #: (n_c,) rebounds leaving faster than the floor (first included)
    stuck: np.ndarray       #: (n_c,) bool: a sticking phase follows (before the next collision)
    stick_time: np.ndarray  #: (n_c,) time on the wall in those sticking phases
    duration: np.ndarray    #: (n_c,) first impact to the release (stuck) or to the last impact
    floor: float            #: the velocity floor of ``rebounds``
    dt: float               #: the sample step of ``step``
    wall: np.ndarray        #: (n_c,) int8 wall of the collision (0: at delta, 1: delta - gap)

    @property
    def intervals(self) -> np.ndarray:
        """Intervals between collisions, first impact to first impact, in full precision
        (between collisions at the same wall: ``at_wall(w).intervals``)."""
        return np.diff(self.step).astype(float) * self.dt + np.diff(self.offset)

    def at_wall(self, wall: int) -> "Collisions":
        """The collisions at one wall (0: the wall at delta, 1: the wall at delta - gap);
        their ``intervals`` run between consecutive collisions at that wall.
        ``impact_collision`` is renumbered, -1 for impacts of the other wall's collisions."""
        if wall not in (0, 1):
            raise ValueError(f"wall must be 0 (the wall at delta) or 1 (the wall at "
                             f"delta - gap), got {wall!r}")
        return self._select(self.wall == wall)

    def _select(self, keep):
        """The collisions where ``keep``, impacts renumbered (-1: a dropped collision's)."""
        new = np.where(keep, np.cumsum(keep) - 1, -1)
        ic = self.impact_collision
        impact_collision = np.where(ic >= 0, new[np.maximum(ic, 0)] if new.size else -1, -1)
        return self._replace(
            first=self.first[keep], impact_collision=impact_collision.astype(ic.dtype),
            step=self.step[keep], offset=self.offset[keep], time=self.time[keep],
            velocity=self.velocity[keep], rebounds=self.rebounds[keep], stuck=self.stuck[keep],
            stick_time=self.stick_time[keep], duration=self.duration[keep],
            wall=self.wall[keep])

    def after(self, t0: float) -> "Collisions":
        """The collisions whose first impact is at or after ``t0`` (``impact_collision`` is
        renumbered, -1 for impacts of collisions before ``t0``)."""
        keep = self.time >= t0
        n_before = int(np.count_nonzero(~keep))
        return self._replace(
            first=self.first[keep],
            impact_collision=np.maximum(self.impact_collision - n_before, -1),
            step=self.step[keep], offset=self.offset[keep], time=self.time[keep],
            velocity=self.velocity[keep], rebounds=self.rebounds[keep], stuck=self.stuck[keep],
            stick_time=self.stick_time[keep], duration=self.duration[keep],
            wall=self.wall[keep])


def close_open_phase(stick_start, stick_end, stuck_since, t_end, stick_wall=None,
                     stuck_wall=0):
    """The sticking phases of a record with one still going on at its end (begun at
    ``stuck_since``, NaN if none, and not yet among them) ending at ``t_end``.

    With ``stick_wall`` (the wall of each phase, two walls) the walls are returned too,
    ``(start, end, wall)``, the open phase's wall being ``stuck_wall``."""
    start, end = np.asarray(stick_start, dtype=float), np.asarray(stick_end, dtype=float)
    wall = None if stick_wall is None else np.asarray(stick_wall, dtype=np.int8)
    if np.isfinite(stuck_since) and not (start.size and start[-1] == stuck_since):
        start, end = np.append(start, stuck_since), np.append(end, t_end)
        if wall is not None:
            wall = np.append(wall, np.int8(stuck_wall))
    return (start, end) if wall is None else (start, end, wall)


def _next_true(mask):
    """``out[j]``: the smallest index ``>= j`` where ``mask`` is true (``len(mask)`` if none)."""
    n = mask.size
    idx = np.where(mask, np.arange(n), n)
    return np.minimum.accumulate(idx[::-1])[::-1]


def pressed_flights(impact_step, impact_offset, noise, dt, *, delta, amplitude=0.0, beta=1.0,
                    flights=None, wall=None, gap=None):
    """Which flights between consecutive impacts are pressed throughout (the hops).

    ``out[j]`` is True when the push ``f(tau) - delta`` is ``> 0`` at every instant of
    ``[t_j, t_{j+1}]``, with ``f(tau) = r(tau) + amplitude sin(beta tau)`` and ``r`` the
    straight line between the samples ``noise[k] = r(k dt)`` (the simulator's force). Exact,
    not sampled: over each step of the flight the push's minimum is at one of the step's
    ends or, with a harmonic part, at the closed-form root of
    ``r' + amplitude beta cos(beta tau) = 0`` where the curvature is positive. It reads the
    force only, never a tolerance of the simulator. The work is proportional to the steps of
    the flights whose two impacts are pressed.

    With two walls (``wall`` and ``gap`` given) a flight between two impacts at the lower
    wall is pressed when ``(delta - gap) - f > 0`` throughout (the same test in the mirrored
    frame ``x -> -x``: force and amplitude negated, wall at ``-(delta - gap)``), and a flight
    between the two walls never is.

    Parameters
    ----------
    impact_step, impact_offset : array_like, shape (n,)
        Impact instants ``t_j = step * dt + offset``, increasing.
    noise : array_like or None
        The random force samples the record was simulated with (None: no random force).
    dt : float
        Sample step.
    delta, amplitude, beta : float
        Play, harmonic amplitude and frequency ratio.
    flights : array_like of bool, shape (n - 1,), optional
        Only these flights are examined (the others are reported False), e.g. leaving out
        the flights with a sticking phase, which are never hops.
    wall : array_like of int, shape (n,), optional
        The wall of each impact (0: at ``delta``, 1: at ``delta - gap``); needs ``gap``.
    gap : float, optional
        Width of the clearance (the second wall at ``delta - gap``); needs ``wall``.

    Returns
    -------
    ndarray of bool, shape (max(n - 1, 0),)
    """
    sides = flight_sides(impact_step, wall, gap, flights)
    if sides is None:
        return _pressed(impact_step, impact_offset, noise, dt, delta, amplitude, beta, flights)
    upper, lower = sides
    out = _pressed(impact_step, impact_offset, noise, dt, delta, amplitude, beta, upper)
    if lower.any():
        out |= _pressed(impact_step, impact_offset, noise, dt, -(delta - gap), -amplitude,
                        beta, lower, sign=-1.0)
    return out


def flight_sides(impact_step, wall, gap, flights):
    """None with one wall; else the flights to examine at the upper and at the lower wall
    (both impacts at that wall, and among ``flights``), checked."""
    if wall is None and gap is None:
        return None
    if wall is None or gap is None:
        raise ValueError("wall and gap go together: give the wall of each impact and the gap "
                         "of the clearance, or neither (one wall)")
    gap = _checks.real("gap", gap, low=0.0, low_open=True)
    wall = np.asarray(wall)
    n = np.shape(impact_step)[0] if np.ndim(impact_step) else 0
    if wall.shape != (n,) or not np.all((wall == 0) | (wall == 1)):
        raise ValueError(f"wall must hold one value per impact, each 0 (the wall at delta) "
                         f"or 1 (the wall at delta - gap), shape ({n},), got shape "
                         f"{wall.shape}")
    base = (np.ones(max(n - 1, 0), bool) if flights is None
            else np.asarray(flights, dtype=bool))
    return (base & (wall[:-1] == 0) & (wall[1:] == 0),
            base & (wall[:-1] == 1) & (wall[1:] == 1))


def _pressed(impact_step, impact_offset, noise, dt, delta, amplitude, beta, flights,
             sign=1.0):
    """:func:`pressed_flights` at one wall; ``sign = -1``: the force samples negated (the
    mirrored frame of the lower wall, ``delta`` and ``amplitude`` given in it)."""
    step = np.asarray(impact_step, dtype=np.int64)
    offset = np.asarray(impact_offset, dtype=float)
    n = step.size
    if n < 2:
        return np.zeros(0, bool)
    k_lo, k_hi = int(step[0]), int(step[-1]) + 2          # samples k_lo .. k_hi - 1
    if noise is None:
        r = np.zeros(k_hi - k_lo)
    else:
        r = np.asarray(noise[k_lo : min(k_hi, len(noise))], dtype=float)
        if r.size < k_hi - k_lo:     # an impact on the record's last sample: no slope needed
            r = np.append(r, np.full(k_hi - k_lo - r.size, r[-1]))
        if sign < 0.0:
            r = -r
    harmonic = amplitude != 0.0

    def push(k, s):
        """The push at ``k dt + s`` (k absolute sample indices, 0 <= s <= dt)."""
        i = k - k_lo
        value = r[i] + (r[i + 1] - r[i]) / dt * s - delta
        if harmonic:
            value = value + amplitude * np.sin(beta * (k * dt + s))
        return value

    at_impact = push(step, offset) > 0.0
    pressed = at_impact[:-1] & at_impact[1:]
    if flights is not None:
        pressed &= np.asarray(flights, dtype=bool)
    j = np.flatnonzero(pressed)
    if j.size == 0:
        return pressed
    # the flights' steps: [s_lo, s_hi] of step k, from t_j's step to t_{j+1}'s
    count = step[j + 1] - step[j] + 1
    flight = np.repeat(j, count)
    k = step[flight] + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    s_lo = np.where(k == step[flight], offset[flight], 0.0)
    s_hi = np.where(k == step[flight + 1], offset[flight + 1], dt)
    low = push(k, s_hi)                    # each step's end (the flight's start is pressed)
    if harmonic:
        # interior minima of amplitude sin(theta) + slope theta / beta: cos(theta) = c with
        # amplitude sin(theta) < 0
        i = k - k_lo
        c = -(r[i + 1] - r[i]) / dt / (amplitude * beta)
        ok = np.abs(c) <= 1.0
        theta0 = -np.sign(amplitude) * np.arccos(np.clip(c, -1.0, 1.0))
        two_pi = 2.0 * np.pi
        th_lo, th_hi = beta * (k * dt + s_lo), beta * (k * dt + s_hi)
        for n_turn in (np.ceil((th_lo - theta0) / two_pi), np.floor((th_hi - theta0) / two_pi)):
            theta = theta0 + two_pi * n_turn
            inside = ok & (theta >= th_lo) & (theta <= th_hi)
            if inside.any():
                s = np.clip(s_lo[inside] + (theta[inside] - th_lo[inside]) / beta,
                            s_lo[inside], s_hi[inside])
                low[inside] = np.minimum(low[inside], push(k[inside], s))
    pulled = np.zeros(n - 1, bool)
    np.logical_or.at(pulled, flight, low <= 0.0)
    return pressed & ~pulled


def group_collisions(impact_step, impact_offset, impact_velocity, stick_start, stick_end, *,
                     dt: float, eps: float, floor: float = DEFAULT_REBOUND_FLOOR,
                     pressed=None, rule: str = "physical", wall=None, stick_wall=None,
                     eps_lower=None) -> Collisions:
    """Group a record's impacts into collisions (definition: module docstring).

    Parameters
    ----------
    impact_step, impact_offset : array_like, shape (n,)
        The simulator's impact instants ``step * dt + offset``, increasing.
    impact_velocity : array_like, shape (n,)
        Approach velocities ``u > 0``.
    stick_start, stick_end : array_like, shape (m,)
        The sticking phases of the same record (a phase still going on at the record's end
        ends there), increasing.
    dt : float
        Sample step.
    eps : float or array_like, shape (n,)
        Restitution coefficient (rebound speed ``eps * u``) of the wall at ``delta``; or one
        per impact, under a law whose restitution varies with the speed
        (`vibroimpact.model.Model.restitution`, both walls' impacts, ``eps_lower`` None).
    floor : float
        Rebounds leaving the wall at speed ``>= floor`` are counted in ``rebounds``
        (default `DEFAULT_REBOUND_FLOOR`; ``>= MIN_REBOUND_FLOOR``).
    pressed : array_like of bool, shape (n - 1,)
        Which flights the push presses throughout, the hops (:func:`pressed_flights`);
        required by the physical rule, unused by the others.
    rule : {"physical", "impacts", "rebounds"}
        The grouping (module docstring): the physical rule, the earlier impacts-only rule,
        or every rebound above ``floor`` on its own (impacts before the first such rebound
        then belong to no event, ``impact_collision = -1``).
    wall : array_like of int, shape (n,), optional
        The wall of each impact (0: at ``delta``, 1: at ``delta - gap``; the simulator's
        ``impact_wall``). An impact at the other wall than the one before it always starts
        a new collision. Default: all at the wall at ``delta`` (one wall).
    stick_wall : array_like of int, shape (m,) or (m - 1,), optional
        The wall of each sticking phase (the simulator's ``stick_wall``; a phase still open
        at a chunk's end, appended by :func:`close_open_phase`, may lack its own). Checked
        against the impacts: a phase rests on the wall of the last impact before it, so
        its time counts for the collision at that wall; a record where it does not is
        refused.
    eps_lower : float, optional
        Restitution of the wall at ``delta - gap`` (default ``eps``): the rebound speed of
        an impact there is ``eps_lower * u``.

    Returns
    -------
    Collisions
        ``wall`` holds each collision's wall (all 0 with one wall).
    """
    step, offset, u, start, end, dt, eps, floor, pressed, wall = group_arguments(
        impact_step, impact_offset, impact_velocity, stick_start, stick_end, dt=dt, eps=eps,
        floor=floor, pressed=pressed, rule=rule, wall=wall, stick_wall=stick_wall,
        eps_lower=eps_lower)
    n = step.size
    if rule == "rebounds" and n and not np.any(eps * u >= floor):
        n = 0
    if n == 0:
        return no_collisions(floor, dt)
    t = step * dt + offset
    # the first sticking phase that begins at or after each impact, and whether it begins
    # before the next impact
    k = np.searchsorted(start, t, side="left")
    t_next = np.append(t[1:], np.inf)
    ends = k < start.size
    ends[ends] = start[k[ends]] < t_next[ends]
    first_mask = np.ones(n, bool)
    if rule == "physical":
        # hops: no sticking between, pressed throughout; a run of them that ends in sticking
        # is a chatter sequence, joined to the impact that starts it
        cont = np.zeros(n, bool)
        cont[:-1] = ~ends[:-1] & pressed
        first_mask[1:] = ~_chatter_joins(cont, ends)
    elif rule == "rebounds":
        first_mask = eps * u >= floor
    else:
        first_mask[1:] = ~_impacts_only_joins(step, offset, u, ends, dt)
    first_mask[1:] |= wall[1:] != wall[:-1]          # a collision stays at one wall
    first = np.flatnonzero(first_mask)
    impact_collision = np.cumsum(first_mask) - 1     # -1 before a first rebound (rule "rebounds")
    # sticking phases that begin inside each collision [t_first, t_next_first)
    bounds = np.append(t[first], np.inf)
    lo = np.searchsorted(start, bounds[:-1], side="left")
    hi = np.searchsorted(start, bounds[1:], side="left")
    stuck = hi > lo
    cum = np.concatenate([[0.0], np.cumsum(end - start)])
    stick_time = cum[hi] - cum[lo]
    last = np.append(first[1:], n) - 1
    duration = t[last] - t[first]
    release = end[np.maximum(hi - 1, 0)] if end.size else np.zeros(first.size)
    duration = np.where(stuck, release - t[first], duration)
    rebounds = np.add.reduceat((eps * u >= floor).astype(np.int64), first)
    return Collisions(first, impact_collision, step[first], offset[first], t[first], u[first],
                      rebounds, stuck, stick_time, duration, floor, dt, wall[first])


def group_arguments(impact_step, impact_offset, impact_velocity, stick_start, stick_end, *,
                    dt, eps, floor, pressed, rule, wall, stick_wall, eps_lower):
    """`group_collisions`'s arguments as arrays, checked: ``(step, offset, u, start, end, dt,
    eps, floor, pressed, wall)``, ``eps`` per impact where a second wall has its own
    restitution (else the float), ``wall`` int8."""
    step = np.asarray(impact_step, dtype=np.int64)
    offset = np.asarray(impact_offset, dtype=float)
    u = np.asarray(impact_velocity, dtype=float)
    start = np.asarray(stick_start, dtype=float)
    end = np.asarray(stick_end, dtype=float)
    dt = _checks.real("dt", dt, low=0.0, low_open=True)
    eps = _restitution(eps, u.shape)
    floor = _checks.real("rebound_floor", floor, low=MIN_REBOUND_FLOOR)
    if rule not in RULES:
        raise ValueError(f"rule must be one of {RULES}, got {rule!r}")
    if not (step.shape == offset.shape == u.shape) or step.ndim != 1:
        raise ValueError(f"impact_step, impact_offset and impact_velocity must be 1-D of one "
                         f"length, got {step.shape}, {offset.shape}, {u.shape}")
    if start.shape != end.shape or start.ndim != 1:
        raise ValueError(f"stick_start and stick_end must be 1-D of one length, got "
                         f"{start.shape} and {end.shape}")
    wall = _impact_walls(wall, step.size)
    if stick_wall is not None:
        _check_stick_walls(stick_wall, start, step * dt + offset, wall)
    # the rebound speed's coefficient, per impact where a second wall has its own
    if eps_lower is not None:
        eps_lower = _checks.eps(eps_lower, "eps_lower")
        eps = np.where(wall == 1, eps_lower, eps)
    n = step.size
    if rule == "physical":
        if pressed is None:
            raise ValueError("pressed (the flights pressed throughout, pressed_flights) is "
                             "required by rule='physical'")
        pressed = np.asarray(pressed, dtype=bool)
        if pressed.shape != (max(n - 1, 0),):
            raise ValueError(f"pressed must have one value per flight, shape "
                             f"({max(n - 1, 0)},), got {pressed.shape}")
    return step, offset, u, start, end, dt, eps, floor, pressed, wall


def _restitution(eps, shape):
    """``eps`` checked: one coefficient (a float), or one per impact (a law whose restitution
    varies with the speed, `vibroimpact.model.Model.restitution`), each in [0, 1]."""
    if np.ndim(eps) == 0:
        return _checks.eps(eps)
    eps = np.asarray(eps, dtype=float)
    if eps.shape != shape or not np.all((eps >= 0.0) & (eps <= 1.0)):
        raise ValueError(f"eps must be a real number in [0, 1] or one such value per impact "
                         f"(shape {shape}), got an array of shape {eps.shape}"
                         + ("" if eps.shape != shape else " with values outside [0, 1]"))
    return eps


def no_collisions(floor, dt):
    """The `Collisions` of a record without any."""
    e_i, e_f = np.empty(0, np.int64), np.empty(0)
    return Collisions(e_i, e_i.copy(), e_i.copy(), e_f, e_f.copy(), e_f.copy(), e_i.copy(),
                      np.empty(0, bool), e_f.copy(), e_f.copy(), floor, dt,
                      np.empty(0, np.int8))


def _check_stick_walls(stick_wall, start, t, wall):
    """Refuse sticking phases whose wall is not that of the last impact before them."""
    sw = np.asarray(stick_wall)
    if sw.ndim != 1 or sw.size not in (start.size, start.size - 1) or not np.all(
            (sw == 0) | (sw == 1)):
        raise ValueError(f"stick_wall must hold one value per sticking phase (the last may "
                         f"be missing), each 0 or 1, shape ({start.size},), got shape "
                         f"{sw.shape}")
    if t.size == 0:
        return
    last = np.searchsorted(t, start[:sw.size], side="right") - 1
    seen = last >= 0
    bad = np.flatnonzero(seen & (sw != wall[np.maximum(last, 0)]))
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"sticking phase {i} (from {start[i]!r}) rests on wall {sw[i]} but "
                         f"the impact before it hit wall {wall[last[i]]}: stick_wall and "
                         f"wall disagree")


def _impact_walls(wall, n):
    """The wall of each of ``n`` impacts as int8 (zeros when None), checked."""
    if wall is None:
        return np.zeros(n, np.int8)
    wall = np.asarray(wall)
    if wall.shape != (n,) or not np.all((wall == 0) | (wall == 1)):
        raise ValueError(f"wall must hold one value per impact, each 0 (the wall at delta) "
                         f"or 1 (the wall at delta - gap), shape ({n},), got shape "
                         f"{wall.shape}")
    return wall.astype(np.int8)


def _impacts_only_joins(step, offset, u, ends, dt):
    """The earlier, impacts-only rule: ``joins[j]`` when impact ``j + 1`` belongs to the
    collision of ``j``, that is ``j`` lies on a run of shrinking rebounds (``u`` and the
    flights falling) that ends in sticking."""
    n = step.size
    z = np.diff(step).astype(float) * dt + np.diff(offset)
    # the chain j -> j+1 continues towards a sticking end when the rebounds shrink (the
    # approach velocity falls, u_{j+1} < u_j) and so do the flights (z_j > z_{j+1}, unless
    # j + 1 ends the sequence)
    cont = np.zeros(n, bool)
    shrinks = np.append(z[:-1] > z[1:], True)[: n - 1]
    cont[:-1] = ~ends[:-1] & (u[1:] < u[:-1]) & (ends[1:] | shrinks)
    return _chatter_joins(cont, ends)


def _chatter_joins(cont, ends):
    """``joins[j]`` (impact ``j + 1`` belongs to the collision of ``j``): ``j`` lies on a run
    of links ``cont`` that ends in sticking (``ends``) at or after ``j``, and does not end."""
    n = ends.size
    # chatter[j]: impact j lies on a run that ends in sticking at or after j
    next_end = _next_true(ends)
    next_break = _next_true(~ends & ~cont)
    chatter = (next_end < n) & (next_break > next_end)
    return chatter[:-1] & ~ends[:-1]
