"""Elastic impacts (eps = 1) under white noise: exact stationary results (issue 3).

For x'' + 2 zeta x' + x = w(tau), w white, and a rigid elastic wall at x = delta, the
stationary density is the wall-free Gaussian restricted to x <= delta (the elastic reflection
v -> -v preserves the Gaussian's symmetry in v), so the velocity stays N(0, sigma_v^2), the
approach velocity at impact is Rayleigh(sigma_v) and the impact rate is Rice's crossing rate
renormalised by the mass fraction below the wall. We check all four on simulated records.

The force here is piecewise linear between white samples at dt = 0.05, white to within
1 - sinc^4(beta dt/2) ~ 4e-4 at the resonance; sigma_x, sigma_v are computed from the exact
spectrum of that force (``psd_piecewise_linear``). Statistical tolerances are 4 standard
errors from batch means (20 batches of a correlated record) plus a 2 % allowance for the
residual non-whiteness at high frequency (it matters most for negative delta, where the mass
stays near the wall).
"""
import numpy as np
import pytest
from scipy import special

from vibroimpact import noise, simulate, stats

ZETA = 0.05
DT = 0.05
N_SAMPLES = 2_000_001
SYSTEMATIC = 0.02


@pytest.fixture(scope="module")
def white():
    spec = noise.NoiseSpec(kind="white", rms=1.0, dt=DT)
    r = noise.generate_array(spec, N_SAMPLES, seed=20261121)
    sigma_x, sigma_v = stats.linear_response_std(spec.psd_piecewise_linear, ZETA)
    return r, sigma_x, sigma_v


def _batch(x):
    b = stats.batch_means(np.asarray(x, dtype=float), 20)
    return b.mean, b.stderr


def _close(measured, stderr, expected, name):
    tol = 4.0 * stderr + SYSTEMATIC * abs(expected)
    assert abs(measured - expected) <= tol, \
        f"{name}: {measured:.5g} vs {expected:.5g} (tol {tol:.3g})"


@pytest.mark.parametrize("delta_over_sigma", [-0.5, 0.0, 1.0])
def test_elastic_white_noise(white, delta_over_sigma):
    r, sigma_x, sigma_v = white
    delta = delta_over_sigma * sigma_x
    res = simulate(zeta=ZETA, eps=1.0, delta=delta, noise=r, dt=DT, record_every=1)
    keep = res.grid_time > 200.0                      # discard the start from rest
    x = delta - res.a[keep]
    v = res.v[keep]
    t_total = res.t_end - 200.0
    # (1) displacement: Gaussian cut off at the wall -> its first two moments
    alpha = delta / sigma_x
    lam = np.exp(-0.5 * alpha**2) / np.sqrt(2 * np.pi) / special.ndtr(alpha)
    _close(*_batch(x), -sigma_x * lam, "mean x")
    _close(*_batch(x**2), sigma_x**2 * (1.0 - alpha * lam), "mean x^2")
    # (2) velocity stays N(0, sigma_v^2) whatever delta is
    _close(*_batch(v**2), sigma_v**2, "mean v^2")
    assert abs(np.mean(v)) < 4 * _batch(v)[1] + 0.01 * sigma_v
    # (3) approach velocity at impact: Rayleigh(sigma_v)
    u = res.impact_velocity[res.impact_time > 200.0]
    assert u.size > 5000
    _close(*_batch(u), sigma_v * np.sqrt(np.pi / 2), "mean u")
    _close(*_batch(u**2), 2.0 * sigma_v**2, "mean u^2")
    # (4) impact rate nu(delta): counts in 20 equal time batches
    counts, _ = np.histogram(res.impact_time, bins=20, range=(200.0, res.t_end))
    rates = counts / (t_total / 20)
    _close(rates.mean(), rates.std(ddof=1) / np.sqrt(20),
           stats.elastic_impact_rate(delta, sigma_x, sigma_v), "impact rate")
