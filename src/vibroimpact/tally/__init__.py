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

__all__ = ["group_collisions", "motion_statistics"]

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

    step, offset, u, start, end, dt, eps, floor, pressed, wall = _collisions._checked(
        impact_step, impact_offset, impact_velocity, stick_start, stick_end, dt=dt, eps=eps,
        floor=floor, pressed=pressed, rule=rule, wall=wall, stick_wall=stick_wall,
        eps_lower=eps_lower)
    n = step.size
    if n == 0:
        return _collisions._no_collisions(floor, dt)
    eps = np.full(n, eps) if np.ndim(eps) == 0 else np.ascontiguousarray(eps, dtype=float)
    t0 = -np.inf if after is None else float(after)
    pressed = (np.ascontiguousarray(pressed, dtype=np.bool_) if rule == "physical"
               else np.zeros(0, np.bool_))
    n_counted, *fields = kernels.group(
        np.ascontiguousarray(step), np.ascontiguousarray(offset), np.ascontiguousarray(u),
        np.ascontiguousarray(start), np.ascontiguousarray(end), dt, eps, floor, pressed,
        _collisions.RULES.index(rule), np.ascontiguousarray(wall), t0)
    if rule == "rebounds" and n_counted == 0:     # no rebound reaches the floor: no event
        return _collisions._no_collisions(floor, dt)
    first, impact_collision, step, offset, time, u, rebounds, stuck, stick_time, duration, \
        wall = fields
    return _collisions.Collisions(first, impact_collision, step, offset, time, u, rebounds,
                                  stuck, stick_time, duration, floor, dt, wall)


def motion_statistics(impact_time, intervals, beta, t_start, t_stop, *,
                      window=DEFAULT_MOTION_WINDOW, motions=DEFAULT_MOTIONS, n_batches=20,
                      stuck=None, walls=None):
    """``stats.motion_statistics``: the same arguments, checks and result, bit for bit."""
    from vibroimpact.stats import motions as _motions

    return _motions._motion_statistics(impact_time, intervals, beta, t_start, t_stop, window,
                                       motions, n_batches, stuck, walls, _labelled, _at_edges)


def _labelled(ratio, window, motions, walls, stuck):
    """``stats.motions._labelled`` compiled."""
    from vibroimpact.stats import motions as _motions
    from vibroimpact.tally import kernels

    ratio = np.ascontiguousarray(ratio, dtype=float)
    window = _checks.real("window", window, low=0.0, high=0.5, low_open=True)
    walls = _motions._walls(walls, ratio.size)
    motions = _motions._check_motions(motions, walls=walls is not None)
    if stuck is not None:
        stuck = np.asarray(stuck, dtype=bool)
        if stuck.shape != ratio.shape:
            raise ValueError(f"stuck must hold one flag per interval ({ratio.size}), got "
                             f"shape {stuck.shape}")
    lengths = np.array([_motions._length(m) for m in motions], dtype=np.int64)
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
