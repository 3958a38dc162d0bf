"""Residence times in the impact motions and the rates of switching between them.

A labelled record is a piecewise-constant state: the (m/n) motion of each interval between
collisions (`classify_impact_intervals`), or "none" where no listed motion holds (an
unclassified interval), from the first to the last collision (`label_pieces`). A *stretch* is a
maximal run of one state; its length is a residence time.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["ResidenceStatistics", "label_pieces", "residence_statistics", "by_state",
           "stationary_distribution", "MarkovCheck", "markov_residence_check",
           "jump_chain_independence"]

#: Fewest complete stretches a state needs before `markov_residence_check` judges it.
MARKOV_MIN_STRETCHES = 10
#: |z| above which `markov_residence_check` calls the stretches not Markov (z: the distance of
#: their coefficient of variation from the Markov one in units of 1/sqrt(n)).
MARKOV_Z = 2.0


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


class MarkovCheck(NamedTuple):
    """Whether a state's residence times look like those of a Markov chain
    (`markov_residence_check`); arrays of the shape of the inputs."""

    cv: np.ndarray         #: std / mean of the complete stretches (NaN with n < 2)
    cv_markov: np.ndarray  #: what a Markov chain gives: sqrt(1 - unit / mean), 1 for unit 0
    z: np.ndarray          #: (cv - cv_markov) * sqrt(n)
    markov: np.ndarray     #: 1.0: |z| <= z_max, 0.0: not, NaN: fewer than min_stretches


def markov_residence_check(mean, stderr, n_stretches, unit=0.0,
                           min_stretches: int = MARKOV_MIN_STRETCHES,
                           z_max: float = MARKOV_Z) -> MarkovCheck:
    """Are the residence times in a state those of a Markov chain? Their coefficient of
    variation against the one a Markov chain gives.

    Parameters
    ----------
    mean, stderr, n_stretches : array_like, one shape
        Mean length of the complete stretches of a state, its standard error
        ``std(ddof=1) / sqrt(n)`` and their number n (`residence_statistics`, or the map's
        ``residence_time``, ``residence_time_stderr``, ``n_stretches``).
    unit : float or array_like
        The shortest step of the state, in the units of `mean`: a stretch of an (m/n) motion
        is a whole number of its groups, each n forcing periods long (``unit = n`` with
        `mean` in periods); 0 for a state of any length (continuous time).
    min_stretches : int
        Fewer complete stretches are not judged (``markov`` NaN).
    z_max : float
        Largest ``|z|`` called Markov.

    Returns
    -------
    MarkovCheck

    Notes
    -----
    A continuous-time Markov chain leaves a state at a constant rate: its residence times are
    exponential, whose standard deviation equals the mean (CV = 1). A chain that steps in
    units (a motion group repeats with a fixed probability q, whatever happened before)
    stays a geometric number of units, CV = sqrt(1 - q) = sqrt(1 - unit / mean). A
    deterministic sequence (every stretch of one length) has CV 0; a mixture of short and
    long stays (two time scales, e.g. a hidden slow variable) has CV above the Markov one.
    The sample CV of n exponential (or geometric) values has a standard deviation of at
    most about 1/sqrt(n) (the delta method gives exactly 1/sqrt(n) for the exponential;
    simulated, 0.65/sqrt(n) at n = 5 to 0.99/sqrt(n) at n = 1000), so ``|z| <= 2`` keeps a
    Markov state with probability 95 % or more; below 10 stretches the CV is biased low
    (0.93 at n = 10) and the check is not made. This checks one consequence of the Markov
    property (memoryless stays), not the whole of it: `jump_chain_independence` checks
    where the switches go.
    """
    mean = np.asarray(mean, dtype=float)
    stderr = np.asarray(stderr, dtype=float)
    n = np.asarray(n_stretches, dtype=float)
    unit = np.broadcast_to(np.asarray(unit, dtype=float), mean.shape)
    with np.errstate(invalid="ignore", divide="ignore"):
        cv = stderr * np.sqrt(n) / mean
        cv_markov = np.sqrt(np.clip(1.0 - unit / mean, 0.0, 1.0))
        z = (cv - cv_markov) * np.sqrt(n)
    judged = (n >= min_stretches) & np.isfinite(z)
    markov = np.where(judged, (np.abs(z) <= z_max).astype(float), np.nan)
    return MarkovCheck(cv, cv_markov, z, markov)


def jump_chain_independence(states, n_states: int):
    """Does the state a switch leads to depend on the state before the current one? A
    chi-square test of the first-order jump chain on a sequence of stretches.

    Parameters
    ----------
    states : array_like of int, shape (K,)
        The state of each piece of a labelled record (`label_pieces`); consecutive equal
        states are one stretch.
    n_states : int
        Number of states.

    Returns
    -------
    statistic : float
        Pearson's chi-square, summed over the current states, of the tables (previous state
        x next state) of the stretches' triples.
    dof : int
        Its degrees of freedom: per current state, (rows - 1) (columns - 1) of its table
        without empty rows and columns.
    p_value : float
        ``P(chi2(dof) >= statistic)``; NaN with 0 degrees of freedom (no information: e.g.
        two states, where a switch always returns to the previous state).

    Notes
    -----
    For a Markov chain the sequence of stretches (the jump chain) is a first-order Markov
    chain: where the record goes next from state j does not depend on where it came from.
    A sequence that cycles A B A C A B ... fails: from A it goes to C after B and to B after
    C. The cells of a table should hold about 5 triples or more for the chi-square law.
    """
    from vibroimpact.stats.ranks import chi2_sf

    states = np.asarray(states, dtype=np.int64)
    runs = states[np.flatnonzero(np.diff(states, prepend=-1) != 0)] if states.size else states
    counts = np.zeros((n_states, n_states, n_states))
    np.add.at(counts, (runs[:-2], runs[1:-1], runs[2:]), 1.0)
    statistic, dof = 0.0, 0
    for j in range(n_states):
        table = counts[:, j, :]
        table = table[table.sum(axis=1) > 0][:, table.sum(axis=0) > 0]
        if min(table.shape) < 2:
            continue
        expected = table.sum(axis=1, keepdims=True) * table.sum(axis=0) / table.sum()
        statistic += float(((table - expected) ** 2 / expected).sum())
        dof += (table.shape[0] - 1) * (table.shape[1] - 1)
    p_value = float(chi2_sf(statistic, dof)) if dof else np.nan
    return statistic, dof, p_value


def by_state(motion_map):
    """The residence statistics of a map dataset over one dimension ``state``: its motions,
    then "none".

    The map stores them as a probability map does, over ``motion`` (``residence_time``,
    ``residence_time_stderr``, ``n_stretches``, ``n_censored``), with "none" (time in no
    listed motion) under the same names plus ``_none`` (docs/datasets.md). The one function
    of this package on an xarray Dataset: the figure and the reports read the four states
    alike.

    Returns
    -------
    xarray.Dataset
        Those of the four variables the map holds, over ``("state", *the map's plane)``
        (``inv_beta, delta`` for the paper's, any two parameters for another), states named
        as the map's motions ("1/1", ...) then "none".
    """
    import xarray as xr

    names = ("residence_time", "residence_time_stderr", "n_stretches", "n_censored")
    parts = {}
    for name in (n for n in names if n in motion_map):
        motions = motion_map[name].rename(motion="state")
        none = motion_map[f"{name}_none"].expand_dims(state=["none"])
        parts[name] = xr.concat([motions, none], dim="state")
    return xr.Dataset(parts).transpose("state", ...)
