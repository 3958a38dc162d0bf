"""Edge cases of the simulator found in use (regressions), each checked against physics."""
import numpy as np
import pytest

from vibroimpact import simulate


@pytest.mark.parametrize("r0", [-0.29, -1e-3, -1e-9])
def test_leaves_the_wall_from_rest_when_pulled(r0):
    """At rest on the wall (x0 = delta = 0) with f(0) - delta = r0 < 0 and sin(1.1 tau) on top.
    Before the fix the mass crept off in steps of 1e-15 and hit the per-step event limit.
    It must leave at once (no sticking at tau = 0) unless the pull reverses before any
    resolvable separation (r0 = -1e-9: f turns positive at tau ~ 1e-9), and never cross."""
    r = np.full(1001, r0)
    res = simulate(0.05, 0.5, 0.0, noise=r, dt=0.1, amplitude=1.0, beta=1.1, record_every=1)
    if r0 < -1e-6:
        assert res.stick_start.size == 0 or res.stick_start[0] > 0.0
        assert res.impact_time[0] > 0.0
    assert np.all(res.a >= -1e-12)
    assert res.n_impacts > 0


def test_negative_play_starts_pressed_and_stays_until_the_force_releases_it():
    """delta < 0 at rest in contact: stuck while f - delta > 0, released exactly at the root
    of the piecewise-linear force: f = 0 for tau <= 10, then falls by 0.01 per sample step
    (0.1 per unit time), so f - delta = 0 at tau = 10 + 0.5/0.1 = 15."""
    delta = -0.5
    r = np.concatenate([np.zeros(101), np.linspace(0.0, -1.0, 101)[1:]])
    res = simulate(0.05, 0.5, delta, noise=r, dt=0.1)
    assert res.stick_start[0] == 0.0
    assert res.stick_end[0] == pytest.approx(15.0, abs=1e-12)
    assert res.contact_time == pytest.approx(15.0, abs=1e-12)


def test_chunking_and_buffer_flushes_give_identical_results():
    """Streaming in chunks and flushing full event buffers mid-record (246k impacts, more than
    the 131k-event buffer) must not change a single bit, nor duplicate a recorded sample."""
    r = np.random.default_rng(0).standard_normal(300_001)
    a = simulate(0.05, 0.5, -0.5, noise=r, record_every=3)
    b = simulate(0.05, 0.5, -0.5, noise=r, record_every=3, chunk_size=999)
    assert a.n_impacts > 200_000
    assert a.a.size == 100_001 and np.array_equal(a.grid_time, (np.arange(100_001) * 3) * 0.1)
    for name in ("impact_time", "impact_velocity", "stick_start", "stick_end", "a", "v"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name


def test_elastic_micro_bounces_end_in_contact():
    """eps = 1 pressed on the wall: bounces shrink only by damping (no finite-time accumulation);
    the run must end (micro-bounces below ELASTIC_MICRO_FLIGHT are resting contact)."""
    res = simulate(0.6, 1.0, -0.6, np.zeros(401), 0.1, x0=-1.5)
    assert res.stuck_end and res.stick_start.size == 1
