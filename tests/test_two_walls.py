"""The exact simulator with a second wall (a clearance): ``simulate(..., gap=, eps_lower=)``.

Checks against what does not share its code: an event-located DOP853 integration
(scipy's ``solve_ivp``), the releases' closed form, the mirror symmetry of the equation,
and the one-wall simulator itself in the limit of a far second wall (bit for bit).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from vibroimpact import simulate
from vibroimpact.model import Model

ZETA, DT = 0.05, 0.1


def _noise(seed, n, sigma=0.5):
    return sigma * np.random.default_rng(seed).standard_normal(n)


FIELDS = ("impact_time", "impact_velocity", "impact_step", "impact_offset", "stick_start",
          "stick_end", "a", "v")


@pytest.mark.parametrize("delta, eps, amplitude", [(0.5, 0.5, 0.0), (-0.5, 0.5, 0.0),
                                                   (0.0, 0.0, 0.0), (0.3, 0.5, 1.0)])
def test_a_far_second_wall_is_the_one_wall_simulator_bit_for_bit(delta, eps, amplitude):
    """gap = 1e6 is never reached (the response's rms is ~1): every field is identical, as
    are the counters and the end state; at delta = -0.5 the record chatters and sticks.
    One wall steps through ``slow_step_one``, two through the generic ``slow_step``: this
    holds the two step functions to the same arithmetic."""
    r = _noise(3, 100_001)
    kw = dict(noise=r, dt=DT, amplitude=amplitude, beta=1 / 1.1, record_every=3)
    one = simulate(ZETA, eps, delta, **kw)
    far = simulate(ZETA, eps, delta, gap=1e6, **kw)
    assert one.n_impacts > 100
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(far, name), getattr(one, name), err_msg=name)
    assert (far.n_chatter, far.contact_time, far.x_end, far.v_end, far.stuck_end) == (
        one.n_chatter, one.contact_time, one.x_end, one.v_end, one.stuck_end)
    assert not far.impact_wall.any() and not far.stick_wall.any()
    if delta < 0:
        assert one.stick_start.size > 10 and one.n_chatter > 10


@pytest.mark.parametrize("delta", [0.0, -0.5])
def test_a_far_second_wall_is_the_one_wall_simulator_in_a_partial_last_step(delta):
    """A record that ends inside a sample step: the driver's last, partial step goes through
    the one-wall step or the generic one as run_steps does, bit for bit the same; at
    delta = -0.5 the mass is stuck or chattering at some of the ends."""
    r = _noise(11, 3_001)
    ends = []
    for t_end in np.linspace(100.03, 299.97, 23):
        one = simulate(ZETA, 0.5, delta, noise=r, dt=DT, t_end=t_end)
        far = simulate(ZETA, 0.5, delta, noise=r, dt=DT, t_end=t_end, gap=1e6)
        for name in FIELDS[:6]:
            np.testing.assert_array_equal(getattr(far, name), getattr(one, name), err_msg=name)
        assert (far.x_end, far.v_end, far.stuck_end, far.contact_time, far.n_chatter) == (
            one.x_end, one.v_end, one.stuck_end, one.contact_time, one.n_chatter)
        ends.append(one.stuck_end)
    if delta < 0:
        assert any(ends) and not all(ends)


def test_the_mass_stays_between_the_walls_and_meets_both():
    r = _noise(5, 200_001, 0.8)
    res = simulate(ZETA, 0.5, 0.8, noise=r, dt=DT, gap=1.5, eps_lower=0.3, record_every=1)
    x = 0.8 - res.a
    assert x.max() <= 0.8 and x.min() >= 0.8 - 1.5
    counts = np.bincount(res.impact_wall, minlength=2)
    assert counts.min() > 50, counts
    assert np.all(res.impact_velocity > 0.0)
    assert res.model.gap == 1.5 and res.model.eps_lower == 0.3


def test_mirror_symmetry():
    """x -> -x with f -> -f maps the clearance [-g/2, g/2] onto itself and swaps the walls:
    the mirrored run has the same impacts at the other wall. The kernel follows each flight
    in the frame of the nearer wall and walks the lower wall in the mirrored frame, and IEEE
    arithmetic commutes with negation, so the two runs agree bit for bit (a(tau) = g - a to
    the rounding of that subtraction, one ulp of g)."""
    r = _noise(7, 100_001, 0.7)
    kw = dict(dt=DT, amplitude=0.6, beta=0.3, gap=1.2, record_every=1)
    a = simulate(ZETA, 0.3, 0.6, noise=r, **kw)
    b = simulate(ZETA, 0.3, 0.6, noise=-r, **{**kw, "amplitude": -0.6})
    # chatter closed and sticking at both walls (measured: 123 sequences, 62 and 61 rests)
    assert a.n_impacts > 1000 and a.n_chatter > 50 and set(a.stick_wall) == {0, 1}
    np.testing.assert_array_equal(a.impact_wall, 1 - b.impact_wall)
    np.testing.assert_array_equal(a.stick_wall, 1 - b.stick_wall)
    for name in ("impact_step", "impact_offset", "impact_velocity", "stick_start", "stick_end",
                 "v"):
        want = -getattr(a, name) if name == "v" else getattr(a, name)
        np.testing.assert_array_equal(getattr(b, name), want, err_msg=name)
    np.testing.assert_allclose(b.a, 1.2 - a.a, rtol=0, atol=np.spacing(1.2))
    # and so are the collisions (the physical rule reads the push into each wall)
    assert a.n_collisions < a.n_impacts
    np.testing.assert_array_equal(a.collision_wall, 1 - b.collision_wall)
    for name in ("collision_time", "collision_rebounds", "collision_stuck",
                 "collision_duration"):
        np.testing.assert_array_equal(getattr(b, name), getattr(a, name), err_msg=name)


def _dop853_impacts(zeta, eps, eps_lower, delta, gap, amplitude, beta, t_end):
    """Impacts of the forced two-wall oscillator by event-located DOP853 (rtol 1e-12):
    an independent integration with scipy's root finding at each wall."""
    lower = delta - gap

    def rhs(t, y):
        return [y[1], amplitude * math.sin(beta * t) - 2 * zeta * y[1] - y[0]]

    def up(t, y):
        return y[0] - delta
    up.terminal, up.direction = True, 1

    def down(t, y):
        return y[0] - lower
    down.terminal, down.direction = True, -1

    t, y, out = 0.0, [0.0, 0.0], []
    while t < t_end:
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-12, atol=1e-13,
                        events=(up, down))
        hits = [(ev[0], w) for w, ev in enumerate(sol.t_events) if ev.size]
        if not hits:
            break
        t, w = min(hits)
        v = sol.y_events[w][0][1]
        out.append((t, abs(v), w))
        y = [delta if w == 0 else lower, -(eps if w == 0 else eps_lower) * v]
        t = t + 1e-12   # step off the wall (the event's own root is at t)
    return np.array(out)


def test_impacts_at_both_walls_against_dop853():
    """A harmonic drive with two unequal walls (eps 0.8 above, 0.6 below); forty impacts.
    Tolerance 1e-9 in time and speed: DOP853 at rtol 1e-12 loses ~1e-12 per flight and
    places its events to ~1e-12, amplified along the sequence (measured: 4.5e-12 in time,
    1.0e-12 in speed); an unequal restitution used at the wrong wall moves the third impact
    by 0.13."""
    zeta, eps, eps_lower, delta, gap, A, beta = 0.05, 0.8, 0.6, 0.7, 1.6, 1.2, 1.3
    ref = _dop853_impacts(zeta, eps, eps_lower, delta, gap, A, beta, 120.0)
    res = simulate(zeta, eps, delta, noise=None, dt=0.05, amplitude=A, beta=beta, x0=0.0,
                   t_end=120.0, gap=gap, eps_lower=eps_lower)
    n = min(40, len(ref))
    assert n == 40 and res.n_impacts >= n
    assert set(ref[:n, 2]) == {0, 1}
    np.testing.assert_array_equal(res.impact_wall[:n], ref[:n, 2].astype(np.int8))
    np.testing.assert_allclose(res.impact_time[:n], ref[:n, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res.impact_velocity[:n], ref[:n, 1], rtol=0, atol=1e-9)


@pytest.mark.parametrize("side", [0, 1])
def test_plastic_walls_stick_and_release_where_the_force_crosses_the_wall(side):
    """eps = 0 at both walls, harmonic force alone, walls at +-0.3: the mass rests on the
    upper wall while f = sin(0.5 tau) >= 0.3 and on the lower one while f <= -0.3. A release
    is exact: there f equals the wall's position (|f - wall| to round-off, 1e-12), with f
    moving away from the wall."""
    beta, wall = 0.5, 0.3
    res = simulate(ZETA, 0.0, wall, noise=None, dt=0.1, amplitude=1.0, beta=beta, x0=0.0,
                   t_end=400.0, gap=2 * wall, eps_lower=0.0)
    mine = res.stick_wall == side
    assert mine.sum() >= 10
    sign = 1.0 if side == 0 else -1.0
    end = res.stick_end[mine][:-1]          # the last may be cut by the record's end
    f = np.sin(beta * end)
    np.testing.assert_allclose(f, sign * wall, rtol=0, atol=1e-12)
    assert np.all(sign * np.cos(beta * end) < 0)    # the force leaves the wall there
    assert res.contact_time > 0


def test_chatter_closes_at_the_lower_wall():
    """A drive that presses the mass into the lower wall: chatter sequences accumulate and
    stick there (the closed-form tail), at the lower wall's own restitution."""
    beta = 0.1
    res = simulate(ZETA, 0.9, 0.5, noise=None, dt=0.1, amplitude=1.0, beta=beta, x0=0.0,
                   t_end=600.0, gap=1.0, eps_lower=0.5, record_every=1)
    assert res.n_chatter >= 10
    lower = res.stick_wall == 1
    assert lower.sum() >= 5
    # each rest on the lower wall ends where the force rises through it, exactly
    end = res.stick_end[lower]
    end = end[end < 600.0]
    np.testing.assert_allclose(np.sin(beta * end), -0.5, rtol=0, atol=1e-12)
    assert np.all(np.cos(beta * end) > 0)
    x = 0.5 - res.a
    assert x.min() >= -0.5 and x.max() <= 0.5


@pytest.mark.parametrize("kwargs, field", [
    (dict(gap=0.0), "gap"), (dict(gap=-1.0), "gap"), (dict(gap=math.inf), "gap"),
    (dict(eps_lower=0.5), "eps_lower"), (dict(gap=1.0, eps_lower=1.5), "eps_lower"),
    (dict(gap=1.0, x0=-2.0), "x0"),
])
def test_bad_clearances_are_refused_naming_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        simulate(ZETA, 0.5, 0.5, noise=np.zeros(11), dt=0.1, **kwargs)


def test_the_static_start_is_on_the_nearer_wall_when_the_clearance_leaves_out_zero():
    res = simulate(ZETA, 0.5, 2.0, noise=np.zeros(101), dt=0.1, gap=1.0)
    assert res.params["x0"] == 1.0 and res.model == Model.paper(ZETA, 0.5, 2.0, gap=1.0)
