"""The (m/n) classification of impact intervals and the probabilities of motions (Fig. 15)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from vibroimpact import _checks
from vibroimpact.stats.events import interval_ratio

__all__ = ["DEFAULT_MOTION_WINDOW", "DEFAULT_MOTIONS", "classify_impact_intervals", "motion_key",
           "impact_motion_probabilities", "count_motion_switches", "MotionStatistics",
           "motion_statistics", "motion_map_agreement"]

#: Half-width w of the window on r_j = z_j / z that assigns an interval to a motion type (fig15).
DEFAULT_MOTION_WINDOW = 0.1
#: The impact motions mapped in fig15, as (m, n): m impacts per n forcing periods.
DEFAULT_MOTIONS = ((1, 1), (2, 1), (1, 2))


def _motion_key(motion) -> str:
    """``"m/n"`` of a one-wall motion, ``"(m_upper,m_lower)/n"`` of a two-wall one."""
    if len(motion) == 3:
        return f"({motion[0]},{motion[1]})/{motion[2]}"
    return f"{motion[0]}/{motion[1]}"


def motion_key(motion) -> str:
    """The name of a motion: ``"1/1"`` for ``(1, 1)`` (m collisions per n forcing periods,
    whatever the wall), ``"(1,1)/1"`` for ``(1, 1, 1)`` (one collision at each wall per
    forcing period: ``(m_upper, m_lower, n)``, two walls)."""
    return _motion_key(checked_motions([motion])[0])


def checked_motions(motions, walls=None):
    """Motions as tuples: ``(m, n)`` (m collisions per n periods, any wall) or
    ``(m_upper, m_lower, n)`` (a two-wall motion: that many at each wall); the latter need
    ``walls`` (the wall of each collision) when classifying (``walls`` not None here)."""
    out = []
    for motion in motions:
        motion = tuple(int(k) for k in motion)
        if len(motion) == 2 and motion[0] >= 1 and motion[1] >= 1:
            out.append(motion)
        elif len(motion) == 3 and min(motion) >= 0 and motion[0] + motion[1] >= 1 \
                and motion[2] >= 1:
            out.append(motion)
        else:
            raise ValueError(f"motions must be (m, n) pairs of positive integers or "
                             f"(m_upper, m_lower, n) triples (m_upper, m_lower >= 0, their sum "
                             f">= 1, n >= 1), got {motion!r}")
    if not out:
        raise ValueError("motions must hold at least one motion, got none")
    if walls is False and any(len(m) == 3 for m in out):
        raise ValueError("a two-wall motion (m_upper, m_lower, n) needs the wall of each "
                         "collision (walls=)")
    return tuple(out)


def motion_length(motion):
    """Collisions (intervals) of one group of the motion."""
    return motion[0] + motion[1] if len(motion) == 3 else motion[0]


def _match_masks(ratio: np.ndarray, window: float, motions, walls=None) -> np.ndarray:
    """match[i, j]: intervals j .. j+m_i-1 form motion i (see `classify_impact_intervals`)."""
    match = np.zeros((len(motions), ratio.size), dtype=bool)
    for i, motion in enumerate(motions):
        m, n = motion_length(motion), motion[-1]
        if ratio.size < m:
            continue
        if m == 1:
            match[i] = np.abs(ratio - n) < window
        else:
            groups = sliding_window_view(ratio, m)
            match[i, :groups.shape[0]] = ((groups.max(axis=1) < n - window)
                                          & (np.abs(groups.sum(axis=1) - n) < window))
        if len(motion) == 3:
            # the walls of the group's collisions: m_lower of them at the lower wall
            lower = sliding_window_view((walls == 1).astype(np.int64), m).sum(axis=1)
            match[i, :lower.size] &= lower == motion[1]
    return match


def classify_impact_intervals(ratio, window: float = DEFAULT_MOTION_WINDOW,
                              motions=DEFAULT_MOTIONS, walls=None) -> np.ndarray:
    """Label each interval with the impact motion it belongs to (fig15 definition).

    Parameters
    ----------
    ratio : array_like of float, shape (N,)
        ``r_j = z_j / z`` in time order (see `interval_ratio`).
    window : float, optional
        Half-width w, 0 < w <= 0.5 (default 0.1, `DEFAULT_MOTION_WINDOW`).
    motions : sequence of (m, n) or (m_upper, m_lower, n), optional
        Candidate (m/n) motions, in priority order (default (1/1), (2/1), (1/2)). A triple
        is a two-wall motion: ``m_upper + m_lower`` collisions per n periods, that many at
        each wall (``(1, 1, 1)``, "(1,1)/1": one at each wall per period); it needs `walls`.
    walls : array_like of int, shape (N,), optional
        The wall of the collision that starts each interval (0: the wall at delta, 1: the
        wall at delta - gap; `Collisions.wall`). A pair (m, n) ignores it: with two walls it
        counts the collisions at either wall.

    Returns
    -------
    ndarray of int, shape (N,)
        Index into `motions` of the motion each interval is assigned to, -1 if none.

    Notes
    -----
    An (m/n) motion has m impacts per n forcing periods (docs/model.md, section 8). A group of m
    consecutive intervals starting at j is of that type when

    - m = 1: ``|r_j - n| < w``;
    - m >= 2: every ``r_{j+i} < n - w`` and ``|r_j + ... + r_{j+m-1} - n| < w``

    which for (1/1), (1/2), (2/1) is the definition of docs/figures.md; a two-wall motion
    ``(m_u, m_l, n)`` asks the same of its ``m = m_u + m_l`` intervals and, besides, that
    ``m_l`` of the m collisions starting them are at the lower wall. Groups may overlap (three
    intervals of 0.5 hold two candidate (2/1) pairs), and an interval is counted at most once,
    so groups are taken greedily left to right: at the first unassigned interval j that starts
    some matching group, the first motion in `motions` that matches there claims its m
    intervals, and the scan resumes after them. For the default motions the candidates at one
    j are mutually exclusive (r_j near 1, near 2, or below 0.9), so the priority order only
    matters for user-supplied motions; the greedy pairing reads a (2/1) record in time order
    and pairs a run of short intervals (r1, r2), (r3, r4), ...
    """
    return _classify(ratio, window, motions, walls)[0]


def checked_walls(walls, n):
    """The walls of the intervals' first collisions as int8 (None stays None)."""
    if walls is None:
        return None
    walls = np.asarray(walls)
    if walls.shape != (n,):
        raise ValueError(f"walls must hold one wall per interval ({n}), got shape "
                         f"{walls.shape}")
    if walls.size and not np.isin(walls, (0, 1)).all():
        raise ValueError("walls must be 0 (the wall at delta) or 1 (the wall at delta - gap)")
    return walls.astype(np.int8)


def _classify(ratio, window, motions, walls=None):
    """Labels (as `classify_impact_intervals`) and the first interval of each one's group."""
    ratio = np.asarray(ratio, dtype=float)
    _checks.real("window", window, low=0.0, high=0.5, low_open=True)
    walls = checked_walls(walls, ratio.size)
    motions = checked_motions(motions, walls=walls is not None)
    match = _match_masks(ratio, window, motions, walls)
    labels = np.full(ratio.size, -1, dtype=np.int64)
    group = np.arange(ratio.size)
    lengths = np.array([motion_length(m) for m in motions])
    candidates = np.flatnonzero(match.any(axis=0))
    first = np.argmax(match[:, candidates], axis=0)       # the first motion matching there
    if (lengths == 1).all():
        starts, chosen = candidates, first               # nothing to skip
    else:
        kept = _greedy(candidates, lengths[first])
        starts, chosen = candidates[kept], first[kept]
    m = lengths[chosen]
    at = np.repeat(starts, m) + (np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m))
    labels[at] = np.repeat(chosen, m)
    group[at] = np.repeat(starts, m)
    return labels, group


def _greedy(j, m):
    """Indices of the candidate groups (starts ``j``, lengths ``m``) that the greedy scan in
    time order keeps: a group claims its ``m`` intervals, and a candidate inside a kept group
    is skipped.

    A candidate beyond the reach of every earlier one is kept for sure; the others form
    clusters behind such a candidate. A cluster of consecutive (2/n) candidates (a run of
    short intervals) keeps every other one; any other cluster is scanned one by one.
    """
    n = j.size
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    reach = np.maximum.accumulate(np.concatenate([[-1], (j + m)[:-1]]))
    sure = j >= reach
    cluster = np.cumsum(sure) - 1
    head = np.flatnonzero(sure)
    pos = np.arange(n) - head[cluster]
    step_ok = np.ones(n, bool)
    step_ok[1:] = (np.diff(j) == 1) | sure[1:]
    plain = np.bincount(cluster, weights=~((m == 2) & step_ok), minlength=head.size) == 0
    keep = np.where(plain[cluster], pos % 2 == 0, sure)
    for c in np.flatnonzero(~plain & (np.bincount(cluster, minlength=head.size) > 1)):
        members = np.flatnonzero(cluster == c)
        free_from = -1
        for k in members.tolist():
            keep[k] = j[k] >= free_from
            if keep[k]:
                free_from = j[k] + m[k]
    return np.flatnonzero(keep)


def _with_sticking(labels, group, stuck):
    """Per interval: its motion's group holds a collision that ended sticking."""
    stuck = np.asarray(stuck, dtype=bool)
    if stuck.shape != labels.shape:
        raise ValueError(f"stuck must hold one flag per interval ({labels.size}), got shape "
                         f"{stuck.shape}")
    if not labels.size:
        return stuck.copy()
    # any sticking among the intervals of each group: a cumulative count over the group
    count = np.concatenate([[0], np.cumsum(stuck)])
    return (count[_group_ends(group) + 1] - count[group]) > 0


def _group_ends(group):
    """Index of the last interval of each interval's group (groups are contiguous)."""
    n = group.size
    starts = np.flatnonzero(np.diff(np.concatenate([[-1], group])) != 0)
    stops = np.append(starts[1:], n) - 1
    return np.repeat(stops, np.diff(np.append(starts, n)))


def impact_motion_probabilities(intervals, beta: float, window: float = DEFAULT_MOTION_WINDOW,
                                total_time: float | None = None,
                                motions=DEFAULT_MOTIONS, stuck=None,
                                walls=None) -> dict[str, float]:
    """Probability of each impact motion: fraction of the recorded time it covers (fig15).

    Parameters
    ----------
    intervals : array_like of float, shape (N,)
        Intervals z_j between adjacent collisions in time order (`Collisions.intervals`).
    beta : float
        Forcing frequency ratio of ``sin(beta tau)``; the forcing period is ``z = 2 pi / beta``.
    window : float, optional
        Half-width w on r_j = z_j / z (default 0.1, config value in the workflow).
    total_time : float, optional
        Recorded time the probabilities refer to (>= sum of intervals). Default: the time
        from the first to the last collision, ``sum(intervals)``.
    motions : sequence of (m, n), optional
        Motions to report, default (1/1), (2/1), (1/2). Generic (m/n) are classified by the
        same rule (m consecutive intervals summing to n periods within w).
    stuck : array_like of bool, shape (N,), optional
        Whether the collision that starts each interval ended sticking
        (`Collisions.stuck`). Given, a motion whose group holds such a collision is the
        *impact-stick* variant of the motion, reported apart under the key ``"m/n stick"``,
        and ``"m/n"`` keeps the motions with free flights only (those of Fig. 16).
    walls : array_like of int, shape (N,), optional
        The wall of the collision that starts each interval (two walls; needed by the
        two-wall motions ``(m_upper, m_lower, n)``, keys ``"(m_upper,m_lower)/n"``: see
        `classify_impact_intervals`).

    Returns
    -------
    dict
        ``{"1/1": p11, "2/1": p21, "1/2": p12}`` (keys ``"m/n"``), each in [0, 1], and with
        `stuck` also ``"1/1 stick"``, ...; their sum is at most 1. With no interval, every
        probability is 0 (no impact motion occurred).

    Notes
    -----
    The probability of a type is the summed duration of the intervals assigned to it by
    `classify_impact_intervals` (a (2/1) pair contributes both of its intervals) divided by
    `total_time`. The paper (section 5, Fig. 15) does not define it precisely; this is the
    pipeline's definition (docs/figures.md, "The probability of an impact motion").
    """
    intervals = np.asarray(intervals, dtype=float)
    motions = checked_motions(motions, walls=walls is not None)
    covered = float(intervals.sum())
    if total_time is None:
        total_time = covered
    elif not np.isfinite(total_time) or total_time < covered * (1.0 - 1e-12):
        raise ValueError(f"total_time must be >= the sum of the intervals ({covered!r}), "
                         f"got {total_time!r}")
    labels, group = _classify(interval_ratio(intervals, beta), window, motions, walls)
    keys = list(map(_motion_key, motions))
    if stuck is None:
        return dict(zip(keys, _fractions(intervals, labels, len(motions), total_time)))
    classes = _refine(labels, _with_sticking(labels, group, stuck), len(motions))
    values = _fractions(intervals, classes, 2 * len(motions), total_time)
    return dict(zip(keys + [f"{k} stick" for k in keys], values))


def _refine(labels, sticking, n_motions):
    """Class of each interval: its motion ``i``, or ``i + n_motions`` for the motion's
    impact-stick variant; -1 unclassified."""
    return np.where(labels >= 0, labels + n_motions * sticking, -1)


def _fractions(intervals, labels, n_motions, total_time):
    """Covered time of each motion over `total_time` (the one formula of the probability)."""
    if total_time <= 0.0:
        return [0.0] * n_motions
    return [float(intervals[labels == i].sum() / total_time) for i in range(n_motions)]


def count_motion_switches(labels) -> int:
    """Changes from one classified motion to another along a labelled record.

    Parameters
    ----------
    labels : array_like of int, shape (N,)
        Output of `classify_impact_intervals` (-1: unclassified).

    Returns
    -------
    int
        The number of adjacent pairs of classified intervals, unclassified ones skipped,
        whose motions differ: ``(1/1) (1/1) - - (2/1) (2/1) (1/1)`` holds two switches.

    Notes
    -----
    Under weak noise a cell with two stable motions may stay in one of them for most of
    the record; its probabilities then say where the record started, not how the time is
    shared in the long run. Few switches are the sign of it (fig15 marks such cells).
    """
    labels = np.asarray(labels)
    typed = labels[labels >= 0]
    return int(np.count_nonzero(typed[1:] != typed[:-1]))


class MotionStatistics(NamedTuple):
    """Probabilities of motions on one record, with their batch-means standard errors."""

    probability: np.ndarray   #: (n_motions,) fraction of the recorded time covered
    stderr: np.ndarray        #: (n_motions,) batch-means standard error of `probability`
    n_switches: int           #: changes between classified motions (`count_motion_switches`)
    labels: np.ndarray        #: (N,) motion index of each interval, -1 if none
    #: (n_motions,) fraction covered by the motions' impact-stick variants (NaN without `stuck`)
    stick_probability: np.ndarray = np.empty(0)
    stick_stderr: np.ndarray = np.empty(0)    #: its batch-means standard error


def motion_statistics(impact_time, intervals, beta: float, t_start: float, t_stop: float, *,
                      window: float = DEFAULT_MOTION_WINDOW, motions=DEFAULT_MOTIONS,
                      n_batches: int = 20, stuck=None, walls=None) -> MotionStatistics:
    """Probabilities of the (m/n) motions over ``[t_start, t_stop]`` with standard errors.

    Parameters
    ----------
    impact_time : array_like of float, shape (N + 1,)
        Collision instants (first impacts) in ``[t_start, t_stop]``, increasing.
    intervals : array_like of float, shape (N,)
        The intervals between them in full precision (`Collisions.intervals`).
    beta : float
        Forcing frequency ratio (period ``z = 2 pi / beta``).
    t_start, t_stop : float
        The recorded stretch the probabilities refer to (after the transient).
    window, motions
        As for `classify_impact_intervals`.
    n_batches : int
        B equal stretches of time for the standard errors (>= 2).
    stuck : array_like of bool, shape (N + 1,) or (N,), optional
        Whether each collision ended sticking (`Collisions.stuck`; the last collision's flag
        is not used). Given, the impact-stick variants are counted apart
        (`impact_motion_probabilities`): ``probability`` keeps the motions with free flights
        and ``stick_probability`` holds the variants.
    walls : array_like of int, shape (N + 1,) or (N,), optional
        The wall of each collision (two walls: `Collisions.wall`; the last one's is not
        used), for the two-wall motions ``(m_upper, m_lower, n)``.

    Returns
    -------
    MotionStatistics
        ``probability`` is exactly `impact_motion_probabilities` with ``total_time =
        t_stop - t_start``. ``stderr`` is ``std(p_b, ddof=1) / sqrt(B)`` of the fractions
        ``p_b`` of the B consecutive stretches of length ``(t_stop - t_start) / B`` covered by
        each motion (an interval across a stretch boundary counts in both, by its overlap),
        whose mean is ``probability``: the batch-means error of a time average.

    Notes
    -----
    The error is honest when the stretches are much longer than the time the motion takes
    to forget its type; a record with few switches between motions (`n_switches`) violates
    that, and its error is then too small (the workflow marks such cells).
    """
    return motion_statistics_with(impact_time, intervals, beta, t_start, t_stop, window,
                                  motions, n_batches, stuck, walls, _labelled, _at_edges)


def motion_statistics_with(impact_time, intervals, beta, t_start, t_stop, window, motions,
                           n_batches, stuck, walls, labelled, at_edges):
    """`motion_statistics` with its two passes over the intervals given: ``labelled(ratio,
    window, motions, walls, stuck) -> (labels, classes, n_switches)`` (`_labelled`) and
    ``at_edges(t, z, classes, n_classes, edges) -> (n_classes, B + 1)`` (`_at_edges`); the
    compiled twins (`vibroimpact.tally`) return the same values to the bit."""
    t = np.asarray(impact_time, dtype=float)
    z = np.asarray(intervals, dtype=float)
    if walls is not None:
        walls = np.asarray(walls)[: z.size]
    motions = checked_motions(motions, walls=walls is not None)
    n_batches = _checks.integer("n_batches", n_batches, low=2)
    duration = float(t_stop) - float(t_start)
    if not duration > 0.0:
        raise ValueError(f"t_stop must be > t_start, got [{t_start!r}, {t_stop!r}]")
    if t.size != z.size + 1 and not (t.size == 0 and z.size == 0):
        raise ValueError(f"impact_time must hold one more value than intervals, got "
                         f"{t.size} and {z.size}")
    if stuck is not None:
        stuck = np.asarray(stuck, dtype=bool)[: z.size]
    labels, classes, n_switches = labelled(interval_ratio(z, beta), window, motions, walls,
                                           stuck)
    n_motions = len(motions)
    n_classes = n_motions if stuck is None else 2 * n_motions
    probability = np.array(_fractions(z, classes, n_classes, duration))
    stderr = np.zeros(n_classes)
    if z.size:
        stderr = _batch_stderr(t, z, classes, n_classes, float(t_start), duration, n_batches,
                               at_edges)
    nan = np.full(n_motions, np.nan)
    stick, stick_err = ((probability[n_motions:], stderr[n_motions:]) if stuck is not None
                        else (nan, nan.copy()))
    return MotionStatistics(probability[:n_motions], stderr[:n_motions], n_switches, labels,
                            stick, stick_err)


def _labelled(ratio, window, motions, walls, stuck):
    """Labels (`classify_impact_intervals`), classes (the labels, or with ``stuck`` the
    motions and their impact-stick variants, `_refine`) and switches of the intervals."""
    labels, group = _classify(ratio, window, motions, walls)
    classes = labels
    if stuck is not None:
        classes = _refine(labels, _with_sticking(labels, group, stuck), len(motions))
    return labels, classes, count_motion_switches(labels)


def _at_edges(t, z, classes, n_classes, edges):
    """``(n_classes, B + 1)``: the time each class covered from the first collision to each
    stretch edge (linear within an interval of that class, flat elsewhere; 0 before the
    first collision)."""
    onehot = classes[None, :] == np.arange(n_classes)[:, None]            # (n_classes, N)
    cover = np.concatenate([np.zeros((n_classes, 1)), np.cumsum(z * onehot, axis=1)], axis=1)
    j = np.clip(np.searchsorted(t, edges, side="right") - 1, 0, t.size - 1)   # collision before
    inside = (edges > t[0]) & (j < z.size)                                   # within interval j
    jj = np.minimum(j, z.size - 1)
    extra = np.where(inside[None, :] & onehot[:, jj], np.minimum(edges - t[j], z[jj])[None, :],
                     0.0)
    return np.where(edges[None, :] > t[0], cover[:, j] + extra, 0.0)


def _batch_stderr(t, z, classes, n_classes, t_start, duration, n_batches, at_edges=_at_edges):
    """Batch-means standard error of each class's covered fraction (`motion_statistics`)."""
    edges = batch_edges(t_start, duration, n_batches)
    return stderr_of_covered(at_edges(t, z, classes, n_classes, edges), duration, n_batches)


def batch_edges(t_start, duration, n_batches):
    """The edges of the B stretches of `_batch_stderr`."""
    return t_start + duration * np.arange(n_batches + 1) / n_batches


def stderr_of_covered(covered, duration, n_batches):
    """`_batch_stderr` from the time each class covered up to each edge (`_at_edges`)."""
    # in Fortran order, as the fancy-indexed ``cover[:, j]`` makes it: the standard deviation
    # below sums each class's batches in the order the stored maps were built with
    covered = np.asfortranarray(covered)
    batches = np.diff(covered, axis=1) * (n_batches / duration)           # (n_classes, B)
    return batches.std(axis=1, ddof=1) / np.sqrt(n_batches)


def motion_map_agreement(probability, stable, S, threshold: float = 0.5) -> dict[str, float]:
    """How well a probability map of one motion matches its stable domain (fig15 vs fig16).

    Parameters
    ----------
    probability : array_like, shape (n_inv_beta, n_delta)
        Probability of the motion under harmonic plus random force (NaN: not computed).
    stable : array_like of bool, same shape
        Where a stable periodic motion of that type exists under the harmonic force alone.
    S : array_like, same shape
        Its degree of stability (%), NaN outside the stable domain.
    threshold : float
        Probability above which the motion counts as dominant (default 0.5).

    Returns
    -------
    dict
        ``n_dominant``: cells with probability >= threshold; ``dominant_inside``: the share of
        them inside the stable domain (NaN if none); ``domain_covered``: the share of the
        stable domain where the motion is dominant; ``rank_correlation``: Spearman's rank
        correlation of probability and S over the stable domain (NaN with fewer than 3
        cells or no spread), and ``n_domain`` its cells.
    """
    from vibroimpact.stats.ranks import spearman

    p = np.asarray(probability, dtype=float)
    stable = np.asarray(stable, dtype=bool)
    S = np.asarray(S, dtype=float)
    if not p.shape == stable.shape == S.shape:
        raise ValueError(f"probability, stable and S must have one shape, got {p.shape}, "
                         f"{stable.shape}, {S.shape}")
    known = np.isfinite(p)
    dominant = known & (p >= threshold)
    domain = known & stable & np.isfinite(S)
    n_dom = int(dominant.sum())
    rho = np.nan
    if domain.sum() >= 3 and np.ptp(p[domain]) > 0 and np.ptp(S[domain]) > 0:
        rho = spearman(p[domain], S[domain])
    return dict(n_dominant=n_dom,
                dominant_inside=float((dominant & stable).sum() / n_dom) if n_dom else np.nan,
                domain_covered=(float((dominant & domain).sum() / domain.sum())
                                if domain.any() else np.nan),
                rank_correlation=rho, n_domain=int(domain.sum()))
