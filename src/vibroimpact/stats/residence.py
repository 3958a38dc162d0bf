"""Residence times in the impact motions and the rates of switching between them.

A labelled record is a piecewise-constant state: the (m/n) motion of each interval between
collisions (`classify_impact_intervals`), or "none" where no listed motion holds (an
unclassified interval), from the first to the last collision (`label_pieces`). A *stretch* is a
maximal run of one state; its length is a residence time.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["ResidenceStatistics", "label_pieces", "residence_statistics",
           "stationary_distribution"]


class ResidenceStatistics(NamedTuple):
    """Stretches of each state and the switches between states (`residence_statistics`)."""

    mean: np.ndarray         #: (S,) mean length of the complete stretches (NaN: none)
    stderr: np.ndarray       #: (S,) std(ddof=1) / sqrt(n) of them (NaN with n < 2)
    n_stretches: np.ndarray  #: (S,) complete stretches (both ends inside the record)
    n_censored: np.ndarray   #: (S,) stretches cut by the record's start or end (excluded)
    time: np.ndarray         #: (S,) total time in the state, censored stretches included
    count: np.ndarray        #: (S, S) switches from state i to state j (diagonal 0)
    rate: np.ndarray         #: (S, S) ``count[i, j] / time[i]`` (NaN rows: state never seen)


def label_pieces(impact_time, labels, t_start: float, t_stop: float, n_motions: int):
    """The record as pieces: boundaries and the state of each piece, "none" = ``n_motions``.

    Parameters
    ----------
    impact_time : array_like of float, shape (N + 1,)
        Collision instants in ``[t_start, t_stop]``, increasing (none: N + 1 = 0).
    labels : array_like of int, shape (N,)
        Motion index of each interval between them, -1 if none (`classify_impact_intervals`).
    t_start, t_stop : float
        The recorded stretch.
    n_motions : int
        Number of listed motions; the state "none" gets index ``n_motions``.

    Returns
    -------
    edges : ndarray, shape (K + 1,)
        ``[t_0, ..., t_N]``: the collisions; with no interval ``[t_start, t_stop]``.
    states : ndarray of int, shape (K,)
        State of each piece: the interval's motion, "none" for -1; with no interval the
        one piece is "none".

    Notes
    -----
    The stretches before the first and after the last collision belong to intervals that
    began before ``t_start`` or end after ``t_stop``, whose type is unknown: the probabilities
    count them as no motion, but they are left out here, so that the first and the last
    classified stretches are the ones cut by the record's ends (`residence_statistics`
    censors them). With fewer than two collisions there is no interval, every probability is
    0, and the record is one cut stretch of "none" (with one collision, the neighbouring
    intervals run beyond the record and their type is unknown; "none" is what the
    probabilities say).
    """
    t = np.asarray(impact_time, dtype=float)
    labels = np.asarray(labels, dtype=np.int64)
    if t.size != labels.size + 1 and not (t.size == 0 and labels.size == 0):
        raise ValueError(f"impact_time must hold one more value than labels, got {t.size} "
                         f"and {labels.size}")
    if t.size < 2:
        return np.array([float(t_start), float(t_stop)]), np.array([int(n_motions)])
    return t.copy(), np.where(labels >= 0, labels, int(n_motions))


def residence_statistics(edges, states, n_states: int) -> ResidenceStatistics:
    """Residence times of each state and the matrix of switching rates on a labelled record.

    Parameters
    ----------
    edges : array_like of float, shape (K + 1,)
        Boundaries of the pieces, increasing: piece k is ``[edges[k], edges[k + 1]]``; the
        record is ``[edges[0], edges[-1]]``.
    states : array_like of int, shape (K,)
        State of each piece, in ``0 .. n_states - 1`` (consecutive equal states are one
        stretch).
    n_states : int
        Number of states S.

    Returns
    -------
    ResidenceStatistics
        Lengths and rates in the units of `edges` (divide, or multiply, by the forcing
        period to express them in periods).

    Notes
    -----
    *Censoring.* At most two stretches are cut: the one holding the record's start and the
    one holding its end (one stretch when the record never switches). Their true lengths are
    unknown (only a lower bound), so they are left out of ``mean`` and counted apart in
    ``n_censored``. The mean is then that of the complete stretches, whose number and
    spread give ``stderr = std(ddof=1) / sqrt(n_stretches)`` (stretches of one state are
    separated by other states and taken as independent). Leaving out the cut stretches
    biases the mean low by O(1/n_stretches) relative (a long stretch is more likely to be
    cut), below its stderr once there are a few stretches; with none or one complete stretch
    the mean is NaN or has no error, and the map marks such cells. The censored-data
    estimator ``time / exits`` would keep the cut stretches' time; it is the
    maximum-likelihood mean only for exponential residence times (a Markov sequence, which
    is what one wants to check, not assume), whereas the mean of the complete stretches
    assumes nothing about their distribution and gives its spread directly.

    *Rates.* ``rate[i, j] = count[i, j] / time[i]``: switches from i to j per unit time spent
    in i, with ``time[i]`` holding the cut stretches too. This is the maximum-likelihood
    generator of a continuous-time Markov chain observed on the record (a cut stretch adds
    exposure time but no switch, which is how that estimator treats censoring). The
    diagonal is 0; a state never visited has a NaN row.

    Note that the stationary distribution of this rate matrix (`stationary_distribution`)
    equals the fractions of time ``time / time.sum()`` up to O(1 / switches) for any record,
    Markov or not: ``sum_i time[i] rate[i, j] - time[j] sum_k rate[j, k]`` is the number of
    switches into j minus those out of j, which is 0 for every state but the first and the
    last (+1 and -1 when they differ). Agreement with the probabilities therefore checks the
    bookkeeping, not the Markov property; that shows in the residence times instead (for
    exponential ones, the stretches' standard deviation equals their mean).
    """
    edges = np.asarray(edges, dtype=float)
    states = np.asarray(states, dtype=np.int64)
    n_states = int(n_states)
    if edges.size != states.size + 1:
        raise ValueError(f"edges must hold one more value than states, got {edges.size} and "
                         f"{states.size}")
    if states.size and (states.min() < 0 or states.max() >= n_states):
        raise ValueError(f"states must lie in 0 .. {n_states - 1}")
    if np.any(np.diff(edges) < 0.0):
        raise ValueError("edges must be non-decreasing")
    time = np.bincount(states, weights=np.diff(edges), minlength=n_states)
    # stretches: runs of one state
    start = np.flatnonzero(np.diff(states, prepend=-1) != 0)
    stop = np.append(start[1:], states.size)
    who = states[start]
    length = edges[stop] - edges[start]
    cut = np.zeros(start.size, dtype=bool)
    if start.size:
        cut[0] = cut[-1] = True
    n_censored = np.bincount(who[cut], minlength=n_states)
    whole = ~cut
    n = np.bincount(who[whole], minlength=n_states)
    total = np.bincount(who[whole], weights=length[whole], minlength=n_states)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(n > 0, total / np.maximum(n, 1), np.nan)
        # spread of each state's complete stretches, by its own mean (two-pass for accuracy)
        dev = np.bincount(who[whole], weights=(length[whole] - mean[who[whole]]) ** 2,
                          minlength=n_states)
        stderr = np.where(n > 1, np.sqrt(dev / np.maximum(n - 1, 1) / np.maximum(n, 1)),
                          np.nan)
    count = np.zeros((n_states, n_states), dtype=np.int64)
    np.add.at(count, (who[:-1], who[1:]), 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        rate = np.where(time[:, None] > 0.0, count / time[:, None], np.nan)
    return ResidenceStatistics(mean, stderr, n, n_censored, time, count, rate)


def stationary_distribution(rate) -> np.ndarray:
    """Stationary distribution pi of the continuous-time chain with switching rates `rate`.

    Parameters
    ----------
    rate : array_like, shape (S, S)
        Off-diagonal switching rates (the diagonal is ignored); a row of NaN marks a state
        never visited, which gets probability 0.

    Returns
    -------
    ndarray, shape (S,)
        pi with ``pi Q = 0``, ``sum(pi) = 1`` for the generator ``Q`` (off-diagonal `rate`,
        diagonal minus the row sums), over the visited states; NaN everywhere when it is not
        unique (the visited states do not form one closed class: e.g. two states that are
        never left).
    """
    rate = np.asarray(rate, dtype=float)
    seen = ~np.isnan(rate).all(axis=1)
    pi = np.zeros(rate.shape[0])
    q = np.nan_to_num(rate[np.ix_(seen, seen)])
    np.fill_diagonal(q, 0.0)
    q -= np.diag(q.sum(axis=1))
    k = q.shape[0]
    if k == 0:
        return np.full(rate.shape[0], np.nan)
    a = np.vstack([q.T, np.ones((1, k))])
    b = np.append(np.zeros(k), 1.0)
    if np.linalg.matrix_rank(q) < k - 1:
        return np.full(rate.shape[0], np.nan)
    sol, *_ = np.linalg.lstsq(a, b, rcond=None)
    pi[seen] = sol
    return pi
