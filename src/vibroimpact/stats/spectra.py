"""Power spectral densities in the paper's convention (eqs. 8, 9).

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

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from vibroimpact import _checks

__all__ = ["PSD_DETREND", "WelchAccumulator", "welch_psd", "onesided_to_angular", "line_power",
           "variance_from_psd", "linear_psd_response"]

#: Detrending of every PSD estimate in the package (input force and response alike): the mean
#: of the whole record is removed, nothing per segment, so S is the spectrum of the fluctuation
#: about the mean. The response a(tau) of a mass against a wall has a non-zero mean that would
#: otherwise fill the beta = 0 bin and leak into its neighbours; per-segment detrending
#: ("constant", scipy's default) would instead bias the lowest bins of every spectrum low
#: (it removes the power of all variations slower than a segment).
PSD_DETREND = "mean"
_DETRENDS = ("mean", "constant", "linear", False)

# Segments processed per FFT batch: bounds the memory of one feed() to ~_BATCH * nperseg floats.
_BATCH = 256

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
    detrend : {'mean', 'constant', 'linear', False}, optional
        ``'mean'`` (default, `PSD_DETREND`): the mean of everything fed is removed, exactly
        (the estimate equals scipy's with ``detrend=False`` on ``x - mean(x)``). The others
        are per-segment, as in ``scipy.signal.welch``: ``'constant'`` removes
        each segment's mean, so the PSD is that of the fluctuation about the mean.
    batches : (int, int), optional
        ``(n_batches, n_segments)``: the signal will hold ``n_segments`` complete segments,
        and segment ``s`` (counted from 0) is also averaged into batch
        ``s * n_batches // n_segments`` (consecutive stretches of the record, their sizes
        differing by at most one segment). `result_batches` then gives one estimate per
        batch, whose spread is the estimate's sampling error (batch means). ``result`` is
        the same with or without batches, bit for bit.

    Notes
    -----
    Segments start at multiples of ``step = nperseg - nperseg // 2``; the samples after the
    last complete segment are carried to the next `feed`, so chunk boundaries do not matter.
    Trailing samples that never fill a segment are dropped, exactly as scipy does.

    The returned S is the paper's eq. (9) two-sided angular density on beta >= 0; see the
    module docstring for its relation to scipy's one-sided per-Hz density. Relative standard
    deviation of each bin (0 < beta < Nyquist) is about ``1 / sqrt(n_effective)``.
    """

    def __init__(self, dt: float, nperseg: int, detrend: str | bool = PSD_DETREND,
                 batches: tuple[int, int] | None = None):
        from scipy import signal   # here, not at import: a figure job never estimates a PSD

        dt = _checks.real("dt", dt, low=0.0, low_open=True)
        nperseg = _checks.integer("nperseg", nperseg, low=2)
        if detrend not in _DETRENDS:
            raise ValueError(f"detrend must be one of {_DETRENDS}, got {detrend!r}")
        self.dt = dt
        self.nperseg = int(nperseg)
        self.noverlap = self.nperseg // 2
        self.step = self.nperseg - self.noverlap
        self.detrend = detrend
        self.window = signal.get_window("hann", self.nperseg)
        self._win_energy = float(np.sum(self.window**2))
        self._sum_power = np.zeros(self.nperseg // 2 + 1)
        # detrend "mean": sum of the segments' windowed spectra and of all samples, from which
        # the spectrum of (x - mean) follows exactly once the mean is known (see `result`)
        self._sum_spectrum = np.zeros(self.nperseg // 2 + 1, dtype=complex)
        self._sum_x = 0.0
        self._leftover = np.empty(0)
        self._n_segments = 0
        self._n_samples = 0
        self._batches = None
        if batches is not None:
            n_segments = _checks.integer("batches[1] (n_segments)", batches[1], low=1)
            n_batches = _checks.integer("batches[0] (n_batches)", batches[0], low=1,
                                        high=n_segments)
            self._batches = (n_batches, n_segments)
            self._batch_power = np.zeros((n_batches, self.nperseg // 2 + 1))
            self._batch_spectrum = np.zeros((n_batches, self.nperseg // 2 + 1), dtype=complex)

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
        self._sum_x += float(chunk.sum())
        buf = np.concatenate([self._leftover, chunk])
        if buf.size < self.nperseg:
            self._leftover = buf
            return self
        n_seg = (buf.size - self.nperseg) // self.step + 1
        segments = sliding_window_view(buf, self.nperseg)[::self.step][:n_seg]
        if self._batches is not None and self._n_segments + n_seg > self._batches[1]:
            raise ValueError(f"more segments than the {self._batches[1]} the batches were "
                             f"set for: {self._n_segments + n_seg}")
        for start in range(0, n_seg, _BATCH):
            self._sum_power += self._periodogram_sum(segments[start:start + _BATCH],
                                                     self._n_segments + start)
        self._n_segments += n_seg
        self._leftover = buf[n_seg * self.step:].copy()
        return self

    def _periodogram_sum(self, segments: np.ndarray, first: int) -> np.ndarray:
        """The summed periodograms of ``segments``, the first of which is segment ``first``
        of the record (its batches, when asked for, take theirs)."""
        if self.detrend in ("constant", "linear"):
            from scipy import signal

            segments = signal.detrend(segments, type=self.detrend, axis=-1)
        spectrum = np.fft.rfft(segments * self.window, axis=-1)
        if self.detrend == "mean":
            self._sum_spectrum += spectrum.sum(axis=0)
        power = spectrum.real**2 + spectrum.imag**2
        if self._batches is not None:
            n_batches, n_segments = self._batches
            batch = (first + np.arange(len(segments))) * n_batches // n_segments
            np.add.at(self._batch_power, batch, power)
            if self.detrend == "mean":
                np.add.at(self._batch_spectrum, batch, spectrum)
        return np.sum(power, axis=0)

    def _power(self, sum_power=None, sum_spectrum=None, n_segments=None) -> np.ndarray:
        """Summed periodograms (of every segment, or those given); for "mean", those of
        ``x - mean(x)`` (mean of all samples fed):
        ``sum_s |X_s - m W|^2 = sum_s |X_s|^2 - 2 m Re(conj(W) sum_s X_s) + K m^2 |W|^2``."""
        if sum_power is None:
            sum_power, sum_spectrum = self._sum_power, self._sum_spectrum
            n_segments = self._n_segments
        if self.detrend != "mean":
            return sum_power
        m = self._sum_x / self._n_samples
        w = np.fft.rfft(self.window)
        cross = np.real(np.conj(w) * sum_spectrum)
        power = sum_power - 2.0 * m * cross + n_segments * m * m * np.abs(w) ** 2
        return np.maximum(power, 0.0)

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
        S = self._power() / self._n_segments * (self.dt / self._win_energy)
        return beta, S

    def result_batches(self) -> np.ndarray:
        """The estimate of each batch (``batches``), as `result`'s S: shape
        ``(n_batches, nperseg // 2 + 1)``. With detrend "mean" every batch has the mean of
        the whole record removed, so the batches' average weighted by their segment counts
        is `result`'s S (to round-off).

        Raises
        ------
        ValueError
            Without ``batches``, or when fewer segments were fed than they were set for.
        """
        if self._batches is None:
            raise ValueError("no batches: give batches=(n_batches, n_segments)")
        n_batches, n_segments = self._batches
        if self._n_segments != n_segments:
            raise ValueError(f"{self._n_segments} segments fed, the batches were set for "
                             f"{n_segments}")
        counts = np.bincount(np.arange(n_segments) * n_batches // n_segments,
                             minlength=n_batches)
        return np.stack([self._power(self._batch_power[b], self._batch_spectrum[b], counts[b])
                         / counts[b] for b in range(n_batches)]) * (self.dt / self._win_energy)

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


def onesided_to_angular(f, P, nperseg: int):
    """scipy's one-sided per-Hz density ``P(f)`` as the paper's two-sided angular ``S(beta)``.

    The one place the convention is converted (module docstring): ``beta = 2 pi f`` and
    ``S = P / 2``, except at ``f = 0`` and, for even ``nperseg``, at Nyquist, which
    ``scipy.signal.welch`` does not double.

    Parameters
    ----------
    f, P : ndarray, shape (nperseg // 2 + 1,)
        Frequencies (cycles per unit tau) and density, as ``scipy.signal.welch`` returns them
        with ``return_onesided=True, scaling="density"``.
    nperseg : int
        Segment length used.

    Returns
    -------
    beta, S : ndarray
    """
    S = np.asarray(P, dtype=float) / 2.0
    S[0] = P[0]
    if nperseg % 2 == 0:
        S[-1] = P[-1]
    return 2.0 * np.pi * np.asarray(f, dtype=float), S


def welch_psd(x, dt: float, nperseg: int, detrend: str | bool = PSD_DETREND):
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
    from scipy import integrate

    return float(integrate.trapezoid(np.asarray(S, float), np.asarray(beta, float)) / np.pi)


#: A spectral line's power is summed over this many bins either side of it: Welch's Hann
#: window puts all but ~1e-4 of a line's power within +-3 bins of its frequency.
LINE_HALF_WIDTH = 4
#: The continuous background under a line: the median of the PSD between `LINE_HALF_WIDTH`
#: and this many bins from the line on both sides.
LINE_BACKGROUND = 24


def line_power(beta, S, beta_line: float) -> float:
    """Power of a spectral line at ``beta_line`` in a two-sided angular Welch PSD.

    Parameters
    ----------
    beta, S : array_like
        PSD on an evenly spaced grid beta >= 0 (`welch_psd`), eq. (9)'s convention.
    beta_line : float
        Frequency of the line (e.g. the forcing's beta_f).

    Returns
    -------
    float
        ``(1/pi) sum (S - background) dbeta`` over the `LINE_HALF_WIDTH` bins either side of
        the bin nearest ``beta_line``: the variance the line carries (``A^2 / 2`` for
        ``A sin(beta_f tau)``), independent of the frequency resolution, where the peak
        height of the line is not (it grows as 1 / dbeta). NaN when the line's bins do not
        fit in the grid (the background takes what fits of its bins on either side).
    """
    beta = np.asarray(beta, dtype=float)
    S = np.asarray(S, dtype=float)
    step = beta[1] - beta[0]
    k = int(np.rint((beta_line - beta[0]) / step))
    if k - LINE_HALF_WIDTH < 0 or k + LINE_HALF_WIDTH >= beta.size:
        return float("nan")
    near = S[k - LINE_HALF_WIDTH:k + LINE_HALF_WIDTH + 1]
    side = np.r_[S[max(k - LINE_BACKGROUND, 0):k - LINE_HALF_WIDTH],
                 S[k + LINE_HALF_WIDTH + 1:k + LINE_BACKGROUND + 1]]
    return float(np.sum(near - np.median(side)) * step / np.pi)


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
    ``H(beta) = 1 / (1 - beta^2 + 2 j zeta beta)`` (docs/model.md, section 7), so
    ``|H|^2 = 1 / ((1 - beta^2)^2 + (2 zeta beta)^2)``.
    """
    _checks.zeta(zeta)
    beta = np.asarray(beta, dtype=float)
    return np.asarray(S_f, dtype=float) / ((1.0 - beta**2) ** 2 + (2.0 * zeta * beta) ** 2)
