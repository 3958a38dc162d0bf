"""The attractor kernels with a second wall (a clearance between two stops).

Cell: symmetric stops at +-0.25 (delta = 0.25, clearance 0.5), zeta = 0.05, restitution 0.7
at the wall above and 0.9 at the wall below, force sin(beta tau) with 1/beta = 1.2: every
start found chaotic (largest exponent ~0.02, above 3 batch-means standard errors), with
impacts at both walls (found by a scan of 15 cells, 8 starts each).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import vibroimpact
from vibroimpact import model
from vibroimpact.attractors import api as A
from vibroimpact.attractors import attractor_map
from vibroimpact.attractors import kernels as ak
from vibroimpact.orbits.flight import propagator

ZETA, EPS, EPS_LO = 0.05, 0.7, 0.9
INV_BETA, CLEARANCE = 1.2, 0.5
DELTA = 0.5 * CLEARANCE
LOWER = DELTA - CLEARANCE


def _chaotic_starts(n=8):
    _, theta, g, v0 = A.sobol_starts(n, (0.0, CLEARANCE), (-2.0, 2.0), 0)
    return A._starts_at_cell(INV_BETA, DELTA, ZETA, EPS, theta, DELTA - g, v0,
                             clearance=CLEARANCE, eps_lower=EPS_LO)


def test_start_follows_the_public_two_wall_simulator():
    h, k0, t0 = ak.start_step(1.0 / INV_BETA, 0.0)
    x0, v0 = 0.0, 0.8
    outf, outi, (tk, ts, tu) = A._starts_at_cell(INV_BETA, DELTA, ZETA, EPS, [0.0], [x0], [v0],
                                                 trace=40, clearance=CLEARANCE,
                                                 eps_lower=EPS_LO)
    n = int(np.count_nonzero(np.isfinite(tu)))
    assert n >= 20 and np.any(tu[:n] < 0) and np.any(tu[:n] > 0)     # both walls met
    t_kernel = tk[:n] * h + ts[:n]
    res = vibroimpact.simulate(ZETA, EPS, DELTA, amplitude=1.0, beta=1.0 / INV_BETA, x0=x0,
                               v0=v0, t_end=t_kernel[-1] + 1.0, dt=h, gap=CLEARANCE,
                               eps_lower=EPS_LO)
    # the same steps and the same kernel: bit for bit, the wall told by the velocity's sign
    np.testing.assert_array_equal(res.impact_time[:n], t_kernel)
    np.testing.assert_array_equal(res.impact_velocity[:n], np.abs(tu[:n]))
    np.testing.assert_array_equal(res.impact_wall[:n], (tu[:n] < 0).astype(np.int8))


def _through_lower_impact(state, t0, t1, eps_lo, lower, beta):
    """The exact flow (DOP853) from (t0, state) to t1 across one impact on the wall at
    ``lower``, met moving down; its instant and (lab-frame) velocity."""
    def rhs(t, y):
        return [y[1], math.sin(beta * t) - 2 * ZETA * y[1] - y[0]]

    def hit(t, y):
        return y[0] - lower
    hit.terminal, hit.direction = True, -1.0
    a = solve_ivp(rhs, (t0, t1), state, method="DOP853", rtol=1e-13, atol=1e-13, events=hit)
    ts, u = a.t_events[0][0], a.y_events[0][0][1]
    b = solve_ivp(rhs, (ts, t1), [lower, model.rebound_velocity(eps_lo, u)], method="DOP853",
                  rtol=1e-13, atol=1e-13)
    return b.y[:, -1], ts, u


def test_lower_wall_saltation_is_the_tangent_of_the_flow_through_it():
    beta, lower = 1.3, -0.3
    t0, t1, state = 0.0, 1.6, np.array([0.2, -1.1])
    _, ts, u = _through_lower_impact(state, t0, t1, EPS_LO, lower, beta)
    assert t0 < ts < t1 and u < -0.3
    h = 1e-6
    jac_fd = np.empty((2, 2))
    for c in range(2):
        dy = np.zeros(2)
        dy[c] = h
        plus = _through_lower_impact(state + dy, t0, t1, EPS_LO, lower, beta)[0]
        minus = _through_lower_impact(state - dy, t0, t1, EPS_LO, lower, beta)[0]
        jac_fd[:, c] = (plus - minus) / (2 * h)
    wd = math.sqrt(1 - ZETA * ZETA)
    # the upper wall's (delta, eps) are given too: the sign of u must pick the lower one's
    s11, s21, s22 = ak.wall_saltation(0.5, u, math.sin(beta * ts), 1.0, EPS_LO, lower, ZETA)
    salt = np.array([[s11, 0.0], [s21, s22]])
    before = np.array(propagator(ts - t0, ZETA, wd)).reshape(2, 2)
    after = np.array(propagator(t1 - ts, ZETA, wd)).reshape(2, 2)
    # DOP853 at 1e-13 over differences of 2e-6: ~1e-7 relative, O(h^2) ~ 1e-12 truncation
    np.testing.assert_allclose(after @ salt @ before, jac_fd, rtol=1e-6, atol=1e-6)


def test_exponent_sum_has_a_term_per_wall():
    # Benettin's logs, impact by impact: sum = -2 zeta + 2 sum_w nu_w ln eps_w with the
    # window's own impact counts, to round-off (a lower-wall saltation with the upper
    # wall's eps, or a missed lower impact, would be off by 2 nu_lo ln(0.9/0.7) ~ 0.13)
    outf, outi, _ = _chaotic_starts()
    chaotic = outi[:, ak.I_CLASS] == ak.CHAOTIC
    assert chaotic.sum() >= 6
    f = outf[chaotic]
    assert np.all(f[:, ak.F_LYAP1] > 3 * f[:, ak.F_STDERR])
    n_lo = f[:, ak.F_IMPACTS_LO]
    n_up = f[:, ak.F_IMPACTS] - n_lo
    assert np.all(n_lo > 100) and np.all(n_up > 100)
    win = f[:, ak.F_WINDOW]
    law = -2 * ZETA + 2 * (n_up * math.log(EPS) + n_lo * math.log(EPS_LO)) / win
    np.testing.assert_allclose(f[:, ak.F_LYAP1] + f[:, ak.F_LYAP2], law, rtol=0, atol=1e-9)


def test_exponent_sum_against_the_simulators_rates():
    # the same law with each wall's impact rate measured independently: the public two-wall
    # simulator over a long run (starts' rates agree with it within the batch-means error)
    outf, outi, _ = _chaotic_starts()
    f = outf[outi[:, ak.I_CLASS] == ak.CHAOTIC]
    total = f[:, ak.F_LYAP1] + f[:, ak.F_LYAP2]
    t_end, n_batch = 40000.0, 40
    res = vibroimpact.simulate(ZETA, EPS, DELTA, amplitude=1.0, beta=1.0 / INV_BETA, x0=0.0,
                               v0=0.8, t_end=t_end, dt=0.1, gap=CLEARANCE, eps_lower=EPS_LO)
    keep = res.impact_time > 0.25 * t_end
    edges = np.linspace(0.25 * t_end, t_end, n_batch + 1)
    per = np.empty((n_batch, 2))
    for w in (0, 1):
        hits = res.impact_time[keep & (res.impact_wall == w)]
        per[:, w] = np.histogram(hits, edges)[0] / np.diff(edges)
    nu = per.mean(axis=0)
    law = -2 * ZETA + 2 * (nu[0] * math.log(EPS) + nu[1] * math.log(EPS_LO))
    # a start's window estimate scatters like a batch of its length: scale the batch SD
    batch_len = edges[1] - edges[0]
    sd_win = per.std(axis=0, ddof=1) * np.sqrt(batch_len / f[:, ak.F_WINDOW].mean())
    se = 2 * math.hypot(sd_win[0] * math.log(EPS), sd_win[1] * math.log(EPS_LO))
    assert abs(total.mean() - law) < 4 * (se / math.sqrt(len(total)) + se / math.sqrt(n_batch))


def test_map_keywords_and_refusals():
    r = attractor_map([INV_BETA], [DELTA], ZETA, EPS, n_starts=4, gap=(0.0, CLEARANCE),
                      velocity=(-2.0, 2.0), clearance=CLEARANCE, eps_lower=EPS_LO)
    assert r["n_stable"].sum() == 0       # no stable one-wall orbit stays above the wall below
    assert r["impact_rate_lower"][0, 0] > 0.1
    one = attractor_map([INV_BETA], [DELTA], ZETA, EPS, n_starts=4, gap=(0.0, CLEARANCE))
    assert np.all(one["impact_rate_lower"][np.isfinite(one["impact_rate_lower"])] == 0)
    with pytest.raises(ValueError, match="clearance"):
        attractor_map([INV_BETA], [DELTA], ZETA, EPS, n_starts=4, clearance=CLEARANCE)
    with pytest.raises(ValueError, match="eps_lower"):
        attractor_map([INV_BETA], [DELTA], ZETA, EPS, n_starts=4, eps_lower=0.5)
    with pytest.raises(ValueError, match="eps_lower"):
        attractor_map([INV_BETA], [DELTA], ZETA, EPS, n_starts=4, gap=(0.0, 0.5),
                      clearance=CLEARANCE, eps_lower=1.5)
    with pytest.raises(ValueError, match="clearance"):
        attractor_map([INV_BETA], [DELTA], ZETA, EPS, n_starts=4, gap=(0.0, 0.5),
                      clearance=-1.0)


def test_orbit_floor_is_the_lowest_point_of_the_flights():
    # a stable (1/1) orbit of the Fig. 15 plane: its lowest point by dense sampling of the
    # closed-form flight (the floor is found exactly, so sampling can only come out higher)
    from vibroimpact import periodic_orbits
    from vibroimpact.orbits.flight import flight
    from vibroimpact.orbits.tolerances import FLIGHT_STACK
    beta, delta = 1.0, 2.0
    orbit = [o for o in periodic_orbits(1, 1, beta, delta, ZETA, 0.5) if o.stable][0]
    y = np.array([orbit.tau0, orbit.velocities[0]])
    z = 2 * math.pi / beta
    floor = ak.orbit_floor(y, 1, z, beta, delta, ZETA, 0.5, np.empty((FLIGHT_STACK, 2)))
    wd = math.sqrt(1 - ZETA ** 2)
    q = 1 / math.hypot(1 - beta ** 2, 2 * ZETA * beta)
    phi = math.atan2(2 * ZETA * beta, 1 - beta ** 2)
    xs = [flight(y[0], y[1], s, beta, delta, ZETA, 0.5, wd, q, phi)[0]
          for s in np.linspace(0, z, 20001)]
    assert min(xs) - 1e-6 <= floor <= min(xs) + 1e-12
    # the two-wall map lists the orbit while the wall below stays under its floor
    clear = delta - floor
    for c, listed in ((clear + 0.05, 1), (clear - 0.05, 0)):
        ns = A.stable_orbits(np.array([1 / beta]), np.array([delta]), A._types(((1, 1),)),
                             ZETA, 0.5, c)[0]
        assert ns[0, 0, 0] == listed


def test_a_far_wall_below_changes_nothing():
    # the Fig. 15 plane's cells with one stable (1/1), one (2/1), chaotic starts: a wall 60
    # below, out of reach, leaves every start's record bit for bit as with one wall
    kw = dict(n_starts=6, max_time=600.0)
    one = attractor_map([1.0, 0.35], [2.0, 0.0], ZETA, 0.5, **kw)
    far = attractor_map([1.0, 0.35], [2.0, 0.0], ZETA, 0.5, clearance=60.0, eps_lower=0.3,
                        **kw)
    assert np.all(far.pop("impact_rate_lower")[np.isfinite(one["impact_rate_lower"])] == 0)
    one.pop("impact_rate_lower")
    assert one.keys() == far.keys()
    assert one["n_stable"].sum() > 0 and np.any(one["class_start"] == ak.CHAOTIC)
    for key, value in one.items():
        np.testing.assert_array_equal(far[key], value, err_msg=key)


# (1/beta, delta, clearance, eps, eps_lower): a (1/1) at the wall above, restitutions alike
# and unlike, and a (2/1) with an impact at each wall, faster than 1 at the wall below
MIRROR_CELLS = [(1.1, 0.5, 5.5, 0.5, 0.5), (1.1, 0.5, 3.0, 0.6, 0.8),
                (1.0, 1.5, 3.0, 0.7, 0.9)]


@pytest.mark.parametrize("inv_beta, delta, clearance, eps, eps_lower", MIRROR_CELLS)
def test_the_mirror_image_of_a_cell_settles_alike(inv_beta, delta, clearance, eps, eps_lower):
    """x -> -x maps the oscillator with walls at (delta - c, delta) under sin(beta tau) onto
    the one with walls at (-delta, c - delta) under -sin(beta tau) = sin(beta (tau + T_f/2)),
    restitutions swapped: the start (theta, x0, v0) onto (theta + pi, -x0, -v0). Every start
    and its mirror image settle in the same class on the same type, with the walls' impacts
    swapped; on a listed orbit the exponents are equal bit for bit (the mirror cell solves
    the same one-wall orbit, play and restitution, for its wall below), on another periodic
    motion within 1e-5 (each is taken along its trajectory's last period, within match_tol =
    1e-6 of the motion)."""
    _, theta, g, v0 = A.sobol_starts(12, (0.0, clearance), (-3.0, 3.0), 1)
    x0 = delta - g
    kw = dict(clearance=clearance)
    f, i, _ = A._starts_at_cell(inv_beta, delta, ZETA, eps, theta, x0, v0,
                                eps_lower=eps_lower, **kw)
    fm, im, _ = A._starts_at_cell(inv_beta, clearance - delta, ZETA, eps_lower,
                                  np.mod(theta + math.pi, 2 * math.pi), -x0, -v0,
                                  eps_lower=eps, **kw)
    settled = np.isin(i[:, ak.I_CLASS], (ak.LISTED, ak.PERIODIC_OTHER))
    assert settled.all()
    for slot in (ak.I_CLASS, ak.I_MOTION, ak.I_PERIOD_M, ak.I_PERIOD_P):
        np.testing.assert_array_equal(im[:, slot], i[:, slot])
    np.testing.assert_array_equal(fm[:, ak.F_IMPACTS_LO],
                                  f[:, ak.F_IMPACTS] - f[:, ak.F_IMPACTS_LO])
    listed = i[:, ak.I_CLASS] == ak.LISTED
    for slot in (ak.F_LYAP1, ak.F_LYAP2):
        np.testing.assert_array_equal(fm[listed, slot], f[listed, slot])
        np.testing.assert_allclose(fm[~listed, slot], f[~listed, slot], rtol=0, atol=1e-5)
    # an impact faster than 1 at the wall below in the cell or its mirror: a tolerance
    # relative to 1 + u (u < 0 there) would be negative, and no motion recognised
    lowest = []
    for d, e, e_lo, start in ((delta, eps, eps_lower, (theta[0], x0[0], v0[0])),
                              (clearance - delta, eps_lower, eps,
                               (np.mod(theta[0] + math.pi, 2 * math.pi), -x0[0], -v0[0]))):
        _, _, (_, _, tu) = A._starts_at_cell(inv_beta, d, ZETA, e, *start, trace=400,
                                             eps_lower=e_lo, **kw)
        lowest.append(np.min(tu[np.isfinite(tu)][-20:]))
    assert min(lowest) < -1.0


def test_the_issue_cell_and_its_mirror_are_listed_alike():
    """The map's own starts (Sobol, not mirror images of each other) at a cell and its mirror:
    every start on the (1/1) orbit, at the wall above in one and below in the other, with
    the same exponent."""
    one = attractor_map([1.1], [0.5], ZETA, 0.5, n_starts=16, gap=(0, 4), clearance=5.5)
    mirror = attractor_map([1.1], [5.0], ZETA, 0.5, n_starts=16, gap=(1.5, 5.5), clearance=5.5)
    for res in (one, mirror):
        assert res["count"][0, 0, 0] == 16 and res["class_count"][0, 0, 0] == 16
        assert res["n_stable"][0, 0, 0] == 1
    assert mirror["lyapunov"][0, 0] == one["lyapunov"][0, 0]
    assert one["impact_rate_lower"][0, 0] == 0.0
    assert mirror["impact_rate_lower"][0, 0] == mirror["impact_rate"][0, 0] > 0


def test_a_two_wall_plane_counts_the_studys_own_motions():
    """The basins of a two-wall plane are over the study's motions (m_upper, m_lower, n): a
    start counts for one when it settled periodic with m_upper + m_lower impacts per n
    forcing periods, m_lower of them below (here the (2/1) with an impact at each wall of
    MIRROR_CELLS and its mirror image, counted start by start)."""
    from vibroimpact.attractors.plane import attractor_plane
    from vibroimpact.pipeline import datasets

    fixed = dict(zeta=ZETA, eps=0.7, eps_lower=0.9, delta=1.5, amplitude=1.0)
    res = attractor_plane("gap", [3.0], "inv_beta", [1.0], fixed, types=((1, 1), (2, 1)),
                          n_starts=12, gap=(0.0, 3.0), velocity=(-3.0, 3.0))
    tiles = datasets.attractor_tile_dataset(res, dict(n_starts=12))
    motions = [(1, 1, 1), (1, 0, 1), (0, 1, 1)]
    basins = datasets.basins_dataset(tiles, motions)
    assert list(basins["motion"].values) == ["(1,1)/1", "(1,0)/1", "(0,1)/1", "other"]
    cls = res["class_start"][:, 0, 0]
    m, n = res["period_start"][:, :, 0, 0]
    low = res["impacts_lower_start"][:, 0, 0]
    want = [0, 0, 0, 0]
    for s in range(12):
        periodic = cls[s] in (ak.LISTED, ak.PERIODIC_OTHER)
        key = (int(m[s] - low[s]), int(low[s]), int(n[s]))
        want[motions.index(key) if periodic and key in motions else 3] += 1
    assert basins["count"].values[:, 0, 0].tolist() == want
    assert want[0] > 0                  # the motion at both walls is there
    assert basins["fraction"].sum("motion").values.tolist() == [[1.0]]
