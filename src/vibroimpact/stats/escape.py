"""Escape from an impact motion against the noise level: the Arrhenius fit of residence times.

Under weak noise a stable periodic motion is left by rare large fluctuations, and its mean
residence time grows like ``T ~ C exp(Delta / rms^2)`` (an activated escape, Freidlin-Wentzell;
the classification of the intervals (`classify_impact_intervals`) is also left by a Gaussian
tail event of the same form). `escape_fit` estimates the slope ``Delta`` of
``ln T`` against ``1 / rms^2`` from the residence times of several noise levels
(`residence_statistics`, one record each).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from vibroimpact.stats.events import t_quantile

__all__ = ["EscapeFit", "escape_fit", "FIT_CONFIDENCE"]

#: Confidence of the slope's interval (see `escape_fit`).
FIT_CONFIDENCE = 0.95


class EscapeFit(NamedTuple):
    """Straight line ``ln T = intercept + slope / rms^2`` fitted by `escape_fit`."""

    slope: float           #: Delta, in units of rms^2 (NaN: fewer than two points)
    slope_stderr: float    #: its standard error (scaled by sqrt(chi2_red) when that is > 1)
    slope_lo: float        #: lower end of the 95 % interval
    slope_hi: float        #: upper end
    intercept: float       #: ln C, C in the units of T
    chi2_red: float        #: chi^2 / (points - 2) of the weighted fit (NaN: two points)
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
        NaN slope, ``n_used = 0`` and no level used with fewer than two usable levels.

    Notes
    -----
    ``y = ln T`` has the standard error ``s = stderr / T`` (first order); the weights are
    ``1 / s^2``. The slope's standard error comes from the weighted normal equations and is
    multiplied by ``sqrt(chi2_red)`` when the points scatter more than their errors allow
    (``chi2_red > 1``, the Particle Data Group's scale factor: a curved ``ln T`` shows as a
    wide interval rather than a falsely precise slope). The interval is ``slope +- q
    stderr``: with the errors as given, ``q`` is the normal quantile (1.96); when the scatter
    sets the error (``chi2_red > 1``), it is estimated from the ``K - 2`` residual degrees of
    freedom of a few levels, and ``q`` is Student's t quantile with ``K - 2`` degrees of
    freedom (4.30 for K = 4). ``chi2_red`` itself says whether ``ln T`` is linear in
    ``1 / rms^2`` over the levels used: about 1 when it is.
    """
    x = np.asarray(inv_rms2, dtype=float)
    t = np.asarray(time, dtype=float)
    e = np.asarray(time_stderr, dtype=float)
    n = np.asarray(n_stretches)
    ok = np.ones(x.shape, dtype=bool) if allowed is None else np.asarray(allowed, dtype=bool)
    with np.errstate(invalid="ignore"):
        used = ok & (n >= int(min_stretches)) & np.isfinite(t) & (t > 0) & np.isfinite(e) & (e > 0)
    k = int(used.sum())
    if k < 2 or np.ptp(x[used]) == 0.0:
        nan = float("nan")
        return EscapeFit(nan, nan, nan, nan, nan, nan, 0, np.zeros(x.shape, dtype=bool))
    y, w = np.log(t[used]), (t[used] / e[used]) ** 2
    a = np.stack([np.ones(k), x[used]], axis=1)
    cov = np.linalg.inv(a.T @ (w[:, None] * a))
    intercept, slope = cov @ (a.T @ (w * y))
    chi2 = float(np.sum(w * (y - intercept - slope * x[used]) ** 2))
    chi2_red = chi2 / (k - 2) if k > 2 else float("nan")
    scale = max(1.0, chi2_red) if k > 2 else 1.0
    se = float(np.sqrt(cov[1, 1] * scale))
    # t_quantile(B) has B - 1 degrees of freedom: K - 1 of them gives K - 2
    q = float(t_quantile(k - 1, FIT_CONFIDENCE) if scale > 1.0
              else t_quantile(2**30, FIT_CONFIDENCE))
    return EscapeFit(float(slope), se, float(slope - q * se), float(slope + q * se),
                     float(intercept), chi2_red, k, used)
