"""The (m/n) classification of impact intervals and the probabilities of motions (Fig. 15)."""
from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from vibroimpact import _checks
from vibroimpact.stats.events import interval_ratio

__all__ = ["DEFAULT_MOTION_WINDOW", "DEFAULT_MOTIONS", "classify_impact_intervals",
           "impact_motion_probabilities"]

#: Half-width w of the window on r_j = z_j / z that assigns an interval to a motion type (fig15).
DEFAULT_MOTION_WINDOW = 0.1
#: The impact motions mapped in fig15, as (m, n): m impacts per n forcing periods.
DEFAULT_MOTIONS = ((1, 1), (2, 1), (1, 2))


def _motion_key(motion) -> str:
    return f"{motion[0]}/{motion[1]}"


def _check_motions(motions):
    motions = tuple((int(m), int(n)) for m, n in motions)
    if not motions or any(m < 1 or n < 1 for m, n in motions):
        raise ValueError(f"motions must be (m, n) pairs of positive integers, got {motions!r}")
    return motions


def _match_masks(ratio: np.ndarray, window: float, motions) -> np.ndarray:
    """match[i, j]: intervals j .. j+m_i-1 form motion i (see `classify_impact_intervals`)."""
    match = np.zeros((len(motions), ratio.size), dtype=bool)
    for i, (m, n) in enumerate(motions):
        if ratio.size < m:
            continue
        if m == 1:
            match[i] = np.abs(ratio - n) < window
            continue
        groups = sliding_window_view(ratio, m)
        match[i, :groups.shape[0]] = ((groups.max(axis=1) < n - window)
                                      & (np.abs(groups.sum(axis=1) - n) < window))
    return match


def classify_impact_intervals(ratio, window: float = DEFAULT_MOTION_WINDOW,
                              motions=DEFAULT_MOTIONS) -> np.ndarray:
    """Label each interval with the impact motion it belongs to (fig15 definition).

    Parameters
    ----------
    ratio : array_like of float, shape (N,)
        ``r_j = z_j / z`` in time order (see `interval_ratio`).
    window : float, optional
        Half-width w, 0 < w <= 0.5 (default 0.1, `DEFAULT_MOTION_WINDOW`).
    motions : sequence of (m, n), optional
        Candidate (m/n) motions, in priority order (default (1/1), (2/1), (1/2)).

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

    which for (1/1), (1/2), (2/1) is the definition of docs/figures.md. Groups may overlap (three
    intervals of 0.5 hold two candidate (2/1) pairs), and an interval is counted at most once,
    so groups are taken greedily left to right: at the first unassigned interval j that starts
    some matching group, the first motion in `motions` that matches there claims its m
    intervals, and the scan resumes after them. For the default motions the candidates at one
    j are mutually exclusive (r_j near 1, near 2, or below 0.9), so the priority order only
    matters for user-supplied motions; the greedy pairing reads a (2/1) record in time order
    and pairs a run of short intervals (r1, r2), (r3, r4), ...
    """
    ratio = np.asarray(ratio, dtype=float)
    _checks.real("window", window, low=0.0, high=0.5, low_open=True)
    motions = _check_motions(motions)
    match = _match_masks(ratio, window, motions)
    labels = np.full(ratio.size, -1, dtype=np.int64)
    lengths = [m for m, _ in motions]
    free_from = 0
    for j in np.flatnonzero(match.any(axis=0)):
        if j < free_from:
            continue
        i = int(np.argmax(match[:, j]))
        labels[j:j + lengths[i]] = i
        free_from = j + lengths[i]
    return labels


def impact_motion_probabilities(intervals, beta: float, window: float = DEFAULT_MOTION_WINDOW,
                                total_time: float | None = None,
                                motions=DEFAULT_MOTIONS) -> dict[str, float]:
    """Probability of each impact motion: fraction of the recorded time it covers (fig15).

    Parameters
    ----------
    intervals : array_like of float, shape (N,)
        Intervals z_j between adjacent impacts in time order (`impact_intervals`).
    beta : float
        Forcing frequency ratio of ``sin(beta tau)``; the forcing period is ``z = 2 pi / beta``.
    window : float, optional
        Half-width w on r_j = z_j / z (default 0.1, config value in the workflow).
    total_time : float, optional
        Recorded time the probabilities refer to (>= sum of intervals). Default: the time
        from the first to the last impact, ``sum(intervals)``.
    motions : sequence of (m, n), optional
        Motions to report, default (1/1), (2/1), (1/2). Generic (m/n) are classified by the
        same rule (m consecutive intervals summing to n periods within w).

    Returns
    -------
    dict
        ``{"1/1": p11, "2/1": p21, "1/2": p12}`` (keys ``"m/n"``), each in [0, 1]; their sum is
        at most 1. With no interval, every probability is 0 (no impact motion occurred).

    Notes
    -----
    The probability of a type is the summed duration of the intervals assigned to it by
    `classify_impact_intervals` (a (2/1) pair contributes both of its intervals) divided by
    `total_time`. The paper (section 5, Fig. 15) does not define it precisely; this is the
    pipeline's definition (docs/figures.md, "The probability of an impact motion").
    """
    intervals = np.asarray(intervals, dtype=float)
    motions = _check_motions(motions)
    covered = float(intervals.sum())
    if total_time is None:
        total_time = covered
    elif not np.isfinite(total_time) or total_time < covered * (1.0 - 1e-12):
        raise ValueError(f"total_time must be >= the sum of the intervals ({covered!r}), "
                         f"got {total_time!r}")
    labels = classify_impact_intervals(interval_ratio(intervals, beta), window, motions)
    if total_time <= 0.0:
        return {_motion_key(mn): 0.0 for mn in motions}
    return {_motion_key(mn): float(intervals[labels == i].sum() / total_time)
            for i, mn in enumerate(motions)}
