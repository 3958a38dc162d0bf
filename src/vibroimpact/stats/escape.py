"""Escape from an impact motion against the noise level: the Arrhenius fit of residence times.

Under weak noise a stable periodic motion is left by rare large fluctuations, and its mean
residence time grows like ``T ~ C exp(Delta / rms^2)`` (an activated escape, Freidlin-Wentzell;
the classification of the intervals (`classify_impact_intervals`) is also left by a Gaussian
tail event of the same form). `escape_fit` estimates the slope ``Delta`` of
``ln T`` against ``1 / rms^2`` from the residence times of several noise levels
(`residence_statistics`, one record each); `censored_bound` gives the lower bound of the
levels where the motion was never left in the record (no complete stretch to average).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from vibroimpact._limits import MIN_FIT_LEVELS
from vibroimpact.stats.events import t_quantile

__all__ = ["EscapeFit", "escape_fit", "censored_bound", "FIT_CONFIDENCE", "MIN_FIT_LEVELS"]

#: Confidence of the slope's interval (see `escape_fit`).
FIT_CONFIDENCE = 0.95


class EscapeFit(NamedTuple):
    """Straight line ``ln T = intercept + slope / rms^2`` fitted by `escape_fit`."""

    slope: float           #: Delta, in units of rms^2 (NaN: no fit)
    slope_stderr: float    #: its standard error (scaled by sqrt(chi2_red) when that is > 1)
    slope_lo: float        #: lower end of the 95 % interval
    slope_hi: float        #: upper end
    intercept: float       #: ln C, C in the units of T
    chi2_red: float        #: chi^2 / (points - 2) of the weighted fit (NaN: no fit)
    n_used: int            #: noise levels in the fit (0: no fit)
    used: np.ndarray       #: (K,) bool: the levels in the fit (none without a fit)


def escape_fit(inv_rms2, time, time_stderr, n_stretches, min_stretches=20, allowed=None):
    """Weighted least-squares line of ``ln(time)`` against ``1 / rms^2``.

    Parameters
    ----------
    inv_rms2 : array_like, shape (K,)
        ``1 / rms^2`` of each noise level.
    time, time_stderr : array_like, shape (K,)
        Mean residence time and its standard error at each level (any unit; NaN: none).
    n_stretches : array_like of int, shape (K,)
        Complete stretches behind each mean.
    min_stretches : int
        A level enters the fit only with at least this many complete stretches (the mean of
        a few stretches, and its error, are unreliable; the level's residence time is then
        mostly censored by the record's length).
    allowed : array_like of bool, shape (K,), optional
        Further selection (e.g. the weak-noise levels only); default all.

    Returns
    -------
    EscapeFit
        No fit (NaN slope, ``n_used = 0``, no level used) with fewer than `MIN_FIT_LEVELS`
        (3) usable levels at distinct noise levels.

    Notes
    -----
    ``y = ln T`` has the standard error ``s = stderr / T`` (first order); the weights are
    ``1 / s^2``. With K levels the line has ``nu = K - 2`` residual degrees of freedom, and
    ``chi2_red = chi^2 / nu`` says whether ``ln T`` is linear in ``1 / rms^2`` within the
    errors (about 1 when it is). A line needs ``nu >= 1``: two levels are refused (no
    residual, no scatter, no t quantile). Overdispersion: when the points scatter more than
    their errors allow (``chi2_red > 1``), the slope's standard error from the weighted
    normal equations is multiplied by ``sqrt(chi2_red)`` (the covariance by ``chi2_red``,
    the Particle Data Group's scale factor): a curved ``ln T`` shows as a wide interval
    rather than a falsely precise slope; with ``chi2_red <= 1`` it is left as the errors
    give it. The interval is ``slope +- q stderr`` with ``q`` Student's t quantile at
    ``nu = K - 2`` degrees of freedom (``scipy.stats.t.ppf(0.975, nu)``: 12.71 for K = 3,
    4.30 for K = 4), never the normal 1.96: the errors of the levels are themselves
    estimated from the spread of their stretches, and the line's adequacy from ``nu`` points.
    """
    x = np.asarray(inv_rms2, dtype=float)
    t = np.asarray(time, dtype=float)
    e = np.asarray(time_stderr, dtype=float)
    n = np.asarray(n_stretches)
    ok = np.ones(x.shape, dtype=bool) if allowed is None else np.asarray(allowed, dtype=bool)
    with np.errstate(invalid="ignore"):
        used = ok & (n >= int(min_stretches)) & np.isfinite(t) & (t > 0) & np.isfinite(e) & (e > 0)
    k = int(used.sum())
    if k < MIN_FIT_LEVELS or np.unique(x[used]).size < MIN_FIT_LEVELS:
        nan = float("nan")
        return EscapeFit(nan, nan, nan, nan, nan, nan, 0, np.zeros(x.shape, dtype=bool))
    y, w = np.log(t[used]), (t[used] / e[used]) ** 2
    a = np.stack([np.ones(k), x[used]], axis=1)
    cov = np.linalg.inv(a.T @ (w[:, None] * a))
    intercept, slope = cov @ (a.T @ (w * y))
    chi2 = float(np.sum(w * (y - intercept - slope * x[used]) ** 2))
    chi2_red = chi2 / (k - 2)
    se = float(np.sqrt(cov[1, 1] * max(1.0, chi2_red)))
    # t_quantile(B) has B - 1 degrees of freedom: K - 1 of them gives K - 2
    q = float(t_quantile(k - 1, FIT_CONFIDENCE))
    return EscapeFit(float(slope), se, float(slope - q * se), float(slope + q * se),
                     float(intercept), chi2_red, k, used)


def censored_bound(n_stretches, n_censored, censored_time, probability, min_share=0.5):
    """Lower bound of the residence time at the levels where a state was never left.

    Parameters
    ----------
    n_stretches, n_censored : array_like of int
        Complete stretches of the state, and stretches cut by the record's start or end.
    censored_time : array_like of float
        Total length of the cut stretches (the units of the result).
    probability : array_like of float
        Fraction of the record in the state.
    min_share : float
        The state must hold at least this fraction of the record (default a half): it held
        the record without a complete stretch, rather than being seen once before the motion
        settled (a short stretch cut by the record's start).

    Returns
    -------
    ndarray of float
        ``censored_time / n_censored`` where the state has no complete stretch, a cut one and
        at least ``min_share`` of the record: it was not left (or left once) in the run, its
        mean residence time is longer than the observed mean length of its cut stretches.
        NaN elsewhere (a mean exists, or the state was not held).
    """
    n = np.asarray(n_stretches)
    c = np.asarray(n_censored)
    time = np.asarray(censored_time, dtype=float)
    share = np.asarray(probability, dtype=float)
    shape = np.broadcast(n, c, time, share).shape
    n, c, time, share = (np.broadcast_to(v, shape) for v in (n, c, time, share))
    with np.errstate(invalid="ignore"):
        hit = (n == 0) & (c > 0) & (time > 0) & (share >= float(min_share))
    bound = np.full(shape, np.nan)
    bound[hit] = time[hit] / c[hit]
    return bound
