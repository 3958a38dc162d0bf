"""Periodic impact motions (paper section 4): physics checks of ``vibroimpact.orbits``.

The independent references here share no code with the package: a textbook closed-form flight
(particular solution ``P sin + Q cos``), a first-crossing impact map by sampling and bisection,
scipy's DOP853 with events, and brute-force scans of phase/velocity and phase/interval space.
"""
import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, root

from vibroimpact.orbits import PeriodicOrbit, orbit_map, periodic_orbits
from vibroimpact.orbits.flight import harmonic_constants
from vibroimpact.orbits.newton import _residual_jacobian
from vibroimpact.orbits.scan_m2 import _m2_null

ZETA, EPS = 0.05, 0.5


# ------------------------------------------------------------------------------------------
# independent references

def textbook_flight(tau_a, u_a, s, beta, delta, zeta, eps):
    """x, v of x'' + 2 zeta x' + x = sin(beta t) from x = delta, x' = -eps u_a at t = tau_a."""
    w = math.sqrt(1.0 - zeta ** 2)
    den = (1.0 - beta ** 2) ** 2 + (2.0 * zeta * beta) ** 2
    p, qq = (1.0 - beta ** 2) / den, -2.0 * zeta * beta / den
    t = tau_a + s
    xp = p * np.sin(beta * t) + qq * np.cos(beta * t)
    vp = beta * (p * np.cos(beta * t) - qq * np.sin(beta * t))
    y0 = delta - (p * np.sin(beta * tau_a) + qq * np.cos(beta * tau_a))
    v0 = -eps * u_a - beta * (p * np.cos(beta * tau_a) - qq * np.sin(beta * tau_a))
    c2 = (v0 + zeta * y0) / w
    e, cs, sn = np.exp(-zeta * s), np.cos(w * s), np.sin(w * s)
    x = xp + e * (y0 * cs + c2 * sn)
    v = vp + e * ((-zeta * y0 + w * c2) * cs + (-zeta * c2 - w * y0) * sn)
    return x, v


#: Samples of the flights scanned at once: a flight found above delta leaves the scan, so
#: most of the range up to smax (sized for the longest flight) is never evaluated.
SCAN_BLOCK = 128


def sampled_impact_map(tau, u, beta, delta, zeta, eps, smax, ds):
    """Vectorized first upward crossing of delta (sampling + bisection); NaN if none by smax."""
    tau = np.asarray(tau, float).ravel()
    u = np.asarray(u, float).ravel()
    s = np.arange(1, int(np.ceil(smax / ds)) + 1) * ds
    first = np.full(tau.size, -1)               # index of the first sample above delta
    todo = np.arange(tau.size)
    for start in range(0, s.size, SCAN_BLOCK):
        block = s[None, start:start + SCAN_BLOCK]
        left = []
        for sl in np.array_split(todo, max(1, todo.size * block.size // 2_000_000)):
            above = textbook_flight(tau[sl][:, None], u[sl][:, None], block, beta, delta,
                                    zeta, eps)[0] > delta
            has = above.any(axis=1)
            first[sl[has]] = start + np.argmax(above[has], axis=1)
            left.append(sl[~has])
        todo = np.concatenate(left) if left else todo
        if not todo.size:
            break
    out_t = np.full(tau.size, np.nan)
    out_u = np.full(tau.size, np.nan)
    has = first >= 0
    k = first[has]
    lo = np.where(k > 0, s[np.maximum(k - 1, 0)], 0.0)
    ta1, ua1 = tau[has], u[has]
    if ta1.size == 1:       # a root finder's point: the same steps on floats, ~10x cheaper
        s1 = np.array([_crossing_one(float(ta1[0]), float(ua1[0]), float(lo[0]),
                                     float(s[k[0]]), beta, delta, zeta, eps)])
    else:
        s1 = _crossing(ta1, ua1, lo, s[k], beta, delta, zeta, eps)
    out_t[has] = ta1 + s1
    out_u[has] = textbook_flight(ta1, ua1, s1, beta, delta, zeta, eps)[1]
    return out_t, out_u


def _crossing(ta, ua, lo, hi, beta, delta, zeta, eps):
    """A root of ``x - delta`` in ``(lo, hi]`` (``x(lo) <= delta < x(hi)``) to round-off: Newton
    steps with the flight's own velocity from ``hi``, a bisection wherever one leaves the
    bracket (the fixed points found agree with those of plain bisection to 1e-13)."""
    s = hi.copy()
    for _ in range(100):
        x, v = textbook_flight(ta, ua, s, beta, delta, zeta, eps)
        up = x > delta
        hi, lo = np.where(up, s, hi), np.where(up, lo, s)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = s - (x - delta) / v
        inside = (newton > lo) & (newton < hi)
        s_new = np.where(inside, newton, 0.5 * (lo + hi))
        done = (np.abs(s_new - s) <= 4e-16 * np.abs(s)) | (hi - lo <= 4e-16 * hi)
        s = s_new
        if done.all():
            break
    return s


def _crossing_one(ta, ua, lo, hi, beta, delta, zeta, eps):
    """:func:`_crossing` of one flight, on floats (numpy's per-call cost on arrays of one
    element made most of the dense searches' root finding)."""
    s = hi
    for _ in range(100):
        x, v = textbook_flight(ta, ua, s, beta, delta, zeta, eps)
        if x > delta:
            hi = s
        else:
            lo = s
        newton = s - (x - delta) / v if v != 0.0 else math.nan
        s_new = newton if lo < newton < hi else 0.5 * (lo + hi)
        done = abs(s_new - s) <= 4e-16 * abs(s) or hi - lo <= 4e-16 * hi
        s = s_new
        if done:
            break
    return s


def dop853_impact_map(tau, u, beta, delta, zeta, eps, smax, max_step=0.01):
    """One impact-map step by scipy DOP853 (rtol = atol = 1e-12) with a crossing event.

    ``max_step`` keeps a low-velocity impact (a short excursion above delta) from slipping
    between two steps, where the event's sign test would not see it.
    """
    def rhs(t, y):
        return [y[1], math.sin(beta * t) - 2.0 * zeta * y[1] - y[0]]

    def hit(t, y):
        return y[0] - delta
    hit.terminal, hit.direction = True, 1.0
    sol = solve_ivp(rhs, (tau, tau + smax), [delta, -eps * u], method="DOP853", rtol=1e-12,
                    atol=1e-12, events=hit, max_step=max_step)
    return sol.t_events[0][0], sol.y_events[0][0][1]


def circ_dist(a, b, period):
    d = abs(a - b) % period
    return min(d, period - d)


def impact_points(orbits):
    """(orbit index, phase mod T_f, approach velocity) of every impact of every orbit."""
    pts = []
    for k, o in enumerate(orbits):
        for j, t in enumerate(o.impact_times):
            pts.append((k, t % (2 * math.pi / o.beta), o.velocities[j - 1]))
    return pts


def exhaustive_fixed_points(m, n, beta, delta, zeta, eps, nt, nu):
    """Fixed points of the m-fold (sampled) impact map advancing by z: admissible orbits.

    Dense scan of (phase, velocity); a cell where both residual components change sign seeds
    a root finder; roots are kept when the map returns to within 1e-8.
    """
    tf = 2 * math.pi / beta
    z = n * tf
    amp = 1.0 / math.sqrt((1 - beta ** 2) ** 2 + (2 * zeta * beta) ** 2)
    umax = 2.5 * (beta * amp + abs(delta) + 1.0)
    ds = 0.01 / max(beta, 1.0)

    def pm(t, u):
        for _ in range(m):
            t, u = sampled_impact_map(t, u, beta, delta, zeta, eps, 1.25 * z + 1.0, ds)
        return t, u

    taus = (np.arange(nt + 1) + 0.5) * tf / nt          # one extra row wraps the phase
    us = np.linspace(umax / nu, umax, nu)
    tt, uu = np.meshgrid(taus, us, indexing="ij")
    t1, u1 = pm(tt, uu)
    r1 = t1.reshape(tt.shape) - tt - z
    r2 = u1.reshape(tt.shape) - uu

    def resid(p):
        a, b = pm(np.array([p[0]]), np.array([p[1]]))
        return [a[0] - p[0] - z, b[0] - p[1]]

    def shorter(p):
        # a fixed point of a shorter map (m/d impacts over n/d cycles) repeats a shorter orbit
        for d in range(2, math.gcd(m, n) + 1):
            if m % d or n % d:
                continue
            t, u = np.array([p[0]]), np.array([p[1]])
            for _ in range(m // d):
                t, u = sampled_impact_map(t, u, beta, delta, zeta, eps, 1.25 * z + 1.0, ds)
            if abs(t[0] - p[0] - z / d) < 1e-7 and abs(u[0] - p[1]) < 1e-7:
                return True
        return False

    found = []
    for i in range(nt):
        for j in range(nu - 1):
            c1, c2 = r1[i:i + 2, j:j + 2], r2[i:i + 2, j:j + 2]
            if np.isnan(c1).any() or np.isnan(c2).any():
                continue
            if c1.min() > 0 or c1.max() < 0 or c2.min() > 0 or c2.max() < 0:
                continue
            sol = root(resid, [taus[i] + 0.5 * tf / nt, us[j] + 0.5 * (us[1] - us[0])],
                       method="hybr", tol=1e-13)
            if (sol.success and np.max(np.abs(resid(sol.x))) < 1e-8 and sol.x[1] > 0
                    and not shorter(sol.x)):
                p = (sol.x[0] % tf, sol.x[1])
                if not any(circ_dist(p[0], q[0], tf) < 1e-6 and abs(p[1] - q[1]) < 1e-6
                           for q in found):
                    found.append(p)
    return found


def phase_interval_roots(m, beta, delta, zeta, eps, nt, nz):
    """All solutions of the (m/1) equations, admissible or not, for m = 1, 2.

    Independent residual: from an impact at tau0 the position condition of each flight is
    linear in the leaving velocity, which fixes it; the velocity mismatches are the residual.
    m = 1 scans tau0; m = 2 scans (tau0, z1). Returns (phase, approach velocity) pairs.
    """
    tf = 2 * math.pi / beta
    z = tf

    def leave_velocity(ta, s):
        # x(s) is affine in the approach velocity u_a: solve x(s) = delta for u_a
        x0 = textbook_flight(ta, 0.0, s, beta, delta, zeta, eps)[0]
        x1 = textbook_flight(ta, 1.0, s, beta, delta, zeta, eps)[0]
        return (delta - x0) / (x1 - x0)

    def resid(p):
        if m == 1:
            ta = p[0]
            ua = leave_velocity(ta, z)
            return np.array([textbook_flight(ta, ua, z, beta, delta, zeta, eps)[1] - ua]), ua
        ta, z1 = p
        u0 = leave_velocity(ta, z1)                    # approach velocity at tau0
        u1 = textbook_flight(ta, u0, z1, beta, delta, zeta, eps)[1]
        u1_needed = leave_velocity(ta + z1, z - z1)          # flight 2 lands at tau0 + z
        v2 = textbook_flight(ta + z1, u1, z - z1, beta, delta, zeta, eps)[1]
        return np.array([u1 - u1_needed, v2 - u0]), u0

    out = []
    if m == 1:
        taus = np.linspace(0.0, tf, nt + 1)
        r = np.array([resid([t])[0][0] for t in taus])
        for i in range(nt):
            if r[i] * r[i + 1] < 0:
                t = brentq(lambda x: resid([x])[0][0], taus[i], taus[i + 1], xtol=1e-14)
                out.append((t % tf, resid([t])[1]))
        return out
    taus = np.linspace(0.0, tf, nt + 1)
    zs = np.linspace(0.0, z, nz + 1)[1:-1]
    tt, zz = np.meshgrid(taus, zs, indexing="ij")
    r = np.array([resid([a, b])[0] for a, b in zip(tt.ravel(), zz.ravel())])
    r1, r2 = r[:, 0].reshape(tt.shape), r[:, 1].reshape(tt.shape)
    for i in range(nt):
        for j in range(zs.size - 1):
            c1, c2 = r1[i:i + 2, j:j + 2], r2[i:i + 2, j:j + 2]
            if not (np.isfinite(c1).all() and np.isfinite(c2).all()):
                continue
            if c1.min() > 0 or c1.max() < 0 or c2.min() > 0 or c2.max() < 0:
                continue
            sol = root(lambda p: resid(p)[0], [tt[i, j] + 0.5 * tf / nt, zz[i, j]], tol=1e-13)
            if not sol.success or np.max(np.abs(resid(sol.x)[0])) > 1e-9:
                continue
            if not 0 < sol.x[1] < z:
                continue
            u0 = resid(sol.x)[1]
            u1 = textbook_flight(sol.x[0], u0, sol.x[1], beta, delta, zeta, eps)[1]
            if u0 > 0 and u1 > 0:
                out.append((sol.x[0] % tf, u0))
    return out


def assert_all_found(reference, orbits, tf, what):
    pts = impact_points(orbits)
    for phase, u in reference:
        assert any(circ_dist(phase, p, tf) < 1e-6 and abs(u - uu) < 1e-6 for _, p, uu in pts), (
            f"{what}: independent search found an impact at phase {phase:.9f}, u = {u:.9f} "
            f"that periodic_orbits misses")


# ------------------------------------------------------------------------------------------
# the acceptance call and the result object

def test_acceptance_call():
    orbits = periodic_orbits(m=1, n=1, beta=1 / 1.2, delta=0.5, zeta=0.05, eps=0.5)
    assert len(orbits) >= 1
    tf = 2 * math.pi * 1.2
    for o in orbits:
        assert isinstance(o, PeriodicOrbit)
        assert 0.0 <= o.tau0 < tf
        assert o.intervals.shape == (1,) and o.velocities.shape == (1,)
        assert o.intervals.sum() == pytest.approx(tf, rel=1e-12)
        assert np.all(o.velocities > 0)
        assert o.multipliers.shape == (2,) and np.iscomplexobj(o.multipliers)
        assert o.lam == pytest.approx(np.abs(o.multipliers).max(), rel=1e-12)
        assert o.S == pytest.approx(100 * (1 - o.lam), rel=1e-12)
        assert o.stable == (o.lam < 1)
        assert o.admissible and o.margin >= 0
        assert (o.m, o.n, o.zeta, o.eps, o.delta) == (1, 1, 0.05, 0.5, 0.5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        orbits[0].tau0 = 0.0                              # frozen


def test_multiplicity_one_orbit_at_acceptance_point():
    """At 1/beta = 1.2, delta = 0.5 there is exactly one (1/1) motion, stable with complex mu
    of modulus eps exp(-zeta z) (1e-12)."""
    orbits = periodic_orbits(1, 1, 1 / 1.2, 0.5, ZETA, EPS)
    assert len(orbits) == 1
    o = orbits[0]
    assert abs(o.multipliers[0].imag) > 0
    assert abs(o.multipliers[0]) == pytest.approx(EPS * math.exp(-ZETA * o.period), rel=1e-12)


@pytest.mark.parametrize("kwargs, name", [
    (dict(m=0), "m"), (dict(m=1.5), "m"), (dict(n=-1), "n"), (dict(n=True), "n"),
    (dict(beta=0.0), "beta"), (dict(beta=float("inf")), "beta"), (dict(beta="a"), "beta"),
    (dict(delta=float("nan")), "delta"), (dict(delta="abc"), "delta"),
    (dict(zeta=0.0), "zeta"), (dict(zeta=1.0), "zeta"),
    (dict(eps=-0.1), "eps"), (dict(eps=1.5), "eps"),
])
def test_invalid_input_names_the_argument(kwargs, name):
    args = dict(m=1, n=1, beta=1.0, delta=0.5, zeta=0.05, eps=0.5)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        periodic_orbits(**args)


def test_a_model_gives_the_loose_call_bit_for_bit_and_any_other_law_is_refused():
    """``model=`` is the loose call (every field of every orbit equal to the bit); a model the
    closed form does not solve (second wall, speed-dependent law, amplitude other than 1) is
    refused in one line that names ``periodic_motions``, and so is a call giving both."""
    from vibroimpact import Model
    for m, n, ib, d in ((1, 1, 1.1, 0.5), (2, 1, 2.0, -0.5), (1, 2, 0.7, 0.5)):
        loose = periodic_orbits(m, n, 1 / ib, d, ZETA, EPS, include_inadmissible=True)
        shared = periodic_orbits(m, n, model=Model.paper(ZETA, EPS, d, 1.0, 1 / ib),
                                 include_inadmissible=True)
        assert len(loose) == len(shared) >= 1
        for a, b in zip(loose, shared):
            for f in dataclasses.fields(a):
                np.testing.assert_array_equal(getattr(a, f.name), getattr(b, f.name))
    for model, what in ((Model.paper(ZETA, EPS, 0.5, 1.0, 0.9, gap=2.0), "second wall"),
                        (Model.paper(ZETA, EPS, 0.5, 1.0, 0.9, speed_scale=3.0), "speed"),
                        (Model.paper(ZETA, EPS, 0.5, 2.0, 0.9), "amplitude 2.0")):
        with pytest.raises(ValueError, match=f"{what}.*periodic_motions") as err:
            periodic_orbits(1, 1, model=model)
        assert "\n" not in str(err.value)
    with pytest.raises(TypeError, match="not both.*zeta"):
        periodic_orbits(1, 1, zeta=ZETA, model=Model.paper(ZETA, EPS, 0.5, 1.0, 0.9))
    with pytest.raises(TypeError, match="missing eps"):
        periodic_orbits(1, 1, 0.9, 0.5, ZETA)
    with pytest.raises(TypeError, match="vibroimpact.Model"):
        periodic_orbits(1, 1, model=dict(zeta=ZETA))


def test_m_above_three_not_supported():
    with pytest.raises(NotImplementedError, match="m"):
        periodic_orbits(4, 1, 1.0, 0.0, ZETA, EPS)


# ------------------------------------------------------------------------------------------
# the orbit itself, the Jacobian and its determinant

ORBIT_CASES = [  # (m, n, 1/beta, delta): points with admissible orbits, stable or not
    (1, 1, 1.2, 0.5), (1, 1, 0.2, -0.6), (1, 1, 1.3, 2.3), (2, 1, 1.5, 1.0),
    (2, 1, 1.0, 0.1), (2, 1, 0.7, -0.3), (1, 2, 0.4, 0.3), (3, 1, 0.8, -0.4),
    (2, 2, 1.2, 2.1),
]
FAST_ORBIT_CASES = [(1, 1, 1.2, 0.5), (1, 1, 1.3, 2.3), (2, 1, 1.5, 1.0), (3, 1, 0.8, -0.4)]


def all_case_orbits(include_inadmissible=False, cases=ORBIT_CASES):
    for m, n, ib, d in cases:
        orbits = periodic_orbits(m, n, 1 / ib, d, ZETA, EPS,
                                 include_inadmissible=include_inadmissible)
        assert orbits, (m, n, ib, d)
        yield from orbits


def _check_repeat(cases, max_step):
    for o in all_case_orbits(cases=cases):
        tau, u = o.tau0, o.velocities[-1]
        for j in range(o.m):
            tau, u = dop853_impact_map(tau, u, o.beta, o.delta, ZETA, EPS, 1.5 * o.period,
                                       max_step)
            assert tau - o.impact_times[0] - o.intervals[:j + 1].sum() == pytest.approx(
                0.0, abs=1e-9)
            assert u == pytest.approx(o.velocities[j], abs=1e-9)


def test_orbits_repeat_under_independent_impact_map():
    """m DOP853 impact-map steps from (tau0, u) return to (tau0 + z, u): 1e-9 in time/velocity."""
    _check_repeat(FAST_ORBIT_CASES, 0.05)


@pytest.mark.slow
def test_orbits_repeat_under_independent_impact_map_all_cases():
    """Same on every case, including a (2/1) motion with an impact at u = 0.006 (small DOP853
    steps, so its short excursion above the wall is not stepped over)."""
    _check_repeat(ORBIT_CASES, 0.002)


def test_jacobian_determinant_identity():
    """det T = eps^(2m) exp(-2 zeta z) for every solution, admissible or not (rel. 1e-12)."""
    for o in all_case_orbits(include_inadmissible=True):
        expected = EPS ** (2 * o.m) * math.exp(-2 * ZETA * o.period)
        assert np.linalg.det(o.jacobian) == pytest.approx(expected, rel=1e-12)
        assert np.prod(o.multipliers).real == pytest.approx(expected, rel=1e-9)


def _check_fd(cases, max_step):
    for o in all_case_orbits(cases=cases):
        _check_fd_orbit(o, max_step)


def _check_fd_orbit(o, max_step):
    h = 1e-5 * min(1.0, o.velocities.min())

    def period_map(t, u):
        for _ in range(o.m):
            t, u = dop853_impact_map(t, u, o.beta, o.delta, ZETA, EPS, 1.5 * o.period,
                                     max_step)
        return np.array([t - o.period, u])

    def diff(f):
        return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12 * h)
    t0, u0 = o.tau0, o.velocities[-1]
    fd = np.column_stack([diff(lambda e: period_map(t0 + e, u0)),
                          diff(lambda e: period_map(t0, u0 + e))])
    scale = max(1.0, np.abs(fd).max())
    np.testing.assert_allclose(o.jacobian, fd, atol=1e-6 * scale)
    mu_fd = np.sort_complex(np.linalg.eigvals(fd))
    np.testing.assert_allclose(np.sort_complex(o.multipliers), mu_fd, atol=1e-6 * scale)


def test_multipliers_match_finite_differences_of_independent_map():
    """T from fourth-order central differences of the DOP853 impact map: entries and
    multipliers to 1e-6 of the largest entry. The step shrinks with the smallest impact
    velocity, since the map's curvature grows like 1/u."""
    _check_fd(FAST_ORBIT_CASES, 0.05)


@pytest.mark.slow
def test_multipliers_match_finite_differences_all_cases():
    _check_fd(ORBIT_CASES, 0.002)


def test_state_is_on_the_wall_at_impacts_and_below_it_between():
    for o in all_case_orbits():
        x, v = o.state(o.impact_times + 1e-13)
        np.testing.assert_allclose(x, o.delta, atol=1e-9)
        np.testing.assert_allclose(v, -EPS * np.roll(o.velocities, 1), atol=1e-9)
        tau = o.tau0 + np.linspace(0, o.period, 4001)
        assert o.state(tau)[0].max() <= o.delta + 1e-12


# ------------------------------------------------------------------------------------------
# admissibility: the grazing edge of the (1/1) motion

def _margin_11(beta, delta):
    orbits = periodic_orbits(1, 1, beta, delta, ZETA, EPS, include_inadmissible=True)
    assert len(orbits) == 1
    return orbits[0]


def test_grazing_edge_of_the_11_motion():
    """Along 1/beta = 1.2 the (1/1) flight's maximum reaches the wall between delta = 0.4
    and 0.5. At the edge the maximum touches delta (dense independent sampling, 1e-9); just
    above it the motion is returned, just below it is not (its flight crosses the wall)."""
    beta = 1 / 1.2
    d_g = brentq(lambda d: _margin_11(beta, d).margin, 0.4, 0.5, xtol=1e-13)
    o = _margin_11(beta, d_g)
    s = np.linspace(0.0, o.period, 200001)
    x, _ = textbook_flight(o.tau0, o.velocities[0], s, beta, d_g, ZETA, EPS)
    k = int(np.argmax(x[100:-100])) + 100          # interior maximum, away from the impacts
    assert x[k] - d_g == pytest.approx(0.0, abs=1e-9)
    assert 0.05 * o.period < s[k] < 0.95 * o.period
    above = periodic_orbits(1, 1, beta, d_g + 1e-6, ZETA, EPS)
    below = periodic_orbits(1, 1, beta, d_g - 1e-6, ZETA, EPS)
    assert len(above) == 1 and above[0].margin > 0
    assert below == []
    crossing = _margin_11(beta, d_g - 1e-6)
    xs = textbook_flight(crossing.tau0, crossing.velocities[0], s, beta, d_g - 1e-6, ZETA,
                         EPS)[0]
    assert xs[100:-100].max() > d_g - 1e-6           # the flight does cross the wall


# ------------------------------------------------------------------------------------------
# completeness: nothing missed, nothing repeated

FAST_EXHAUSTIVE = [(1, 1, 0.2, -0.6), (2, 1, 0.7, -0.3)]
SLOW_EXHAUSTIVE = [
    (1, 1, 1.2, 0.5), (1, 1, 2.0, 1.0), (1, 1, 0.3, -0.6), (2, 1, 1.5, 1.0), (2, 1, 0.7, -0.3),
    (2, 1, 1.0, 0.0), (2, 1, 3.0, 0.0), (1, 2, 0.4, 0.3), (1, 2, 0.2, -0.1), (1, 3, 0.3, 0.4),
    (3, 1, 0.8, -0.4), (3, 1, 0.2, -0.6), (2, 2, 1.2, 2.1), (2, 2, 1.2, 0.5), (2, 1, 1.0, 0.1),
]


def _check_exhaustive(m, n, ib, d, nt, nu):
    beta = 1 / ib
    orbits = periodic_orbits(m, n, beta, d, ZETA, EPS)
    ref = exhaustive_fixed_points(m, n, beta, d, ZETA, EPS, nt, nu)
    tf = 2 * math.pi / beta
    assert_all_found(ref, orbits, tf, f"({m}/{n}) at 1/beta={ib}, delta={d}")
    # and every returned orbit is a fixed point the brute force also sees
    ref_pts = [(p, u) for p, u in ref]
    for o in orbits:
        assert any(circ_dist(o.tau0, p, tf) < 1e-6 for p, _ in ref_pts) or any(
            circ_dist(t % tf, p, tf) < 1e-6 for t in o.impact_times for p, _ in ref_pts), o


@pytest.mark.parametrize("m, n, ib, d", FAST_EXHAUSTIVE)
def test_exhaustive_search_finds_nothing_missed(m, n, ib, d):
    """Brute force over (phase, velocity) of the m-fold impact map (70 x 70 cells)."""
    _check_exhaustive(m, n, ib, d, 70, 70)


@pytest.mark.slow
@pytest.mark.parametrize("m, n, ib, d", SLOW_EXHAUSTIVE)
def test_exhaustive_search_finds_nothing_missed_dense(m, n, ib, d):
    """Brute force over (phase, velocity), 150 x 150 cells, on a wider set of points."""
    _check_exhaustive(m, n, ib, d, 150, 150)


@pytest.mark.parametrize("ib, d", [(1.2, 0.5), (2.0, -0.5), (0.8, -0.5), (1.0, 0.0)])
def test_phase_interval_scan_all_solutions_m1(ib, d):
    """Every solution of eqs. (10)-(11), admissible or not, from a dense scan of the phase."""
    beta = 1 / ib
    ref = [(p, u) for p, u in phase_interval_roots(1, beta, d, ZETA, EPS, 4000, 0) if u > 0]
    orbits = periodic_orbits(1, 1, beta, d, ZETA, EPS, include_inadmissible=True)
    assert_all_found(ref, orbits, 2 * math.pi / beta, f"(1/1) at 1/beta={ib}, delta={d}")
    assert len(orbits) == len(ref)


@pytest.mark.slow
@pytest.mark.parametrize("ib, d", [(2.0, -0.5), (1.0, 0.0), (1.5, 1.0), (2.5, 0.3),
                                   (0.7, -0.3)])
def test_phase_interval_scan_all_solutions_m2(ib, d):
    """Every (2/1) solution, admissible or not, from a dense (tau0, z1) scan (300 x 300)."""
    beta = 1 / ib
    ref = phase_interval_roots(2, beta, d, ZETA, EPS, 300, 300)
    orbits = periodic_orbits(2, 1, beta, d, ZETA, EPS, include_inadmissible=True)
    assert_all_found(ref, orbits, 2 * math.pi / beta, f"(2/1) at 1/beta={ib}, delta={d}")


def test_no_duplicates():
    for m, n, ib, d in ORBIT_CASES:
        orbits = periodic_orbits(m, n, 1 / ib, d, ZETA, EPS, include_inadmissible=True)
        tf = 2 * math.pi * ib
        for i, a in enumerate(orbits):
            for b in orbits[i + 1:]:
                same = circ_dist(a.tau0, b.tau0, tf) < 1e-7 and np.allclose(
                    a.velocities, b.velocities, atol=1e-7)
                assert not same, (m, n, ib, d)


def test_repeated_shorter_orbit_is_not_a_22_motion():
    """A (1/1) motion traversed twice solves the (2/2) equations (residual 1e-12) but is not
    returned as (2/2); a genuine (2/2) motion at the same point is."""
    beta, delta = 1 / 1.2, 2.1
    (o11,) = periodic_orbits(1, 1, beta, delta, ZETA, EPS)
    z = 2 * o11.period
    y = np.array([o11.tau0, o11.tau0 + o11.period, o11.velocities[0], o11.velocities[0]])
    res = np.empty(4)
    jac = np.empty((4, 4))
    wd, q, phi = harmonic_constants(beta, ZETA)
    _residual_jacobian(y, 2, z, beta, delta, ZETA, EPS, wd, q, phi, res, jac)
    assert np.abs(res).max() < 1e-12
    orbits22 = periodic_orbits(2, 2, beta, delta, ZETA, EPS, include_inadmissible=True)
    for o in orbits22:
        assert not np.allclose(o.intervals, o11.period, atol=1e-6)
    assert len(orbits22) >= 1      # the genuine (2/2) motion there (see the dense scan)


def test_symmetric_22_system_has_the_same_null_space():
    """For even n the m = 2 scan takes the interval system in a symmetric form (sums and
    differences over 2 o of the two flights' rows, z_1 = z/2 + o): the same null vector as the
    plain system where that is well conditioned, and a regular one at o = 0, where the plain
    system has rank 3 (the doubled (1/(n/2)) motion)."""
    beta, delta = 1 / 1.3, 0.7
    wd, q, _ = harmonic_constants(beta, ZETA)
    kmat, sub, zs = np.empty((4, 5)), np.empty((4, 5)), np.empty(2)
    for n in (2, 4):
        z = 2 * math.pi * n / beta
        for o in (-1.1, -0.3, 0.05, 0.9):
            plain, sym = np.empty(5), np.empty(5)
            _m2_null(z / 2 + o, z, False, beta, delta, ZETA, EPS, wd, zs, kmat, sub, plain)
            _m2_null(z / 2 + o, z, True, beta, delta, ZETA, EPS, wd, zs, kmat, sub, sym)
            a, b = plain / np.linalg.norm(plain), sym / np.linalg.norm(sym)
            assert min(np.abs(a - b).max(), np.abs(a + b).max()) < 1e-12, (n, o)
        at_half = np.empty(5)
        _m2_null(z / 2, z, True, beta, delta, ZETA, EPS, wd, zs, kmat, sub, at_half)
        assert np.all(np.isfinite(at_half)) and np.linalg.norm(at_half) > 1e-6


def test_21_fold_pair_found_at_every_distance():
    """Next to a (2/1) fold both orbits of the pair are returned (multipliers straddling +1),
    from 1e-5 down to 1e-12 in delta (further away the unstable one has lost its slow impact),
    and none just past the fold: the scan resolves the near-double root of its circle
    condition instead of needing a sign change in a cell."""
    from vibroimpact.validation.orbit_families import fold_points
    beta, zeta, eps = 0.4632189831209864, 0.140252977051332, 0.6902755657606898
    folds = fold_points(2, 1, beta, zeta, eps)
    assert folds
    tf = 2 * math.pi / beta
    for delta_f, side, merged in folds:
        def near(orbits, merged=merged):
            return [o for o in orbits if circ_dist(o.tau0, merged.taus[0], tf) < 0.05 * tf
                    or circ_dist(o.tau0, merged.taus[1], tf) < 0.05 * tf]
        for d in (1e-5, 1e-7, 1e-9, 1e-10, 1e-12):
            pair = near(periodic_orbits(2, 1, beta, delta_f + side * d, zeta, eps,
                                        include_inadmissible=True))
            assert len(pair) == 2, (delta_f, d)
            mu = sorted(o.multipliers[np.argmin(np.abs(o.multipliers - 1))].real for o in pair)
            assert mu[0] < 1.0 < mu[1], (delta_f, d, mu)
        past = near(periodic_orbits(2, 1, beta, delta_f - side * 1e-7, zeta, eps,
                                    include_inadmissible=True))
        assert past == [], delta_f


def test_22_motion_next_to_a_period_doubling():
    """On one side of a period doubling of the (1/1) motion one (2/2) motion is born (intervals
    z/2 +- ~sqrt(distance)), on the other side none: from 1e-4 down to 1e-10 in delta the
    (2/2) call returns it exactly once there and never the doubled (1/1) motion, which is
    within ~1e-16/distance of solving the (2/2) equations with a nearly singular Jacobian."""
    from vibroimpact.validation.orbit_families import period_doubling_points
    beta, zeta, eps = 1.1961933965658853, 0.019884047202237826, 0.542731103892917
    points = period_doubling_points(beta, zeta, eps)
    assert points
    delta_pd = points[0][0]
    z = 4 * math.pi / beta
    counts = {}
    for side in (1, -1):
        for d in (1e-4, 1e-6, 1e-8, 1e-9, 1e-10):
            delta = delta_pd + side * d
            (o11,) = [o for o in periodic_orbits(1, 1, beta, delta, zeta, eps)
                      if abs(o.multipliers[0] + 1) < 0.1]
            near = [o for o in periodic_orbits(2, 2, beta, delta, zeta, eps,
                                               include_inadmissible=True)
                    if abs(o.intervals[0] - z / 2) < 0.1 and
                    circ_dist(o.tau0, o11.tau0, 2 * math.pi / beta) < 0.1]
            counts.setdefault(side, set()).add(len(near))
            for o in near:
                # a genuine (2/2) motion: intervals apart by ~ sqrt(d), not the doubled one
                assert abs(o.intervals[0] - o.intervals[1]) > 1e-2 * math.sqrt(d), (side, d)
    assert sorted(map(tuple, counts.values())) == [(0,), (1,)], counts


# ------------------------------------------------------------------------------------------
# eps = 0: plastic impacts, a rank-one map

def test_eps_zero_rank_one_map():
    """With eps = 0 the mass leaves the wall at rest: det T = 0 exactly, one multiplier is 0,
    lam = |tr T|; the orbit repeats under the DOP853 map (1e-9) and leaves the wall pulled
    by the force (x'' < 0 at every take-off)."""
    found = 0
    for ib, d in [(1.2, 0.5), (0.8, 0.2), (1.5, 1.0), (2.0, 1.0)]:
        beta = 1 / ib
        for o in periodic_orbits(1, 1, beta, d, ZETA, 0.0):
            found += 1
            assert np.linalg.det(o.jacobian) == 0.0
            assert abs(o.multipliers[1]) == 0.0
            assert o.lam == pytest.approx(abs(np.trace(o.jacobian)), rel=1e-12)
            assert math.sin(beta * o.tau0) - d < 0
            tau, u = dop853_impact_map(o.tau0, o.velocities[0], beta, d, ZETA, 0.0,
                                       1.5 * o.period)
            assert tau - o.tau0 == pytest.approx(o.period, abs=1e-9)
            assert u == pytest.approx(o.velocities[0], abs=1e-9)
    assert found >= 2


# ------------------------------------------------------------------------------------------
# the domain map

def _assert_map_is_pointwise(inv_beta, delta, types):
    """Every cell of ``orbit_map`` classifies as ``periodic_orbits`` does at the same point:
    the same numbers of admissible and stable solutions, the same reason, and the same
    smallest lam (to 1e-9 relative: the map's branch following converges Newton from another
    start than the scan, to the same root within the solver's tolerance, ~1e-12)."""
    r = orbit_map(inv_beta, delta, types, ZETA, EPS)
    assert r["exists"].shape == (len(types), inv_beta.size, delta.size)
    for t, (m, n) in enumerate(types):
        for i, ib in enumerate(inv_beta):
            for j, d in enumerate(delta):
                allsol = periodic_orbits(m, n, 1 / ib, d, ZETA, EPS, include_inadmissible=True)
                adm = [o for o in allsol if o.admissible]
                stable = [o for o in adm if o.stable]
                reason = 0 if stable else 1 if not allsol else 2 if not adm else 3
                where = (m, n, ib, d)
                assert r["n_solutions"][t, i, j] == len(adm), where
                assert r["n_stable"][t, i, j] == len(stable), where
                assert r["reason"][t, i, j] == reason, where
                assert r["exists"][t, i, j] == bool(adm), where
                if adm:
                    lam = min(o.lam for o in adm)
                    assert r["lam"][t, i, j] == pytest.approx(lam, rel=1e-9), where
                    assert r["S"][t, i, j] == pytest.approx(100 * (1 - lam), rel=1e-9), where
                else:
                    assert np.isnan(r["lam"][t, i, j]), where


def test_orbit_map_agrees_with_pointwise_calls():
    """The map's cells classify as periodic_orbits does at the same point, every cell: for
    m <= 2 the map runs the same global scan; for (3/1), whose map scans every 4th delta and
    follows branches in between, the branch following and the rescans where a branch ends
    find what the point solver finds."""
    _assert_map_is_pointwise(np.array([0.3, 0.8, 1.0, 1.5, 2.2]),
                             np.round(np.arange(-1.0, 2.0, 0.02), 10),
                             [(1, 1), (2, 1), (1, 2), (3, 1)])


def test_the_map_finds_a_fold_partner_born_and_lost_between_two_scans():
    """Issue 43: on the default Fig. 16 grid (delta step 0.02 from -1.5) the (3/1) map held
    one solution at 1/beta = 1.5, delta = 0.28 and 0.30 where the point solver (and a shooting
    written apart) find two, S = 17.6 stable and -21.2 unstable at 0.30: the unstable one is
    born at a zero impact velocity at ~0.28 and meets the stable one at a fold before 0.32,
    between two scans of the row. The same at 1/beta = 1.3, 1.7, 1.9 (a fold at a scan point,
    and between scans); every cell of these rows now agrees with the point solver."""
    delta = np.round(np.arange(-1.5, 3.0 + 1e-9, 0.02), 10)
    r = orbit_map([1.5], delta, [(3, 1)], ZETA, EPS)
    k = int(np.flatnonzero(delta == 0.3)[0])
    assert r["n_solutions"][0, 0, k] == 2 and r["n_stable"][0, 0, k] == 1
    (stable,) = [o for o in periodic_orbits(3, 1, 1 / 1.5, 0.3, ZETA, EPS) if o.stable]
    assert stable.S == pytest.approx(17.64, abs=0.01)
    _assert_map_is_pointwise(np.array([1.3, 1.5, 1.7, 1.9]), delta, [(3, 1)])


def test_orbit_map_validates_input():
    with pytest.raises(ValueError, match="inv_beta"):
        orbit_map([0.0, 1.0], [0.0], [(1, 1)], ZETA, EPS)
    with pytest.raises(ValueError, match="delta"):
        orbit_map([1.0], [np.nan], [(1, 1)], ZETA, EPS)
    with pytest.raises(ValueError, match="zeta"):
        orbit_map([1.0], [0.0], [(1, 1)], 0.0, EPS)
    with pytest.raises(ValueError, match="m"):
        orbit_map([1.0], [0.0], [(0, 1)], ZETA, EPS)


# ------------------------------------------------------------------------------------------
# the simulator follows a stable orbit and leaves an unstable one

def _simulator():
    try:
        from vibroimpact import simulate
    except (ImportError, AttributeError):
        pytest.skip("vibroimpact.simulate is not available")
    return simulate


def _simulate_from_orbit(o, periods, kick=0.0):
    """Run the simulator from the orbit's state at an instant where the force phase is 0.

    ``simulate`` starts at tau = 0 with ``sin(beta tau)``: take t_start = k T_f (away from any
    impact), start there with the orbit's closed-form state and shift the orbit by t_start.
    """
    simulate = _simulator()
    tf = 2 * math.pi / o.beta
    k = math.floor(o.tau0 / tf) + 1
    while min(circ_dist(k * tf, t, o.period) for t in o.impact_times) < 0.05:
        k += 1
    t_start = k * tf
    x0, v0 = o.state(t_start)
    res = simulate(o.zeta, o.eps, o.delta, noise=None, dt=0.05, amplitude=1.0, beta=o.beta,
                   x0=float(x0) - kick, v0=float(v0), t_end=periods * o.period)
    j = np.arange(-1, periods + 2)
    pred_t = (o.impact_times[None, :] + o.period * j[:, None]).ravel() - t_start
    pred_u = np.tile(np.roll(o.velocities, 1), j.size)
    keep = (pred_t > 0) & (pred_t <= periods * o.period)
    order = np.argsort(pred_t[keep])
    return res, pred_t[keep][order], pred_u[keep][order]


def test_simulate_stays_on_a_stable_orbit():
    """50 periods of the exact simulator started on a stable (1/1) and a stable (2/1) orbit:
    impact instants and velocities within 1e-9 of the orbit's."""
    _simulator()
    for m, n, ib, d in [(1, 1, 1.2, 0.5), (2, 1, 1.5, 1.0)]:
        (o,) = [o for o in periodic_orbits(m, n, 1 / ib, d, ZETA, EPS) if o.stable]
        res, pred_t, pred_u = _simulate_from_orbit(o, 50)
        assert res.impact_time.size == pred_t.size
        np.testing.assert_allclose(res.impact_time, pred_t, atol=1e-9)
        np.testing.assert_allclose(res.impact_velocity, pred_u, atol=1e-9)


def test_simulate_departs_from_an_unstable_orbit():
    """The unstable (1/1) motion at 1/beta = 1.3, delta = 2.3 (mu = -6): started on it with a
    1e-12 offset, the simulation is 1e-3 away from it within 50 periods."""
    _simulator()
    (o,) = periodic_orbits(1, 1, 1 / 1.3, 2.3, ZETA, EPS)
    assert not o.stable and o.multipliers[0].real < -5
    res, pred_t, pred_u = _simulate_from_orbit(o, 50, kick=1e-12)
    n = min(res.impact_time.size, pred_t.size)
    early = np.abs(res.impact_time[:5] - pred_t[:5]).max()
    late = np.abs(res.impact_time[:n] - pred_t[:n]).max() if n == pred_t.size else np.inf
    assert early < 1e-6
    assert late > 1e-3 or res.impact_time.size != pred_t.size
