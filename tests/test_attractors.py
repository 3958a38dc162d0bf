"""Basins of attraction and Lyapunov exponents under sin(beta tau) alone (`attractor_map`).

Cells of the default Fig. 15 plane (zeta = 0.05, eps = 0.5), found with `periodic_orbits`:
(1/beta, delta) = (1.0, 2.0) has one stable motion, (1/1); (1.0, 0.0) one, (2/1);
(1.45, 0.95) has a stable (1/1) and a stable (2/1) with basins of comparable size;
(0.35, 0.0) has chaotic starts.
"""
import math

import numpy as np
import pytest

import vibroimpact
from vibroimpact import periodic_orbits
from vibroimpact.attractors import attractor_map
from vibroimpact.attractors import api as A
from vibroimpact.attractors import kernels as ak

ZETA, EPS = 0.05, 0.5


def _one_cell(inv_beta, delta, **kw):
    return attractor_map([inv_beta], [delta], ZETA, EPS, **kw)


def _stable(m, n, inv_beta, delta):
    return [o for o in periodic_orbits(m, n, 1.0 / inv_beta, delta, ZETA, EPS) if o.stable]


def test_single_stable_motion_takes_every_start():
    assert len(_stable(1, 1, 1.0, 2.0)) == 1
    assert all(not _stable(m, n, 1.0, 2.0) for m, n in ((2, 1), (1, 2), (1, 3), (3, 1)))
    r = _one_cell(1.0, 2.0, n_starts=64)
    assert r["motions"][0] == "1/1" and r["motions"][-1] == "other"
    assert np.all(r["lyapunov_start"] < 0.0)
    assert r["count"][0, 0, 0] == 64 and r["fraction"][0, 0, 0] == 1.0
    assert r["fraction_hi"][0, 0, 0] == 1.0 and r["fraction_lo"][0, 0, 0] > 0.9
    assert r["n_stable"][:, 0, 0].tolist() == [1, 0, 0, 0, 0]
    assert r["class_count"][0, 0, 0] == 64 and r["cell_class"][0, 0] == 0
    assert np.all(np.isfinite(r["settle_time"])) and np.isnan(r["lyapunov_stderr"][0, 0])
    # one collision per forcing period
    assert r["impact_rate"][0, 0] == pytest.approx(1.0 / (2.0 * math.pi), rel=1e-12)


def test_bistable_fraction_agrees_with_a_dense_grid():
    inv_beta, delta = 1.45, 0.95
    assert _stable(1, 1, inv_beta, delta) and _stable(2, 1, inv_beta, delta)
    r = _one_cell(inv_beta, delta, n_starts=64)
    frac = r["fraction"][:, 0, 0]
    assert 0.1 < frac[0] < 0.9 and 0.1 < frac[1] < 0.9
    # brute force: a regular 16 x 16 x 16 grid (cell centres) over the same box
    g = (np.arange(16) + 0.5) / 16
    th, gg, vv = np.meshgrid(2 * math.pi * g, 4.0 * g, -4.0 + 8.0 * g, indexing="ij")
    outf, outi, _ = A._starts_at_cell(inv_beta, delta, ZETA, EPS, th.ravel(),
                                      delta - gg.ravel(), vv.ravel())
    motion = outi[:, ak.I_MOTION]
    for t in (0, 1):
        dense = np.mean(motion == t)
        assert r["fraction_lo"][t, 0, 0] <= dense <= r["fraction_hi"][t, 0, 0], (t, dense)
    assert np.mean(motion >= 0) > 0.95


@pytest.mark.parametrize("m, n, inv_beta, delta", [
    (1, 1, 0.8, 0.0),       # real multipliers 0.70, 0.22
    (2, 1, 1.0, -0.1),      # real multipliers 0.38, 0.087
    (1, 1, 1.0, 2.0),       # complex: |mu| = eps exp(-zeta z) for both
])
def test_settled_exponent_is_the_solver_multiplier(m, n, inv_beta, delta):
    (orbit,) = _stable(m, n, inv_beta, delta)
    expected = math.log(abs(orbit.multipliers[0])) / orbit.period
    second = math.log(abs(orbit.multipliers[1])) / orbit.period
    r = _one_cell(inv_beta, delta, n_starts=16)
    t = r["motions"].index(f"{m}/{n}")
    on = r["motion_start"][:, 0, 0] == t
    assert on.sum() >= 8
    np.testing.assert_allclose(r["lyapunov_start"][on, 0, 0], expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["lyapunov_second_start"][on, 0, 0], second, rtol=0,
                               atol=1e-12)
    assert r["lyapunov"][0, 0] >= expected - 1e-12


def _exponent_sum_residual(outf):
    nu = outf[:, ak.F_IMPACTS] / outf[:, ak.F_WINDOW]
    total = outf[:, ak.F_LYAP1] + outf[:, ak.F_LYAP2]
    return total - (-2.0 * ZETA + 2.0 * nu * math.log(EPS))


def test_exponent_sum_is_the_phase_space_contraction():
    # unsettled and chaotic (Benettin over the last three quarters of the run): the tangent
    # products' QR logs, impact by impact (a settled start's determinant is taken in its
    # exact form, so its sum would hold by construction and is not a check)
    _, theta, g, v0 = A.sobol_starts(64, (0.0, 4.0), (-4.0, 4.0), 0)
    outf, outi, _ = A._starts_at_cell(0.35, 0.0, ZETA, EPS, theta, 0.0 - g, v0)
    chaotic = outi[:, ak.I_CLASS] == ak.CHAOTIC
    assert chaotic.any()
    assert np.all(outf[chaotic, ak.F_LYAP1] > 3 * outf[chaotic, ak.F_STDERR])
    np.testing.assert_allclose(_exponent_sum_residual(outf[chaotic]), 0.0, atol=1e-9)


@pytest.mark.parametrize("dt", [0.2, 0.1])
def test_start_follows_the_public_simulator(dt):
    inv_beta, delta, x0, v0 = 1.0, 2.0, 1.0, 0.5
    h, k0, t0 = ak.start_step(1.0 / inv_beta, 0.0)
    assert (h, k0, t0) == (0.2, 0, 0.0)
    outf, outi, (tk, ts, tu) = A._starts_at_cell(inv_beta, delta, ZETA, EPS, [0.0], [x0],
                                                 [v0], trace=20)
    n = int(np.count_nonzero(np.isfinite(tu)))
    assert n >= 5
    t_kernel = tk[:n] * h + ts[:n]
    res = vibroimpact.simulate(ZETA, EPS, delta, amplitude=1.0, beta=1.0 / inv_beta, x0=x0,
                               v0=v0, t_end=t_kernel[-1] + 1.0, dt=dt)
    assert res.n_impacts >= n
    tol = 0.0 if dt == h else 1e-9        # the same steps: bit for bit; other steps: round-off
    np.testing.assert_allclose(res.impact_time[:n], t_kernel, rtol=0, atol=tol)
    np.testing.assert_allclose(res.impact_velocity[:n], tu[:n], rtol=0, atol=tol)


@pytest.mark.parametrize("kw, name", [
    (dict(n_starts=0), "n_starts"),
    (dict(gap=(-0.5, 1.0)), "gap"),
    (dict(gap=(1.0, 1.0)), "gap"),
    (dict(velocity=(2.0, -2.0)), "velocity"),
    (dict(max_time=100.0), "max_time"),
    (dict(match_tol=0.0), "match_tol"),
    (dict(types=((4, 1),)), "m of types"),
])
def test_bad_input_is_refused_naming_the_argument(kw, name):
    with pytest.raises(ValueError, match=name):
        _one_cell(1.0, 2.0, **kw)


def test_gap_below_zero_says_beyond_the_wall():
    with pytest.raises(ValueError, match="beyond the wall"):
        _one_cell(1.0, 2.0, gap=(-0.1, 1.0))
    with pytest.raises(ValueError, match=r"ln\(1/match_tol\)/zeta = 276"):
        _one_cell(1.0, 2.0, max_time=200.0)


def test_sticking_starts_have_minus_infinite_exponents():
    # delta < -1: f - delta > 0 always, every start ends resting on the wall for good;
    # (1/beta, delta) = (2.0, -0.2): a (1/1) impact-stick motion (one collision per period:
    # an impact, its chatter and the sticking up to the release) takes every start
    r = attractor_map([2.0], [-1.2, -0.2], ZETA, EPS, n_starts=16)
    sticking = A.CLASSES.index("sticking")
    assert np.all(r["class_count"][sticking] == 16)
    assert np.all(r["lyapunov"] == -np.inf) and np.all(r["lyapunov_start"] == -np.inf)
    assert np.all(r["count"][-1] == 16)                   # not on a listed solver orbit
    assert r["impact_rate"][0, 0] == 0.0
    assert r["stick_count"][0, 0, 1] == 16 and r["stick_count"][:, 0, 0].sum() == 0
    assert r["impact_rate"][0, 1] == pytest.approx(1.0 / (4.0 * math.pi), rel=1e-12)
    assert np.all(r["period_start"][1, :, 0, 1] == 1)


def test_unlisted_orbit_exponent_from_the_trajectory_itself():
    # (1/1) left out of types: the same motion settles as "periodic_other", and its exponent
    # comes from the tangent product along the last period of the trajectory (real
    # multipliers 0.70 and 0.22, so not fixed by the determinant alone)
    (orbit,) = _stable(1, 1, 0.8, 0.0)
    expected = [math.log(abs(mu)) / orbit.period for mu in orbit.multipliers]
    _, theta, g, v0 = A.sobol_starts(8, (0.0, 4.0), (-4.0, 4.0), 0)
    outf, outi, _ = A._starts_at_cell(0.8, 0.0, ZETA, EPS, theta, 0.0 - g, v0, types=((1, 3),))
    other = outi[:, ak.I_CLASS] == ak.PERIODIC_OTHER
    assert other.sum() >= 4
    assert np.all(outi[other, ak.I_PERIOD_M] == 1) and np.all(outi[other, ak.I_PERIOD_P] == 1)
    np.testing.assert_allclose(outf[other, ak.F_LYAP1], expected[0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(outf[other, ak.F_LYAP2], expected[1], rtol=0, atol=1e-6)


@pytest.mark.parametrize("inv_beta, delta", [(1.0, -0.5), (0.7, -0.6), (2.0, -0.2)])
def test_impact_stick_collisions_agree_with_the_simulator(inv_beta, delta):
    # a (1/1) impact-stick motion: ~15 resolved rebounds per period, one collision
    beta = 1.0 / inv_beta
    tf = 2.0 * math.pi / beta
    outf, outi, _ = A._starts_at_cell(inv_beta, delta, ZETA, EPS, [0.0], [delta - 1.0], [0.5])
    assert outi[0, ak.I_CLASS] == ak.STICKING and outf[0, ak.F_LYAP1] == -np.inf
    mc, p, mm = outi[0, ak.I_STICK_M], outi[0, ak.I_STICK_P], outi[0, ak.I_PERIOD_M]
    assert (mc, p) == (1, 1) and mm > 5
    t_end = outf[0, ak.F_SETTLE] + 13 * tf
    res = vibroimpact.simulate(ZETA, EPS, delta, amplitude=1.0, beta=beta, x0=delta - 1.0,
                               v0=0.5, t_end=t_end, dt=ak.start_step(beta, 0.0)[0])
    # periods well inside the record (the record's last chatter run is cut by its end)
    lo, hi = outf[0, ak.F_SETTLE] + 2 * tf, t_end - 3 * tf
    inside = (res.collision_time >= lo) & (res.collision_time < lo + 7 * tf)
    assert hi > lo + 7 * tf
    assert np.count_nonzero(inside) == 7 * mc
    assert np.all(res.collision_stuck[inside])
    # and every one of them holds the period's mm resolved impacts
    first = np.flatnonzero(inside)
    assert np.all(np.diff(res.collisions.first)[first] == mm)


@pytest.mark.slow
def test_whole_plane_exponents_and_bookkeeping():
    # the default Fig. 15 plane, 4 starts per cell (~20 s on 2 threads)
    inv_beta = np.round(np.arange(0.2, 3.0 + 1e-9, 0.05), 10)
    delta = np.round(np.arange(-1.5, 3.0 + 1e-9, 0.05), 10)
    checked = A._validate(inv_beta, delta, ZETA, EPS, A.DEFAULT_TYPES, 4, (0.0, 4.0),
                          (-4.0, 4.0), A.DEFAULT_MAX_TIME, A.DEFAULT_MATCH_TOL, 0)
    raw = A._simulate_starts(*checked)
    outf, outi, lnmu = raw["outf"], raw["outi"], raw["lnmu"]
    assert not np.any(outi[:, ak.I_STATUS])
    cls = outi[:, ak.I_CLASS]
    # every listed start: the exponent of one of the cell's stable solver orbits of its type
    for i in np.flatnonzero(cls == ak.LISTED):
        b, d = divmod(raw["cell_of"][i], delta.size)
        t = outi[i, ak.I_MOTION]
        z = 2 * math.pi * A.DEFAULT_TYPES[t][1] * inv_beta[b]
        cand = lnmu[b, d, t][np.isfinite(lnmu[b, d, t])] / z
        assert np.min(np.abs(cand - outf[i, ak.F_LYAP1])) < 1e-12
    # both exponents sum to the contraction, settled or not (Benettin's QR logs)
    finite = np.isfinite(outf[:, ak.F_LYAP1]) & (outf[:, ak.F_IMPACTS] > 0)
    assert np.max(np.abs(_exponent_sum_residual(outf[finite]))) < 1e-6
    unsettled = (cls == ak.CHAOTIC) | (cls == ak.UNDECIDED)
    assert np.max(np.abs(_exponent_sum_residual(outf[unsettled & finite]))) < 1e-9
    assert np.all(np.isnan(outf[unsettled, ak.F_SETTLE]))
    # the rest settled, except starts still sticking now and then at the cap (class
    # "sticking", not periodic within the cap)
    late = np.isnan(outf[:, ak.F_SETTLE]) & ~unsettled
    assert np.all(cls[late] == ak.STICKING) and late.sum() < 0.01 * cls.size
    # sticking: exponents -inf; the wall-free response: both -zeta, and only where the
    # linear steady response stays off the wall; every other periodic motion impacts
    assert np.all(outf[cls == ak.STICKING, ak.F_LYAP1] == -np.inf)
    free = cls == ak.WALL_FREE
    assert free.any() and np.all(outf[free, ak.F_LYAP1] == -ZETA)
    b, d = np.divmod(raw["cell_of"], delta.size)
    assert np.all(_steady_amplitude(inv_beta[b[free]]) < delta[d[free]])
    assert np.all(outi[cls == ak.PERIODIC_OTHER, ak.I_PERIOD_M] > 0)
    # and conversely: a start that ends without impacts and off the wall is wall-free
    quiet = (outf[:, ak.F_RATE] == 0.0) & (cls != ak.STICKING)
    assert np.all(cls[quiet] == ak.WALL_FREE)


def _steady_amplitude(inv_beta):
    """q(beta) of the linear steady response q sin(beta tau - phi) (MODEL.md)."""
    beta = 1.0 / np.asarray(inv_beta, dtype=float)
    return 1.0 / np.hypot(1.0 - beta ** 2, 2.0 * ZETA * beta)


def test_wall_free_response_is_its_own_class():
    # q(beta) from the closed form: 1/beta = 0.5 -> q = 0.33, 2.5 -> 1.19, 1.0 -> 10 (the
    # resonance); delta = 1.5 and 3 clear the first and the last, delta = 0.2 none
    inv_beta = np.array([0.5, 1.0, 2.5])
    delta = np.array([0.2, 1.5, 3.0])
    q = _steady_amplitude(inv_beta)
    r = attractor_map(inv_beta, delta, ZETA, EPS, n_starts=16)
    free = A.CLASSES.index("wall_free")
    cls = r["class_start"]
    clear = q[:, None] < delta[None, :]         # (nb, nd): the response misses the wall
    assert clear.sum() == 4
    # a wall-free start only where the closed form clears the wall, and there both of its
    # exponents are -zeta (tolerance 0: a free flight's tangent map is the damped propagator,
    # whose exponents are -zeta exactly), no collision, not a listed motion
    on = cls == free
    assert not np.any(on & ~clear[None])
    assert np.all(r["lyapunov_start"][on] == -ZETA)
    assert np.all(r["lyapunov_second_start"][on] == -ZETA)
    assert np.all(r["motion_start"][on] == len(r["motions"]) - 1)
    # cells that clear the wall and where no start impacts: the wall-free class, exponent
    # -zeta, with the largest exponent's owner the wall-free response itself
    quiet = clear & (r["impact_rate"] == 0.0)
    assert quiet.sum() == 4
    assert np.all(r["class_count"][free][quiet] == 16)
    assert np.all(r["cell_class"][quiet] == free)
    assert np.all(r["lyapunov"][quiet] == -ZETA) and np.all(r["lyapunov_class"][quiet] == free)
    # and it is no longer counted as a periodic impact motion of another type
    assert np.all(r["class_count"][A.CLASSES.index("periodic_other")][quiet] == 0)
    assert not np.any(r["class_count"][free][~clear])


def test_wall_free_start_converges_to_the_linear_response_in_the_simulator():
    # independent of the kernel's settling test: the public simulator from a start that the
    # map calls wall-free makes no impact after the settle time, and its distance from
    # q sin(beta tau - phi) shrinks like exp(-zeta tau) (the exponent -zeta)
    inv_beta, delta = 2.5, 3.0
    beta = 1.0 / inv_beta
    q = float(_steady_amplitude(inv_beta))
    phi = math.atan2(2.0 * ZETA * beta, 1.0 - beta ** 2)
    x0, v0 = delta - 0.5, 3.0
    outf, outi, _ = A._starts_at_cell(inv_beta, delta, ZETA, EPS, [0.0], [x0], [v0])
    assert outi[0, ak.I_CLASS] == ak.WALL_FREE
    settle = outf[0, ak.F_SETTLE]
    dt = ak.start_step(beta, 0.0)[0]
    res = vibroimpact.simulate(ZETA, EPS, delta, amplitude=1.0, beta=beta, x0=x0, v0=v0,
                               t_end=settle + 200.0, dt=dt, record_every=1)
    assert res.n_impacts >= 1 and np.all(res.impact_time < settle)
    t = np.asarray(res.grid_time)
    x = delta - np.asarray(res.a)
    v = np.asarray(res.v)
    # the free part w = x - q sin(beta t - phi) and its envelope sqrt(w^2 + ((w' + zeta w)
    # / omega_d)^2), which decays exactly like exp(-zeta t) between impacts
    w = x - q * np.sin(beta * t - phi)
    wv = v - q * beta * np.cos(beta * t - phi)
    env = np.hypot(w, (wv + ZETA * w) / math.sqrt(1.0 - ZETA ** 2))
    after = t > settle
    slope = np.polyfit(t[after], np.log(env[after]), 1)[0]
    # a straight line in log: the slope is -zeta to the round-off of x (env falls from
    # delta - q to 1e-4 of it over the 200 time units)
    assert slope == pytest.approx(-ZETA, abs=1e-6)
    assert np.max(q + env[after]) < delta


def test_a_stable_orbit_at_its_grazing_edge_has_a_tiny_basin_not_a_failed_match():
    # (1/beta, delta) = (2.85, 0.75): a stable admissible (3/1) with margin 3.2e-4 (its
    # grazing edge lies 2e-4 below in delta); the default plane's 64 starts all settle on a
    # (4/1) impact motion (an extra slow impact, u = 0.04, where the (3/1)'s flight nearly
    # touches the wall) at exponent -0.138. A start on the solver orbit is matched to it, at
    # the solver's exponent ln max|mu| / z = -0.0965; a velocity kick of 1e-2 leaves it
    inv_beta, delta = 2.85, 0.75
    (orbit,) = _stable(3, 1, inv_beta, delta)
    assert 0.0 < orbit.margin < 1e-3
    expected = math.log(max(abs(orbit.multipliers))) / orbit.period
    ns, oph, ou, _, _ = A.stable_orbits(np.array([inv_beta]), np.array([delta]),
                                        A._types(A.DEFAULT_TYPES), ZETA, EPS)
    t = A.DEFAULT_TYPES.index((3, 1))
    assert ns[:, 0, 0].tolist() == [0, 0, 0, 0, 1]
    theta, u = 2.0 * math.pi * oph[0, 0, t, 0, 0], ou[0, 0, t, 0, 0]
    kicks = np.array([0.0, 1e-6, -1e-4, 1e-2, -1e-2])
    outf, outi, _ = A._starts_at_cell(inv_beta, delta, ZETA, EPS, np.full(5, theta),
                                      np.full(5, delta), -EPS * u + kicks)
    assert outi[:3, ak.I_MOTION].tolist() == [t] * 3
    np.testing.assert_allclose(outf[:3, ak.F_LYAP1], expected, rtol=0, atol=1e-12)
    other = outi[3:]
    assert np.all(other[:, ak.I_CLASS] == ak.PERIODIC_OTHER)
    assert np.all(other[:, ak.I_PERIOD_M] == 4) and np.all(other[:, ak.I_PERIOD_P] == 1)
    assert np.all(outf[3:, ak.F_LYAP1] < expected - 0.03)
    # the basin is there, but small: 1024 Sobol starts of the default box (seed 1, as the
    # default plane) find it; 0.4 % of them (0.70 % of 16 384: 64 starts miss it 64 % of
    # the time)
    _, th, g, v0 = A.sobol_starts(1024, (0.0, 4.0), (-4.0, 4.0), 1)
    outf, outi, _ = A._starts_at_cell(inv_beta, delta, ZETA, EPS, th, delta - g, v0)
    on = outi[:, ak.I_MOTION] == t
    assert 0 < on.sum() < 0.02 * on.size
    assert np.all(outi[~on, ak.I_PERIOD_M] == 4)


def test_a_cell_does_not_depend_on_the_rows_it_is_solved_with():
    """The workflow splits the plane's rows into tiles of any size (`tile_rows`) and joins
    them sorted (`datasets.concat_attractor_tiles`): a cell's result must be the same bit for
    bit whichever rows share its job, so that a change of tiling leaves the datasets alone."""
    rows, deltas = np.array([0.35, 1.0, 1.45]), np.array([0.0, 0.95])
    kw = dict(n_starts=8, max_time=300.0, seed=3)
    whole = attractor_map(rows, deltas, ZETA, EPS, **kw)
    parts = [(sel, attractor_map(rows[sel], deltas, ZETA, EPS, **kw))
             for sel in (slice(0, None, 2), slice(1, None, 2))]
    compared = 0
    for key, value in whole.items():
        if not (isinstance(value, np.ndarray) and value.ndim >= 2
                and value.shape[-2:] == (rows.size, deltas.size)):
            continue
        for sel, part in parts:
            np.testing.assert_array_equal(part[key], value[..., sel, :], err_msg=key)
        compared += 1
    assert compared >= 10


@pytest.mark.parametrize("inv_beta, n", [(3.0, 1), (1.0, 1), (0.6, 2)])
def test_shared_m3_scan_is_the_solvers_bit_for_bit(inv_beta, n):
    """`cell_orbits` computes the m = 3 scan's node values that do not involve delta once per
    1/beta row (`kernels._m3_nodes`) and finishes each cell from them (`kernels._m3_cell`):
    its solutions must be `solve_type`'s (the orbit solver's own m = 3 path), every bit of
    every row, across a row of plays on which solutions exist."""
    from vibroimpact.orbits.flight import harmonic_constants
    from vibroimpact.orbits.solve import solve_type
    from vibroimpact.orbits.tolerances import M3_MIN_NODES, MAX_SOLUTIONS, SCAN_STEP_M3

    beta = 1.0 / inv_beta
    wd = harmonic_constants(beta, ZETA)[0]
    npt = max(M3_MIN_NODES,
              math.ceil(2.0 * math.pi * n / beta * max(beta, wd) / SCAN_STEP_M3))
    f1, hyp, wt = (np.empty((npt + 1, npt + 1)) for _ in range(3))
    ak._m3_nodes(n, beta, ZETA, EPS, npt, f1, hyp, wt)
    found = 0
    for delta in np.linspace(-1.5, 3.0, 19):
        mine, theirs = np.empty((MAX_SOLUTIONS, 7)), np.empty((MAX_SOLUTIONS, 7))
        count = ak._m3_cell(n, beta, delta, ZETA, EPS, f1, hyp, wt, mine)
        assert count == solve_type(3, n, beta, delta, ZETA, EPS, np.empty((1, 7)), 0,
                                   SCAN_STEP_M3, theirs)
        assert np.array_equal(mine[:count].view(np.int64), theirs[:count].view(np.int64))
        found += count
    assert found >= 5
