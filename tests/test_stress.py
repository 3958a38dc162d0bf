"""Stress: random parameters across the whole admissible range (slow suite).

Every run must return (never raise, never hang) and keep the invariants: x <= delta on the
recorded grid (1e-9: round-off of a near-grazing sample), finite samples, positive approach
velocities, non-decreasing impact times in full precision (step*dt + offset).
"""
import numpy as np
import pytest

from vibroimpact import simulate


@pytest.mark.slow
def test_random_parameters_never_fail():
    rng = np.random.default_rng(20261121)
    for _ in range(4000):
        zeta = rng.uniform(0.005, 0.9)
        eps = float(rng.choice([0.0, 1.0, rng.uniform(0.0, 1.0)]))
        delta = rng.uniform(-2.0, 2.0)
        amplitude = float(rng.choice([0.0, rng.uniform(0.0, 2.0)]))
        beta = rng.uniform(0.2, 4.0)
        dt = float(rng.choice([0.01, 0.1, 0.5]))
        r = rng.standard_normal(2001) * float(rng.choice([0.0, 0.1, 1.0, 3.0]))
        x0 = min(0.0, delta) if rng.random() < 0.5 else delta - abs(rng.normal())
        case = dict(zeta=zeta, eps=eps, delta=delta, noise=r, dt=dt, amplitude=amplitude,
                    beta=beta, x0=x0, v0=rng.normal())
        res = simulate(**case, record_every=1)
        assert np.all(np.isfinite(res.a)) and res.a.min() >= -1e-9, case
        assert np.all(res.impact_velocity > 0.0), case
        times = res.impact_step * dt + res.impact_offset
        assert np.all(np.diff(times) >= -1e-12), case
