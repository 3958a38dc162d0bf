"""Energy-envelope averaging for eps near 1 (docs/model.md, section 7.2; issue 25).

(1) At eps = 1 the averaged density of the energy is the exact elastic one, so the theory
must reproduce `elastic_impact_rate`, the Rayleigh mean and density of the impact velocity
and the mean energy of the cut Gaussian to quadrature tolerance (1e-9 relative; the only
error is Simpson's rule on 4097 points, 1e-12 measured, and the velocity density's linear
interpolation on that grid, 1e-5).

(2) At eps = 0.95 it is compared with a simulation under white noise. Tolerance: 4
batch-means standard errors plus (1 - eps) relative, the theory's leading error (the
averaging is exact at eps = 1 for every zeta, so what it leaves out vanishes with 1 - eps).
The force is white samples at dt = 0.02 joined by straight lines: white to 1 - sinc^4(0.01)
~ 7e-5 at the resonance, and non-white on the scale of an impact to O(nu dt) ~ 1 %, well
inside the allowance (at dt = 0.1 the elastic record's mean energy at delta = 0 is 7 % low:
the force is correlated over a step, and each impact reverses v within it).
"""
import numpy as np
import pytest
from scipy import special

from vibroimpact import noise, simulate, stats

ZETA = 0.05


@pytest.mark.parametrize("S0", [0.05, 0.2])
def test_at_eps_one_the_averaging_is_the_exact_elastic_result(S0):
    sigma = np.sqrt(S0 / (4.0 * ZETA))
    delta = np.linspace(-3.0, 6.0, 37) * sigma
    th = stats.energy_envelope(delta, eps=1.0, zeta=ZETA, S0=S0)
    assert th.impact_rate.shape == delta.shape
    np.testing.assert_allclose(th.impact_rate, stats.elastic_impact_rate(delta, sigma, sigma),
                               rtol=1e-9)
    np.testing.assert_allclose(th.interval_mean * th.impact_rate, 1.0, rtol=1e-12)
    np.testing.assert_allclose(th.v_after_mean, sigma * np.sqrt(np.pi / 2.0), rtol=1e-9)
    # <H> = (<x^2> + sigma^2) / 2 with x the Gaussian cut at delta
    a = delta / sigma
    lam = np.exp(-0.5 * a * a) / np.sqrt(2.0 * np.pi) / special.ndtr(a)
    np.testing.assert_allclose(th.mean_energy, 0.5 * sigma**2 * (2.0 - a * lam), rtol=1e-9)
    w = np.linspace(0.0, 6.0 * sigma, 301)
    for d in (-1.0 * sigma, 0.0, 1.5 * sigma):
        np.testing.assert_allclose(
            stats.envelope_v_after_pdf(w, d, eps=1.0, zeta=ZETA, S0=S0),
            stats.rayleigh_pdf(w, sigma), rtol=0, atol=1e-5 / sigma)


@pytest.mark.parametrize("delta", [-0.5, 0.0, 1.0])
def test_energy_density_is_normalised_and_loses_energy_as_eps_falls(delta):
    S0 = 0.2
    grid = np.linspace(0.0, 40.0, 400_001)
    for eps in (1.0, 0.9, 0.5):
        p = stats.envelope_energy_pdf(grid, delta, eps=eps, zeta=ZETA, S0=S0)
        assert np.all(p[grid < 0.5 * min(delta, 0.0) ** 2] == 0.0)
        assert abs(np.trapezoid(p, grid) - 1.0) < 1e-4
    means = [stats.energy_envelope(delta, eps=eps, zeta=ZETA, S0=S0).mean_energy
             for eps in (1.0, 0.9, 0.5)]
    assert means[0] > means[1] > means[2]


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="eps"):
        stats.energy_envelope(0.0, eps=1.5, zeta=ZETA, S0=0.2)
    with pytest.raises(ValueError, match="S0"):
        stats.energy_envelope(0.0, eps=0.9, zeta=ZETA, S0=-1.0)
    with pytest.raises(ValueError, match="delta"):
        stats.envelope_v_after_pdf(1.0, [0.0, 1.0], eps=0.9, zeta=ZETA, S0=0.2)


DT = 0.02
EPS = 0.95


@pytest.fixture(scope="module")
def white():
    spec = noise.NoiseSpec(kind="white", rms=3.0, dt=DT)
    return noise.generate_array(spec, 5_000_001, seed=20261125), float(
        spec.psd_piecewise_linear(1.0))


def _close(measured, stderr, expected, name):
    tol = 4.0 * stderr + (1.0 - EPS) * abs(expected)
    assert abs(measured - expected) <= tol, \
        f"{name}: {measured:.5g} vs theory {expected:.5g} (tol {tol:.3g})"


@pytest.mark.parametrize("delta", [-0.5, 0.0, 1.0])
def test_near_elastic_simulation_agrees_with_the_averaging(white, delta):
    r, S0 = white
    th = stats.energy_envelope(delta, eps=EPS, zeta=ZETA, S0=S0)
    res = simulate(zeta=ZETA, eps=EPS, delta=delta, noise=r, dt=DT, record_every=5)
    t0 = 200.0                                       # ten decay times from rest
    keep = res.grid_time > t0
    x, v = delta - res.a[keep], res.v[keep]
    energy = stats.batch_means(0.5 * (x * x + v * v), 20)
    _close(energy.mean, energy.stderr, th.mean_energy, "<H>")
    after = res.impact_time > t0
    assert after.sum() > 5000
    speed = stats.batch_means(EPS * res.impact_velocity[after], 20)
    _close(speed.mean, speed.stderr, th.v_after_mean, "eps <V>")
    counts, _ = np.histogram(res.impact_time, bins=20, range=(t0, res.t_end))
    rates = counts / ((res.t_end - t0) / 20)
    _close(rates.mean(), rates.std(ddof=1) / np.sqrt(20), th.impact_rate, "nu")
