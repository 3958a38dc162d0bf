"""Event-by-event comparison of a simulation with the high-precision reference.

Impacts are matched in time order; sticking intervals by their ends. What a float64 simulator
cannot decide is not compared: impacts closing a chatter sequence (both simulators sum that tail
in closed form below thresholds of their own; its accumulation point is compared instead), and
everything after an event too slight for round-off to resolve (a graze whose top is within
``GRAZE_HEIGHT`` of the wall: one simulator may touch where the other misses, and the motions
then differ by that event's speed).
"""
from dataclasses import dataclass
import math

import numpy as np

from vibroimpact.validation.reference import agreeing_prefix, chatter_tail_mask, comparable_impacts

#: What a family's worst error measures.
MEASURE = "error / allowance: impacts, contact edges, a(tau) and x' at samples"
#: Impact times (absolute) and approach velocities (relative) must match to this: a
#: well-conditioned impact is computed to ~1e-13; the rest is room for round-off amplified
#: along a short record.
TOL = 1e-9
#: Position round-off of a float64 simulator near the wall, per unit of the problem's scale
#: (``1 + |delta| + force size``): ~100 propagator steps of 1e-16, times 10. A slow impact is a
#: near-tangency: a position error X moves its time by X / u and its speed by |x''| X / u^2.
X_ERR = 1e-14
#: A graze whose top rises less than this (times the scale) above the wall, or stays less than
#: this below it, is not decidable in float64 arithmetic: there a touch may be found or not.
GRAZE_HEIGHT = 1e-12
#: Chatter-tail impacts slower than this (relative to the scale of velocities) are not
#: compared one by one (see ``chatter_tail_mask``).
U_TAIL = 1e-4
#: Impacts slower than this (times the velocity scale) change the motion after them by less
#: than the tolerance's 1e-3: an undecidable one among them does not end the comparison.
U_NEGLIGIBLE = 1e-12


@dataclass
class Comparison:
    """Outcome of comparing one case (counts and the largest error)."""

    compared: int = 0
    missed: int = 0
    spurious: int = 0
    approximated: int = 0
    ambiguous: int = 0
    worst: float = 0.0      # largest error as a fraction of its allowance (> 1: a failure)
    first_problem: str = ""

    @property
    def failed(self):
        return bool(self.missed or self.spurious or self.first_problem)


def _merge(starts, ends, times, slight):
    """Contact intervals, with the interruptions that round-off cannot resolve merged: those
    whose every impact is ``slight`` (too slight to decide). An interruption without impact
    is one too: a float64 simulator ends a flight without impact only by a touch, an arrival
    at the wall with a speed below round-off."""
    out = []
    for a, b in zip(starts, ends):
        if out:
            if all(d for t, d in zip(times, slight) if out[-1][1] < t < a):
                out[-1][1] = max(out[-1][1], b)
                continue
        out.append([a, b])
    return out


def _in_contact(t, intervals, tol):
    return any(a - tol <= t <= b + tol for a, b in intervals)


def _edge_tolerance(edge, kind, force, delta, r_t, r_u, eps, x_err, tol):
    """How far a contact edge may move by round-off.

    A release (``kind`` "end") is the root of ``f - delta``, known to ``x_err``: it moves by
    ``x_err / |f'|`` (at a sample point, the smaller slope of the two sides; a force equal to
    ``delta`` over a stretch leaves the release undetermined, and the motion the same). A
    sticking onset after impacts is the accumulation point of a chatter sequence: the first
    impact of speed ``u`` is known to ``x_err / u`` in time, and the geometric tail multiplies
    that by ``1 + 2 / (1 - eps)``; moreover the bounces lower than ``x_err`` (speeds below
    ``u* = sqrt(2 F x_err)`` under the push ``F = f - delta``) are below round-off, and the
    tail they span, ``2 u* / (F (1 - eps))``, is not determined by float64 arithmetic (a
    flight across a sample point keeps its height only to one ulp of ``delta``). An onset
    without impact is a touch (an arrival with zero speed), as ill-determined as a release.
    """
    f0 = float(force(np.array([edge]))[0])
    slope = min(abs(v) for v in force.slopes(edge))
    by_force = tol + x_err / max(slope, 1e-300)
    if kind == "end" or eps >= 1.0:
        return by_force
    # the chatter sequence closed at this onset: impacts before it whose speeds shrink
    before = [(t, u) for t, u in zip(r_t, r_u) if t <= edge + tol]
    if not before:
        return by_force
    j = len(before) - 1
    while j > 0 and before[j - 1][1] > before[j][1]:
        j -= 1
    push = max(f0 - delta, 1e-300)
    unresolved = 2.0 * math.sqrt(2.0 * x_err / push) / (1.0 - eps)
    return tol + x_err / before[j][1] * (1.0 + 2.0 / (1.0 - eps)) + unresolved


def compare_events(res, ref, force, scale=1.0, u_scale=1.0, tol=TOL, horizon=math.inf):
    """Compare a :class:`~vibroimpact.simulate.SimulationResult` with a reference run.

    Parameters
    ----------
    res : SimulationResult
        The simulation.
    ref : dict
        :func:`~vibroimpact.validation.reference.reference_impacts` output (34 digits).
    force : callable
        ``force(tau)``: the input force ``f`` at an array of instants (to get ``x''`` at the
        simulation's impacts, ``f - 2 zeta u - delta``), with ``force.slopes(tau)``: ``f'``
        just before and just after ``tau`` (a release's conditioning).
    scale : float
        Size of positions and forces (``1 + |delta| + |force|``): scales ``X_ERR`` and
        ``GRAZE_HEIGHT``.
    u_scale : float
        Size of velocities: scales ``U_TAIL``.
    tol : float
        Time and relative velocity tolerance of a well-conditioned impact.
    horizon : float
        Compare nothing from this instant on (e.g. where a 53-bit run of the reference stops
        agreeing with the 34-digit one: see :func:`trusted_horizon`).

    Returns
    -------
    Comparison
    """
    out = Comparison()
    x_err = X_ERR * scale
    graze = GRAZE_HEIGHT * scale
    u_tail = U_TAIL * u_scale
    u_small = U_NEGLIGIBLE * u_scale
    t_end = min(float(ref["t_end"]), horizon)
    if ref.get("truncated"):
        # stopped at an impact: the simulation's may fall just before or after it
        t_end = min(t_end, float(ref["time"][-2] + ref["time"][-1]) / 2
                    if len(ref["time"]) > 1 else 0.0)
    # impacts, chatter tails marked (their accumulation point is the sticking start)
    r_t = [float(t) for t in ref["time"]]
    r_u = [float(u) for u in ref["velocity"]]
    r_a = [float(a) for a in ref["acceleration"]]
    r_tail = chatter_tail_mask(r_t, r_u, ref["stick_start"], ref["stick_end"], u_tail,
                               open_end=bool(ref.get("truncated")))
    s_t = res.impact_time.tolist()
    s_u = res.impact_velocity.tolist()
    s_tail = chatter_tail_mask(s_t, s_u, res.stick_start, res.stick_end, u_tail)
    # impacts too slight to decide (a graze within round-off of the wall) are not compared;
    # the first one that is not also negligible ends the comparison (the horizon)
    horizon = t_end
    r_amb = [u * u <= 2.0 * max(abs(a), 1e-300) * graze for u, a in zip(r_u, r_a)]
    zeta, delta = res.params["zeta"], res.params["delta"]
    s_a = np.asarray(force(res.impact_time), float) - 2.0 * zeta * res.impact_velocity - delta
    s_amb = [u * u <= 2.0 * max(abs(a), 1e-300) * graze for u, a in zip(s_u, s_a.tolist())]
    for times, speeds, amb, tail in ((r_t, r_u, r_amb, r_tail), (s_t, s_u, s_amb, s_tail)):
        for t, u, d, in_tail in zip(times, speeds, amb, tail):
            if d and not in_tail and t < horizon:
                out.ambiguous += 1
                if u > u_small:
                    horizon = t
                    break
    if ref.get("truncated"):
        # stopped inside a run of undecidable impacts: whether the contact before them ended
        # for good is not known, so the edge before that run is not compared either
        j = len(r_amb)
        while j > 0 and (r_amb[j - 1] or r_tail[j - 1]):
            j -= 1
        if j < len(r_amb):
            before = [float(e) for e in ref["stick_end"] if float(e) <= r_t[j]]
            t_end = min(t_end, max(before) if before else r_t[j])
    # the reference's and the simulation's contact, unresolvable interruptions merged; a start
    # on the wall counts as contact at tau = 0 (a flight from there may be unresolvable too)
    lead = [0.0] if res.params["x0"] == delta and res.params["v0"] <= 0.0 else []
    r_stick = _merge(lead + [float(a) for a in ref["stick_start"]],
                     lead + [float(b) for b in ref["stick_end"]]
                     + ([t_end] if len(ref["stick_end"]) < len(ref["stick_start"]) else []),
                     r_t, r_amb)
    s_stick = _merge(lead + res.stick_start.tolist(), lead + res.stick_end.tolist(), s_t, s_amb)
    ref_imp = [(t, u, a) for t, u, a, d, e in zip(r_t, r_u, r_a, r_tail, r_amb)
               if not (d or e) and t < horizon]
    sim_imp = [(t, u) for t, u, d, e in zip(s_t, s_u, s_tail, s_amb)
               if not (d or e) and t < horizon]
    j = 0
    matched = [False] * len(sim_imp)
    for t, u, a in ref_imp:
        tol_t = tol + x_err / u
        tol_u = tol + x_err * abs(a) / (u * u)
        while j < len(sim_imp) and sim_imp[j][0] < t - tol_t:
            j += 1
        if j < len(sim_imp) and abs(sim_imp[j][0] - t) <= tol_t:
            err_t = abs(sim_imp[j][0] - t)
            err_u = abs(sim_imp[j][1] / u - 1.0)
            matched[j] = True
            out.compared += 1
            out.worst = max(out.worst, err_t / tol_t, err_u / tol_u)
            if err_u > tol_u and not out.first_problem:
                out.first_problem = (f"impact at tau={t!r}: velocity {sim_imp[j][1]!r} vs "
                                     f"reference {u!r} (|du/u| {err_u:.3g} > {tol_u:.3g})")
            j += 1
        elif _in_contact(t, s_stick, tol_t):
            out.approximated += 1      # the simulation rests on the wall there (documented)
        else:
            out.missed += 1
            if not out.first_problem:
                out.first_problem = f"missed impact at tau={t!r}, u={u!r}"
    for (t, u), m in zip(sim_imp, matched):
        if not m and not _in_contact(t, r_stick, tol):
            out.spurious += 1
            if not out.first_problem:
                out.first_problem = f"spurious impact at tau={t!r}, u={u!r}"
    # contact edges: every start and end before the horizon must have a counterpart within
    # its conditioning (see _edge_tolerance)
    eps = res.params["eps"]
    for mine, theirs, what in ((r_stick, s_stick, "reference"), (s_stick, r_stick, "simulation")):
        for a, b in mine:
            for edge, kind in ((a, "start"), (b, "end")):
                if edge >= horizon or edge >= t_end - tol or (edge == 0.0 and lead):
                    continue
                allowed = _edge_tolerance(edge, kind, force, delta, r_t, r_u, eps, x_err, tol)
                near = min((abs(edge - e) for iv in theirs for e in iv), default=math.inf)
                if what == "reference" and allowed <= 1e-3:
                    out.compared += 1
                    out.worst = max(out.worst, near / allowed if near < math.inf else 0.0)
                if near > allowed:
                    if what == "reference":
                        out.missed += 1
                    else:
                        out.spurious += 1
                    if not out.first_problem:
                        out.first_problem = (f"{what} contact {kind} at tau={edge!r} has no "
                                             f"counterpart within {allowed:.3g} "
                                             f"(nearest {near:.3g})")
    # the motion itself at every sample before the horizon (contact or flight alike)
    if "x" in ref and res.a.size:
        n = min(len(ref["x"]), res.a.size)
        r_a = np.array([float(delta - x) for x in ref["x"][:n]])
        r_v = np.array([float(v) for v in ref["v"][:n]])
        times = res.grid_time[:n]
        keep = times < horizon
        # position and velocity at once, both against the allowance of the position; the
        # velocity jumps at an impact, so where one falls on a sample either side is right
        jump = np.zeros(n, bool)
        if r_t:
            gaps = np.abs(times[:, None] - np.array(r_t)[None, :]).min(axis=1)
            jump = gaps <= tol * (1.0 + np.abs(times))
        err_v = np.where(jump, 0.0, np.abs(res.v[:n] - r_v))
        err = np.maximum(np.abs(res.a[:n][keep] - r_a[keep]), err_v[keep] * scale / u_scale)
        tol_x = tol * (scale + u_scale)
        if err.size:
            out.compared += int(err.size)
            out.worst = max(out.worst, float(err.max()) / tol_x)
            if err.max() > tol_x and not out.first_problem:
                k = int(np.argmax(err))
                out.first_problem = (f"a(tau) or x' at tau={times[keep][k]!r} differs by "
                                     f"{err[k]:.3g} (> {tol_x:.3g})")
    return out


def trusted_horizon(ref, ref53, u_tail=U_TAIL, tol=TOL / 10):
    """The instant up to which float64 arithmetic can follow the reference: the first impact
    at which a 53-bit run of the reference (``ref53``) leaves the 34-digit one (``ref``) by
    more than ``tol`` (round-off amplified by a long sequence of slow impacts); ``inf`` if
    they agree throughout."""
    n = agreeing_prefix(ref, ref53, tol=tol, u_tail=u_tail)
    times, _, _ = comparable_impacts(ref, u_tail)
    if n >= len(times):
        return math.inf
    # halfway from the last impact that agrees: the simulation's counterpart of the first
    # that does not may fall just before it
    return 0.5 * (times[n - 1] + times[n]) if n > 0 else 0.0


def invariant_problems(res, delta, eps, grid_tol):
    """What breaks the simulator's invariants, as a list of strings (empty: none).

    ``x <= delta`` on the recorded grid (to ``grid_tol``), finite values, positive approach
    velocities, impact times non-decreasing in full precision, offsets inside their step,
    contact intervals ordered and disjoint.
    """
    problems = []
    if res.a.size and not (np.all(np.isfinite(res.a)) and res.a.min() >= -grid_tol):
        problems.append(f"x > delta on the grid: min a = {res.a.min()!r}")
    if not np.all(np.isfinite(res.impact_velocity)) or np.any(res.impact_velocity <= 0.0):
        problems.append("non-positive or non-finite approach velocity")
    key = res.impact_step.astype(float) * res.params["dt"] + res.impact_offset
    if np.any(np.diff(res.impact_step) < 0) or np.any(np.diff(key) < -1e-12 * (1 + key[:-1])):
        problems.append("impact times decrease")
    if np.any(res.impact_offset < 0.0) or np.any(res.impact_offset > res.params["dt"]):
        problems.append("impact offset outside its step")
    if np.any(res.stick_end < res.stick_start) or np.any(res.stick_start[1:] < res.stick_end[:-1]):
        problems.append("contact intervals overlap or run backwards")
    if not (math.isfinite(res.x_end) and res.x_end <= delta + grid_tol):
        problems.append(f"final x - delta = {res.x_end - delta!r}")
    return problems
