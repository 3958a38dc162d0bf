"""Collisions: impacts grouped with the chatter and sticking they start (docs/figures.md).

With ``eps < 1`` a mass pressed into the wall rebounds ever lower: a chatter sequence has
infinitely many impacts in finite time and ends in sticking. The simulator resolves its
rebounds one by one until the remaining tail is below a numerical tolerance and sums the
rest, so any count of individual rebounds is set by that tolerance. The unit of every impact
statistic is therefore the **collision**: an impact that follows a free flight, together with
the chatter sequence it starts and the sticking that follows, up to the release.

Definition (exact on the recorded events, independent of where resolving stops): with impacts
at ``t_0 < t_1 < ...`` and flights ``z_j = t_{j+1} - t_j``,

- impact ``j`` *ends in sticking* when a sticking phase begins in ``[t_j, t_{j+1})`` (the
  accumulation point of a chatter sequence, or a plastic impact with ``eps = 0``);
- the *chatter sequence* ending at such an impact ``j`` is the longest run of impacts
  ``i, ..., j`` with no sticking between them whose rebounds shrink all the way to it: the
  approach velocities fall, ``u_i > u_{i+1} > ... > u_j``, and so do the flights,
  ``z_i > z_{i+1} > ... > z_{j-1}`` (a geometric sequence shrinks so; an impact faster than
  the one before it, or a flight longer than the next, follows a free flight);
- a *collision* is a chatter sequence with the sticking phase after it, or any other impact
  on its own. Its first impact follows a free flight (a flight that is not part of a chatter
  sequence, or a release from the wall).

A cycle of one impact, a chatter sequence and sticking is therefore one collision, and the
interval between collisions runs from one collision's first impact to the next's. A run of
shrinking rebounds that the force interrupts before its accumulation point (the push turns
and the mass flies off) does not end in sticking: it is no chatter sequence, and its impacts
are collisions of their own, as the input makes them. The tail
rebounds that a tolerance decides to resolve or to sum all lie in the shrinking run, so they
never change the grouping: every collision field below is independent of the simulator's
tolerances (tests/test_collisions.py changes them by three orders of magnitude).

Pure numpy on the simulator's event arrays: :func:`group_collisions`.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from vibroimpact import _checks

__all__ = ["DEFAULT_REBOUND_FLOOR", "MIN_REBOUND_FLOOR", "Collisions", "group_collisions",
           "close_open_phase"]

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

    @property
    def intervals(self) -> np.ndarray:
        """Intervals between collisions, first impact to first impact, in full precision."""
        return np.diff(self.step).astype(float) * self.dt + np.diff(self.offset)

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
            stick_time=self.stick_time[keep], duration=self.duration[keep])


def close_open_phase(stick_start, stick_end, stuck_since, t_end):
    """The sticking phases of a record with one still going on at its end (begun at
    ``stuck_since``, NaN if none, and not yet among them) ending at ``t_end``."""
    start, end = np.asarray(stick_start, dtype=float), np.asarray(stick_end, dtype=float)
    if np.isfinite(stuck_since) and not (start.size and start[-1] == stuck_since):
        start, end = np.append(start, stuck_since), np.append(end, t_end)
    return start, end


def _next_true(mask):
    """``out[j]``: the smallest index ``>= j`` where ``mask`` is true (``len(mask)`` if none)."""
    n = mask.size
    idx = np.where(mask, np.arange(n), n)
    return np.minimum.accumulate(idx[::-1])[::-1]


def group_collisions(impact_step, impact_offset, impact_velocity, stick_start, stick_end, *,
                     dt: float, eps: float, floor: float = DEFAULT_REBOUND_FLOOR) -> Collisions:
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
    eps : float
        Restitution coefficient (rebound speed ``eps * u``).
    floor : float
        Rebounds leaving the wall at speed ``>= floor`` are counted in ``rebounds``
        (default `DEFAULT_REBOUND_FLOOR`; ``>= MIN_REBOUND_FLOOR``).

    Returns
    -------
    Collisions
    """
    step = np.asarray(impact_step, dtype=np.int64)
    offset = np.asarray(impact_offset, dtype=float)
    u = np.asarray(impact_velocity, dtype=float)
    start = np.asarray(stick_start, dtype=float)
    end = np.asarray(stick_end, dtype=float)
    dt = _checks.real("dt", dt, low=0.0, low_open=True)
    eps = _checks.eps(eps)
    floor = _checks.real("rebound_floor", floor, low=MIN_REBOUND_FLOOR)
    if not (step.shape == offset.shape == u.shape) or step.ndim != 1:
        raise ValueError(f"impact_step, impact_offset and impact_velocity must be 1-D of one "
                         f"length, got {step.shape}, {offset.shape}, {u.shape}")
    if start.shape != end.shape or start.ndim != 1:
        raise ValueError(f"stick_start and stick_end must be 1-D of one length, got "
                         f"{start.shape} and {end.shape}")
    n = step.size
    t = step * dt + offset
    if n == 0:
        e_i, e_f = np.empty(0, np.int64), np.empty(0)
        return Collisions(e_i, e_i.copy(), e_i.copy(), e_f, e_f.copy(), e_f.copy(), e_i.copy(),
                          np.empty(0, bool), e_f.copy(), e_f.copy(), floor, dt)
    z = np.diff(step).astype(float) * dt + np.diff(offset)
    # the first sticking phase that begins at or after each impact, and whether it begins
    # before the next impact
    k = np.searchsorted(start, t, side="left")
    t_next = np.append(t[1:], np.inf)
    ends = k < start.size
    ends[ends] = start[k[ends]] < t_next[ends]
    # the chain j -> j+1 continues towards a sticking end when the rebounds shrink (the
    # approach velocity falls, u_{j+1} < u_j) and so do the flights (z_j > z_{j+1}, unless
    # j + 1 ends the sequence)
    cont = np.zeros(n, bool)
    shrinks = np.append(z[:-1] > z[1:], True)[: n - 1]
    cont[:-1] = ~ends[:-1] & (u[1:] < u[:-1]) & (ends[1:] | shrinks)
    # chatter[j]: impact j lies on a shrinking run that ends in sticking at or after j
    next_end = _next_true(ends)
    next_break = _next_true(~ends & ~cont)
    chatter = (next_end < n) & (next_break > next_end)
    joins = chatter[:-1] & ~ends[:-1]          # impact j + 1 belongs to the collision of j
    first_mask = np.ones(n, bool)
    first_mask[1:] = ~joins
    first = np.flatnonzero(first_mask)
    impact_collision = np.cumsum(first_mask) - 1
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
                      rebounds, stuck, stick_time, duration, floor, dt)
