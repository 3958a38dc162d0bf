"""Where a spectrum's power lies: its centroid over a band (the paper's section 5, finding 5:
the response's power "moves to lower frequency as delta decreases").

Under ``amplitude sin(beta_f tau) + r(tau)`` the response's PSD holds two things: lines at
k beta_f (the periodic part of the motion, whose power follows the play) and the broadband
response to r(tau), the part the paper's Fig. 12 shows moving. :func:`broadband` takes the
lines out and measures them apart; :func:`shift` reads the broadband centroid and peak of
each play with an interval from the spread of the dataset's batch spectra (``S_a_batch``),
and the centroid's change between two plays under each of the measure's reasonable choices
(`LINE_BINS_CHOICES` x `BAND_CHOICES` x `FILL_CHOICES`).

A module of its own, not in `vibroimpact.stats.spectra`: only the figures and the reports
read it, and the simulation jobs that reach `spectra` keep their code digests.
"""
from dataclasses import dataclass
import itertools

import numpy as np

__all__ = ["BAND_CHOICES", "CENTROID_BAND", "FILL_CHOICES", "LINE_BINS", "LINE_BINS_CHOICES",
           "Shift", "batch_counts", "broadband", "line_mask", "shift", "spectral_centroid"]

#: Upper end of the band over which a response's centroid is taken (`spectral_centroid`): the
#: resonance and the forcing frequencies of the paper's section 5, not the round-off tail.
CENTROID_BAND = 3.0

#: Half-width, in bins of the Welch grid, of each line at k beta_f taken out of the broadband
#: response (around the bin nearest k beta_f). The estimator's Hann window has a main lobe of
#: +-2 bins; a line half a bin off its nearest bin (the worst case) leaves 5.1e-4 of its
#: power beyond +-2 bins, 7.0e-5 beyond +-3, 6.1e-6 beyond +-5 and 6.4e-7 beyond +-8
#: (tests/test_centroid.py measures them): at +-5 the study's strongest line (power 1.9)
#: leaks 1.2e-5 into a broadband that carries ~0.1-0.3.
LINE_BINS = 5
#: The half-widths (bins) a verdict on the broadband shift must hold under: the main lobe and
#: a bin (3), `LINE_BINS`, and wider (8).
LINE_BINS_CHOICES = (3, 5, 8)
#: The upper ends of the band a verdict must hold under: the resonance and beta_f with their
#: first harmonic (2), `CENTROID_BAND`, and wider (4).
BAND_CHOICES = (2.0, 3.0, 4.0)
#: What stands in a line's bins once it is taken out: "bridge" (default), the straight line
#: between the neighbouring clean bins, the broadband under the line; "drop", nothing (the
#: bins leave the sums, and the broadband under the line with them: ~10 % of the broadband's
#: power near beta_f at the smallest plays, which lowers the centroid there).
FILL_CHOICES = ("bridge", "drop")
#: The clean bins on each side of a line from whose mean the broadband under it is
#: interpolated (linearly, across the removed bins).
_SIDE_BINS = 3


def spectral_centroid(beta, S, band: float = CENTROID_BAND) -> float:
    """Mean frequency of a PSD over ``0 < beta <= band``: ``sum(beta S) / sum(S)``.

    Parameters
    ----------
    beta, S : array_like
        PSD on an evenly spaced grid beta >= 0 (`vibroimpact.stats.spectra.welch_psd`).
    band : float
        Upper end of the frequencies taken.

    Returns
    -------
    float
        Where the power of ``S`` lies on average in the band; NaN when ``S`` has no power
        there. With the lines at k beta_f in ``S`` this follows their strength; the paper's
        "moves to lower frequency" is read on the broadband part (:func:`broadband`).
    """
    beta = np.asarray(beta, dtype=float)
    S = np.asarray(S, dtype=float)
    inside = (beta > 0) & (beta <= band)
    total = float(S[inside].sum())
    return float((beta[inside] * S[inside]).sum() / total) if total > 0 else float("nan")


def line_mask(beta, beta_f, band=CENTROID_BAND, halfwidth=LINE_BINS):
    """The bins of the lines at ``k beta_f`` (k = 1, 2, ... up to ``band`` and the bins
    beyond it that a line's half-width reaches): ``halfwidth`` bins either side of the bin
    nearest each. Returns ``(mask, centres)``: a boolean array over ``beta`` and the index
    of each line's nearest bin."""
    beta = np.asarray(beta, dtype=float)
    step = beta[1] - beta[0]
    if not (np.isfinite(beta_f) and beta_f > 0):
        raise ValueError(f"beta_f must be > 0, got {beta_f!r}")
    halfwidth = int(halfwidth)
    if halfwidth < 0:
        raise ValueError(f"halfwidth must be >= 0 bins, got {halfwidth}")
    k_max = int(np.floor((band + halfwidth * step) / beta_f))
    centres = [int(np.rint((k * beta_f - beta[0]) / step)) for k in range(1, k_max + 1)]
    centres = [c for c in centres if c < beta.size]
    mask = np.zeros(beta.size, dtype=bool)
    for c in centres:
        mask[max(c - halfwidth, 0):c + halfwidth + 1] = True
    return mask, centres


def broadband(beta, S, beta_f, band=CENTROID_BAND, halfwidth=LINE_BINS, fill="bridge"):
    """A response PSD without its lines at k beta_f, and each line's power.

    The bins of each line (:func:`line_mask`) are replaced by the straight line between the
    means of the `_SIDE_BINS` clean bins on either side (outside every line); a line's power
    is what it adds over that, ``(1/pi) sum (S - S_broadband) dbeta`` over its bins (eq. 9's
    convention: ``A^2 / 2`` for ``A sin(beta_f tau)``, as `vibroimpact.stats.line_power`).
    With ``fill="drop"`` the line's bins are set to 0 in the returned PSD instead (they leave
    a centroid's sums); the powers are the same.

    Parameters
    ----------
    beta : array_like, shape (n,)
        Evenly spaced grid, beta >= 0.
    S : array_like, shape (..., n)
        PSDs on it (e.g. one per batch).
    beta_f : float
        The forcing frequency.
    band, halfwidth : float, int
        The lines taken out: up to ``band``; half-width in bins.
    fill : {"bridge", "drop"}
        What stands in a line's bins (`FILL_CHOICES`).

    Returns
    -------
    S_broadband : ndarray, shape of ``S``
    powers : ndarray, shape (..., n_lines)
        The power of the line at k beta_f, k = 1 .. n_lines.
    """
    if fill not in FILL_CHOICES:
        raise ValueError(f"fill must be one of {FILL_CHOICES}, got {fill!r}")
    beta = np.asarray(beta, dtype=float)
    S = np.asarray(S, dtype=float)
    out = S.copy()
    mask, centres = line_mask(beta, beta_f, band, halfwidth)
    step = beta[1] - beta[0]
    clean = np.flatnonzero(~mask)
    powers = []
    for c in centres:
        lo, hi = max(c - halfwidth, 0), min(c + halfwidth, beta.size - 1)
        left = clean[clean < lo][-_SIDE_BINS:]
        right = clean[clean > hi][:_SIDE_BINS]
        sides = [s for s in (left, right) if s.size]
        x = np.array([beta[s].mean() for s in sides])
        y = np.stack([S[..., s].mean(-1) for s in sides], axis=-1)
        span = np.arange(lo, hi + 1)
        if len(sides) == 1:
            under = np.repeat(y, span.size, axis=-1)
        else:
            under = y[..., :1] + (y[..., 1:] - y[..., :1]) * (beta[span] - x[0]) / (x[1] - x[0])
        out[..., span] = under if fill == "bridge" else 0.0
        powers.append((S[..., span] - under).sum(-1) * step / np.pi)
    return out, np.stack(powers, axis=-1) if powers else np.zeros(S.shape[:-1] + (0,))


def _jackknife(values, full, level):
    """``(low, high)``: ``full`` -+ t sd over the leave-one-batch-out ``values`` (last axis),
    the delete-one jackknife's standard error, with Student's t at ``level`` (B - 1 degrees
    of freedom)."""
    from scipy import stats as sps

    b = values.shape[-1]
    se = np.sqrt((b - 1) / b * ((values - values.mean(-1, keepdims=True)) ** 2).sum(-1))
    t = sps.t.ppf(0.5 + level / 2, b - 1)
    return full - t * se, full + t * se


def _leave_one_out(S_batch, counts):
    """The whole estimate without each batch in turn: shape (..., B, n) from (..., B, n),
    the batches weighted by their segment counts (as they make the whole estimate)."""
    w = counts[:, None].astype(float)
    total = (w * S_batch).sum(-2, keepdims=True)
    return (total - w * S_batch) / (counts.sum() - w)


def batch_counts(n_segments, n_batches):
    """The Welch segments in each batch (`vibroimpact.stats.WelchAccumulator`'s
    ``batches``: segment s is in batch ``s * n_batches // n_segments``)."""
    return np.bincount(np.arange(int(n_segments)) * int(n_batches) // int(n_segments),
                       minlength=int(n_batches))


def _centroids(beta, S, band):
    inside = (beta > 0) & (beta <= band)
    total = S[..., inside].sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return (beta[inside] * S[..., inside]).sum(-1) / total


def _peak(beta, S, inside, halfwidth):
    """Where ``S`` (..., n), smoothed by a running mean over +-``halfwidth`` bins, is largest
    within ``inside``."""
    kernel = np.ones(2 * halfwidth + 1) / (2 * halfwidth + 1)
    smooth = np.apply_along_axis(np.convolve, -1, S, kernel, mode="same")
    return beta[inside][np.argmax(smooth[..., inside], axis=-1)]


@dataclass(frozen=True)
class Shift:
    """The response's centroid and broadband peak at each play of one 1/beta_f row, and the
    broadband centroid's change between the largest and the smallest play under each choice.

    Attributes
    ----------
    delta : ndarray
        The plays, increasing.
    centroid_lines : ndarray
        The centroid of the whole response (lines included), beta <= ``band``.
    centroid, centroid_low, centroid_high : ndarray
        The broadband centroid (lines removed, ``halfwidth`` bins) and its interval; NaN
        without batch spectra.
    peak, peak_low, peak_high : ndarray
        Where the broadband response, smoothed over +-``halfwidth`` bins, peaks in
        ``0 < beta <= band``, and its interval (NaN without batches; clipped to the band):
        t sd / sqrt(B) of the peaks of the B batches' own broadband spectra, smoothed alike
        (a maximum is no smooth statistic, which the jackknife needs).
    lines : ndarray, shape (n_delta, n_lines)
        The power of the line at k beta_f.
    change : dict
        ``{(halfwidth, band, fill): (difference, low, high)}``: the broadband centroid at
        the smallest play less that at the largest, with its jackknife interval (the same
        batches at both plays: one record), for every choice in `LINE_BINS_CHOICES` x
        `BAND_CHOICES` x `FILL_CHOICES`; NaN bounds without batches.
    ends : dict
        ``{(halfwidth, band, fill): (at the largest play, at the smallest)}``: the broadband
        centroids whose difference ``change`` gives.
    halfwidth, band, level, n_batches : int, float, float, int
        The main choice, the interval's level and the batches (0: none).
    """

    delta: np.ndarray
    centroid_lines: np.ndarray
    centroid: np.ndarray
    centroid_low: np.ndarray
    centroid_high: np.ndarray
    peak: np.ndarray
    peak_low: np.ndarray
    peak_high: np.ndarray
    lines: np.ndarray
    change: dict
    ends: dict
    halfwidth: int
    band: float
    level: float
    n_batches: int

    def reading(self):
        """``"falls"`` when the broadband centroid's change from the largest play to the
        smallest has its interval below 0 under every choice, ``"rises"`` when above 0 under
        every choice, else ``"unresolved"`` (the choices disagree, or an interval holds 0,
        or there are no batches)."""
        signs = {("falls" if high < 0 else "rises" if low > 0 else "unresolved")
                 for _, low, high in self.change.values()}
        return signs.pop() if len(signs) == 1 else "unresolved"


def shift(spectra_row, beta_f, band=CENTROID_BAND, halfwidth=LINE_BINS, level=0.95):
    """The response's centroid (with and without its lines) and broadband peak, per play, of
    one 1/beta_f row of a spectra dataset (``S_a``, and ``S_a_batch`` with ``n_segments`` for
    the intervals); see :class:`Shift`.

    The intervals are the delete-one-batch jackknife's (each batch a consecutive stretch of
    the record; the statistic recomputed on the whole estimate less one batch) with Student's
    t at ``level``: the batches' spread measures the record's sampling error whatever the
    response's statistics (impacts make it non-Gaussian), and a ratio such as the centroid
    is what the jackknife suits.
    """
    row = spectra_row.sortby("delta")
    beta = np.asarray(row.beta, dtype=float)
    S = np.asarray(row.S_a, dtype=float)
    broad, lines = broadband(beta, S, beta_f, band, halfwidth)
    inside = (beta > 0) & (beta <= band)
    peak = _peak(beta, broad, inside, halfwidth)
    n_delta = S.shape[0]
    nan = np.full(n_delta, np.nan)
    cl, ch, pl, ph = nan.copy(), nan.copy(), nan.copy(), nan.copy()
    change, ends = {}, {}
    has_batches = "S_a_batch" in row and row.sizes.get("batch", 0) >= 2
    if has_batches:
        n_batches = row.sizes["batch"]
        counts = batch_counts(int(row.n_segments.values.ravel()[0]), n_batches)
        loo = _leave_one_out(np.asarray(row.S_a_batch, dtype=float), counts)  # (delta, B, n)
    for h, top, fill in itertools.product(LINE_BINS_CHOICES, BAND_CHOICES, FILL_CHOICES):
        whole = _centroids(beta, broadband(beta, S, beta_f, top, h, fill)[0], top)
        diff = float(whole[0] - whole[-1])
        key = (h, float(top), fill)
        ends[key] = (float(whole[-1]), float(whole[0]))
        if has_batches:
            c = _centroids(beta, broadband(beta, loo, beta_f, top, h, fill)[0], top)
            low, high = _jackknife(c[0] - c[-1], diff, level)
            change[key] = (diff, float(low), float(high))
        else:
            change[key] = (diff, float("nan"), float("nan"))
    if has_batches:
        c = _centroids(beta, broadband(beta, loo, beta_f, band, halfwidth)[0], band)
        cl, ch = _jackknife(c, _centroids(beta, broad, band), level)
        # a maximum is no smooth statistic (the jackknife's leave-one-out peaks mostly share
        # one bin): the batch means' error instead, from the peaks of the batches' own
        # broadband spectra, each smoothed over +-halfwidth bins
        own = broadband(beta, np.asarray(row.S_a_batch, dtype=float), beta_f, band,
                        halfwidth)[0]
        peaks = _peak(beta, own, inside, halfwidth)
        from scipy import stats as sps

        half = (sps.t.ppf(0.5 + level / 2, n_batches - 1) * peaks.std(-1, ddof=1)
                / np.sqrt(n_batches))
        pl = np.maximum(peak - half, beta[inside][0])
        ph = np.minimum(peak + half, beta[inside][-1])
    return Shift(delta=np.asarray(row.delta, dtype=float),
                 centroid_lines=_centroids(beta, S, band),
                 centroid=_centroids(beta, broad, band), centroid_low=cl, centroid_high=ch,
                 peak=peak, peak_low=pl, peak_high=ph, lines=lines, change=change, ends=ends,
                 halfwidth=int(halfwidth), band=float(band), level=float(level),
                 n_batches=int(row.sizes["batch"]) if has_batches else 0)
