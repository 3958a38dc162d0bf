"""Two elastic walls under white noise: the exact stationary results of a clearance (issue 35).

For x'' + 2 zeta x' + x = w(tau), w white, between elastic walls at x = delta and
x = delta - gap, the stationary density is the wall-free Gaussian cut to the clearance,
``N(x; 0, sigma_x^2) N(v; 0, sigma_v^2) / Z_x`` (docs/model.md, section 7, "A clearance
between two walls"): each wall's impact rate is ``nu_w = p_x(x_w) sigma_v / sqrt(2 pi) / Z_x``,
the approach speed at either wall is Rayleigh(sigma_v), the mean interval between impacts at
a wall is ``1 / nu_w``, and the displacement is the truncated Gaussian. Checked on a record
of the exact two-wall simulator, at walls placed so that the two rates differ by half.

Tolerances: 4 standard errors plus a systematic allowance. The errors come from the counts:
a rate's is ``sqrt(D N) / T`` (N impacts at the wall in T, D >= 1 the index of dispersion of
the counts in 20 equal stretches of time, 1 for a Poisson count), a mean's and a histogram
bin's are batch means over 20 batches (the impacts are correlated). The systematic part is
the force's: the piecewise-linear white force is correlated over one sample step h, and at
each reflection v flips while f does not, so for about h after an impact the force feeds the
rebound less than white noise would. That is a first-order bias in nu h (nu the impacts of
both walls per unit time), measured on the simulator at h = 0.05, 0.025, 0.0125
(delta = 0.3 sigma_x, gap = 0.8 sigma_x, nu = 0.94, four seeds each): about -2 nu h on
<u^2>, -1 nu h on <u>, -0.8 nu h on the rates (docs/model.md, section 7). The allowance is
3 nu h of each quantity (1.8 % here, with h = 0.0125 and nu = 0.49).
"""
import numpy as np
import pytest
from scipy import special

from vibroimpact import noise, simulate, stats

ZETA = 0.05
DT = 0.0125
N_SAMPLES = 8_000_001            # T = 1e5: about 3e4 and 2e4 impacts at the two walls
TRANSIENT = 200.0                # 10 / zeta: the start from rest forgotten
DELTA_OVER_SIGMA, GAP_OVER_SIGMA = 0.4, 1.4       # walls at +0.4 and -1.0 sigma_x
N_BATCHES = 20


def _close(measured, stderr, expected, allowance, name):
    tol = 4.0 * stderr + allowance
    assert abs(measured - expected) <= tol, \
        f"{name}: {measured:.5g} vs {expected:.5g} (tol {tol:.3g}, s.e. {stderr:.3g})"


@pytest.fixture(scope="module")
def clearance():
    spec = noise.NoiseSpec(kind="white", rms=1.0, dt=DT)
    r = noise.generate_array(spec, N_SAMPLES, seed=20261127)
    sigma_x, sigma_v = stats.linear_response_std(spec.psd_piecewise_linear, ZETA)
    delta, gap = DELTA_OVER_SIGMA * sigma_x, GAP_OVER_SIGMA * sigma_x
    res = simulate(ZETA, 1.0, delta, noise=r, dt=DT, gap=gap, eps_lower=1.0, record_every=8)
    return res, delta, gap, sigma_x, sigma_v


@pytest.mark.slow
def test_each_walls_rate_and_speed_density(clearance):
    res, delta, gap, sigma_x, sigma_v = clearance
    nu = stats.clearance_impact_rates(delta, gap, sigma_x, sigma_v)
    systematic = 3.0 * sum(nu) * DT
    assert nu[0] > 1.4 * nu[1]                        # the walls are told apart
    keep = res.impact_time > TRANSIENT
    edges = np.linspace(0.0, 4.0 * sigma_v, 21)
    for wall in (0, 1):
        at = keep & (res.impact_wall == wall)
        t, u = res.impact_time[at], res.impact_velocity[at]
        # the rate, its error from the count
        rate = stats.event_rate(t, TRANSIENT, res.t_end, N_BATCHES)
        assert rate.count > 15_000
        stderr = np.sqrt(max(rate.dispersion, 1.0) * rate.count) / rate.duration
        _close(rate.rate, stderr, nu[wall], systematic * nu[wall], f"rate at wall {wall}")
        _close(rate.mean_interval, stderr / rate.rate ** 2, 1.0 / nu[wall],
               systematic / nu[wall], f"mean interval at wall {wall}")
        # the approach speed: Rayleigh(sigma_v), its moments and its histogram
        for power, expected in ((1, sigma_v * np.sqrt(np.pi / 2)), (2, 2.0 * sigma_v ** 2)):
            b = stats.batch_means(u ** power, N_BATCHES)
            _close(b.mean, b.stderr, expected, systematic * expected,
                   f"mean u^{power} at wall {wall}")
        dens = stats.density(u, edges, total=u.size, n_batches=N_BATCHES)
        cdf = 1.0 - np.exp(-0.5 * (edges / sigma_v) ** 2)
        expected = np.diff(cdf) / np.diff(edges)                 # bin averages of the pdf
        peak = stats.rayleigh_pdf(sigma_v, sigma_v)
        for i in range(expected.size):
            _close(dens.density[i], dens.stderr[i], expected[i], systematic * peak,
                   f"speed density at wall {wall}, bin {i}")


@pytest.mark.slow
def test_the_displacement_is_the_gaussian_cut_to_the_clearance(clearance):
    """The truncated Gaussian's mean and variance, and the velocity's variance, from the
    record every 8 samples."""
    res, delta, gap, sigma_x, sigma_v = clearance
    keep = res.grid_time > TRANSIENT
    x, v = delta - res.a[keep], res.v[keep]
    assert x.min() >= delta - gap and x.max() <= delta
    a, b = (delta - gap) / sigma_x, delta / sigma_x
    Z = stats.clearance_mass(delta, gap, sigma_x)
    assert Z == pytest.approx(special.ndtr(b) - special.ndtr(a), rel=1e-12)
    phi = lambda z: np.exp(-0.5 * z * z) / np.sqrt(2.0 * np.pi)
    mean = sigma_x * (phi(a) - phi(b)) / Z
    second = sigma_x ** 2 * (1.0 + (a * phi(a) - b * phi(b)) / Z)
    nu = sum(stats.clearance_impact_rates(delta, gap, sigma_x, sigma_v))
    systematic = 3.0 * nu * DT
    for values, expected, name in ((x, mean, "mean x"), (x * x, second, "mean x^2"),
                                   (v * v, sigma_v ** 2, "mean v^2")):
        bm = stats.batch_means(values, N_BATCHES)
        _close(bm.mean, bm.stderr, expected, systematic * max(abs(expected), sigma_x ** 2),
               name)
    # the density itself (clearance_pdf) integrates to one on the clearance
    grid = np.linspace(delta - gap, delta, 2001)
    assert np.trapezoid(stats.clearance_pdf(grid, delta, gap, sigma_x), grid) == \
        pytest.approx(1.0, rel=1e-6)
