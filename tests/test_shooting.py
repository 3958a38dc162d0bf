"""Periodic motions of any wall layout by Newton shooting (``vibroimpact.periodic_motions``).

Held against what shares no code with it: the closed-form (m/n) solver for one wall (its own
flights, Jacobians and search), the exact two-wall simulator (``vibroimpact.simulate``: its own
event searches, run forward from the motion's state), the mirror symmetry of symmetric stops,
and the determinant of the monodromy (phase-space contraction, known in closed form).
"""
import math

import numpy as np
import pytest

from vibroimpact import periodic_motions, periodic_orbits, simulate
from vibroimpact.model import Model
from vibroimpact.attractors import shooting
from vibroimpact.impact.layout import P_DELTA

ZETA, EPS = 0.05, 0.5           # config/config.yaml, orbits.harmonic (Fig. 16)
TYPES = ((1, 1), (2, 1), (1, 2), (1, 3), (3, 1))
# Agreement asked of shooting against the closed form (issue 35): both are converged to
# ~1e-12 on well-conditioned orbits (measured: <= 1e-14 on the 240 cells of a coarse grid).
AGREE = 1e-9


def closed_form(inv_beta, delta, stable_only=True, eps=EPS):
    beta = 1.0 / inv_beta
    return [o for m, n in TYPES for o in periodic_orbits(m, n, beta, delta, ZETA, eps)
            if o.stable or not stable_only]


def match(motions, orbit):
    """The motion holding the closed-form orbit's state at phase 0, and the distance."""
    x0 = np.array(orbit.state(0.0), dtype=float)
    best, dist = None, np.inf
    for mo in motions:
        if (mo.m, mo.n) != (orbit.m, orbit.n):
            continue
        d = float(np.min(np.max(np.abs(mo.phase0_states - x0), axis=1)))
        if d < dist:
            best, dist = mo, d
    return best, dist


def same_multipliers(a, b):
    return float(np.max(np.abs(np.sort_complex(a) - np.sort_complex(b))))


# points of the Fig. 16 grid (1/beta, delta) holding stable (1/1), (1/2), (2/1), (3/1) motions;
# (1.2, 3.0) is a (1/2) with lam = 0.962, slow to settle
FIG16_POINTS = [(1.0, 0.5), (0.4, 0.6), (1.2, 0.3), (1.6, 0.3), (1.0, -0.3), (2.2, 1.2),
                (1.2, 3.0), (0.5, 0.3)]


@pytest.mark.parametrize("inv_beta, delta", FIG16_POINTS)
def test_one_wall_every_stable_closed_form_motion_is_found(inv_beta, delta):
    model = Model.paper(ZETA, EPS, delta, 1.0, 1.0 / inv_beta)
    motions = periodic_motions(model, (1, 2, 3))
    expected = closed_form(inv_beta, delta)
    assert expected, "the point was chosen to hold a stable motion"
    for orbit in expected:
        mo, dist = match(motions, orbit)
        assert mo is not None and dist <= AGREE, (orbit.m, orbit.n, dist)
        assert same_multipliers(mo.multipliers, orbit.multipliers) <= AGREE
        assert mo.stable and mo.admissible and mo.counts == (orbit.m, 0)
        # the same rotation: the earliest impact phase in the first forcing cycle
        assert np.max(np.abs(mo.state - np.array(orbit.state(0.0), dtype=float))) <= AGREE
        np.testing.assert_allclose(np.sort(np.mod(mo.impact_time, mo.period)),
                                   np.sort(np.mod(orbit.impact_times, mo.period)), atol=AGREE)
    # and conversely: every stable impact motion shooting finds of these types is a closed-form one
    for mo in motions:
        if mo.stable and (mo.m, mo.n) in TYPES:
            assert any(match([mo], o)[1] <= AGREE for o in expected), mo.name


@pytest.mark.parametrize("eps, inv_beta, delta", [
    (0.0, 1.2, 1.75), (0.0, 2.4, 1.0),                    # plastic: each impact leaves v = 0
    (1.0, 1.2, 0.5), (1.0, 1.5, 0.0), (1.0, 1.5, 1.5),    # elastic, coexisting stable motions
])
def test_plastic_and_elastic_walls(eps, inv_beta, delta):
    model = Model.paper(ZETA, eps, delta, 1.0, 1.0 / inv_beta)
    motions = periodic_motions(model, (1, 2, 3))
    expected = closed_form(inv_beta, delta, eps=eps)
    assert expected
    for orbit in expected:
        mo, dist = match(motions, orbit)
        assert mo is not None and dist <= AGREE, (orbit.m, orbit.n, dist)
        assert same_multipliers(mo.multipliers, orbit.multipliers) <= AGREE


@pytest.mark.parametrize("inv_beta, delta", [(0.4, 0.3), (0.4, 0.6)])
def test_unstable_motions_from_their_seeds(inv_beta, delta):
    """Newton converges to the unstable closed-form orbits from near their states (no
    settling: an unstable motion is no attractor)."""
    unstable = [o for o in closed_form(inv_beta, delta, stable_only=False) if not o.stable]
    assert unstable
    model = Model.paper(ZETA, EPS, delta, 1.0, 1.0 / inv_beta)
    for orbit in unstable:
        seed = np.array(orbit.state(0.0), dtype=float) + 1e-4
        motions = periodic_motions(model, orbit.n, seeds=[seed])
        mo, dist = match(motions, orbit)
        assert mo is not None and dist <= AGREE and not mo.stable
        assert same_multipliers(mo.multipliers, orbit.multipliers) <= AGREE


def test_symmetric_stops_give_the_antisymmetric_motion():
    """delta = g/2, gap = g, equal eps: the (1,1)/1 motion has x(t + T/2) = -x(t)."""
    g = 2.0
    model = Model.paper(ZETA, EPS, g / 2, 1.0, 1.0, gap=g)
    motions = [mo for mo in periodic_motions(model, 1) if mo.name == "(1,1)/1"]
    assert len(motions) == 1
    mo = motions[0]
    half = mo.period / 2
    np.testing.assert_allclose(mo.state_at(half), -mo.state, rtol=0, atol=1e-10)
    np.testing.assert_allclose(mo.state_at(0.3 + half), -mo.state_at(0.3), rtol=0, atol=1e-10)
    assert sorted(mo.impact_wall) == [0, 1]
    assert abs(abs(mo.impact_time[1] - mo.impact_time[0]) - half) <= 1e-10
    assert abs(mo.impact_velocity[1] - mo.impact_velocity[0]) <= 1e-10
    assert mo.stable and mo.admissible and not mo.grazing


@pytest.mark.parametrize("model", [
    Model.paper(ZETA, EPS, 0.5, 1.0, 1.0),
    Model.paper(ZETA, EPS, 1.0, 1.0, 1.0, gap=2.0),
    Model.paper(ZETA, 0.7, 1.5, 1.0, 1 / 1.4, gap=3.0, eps_lower=0.3),
    Model.paper(0.1, 0.8, 0.5, 1.3, 1 / 0.9, gap=1.2, eps_lower=0.6),
])
def test_monodromy_determinant(model):
    """det M = prod over the period's impacts of eps_w^2, times exp(-2 zeta z) (saltation
    det eps_w^2, flight det exp(-2 zeta s))."""
    motions = periodic_motions(model, (1, 2))
    assert len(motions) > 0 and any(mo.m > 0 for mo in motions)
    eps_w = np.array([model.eps, model.eps_lower or 0.0])
    for mo in motions:
        expected = np.prod(eps_w[mo.impact_wall] ** 2) * math.exp(-2 * model.zeta * mo.period)
        assert abs(np.linalg.det(mo.monodromy) - expected) <= 1e-10 * expected
        assert abs(np.prod(mo.multipliers) - expected) <= 1e-10 * expected


@pytest.mark.parametrize("inv_beta, delta", [(1.0, 0.5), (1.6, 1.0), (0.5, 0.3), (1.2, 0.3)])
def test_far_second_wall_gives_the_one_wall_motions(inv_beta, delta):
    one = periodic_motions(Model.paper(ZETA, EPS, delta, 1.0, 1.0 / inv_beta), (1, 2))
    far = periodic_motions(Model.paper(ZETA, EPS, delta, 1.0, 1.0 / inv_beta, gap=1e6), (1, 2))
    assert len(one) == len(far) > 0
    for a, b in zip(one, far):
        assert a.name == b.name and b.counts[1] == 0
        for field in ("state", "impact_time", "impact_velocity", "multipliers", "monodromy"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), field
        # the far wall only adds the distance of the flights' minima to it
        assert b.margin == a.margin or (math.isinf(a.margin) and b.margin > 1e5)


def test_two_wall_motions_against_the_simulator():
    """The exact simulator, started on the motion, repeats its impacts; its finite differences
    give the monodromy."""
    zeta, eps, eps_lower, delta, gap, beta = 0.05, 0.6, 0.4, 1.0, 2.5, 1 / 1.3
    model = Model.paper(zeta, eps, delta, 1.0, beta, gap=gap, eps_lower=eps_lower)
    motions = [mo for mo in periodic_motions(model, (1, 2)) if mo.m > 0]
    assert any(mo.counts[0] and mo.counts[1] for mo in motions)

    def run(x0, v0, periods, mo):
        return simulate(zeta, eps, delta, None, dt=mo.period / (64 * mo.n), amplitude=1.0,
                        beta=beta, x0=x0, v0=v0, t_end=periods * mo.period, gap=gap,
                        eps_lower=eps_lower)

    for mo in motions:
        r = run(*mo.state, 3, mo)
        k = 3 * mo.m
        assert r.n_impacts == k and r.n_chatter == 0
        times = np.concatenate([mo.impact_time + j * mo.period for j in range(3)])
        np.testing.assert_allclose(r.impact_time, times, rtol=0, atol=1e-9)
        np.testing.assert_allclose(r.impact_velocity, np.tile(mo.impact_velocity, 3), rtol=0,
                                   atol=1e-9)
        assert np.array_equal(r.impact_wall, np.tile(mo.impact_wall, 3))
        # central differences of the simulator's one-period map (h^2 truncation ~1e-10,
        # round-off ~1e-15/h ~ 1e-9)
        h = 1e-6
        fd = np.empty((2, 2))
        for j in range(2):
            dx = np.zeros(2)
            dx[j] = h
            p = run(*(mo.state + dx), 1, mo)
            m = run(*(mo.state - dx), 1, mo)
            fd[:, j] = (np.array([p.x_end, p.v_end]) - np.array([m.x_end, m.v_end])) / (2 * h)
        np.testing.assert_allclose(mo.monodromy, fd, rtol=0,
                                   atol=1e-6 * np.max(np.abs(fd)))


@pytest.mark.parametrize("depth", [1e-10, 1e-13])
def test_grazing_is_not_jumped_over(depth):
    """A flight that pokes ``depth`` above the wall and comes back (both ends of the flight
    below the wall) hits it; one that stays ``depth`` below does not, with that margin."""
    model = Model.paper(0.05, 0.5, 1.0, 0.0, 1.0)      # unforced: x = e^-zs sin(wd s) / wd
    wd = math.sqrt(1 - model.zeta ** 2)
    s_max = math.atan2(wd, model.zeta) / wd
    x_max = math.exp(-model.zeta * s_max) * math.sin(wd * s_max) / wd
    length = 6.0
    res = np.empty(3)
    stack = np.empty((shooting.STACK, 2))
    for above in (True, False):
        P = shooting._Flow(model, 1).P
        wall = x_max - depth if above else x_max + depth
        P[P_DELTA] = wall
        fit = shooting._fit(0.0, 0.0, 1.0, P)
        assert shooting._eval(length, *fit, P)[0] < wall - 1e-3
        shooting._first_contact(0.0, 0.0, 1.0, length, P, stack, res)
        if above:
            assert res[1] == 0 and abs(res[0] - s_max) < 1e-4
            assert abs(shooting._eval(res[0], *fit, P)[0] - wall) < 1e-15
        else:
            assert res[1] == -1 and res[0] == length
            assert abs(res[2] - depth) < 1e-14


def test_sticking_and_chatter_are_reported_not_followed():
    # 1/beta = 2.4, delta = 0.2: every start settles onto an impact-stick motion
    model = Model.paper(ZETA, EPS, 0.2, 1.0, 1 / 2.4)
    found = periodic_motions(model, 1)
    assert len(found) == 0 and found.skipped
    assert {s.kind for s in found.skipped} == {"sticking"}
    # Newton from a seed of that motion meets the chatter and stops
    seeded = periodic_motions(model, 1, seeds=[(0.2 - 1e-3, 0.0)])
    assert len(seeded) == 0 and [s.kind for s in seeded.skipped] == ["chatter"]


def test_shorter_periods_are_left_to_their_own_n():
    model = Model.paper(ZETA, EPS, 0.5, 1.0, 1.0)
    two = periodic_motions(model, 2)
    assert all(mo.n == 2 for mo in two)
    assert "shorter_period" in {s.kind for s in two.skipped}


@pytest.mark.parametrize("kwargs, field", [
    (dict(model=(0.05, 0.5, 1.0), n=1), "model"),
    (dict(n=0), "n"),
    (dict(n=1.5), "n"),
    (dict(n=1, seeds=[1.0, 2.0]), "seeds"),
    (dict(n=1, seeds=[(5.0, 0.0)]), "seeds"),
    (dict(n=1, starts=[(np.nan, 0.0)]), "starts"),
])
def test_bad_input_names_the_field(kwargs, field):
    kwargs = {"model": Model.paper(ZETA, EPS, 1.0, 1.0, 1.0), **kwargs}
    with pytest.raises(ValueError, match=field):
        periodic_motions(**kwargs)


@pytest.mark.slow
def test_a_whole_fig16_row():
    """Every stable closed-form motion of a Fig. 16 row (1/beta = 1.2, 226 plays) is found."""
    inv_beta = 1.2
    for delta in np.round(np.arange(-1.5, 3.0 + 1e-9, 0.02), 10):
        model = Model.paper(ZETA, EPS, delta, 1.0, 1.0 / inv_beta)
        motions = periodic_motions(model, (1, 2, 3))
        for orbit in closed_form(inv_beta, delta):
            mo, dist = match(motions, orbit)
            assert mo is not None and dist <= AGREE, (delta, orbit.m, orbit.n, dist)
            assert same_multipliers(mo.multipliers, orbit.multipliers) <= AGREE


def test_derivative_bound_holds_on_random_flights():
    """The bracket bound of |x''|, |x'''| (docs/model.md, section 8.8) is a bound: never below
    the maximum over 400 samples of the bracket, on random flights, forces and brackets."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        model = Model.paper(rng.uniform(0.01, 0.5), 0.5, 1.0, rng.uniform(-2, 2),
                            rng.uniform(0.2, 5))
        P = shooting._Flow(model, 1).P
        th0, c1, c2 = shooting._fit(rng.uniform(0, 20), rng.uniform(-3, 1), rng.uniform(-5, 5),
                                    P)
        lo, h = rng.uniform(0, 10), rng.uniform(0, 1.5)
        vals = np.array([shooting._eval(s, th0, c1, c2, P)
                         for s in np.linspace(lo, lo + h, 400)])
        for k in (2, 3):
            bound = shooting._bound(k, lo, h, th0, math.atan2(c1, c2), math.hypot(c1, c2), P)
            assert np.max(np.abs(vals[:, k])) <= bound * (1 + 1e-12)


@pytest.mark.parametrize("g, inv_beta", [(3.0, 1.4), (2.0, 0.6), (1.0, 2.0)])
def test_symmetric_stops_give_mirror_pairs(g, inv_beta):
    """With symmetric stops, y(tau) = -x(tau + pi/beta) is a motion whenever x is (the force
    changes sign over half a cycle), with the walls' counts swapped; the default starts are a
    mirror-symmetric grid, so the mirror of every motion found is found."""
    model = Model.stops(ZETA, g, 0.0, eps=EPS, amplitude=1.0, beta=1.0 / inv_beta)
    motions = periodic_motions(model, (1, 2))
    assert len(motions) > 0
    for mo in motions:
        mirror = -mo.state_at(math.pi / model.beta)
        twins = [o for o in motions if o.n == mo.n and o.counts == mo.counts[::-1]]
        dist = min(np.min(np.max(np.abs(o.phase0_states - mirror), axis=1)) for o in twins)
        assert dist <= 1e-9, (mo.name, dist)
