"""Tests of vibroimpact.stats: spectra, densities, batch means, impact-motion types, oracles.

Every assertion states its tolerance; random inputs come from fixed seeds, so the outcomes
are deterministic, and each statistical tolerance is several standard errors wide.
"""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from scipy import integrate, linalg, signal
from scipy import stats as sps

from vibroimpact.stats import (
    WelchAccumulator, batch_means, classify_impact_intervals, count_motion_switches, density,
    elastic_impact_rate, impact_intervals, impact_motion_probabilities, interval_ratio,
    linear_psd_response, linear_response_std, motion_map_agreement, motion_statistics,
    rayleigh_pdf, truncated_gaussian_pdf, variance_from_psd, velocity_after_impact, welch_psd,
)
from vibroimpact.stats.events import event_rate, mark_mean, poisson_interval, t_quantile


def _ar1(rng, phi, n, reps=None, sigma_e=1.0):
    """AR(1) x_k = phi x_{k-1} + e_k started in its stationary distribution."""
    shape = (n,) if reps is None else (reps, n)
    e = sigma_e * rng.standard_normal(shape)
    e[..., 0] /= np.sqrt(1.0 - phi**2)
    return signal.lfilter([1.0], [1.0, -phi], e, axis=-1)


# --------------------------------------------------------------------------------- spectra

@settings(max_examples=25, deadline=None)
@given(cuts=st.lists(st.integers(0, 20_000), max_size=12),
       nperseg=st.sampled_from([64, 127, 256]),
       detrend=st.sampled_from(["mean", "constant", "linear", False]))
def test_streaming_welch_equals_scipy_on_concatenation(cuts, nperseg, detrend):
    # Tolerance: 1e-12 relative to the largest bin (round-off only; chunking must not matter).
    x = 1.5 + _ar1(np.random.default_rng(0), 0.8, 20_000)
    acc = WelchAccumulator(0.3, nperseg, detrend=detrend)
    for chunk in np.split(x, sorted(cuts)):
        acc.feed(chunk)
    f, P = acc.onesided_density()
    if detrend == "mean":   # the record's mean removed, nothing per segment
        f_ref, P_ref = signal.welch(x - x.mean(), fs=1 / 0.3, nperseg=nperseg, detrend=False)
    else:
        f_ref, P_ref = signal.welch(x, fs=1 / 0.3, nperseg=nperseg, detrend=detrend)
    np.testing.assert_allclose(f, f_ref, rtol=1e-14)
    np.testing.assert_allclose(P, P_ref, rtol=1e-12, atol=1e-12 * P_ref.max())
    assert acc.n_segments == (x.size - nperseg) // (nperseg - nperseg // 2) + 1
    assert acc.n_samples == x.size


@pytest.mark.parametrize("detrend", ["mean", "constant"])
def test_welch_batches_are_welch_of_their_stretches_and_average_to_the_whole(detrend):
    # Each batch is scipy's Welch estimate of its own consecutive segments (for "mean", of the
    # record less its whole mean); the batches weighted by their segment counts give the
    # whole estimate, which batches leave bit for bit unchanged. Tolerances: round-off only.
    x = 1.5 + _ar1(np.random.default_rng(1), 0.8, 10_000)
    nperseg, step, n_batches = 256, 128, 7
    n_seg = (x.size - nperseg) // step + 1
    plain = WelchAccumulator(0.3, nperseg, detrend=detrend)
    acc = WelchAccumulator(0.3, nperseg, detrend=detrend, batches=(n_batches, n_seg))
    for chunk in np.split(x, [1000, 1001, 5555]):
        plain.feed(chunk)
        acc.feed(chunk)
    beta, S = acc.result()
    assert np.array_equal(S, plain.result()[1])
    S_b = acc.result_batches()
    batch = np.arange(n_seg) * n_batches // n_seg
    counts = np.bincount(batch)
    assert S_b.shape == (n_batches, beta.size) and counts.min() >= counts.max() - 1
    np.testing.assert_allclose((counts[:, None] * S_b).sum(0) / n_seg, S, rtol=1e-12,
                               atol=1e-12 * S.max())
    y = x - x.mean() if detrend == "mean" else x
    for b in (0, n_batches - 1):
        first, last = np.flatnonzero(batch == b)[[0, -1]]
        stretch = y[first * step:last * step + nperseg]
        _, P = signal.welch(stretch, fs=1 / 0.3, nperseg=nperseg,
                            detrend=False if detrend == "mean" else detrend)
        np.testing.assert_allclose(S_b[b, 1:-1], P[1:-1] / 2, rtol=1e-10,
                                   atol=1e-12 * P.max())
    with pytest.raises(ValueError, match="segments fed"):
        WelchAccumulator(0.3, nperseg, batches=(2, n_seg + 1)).feed(x).result_batches()
    with pytest.raises(ValueError, match="more segments"):
        WelchAccumulator(0.3, nperseg, batches=(2, n_seg - 1)).feed(x)
    with pytest.raises(ValueError, match="n_batches"):
        WelchAccumulator(0.3, nperseg, batches=(n_seg + 1, n_seg))


def test_welch_rejects_bad_input_and_empty_result():
    with pytest.raises(ValueError, match="dt"):
        WelchAccumulator(0.0, 64)
    with pytest.raises(ValueError, match="nperseg"):
        WelchAccumulator(0.1, 1)
    with pytest.raises(ValueError, match="detrend"):
        WelchAccumulator(0.1, 64, detrend="quadratic")
    acc = WelchAccumulator(0.1, 64).feed(np.zeros(63))
    with pytest.raises(ValueError, match="no complete segment"):
        acc.result()
    with pytest.raises(ValueError, match="NaN"):
        acc.feed([0.0, np.nan])


def test_white_noise_level_and_variance_in_paper_convention():
    # White sequence of variance s2 at spacing dt has S(beta) = s2 * dt (eq. 9, two-sided angular)
    # and (1/pi) int_0^{pi/dt} S dbeta = s2. Tolerance 1 %: statistical error of the mean level
    # over ~500 bins x ~1900 segments is ~0.1 %.
    rng = np.random.default_rng(1)
    s2, dt = 2.25, 0.2
    x = np.sqrt(s2) * rng.standard_normal(500_000)
    beta, S, n_eff = welch_psd(x, dt, 1024)
    assert beta[-1] == pytest.approx(np.pi / dt, rel=1e-14)
    assert np.mean(S[1:-1]) == pytest.approx(s2 * dt, rel=0.01)
    assert variance_from_psd(beta, S) == pytest.approx(s2, rel=0.01)
    # The package's convention removes the record's mean only, so the lowest bins are not
    # biased low as per-segment detrending makes them (bin 0 keeps ~0 of its power there):
    # the mean of bins 0-1 over 20 independent records within 25 % (their scatter ~ 20 %).
    low = [welch_psd(np.sqrt(s2) * rng.standard_normal(20_000), dt, 1024)[1][:2]
           for _ in range(20)]
    assert np.mean(low) == pytest.approx(s2 * dt, rel=0.25)
    # One-sided per-Hz density is twice S inside the band (module docstring).
    f, P = WelchAccumulator(dt, 1024).feed(x).onesided_density()
    np.testing.assert_allclose(P[1:-1], 2 * S[1:-1], rtol=1e-14)
    np.testing.assert_allclose(f, beta / (2 * np.pi), rtol=1e-14)


def test_sinusoid_variance_and_peak_location():
    # A sin(beta0 tau): variance A^2/2 recovered to < 1 %, peak within one bin of beta0.
    A, beta0, dt = 1.7, 1.1, 0.1
    tau = dt * np.arange(400_000)
    beta, S, _ = welch_psd(A * np.sin(beta0 * tau), dt, 4096)
    assert variance_from_psd(beta, S) == pytest.approx(A**2 / 2, rel=0.01)
    assert abs(beta[np.argmax(S)] - beta0) <= beta[1]


def test_ar1_spectrum_shape_and_scatter_match_theory():
    # AR(1) with innovation variance 1 at spacing dt: S(beta) = dt / |1 - phi e^{-j beta dt}|^2.
    # Mean ratio estimate/theory within 2 %; the bin-to-bin scatter of that ratio within 15 % of
    # 1/sqrt(K_eff) (chi-square with 2 K_eff dof); both would fail with a wrong factor or K_eff.
    phi, dt = 0.7, 0.5
    x = _ar1(np.random.default_rng(2), phi, 300_000)
    acc = WelchAccumulator(dt, 512).feed(x)
    beta, S = acc.result()
    theory = dt / np.abs(1 - phi * np.exp(-1j * beta * dt)) ** 2
    ratio = S[1:-1] / theory[1:-1]
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.02)
    assert np.std(ratio) == pytest.approx(1 / np.sqrt(acc.n_effective), rel=0.15)
    assert acc.n_segments / 1.1 < acc.n_effective < acc.n_segments


def test_linear_response_variance_equals_closed_form_for_white_force():
    # (1/pi) int_0^inf |H|^2 S0 dbeta = S0 / (4 zeta): fine grid to beta = 200 plus the
    # analytic tail S0/(3 pi B^3) of |H|^2 ~ beta^-4; tolerance 1e-4 relative.
    S0, zeta = 0.8, 0.05
    beta = np.linspace(0.0, 200.0, 2_000_001)
    var = variance_from_psd(beta, linear_psd_response(beta, S0, zeta)) + S0 / (3 * np.pi * 200**3)
    assert var == pytest.approx(S0 / (4 * zeta), rel=1e-4)


def test_linear_response_std_matches_lyapunov_and_quadrature():
    # Time-domain check of sigma_x^2 = sigma_v^2 = S0/(4 zeta): the stationary covariance of
    # x'' + 2 zeta x' + x = w with E[w(t) w(t')] = S0 delta(t - t') solves A P + P A^T + Q = 0.
    # Tolerances: 1e-10 (closed form vs Lyapunov), 1e-7 (quad vs closed form).
    S0, zeta = 1.3, 0.05
    A = np.array([[0.0, 1.0], [-1.0, -2 * zeta]])
    P = linalg.solve_continuous_lyapunov(A, -np.array([[0.0, 0.0], [0.0, S0]]))
    sx, sv = linear_response_std(S0, zeta)
    assert sx**2 == pytest.approx(P[0, 0], rel=1e-10)
    assert sv**2 == pytest.approx(P[1, 1], rel=1e-10)
    qx, qv = linear_response_std(lambda b: S0, zeta)
    assert (qx, qv) == (pytest.approx(sx, rel=1e-7), pytest.approx(sv, rel=1e-7))
    # Coloured force: Lorentzian S_f = 2 c s2 / (c^2 + beta^2) is the OU force of variance s2,
    # x'' + 2 zeta x' + x = y, y' = -c y + sqrt(2 c s2) w; augmented Lyapunov equation, 1e-7.
    c, s2 = 0.7, 0.4
    A3 = np.array([[0.0, 1.0, 0.0], [-1.0, -2 * zeta, 1.0], [0.0, 0.0, -c]])
    Q3 = np.zeros((3, 3))
    Q3[2, 2] = 2 * c * s2
    P3 = linalg.solve_continuous_lyapunov(A3, -Q3)
    qx, qv = linear_response_std(lambda b: 2 * c * s2 / (c**2 + b**2), zeta)
    assert qx**2 == pytest.approx(P3[0, 0], rel=1e-7)
    assert qv**2 == pytest.approx(P3[1, 1], rel=1e-7)


# ------------------------------------------------------------------ densities and intervals

def test_density_normalised_and_binomial_error_matches_replicate_spread():
    # Integral of the density = 1 to 1e-12; the quoted stderr equals the spread of the density
    # over 1000 independent replicates within 10 % (bins with >= 50 expected counts; the spread
    # itself is known to ~2.2 %, so 10 % is > 4 of its standard errors).
    rng = np.random.default_rng(3)
    bins = np.linspace(-3, 3, 25)
    reps = [density(rng.standard_normal(2000), bins) for _ in range(1000)]
    d0 = reps[0]
    assert np.sum(d0.density * np.diff(bins)) == pytest.approx(1.0, abs=1e-12)
    spread = np.std([r.density for r in reps], axis=0, ddof=1)
    quoted = np.mean([r.stderr for r in reps], axis=0)
    well_filled = np.mean([r.density for r in reps], axis=0) * np.diff(bins) * 2000 > 50
    np.testing.assert_allclose(quoted[well_filled], spread[well_filled], rtol=0.10)
    empty = density([], bins)
    assert empty.n == 0 and np.all(np.isnan(empty.density))


def test_batch_density_error_matches_replicate_spread_of_a_correlated_sequence():
    # AR(1), phi = 0.9 (unit variance), 300 replications of 20 000 values, 20 batches. The
    # batch-means stderr per bin equals the spread of the density over replications within
    # 12 % (the spread is known to ~4 %, and the batch estimate's mean is biased low by ~2 %
    # by the square root and the finite batch length), while the binomial one, which assumes
    # independent values, understates it by a factor of ~2 (asserted: below 70 %).
    rng = np.random.default_rng(5)
    phi, n, reps = 0.9, 20_000, 300
    x = _ar1(rng, phi, n, reps, sigma_e=np.sqrt(1.0 - phi**2))
    bins = np.linspace(-2.5, 2.5, 11)
    batch = [density(row, bins, total=n, n_batches=20) for row in x]
    binomial = [density(row, bins, total=n) for row in x]
    spread = np.std([d.density for d in batch], axis=0, ddof=1)
    np.testing.assert_allclose(np.mean([d.stderr for d in batch], axis=0), spread, rtol=0.12)
    assert np.all(np.mean([d.stderr for d in binomial], axis=0) < 0.7 * spread)
    # the same density either way; `beyond` is the exact share above the last edge
    np.testing.assert_array_equal(batch[0].density, binomial[0].density)
    assert batch[0].beyond == np.count_nonzero(x[0] > 2.5) / n
    # too few values for the batches: NaN error, density still given
    short = density(x[0, :15], bins, n_batches=20)
    assert np.all(np.isnan(short.stderr)) and np.isfinite(short.density).all()
    with pytest.raises(ValueError, match="n_batches"):
        density(x[0], bins, n_batches=1)


def test_t_quantile_is_the_factor_of_the_batch_means_interval():
    # Student t of B - 1 dof (2.093 for B = 20 at 95 %), the factor BatchMeans.interval uses.
    assert t_quantile(20) == pytest.approx(sps.t.ppf(0.975, 19), rel=1e-14)
    np.testing.assert_allclose(t_quantile([20, 5]), sps.t.ppf(0.975, [19, 4]), rtol=1e-14)
    assert np.isnan(t_quantile(1)) and np.isnan(t_quantile(0))
    bm = batch_means(_ar1(np.random.default_rng(6), 0.5, 4000), n_batches=20)
    lo, hi = bm.interval(0.95)
    assert (hi - lo) / 2 == pytest.approx(t_quantile(20) * bm.stderr, rel=1e-14)


def test_impact_intervals_exact_on_long_records():
    # Intervals from (step, offset) are exact to round-off of the offsets (1e-15 absolute) even
    # at tau ~ 1e9, where differences of impact_time would lose ~1e-7.
    dt = 0.1
    step = np.array([10**10, 10**10 + 3, 10**10 + 3, 10**10 + 17], dtype=np.int64)
    offset = np.array([0.01, 0.0625, 0.07, 0.1])
    expected = np.array([3 * dt + 0.0525, 0.0075, 14 * dt + 0.03])
    np.testing.assert_allclose(impact_intervals(step, offset, dt), expected, rtol=0, atol=1e-15)
    assert impact_intervals(step[:1], offset[:1], dt).size == 0
    with pytest.raises(ValueError, match="step and offset"):
        impact_intervals(step, offset[:2], dt)
    np.testing.assert_allclose(velocity_after_impact([2.0, 0.5], 0.5), [1.0, 0.25], rtol=1e-15)
    with pytest.raises(ValueError, match="eps"):
        velocity_after_impact([1.0], 1.5)


# -------------------------------------------------------------------------------- batch means

def test_batch_means_interval_covers_truth_at_nominal_rate():
    # AR(1), phi = 0.9, mean 3: 400 replications of 20 000 values. The 95 % batch-means
    # t-interval must cover the true mean in 92-98 % of them (binomial sd 1.1 %); the naive
    # iid interval, for contrast, covers far less (< 60 %), so this test can tell them apart.
    rng = np.random.default_rng(4)
    mu, phi, n, reps = 3.0, 0.9, 20_000, 400
    x = mu + _ar1(rng, phi, n, reps)
    results = [batch_means(row, n_batches=20) for row in x]
    lo, hi = np.array([r.interval(0.95) for r in results]).T
    coverage = np.mean((lo < mu) & (mu < hi))
    assert 0.92 <= coverage <= 0.98
    naive = np.abs(x.mean(axis=1) - mu) < 1.96 * x.std(axis=1) / np.sqrt(n)
    assert np.mean(naive) < 0.6
    # Stderr matches the exact std of the mean, sqrt(var/n (1 + phi)/(1 - phi)), within 10 %.
    exact = np.sqrt(1 / (1 - phi**2) / n * (1 + phi) / (1 - phi))
    assert np.mean([r.stderr for r in results]) == pytest.approx(exact, rel=0.10)
    assert abs(np.mean([r.lag1 for r in results])) < 0.1
    assert all(r.n_batches == 20 for r in results)


def test_batch_means_short_and_invalid():
    short = batch_means(np.arange(5.0), n_batches=20)
    assert short.mean == 2.0 and np.isnan(short.stderr) and short.n_batches == 0
    assert np.isnan(batch_means([]).mean)
    # Leading remainder is dropped: 41 values in 20 batches of 2 use x[1:].
    assert batch_means(np.r_[1000.0, np.ones(40)]).mean == 1.0
    with pytest.raises(ValueError, match="n_batches"):
        batch_means(np.ones(100), n_batches=1)


# ------------------------------------------------------------- event rates of few events

@pytest.mark.parametrize("k", [0, 1, 3, 10, 51])
def test_poisson_interval_is_garwoods(k):
    # Independent check of the defining tails (1e-9): P(X >= k | lo) = P(X <= k | hi) = 2.5 %.
    lo, hi = poisson_interval(k, 0.95)
    assert sps.poisson.cdf(k, hi) == pytest.approx(0.025, abs=1e-9)
    if k:
        assert sps.poisson.sf(k - 1, lo) == pytest.approx(0.025, abs=1e-9)
    else:
        assert lo == 0.0 and hi == pytest.approx(-np.log(0.025), rel=1e-12)   # 3.689
    with pytest.raises(ValueError, match="count"):
        poisson_interval(-1)


def test_event_rate_is_count_over_record_and_garwood_without_overdispersion():
    # 40 events, two in each of the 20 batches: dispersion 0, so exactly Garwood's / T.
    t0, t1 = 100.0, 2100.0
    times = t0 + (np.arange(40) + 0.5) * 50.0
    r = event_rate(times, t0, t1)
    assert r.count == 40 and r.duration == 2000.0 and r.rate == 0.02
    assert r.mean_interval == 50.0 and r.dispersion == 0.0
    lo, hi = poisson_interval(40)
    assert (r.rate_lo, r.rate_hi) == pytest.approx((lo / 2000.0, hi / 2000.0), rel=1e-12)
    assert r.mean_interval_bounds == pytest.approx((2000.0 / hi, 2000.0 / lo), rel=1e-12)
    assert r.mean_interval_stderr == pytest.approx(50.0 / np.sqrt(40), rel=1e-12)
    # No event: the mean interval is unknown but at least T / 3.689 (95 %).
    none = event_rate([], t0, t1)
    assert np.isnan(none.mean_interval) and none.rate == 0.0
    assert none.mean_interval_bounds == pytest.approx((2000.0 / -np.log(0.025), np.inf))
    with pytest.raises(ValueError, match="times must lie"):
        event_rate([50.0], t0, t1)
    with pytest.raises(ValueError, match="t1"):
        event_rate([], t1, t0)


def test_event_rate_widens_for_bursts_and_mean_of_gaps_is_biased_low():
    # Each excursion gives a burst of three events: the batch counts' dispersion is near 3
    # and the interval is wider than Garwood's by about sqrt(3) on the log scale (> 1.4x).
    rng = np.random.default_rng(7)
    T = 1.0e6
    centres = np.sort(rng.uniform(0.0, T - 10.0, 30))
    times = np.repeat(centres, 3) + np.tile([0.0, 2.0, 5.0], 30)
    r = event_rate(times, 0.0, T)
    assert r.count == 90 and 1.5 < r.dispersion < 6.0
    g_lo, g_hi = poisson_interval(90)
    assert np.log(r.rate_hi / r.rate_lo) > 1.4 * np.log(g_hi / g_lo)
    # The mean of the N - 1 gaps between first and last event, E = T / (N + 1) for a
    # Poisson count given N: over 4000 records of 5 events it is 5/6 of T / N's mean ...
    spans = np.sort(rng.uniform(0.0, T, (4000, 5)), axis=1)
    gap_mean = (spans[:, -1] - spans[:, 0]) / 4
    assert gap_mean.mean() == pytest.approx(T / 6, rel=0.03)   # sd of the mean ~ 0.6 %
    # ... while N / T is unbiased for the rate: Poisson counts of mean 5, 4000 records.
    counts = rng.poisson(5.0, 4000)
    assert np.mean(counts / T) == pytest.approx(5.0 / T, rel=0.03)   # sd ~ 0.5 %


def test_mark_mean_over_time_batches():
    rng = np.random.default_rng(8)
    times = np.sort(rng.uniform(0.0, 1000.0, 400))
    v = 2.0 + rng.standard_normal(400)
    m = mark_mean(v, times, 0.0, 1000.0)
    assert m.mean == pytest.approx(v.mean(), rel=1e-14)
    assert m.lo < m.mean < m.hi and 15 <= m.dof <= 19
    # CR2 is exactly unbiased for independent equal-variance values: over 500 records of
    # 400 unit-variance values the mean squared error is 1 / 400 within 5 % (its sd ~1.5 %).
    se2 = [mark_mean(rng.standard_normal(400), times, 0.0, 1000.0).stderr ** 2
           for _ in range(500)]
    assert np.mean(se2) == pytest.approx(1.0 / 400, rel=0.05)
    # All values in one batch: no error; no value: no mean.
    one = mark_mean([1.0, 2.0], [1.0, 2.0], 0.0, 1000.0)
    assert one.mean == 1.5 and np.isnan(one.stderr) and np.isnan(one.lo)
    assert np.isnan(mark_mean([], [], 0.0, 1.0).mean)
    with pytest.raises(ValueError, match="equal shapes"):
        mark_mean([1.0], [1.0, 2.0], 0.0, 10.0)


# --------------------------------------------------------------------- impact-motion types

BETA = 1.1
Z = 2 * np.pi / BETA


def _probs(r, **kw):
    return impact_motion_probabilities(np.asarray(r) * Z, BETA, **kw)


def test_pure_motions_are_fully_classified():
    # Exact fractions (1e-12): pure sequences of each type cover all the recorded time.
    rng = np.random.default_rng(5)
    p = _probs(1 + rng.uniform(-0.09, 0.09, 200))
    assert p == {"1/1": pytest.approx(1.0, abs=1e-12), "2/1": 0.0, "1/2": 0.0}
    p = _probs(np.tile([0.3, 0.7], 100))
    assert p == {"1/1": 0.0, "2/1": pytest.approx(1.0, abs=1e-12), "1/2": 0.0}
    p = _probs(2 + rng.uniform(-0.09, 0.09, 50))
    assert p == {"1/1": 0.0, "2/1": 0.0, "1/2": pytest.approx(1.0, abs=1e-12)}


def test_mixture_fractions_and_total_time():
    # 10 x (1/1) = 10 z, 5 (2/1) pairs = 5 z, 3 x (1/2) = 6 z, two unclassified 1.5 z = 3 z.
    r = np.r_[np.ones(10), np.tile([0.4, 0.6], 5), 1.5, 2.0, 2.0, 1.5, 2.0]
    p = _probs(r)
    expected = {"1/1": 10 / 24, "2/1": 5 / 24, "1/2": 6 / 24}
    assert p == {k: pytest.approx(v, abs=1e-12) for k, v in expected.items()}
    p = _probs(r, total_time=48 * Z)  # a record twice as long as the impacts span
    assert p == {k: pytest.approx(v / 2, abs=1e-12) for k, v in expected.items()}
    with pytest.raises(ValueError, match="total_time"):
        _probs(r, total_time=10 * Z)
    assert _probs([]) == {"1/1": 0.0, "2/1": 0.0, "1/2": 0.0}


def test_overlapping_pairs_are_taken_greedily_and_counted_once():
    # Three intervals of z/2: two candidate (2/1) pairs overlap; the first is taken.
    assert list(classify_impact_intervals([0.5, 0.5, 0.5])) == [1, 1, -1]
    assert _probs([0.5] * 7)["2/1"] == pytest.approx(6 / 7, abs=1e-12)
    # A chatter-like short interval before a (2/1) record shifts the pairing, not the coverage.
    assert list(classify_impact_intervals([0.05, 0.3, 0.7, 0.3, 0.7])) == [-1, 1, 1, 1, 1]
    # Window edges are strict: |r - 1| = w is not (1/1); a pair needs both below 1 - w.
    assert list(classify_impact_intervals([0.85, 0.9 + 1e-9, 1.9 + 1e-9])) == [-1, 0, 2]
    assert list(classify_impact_intervals([0.95, 0.05])) == [0, -1]
    with pytest.raises(ValueError, match="window"):
        classify_impact_intervals([1.0], window=0.7)


def test_generic_motion_three_over_one():
    labels = classify_impact_intervals(np.tile([0.3, 0.3, 0.4], 4), motions=[(3, 1), (1, 1)])
    assert list(labels) == [0] * 12
    p = _probs(np.r_[np.tile([0.3, 0.3, 0.4], 4), np.ones(4)], motions=[(3, 1), (1, 1)])
    assert p == {"3/1": pytest.approx(0.5, abs=1e-12), "1/1": pytest.approx(0.5, abs=1e-12)}


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(0.01, 3.0), max_size=60))
def test_probabilities_are_fractions_summing_to_at_most_one(r):
    p = _probs(r)
    assert all(0.0 <= v <= 1.0 for v in p.values())
    assert sum(p.values()) <= 1.0 + 1e-12
    np.testing.assert_allclose(interval_ratio(np.asarray(r) * Z, BETA), r, rtol=1e-14)


def test_sticking_and_a_record_ending_mid_motion():
    # A chatter sequence (tiny intervals) ending in sticking: the interval that holds the rest
    # on the wall counts by its whole length, here one period: (1/1).
    r = np.r_[np.ones(4), [0.02, 0.01, 0.005], 0.965, np.ones(3)]
    labels = classify_impact_intervals(r)
    assert list(labels) == [0] * 4 + [-1] * 3 + [0] * 4
    # A (2/1) record cut after the first impact of a pair: the lone short interval is no type.
    assert list(classify_impact_intervals([0.3, 0.7, 0.3, 0.7, 0.3])) == [1, 1, 1, 1, -1]
    # No impact, or a single one: no interval, no motion.
    assert list(classify_impact_intervals([])) == []
    assert count_motion_switches([]) == 0


def test_switches_count_changes_between_classified_motions_only():
    assert count_motion_switches([0, 0, -1, -1, 1, 1, 0]) == 2
    assert count_motion_switches([0, -1, 0, -1, 0]) == 0       # unclassified is no type
    assert count_motion_switches([1, 1, 1, 1]) == 0
    assert count_motion_switches([-1, 2, -1, 0, 0, 2]) == 2


def _brute_force_batches(t, labels, n_motions, t0, t1, n_batches, n_points=400_000):
    """Fractions of each batch covered by each motion, by sampling time on a fine grid."""
    grid = t0 + (np.arange(n_points) + 0.5) * (t1 - t0) / n_points
    j = np.searchsorted(t, grid, side="right") - 1
    lab = np.where((j >= 0) & (j < len(labels)), labels[np.clip(j, 0, len(labels) - 1)], -1)
    per = grid.size // n_batches
    return np.array([[np.mean(lab[b * per:(b + 1) * per] == i) for b in range(n_batches)]
                     for i in range(n_motions)])


def test_motion_statistics_time_batches_against_sampling():
    """Probability = impact_motion_probabilities (exactly); the batch fractions behind the
    error match a brute-force time sampling of the labelled record to its resolution."""
    rng = np.random.default_rng(8)
    r = np.concatenate([np.ones(30) + rng.uniform(-0.05, 0.05, 30), np.tile([0.3, 0.7], 20),
                        2 + rng.uniform(-0.05, 0.05, 12), rng.uniform(0.1, 3.0, 15),
                        np.ones(25)])
    z = r * Z
    t = 7.0 + np.r_[0.0, np.cumsum(z)]
    t0, t1 = 3.0, t[-1] + 5.0
    res = motion_statistics(t, z, BETA, t0, t1, n_batches=10)
    expected = impact_motion_probabilities(z, BETA, total_time=t1 - t0)
    assert list(res.probability) == list(expected.values())
    brute = _brute_force_batches(t, res.labels, 3, t0, t1, 10)
    np.testing.assert_allclose(brute.mean(axis=1), res.probability, atol=1e-4)
    stderr = brute.std(axis=1, ddof=1) / np.sqrt(10)
    np.testing.assert_allclose(res.stderr, stderr, atol=2e-4)
    assert res.n_switches == count_motion_switches(res.labels) >= 4
    # a pure record has no spread between batches; no impacts: zero probability, zero error
    pure = motion_statistics(np.arange(41) * Z, np.full(40, Z), BETA, 0.0, 40 * Z)
    assert list(pure.probability) == [1.0, 0.0, 0.0] and pure.stderr.max() < 1e-12
    empty = motion_statistics([], [], BETA, 0.0, 100.0)
    assert not empty.probability.any() and empty.n_switches == 0
    with pytest.raises(ValueError, match="t_stop"):
        motion_statistics(t, z, BETA, 5.0, 5.0)


def test_map_agreement_shares_and_rank_correlation():
    p = np.array([[0.9, 0.6, 0.1], [0.7, 0.2, np.nan]])
    stable = np.array([[True, True, False], [True, False, False]])
    S = np.where(stable, np.array([[30.0, 10.0, 0.0], [20.0, 0.0, 0.0]]), np.nan)
    a = motion_map_agreement(p, stable, S)
    assert a["n_dominant"] == 3 and a["dominant_inside"] == 1.0 and a["domain_covered"] == 1.0
    assert a["rank_correlation"] == pytest.approx(1.0) and a["n_domain"] == 3
    none = motion_map_agreement(np.zeros((2, 3)), stable, S)
    assert none["n_dominant"] == 0 and np.isnan(none["dominant_inside"])


# ------------------------------------------------------------- exact elastic-impact oracles

@pytest.mark.parametrize("delta", [-3.0, -0.5, 0.0, 1.2, 4.0])
def test_truncated_gaussian_normalised(delta):
    # Integral over x <= delta equals 1 to 1e-8; zero beyond the wall.
    sx = 1.7
    total = integrate.quad(truncated_gaussian_pdf, -np.inf, delta, args=(sx, delta))[0]
    assert total == pytest.approx(1.0, abs=1e-8)
    assert truncated_gaussian_pdf(delta + 1e-9, sx, delta) == 0.0


def test_rayleigh_normalised_with_known_mean():
    # Integral 1 and mean sigma_v sqrt(pi/2), both to 1e-8.
    sv = 0.6
    assert integrate.quad(rayleigh_pdf, 0, np.inf, args=(sv,))[0] == pytest.approx(1.0, abs=1e-8)
    mean = integrate.quad(lambda u: u * rayleigh_pdf(u, sv), 0, np.inf)[0]
    assert mean == pytest.approx(sv * np.sqrt(np.pi / 2), rel=1e-8)
    assert rayleigh_pdf(-0.1, sv) == 0.0


def test_impact_rate_is_flux_into_wall_and_tends_to_rice():
    # nu(delta) = int_0^inf v p_x(delta) p_v(v) dv with p_x the truncated Gaussian (1e-8);
    # for delta = 4 sigma_x it equals Rice's up-crossing rate within 1e-4 (1/Phi(4) - 1 = 3e-5);
    # it vanishes as delta -> +inf and stays finite and growing as delta -> -inf.
    sx, sv = 1.3, 0.9
    for delta in (-2.0, 0.0, 1.0, 4 * sx):
        p_x = sps.norm.pdf(delta, scale=sx) / sps.norm.cdf(delta / sx)
        flux = p_x * integrate.quad(lambda v: v * sps.norm.pdf(v, scale=sv), 0, np.inf)[0]
        assert elastic_impact_rate(delta, sx, sv) == pytest.approx(flux, rel=1e-8)
    rice = sv / sx / (2 * np.pi) * np.exp(-0.5 * 16)
    assert elastic_impact_rate(4 * sx, sx, sv) == pytest.approx(rice, rel=1e-4)
    rates = elastic_impact_rate(np.array([10.0, 20.0, 40.0]) * sx, sx, sv)
    assert rates[0] < 1e-20 and rates[2] == 0.0 and np.all(np.diff(rates) <= 0)
    far = elastic_impact_rate(np.array([-5.0, -50.0]) * sx, sx, sv)
    assert np.all(np.isfinite(far)) and far[1] > far[0] > 0


def test_line_power_is_the_sine_variance_at_every_resolution():
    """A sin(b0 t) carries variance A^2/2; Welch's peak height grows as 1/dbeta, the summed
    line power does not (within 1 %: the median background's noise over 9 bins)."""
    from vibroimpact.stats import line_power, welch_psd
    rng = np.random.default_rng(20261124)
    dt, amplitude, b0 = 0.1, 0.7, 1.0 / 1.1
    t = np.arange(1_000_000) * dt
    x = amplitude * np.sin(b0 * t + 0.4) + 0.5 * rng.standard_normal(t.size)
    peaks = []
    for nperseg in (1024, 4096, 16384):
        beta, S, _ = welch_psd(x, dt, nperseg)
        assert line_power(beta, S, b0) == pytest.approx(amplitude**2 / 2, rel=0.01)
        peaks.append(S.max())
    assert peaks[2] > 10 * peaks[0]       # the peak height is no measure of the line
    beta, S, _ = welch_psd(0.5 * rng.standard_normal(t.size), dt, 4096)
    assert abs(line_power(beta, S, b0)) < 0.005      # no line, no power
