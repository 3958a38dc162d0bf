"""The response's centroid with and without its lines (vibroimpact.stats.centroid).

Spectra here are Welch estimates (`WelchAccumulator`, with batches) of synthetic records:
a broadband part, filtered white noise through a resonance whose frequency the test sets, plus
a sinusoid at beta_f whose amplitude it sets, so the line is smeared by the estimator's own
window as in the study's spectra.
"""
import numpy as np
import pytest
import xarray as xr
from scipy import signal

from vibroimpact.stats import WelchAccumulator
from vibroimpact.stats.centroid import (
    BAND_CHOICES, FILL_CHOICES, LINE_BINS, LINE_BINS_CHOICES, broadband, line_mask, shift)

DT, NPERSEG, N_BATCHES = 0.1, 4096, 10   # the study's resolution: 0.0153
N_SEGMENTS = 60
N_SAMPLES = (N_SEGMENTS + 1) * NPERSEG // 2
BETA_F = 1 / 1.1


def record(resonance, line, seed, rms=0.3, zeta=0.1):
    """Broadband response of a resonance at ``resonance`` (a digital two-pole filter of
    white noise, damping ``zeta``) plus ``line * sin(beta_f tau)``."""
    rng = np.random.default_rng(seed)
    r = np.exp(-zeta * resonance * DT)
    a = [1.0, -2 * r * np.cos(resonance * DT), r * r]
    x = signal.lfilter([1.0], a, rng.standard_normal(N_SAMPLES + 2000))[2000:]
    x *= rms / x.std()
    tau = DT * np.arange(N_SAMPLES)
    return x + line * np.sin(BETA_F * tau + 0.3)


def welch(x):
    acc = WelchAccumulator(DT, NPERSEG, batches=(N_BATCHES, N_SEGMENTS)).feed(x)
    beta, S = acc.result()
    return beta, S, acc.result_batches()


def spectra_row(plays):
    """A spectra dataset's row (one 1/beta_f): ``plays`` is ``{delta: (resonance, line)}``,
    every play on its own noise (seeded by its rank)."""
    deltas = sorted(plays)
    est = [welch(record(*plays[d], seed=k)) for k, d in enumerate(deltas)]
    beta = est[0][0]
    return xr.Dataset(
        {"S_a": (("delta", "beta"), np.stack([e[1] for e in est])),
         "S_a_batch": (("delta", "batch", "beta"), np.stack([e[2] for e in est])),
         "n_segments": ("delta", np.full(len(deltas), N_SEGMENTS))},
        coords=dict(delta=deltas, beta=beta, inv_beta=1.1))


def test_hann_leaks_what_the_line_half_width_says():
    """The numbers `LINE_BINS` is justified by: a line half a bin off its nearest bin (the
    worst case) puts 5.1e-4 of its power beyond +-2 bins of it (the main lobe), 7.0e-5
    beyond +-3, 6.1e-6 beyond +-5, 6.4e-7 beyond +-8 (each bound 10 % above the value
    measured here); the broadband's line power of a sinusoid alone is A^2/2 (to 5e-5: the
    leakage beyond the bins taken out and in the bridge's side bins), and over a broadband
    record within 3 % (the cross term of the line and the noise under it, which 60 segments
    average to 1-2 %)."""
    n = NPERSEG
    window = signal.get_window("hann", n)
    k = 200
    P = np.abs(np.fft.rfft(window * np.sin(2 * np.pi * (k + 0.5) * np.arange(n) / n))) ** 2
    for half, bound in ((2, 5.6e-4), (3, 7.7e-5), (5, 6.7e-6), (8, 7.1e-7)):
        outside = 1 - P[k - half:k + half + 1].sum() / P.sum()
        assert outside < bound, (half, outside)
    tau = DT * np.arange(N_SAMPLES)
    beta, S, _ = welch(1.5 * np.sin(BETA_F * tau + 0.3))
    assert broadband(beta, S, BETA_F)[1][0] == pytest.approx(1.5 ** 2 / 2, rel=5e-5)
    beta, S, _ = welch(record(1.3, 1.5, seed=1))
    assert broadband(beta, S, BETA_F)[1][0] == pytest.approx(1.5 ** 2 / 2, rel=3e-2)


def test_broadband_centroid_does_not_count_the_lines():
    """The same broadband record with a line at beta_f of power 0, 0.5 and 2 (the study's
    strongest is 1.9): the centroid with the lines follows the line (it moves by more than
    0.1 toward beta_f), the broadband centroid does not (within 1e-3: the line leaks < 7e-6
    of its power beyond its +-5 bins, 1.4e-5 against the broadband's 0.09 at power 2; the
    bridge under the line is the broadband's, whatever the line)."""
    readings = []
    for amplitude in (0.0, 1.0, 2.0):
        row = spectra_row({2.0: (1.3, amplitude), -0.5: (1.1, 0.1)})
        readings.append(shift(row, BETA_F))
    lines = [r.centroid_lines[-1] for r in readings]
    broad = [r.centroid[-1] for r in readings]
    assert lines[0] - lines[-1] > 0.1
    assert max(broad) - min(broad) < 1e-3, broad
    # and the lines' power is read apart: A^2 / 2 within 3 % (the test above says why)
    assert readings[-1].lines[-1, 0] == pytest.approx(2.0, rel=3e-2)
    # no line: what the bridge misses of the broadband's curvature over the 11 bins on the
    # resonance's flank, and the noise of 60 segments (1.1e-3 of the broadband's 0.09 here)
    assert abs(readings[0].lines[-1, 0]) < 2e-3
    # counted with the lines, the measure would follow them: the test above would fail
    with_lines = [r.centroid_lines[-1] for r in readings]
    assert max(with_lines) - min(with_lines) > 100 * (max(broad) - min(broad))


def test_the_shift_reads_the_same_under_every_choice():
    """A broadband resonance moving 1.3 -> 1.0 as delta falls, under a line strong at the
    large play and weak at the small (the study's case: with the lines the centroid rises):
    every choice (half-width x band x fill) reads "falls", with intervals from the batches
    below 0. Swapped plays read "rises" under every choice; the same resonance at both plays
    on different noise reads "unresolved" (an interval holds 0)."""
    falls = shift(spectra_row({2.0: (1.3, 1.7), -0.5: (1.0, 0.2)}), BETA_F)
    assert falls.centroid_lines[0] > falls.centroid_lines[-1]     # with the lines: rises
    assert set(falls.change) == {(h, b, f) for h in LINE_BINS_CHOICES for b in BAND_CHOICES
                                 for f in FILL_CHOICES}
    assert all(high < 0 for _, _, high in falls.change.values()), falls.change
    assert falls.reading() == "falls" and falls.n_batches == N_BATCHES
    assert np.all((falls.centroid_low < falls.centroid) & (falls.centroid < falls.centroid_high))
    assert falls.peak[0] < falls.peak[-1]
    rises = shift(spectra_row({2.0: (1.0, 1.7), -0.5: (1.3, 0.2)}), BETA_F)
    assert rises.reading() == "rises"
    same = shift(spectra_row({2.0: (1.2, 1.7), -0.5: (1.2, 0.2)}), BETA_F)
    assert same.reading() == "unresolved", same.change
    # no batches: no interval, no verdict
    row = spectra_row({2.0: (1.3, 1.7), -0.5: (1.0, 0.2)}).drop_vars("S_a_batch")
    assert shift(row, BETA_F).reading() == "unresolved"


def test_line_mask_covers_every_harmonic_in_the_band():
    beta = np.arange(0, 400) * 0.01
    mask, centres = line_mask(beta, 0.9, band=3.0, halfwidth=LINE_BINS)
    assert centres == [90, 180, 270]
    assert mask.sum() == 3 * (2 * LINE_BINS + 1)
    with pytest.raises(ValueError, match="beta_f"):
        line_mask(beta, 0.0)
    with pytest.raises(ValueError, match="fill"):
        broadband(beta, np.ones_like(beta), 0.9, fill="zero")
