"""Response statistics: spectra, densities, means with error bars, impact-motion types.

Everything here is pure numpy/scipy on arrays: no file I/O, no simulation, no randomness.
The simulator (`vibroimpact.simulate`) produces the impact events and the sampled record
a(tau); this module turns them into the quantities the paper plots (Figs. 6-9, 12-15), and
holds the exact elastic-impact results used as test oracles.

Conventions (paper eqs. 8, 9)
-----------------------------
Autocorrelation ``phi(t) = lim (1/T) int f(tau) f(tau + t) dtau`` and two-sided angular power
spectral density ``S(beta) = int phi(t) exp(-j beta t) dt``, so that

    variance = phi(0) = (1/2pi) int_{-inf}^{inf} S(beta) dbeta = (1/pi) int_0^inf S(beta) dbeta.

With ``beta = 2 pi f``, ``(1/2pi) dbeta = df``, hence S(beta) equals the two-sided per-Hz
density G(f) at ``f = beta / 2pi``. scipy's one-sided density doubles G at every bin except
the zero frequency and (for even ``nperseg``) the Nyquist bin, so

    S(beta_k) = P_onesided(f_k) / 2   for 0 < f_k < f_Nyquist,
    S(beta_k) = P_onesided(f_k)       at f_k = 0 and f_k = f_Nyquist.

Directly from the samples: ``S(beta_k) = dt <|sum_n w_n x_n exp(-j beta_k n dt)|^2> / sum_n w_n^2``
(``<>`` = mean over Welch segments). A white sequence of variance s^2 at spacing dt has the
flat level ``S = s^2 dt`` on ``|beta| <= pi / dt``.
"""
from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy import integrate, signal, special
from scipy import stats as _sps

__all__ = [
    "DEFAULT_MOTION_WINDOW", "DEFAULT_N_BATCHES", "DEFAULT_MOTIONS",
    "WelchAccumulator", "welch_psd", "variance_from_psd", "linear_psd_response",
    "Density", "density", "impact_intervals", "velocity_after_impact", "interval_ratio",
    "BatchMeans", "batch_means",
    "classify_impact_intervals", "impact_motion_probabilities",
    "linear_response_std", "elastic_impact_rate", "rayleigh_pdf", "truncated_gaussian_pdf",
]

#: Half-width w of the window on r_j = z_j / z that assigns an interval to a motion type (fig15).
DEFAULT_MOTION_WINDOW = 0.1
#: Batches in a batch-means standard error; >= 20 keeps the t-quantile close to the normal one.
DEFAULT_N_BATCHES = 20
#: The impact motions mapped in fig15, as (m, n): m impacts per n forcing periods.
DEFAULT_MOTIONS = ((1, 1), (2, 1), (1, 2))

# Segments processed per FFT batch: bounds the memory of one feed() to ~_BATCH * nperseg floats.
_BATCH = 256


# --------------------------------------------------------------------------------------------
# Power spectral density
# --------------------------------------------------------------------------------------------

class WelchAccumulator:
    """Streaming Welch estimate of the two-sided angular PSD of a long sampled signal.

    Feed the signal chunk by chunk (e.g. the simulator's ``a`` grid, one chunk per
    `simulate_chunks` result); the estimate equals ``scipy.signal.welch`` applied to the
    concatenated signal (Hann window, 50 % overlap, mean averaging), to round-off.

    Parameters
    ----------
    dt : float
        Sample spacing of the signal, in units of tau (for the simulator's record:
        ``record_every * dt``).
    nperseg : int
        Segment length in samples (>= 2). The frequency resolution is
        ``dbeta = 2 pi / (nperseg dt)``.
    detrend : {'constant', 'linear', False}, optional
        Per-segment detrending, as in ``scipy.signal.welch``. Default ``'constant'`` removes
        each segment's mean, so the PSD is that of the fluctuation about the mean.

    Notes
    -----
    Segments start at multiples of ``step = nperseg - nperseg // 2``; the samples after the
    last complete segment are carried to the next `feed`, so chunk boundaries do not matter.
    Trailing samples that never fill a segment are dropped, exactly as scipy does.

    The returned S is the paper's eq. (9) two-sided angular density on beta >= 0; see the
    module docstring for its relation to scipy's one-sided per-Hz density. Relative standard
    deviation of each bin (0 < beta < Nyquist) is about ``1 / sqrt(n_effective)``.
    """

    def __init__(self, dt: float, nperseg: int, detrend: str | bool = "constant"):
        dt = float(dt)
        if not np.isfinite(dt) or dt <= 0.0:
            raise ValueError(f"dt must be a finite positive number, got {dt!r}")
        if int(nperseg) != nperseg or nperseg < 2:
            raise ValueError(f"nperseg must be an integer >= 2, got {nperseg!r}")
        if detrend not in ("constant", "linear", False):
            raise ValueError(f"detrend must be 'constant', 'linear' or False, got {detrend!r}")
        self.dt = dt
        self.nperseg = int(nperseg)
        self.noverlap = self.nperseg // 2
        self.step = self.nperseg - self.noverlap
        self.detrend = detrend
        self.window = signal.get_window("hann", self.nperseg)
        self._win_energy = float(np.sum(self.window**2))
        self._sum_power = np.zeros(self.nperseg // 2 + 1)
        self._leftover = np.empty(0)
        self._n_segments = 0
        self._n_samples = 0

    @property
    def n_segments(self) -> int:
        """Number of complete Welch segments averaged so far (K)."""
        return self._n_segments

    @property
    def n_samples(self) -> int:
        """Number of samples fed so far."""
        return self._n_samples

    @property
    def n_effective(self) -> float:
        """Equivalent number of independent segments, K_eff (Welch 1967, eq. for overlap).

        ``K_eff = K / (1 + 2 sum_{l=1}^{K-1} (1 - l/K) rho(l))`` with
        ``rho(l) = (sum_n w_n w_{n + l step})^2 / (sum_n w_n^2)^2``, the correlation of
        periodograms of overlapping segments of a white signal. The relative standard
        deviation of a PSD bin is ``1 / sqrt(K_eff)`` (Hann, 50 % overlap: K_eff ~ K / 1.06).
        """
        k = self._n_segments
        if k == 0:
            return 0.0
        w = self.window
        lags = np.arange(1, min(k, -(-self.nperseg // self.step)))
        rho = np.array([np.dot(w[l * self.step:], w[:self.nperseg - l * self.step])
                        for l in lags]) ** 2 / self._win_energy**2
        return k / (1.0 + 2.0 * np.sum((1.0 - lags / k) * rho))

    def feed(self, chunk) -> "WelchAccumulator":
        """Append the next stretch of the signal.

        Parameters
        ----------
        chunk : array_like of float, shape (n,)
            Consecutive samples, continuing the previous chunk without gap or overlap.

        Returns
        -------
        WelchAccumulator
            ``self``, so feeds can be chained.
        """
        chunk = np.asarray(chunk, dtype=float)
        if chunk.ndim != 1:
            raise ValueError(f"chunk must be one-dimensional, got shape {chunk.shape}")
        if not np.all(np.isfinite(chunk)):
            raise ValueError("chunk contains NaN or inf")
        self._n_samples += chunk.size
        buf = np.concatenate([self._leftover, chunk])
        if buf.size < self.nperseg:
            self._leftover = buf
            return self
        n_seg = (buf.size - self.nperseg) // self.step + 1
        segments = sliding_window_view(buf, self.nperseg)[::self.step][:n_seg]
        for start in range(0, n_seg, _BATCH):
            self._sum_power += self._periodogram_sum(segments[start:start + _BATCH])
        self._n_segments += n_seg
        self._leftover = buf[n_seg * self.step:].copy()
        return self

    def _periodogram_sum(self, segments: np.ndarray) -> np.ndarray:
        if self.detrend:
            segments = signal.detrend(segments, type=self.detrend, axis=-1)
        spectrum = np.fft.rfft(segments * self.window, axis=-1)
        return np.sum(spectrum.real**2 + spectrum.imag**2, axis=0)

    def _check_ready(self):
        if self._n_segments == 0:
            raise ValueError(f"no complete segment yet: {self._n_samples} samples fed, "
                             f"nperseg={self.nperseg}")

    def result(self) -> tuple[np.ndarray, np.ndarray]:
        """The paper's two-sided angular PSD on beta >= 0 (eq. 9).

        Returns
        -------
        beta : ndarray, shape (nperseg // 2 + 1,)
            Angular frequency (in units of the natural frequency), ``2 pi k / (nperseg dt)``.
        S : ndarray, same shape
            ``S(beta) = dt <|sum_n w_n x_n e^{-j beta n dt}|^2> / sum_n w_n^2``, so that
            ``variance = (1/pi) int_0^{pi/dt} S dbeta`` (see `variance_from_psd`).
        """
        self._check_ready()
        beta = 2.0 * np.pi * np.fft.rfftfreq(self.nperseg, d=self.dt)
        S = self._sum_power / self._n_segments * (self.dt / self._win_energy)
        return beta, S

    def onesided_density(self) -> tuple[np.ndarray, np.ndarray]:
        """scipy's convention: frequency f (cycles per unit tau) and one-sided density P(f).

        Equal to ``scipy.signal.welch(x, fs=1/dt, nperseg=nperseg, detrend=detrend)`` on the
        concatenated signal. ``P = 2 S`` except at f = 0 and (even nperseg) at Nyquist.
        """
        beta, S = self.result()
        P = 2.0 * S
        P[0] = S[0]
        if self.nperseg % 2 == 0:
            P[-1] = S[-1]
        return beta / (2.0 * np.pi), P


def welch_psd(x, dt: float, nperseg: int, detrend: str | bool = "constant"):
    """Two-sided angular PSD (paper eq. 9) of a whole record; see `WelchAccumulator`.

    Returns
    -------
    beta, S : ndarray
        As `WelchAccumulator.result`.
    n_effective : float
        Equivalent number of independent segments; relative std of S is 1/sqrt(n_effective).
    """
    acc = WelchAccumulator(dt, nperseg, detrend).feed(x)
    beta, S = acc.result()
    return beta, S, acc.n_effective


def variance_from_psd(beta, S) -> float:
    """Variance carried by a two-sided angular PSD given on beta >= 0.

    ``sigma^2 = (1/2pi) int_{-inf}^{inf} S dbeta = (1/pi) int_0^{beta_max} S dbeta``
    (trapezoid rule). On the Welch grid with even nperseg this is exactly scipy's
    ``sum(P) df`` (the end bins carry half weight on both sides).
    """
    return float(integrate.trapezoid(np.asarray(S, float), np.asarray(beta, float)) / np.pi)


def linear_psd_response(beta, S_f, zeta: float):
    """PSD of the wall-free linear response, ``S_x(beta) = |H(beta)|^2 S_f(beta)``.

    Parameters
    ----------
    beta : array_like of float
        Angular frequency ratio (beta = omega / omega_0).
    S_f : array_like of float or float
        Force PSD at `beta`, in the paper's eq. (9) convention.
    zeta : float
        Damping ratio, 0 < zeta < 1.

    Notes
    -----
    ``H(beta) = 1 / (1 - beta^2 + 2 j zeta beta)`` (MODEL.md, linear reference), so
    ``|H|^2 = 1 / ((1 - beta^2)^2 + (2 zeta beta)^2)``.
    """
    _check_zeta(zeta)
    beta = np.asarray(beta, dtype=float)
    return np.asarray(S_f, dtype=float) / ((1.0 - beta**2) ** 2 + (2.0 * zeta * beta) ** 2)


# --------------------------------------------------------------------------------------------
# Impact events, densities, means
# --------------------------------------------------------------------------------------------

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
    if not 0.0 <= eps <= 1.0:
        raise ValueError(f"eps must lie in [0, 1], got {eps!r}")
    return eps * np.asarray(u_minus, dtype=float)


def interval_ratio(intervals, beta: float) -> np.ndarray:
    """``r_j = z_j / z`` with the forcing period ``z = 2 pi / beta`` (Fig. 13)."""
    if not np.isfinite(beta) or beta <= 0.0:
        raise ValueError(f"beta must be a finite positive number, got {beta!r}")
    return np.asarray(intervals, dtype=float) * (beta / (2.0 * np.pi))


class Density(NamedTuple):
    """A histogram density estimate with per-bin standard errors."""

    centres: np.ndarray  #: bin centres, shape (nbins,)
    density: np.ndarray  #: probability density, integrates to 1 over the bins
    stderr: np.ndarray   #: standard error of `density` per bin (binomial)
    n: int               #: number of values the density is normalised by (inside the bins unless `total`)


def density(values, bins, range=None, total=None) -> Density:
    """Probability density of `values` by histogram, with binomial standard errors.

    Parameters
    ----------
    values : array_like of float
        Samples (e.g. velocities after impact, intervals, z_j / z).
    bins : int or array_like
        Passed to ``numpy.histogram``.
    range : (float, float), optional
        Passed to ``numpy.histogram``.
    total : int, optional
        Normalise by this many values instead of the count inside the bins, so that values
        beyond the bins keep their share of probability (the density then integrates to the
        fraction inside). Must be >= the count inside.

    Returns
    -------
    Density
        ``density_i = c_i / (n w_i)`` with c_i the count in bin i of width w_i and n the
        count inside all bins (values outside are ignored, as ``numpy.histogram`` does);
        ``stderr_i = sqrt(p_i (1 - p_i) / n) / w_i`` with ``p_i = c_i / n``. With no value in
        the bins the density and its error are NaN.

    Notes
    -----
    The binomial error assumes independent samples. Successive impacts are correlated, so it
    is a lower bound; for a mean use `batch_means`.
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
    if n == 0:
        nan = np.full(counts.shape, np.nan)
        return Density(centres, nan, nan.copy(), 0)
    p = counts / n
    return Density(centres, p / widths, np.sqrt(p * (1.0 - p) / n) / widths, n)


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
        half = _sps.t.ppf(0.5 + 0.5 * level, self.n_batches - 1) * self.stderr
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
    if int(n_batches) != n_batches or n_batches < 2:
        raise ValueError(f"n_batches must be an integer >= 2, got {n_batches!r}")
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


# --------------------------------------------------------------------------------------------
# Impact-motion types (fig15)
# --------------------------------------------------------------------------------------------

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
    An (m/n) motion has m impacts per n forcing periods (MODEL.md, section 4). A group of m
    consecutive intervals starting at j is of that type when

    - m = 1: ``|r_j - n| < w``;
    - m >= 2: every ``r_{j+i} < n - w`` and ``|r_j + ... + r_{j+m-1} - n| < w``

    which for (1/1), (1/2), (2/1) is the definition of FIGURES.md. Groups may overlap (three
    intervals of 0.5 hold two candidate (2/1) pairs), and an interval is counted at most once,
    so groups are taken greedily left to right: at the first unassigned interval j that starts
    some matching group, the first motion in `motions` that matches there claims its m
    intervals, and the scan resumes after them. For the default motions the candidates at one
    j are mutually exclusive (r_j near 1, near 2, or below 0.9), so the priority order only
    matters for user-supplied motions; the greedy pairing reads a (2/1) record in time order
    and pairs a run of short intervals (r1, r2), (r3, r4), ...
    """
    ratio = np.asarray(ratio, dtype=float)
    if not 0.0 < window <= 0.5:
        raise ValueError(f"window must lie in (0, 0.5], got {window!r}")
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
    pipeline's definition (FIGURES.md, "The probability of an impact motion").
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


# --------------------------------------------------------------------------------------------
# Exact results: linear response, elastic impacts under white noise
# --------------------------------------------------------------------------------------------

def _check_zeta(zeta):
    if not 0.0 < zeta < 1.0:
        raise ValueError(f"zeta must lie in (0, 1), got {zeta!r}")


def linear_response_std(S_f: float | Callable[[float], float], zeta: float) -> tuple[float, float]:
    """Standard deviations of the wall-free displacement and velocity, sigma_x and sigma_v.

    Parameters
    ----------
    S_f : float or callable
        Force PSD in the paper's convention (eq. 9). A number S0 means white noise,
        ``phi_f(t) = S0 delta(t)``; a callable ``S_f(beta)`` (even in beta) is integrated
        numerically over beta >= 0 with ``scipy.integrate.quad``.
    zeta : float
        Damping ratio, 0 < zeta < 1.

    Returns
    -------
    sigma_x, sigma_v : float

    Notes
    -----
    ``sigma_x^2 = (1/pi) int_0^inf |H|^2 S_f dbeta``,
    ``sigma_v^2 = (1/pi) int_0^inf beta^2 |H|^2 S_f dbeta``, with
    ``|H|^2 = 1 / ((1 - beta^2)^2 + (2 zeta beta)^2)``. For white noise,
    ``int_{-inf}^{inf} |H|^2 dbeta = int beta^2 |H|^2 dbeta = pi / (2 zeta)``, hence
    ``sigma_x^2 = sigma_v^2 = S0 / (4 zeta)``.
    """
    _check_zeta(zeta)
    if not callable(S_f):
        S0 = float(S_f)
        if not np.isfinite(S0) or S0 < 0.0:
            raise ValueError(f"S_f must be a non-negative number or a callable, got {S_f!r}")
        s = np.sqrt(S0 / (4.0 * zeta))
        return float(s), float(s)

    def response(b, power):
        return b**power * float(S_f(b)) / ((1.0 - b * b) ** 2 + (2.0 * zeta * b) ** 2)

    # The resonance peak (width ~ zeta at beta ~ 1) gets its own pieces so quad resolves it.
    edges = sorted({0.0, max(0.0, 1.0 - 5.0 * zeta), 1.0, 1.0 + 5.0 * zeta, 8.0})
    var = []
    for power in (0, 2):
        pieces = [integrate.quad(response, a, b, args=(power,), limit=200)[0]
                  for a, b in zip(edges, edges[1:])]
        tail = integrate.quad(response, edges[-1], np.inf, args=(power,), limit=200)[0]
        var.append((sum(pieces) + tail) / np.pi)
    return float(np.sqrt(var[0])), float(np.sqrt(var[1]))


def elastic_impact_rate(delta, sigma_x: float, sigma_v: float):
    """Mean impact rate for elastic impacts (eps = 1) under white noise, exact.

    Parameters
    ----------
    delta : float or array_like
        Play (wall position).
    sigma_x, sigma_v : float
        Wall-free response std's (`linear_response_std`).

    Returns
    -------
    float or ndarray
        ``nu(delta) = (1/2pi) (sigma_v/sigma_x) exp(-delta^2/2 sigma_x^2) / Phi(delta/sigma_x)``
        impacts per unit tau; the mean interval between impacts is ``1 / nu``.

    Notes
    -----
    With eps = 1 the reflection ``v -> -v`` preserves the stationary density of the wall-free
    oscillator, ``p(x, v) ~ exp(-x^2/2 sigma_x^2 - v^2/2 sigma_v^2)``, which is therefore the
    stationary density on ``x <= delta`` once renormalised (`truncated_gaussian_pdf`). The
    impact rate is the probability flux into the wall, ``int_0^inf v p(delta, v) dv``: Rice's
    up-crossing rate divided by ``Phi(delta / sigma_x)``. Computed with ``log_ndtr`` so it
    stays finite for large negative delta.
    """
    d = np.asarray(delta, dtype=float) / sigma_x
    rate = (sigma_v / sigma_x) / (2.0 * np.pi) * np.exp(-0.5 * d * d - special.log_ndtr(d))
    return rate if rate.ndim else float(rate)


def rayleigh_pdf(u, sigma_v: float):
    """Density of the approach velocity at impact for elastic impacts under white noise.

    ``p(u) = (u / sigma_v^2) exp(-u^2 / 2 sigma_v^2)`` for u >= 0, else 0: the flux-weighted
    velocity ``u p_v(u)`` at the wall, independent of delta. After impact with restitution eps
    the speed is ``eps u``.
    """
    u = np.asarray(u, dtype=float)
    p = np.where(u >= 0.0, u / sigma_v**2 * np.exp(-0.5 * (u / sigma_v) ** 2), 0.0)
    return p if p.ndim else float(p)


def truncated_gaussian_pdf(x, sigma_x: float, delta: float):
    """Stationary displacement density for elastic impacts under white noise.

    ``p(x) = phi(x / sigma_x) / (sigma_x Phi(delta / sigma_x))`` for ``x <= delta``, else 0:
    the wall-free Gaussian N(0, sigma_x^2) cut at the wall and renormalised. The velocity
    keeps its wall-free density N(0, sigma_v^2), independent of x.
    """
    x = np.asarray(x, dtype=float)
    z = x / sigma_x
    log_p = -0.5 * z * z - 0.5 * np.log(2.0 * np.pi) - np.log(sigma_x) - special.log_ndtr(
        delta / sigma_x)
    p = np.where(x <= delta, np.exp(log_p), 0.0)
    return p if p.ndim else float(p)
