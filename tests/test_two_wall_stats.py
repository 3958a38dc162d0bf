"""The statistics of a clearance between two walls (issue 35, section 2): collisions per
wall, the pressed-flight test at the lower wall, per-wall rates and densities, the power
balance and the virial with a term per wall, and the far-wall limit bit for bit.

Records are the exact two-wall simulator's (``simulate(..., gap=, eps_lower=)``); the checks
read what does not share their code: the force sampled densely along every flight, the
boundary terms of the two identities (docs/model.md, section 7.1), hand-made event arrays,
and the one-wall statistics themselves."""
import numpy as np
import pytest

from vibroimpact import noise, simulate, simulate_chunks, stats
from vibroimpact.impact.audit import audit_moments
from vibroimpact.impact.hops import pressed_flights as compiled_pressed_flights
from vibroimpact.pipeline import datasets

NOISE = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)
ZETA, BETA_F, B = 0.05, 1 / 1.1, 10
DT = NOISE.dt
BINS = datasets.bin_edges(dict(v_after=dict(max=2.5, n=50), interval=dict(max=20.0, n=80),
                               ratio=dict(max=4.0, n=80)))
#: (delta, gap, eps, eps_lower, amplitude): the clearance's cases. Chatter and sticking at
#: the upper wall; at both under a harmonic force; both walls elastic; a plastic upper wall
#: pressed by a narrow clearance (the lower wall chatters too).
CASES = [(0.3, 0.8, 0.5, 0.7, 0.0), (0.2, 0.5, 0.5, 0.3, 0.5), (0.4, 0.9, 1.0, 1.0, 0.0),
         (0.0, 0.3, 0.0, 0.5, 0.0)]


@pytest.fixture(scope="module")
def record():
    return noise.generate_array(NOISE, 100_001, seed=20261127)


def _run(record, delta, gap, eps, eps_lower, amplitude, **kw):
    return simulate(ZETA, eps, delta, noise=record, dt=DT, amplitude=amplitude, beta=BETA_F,
                    gap=gap, eps_lower=eps_lower, record_every=1, **kw)


def _phases(res):
    return stats.close_open_phase(res.stick_start, res.stick_end, res.stuck_since, res.t_end,
                                  stick_wall=res.stick_wall,
                                  stuck_wall=int(res.x_end != res.params["delta"]))


# ---- collisions per wall ------------------------------------------------------------------

def _group(times, u, wall, stick_start=(), stick_end=(), **kw):
    times = np.asarray(times, dtype=float)
    step = np.floor(times / DT).astype(np.int64)
    return stats.group_collisions(step, times - step * DT, u, stick_start, stick_end, dt=DT,
                                  eps=0.5, wall=wall, **kw)


@pytest.mark.parametrize("rule", stats.RULES)
def test_a_collision_never_spans_the_two_walls(rule):
    """Shrinking rebounds and pressed flights from the upper wall into a sticking phase at
    the lower one: one wall's run would be one collision, but the impact at the other wall
    starts a new one, under every rule."""
    t = [1.0, 2.0, 2.5, 2.75, 2.875]
    u = [0.9, 0.45, 0.22, 0.11, 0.05]
    kw = dict(pressed=np.ones(4, bool), rule=rule, floor=0.01)
    one = _group(t, u, None, [3.0], [4.0], **kw)
    two = _group(t, u, [0, 0, 1, 1, 1], [3.0], [4.0], stick_wall=[1], eps_lower=0.5, **kw)
    if rule == "rebounds":           # every rebound above the floor is an event anyway
        assert list(one.first) == list(two.first) == [0, 1, 2, 3, 4]
    else:
        assert list(one.first) == [0]
        assert list(two.first) == [0, 2]
    # every collision's impacts share its wall
    w = np.array([0, 0, 1, 1, 1])
    np.testing.assert_array_equal(two.wall[two.impact_collision], w)
    assert not one.wall.any() and one.wall.dtype == np.int8


def test_the_lower_wall_has_its_own_restitution_in_the_rebound_counts():
    # rebounds eps u: 0.5 * 0.03 = 0.015 counts at the upper wall, 0.2 * 0.03 does not below
    c = _group([1.0, 3.0], [0.03, 0.03], [0, 1], rule="rebounds", eps_lower=0.2, floor=0.01)
    assert list(c.first) == [0, 1] and list(c.rebounds) == [1, 0]
    c = _group([1.0, 3.0], [0.03, 0.03], [0, 1], rule="rebounds", floor=0.01)
    assert list(c.rebounds) == [1, 1]                    # eps_lower defaults to eps


def test_a_sticking_phase_on_the_wrong_wall_is_refused():
    with pytest.raises(ValueError, match="stick_wall and wall disagree"):
        _group([1.0, 2.0], [0.5, 0.2], [0, 1], [2.5], [3.0], stick_wall=[0],
               pressed=np.ones(1, bool))
    with pytest.raises(ValueError, match="wall must hold one value per impact"):
        _group([1.0, 2.0], [0.5, 0.2], [0, 2], pressed=np.ones(1, bool))
    with pytest.raises(ValueError, match="stick_wall must hold"):
        _group([1.0, 2.0], [0.5, 0.2], [0, 1], [2.5], [3.0], stick_wall=[1, 1, 0],
               pressed=np.ones(1, bool))


def test_at_wall_selects_and_renumbers():
    c = _group([1.0, 2.0, 4.0, 5.0, 7.5], [0.5] * 5, [0, 1, 0, 1, 1],
               pressed=np.zeros(4, bool))
    up, lo = c.at_wall(0), c.at_wall(1)
    assert np.allclose(up.time, [1.0, 4.0]) and np.allclose(up.intervals, [3.0])
    assert np.allclose(lo.time, [2.0, 5.0, 7.5]) and np.allclose(lo.intervals, [3.0, 2.5])
    assert list(up.impact_collision) == [0, -1, 1, -1, -1]
    assert list(lo.impact_collision) == [-1, 0, -1, 1, 2]
    with pytest.raises(ValueError, match="wall must be 0"):
        c.at_wall(2)


# ---- the pressed flights at either wall ---------------------------------------------------

def _dense_push_minimum(res, record, flights, wall, per_step=64):
    """The push towards the flight's wall sampled densely (the step ends included) along
    each flight: f - delta at the upper wall, (delta - gap) - f at the lower."""
    p = res.params
    delta, lower, A = p["delta"], p["delta"] - p["gap"], p["amplitude"]
    t = res.impact_time
    out = np.empty(flights.size)
    for i, j in enumerate(flights):
        k_lo, k_hi = res.impact_step[j], res.impact_step[j + 1] + 1
        grid = np.concatenate([np.linspace(k * DT, (k + 1) * DT, per_step + 1)
                               for k in range(k_lo, k_hi)])
        s = np.concatenate([[t[j]], grid[(grid > t[j]) & (grid < t[j + 1])], [t[j + 1]]])
        f = np.interp(s, np.arange(record.size) * DT, record) + A * np.sin(BETA_F * s)
        out[i] = (f - delta).min() if wall[j] == 0 else (lower - f).min()
    return out


@pytest.mark.parametrize("case", [CASES[1], (0.1, 0.4, 0.6, 0.4, 0.0)])
def test_the_lower_walls_hops_are_pressed_towards_it(record, case):
    """The exact test against the force sampled every h/64 along each flight between two
    impacts at one wall: a pressed flight is > 0 at every sample; a flight found not pressed
    dips to <= 0 there (or within the samples' gap, 1e-6 for the harmonic part's curvature).
    Flights between the walls are never pressed. The compiled test agrees exactly."""
    delta, gap, eps, eps_lower, amplitude = case
    res = _run(record[:30_001], *case)
    w = res.impact_wall
    kw = dict(delta=delta, amplitude=amplitude, beta=BETA_F, wall=w, gap=gap)
    pressed = stats.pressed_flights(res.impact_step, res.impact_offset, record, DT, **kw)
    compiled = compiled_pressed_flights(res.impact_step, res.impact_offset, record, DT, **kw)
    np.testing.assert_array_equal(compiled, pressed)
    cross = w[:-1] != w[1:]
    assert cross.any() and not pressed[cross].any()
    for side in (0, 1):
        same = ~cross & (w[:-1] == side)
        assert pressed[same].sum() > 20 and (~pressed[same]).sum() > 20, side
        rng = np.random.default_rng(side)
        pick = np.concatenate([rng.choice(np.flatnonzero(same & pressed), 20, replace=False),
                               rng.choice(np.flatnonzero(same & ~pressed), 20,
                                          replace=False)])
        low = _dense_push_minimum(res, record, pick, w)
        assert np.all(low[:20] > 0.0), side
        assert np.all(low[20:] <= 1e-6), side


def test_the_lower_wall_push_is_the_mirrored_upper_one():
    """Hand-made: a constant force f = -0.6 with the walls at 0.1 and -0.4 presses the mass
    onto the lower wall (x_L - f = 0.2 > 0), never onto the upper one (f - delta < 0); a
    force of -0.3 presses onto neither."""
    step = np.array([10, 12, 15, 18, 20])
    offset = np.full(5, 0.05)
    wall = np.array([0, 0, 1, 1, 0])
    for r, want in ((-0.6, [False, False, True, False]), (-0.3, [False] * 4)):
        force = np.full(40, r)
        for fn in (stats.pressed_flights, compiled_pressed_flights):
            got = fn(step, offset, force, DT, delta=0.1, wall=wall, gap=0.5)
            assert list(got) == want, (fn, r)
    with pytest.raises(ValueError, match="wall and gap go together"):
        stats.pressed_flights(step, offset, force, DT, delta=0.1, wall=wall)


# ---- statistics per wall --------------------------------------------------------------------

def test_the_velocity_after_impact_has_each_walls_restitution():
    u = np.array([1.0, 2.0, 3.0])
    v = stats.velocity_after_impact(u, 0.5, wall=[0, 1, 0], eps_lower=0.25)
    np.testing.assert_array_equal(v, [0.5, 0.5, 1.5])
    np.testing.assert_array_equal(stats.velocity_after_impact(u, 0.5), 0.5 * u)
    with pytest.raises(ValueError, match="go together"):
        stats.velocity_after_impact(u, 0.5, wall=[0, 1, 0])
    z = stats.impact_intervals([1, 3, 4, 8], [0.0, 0.0, 0.05, 0.0], DT, wall=[0, 1, 0, 1], at=1)
    np.testing.assert_allclose(z, [0.5])


def test_wall_statistics_are_each_walls_collisions(record):
    """On a clearance record: the counts add up to the collisions, each wall's rate, mean
    interval, speed after impact and densities are the one-wall estimators applied to its
    own collisions (same-wall intervals, eps_w u), and the two walls differ."""
    delta, gap, eps, eps_lower, amplitude = CASES[1]
    res = _run(record, *CASES[1])
    start, end, sw = _phases(res)
    kw = dict(delta=delta, amplitude=amplitude, beta=BETA_F)
    pressed = stats.pressed_flights(res.impact_step, res.impact_offset, record, DT,
                                    wall=res.impact_wall, gap=gap, **kw)
    col = stats.group_collisions(res.impact_step, res.impact_offset, res.impact_velocity,
                                 start, end, dt=DT, eps=eps, pressed=pressed,
                                 wall=res.impact_wall, stick_wall=sw,
                                 eps_lower=eps_lower).after(100.0)
    out = stats.wall_statistics(col, 100.0, res.t_end, eps=eps, eps_lower=eps_lower,
                                bins=BINS, n_batches=B, beta_f=BETA_F)
    assert out["wall_n_collisions"].sum() == col.time.size
    assert out["wall_v_after_density"].shape == (2, BINS["v_after"].size - 1)
    for w, e in enumerate((eps, eps_lower)):
        c = col.at_wall(w)
        assert c.time.size > 1000 and np.all(c.wall == w)
        rate = stats.event_rate(c.time, 100.0, res.t_end, B)
        assert out["wall_collision_rate"][w] == rate.rate
        assert out["wall_interval_mean"][w] == (res.t_end - 100.0) / c.time.size
        mark = stats.mark_mean(e * c.velocity, c.time, 100.0, res.t_end, B)
        assert out["wall_v_after_mean"][w] == mark.mean
        z = np.diff(c.time)
        dens = stats.density(z, BINS["interval"], total=z.size, n_batches=B)
        np.testing.assert_allclose(out["wall_interval_density"][w], dens.density,
                                   rtol=1e-12, atol=1e-12)
    # the restitutions differ (0.5 above, 0.3 below): so do the speeds after impact
    assert out["wall_v_after_mean"][0] > out["wall_v_after_mean"][1]


# ---- the two identities with a term per wall ------------------------------------------------

def _sums(res, k0, n, bounds, u=None):
    """Per wall and batch, the sums of V and V^2 (``u``, default the record's) of the
    impacts in the steps k0 .. n - 1."""
    u = res.impact_velocity if u is None else u
    hit = (res.impact_step >= k0) & (res.impact_step < n)
    b = np.searchsorted(bounds, res.impact_step[hit], side="right") - 1
    u, w = u[hit], res.impact_wall[hit]
    nb = bounds.size - 1
    return (np.array([np.bincount(b[w == s], u[w == s], nb) for s in (0, 1)]),
            np.array([np.bincount(b[w == s], u[w == s] ** 2, nb) for s in (0, 1)]))


def _audit(res, r, case, velocity_scale=(1.0, 1.0), moments=stats.flight_moments):
    """Residuals of a clearance record from step 500 on, with each wall's impact velocities
    scaled (a tampered record), and the boundary terms [E]/T, [x v + zeta x^2]/T."""
    delta, gap, eps, eps_lower, amplitude = case
    k0, n = 500, r.size - 1
    bounds = np.linspace(k0, n, B + 1).astype(np.int64)
    start, end, sw = _phases(res)
    x, v = delta - res.a, res.v
    upper_scale, lower_scale = velocity_scale
    u = res.impact_velocity * np.where(res.impact_wall == 1, lower_scale, upper_scale)
    kw = dict(zeta=ZETA, eps=eps, delta=delta, amplitude=amplitude, beta_f=BETA_F,
              impact_time=res.impact_time, impact_velocity=u, stick_start=start,
              stick_end=end, gap=gap, eps_lower=eps_lower, impact_wall=res.impact_wall,
              stick_wall=sw)
    if moments is audit_moments:
        m = audit_moments(k0, res.a[k0:n], v[k0:n], r[k0:], DT, batch_bounds=bounds, **kw)
    else:
        batch = np.searchsorted(bounds, k0 + np.arange(n - k0), side="right") - 1
        m = stats.flight_moments(k0, x[k0:n], v[k0:n], r[k0:], DT, batch=batch,
                                 n_batches=B, **kw)
    su, su2 = _sums(res, k0, n, bounds, u)
    out = stats.identity_residuals(m, su, su2, np.diff(bounds) * DT, zeta=ZETA, eps=eps,
                                   delta=delta, gap=gap, eps_lower=eps_lower)
    T = (n - k0) * DT
    E = 0.5 * (x[n] ** 2 + v[n] ** 2 - x[k0] ** 2 - v[k0] ** 2) / T
    W = (x[n] * v[n] + ZETA * x[n] ** 2 - x[k0] * v[k0] - ZETA * x[k0] ** 2) / T
    return out, E, W, m


@pytest.mark.parametrize("case", CASES)
def test_the_two_wall_residual_is_the_boundary_term_to_round_off(record, case):
    """With one impact term per wall (its loss, its position times its momentum transfer)
    the residuals minus their boundary terms are round-off, chatter, sticking and tails at
    both walls included; the compiled audit gives the same."""
    res = _run(record, *case)
    assert np.bincount(res.impact_wall, minlength=2).min() > 1000
    for moments in (stats.flight_moments, audit_moments):
        out, E, W, m = _audit(res, record, case, moments=moments)
        assert m.shape == (len(stats.moment_rows(True)), B)
        assert abs(out.power - E) < 1e-12, (moments, out.power, E)
        assert abs(out.virial - W) < 1e-12, (moments, out.virial, W)
        assert abs(out.power) < 3.0 * out.power_stderr
        assert abs(out.virial) < 3.0 * out.virial_stderr


@pytest.mark.parametrize("case, scale, identity", [
    (CASES[0], (1.0, 1.1), "virial"), (CASES[0], (1.0, 1.1), "power"),
    (CASES[2], (1.0, 1.1), "virial")])
def test_a_tampered_lower_wall_shows(record, case, scale, identity):
    """The lower wall's velocities scaled by 1.1 (the upper wall's untouched) move the
    residual far beyond its error: the lower wall's term is read (the power balance reads
    it where eps_lower < 1, the virial where delta - gap != 0)."""
    res = _run(record, *case)
    honest = _audit(res, record, case)[0]
    tampered = _audit(res, record, case, velocity_scale=scale)[0]
    value = lambda o: (getattr(o, identity), getattr(o, f"{identity}_stderr"))
    assert abs(value(honest)[0]) < 3.0 * value(honest)[1]
    assert abs(value(tampered)[0]) > 5.0 * value(tampered)[1]


def test_the_kernel_equals_the_reference_chunk_by_chunk(record):
    """As the events cells feed them: chunks of 2**12 samples, an open sticking phase closed
    at each chunk's end on the wall the mass rests on; rows within 1e-12 of their largest."""
    delta, gap, eps, eps_lower, amplitude = CASES[1]
    r = record[:40_001]
    k_start, k_stop = 777, r.size - 1
    bounds = np.linspace(k_start, k_stop, 5).astype(np.int64)
    got = np.zeros((len(stats.moment_rows(True)), 4))
    ref = np.zeros_like(got)
    params = dict(zeta=ZETA, eps=eps, delta=delta, amplitude=amplitude, beta_f=BETA_F,
                  gap=gap, eps_lower=eps_lower)
    for chunk in simulate_chunks(ZETA, eps, delta, noise=r, dt=DT, amplitude=amplitude,
                                 beta=BETA_F, record_every=1, chunk_size=2**12, gap=gap,
                                 eps_lower=eps_lower):
        k0 = int(round(chunk.grid_time[0] / DT))
        lo, hi = max(k_start, k0), min(k_stop, k0 + chunk.grid_time.size)
        start, end, sw = _phases(chunk)
        kw = dict(params, impact_time=chunk.impact_time, impact_velocity=chunk.impact_velocity,
                  stick_start=start, stick_end=end, impact_wall=chunk.impact_wall,
                  stick_wall=sw)
        a, v = chunk.a[lo - k0:hi - k0], chunk.v[lo - k0:hi - k0]
        got += audit_moments(lo, a, v, r[lo:hi + 1], DT, batch_bounds=bounds, **kw)
        batch = np.searchsorted(bounds, lo + np.arange(hi - lo), side="right") - 1
        ref += stats.flight_moments(lo, delta - a, v, r[lo:hi + 1], DT, batch=batch,
                                    n_batches=4, **kw)
    assert ref[7:].any(axis=1).all()                  # the lower wall rested and chattered
    scale = np.abs(ref).max(axis=1, keepdims=True)
    assert np.all(np.abs(got - ref) <= 1e-12 * np.where(scale > 0, scale, 1.0))


def test_the_identities_refuse_mismatched_walls():
    m = np.zeros((len(stats.moment_rows(True)), 2))
    with pytest.raises(ValueError, match="gap and eps_lower go together"):
        stats.identity_residuals(m, np.zeros((2, 2)), np.zeros((2, 2)), [1.0, 1.0], zeta=0.05,
                                 eps=0.5, delta=0.0, gap=1.0)
    with pytest.raises(ValueError, match="moments must have the rows"):
        stats.identity_residuals(m, np.zeros(2), np.zeros(2), [1.0, 1.0], zeta=0.05,
                                 eps=0.5, delta=0.0, gap=1.0, eps_lower=0.5)
    with pytest.raises(ValueError, match="need a second wall"):
        stats.flight_moments(0, [0.0], [0.0], [0.0, 0.0], DT, zeta=0.05, eps=0.5, delta=0.0,
                             eps_lower=0.5)


def test_identity_residuals_of_given_sums_with_two_walls():
    """The pure combination by hand: the lower wall at x_L = -1.5 (delta = -0.5, gap = 1),
    eps_lower = 0.8, one batch of length 2."""
    # rows v2, x2, fv, xf, push, tail, tail2, push_lower, tail_lower, tail2_lower
    m = np.array([[1.0], [0.5], [0.3], [0.2], [0.4], [0.0], [0.0], [0.3], [0.1], [0.01]])
    out = stats.identity_residuals(np.hstack([m, m]), [[1.0, 1.0], [2.0, 2.0]],
                                   [[2.0, 2.0], [3.0, 3.0]], [2.0, 2.0], zeta=0.05, eps=0.5,
                                   delta=-0.5, gap=1.0, eps_lower=0.8)
    power = (0.3 - 0.1 - 0.375 * 2.0 - 0.18 * 3.0 - 0.005) / 2.0
    virial = (1.0 - 0.5 + 0.2 + 0.5 * (1.5 + 0.4) - 1.5 * (1.8 * 2.0 - 0.1 + 0.3)) / 2.0
    assert out.power == pytest.approx(power)
    assert out.virial == pytest.approx(virial)


# ---- the far-wall limit -------------------------------------------------------------------

@pytest.mark.parametrize("delta, eps, amplitude", [(0.5, 0.5, 0.0), (-0.5, 0.5, 0.0),
                                                   (0.3, 0.5, 1.0), (-0.3, 0.0, 0.0)])
def test_a_far_second_wall_gives_every_one_wall_statistic_bit_for_bit(record, delta, eps,
                                                                      amplitude):
    """gap = 1e6 is never reached: the collisions (every rule), the pressed flights, the
    per-wall statistics' upper row, the audit's moments and residuals are the one-wall ones
    to the bit; the lower wall's rows and counts are empty."""
    r = record[:50_001]
    kw = dict(noise=r, dt=DT, amplitude=amplitude, beta=BETA_F, record_every=1)
    one = simulate(ZETA, eps, delta, **kw)
    far = simulate(ZETA, eps, delta, gap=1e6, **kw)
    assert one.n_impacts > 100 and not far.impact_wall.any()
    force = dict(delta=delta, amplitude=amplitude, beta=BETA_F)
    p1 = stats.pressed_flights(one.impact_step, one.impact_offset, r, DT, **force)
    p2 = stats.pressed_flights(far.impact_step, far.impact_offset, r, DT, **force,
                               wall=far.impact_wall, gap=1e6)
    c2 = compiled_pressed_flights(far.impact_step, far.impact_offset, r, DT, **force,
                                  wall=far.impact_wall, gap=1e6)
    np.testing.assert_array_equal(p2, p1)
    np.testing.assert_array_equal(c2, p1)
    s1 = stats.close_open_phase(one.stick_start, one.stick_end, one.stuck_since, one.t_end)
    s2 = _phases(far)
    for rule in stats.RULES:
        g1 = stats.group_collisions(one.impact_step, one.impact_offset, one.impact_velocity,
                                    *s1, dt=DT, eps=eps, pressed=p1, rule=rule)
        g2 = stats.group_collisions(far.impact_step, far.impact_offset, far.impact_velocity,
                                    *s2[:2], dt=DT, eps=eps, pressed=p2, rule=rule,
                                    wall=far.impact_wall, stick_wall=s2[2], eps_lower=eps)
        for name in g1._fields:
            np.testing.assert_array_equal(getattr(g2, name), getattr(g1, name),
                                          err_msg=(rule, name))
    col1 = stats.group_collisions(one.impact_step, one.impact_offset, one.impact_velocity,
                                  *s1, dt=DT, eps=eps, pressed=p1).after(100.0)
    col2 = stats.group_collisions(far.impact_step, far.impact_offset, far.impact_velocity,
                                  *s2[:2], dt=DT, eps=eps, pressed=p2, wall=far.impact_wall,
                                  eps_lower=eps).after(100.0)
    walls = stats.wall_statistics(col2, 100.0, far.t_end, eps=eps, eps_lower=eps, bins=BINS,
                                  n_batches=B, beta_f=BETA_F)
    rate = stats.event_rate(col1.time, 100.0, one.t_end, B)
    v_after = stats.velocity_after_impact(col1.velocity, eps)
    mark = stats.mark_mean(v_after, col1.time, 100.0, one.t_end, B)
    z_dens = stats.density(col1.intervals, BINS["interval"], total=col1.intervals.size,
                           n_batches=B)
    v_dens = stats.density(v_after, BINS["v_after"], total=v_after.size, n_batches=B)
    assert walls["wall_n_collisions"].tolist() == [col1.time.size, 0]
    for got, want in ((walls["wall_collision_rate"][0], rate.rate),
                      (walls["wall_interval_mean"][0], rate.mean_interval),
                      (walls["wall_v_after_mean"][0], mark.mean),
                      (walls["wall_v_after_density"][0], v_dens.density),
                      (walls["wall_interval_density"][0], z_dens.density)):
        np.testing.assert_array_equal(got, want)
    # the audit: the one-wall rows to the bit, the lower wall's rows zero
    k0, n = 500, r.size - 1
    bounds = np.linspace(k0, n, B + 1).astype(np.int64)
    common = dict(zeta=ZETA, eps=eps, delta=delta, amplitude=amplitude, beta_f=BETA_F,
                  batch_bounds=bounds)
    m1 = audit_moments(k0, one.a[k0:n], one.v[k0:n], r[k0:], DT, impact_time=one.impact_time,
                       impact_velocity=one.impact_velocity, stick_start=s1[0],
                       stick_end=s1[1], **common)
    m2 = audit_moments(k0, far.a[k0:n], far.v[k0:n], r[k0:], DT, impact_time=far.impact_time,
                       impact_velocity=far.impact_velocity, stick_start=s2[0],
                       stick_end=s2[1], gap=1e6, eps_lower=eps, impact_wall=far.impact_wall,
                       stick_wall=s2[2], **common)
    np.testing.assert_array_equal(m2[:len(stats.identities.MOMENTS)], m1)
    assert not m2[len(stats.identities.MOMENTS):].any()
    su, su2 = _sums(far, k0, n, bounds)
    res1 = stats.identity_residuals(m1, su[0], su2[0], np.diff(bounds) * DT, zeta=ZETA,
                                    eps=eps, delta=delta)
    res2 = stats.identity_residuals(m2, su, su2, np.diff(bounds) * DT, zeta=ZETA, eps=eps,
                                    delta=delta, gap=1e6, eps_lower=eps)
    assert tuple(res2) == tuple(res1)
