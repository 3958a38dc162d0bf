"""Random force generation (vibroimpact.noise): targets, statistics, reproducibility.

Statistical tests compare estimates with the target within a stated multiple of their
standard error (5 sigma; seeds are fixed, so the outcome is deterministic). Target pairs
(PSD <-> autocorrelation, eqs. 8, 9) are checked by quadrature to round-off.
"""
import math

import numpy as np
import pytest
import scipy.integrate
import scipy.signal

from vibroimpact import noise
from vibroimpact.noise import (NoiseSpec, estimate_autocorrelation, estimate_psd, generate,
                               generate_array)

SPECS = {
    "white": NoiseSpec("white", rms=0.29, dt=0.1),
    "band_limited": NoiseSpec("band_limited", rms=0.29, dt=0.1, beta_c=5.0),
    "lowpass2": NoiseSpec("lowpass2", rms=0.29, dt=0.1, beta_c=2.0, zeta_f=0.5),
}
KINDS = list(SPECS)
N_RECORD = 2**21
SEED = 20240601
SIGMAS = 5.0
#: Largest |realized - ideal| autocorrelation of the band_limited FIR used here, / rms^2
#: (asserted in test_band_limited_fir_realizes_target).
FIR_PHI_DEVIATION = 1e-3


@pytest.fixture(scope="module")
def records():
    return {kind: generate_array(spec, N_RECORD, SEED) for kind, spec in SPECS.items()}


def inverse_transform(spec, psd, tau, upper):
    """(1/pi) int_0^upper psd(beta) cos(beta tau) dbeta (eq. 9 inverted, psd even), split
    at the band edges beta_c + 2 pi m/dt of the spectrum and its periodic images."""
    images = 2 * math.pi / spec.dt * np.arange(math.ceil(upper * spec.dt / (2 * math.pi)) + 1)
    edges = [0.0, upper]
    if spec.kind == "band_limited":
        edges += [e for e in np.abs(np.r_[images - spec.beta_c, images + spec.beta_c])
                  if 0.0 < e < upper]
    edges = sorted(edges)
    return sum(scipy.integrate.quad(psd, lo, hi, weight="cos", wvar=tau, limit=400)[0]
               for lo, hi in zip(edges[:-1], edges[1:])) / math.pi


def bartlett_std(spec, lags, n, m_max=20_000):
    """Std of the biased autocorrelation estimate of a Gaussian record (Bartlett's formula)."""
    m = np.arange(-m_max, m_max + 1)
    phi = spec.autocorrelation(m * spec.dt)
    var = [np.sum(phi**2) + np.sum(phi[2 * k:] * phi[: phi.size - 2 * k]) for k in lags]
    return np.sqrt(np.array(var) / n)


# --- targets -----------------------------------------------------------------------------

@pytest.mark.parametrize("kind", KINDS)
def test_psd_integrates_to_rms_squared(kind):
    """Eq. 9 normalisation: (1/2 pi) int S dbeta = rms^2, to quadrature accuracy 1e-10."""
    spec = SPECS[kind]
    variance = inverse_transform(spec, spec.psd, 0.0, spec.nyquist)
    assert variance == pytest.approx(spec.rms**2, rel=1e-10)
    assert spec.psd(1.001 * spec.nyquist) == 0.0


@pytest.mark.parametrize("kind", KINDS)
def test_autocorrelation_is_inverse_transform_of_psd(kind):
    """phi(tau) = (1/2 pi) int S exp(j beta tau) dbeta, at sample and in-between lags."""
    spec = SPECS[kind]
    tau = np.array([0.0, 0.1, 0.05, 0.37, 1.234, 5.55])
    expected = [inverse_transform(spec, spec.psd, t, spec.nyquist) for t in tau]
    np.testing.assert_allclose(spec.autocorrelation(tau), expected, rtol=0,
                               atol=1e-10 * spec.rms**2)


@pytest.mark.parametrize("kind", KINDS)
def test_piecewise_linear_pair(kind):
    """The interpolated force: phi_lin(k dt) = (phi_{k-1} + 4 phi_k + phi_{k+1}) / 6 and
    phi_lin is the inverse transform of S_lin (quadrature cut at 100 pi/dt, where the
    sinc^4 tail left out is < 1e-7 rms^2)."""
    spec = SPECS[kind]
    k = np.arange(-3, 4)
    phi = spec.autocorrelation(k * spec.dt)
    np.testing.assert_allclose(spec.autocorrelation_piecewise_linear(k[1:-1] * spec.dt),
                               (phi[:-2] + 4 * phi[1:-1] + phi[2:]) / 6, atol=1e-15)
    for tau in (0.0, 0.05, 0.37):
        expected = inverse_transform(spec, spec.psd_piecewise_linear, tau, 100 * spec.nyquist)
        assert spec.autocorrelation_piecewise_linear(tau) == pytest.approx(
            expected, abs=1e-6 * spec.rms**2)


@pytest.mark.parametrize("zeta_f", [0.05, 0.5, 1.0, 1.0 + 1e-7, 3.0])
def test_lowpass2_targets_are_the_sampled_continuous_process(zeta_f):
    """S = sum_m S_c(beta + 2 pi m/dt) (aliasing) and phi_k = phi_c(k dt), from the
    continuous filter's formulas written independently (poles, rational S_c); 1e-9."""
    spec = NoiseSpec("lowpass2", rms=0.7, dt=0.1, beta_c=2.0, zeta_f=zeta_f)
    beta = np.linspace(0.0, spec.nyquist, 9)
    shifted = beta[None, :] + 2 * math.pi * np.arange(-20_000, 20_001)[:, None] / spec.dt
    s_c = (4 * zeta_f * spec.rms**2 * spec.beta_c**3
           / ((spec.beta_c**2 - shifted**2) ** 2 + (2 * zeta_f * spec.beta_c * shifted) ** 2))
    np.testing.assert_allclose(spec.psd(beta), s_c.sum(axis=0), rtol=1e-9)

    tau = np.arange(0, 40) * spec.dt
    p1, p2 = spec.beta_c * (-zeta_f + np.sqrt(complex(zeta_f**2 - 1)) * np.array([1, -1]))
    if zeta_f != 1.0:  # the pole formula is 0/0 at critical damping
        phi_c = spec.rms**2 * ((p2 * np.exp(p1 * tau) - p1 * np.exp(p2 * tau)) / (p2 - p1)).real
        np.testing.assert_allclose(spec.autocorrelation(tau), phi_c, rtol=0,
                                   atol=1e-9 * spec.rms**2)
    else:
        phi_c = spec.rms**2 * np.exp(-spec.beta_c * tau) * (1 + spec.beta_c * tau)
        np.testing.assert_allclose(spec.autocorrelation(tau), phi_c, atol=1e-15)


def test_band_limited_fir_realizes_target():
    """The FIR's exact output statistics: variance rms^2 (1e-12), PSD within 5e-4 of the
    target in the pass band and below 1e-4 S_0 in the stop band (outside the transition
    band), autocorrelation within FIR_PHI_DEVIATION rms^2 of the ideal sinc."""
    spec = SPECS["band_limited"]
    taps = noise.band_limited_taps(spec)
    assert np.dot(taps, taps) == pytest.approx(spec.rms**2, rel=1e-12)
    theta = np.linspace(0.0, math.pi, 20_001)
    beta = theta / spec.dt
    _, response = scipy.signal.freqz(taps, worN=theta)
    realized = spec.dt * np.abs(response) ** 2
    level = math.pi * spec.rms**2 / spec.beta_c
    half_width = 0.6 * noise.FIR_TRANSITION_FRACTION * spec.beta_c
    passband, stopband = beta < spec.beta_c - half_width, beta > spec.beta_c + half_width
    np.testing.assert_allclose(realized[passband], level, rtol=5e-4)
    assert realized[stopband].max() < 1e-4 * level
    lags = np.arange(200)
    phi = np.correlate(taps, taps, "full")[taps.size - 1:][: lags.size]
    assert np.max(np.abs(phi - spec.autocorrelation(lags * spec.dt))) < (
        FIR_PHI_DEVIATION * spec.rms**2)


# --- generated statistics ----------------------------------------------------------------

@pytest.mark.parametrize("kind", KINDS)
def test_sample_rms_matches_target(records, kind):
    """rms of 2^21 samples within 5 standard errors; se(phi_0) = sqrt(2 sum phi_m^2 / n)."""
    spec, x = SPECS[kind], records[kind]
    std_phi0 = bartlett_std(spec, [0], x.size)[0]
    assert abs(np.sqrt(np.mean(x**2)) - spec.rms) < SIGMAS * std_phi0 / (2 * spec.rms)
    assert abs(np.mean(x)) < SIGMAS * np.sqrt(spec.psd(0.0) / spec.dt / x.size)


@pytest.mark.parametrize("kind", KINDS)
def test_estimated_autocorrelation_matches_target(records, kind):
    """Biased estimate at lags 0..6 (60 samples) within 5 Bartlett standard errors, plus the
    estimator bias k/n phi_k and (band_limited) the FIR's design deviation."""
    spec, x = SPECS[kind], records[kind]
    tau, phi = estimate_autocorrelation(x, spec.dt, 6.0)
    assert tau.size == 61
    lags = np.arange(tau.size)
    target = spec.autocorrelation(tau)
    allowance = SIGMAS * bartlett_std(spec, lags, x.size) + lags / x.size * np.abs(target)
    if kind == "band_limited":
        allowance += FIR_PHI_DEVIATION * spec.rms**2
    assert np.all(np.abs(phi - target) < allowance)


@pytest.mark.parametrize("kind", KINDS)
def test_estimated_psd_matches_target(records, kind):
    """Welch (Hann, nperseg 512, K = 8191 half-overlapping segments): relative standard
    error sqrt(1.056 / K) = 1.1 %; every bin but DC and Nyquist within 5 of them. For
    band_limited, bins within 8 resolutions of beta_c are left out (window leakage of the
    step) and the stop band must stay below 1e-5 S_0 (leakage measured: 2e-7)."""
    spec, x = SPECS[kind], records[kind]
    nperseg = 512
    beta, s_hat = estimate_psd(x, spec.dt, nperseg)
    segments = (x.size - nperseg) // (nperseg // 2) + 1
    rel_se = math.sqrt(1.056 / segments)
    target = spec.psd(beta)
    inner = (beta > 0) & (beta < spec.nyquist)
    if kind == "band_limited":
        resolution = 2 * math.pi / (nperseg * spec.dt)
        away = np.abs(beta - spec.beta_c) > 8 * resolution
        stop = inner & away & (beta > spec.beta_c)
        assert s_hat[stop].max() < 1e-5 * spec.psd(0.0)
        inner &= away & (beta < spec.beta_c)
    assert np.count_nonzero(inner) > 25
    z = (s_hat[inner] / target[inner] - 1) / rel_se
    assert np.max(np.abs(z)) < SIGMAS


def test_record_is_stationary_from_first_sample():
    """lowpass2 starts in its stationary state: over 1000 seeds, var r_0, var r_1 and
    E[r_0 r_1] match phi_0, phi_0, phi_1 within 5 standard errors (a zero start would give
    var r_0 = b_0^2 ~ 1e-4 rms^2 here)."""
    spec = NoiseSpec("lowpass2", rms=1.0, dt=0.1, beta_c=0.5, zeta_f=0.3)
    first = np.array([generate_array(spec, 2, seed) for seed in range(1000)])
    phi_0, phi_1 = spec.autocorrelation(np.array([0.0, spec.dt]))
    se_var = math.sqrt(2.0 / first.shape[0]) * phi_0
    np.testing.assert_allclose(np.mean(first**2, axis=0), phi_0, atol=SIGMAS * se_var)
    se_cov = math.sqrt((phi_0**2 + phi_1**2) / first.shape[0])
    assert abs(np.mean(first[:, 0] * first[:, 1]) - phi_1) < SIGMAS * se_cov


# --- reproducibility ---------------------------------------------------------------------

@pytest.mark.parametrize("kind", KINDS)
def test_chunking_is_bit_identical(kind):
    """Concatenated chunks equal the one-array record bit for bit, for any chunk size
    (the record spans several internal blocks)."""
    spec, n = SPECS[kind], 200_001
    reference = generate_array(spec, n, SEED)
    for chunk_size in (7, 4096, 65_537, 2**20):
        chunks = list(generate(spec, n, SEED, chunk_size=chunk_size))
        assert all(c.dtype == np.float64 and c.size <= chunk_size for c in chunks)
        assert np.array_equal(np.concatenate(chunks), reference)


@pytest.mark.parametrize("kind", KINDS)
def test_seed_reproduces_and_distinguishes(kind):
    """Same seed (int or SeedSequence): identical; another seed: a different, uncorrelated
    record (|correlation| < 5 / sqrt(n), a bound valid for white records and loose here)."""
    spec, n = SPECS[kind], 100_000
    x = generate_array(spec, n, 7)
    assert np.array_equal(x, generate_array(spec, n, np.random.SeedSequence(7)))
    y = generate_array(spec, n, 8)
    assert not np.array_equal(x, y)
    assert abs(np.corrcoef(x, y)[0, 1]) < SIGMAS * 10 / math.sqrt(n)


def test_zero_rms_and_empty_record():
    spec = NoiseSpec("lowpass2", rms=0.0, dt=0.1, beta_c=2.0, zeta_f=0.5)
    assert not np.any(generate_array(spec, 1000, 1))
    assert generate_array(SPECS["white"], 0, 1).shape == (0,)
    assert list(generate(SPECS["white"], 0, 1)) == []


# --- estimators --------------------------------------------------------------------------

def test_estimators_follow_the_paper_convention():
    """estimate_autocorrelation is (1/n) sum x_i x_{i+k} exactly; estimate_psd over one
    boxcar segment obeys Parseval in eq. 9's form, (1/2 pi) sum_{two-sided bins} S dbeta =
    mean square, to round-off (this checks the one- to two-sided conversion at DC and
    Nyquist too)."""
    x = np.random.default_rng(3).standard_normal(4096)
    tau, phi = estimate_autocorrelation(x, 0.5, 10.0)
    direct = np.correlate(x, x, "full")[x.size - 1:][: tau.size] / x.size
    np.testing.assert_allclose(phi, direct, rtol=0, atol=1e-12)
    np.testing.assert_allclose(tau, 0.5 * np.arange(21))
    x += 0.3  # a mean: kept with detrend=False (eq. 8), it must show at beta = 0
    beta, s = estimate_psd(x, 0.5, x.size, window="boxcar", detrend=False)
    assert beta[-1] == pytest.approx(math.pi / 0.5)
    variance = (s[0] + 2 * np.sum(s[1:-1]) + s[-1]) * (beta[1] - beta[0]) / (2 * math.pi)
    assert variance == pytest.approx(np.mean(x**2), rel=1e-12)
    # the package's convention (PSD_DETREND) removes the record's mean: Parseval gives var(x)
    beta, s = estimate_psd(x, 0.5, x.size, window="boxcar")
    variance = (s[0] + 2 * np.sum(s[1:-1]) + s[-1]) * (beta[1] - beta[0]) / (2 * math.pi)
    assert variance == pytest.approx(np.var(x), rel=1e-12)


# --- validation ----------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, field", [
    (dict(kind="white", rms=-0.1, dt=0.1), "rms"),
    (dict(kind="white", rms=float("nan"), dt=0.1), "rms"),
    (dict(kind="white", rms="abc", dt=0.1), "rms"),
    (dict(kind="white", rms=1.0, dt=0.0), "dt"),
    (dict(kind="white", rms=1.0, dt=-0.1), "dt"),
    (dict(kind="pink", rms=1.0, dt=0.1), "kind"),
    (dict(kind="band_limited", rms=1.0, dt=0.1, beta_c=32.0), "beta_c"),
    (dict(kind="band_limited", rms=1.0, dt=0.1, beta_c=0.0), "beta_c"),
    (dict(kind="band_limited", rms=1.0, dt=0.1), "beta_c"),
    (dict(kind="band_limited", rms=1.0, dt=0.1, beta_c=31.4159), "beta_c"),  # FIR too long
    (dict(kind="band_limited", rms=1.0, dt=0.1, beta_c=0.01), "beta_c"),  # FIR too long
    (dict(kind="lowpass2", rms=1.0, dt=0.1, beta_c=40.0, zeta_f=0.5), "beta_c"),
    (dict(kind="lowpass2", rms=1.0, dt=0.1, beta_c=2.0, zeta_f=0.0), "zeta_f"),
    (dict(kind="lowpass2", rms=1.0, dt=0.1, beta_c=2.0), "zeta_f"),
    (dict(kind="white", rms=1.0, dt=0.1, beta_c=2.0), "beta_c"),
])
def test_bad_spec_raises_naming_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        NoiseSpec(**kwargs)


@pytest.mark.parametrize("kwargs, field", [
    (dict(n_samples=-1, seed=1), "n_samples"),
    (dict(n_samples=10.5, seed=1), "n_samples"),
    (dict(n_samples=10, seed=None), "seed"),
    (dict(n_samples=10, seed=-3), "seed"),
    (dict(n_samples=10, seed=1, chunk_size=0), "chunk_size"),
])
def test_bad_generate_arguments_raise_naming_them(kwargs, field):
    with pytest.raises(ValueError, match=field):
        generate(SPECS["white"], **kwargs)


def test_full_band_is_white():
    """band_limited with beta_c = pi/dt is the white spectrum and the white generator."""
    full = NoiseSpec("band_limited", rms=0.29, dt=0.1, beta_c=math.pi / 0.1)
    beta = np.linspace(0, full.nyquist, 5)
    np.testing.assert_allclose(full.psd(beta), SPECS["white"].psd(beta), rtol=1e-12)
    assert np.array_equal(generate_array(full, 1000, 1), generate_array(SPECS["white"], 1000, 1))
