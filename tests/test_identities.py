"""The power balance and the virial (docs/model.md, section 7.1): exact identities of a
stationary record, carried by every events dataset as a self-audit.

Each holds on every record up to a boundary term ([E]/T, [x v + zeta x^2]/T), so the
residual of an exact record is well inside its batch-means standard error; a wrong impact
record (velocities scaled by 1.1) leaves a bias that shows as many standard errors."""

import numpy as np
import pytest

from vibroimpact import Model, noise, simulate, stats
from vibroimpact.pipeline import cells, datasets
from vibroimpact.pipeline.study import Cell

# the random study of config/test.yaml: its noise, zeta, transient and batches
NOISE = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)
ZETA, TRANSIENT, B = 0.05, 100.0, 20
BINS = datasets.bin_edges(dict(v_after=dict(max=2.5, n=50), interval=dict(max=20.0, n=80),
                               ratio=dict(max=4.0, n=80)))


@pytest.fixture(scope="module")
def record():
    return noise.generate_array(NOISE, 400_001, seed=19740914)


@pytest.mark.parametrize("eps", [1.0, 0.5])
@pytest.mark.parametrize("delta, amplitude", [(1.0, 0.0), (0.5, 0.0), (0.0, 0.0),
                                              (-0.5, 0.0), (-1.0, 0.0), (0.25, 1.0)])
def test_the_identities_hold_to_their_standard_error(record, eps, delta, amplitude):
    model = Model.paper(ZETA, eps, delta, amplitude, 1 / 1.1)
    out = cells.event_statistics(record, NOISE.dt, model, transient=TRANSIENT, bins=BINS,
                                 n_batches=B)
    assert out["n_collisions"] > 1000
    for name in ("power", "virial"):
        res, se = out[f"{name}_residual"], out[f"{name}_residual_stderr"]
        assert 0.0 < se < 1e-2 * (out["power_input"] if name == "power" else out["virial_scale"])
        assert abs(res) < 3.0 * se, (name, res, se)


def _audit(res, r, eps, delta, amplitude=0.0, scale=1.0):
    """Residuals of a simulate() record from step 1000 to its end; impact velocities scaled
    by ``scale`` (a tampered record), and the boundary terms [E]/T, [x v + zeta x^2]/T."""
    dt, k0, n = NOISE.dt, 1000, r.size - 1
    x, v = delta - res.a, res.v
    batch = (np.arange(n - k0) * B) // (n - k0)
    u = scale * res.impact_velocity
    m = stats.flight_moments(k0, x[k0:n], v[k0:n], r[k0:], dt, zeta=ZETA, eps=eps, delta=delta,
                             amplitude=amplitude, beta_f=1 / 1.1, impact_time=res.impact_time,
                             impact_velocity=u, stick_start=res.stick_start,
                             stick_end=res.stick_end, batch=batch, n_batches=B)
    hit = res.impact_step >= k0
    b = batch[res.impact_step[hit] - k0]
    out = stats.identity_residuals(m, np.bincount(b, u[hit], B), np.bincount(b, u[hit] ** 2, B),
                                   np.bincount(batch, minlength=B) * dt, zeta=ZETA, eps=eps,
                                   delta=delta)
    T = (n - k0) * dt
    E = 0.5 * (x[n] ** 2 + v[n] ** 2 - x[k0] ** 2 - v[k0] ** 2) / T
    W = (x[n] * v[n] + ZETA * x[n] ** 2 - x[k0] * v[k0] - ZETA * x[k0] ** 2) / T
    return out, E, W


@pytest.mark.parametrize("eps, delta, amplitude", [(1.0, 0.5, 0.0), (1.0, -0.3, 0.0),
                                                   (1.0, 0.3, 1.0), (0.5, 0.0, 0.0),
                                                   (0.5, -0.5, 0.0), (0.5, 0.3, 1.0),
                                                   (0.0, -0.3, 0.0)])
def test_the_residual_is_the_boundary_term_to_round_off(record, eps, delta, amplitude):
    """The quadrature is exact: residual - boundary term is round-off, chatter tails summed
    in closed form and sticking included (docs/model.md, section 7.1)."""
    r = record[:100_001]
    res = simulate(ZETA, eps, delta, noise=r, dt=NOISE.dt, amplitude=amplitude, beta=1 / 1.1,
                   record_every=1)
    out, E, W = _audit(res, r, eps, delta, amplitude)
    assert abs(out.power - E) < 1e-12
    assert abs(out.virial - W) < 1e-12


@pytest.mark.parametrize("eps, delta, identity", [(0.5, 0.5, "power"), (0.5, -0.5, "power"),
                                                  (0.5, 0.5, "virial"), (1.0, -0.5, "virial"),
                                                  (1.0, 1.0, "virial")])
def test_a_tampered_impact_velocity_shows(record, eps, delta, identity):
    """Scaling every impact velocity by 1.1 moves the residual far beyond its error. The
    power balance does not read the velocities at eps = 1, the virial not at delta = 0."""
    res = simulate(ZETA, eps, delta, noise=record, dt=NOISE.dt, record_every=1)
    honest, _, _ = _audit(res, record, eps, delta)
    tampered, _, _ = _audit(res, record, eps, delta, scale=1.1)
    value = lambda o: (getattr(o, identity), getattr(o, f"{identity}_stderr"))
    assert abs(value(honest)[0]) < 3.0 * value(honest)[1]
    assert abs(value(tampered)[0]) > 5.0 * value(tampered)[1]


def test_chunks_do_not_change_the_residuals(record):
    """Sticking phases and chatter across chunk boundaries: the same integrals."""
    kw = dict(transient=TRANSIENT, t_end=10_000.0, bins=BINS)
    model = Model.paper(ZETA, 0.5, -0.5)
    whole = cells.event_statistics(record, NOISE.dt, model, **kw)
    parts = cells.event_statistics(record, NOISE.dt, model, **kw, chunk_size=777)
    for name in ("power_residual", "power_residual_stderr", "power_input", "virial_residual",
                 "virial_residual_stderr", "virial_scale"):
        assert parts[name] == pytest.approx(whole[name], rel=1e-9, abs=1e-14), name


def test_the_events_tile_carries_the_audit(record):
    out = cells.event_statistics(record, NOISE.dt, Model.paper(ZETA, 0.5, 0.0),
                                 transient=TRANSIENT, t_end=5000.0, bins=BINS)
    cell = Cell(index=0, i_inv_beta=0, i_delta=0, inv_beta=1.0, delta=0.0)
    ds = datasets.events_tile([cell], [out], BINS, {})
    for name in ("power_residual", "power_residual_stderr", "power_input", "virial_residual",
                 "virial_residual_stderr", "virial_scale"):
        assert ds[name].dims == ("cell",)
        assert ds[name].attrs["long_name"] and ds[name].attrs["units"] == "1"
        assert ds[name].values[0] == out[name]


def test_identity_residuals_of_given_sums():
    """The pure combination: two batches whose residuals are known by hand."""
    # rows v2, x2, fv, xf, push, tail, tail2; batches of length 2 and 2
    m = np.array([[1.0, 1.0], [0.5, 0.5], [0.3, 0.5], [0.2, 0.2], [0.4, 0.0],
                  [0.0, 0.1], [0.0, 0.01]])
    out = stats.identity_residuals(m, [1.0, 2.0], [2.0, 4.0], [2.0, 2.0], zeta=0.05, eps=0.5,
                                   delta=-0.5)
    power = np.array([0.3 - 0.1 - 0.375 * 2.0, 0.5 - 0.1 - 0.375 * 4.0 - 0.005]) / 2.0
    virial = np.array([1.0 - 0.5 + 0.2 + 0.5 * (1.5 + 0.4), 1.0 - 0.5 + 0.2 + 0.5 * (3.0 - 0.1)]
                      ) / 2.0
    assert out.power == pytest.approx(power.mean())
    assert out.virial == pytest.approx(virial.mean())
    assert out.power_stderr == pytest.approx(np.std(power, ddof=1) / np.sqrt(2.0))
    assert out.virial_stderr == pytest.approx(np.std(virial, ddof=1) / np.sqrt(2.0))
    assert (out.power_input, out.virial_scale, out.n_batches) == (0.2, 0.5, 2)
