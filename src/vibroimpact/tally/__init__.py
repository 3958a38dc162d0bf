"""A streamed cell's statistics compiled: the collision grouping and the motion statistics.

:func:`group_collisions` and :func:`motion_statistics` take the arguments of, and return to
the bit, ``stats.group_collisions(...).after(t0)`` and ``stats.motion_statistics``: their
loops over the impacts and the intervals run in numba (`kernels`) instead of the reference's
some thirty numpy passes each, and the sums numpy takes pairwise stay numpy's. The numpy
functions of `vibroimpact.stats` remain the statement of each rule (tests/test_tally.py holds
these to them on random and simulated records); these are what the simulation cells run
(`pipeline.cells`), where the map's adaptive cell regroups and relabels its whole record at
every check.

Why compiled and not vectorized further: the grouping is a merge of the impacts with the
sticking phases and two backward scans, the labelling a greedy scan in time order with
overlapping candidates; in numpy each is a dozen passes and temporaries over the record,
cut into many small calls per cell (~40 ns an impact in all, 10 times the simulator's
step), in numba one pass each.

``stats`` loads no numba (the drawing and aggregation jobs stay light): this room sits on
the simulator's floor, beside `impact`.

Nothing at the top of this module imports a statistics module or numba: a job that imports
the cells but groups no collision (a trace, a spectrum) reaches neither, and its code digest
(`pipeline.provenance`) does not change with them.
"""
import numpy as np

from vibroimpact import _checks

__all__ = ["group_collisions", "motion_statistics", "MotionTally", "residence_statistics",
           "ends_in_sticking", "collision_firsts", "rule_probabilities"]

#: ``stats.collisions.DEFAULT_REBOUND_FLOOR`` and ``stats.motions.DEFAULT_MOTION_WINDOW``,
#: ``DEFAULT_MOTIONS`` (tests/test_tally.py holds them equal)
DEFAULT_REBOUND_FLOOR = 0.01
DEFAULT_MOTION_WINDOW = 0.1
DEFAULT_MOTIONS = ((1, 1), (2, 1), (1, 2))


def group_collisions(impact_step, impact_offset, impact_velocity, stick_start, stick_end, *,
                     dt, eps, floor=DEFAULT_REBOUND_FLOOR, pressed=None, rule="physical",
                     wall=None, stick_wall=None, eps_lower=None, after=None):
    """``stats.group_collisions(...)``, then ``.after(after)`` unless ``after`` is None: the
    same arguments, checks and result, bit for bit."""
    from vibroimpact.stats import collisions as _collisions
    from vibroimpact.tally import kernels

    step, offset, u, start, end, dt, eps, floor, pressed, wall = _collisions.group_arguments(
        impact_step, impact_offset, impact_velocity, stick_start, stick_end, dt=dt, eps=eps,
        floor=floor, pressed=pressed, rule=rule, wall=wall, stick_wall=stick_wall,
        eps_lower=eps_lower)
    n = step.size
    if n == 0:
        return _collisions.no_collisions(floor, dt)
    eps = np.full(n, eps) if np.ndim(eps) == 0 else np.ascontiguousarray(eps, dtype=float)
    t0 = -np.inf if after is None else float(after)
    pressed = (np.ascontiguousarray(pressed, dtype=np.bool_) if rule == "physical"
               else np.zeros(0, np.bool_))
    n_counted, *fields = kernels.group(
        np.ascontiguousarray(step), np.ascontiguousarray(offset), np.ascontiguousarray(u),
        np.ascontiguousarray(start), np.ascontiguousarray(end), dt, eps, floor, pressed,
        _collisions.RULES.index(rule), np.ascontiguousarray(wall), t0)
    if rule == "rebounds" and n_counted == 0:     # no rebound reaches the floor: no event
        return _collisions.no_collisions(floor, dt)
    first, impact_collision, step, offset, time, u, rebounds, stuck, stick_time, duration, \
        wall = fields
    return _collisions.Collisions(first, impact_collision, step, offset, time, u, rebounds,
                                  stuck, stick_time, duration, floor, dt, wall)


def motion_statistics(impact_time, intervals, beta, t_start, t_stop, *,
                      window=DEFAULT_MOTION_WINDOW, motions=DEFAULT_MOTIONS, n_batches=20,
                      stuck=None, walls=None):
    """``stats.motion_statistics``: the same arguments, checks and result, bit for bit."""
    from vibroimpact.stats import motions as _motions

    return _motions.motion_statistics_with(impact_time, intervals, beta, t_start, t_stop,
                                           window, motions, n_batches, stuck, walls, _labelled,
                                           _at_edges)


class MotionTally:
    """`stats.motion_statistics` of many records with one set of motions, in one compiled
    pass each (`kernels.motion_pass`): the arguments are checked once, here, and each call
    returns the reference's values to the bit.

    The map's cell calls it at every precision check on a record that only grows: what the
    reference spends on checks, conversions and a dozen numpy calls per record is the larger
    part of its cost there.

    Parameters
    ----------
    beta : float
        Forcing frequency ratio.
    window, motions, n_batches
        As `stats.motion_statistics`.
    walls : bool
        Whether the records come with the wall of each collision (two walls).

    Every record comes with ``stuck`` (the impact-stick variants are counted apart), as the
    map's records do.
    """

    def __init__(self, beta, *, window=DEFAULT_MOTION_WINDOW, motions=DEFAULT_MOTIONS,
                 n_batches=20, walls=False):
        from vibroimpact.stats import motions as _motions
        from vibroimpact.tally import kernels

        self._motions, self._kernels = _motions, kernels
        self.beta = _checks.real("beta", beta, low=0.0, low_open=True)
        self.scale = self.beta / (2.0 * np.pi)      # as `stats.interval_ratio`
        self.window = _checks.real("window", window, low=0.0, high=0.5, low_open=True)
        self.motions = _motions.checked_motions(motions, walls=bool(walls))
        self.n_batches = _checks.integer("n_batches", n_batches, low=2)
        self.walls = bool(walls)
        self.lengths = np.array([_motions.motion_length(m) for m in self.motions], dtype=np.int64)
        self.periods = np.array([m[-1] for m in self.motions], dtype=np.int64)
        self.lowers = np.array([m[1] if len(m) == 3 else -1 for m in self.motions],
                               dtype=np.int64)
        self._none = np.zeros(0, np.int8)

    def _pass(self, time, step, offset, dt, stuck, walls, edges):
        n = max(time.size - 1, 0)
        if self.walls:
            walls = np.ascontiguousarray(walls[:n], dtype=np.int8)
        return self._kernels.motion_pass(
            np.ascontiguousarray(time, dtype=float), np.ascontiguousarray(step, dtype=np.int64),
            np.ascontiguousarray(offset, dtype=float), float(dt), self.scale,
            np.ascontiguousarray(stuck[:n], dtype=np.bool_),
            walls if self.walls else self._none, True, self.window, self.lengths,
            self.periods, self.lowers, len(self.motions), edges)

    @staticmethod
    def _fractions(gathered, bounds, duration):
        """`stats.motions._fractions` of the gathered intervals (the same sums: numpy's
        ``ndarray.sum`` is ``add.reduce``)."""
        add = np.add.reduce
        return np.array([float(add(gathered[bounds[c]:bounds[c + 1]]) / duration)
                         for c in range(bounds.size - 1)])

    def statistics(self, time, step, offset, dt, stuck, t_start, t_stop, walls=None):
        """``stats.motion_statistics(time, intervals, beta, t_start, t_stop, window=,
        motions=, n_batches=, stuck=stuck, walls=walls)`` of collisions at ``time`` (split
        ``step * dt + offset``; ``intervals`` their `Collisions.intervals`), to the bit."""
        _motions = self._motions
        duration = float(t_stop) - float(t_start)
        if not duration > 0.0:
            raise ValueError(f"t_stop must be > t_start, got [{t_start!r}, {t_stop!r}]")
        edges = _motions.batch_edges(float(t_start), duration, self.n_batches)
        z, labels, switches, covered, gathered, bounds = self._pass(
            time, step, offset, dt, stuck, walls, edges)
        probability = self._fractions(gathered, bounds, duration)
        m = len(self.motions)
        stderr = (_motions.stderr_of_covered(covered, duration, self.n_batches) if z.size
                  else np.zeros(2 * m))
        return _motions.MotionStatistics(probability[:m], stderr[:m], switches, labels,
                                         probability[m:], stderr[m:])

    def probabilities(self, time, step, offset, dt, stuck, duration, walls=None):
        """The ``probability`` and ``stick_probability`` of `statistics` over a record of
        ``duration`` (no standard errors: no batches)."""
        duration = float(duration)
        m = len(self.motions)
        if duration <= 0.0:                 # as `stats.motions._fractions`
            return np.zeros(m), np.zeros(m)
        *_, gathered, bounds = self._pass(time, step, offset, dt, stuck, walls,
                                          np.zeros(0))
        probability = self._fractions(gathered, bounds, duration)
        return probability[:m], probability[m:]


def rule_probabilities(tallied, impact_step, impact_offset, impact_velocity, stick_start, *,
                       dt, eps, eps_lower, floor, rules, wall, after, duration):
    """``[(probability, stick_probability)]`` of `MotionTally.probabilities` (``tallied``) on
    the collisions at or after ``after`` of each rule of ``rules`` (not the physical rule:
    no hops), grouped as `collision_firsts` groups them, all in one compiled call
    (`kernels.rule_fractions`); the same values."""
    from vibroimpact.stats import collisions as _collisions

    m = len(tallied.motions)
    duration = float(duration)
    if duration <= 0.0:                 # as `stats.motions._fractions`
        return [(np.zeros(m), np.zeros(m)) for _ in rules]
    gathered, bounds = tallied._kernels.rule_fractions(
        impact_step, impact_offset, impact_velocity, stick_start, float(dt),
        restitutions(eps, eps_lower, wall), float(floor), np.zeros(0, np.bool_),
        np.array([_collisions.RULES.index(r) for r in rules], dtype=np.int64), wall,
        float(after), tallied.scale, tallied.walls, tallied.window, tallied.lengths,
        tallied.periods, tallied.lowers, m)
    out = []
    for b in bounds:
        p = MotionTally._fractions(gathered, b, duration)
        out.append((p[:m], p[m:]))
    return out


def ends_in_sticking(time, stick_start):
    """``out[i]``: a sticking phase begins in ``[time[i], time[i + 1])`` (``time[n] = inf``),
    for increasing ``time`` and ``stick_start`` (the ``ends`` of `stats.group_collisions`)."""
    from vibroimpact.tally import kernels

    return kernels._ends(np.ascontiguousarray(time, dtype=float),
                         np.ascontiguousarray(stick_start, dtype=float))


def collision_firsts(impact_step, impact_offset, impact_velocity, stick_start, *, dt, eps,
                     eps_lower, floor, pressed, rule, wall, after):
    """The collisions at or after ``after`` of `group_collisions`, reduced to what a map cell
    reads: ``(first, time, step, offset, velocity, wall, stuck)``, the values of the
    `stats.Collisions` fields of those names (`kernels.firsts`). Nothing is checked: the
    arguments are the simulator's arrays as `group_collisions` takes them after its checks
    (``wall`` int8 per impact, zeros with one wall; ``eps_lower`` the restitution at wall
    1, or ``eps`` one per impact, `restitutions`; ``pressed`` bool per flight for the
    physical rule)."""
    from vibroimpact.stats import collisions as _collisions
    from vibroimpact.tally import kernels

    # the physical rule reads no restitution (its collisions are no rebound counts)
    eps = restitutions(eps, eps_lower, wall) if rule != "physical" else np.zeros(0)
    return kernels.firsts(impact_step, impact_offset, impact_velocity, stick_start, float(dt),
                          eps, float(floor), pressed, _collisions.RULES.index(rule), wall,
                          float(after))


def restitutions(eps, eps_lower, wall):
    """Each impact's restitution as the kernels read it (float64, one per impact of
    ``wall``): ``eps`` given per impact (a law whose restitution varies with the speed,
    `vibroimpact.model.Model.restitution`) as it is, else ``eps_lower`` at wall 1 and
    ``eps`` at wall 0."""
    if np.ndim(eps) != 0:
        return np.ascontiguousarray(eps, dtype=float)
    return np.where(np.asarray(wall) == 1, float(eps_lower), float(eps))


def residence_statistics(edges, states, n_states):
    """``stats.residence_statistics`` compiled: the same arguments, checks and result, bit for
    bit."""
    from vibroimpact.stats import residence as _residence
    from vibroimpact.tally import kernels

    edges = np.ascontiguousarray(edges, dtype=float)
    states = np.ascontiguousarray(states, dtype=np.int64)
    n_states = int(n_states)
    if edges.size != states.size + 1:
        raise ValueError(f"edges must hold one more value than states, got {edges.size} and "
                         f"{states.size}")
    if states.size and (states.min() < 0 or states.max() >= n_states):
        raise ValueError(f"states must lie in 0 .. {n_states - 1}")
    if np.any(edges[1:] < edges[:-1]):
        raise ValueError("edges must be non-decreasing")
    return _residence.ResidenceStatistics(*kernels.residence(edges, states, n_states))


def _labelled(ratio, window, motions, walls, stuck):
    """``stats.motions._labelled`` compiled."""
    from vibroimpact.stats import motions as _motions
    from vibroimpact.tally import kernels

    ratio = np.ascontiguousarray(ratio, dtype=float)
    window = _checks.real("window", window, low=0.0, high=0.5, low_open=True)
    walls = _motions.checked_walls(walls, ratio.size)
    motions = _motions.checked_motions(motions, walls=walls is not None)
    if stuck is not None:
        stuck = np.asarray(stuck, dtype=bool)
        if stuck.shape != ratio.shape:
            raise ValueError(f"stuck must hold one flag per interval ({ratio.size}), got "
                             f"shape {stuck.shape}")
    lengths = np.array([_motions.motion_length(m) for m in motions], dtype=np.int64)
    periods = np.array([m[-1] for m in motions], dtype=np.int64)
    lowers = np.array([m[1] if len(m) == 3 else -1 for m in motions], dtype=np.int64)
    return kernels.label(
        ratio, window, lengths, periods, lowers,
        np.zeros(0, np.int8) if walls is None else np.ascontiguousarray(walls),
        np.zeros(0, np.bool_) if stuck is None else np.ascontiguousarray(stuck),
        len(motions))


def _at_edges(t, z, classes, n_classes, edges):
    """``stats.motions._at_edges`` compiled."""
    from vibroimpact.tally import kernels

    return kernels.at_edges(np.ascontiguousarray(t, dtype=float),
                            np.ascontiguousarray(z, dtype=float),
                            np.ascontiguousarray(classes, dtype=np.int64), int(n_classes),
                            np.ascontiguousarray(edges, dtype=float))
