"""Impact events: intervals, velocities after impact, densities, batch means
(Figs. 7-9, 13, 14)."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from vibroimpact import _checks

__all__ = ["DEFAULT_N_BATCHES", "impact_intervals", "velocity_after_impact", "interval_ratio",
           "Density", "density", "t_quantile", "BatchMeans", "batch_means"]

#: Batches in a batch-means standard error; >= 20 keeps the t-quantile close to the normal one.
DEFAULT_N_BATCHES = 20


def impact_intervals(step, offset, dt: float) -> np.ndarray:
    """Intervals between adjacent impacts, z_j, from the simulator's split impact times.

    Parameters
    ----------
    step : array_like of int, shape (n,)
        ``SimulationResult.impact_step``.
    offset : array_like of float, shape (n,)
        ``SimulationResult.impact_offset`` (0 <= offset <= dt).
    dt : float
        The simulation's sample step.

    Returns
    -------
    ndarray of float, shape (max(n - 1, 0),)
        ``z_j = (k_{j+1} - k_j) dt + (o_{j+1} - o_j)``: the integer difference is exact, so
        short intervals keep full precision on long records where ``impact_time`` would not.
        Intervals that contain a sticking phase include the time spent on the wall.
    """
    step = np.asarray(step, dtype=np.int64)
    offset = np.asarray(offset, dtype=float)
    if step.shape != offset.shape or step.ndim != 1:
        raise ValueError(f"step and offset must be 1-D of equal length, got {step.shape} "
                         f"and {offset.shape}")
    return np.diff(step).astype(float) * float(dt) + np.diff(offset)


def velocity_after_impact(u_minus, eps: float) -> np.ndarray:
    """Speed just after impact, ``eps * u_{j-0}`` (paper eq. 7: u_{j+0} = -eps u_{j-0}).

    Returned as a positive speed (the rebound velocity itself is its negative).
    """
    _checks.eps(eps)
    return eps * np.asarray(u_minus, dtype=float)


def interval_ratio(intervals, beta: float) -> np.ndarray:
    """``r_j = z_j / z`` with the forcing period ``z = 2 pi / beta`` (Fig. 13)."""
    _checks.real("beta", beta, low=0.0, low_open=True)
    return np.asarray(intervals, dtype=float) * (beta / (2.0 * np.pi))


class Density(NamedTuple):
    """A histogram density estimate with per-bin standard errors."""

    centres: np.ndarray  #: bin centres, shape (nbins,)
    density: np.ndarray  #: probability density, integrates to 1 over the bins
    stderr: np.ndarray   #: standard error of `density` per bin (binomial, or batch means)
    n: int               #: number of values normalising the density (in the bins unless `total`)
    beyond: float = np.nan  #: fraction of the `n` values above the last bin edge (NaN if n = 0)


def density(values, bins, range=None, total=None, n_batches=None) -> Density:
    """Probability density of `values` by histogram, with per-bin standard errors.

    Parameters
    ----------
    values : array_like of float, shape (N,)
        Samples (e.g. velocities after impact, intervals, z_j / z), in time order when
        `n_batches` is given.
    bins : int or array_like
        Passed to ``numpy.histogram``.
    range : (float, float), optional
        Passed to ``numpy.histogram``.
    total : int, optional
        Normalise by this many values instead of the count inside the bins, so that values
        beyond the bins keep their share of probability (the density then integrates to the
        fraction inside). Must be >= the count inside.
    n_batches : int, optional
        If given (B >= 2), the standard error is the batch-means one, valid for a correlated
        sequence; otherwise it is binomial, valid for independent values only.

    Returns
    -------
    Density
        ``density_i = c_i / (n w_i)`` with c_i the count in bin i of width w_i and n the
        count inside all bins (values outside are ignored, as ``numpy.histogram`` does) or
        `total`. Binomial: ``stderr_i = sqrt(p_i (1 - p_i) / n) / w_i`` with ``p_i = c_i / n``.
        Batch means: see Notes. ``beyond`` is the fraction of the n values above the last
        edge. With no value in the bins the density and its error are NaN.

    Notes
    -----
    The binomial error assumes independent samples. Successive impacts are correlated, so for
    them it is a lower bound. With `n_batches` = B the sequence is cut into B contiguous
    batches of ``N // B`` values (the first ``N mod B`` dropped, as in `batch_means`); each
    batch gives a density normalised by its own length (values beyond the bins keep their
    share), and ``stderr_i = std_b(density_bi, ddof=1) / sqrt(B)``, the batch-means error of
    the per-bin mean (NaN when N < B). The Student-t factor of a confidence band on it is
    ``t_quantile(B)``, as for `BatchMeans.interval`.
    """
    values = np.asarray(values, dtype=float)
    counts, edges = np.histogram(values, bins=bins, range=range)
    widths = np.diff(edges)
    centres = 0.5 * (edges[:-1] + edges[1:])
    n = int(counts.sum())
    if total is not None:
        if total < n:
            raise ValueError(f"total must be >= the count inside the bins ({n}), got {total!r}")
        n = int(total)
    if n_batches is not None:
        n_batches = _checks.integer("n_batches", n_batches, low=2)
    if n == 0:
        nan = np.full(counts.shape, np.nan)
        return Density(centres, nan, nan.copy(), 0, np.nan)
    p = counts / n
    beyond = float(np.count_nonzero(values > edges[-1]) / n)
    if n_batches is None:
        stderr = np.sqrt(p * (1.0 - p) / n) / widths
    else:
        stderr = _batch_density_stderr(values, edges, int(n_batches))
    return Density(centres, p / widths, stderr, n, beyond)


def _batch_density_stderr(values, edges, n_batches):
    """Batch-means standard error of a histogram density (see `density`, Notes)."""
    size = values.size // n_batches
    if size == 0:
        return np.full(edges.size - 1, np.nan)
    batches = values[values.size - size * n_batches:].reshape(n_batches, size)
    counts = np.stack([np.histogram(batch, bins=edges)[0] for batch in batches])
    per_batch = counts / (size * np.diff(edges))
    return per_batch.std(axis=0, ddof=1) / np.sqrt(n_batches)


def t_quantile(n_batches, level: float = 0.95):
    """Student-t factor of a two-sided batch-means interval: ``t_{(1 + level)/2, B - 1}``.

    Parameters
    ----------
    n_batches : int or array_like of int
        Number of batches B; the quantile has B - 1 degrees of freedom.
    level : float, optional
        Confidence level, 0 < level < 1 (default 0.95).

    Returns
    -------
    float or ndarray
        The factor (2.093 for B = 20 at 95 %); NaN where B < 2.
    """
    # stdtrit is what scipy.stats.t.ppf computes (t._ppf), without the 1 s import of
    # scipy.stats in every figure job that draws a confidence band
    from scipy.special import stdtrit

    _checks.real("level", level, low=0.0, high=1.0, low_open=True, high_open=True)
    b = np.asarray(n_batches, dtype=float)
    q = np.where(b >= 2, stdtrit(np.maximum(b - 1.0, 1.0), 0.5 + 0.5 * level), np.nan)
    return float(q) if q.ndim == 0 else q


class BatchMeans(NamedTuple):
    """Mean of a correlated sequence with its batch-means standard error."""

    mean: float       #: mean of the values used (all batches)
    stderr: float     #: standard error of `mean`; NaN when fewer values than batches
    n_batches: int    #: batches used (0 when the sequence was too short)
    lag1: float       #: lag-1 autocorrelation of the batch means (should be near 0)

    def interval(self, level: float = 0.95) -> tuple[float, float]:
        """Two-sided Student-t confidence interval for the mean (n_batches - 1 dof)."""
        if self.n_batches < 2:
            return (np.nan, np.nan)
        half = t_quantile(self.n_batches, level) * self.stderr
        return (self.mean - half, self.mean + half)


def batch_means(x, n_batches: int = DEFAULT_N_BATCHES) -> BatchMeans:
    """Mean and standard error of a stationary but correlated sequence by batch means.

    Parameters
    ----------
    x : array_like of float, shape (n,)
        The sequence in time order (e.g. velocities after successive impacts).
    n_batches : int, optional
        Number B of contiguous batches of equal length ``n // B`` (>= 2; default 20). The
        first ``n mod B`` values are dropped (they are the earliest, closest to the transient).

    Returns
    -------
    BatchMeans
        ``mean`` of the values used, ``stderr = std(batch means, ddof=1) / sqrt(B)``, B, and the
        lag-1 autocorrelation of the batch means. If ``n < B`` the stderr is NaN and B = 0.

    Notes
    -----
    Successive impacts are strongly correlated (an impact's velocity sets the next flight),
    so ``std(x) / sqrt(n)`` understates the error by the factor ``sqrt(2 tau_int)``. Means
    of long contiguous batches are nearly independent and normal once the batch length is
    much longer than the correlation length, so their spread gives an honest error. With
    B >= 20 the t-interval (`BatchMeans.interval`) is close to the normal one; a lag-1
    correlation of the batch means clearly above ~2/sqrt(B) says the batches are too short.
    """
    x = np.asarray(x, dtype=float)
    n_batches = _checks.integer("n_batches", n_batches, low=2)
    if x.ndim != 1:
        raise ValueError(f"x must be one-dimensional, got shape {x.shape}")
    n_batches = int(n_batches)
    if x.size < n_batches:
        mean = float(x.mean()) if x.size else np.nan
        return BatchMeans(mean, np.nan, 0, np.nan)
    size = x.size // n_batches
    means = x[x.size - size * n_batches:].reshape(n_batches, size).mean(axis=1)
    d = means - means.mean()
    denom = np.dot(d, d)
    lag1 = float(np.dot(d[:-1], d[1:]) / denom) if denom > 0 else np.nan
    return BatchMeans(float(means.mean()), float(means.std(ddof=1) / np.sqrt(n_batches)),
                      n_batches, lag1)
