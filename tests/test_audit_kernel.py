"""The compiled self-audit (`impact.audit.audit_moments`) against its numpy reference
(`stats.flight_moments`, itself held to the exact identities in tests/test_identities.py).

Same integrals on real simulator records fed chunk by chunk as the events cells feed them
(far from the wall, impacts, sticking, chatter tails, a harmonic force, eps 0 and 1), and on
a hand-made record with events at sample instants and at the window's ends. Tolerance: each
row of the per-batch sums within 1e-12 of its largest magnitude (the two differ only in the
order of their sums, ~1e-14 measured)."""
import numpy as np
import pytest

from vibroimpact import noise, simulate, simulate_chunks, stats
from vibroimpact.impact.audit import audit_moments

NOISE = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)
ZETA, BETA_F, B = 0.05, 1 / 1.1, 7
RTOL = 1e-12


@pytest.fixture(scope="module")
def record():
    return noise.generate_array(NOISE, 60_001, seed=19740914)


def assert_rows_close(got, ref):
    scale = np.abs(ref).max(axis=1, keepdims=True)
    worst = np.abs(got - ref).max(axis=1, keepdims=True) / np.where(scale > 0, scale, 1.0)
    assert np.all(worst <= RTOL), worst.ravel()


def both(k_first, a, v, r, bounds, **kw):
    """The kernel's and the reference's moments of the same steps, in the batches of
    samples ``bounds[j] .. bounds[j + 1] - 1``."""
    got = audit_moments(k_first, a, v, r, NOISE.dt, batch_bounds=bounds, **kw)
    batch = np.searchsorted(bounds, k_first + np.arange(len(a)), side="right") - 1
    ref = stats.flight_moments(k_first, kw["delta"] - a, v, r, NOISE.dt, batch=batch,
                               n_batches=len(bounds) - 1, **kw)
    return got, ref


@pytest.mark.parametrize("delta, eps, amplitude", [(3.0, 0.5, 0.0), (0.5, 0.5, 0.0),
                                                   (0.0, 0.5, 0.0), (-0.5, 0.5, 0.0),
                                                   (-0.5, 0.8, 0.0), (0.25, 0.5, 1.0),
                                                   (-0.5, 0.5, 0.5), (-0.3, 0.0, 0.0),
                                                   (0.5, 1.0, 0.0), (-0.3, 1.0, 0.0)])
def test_the_kernel_equals_the_reference_chunk_by_chunk(record, delta, eps, amplitude):
    """As pipeline.cells feeds them: chunks of 2**13 samples, steps from 1234 on, an open
    sticking phase closed at each chunk's end, B batches."""
    dt, k_start, k_stop = NOISE.dt, 1234, record.size - 1
    params = dict(zeta=ZETA, eps=eps, delta=delta, amplitude=amplitude, beta_f=BETA_F)
    bounds = np.linspace(k_start, k_stop, B + 1).astype(np.int64)
    got = np.zeros((len(stats.identities.MOMENTS), B))
    ref = np.zeros_like(got)
    for chunk in simulate_chunks(ZETA, eps, delta, noise=record, dt=dt, amplitude=amplitude,
                                 beta=BETA_F, record_every=1, chunk_size=2**13):
        k0 = int(round(chunk.grid_time[0] / dt))
        lo, hi = max(k_start, k0), min(k_stop, k0 + chunk.grid_time.size)
        start, end = stats.close_open_phase(chunk.stick_start, chunk.stick_end,
                                            chunk.stuck_since, chunk.t_end)
        g, r = both(lo, chunk.a[lo - k0:hi - k0], chunk.v[lo - k0:hi - k0], record[lo:hi + 1],
                    bounds, **params, impact_time=chunk.impact_time,
                    impact_velocity=chunk.impact_velocity, stick_start=start, stick_end=end)
        got += g
        ref += r
    assert_rows_close(got, ref)
    assert np.all(np.abs(ref[:4]).max(axis=1) > 0)
    if delta <= 0.0 and 0.0 < eps < 1.0:               # sticking and chatter tails met
        assert np.all(ref[4:].max(axis=1) > 0)


def test_the_kernel_keeps_the_boundary_term_to_round_off(record):
    """The physical check of tests/test_identities.py on the kernel's integrals: residual
    minus boundary term is round-off, chatter tails and sticking included."""
    eps, delta, dt, k0 = 0.5, -0.3, NOISE.dt, 1000
    r = record[:40_001]
    n = r.size - 1
    res = simulate(ZETA, eps, delta, noise=r, dt=dt, record_every=1)
    bounds = np.linspace(k0, n, B + 1).astype(np.int64)
    batch = np.searchsorted(bounds, np.arange(k0, n), side="right") - 1
    m = audit_moments(k0, res.a[k0:n], res.v[k0:n], r[k0:], dt, zeta=ZETA, eps=eps,
                      delta=delta, impact_time=res.impact_time,
                      impact_velocity=res.impact_velocity, stick_start=res.stick_start,
                      stick_end=res.stick_end, batch_bounds=bounds)
    u = res.impact_velocity[res.impact_step >= k0]
    b = batch[res.impact_step[res.impact_step >= k0] - k0]
    out = stats.identity_residuals(m, np.bincount(b, u, B), np.bincount(b, u * u, B),
                                   np.bincount(batch, minlength=B) * dt, zeta=ZETA, eps=eps,
                                   delta=delta)
    x, v, T = delta - res.a, res.v, (n - k0) * dt
    E = 0.5 * (x[n] ** 2 + v[n] ** 2 - x[k0] ** 2 - v[k0] ** 2) / T
    W = (x[n] * v[n] + ZETA * x[n] ** 2 - x[k0] * v[k0] - ZETA * x[k0] ** 2) / T
    assert m[5].sum() > 0                                # chatter tails met
    assert abs(out.power - E) < 1e-12
    assert abs(out.virial - W) < 1e-12


@pytest.mark.parametrize("amplitude", [0.0, 0.7])
def test_events_at_sample_instants_and_at_the_window_ends(amplitude):
    """Hand-made steps 100 .. 109: an impact at a sample instant and one at the window's end,
    a tail (a slow rebound then an onset in the same step), a phase begun before the window,
    a zero-length phase, and a phase still going on after it."""
    dt, k0, n = NOISE.dt, 100, 10
    rng = np.random.default_rng(5)
    a, v, r = rng.normal(size=n), rng.normal(size=n), rng.normal(size=n + 1)
    t = lambda k, s=0.0: k * dt + s
    kw = dict(zeta=ZETA, eps=0.5, delta=0.2, amplitude=amplitude, beta_f=BETA_F,
              impact_time=[t(99, 0.05), t(102), t(103, 0.03), t(105, 0.02), t(105, 0.02),
                           t(110)],
              impact_velocity=[0.3, 0.4, 0.5, 1e-5, 1e-5, 0.2],
              stick_start=[t(99, 0.05), t(104, 0.04), t(105, 0.02), t(106, 0.01), t(108, 0.05)],
              stick_end=[t(100, 0.03), t(104, 0.04), t(106, 0.005), t(107, 0.02), t(111)])
    got, ref = both(k0, a, v, r, [90, 103, 103, 107, 112], **kw)   # an empty batch too
    assert ref[5].sum() > 0 and ref[4].sum() != 0
    assert_rows_close(got, ref)


def test_no_steps_and_bad_arguments():
    out = audit_moments(7, [], [], [0.0], 0.1, zeta=ZETA, eps=0.5, delta=0.0,
                        batch_bounds=[0, 5, 10])
    assert out.shape == (len(stats.identities.MOMENTS), 2) and not out.any()
    with pytest.raises(ValueError, match="r of n \\+ 1"):
        audit_moments(0, [0.0], [0.0], [0.0], 0.1, zeta=ZETA, eps=0.5, delta=0.0)
    with pytest.raises(ValueError, match="batch_bounds"):
        audit_moments(3, [0.0], [0.0], [0.0, 0.0], 0.1, zeta=ZETA, eps=0.5, delta=0.0,
                      batch_bounds=[0, 3])


def test_a_run_ends_before_an_onset_where_testing_each_step_ends_it():
    """`_before_onset` (the end of a run of free steps, from an estimate) against the test of
    each step in turn that it replaces, bit for bit: onsets on sample midpoints and one ulp
    either side, inside and beyond the run, far into a long record, and none (inf)."""
    from vibroimpact.impact.audit import _before_onset

    def scan(i, stop, onset, k_first, dt):
        j = i + 1
        while j < stop and (k_first + j) * dt + 0.5 * dt < onset:
            j += 1
        return j

    rng = np.random.default_rng(3)
    cases = 0
    for dt in (0.1, 0.05, 0.3):
        for k_first in (0, 9_437_184, 99_999_000):
            for _ in range(300):
                i = int(rng.integers(0, 2000))
                stop = i + 1 + int(rng.integers(0, 1100))
                mid = (k_first + i + int(rng.integers(-3, stop - i + 5))) * dt + 0.5 * dt
                for onset in (mid, np.nextafter(mid, -np.inf), np.nextafter(mid, np.inf),
                              mid + rng.uniform(-dt, dt), np.inf):
                    assert _before_onset(i, stop, onset, k_first, dt) == scan(
                        i, stop, onset, k_first, dt), (i, stop, onset, k_first, dt)
                    cases += 1
    assert cases == 3 * 3 * 300 * 5
