"""A restitution that falls with the impact speed, eps(u) = eps / (1 + |u| / speed_scale),
checked against references that share none of the simulator's code but the law itself.

- The law's own consequences: its derivative against a finite difference, its ratio, the range
  the chatter proof uses, Newton's law as the limit ``speed_scale = inf`` to the bit.
- The simulator against the 34-digit event-located reference integration
  (:func:`vibroimpact.validation.reference.reference_impacts`) run with the same law: impact
  times and speeds on the prefix that a 53-bit run of the reference still reproduces, and the
  sticking onsets that close chatter sequences (the chatter proof, with the law's range).
- The shooting solver's periodic motion under the law against scipy's DOP853 with event
  location (the flow map returns to the state; the monodromy equals finite differences of
  that independent flow), and the monodromy's determinant against the law's saltation.
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from vibroimpact import model as law
from vibroimpact.attractors.shooting import periodic_motions
from vibroimpact.impact.simulate import simulate, simulate_model
from vibroimpact.model import Model
from vibroimpact.validation.reference import (agreeing_prefix, chatter_tail_mask,
                                              comparable_impacts, reference_impacts)

ZETA, DT = 0.05, 0.1
# the reference and the simulator agree to TOL on well-conditioned impacts, as for Newton's law
# (tests/test_simulate_reference.py: float64 computes an impact to ~1e-13; 1e-9 leaves room for
# the amplification of round-off along a sequence); X_ERR the float64 position error near the
# wall, U_TAIL the speed below which chatter tails are compared by their accumulation point
TOL, X_ERR, U_TAIL = 1e-9, 1e-14, 1e-4


@pytest.mark.parametrize("a", [0.0, 0.3, 2.0])
@pytest.mark.parametrize("eps", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("u", [1e-3, 0.7, 4.0, -2.5])
def test_the_law_and_its_consequences_agree(a, eps, u):
    h = 1e-6 * max(1.0, abs(u))
    fd = (law.rebound_velocity(eps, u + h, a) - law.rebound_velocity(eps, u - h, a)) / (2 * h)
    # a central difference of a law smooth away from u = 0: error O(h^2) + 1e-16 / h
    assert law.rebound_derivative(eps, u, a) == pytest.approx(fd, rel=1e-8, abs=1e-9)
    assert law.rebound_ratio(eps, u, a) * u == pytest.approx(law.rebound_velocity(eps, u, a),
                                                             rel=1e-15, abs=1e-300)
    assert -law.rebound_ratio(eps, u, a) == pytest.approx(eps / (1 + a * abs(u)), rel=1e-15)
    lo, hi = law.restitution_range(eps, a, 2 * abs(u))
    speeds = np.linspace(0, 2 * abs(u), 101)
    e = -law.rebound_ratio(eps, speeds, a)
    assert np.all(e >= lo * (1 - 1e-15)) and np.all(e <= hi)
    assert e[0] == hi and e[-1] == pytest.approx(lo, rel=1e-15)


def test_newton_is_the_infinite_speed_scale_to_the_bit():
    rng = np.random.default_rng(5)
    for eps, u in zip(rng.uniform(0, 1, 100), rng.normal(0, 3, 100)):
        assert law.rebound_velocity(eps, u, 0.0) == -eps * u
        assert law.rebound_derivative(eps, u, 0.0) == -eps
        assert law.rebound_ratio(eps, u, 0.0) == -eps
        assert law.restitution_range(eps, 0.0, abs(u)) == (eps, eps)
    assert law.Restitution(0.5).a == 0.0 and law.Restitution(0.5, 4.0).a == 0.25
    noise = np.random.default_rng(2).normal(size=4001)
    a = simulate(ZETA, 0.5, 0.0, noise, DT)
    b = simulate_model(Model.paper(ZETA, 0.5, 0.0, speed_scale=math.inf), noise, DT)
    for name in ("impact_time", "impact_velocity", "stick_start", "stick_end"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert "speed_scale" not in b.params


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), "fast", True])
def test_a_bad_speed_scale_names_the_field(bad):
    with pytest.raises(ValueError, match="speed_scale must be a real number > 0, or inf"):
        Model.paper(ZETA, 0.5, 0.2, speed_scale=bad)
    with pytest.raises(ValueError, match="speed_scale_lower needs a second wall"):
        Model.paper(ZETA, 0.5, 0.2, speed_scale_lower=1.0)


def _sim_impacts(res):
    tail = np.array(chatter_tail_mask(res.impact_time, res.impact_velocity, res.stick_start,
                                      res.stick_end, U_TAIL), dtype=bool)
    return res.impact_time[~tail], res.impact_velocity[~tail]


# (eps, delta, noise rms, amplitude, beta, speed_scale, seed, least impacts compared)
CASES = {
    "random, chatter at the wall": (0.5, 0.0, 1.0, 0.0, 1.0, 0.5, 12, 25),
    "random, below the rest": (0.8, -0.5, 1.0, 0.0, 1.0, 2.0, 13, 20),
    "harmonic and noise": (0.5, 0.3, 0.29, 1.0, 0.8, 1.0, 14, 15),
}


@pytest.mark.parametrize("case", list(CASES))
def test_simulator_agrees_with_the_reference_under_the_law(case):
    eps, delta, rms, amp, beta, scale, seed, least = CASES[case]
    noise = rms * np.random.default_rng(seed).standard_normal(601)
    kw = dict(amplitude=amp, beta=beta, max_impacts=250, speed_scale=scale)
    ref = reference_impacts(ZETA, eps, delta, noise, DT, dps=34, **kw)
    ref53 = reference_impacts(ZETA, eps, delta, noise, DT, prec=53, **kw)
    n = agreeing_prefix(ref, ref53, tol=TOL / 10, u_tail=U_TAIL)
    assert n >= least, f"only {n} well-conditioned impacts: the case tests too little"
    res = simulate_model(Model.paper(ZETA, eps, delta, amp, beta, speed_scale=scale), noise, DT)
    t_sim, u_sim = _sim_impacts(res)
    t_ref, u_ref, a_ref = (np.array(v[:n], dtype=float) for v in comparable_impacts(ref, U_TAIL))
    assert t_sim.size >= n
    tol_t = TOL + X_ERR / u_ref
    tol_u = TOL + X_ERR * np.abs(a_ref) / u_ref ** 2
    assert np.all(np.abs(t_sim[:n] - t_ref) <= tol_t)
    assert np.all(np.abs(u_sim[:n] / u_ref - 1) <= tol_u)
    # the sticking onsets closing chatter sequences (the chatter proof with the law's range)
    # and the releases before the last impact compared, to 1e-8 as for Newton's law
    ref_ss = [float(s) for s in ref["stick_start"] if s < t_ref[-1]]
    ref_se = [float(s) for s in ref["stick_end"]][:len(ref_ss)]
    if case == "random, chatter at the wall":
        closed = [c for c in ref["chatter_end"] if c < t_ref[-1]]
        assert closed and res.n_chatter >= len(closed), "no chatter sequence compared"
    np.testing.assert_allclose(res.stick_start[:len(ref_ss)], ref_ss, rtol=0, atol=1e-8)
    np.testing.assert_allclose(res.stick_end[:len(ref_se)], ref_se, rtol=0, atol=1e-8)
    # the collisions' rebounds count the law's rebound speeds
    col = res.collisions
    speed = res.model.restitution(res.impact_velocity) * res.impact_velocity
    assert np.array_equal(col.rebounds, np.add.reduceat(
        (speed >= res.rebound_floor).astype(np.int64), col.first))


def test_two_walls_each_with_its_law_agree_with_the_reference_in_the_mirror():
    """The second wall's law runs in the mirrored frame: a wall below the mass with
    speed_scale_lower hit by -x is the reference's wall above it with that law."""
    noise = np.random.default_rng(21).standard_normal(601)
    m = Model.paper(ZETA, 0.6, 3.0, gap=3.4, eps_lower=0.5, speed_scale=5.0,
                    speed_scale_lower=0.4)
    res = simulate_model(m, noise, DT)
    ref = reference_impacts(ZETA, 0.5, 0.4, -noise, DT, dps=34, max_impacts=250,
                            speed_scale=0.4)
    ref53 = reference_impacts(ZETA, 0.5, 0.4, -noise, DT, prec=53, max_impacts=250,
                              speed_scale=0.4)
    n = agreeing_prefix(ref, ref53, tol=TOL / 10, u_tail=U_TAIL)
    assert n >= 10
    t_ref = np.array(comparable_impacts(ref, U_TAIL)[0][:n], dtype=float)
    assert not np.any(res.impact_wall[res.impact_time <= t_ref[-1]] == 0), "the upper wall is far"
    t_sim, u_sim = _sim_impacts(res)
    np.testing.assert_allclose(t_sim[:n], t_ref, rtol=0, atol=1e-8)


def _flow(model, state, t0, t1):
    """The exact flow of x'' + 2 zeta x' + x = A sin(beta t) with impacts at x = delta by the
    model's law, by DOP853 with event location (scipy), from (t0, state) to t1."""
    zeta, A, beta, delta = model.zeta, model.amplitude, model.beta, model.delta
    wall = model.walls[0].law

    def rhs(t, y):
        return [y[1], A * math.sin(beta * t) - 2 * zeta * y[1] - y[0]]

    def hit(t, y):
        return y[0] - delta
    hit.terminal, hit.direction = True, 1
    t, y = t0, np.array(state, float)
    while t < t1:
        sol = solve_ivp(rhs, (t, t1), y, method="DOP853", rtol=1e-13, atol=1e-14, events=hit)
        if sol.status == 1:
            t, y = sol.t_events[0][0], sol.y_events[0][0].copy()
            y[0] = delta
            y[1] = wall.rebound(y[1])
        else:
            t, y = t1, sol.y[:, -1]
    return y


@pytest.mark.parametrize("inv_beta, impacts", [(1.0, 1), (1.4, 3)])
def test_a_periodic_motion_under_the_law_against_an_independent_flow(inv_beta, impacts):
    m = Model.paper(ZETA, 0.7, 0.3, 1.0, 1.0 / inv_beta, speed_scale=1.5)
    found = [p for p in periodic_motions(m, 1).motions if p.stable
             and p.counts == (impacts, 0)]
    assert found, f"no stable motion of {impacts} impacts a period"
    p = found[0]
    T = 2 * math.pi / m.beta
    # a period of the independent flow returns to the state (DOP853 at rtol 1e-13 over one
    # period with one located impact: ~1e-10)
    np.testing.assert_allclose(_flow(m, p.state, 0.0, T), p.state, rtol=0, atol=1e-8)
    # the monodromy against central differences of that flow (h = 1e-5: O(h^2) ~ 1e-10 plus
    # the integrator's 1e-12 / h ~ 1e-7)
    h, fd = 1e-5, np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        fd[:, j] = (_flow(m, p.state + e, 0.0, T) - _flow(m, p.state - e, 0.0, T)) / (2 * h)
    np.testing.assert_allclose(p.monodromy, fd, rtol=0, atol=1e-5)
    # det = prod (R R' / u) exp(-2 zeta T): the law's saltation, not eps^2
    u = p.impact_velocity
    eps_u = m.restitution(u)
    det = np.prod(eps_u * -law.rebound_derivative(m.eps, u, m.walls[0].law.a)) * math.exp(
        -2 * ZETA * T)
    assert np.linalg.det(p.monodromy) == pytest.approx(det, rel=1e-9)
    assert not math.isclose(det, m.eps ** 2 * math.exp(-2 * ZETA * T), rel_tol=1e-3)


# --- the law in the statistics and the workflow ------------------------------------------------

def _bins():
    from vibroimpact.pipeline import datasets

    return datasets.bin_edges(dict(v_after=dict(max=2.5, n=50), interval=dict(max=20.0, n=80),
                                   ratio=dict(max=4.0, n=80)))


@pytest.fixture(scope="module")
def record():
    from vibroimpact import noise

    spec = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)
    return noise.generate_array(spec, 400_001, seed=19740914)


@pytest.mark.parametrize("delta, amplitude, gap", [(0.0, 0.0, None), (-0.5, 0.0, None),
                                                   (0.25, 1.0, None), (1.0, 0.0, 2.0)])
def test_the_energy_and_momentum_balances_hold_under_the_law(record, delta, amplitude, gap):
    """The self-audit's identities (docs/model.md 7.1) with each impact's loss by the law:
    ``(1 - eps(u)^2) u^2 / 2`` of energy, ``(1 + eps(u)) u`` of momentum. They hold to their
    standard errors (3 s.e., as for Newton's law in tests/test_identities.py); the same
    record's sums weighed as Newton's law would (the constant eps) miss the power balance at
    delta = 0 by about 80 s.e. The law's ceiling on the rebound speed, ``eps * speed_scale``,
    bounds the mean velocity after impact, which Newton's law at the same eps exceeds."""
    from vibroimpact.pipeline import cells

    walls = {} if gap is None else dict(gap=gap, eps_lower=0.8)
    kw = dict(transient=200.0, bins=_bins(), n_batches=20)
    lower = {} if gap is None else dict(speed_scale_lower=2.0)
    model = Model.paper(ZETA, 0.7, delta, amplitude, 1 / 1.1, speed_scale=0.3, **walls, **lower)
    out = cells.event_statistics(record, 0.1, model, **kw)
    assert out["n_collisions"] > 1000
    for name in ("power", "virial"):
        res, se = out[f"{name}_residual"], out[f"{name}_residual_stderr"]
        assert abs(res) < 3.0 * se, (name, res, se)
    # every rebound below its wall's ceiling eps * speed_scale
    if gap is None:
        assert out["v_after_mean"] < 0.7 * 0.3
    else:
        assert out["wall_v_after_mean"][0] < 0.7 * 0.3 < out["wall_v_after_mean"][1] < 0.8 * 2
        assert np.all(out["wall_n_collisions"] > 100)
    newton = cells.event_statistics(
        record, 0.1, Model.paper(ZETA, 0.7, delta, amplitude, 1 / 1.1, **walls), **kw)
    assert newton["v_after_mean"] > 2 * out["v_after_mean"]


def test_a_study_carries_its_law_to_every_job():
    """`law` and `law_lower` reach the cells' model (`Study`, `study_model`, the jobs'
    keywords), on the paper's plane and on another; a Newton study's keywords are those it
    always had."""
    from vibroimpact.pipeline.cells import study_model
    from vibroimpact.pipeline.study import JOB_KEYS, Study

    entry = dict(noise="n", zeta=0.05, eps=0.5, amplitude=1.0, inv_beta=[1.1],
                 delta=[0.0, 1.0], tile_size=4, gap=2.0, law={"speed_scale": 0.5},
                 law_lower={"speed_scale": 3.0})
    study = Study.from_config("soft", entry)
    cell = study.cells()[1]
    m = study_model(study, cell)
    assert [w.law.speed_scale for w in m.walls] == [0.5, 3.0]
    physics = m.params()
    assert physics["speed_scale"] == 0.5 and physics["speed_scale_lower"] == 3.0
    plane = dict(entry, plane=["eps", "delta"], eps=[0.3, 0.6], inv_beta=1.1)
    plane.pop("law_lower")
    study = Study.from_config("soft_plane", plane)
    m = study_model(study, study.cells()[0])
    assert [w.law.speed_scale for w in m.walls] == [0.5, 0.5]
    for kind in ("events", "map", "spectra", "trace", "escape", "plane_trace",
                 "plane_escape"):
        assert {"law", "law_lower"} <= set(JOB_KEYS[kind]), kind
    newton = Study.from_config("n", dict(entry, law=None, law_lower=None))
    assert study_model(newton, newton.cells()[0]).newton
    assert newton.laws() == {}


def test_rices_large_play_rebound_under_the_law():
    """Fig. 9's large-play asymptote (a): the mean rebound speed over the Rayleigh speeds of
    high up-crossings, by the law (scipy's adaptive quadrature as the reference, to 1e-9),
    and Newton's closed form eps sigma_v sqrt(pi / 2) without a law."""
    import xarray as xr
    from scipy.integrate import quad
    from vibroimpact.plotting.random import _rice_rebound

    sigma_v, eps, scale = 0.98, 0.5, 0.5
    ref = quad(lambda u: eps * u / (1 + u / scale) * u / sigma_v**2
               * math.exp(-0.5 * (u / sigma_v) ** 2), 0, math.inf)[0]
    law_ds = xr.Dataset(attrs=dict(speed_scale=scale))
    assert _rice_rebound(law_ds, eps, sigma_v) == pytest.approx(ref, rel=1e-9)
    assert _rice_rebound(xr.Dataset(), eps, sigma_v) == eps * sigma_v * math.sqrt(math.pi / 2)
    assert ref < eps * scale < eps * sigma_v * math.sqrt(math.pi / 2)


def test_every_header_names_the_law():
    """A dataset under a law says so in the system line of every figure (`_system_text`) and
    in a plane's caption of fixed values (`law_caption`); a Newton dataset's are as before."""
    import xarray as xr
    from vibroimpact.plotting._common import _system_text, law_caption

    law = xr.Dataset(attrs=dict(zeta=0.05, eps=0.5, speed_scale=0.5, speed_scale_lower=2.0))
    assert "(1 + u / 0.5)" in _system_text(law)
    assert law_caption(law, math=False) == "ε(u) = ε/(1 + u/0.5), ε_l(u) = ε_l/(1 + u/2)"
    newton = xr.Dataset(attrs=dict(zeta=0.05, eps=0.5))
    assert law_caption(newton) == "" and "u/" not in _system_text(newton)
    lower = xr.Dataset(attrs=dict(zeta=0.05, eps=0.5, speed_scale_lower=2.0))
    assert law_caption(lower, math=False) == "ε_l(u) = ε_l/(1 + u/2)"
    from vibroimpact.pipeline.tasks import _law_attrs

    attrs = _law_attrs({"speed_scale": math.inf, "speed_scale_lower": 2.0})
    assert "speed_scale" not in attrs and attrs["speed_scale_lower"] == 2.0


def test_the_shooting_map_under_a_vanishing_law_is_the_closed_forms():
    """Fig. 16 by the shooting solver (`attractors.plane.orbit_plane` with a law) against the
    closed form (no law) on a 2 x 3 grid: at speed_scale = 1e12 the restitution differs from
    eps by at most 1e-12 relative at the impact speeds here (u < 5), so the stable domains
    agree cell for cell and lam to 1e-9 (the multiplier's sensitivity to eps is O(1)); at
    speed_scale = 0.5 the law's map differs, and each of its cells is `periodic_motions`'
    own motion at that cell."""
    from vibroimpact.attractors.plane import orbit_plane

    ib, d = [0.9, 1.2], [0.0, 0.5, 1.0]
    fixed, types = dict(zeta=ZETA, eps=0.5), [(1, 1), (2, 1)]
    closed = orbit_plane("inv_beta", ib, "delta", d, fixed, types)
    shot = orbit_plane("inv_beta", ib, "delta", d, fixed, types, speed_scale=1e12)
    assert closed.attrs["solver"] != "periodic_motions" == shot.attrs["solver"]
    assert (closed["n_stable"].values > 0).sum() >= 4
    np.testing.assert_array_equal(closed["n_stable"].values > 0, shot["n_stable"].values > 0)
    both = closed["n_stable"].values > 0
    np.testing.assert_allclose(shot["lam"].values[both], closed["lam"].values[both],
                               rtol=0, atol=1e-9)
    soft = orbit_plane("inv_beta", ib, "delta", d, fixed, types, speed_scale=0.5)
    assert soft.attrs["speed_scale"] == 0.5 and soft.attrs["n_walls"] == 1
    stable = soft["n_stable"].values > 0
    assert stable.any() and np.nanmax(np.abs(soft["lam"].values - closed["lam"].values)) > 0.1
    t, i, j = np.argwhere(stable)[0]
    model = Model.paper(ZETA, 0.5, d[j], 1.0, 1.0 / ib[i], speed_scale=0.5)
    m, n = types[t]
    lam = min(mo.lam for mo in periodic_motions(model, n).motions
              if (mo.m, mo.n) == (m, n) and mo.admissible and mo.stable)
    assert soft["lam"].values[t, i, j] == lam


def test_an_orbits_entry_with_a_law_is_the_shooting_solvers(tmp_path):
    """`law` on an orbits entry: its tiles are the shooting rule's (study.shooting, the plan
    and the rule's folder), its boundary curves are not traced (they continue Newton's closed
    form), and a period the shooting map does not solve for is refused by name."""
    from vibroimpact.pipeline import config as configuration
    from vibroimpact.pipeline.study import shooting

    from helpers import ROOT

    config, plan = configuration.load(
        root=ROOT, user_files=[ROOT / "config" / "examples" / "impact_law.yaml"])
    assert shooting(config["orbits"]["soft_wall_orbits"])
    assert not shooting(config["orbits"]["newton_wall_orbits"])
    rows = {row.key: row.rules for row in plan.rows}
    assert "solve_clearance_orbit_tile" in rows["orbits.soft_wall_orbits"]
    assert "solve_orbit_tile" in rows["orbits.newton_wall_orbits"]
    small = dict(config["orbits"]["soft_wall_orbits"], inv_beta=[0.9, 1.2], delta=[0.5, 1.0],
                 tile_rows=2)
    from vibroimpact.attractors.plane import orbit_plane
    from vibroimpact.pipeline import tasks

    with pytest.raises(ValueError, match="solve_clearance_orbit_tile"):
        tasks.orbit_tile(small, 0, tmp_path / "tile.nc")        # the closed form's rule
    tasks.orbit_tile(small, 0, tmp_path / "tile.nc", solver=orbit_plane)
    tasks.aggregate_orbits(small, [tmp_path / "tile.nc"], tmp_path / "soft.nc")
    tasks.boundaries(small, tmp_path / "soft.nc", tmp_path / "soft_boundaries.nc")
    import xarray as xr

    orbits = xr.load_dataset(tmp_path / "soft.nc")
    assert orbits.attrs["speed_scale"] == 0.5 and "impact_law" in orbits.attrs
    assert (orbits["n_stable"].values > 0).any()
    curves = xr.load_dataset(tmp_path / "soft_boundaries.nc")
    assert curves.attrs["traced"] == 0 and "impact law" in curves.attrs["not_traced"]
    entry = dict(config["orbits"]["soft_wall_orbits"], types=[[1, 1], [1, 5]])
    user = {"paper": False, "orbits": {"soft": entry}}
    with pytest.raises(configuration.ConfigError, match=r"orbits\.soft\.types\[1\].*"
                       r"1 <= n <= 4"):
        configuration.load(user, root=ROOT)
