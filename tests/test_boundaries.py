"""Exact boundaries of the stable (m/n) domains of Fig. 16 (``domain_boundaries``).

References independent of the continuation: the (1/n) closed form (its fold is
``|kappa| = 1``, its grazing impact ``u = 0`` is ``delta = q``, its grazing flight maximum is
solved here from a textbook flight), the multipliers of the orbit at a curve point, and the
solver's own stability classification (``orbit_map``) at 2e-9 on either side of each point.
"""
import dataclasses
import math

import numpy as np
import pytest

from vibroimpact.orbits import (BoundaryCurve, DomainBoundaries, domain_boundaries, orbit_map,
                                periodic_orbits)
from vibroimpact.orbits import boundaries_kernels as bk
from vibroimpact.orbits.api import _raw_solutions
from vibroimpact.orbits.boundaries import _seed_segments
from vibroimpact.orbits.flight import monodromy

ZETA, EPS = 0.05, 0.5
BOX = dict(inv_beta=(0.2, 3.0), delta=(-1.5, 3.0))
GRID = (71, 113)                   # half the Fig. 16 grid: the seeds; the curves are exact
TYPES = [(1, 1), (2, 1), (1, 2)]


@pytest.fixture(scope="module")
def seed():
    ib = np.linspace(*BOX["inv_beta"], GRID[0])
    dd = np.linspace(*BOX["delta"], GRID[1])
    return orbit_map(ib, dd, types=TYPES, zeta=ZETA, eps=EPS)


@pytest.fixture(scope="module")
def curves(seed):
    return {t: domain_boundaries(*t, ZETA, EPS, **BOX, seed_map=seed) for t in TYPES}


# ------------------------------------------------------------------------------------------
# independent references: the (1/n) closed form

def harmonic(beta, zeta=ZETA):
    q = 1.0 / math.hypot(1.0 - beta ** 2, 2.0 * zeta * beta)
    phi = math.atan2(2.0 * zeta * beta, 1.0 - beta ** 2)
    return math.sqrt(1.0 - zeta ** 2), q, phi


def free_propagator(s, zeta=ZETA):
    wd = math.sqrt(1.0 - zeta ** 2)
    e, c, sn = math.exp(-zeta * s), math.cos(wd * s), math.sin(wd * s) / wd
    return e * (c + zeta * sn), e * sn, -e * sn, e * (c - zeta * sn)


def fold_deltas_m1(n, beta, zeta=ZETA, eps=EPS):
    """The (1/n) fold: |kappa| = 1, i.e. delta = +-q sqrt(a_S^2 + a_C^2) / a_S."""
    _, q, _ = harmonic(beta, zeta)
    z = 2.0 * math.pi * n / beta
    p11, p12, p21, p22 = free_propagator(z, zeta)
    a_s = 1.0 - p11 + eps * (p22 - math.exp(-2.0 * zeta * z))
    a_c = -beta * (1.0 + eps) * p12
    d = q * math.hypot(a_s, a_c) / a_s
    return d, -d


def orbit_m1(n, beta, delta, root, zeta=ZETA, eps=EPS):
    """Closed-form (1/n) orbit (psi_0, u) for one root of cos(psi_0 - chi) = kappa."""
    _, q, _ = harmonic(beta, zeta)
    z = 2.0 * math.pi * n / beta
    p11, p12, p21, p22 = free_propagator(z, zeta)
    a_s = 1.0 - p11 + eps * (p22 - math.exp(-2.0 * zeta * z))
    a_c = -beta * (1.0 + eps) * p12
    kappa = delta * a_s / (q * math.hypot(a_s, a_c))
    psi = math.atan2(a_s, a_c) + root * math.acos(max(-1.0, min(1.0, kappa)))
    s0, c0 = q * math.sin(psi), q * math.cos(psi)
    u = (p21 * (delta - s0) + beta * (1.0 - p22) * c0) / (1.0 + eps * p22)
    return psi, u


def flight_xva(psi, u, s, beta, delta, zeta=ZETA, eps=EPS):
    """Textbook flight from the wall at phase psi with rebound -eps u: x, v, a at time s."""
    wd, q, _ = harmonic(beta, zeta)
    y0 = delta - q * math.sin(psi)
    v0 = -eps * u - q * beta * math.cos(psi)
    c2 = (v0 + zeta * y0) / wd
    e, cs, sn = math.exp(-zeta * s), math.cos(wd * s), math.sin(wd * s)
    th = beta * s + psi
    x = q * math.sin(th) + e * (y0 * cs + c2 * sn)
    v = q * beta * math.cos(th) + e * ((-zeta * y0 + wd * c2) * cs + (-zeta * c2 - wd * y0) * sn)
    a = math.sin(th + harmonic(beta, zeta)[2]) - 2.0 * zeta * v - x
    return x, v, a


def grazing_delta_m1(n, beta, delta0, s0, root):
    """Delta at which the flight's interior maximum near s0 reaches the wall, at fixed beta:
    Newton on (v(s*) = 0, x(s*) - delta = 0) in (s*, delta) from the closed-form orbit."""
    s, d = s0, delta0
    for _ in range(60):
        def g(s_, d_):
            psi, u = orbit_m1(n, beta, d_, root)
            x, v, a = flight_xva(psi, u, s_, beta, d_)
            return np.array([v, x - d_]), a
        f, a = g(s, d)
        h = 1e-7 * (1.0 + abs(d))
        fd = (g(s, d + h)[0] - g(s, d - h)[0]) / (2 * h)
        jac = np.array([[a, fd[0]], [f[0], fd[1]]])     # d(x - delta)/ds = v
        step = np.linalg.solve(jac, -f)
        s, d = s + step[0], d + step[1]
        if abs(step[1]) < 1e-16 * (1 + abs(d)) and abs(step[0]) < 1e-15 * (1 + abs(s)):
            break
    return d


def root_of(curve, k, n):
    """Which closed-form root (+1/-1) the curve's orbit at point k is."""
    beta = 1.0 / curve.inv_beta[k]
    _, q, phi = harmonic(beta)
    psi_c = beta * curve.orbits[k, 0] - phi
    best = None
    for r in (1, -1):
        psi, _ = orbit_m1(n, beta, curve.delta[k], r)
        d = abs(math.remainder(psi - psi_c, 2 * math.pi))
        if best is None or d < best[0]:
            best = (d, r)
    return best[1]


# ------------------------------------------------------------------------------------------
# 1. (1/1), (1/2): fold and grazing curves against the closed form

@pytest.mark.parametrize("n", [1, 2])
def test_m1_fold_curves_are_the_closed_form(curves, n):
    folds = [c for c in curves[(1, n)] if c.kind == "fold"]
    assert folds
    worst = 0.0
    for c in folds:
        for ib, d in zip(c.inv_beta, c.delta):
            ref = min(fold_deltas_m1(n, 1.0 / ib), key=lambda r: abs(r - d))
            worst = max(worst, abs(d - ref) / (1.0 + abs(d)))
    assert worst <= 1e-12


@pytest.mark.parametrize("n", [1, 2])
def test_m1_grazing_curves_are_the_closed_form(curves, n):
    graze = [c for c in curves[(1, n)] if c.kind == "grazing"]
    assert graze
    worst, checked = 0.0, 0
    for c in graze:
        # interior points: at an end on a fold the reference's acos(kappa -> 1) loses half the
        # digits (the ends are checked as codimension-two points)
        for k in list(range(1, len(c) - 1, 7)) + [len(c) - 2]:
            slope = np.gradient(c.delta, c.inv_beta)[k] if len(c) > 2 else 0.0
            if not abs(slope) < 50.0:           # near-vertical: delta(1/beta) ill-posed
                continue
            beta = 1.0 / c.inv_beta[k]
            r = root_of(c, k, n)
            psi, u = orbit_m1(n, beta, c.delta[k], r)
            # start s* at the flight's highest sampled maximum
            z = 2 * math.pi * n / beta
            ss = np.linspace(0, z, 4001)[1:-1]
            xs = [flight_xva(psi, u, s, beta, c.delta[k])[0] for s in ss]
            ref = grazing_delta_m1(n, beta, c.delta[k], ss[int(np.argmax(xs))], r)
            worst = max(worst, abs(ref - c.delta[k]) / (1.0 + abs(ref)))
            checked += 1
    assert checked >= 5
    assert worst <= 1e-12


@pytest.mark.parametrize("n", [1, 2])
def test_m1_grazing_impact_corners_are_delta_equals_q(curves, n):
    """Where an impact velocity reaches 0 the (1/n) orbit is the linear response touching the
    wall at its top: delta = q(beta) exactly (fold and period-doubling curves end there)."""
    corners = []
    for c in curves[(1, n)]:
        for k in (0, -1):
            if c.ends[k if k == 0 else 1] == "codim2" and abs(c.orbits[k, 1]) < 1e-9:
                corners.append((c.inv_beta[k], c.delta[k]))
    assert corners
    for ib, d in corners:
        assert abs(d - harmonic(1.0 / ib)[1]) <= 1e-12 * (1 + abs(d))


# ------------------------------------------------------------------------------------------
# 2. a period-doubling curve: multiplier -1, stable on one side only

def _stable_near(m, n, ib, d, y_ref):
    """lam of the orbit at (1/ib, d) closest to y_ref (by its first impact phase and u)."""
    beta = 1.0 / ib
    tf = 2 * math.pi / beta
    best = None
    for o in periodic_orbits(m, n, beta, d, ZETA, EPS):
        dist = min(abs(math.remainder(t - y_ref[0], tf)) for t in o.impact_times)
        dist += min(abs(v - y_ref[m]) for v in o.velocities)
        if best is None or dist < best[0]:
            best = (dist, o)
    return best[1]


@pytest.mark.parametrize("mn", [(1, 1), (2, 1)])
def test_period_doubling_curve_has_multiplier_minus_one(curves, mn):
    m, n = mn
    pds = [c for c in curves[mn] if c.kind == "period_doubling"]
    assert pds
    c = max(pds, key=len)
    tmat = np.empty((2, 2))
    for k in np.linspace(2, len(c) - 3, 5).astype(int):
        beta = 1.0 / c.inv_beta[k]
        z = 2 * math.pi * n / beta
        monodromy(c.orbits[k], m, z, beta, c.delta[k], ZETA, EPS, tmat)
        mu = np.linalg.eigvals(tmat)
        assert np.min(np.abs(mu + 1.0)) <= 1e-9
        assert abs(np.linalg.det(tmat) - EPS ** (2 * m) * math.exp(-2 * ZETA * z)) < 1e-12
        # stable on one side, unstable on the other, 1e-6 off the curve (fixed 1/beta)
        sides = [_stable_near(m, n, c.inv_beta[k], c.delta[k] + s, c.orbits[k]).stable
                 for s in (-1e-6, 1e-6)]
        assert sides[0] != sides[1]


# ------------------------------------------------------------------------------------------
# 3. every kind: the solver's stable count flips 2e-9 either side of the curve

def _flip_points(c, count):
    """Interior points of a curve, away from its ends."""
    if len(c) < 7:
        return []
    return sorted(set(np.linspace(3, len(c) - 4, count).astype(int)))


@pytest.mark.parametrize("mn", TYPES)
def test_curve_points_are_where_the_solver_flips(curves, mn):
    m, n = mn
    kinds = set()
    for c in curves[mn]:
        for k in _flip_points(c, 4):
            ib, d = c.inv_beta[k], c.delta[k]
            slope = np.gradient(c.delta, c.inv_beta)[k]
            if abs(slope) < 20.0:              # fixed 1/beta, delta = d* -+ 2e-9
                mp = orbit_map([ib], [d - 2e-9, d + 2e-9], types=[mn], zeta=ZETA, eps=EPS)
                st = mp["n_stable"][0, 0] > 0
            else:                              # a steep curve: fixed delta instead
                mp = orbit_map([ib - 2e-9, ib + 2e-9], [d], types=[mn], zeta=ZETA, eps=EPS)
                st = mp["n_stable"][0, :, 0] > 0
            assert st[0] != st[1], (c.kind, ib, d)
            kinds.add(c.kind)
    assert {"fold", "period_doubling", "grazing"} <= kinds or mn == (2, 1)
    assert len(kinds) >= 2


# ------------------------------------------------------------------------------------------
# 4. codimension-two points satisfy both conditions

def _conditions(m, n, y, ib, d):
    """(kind, value) of every boundary condition of the orbit y at (1/ib, d); a flight's two
    highest maxima are two conditions (two maxima at the wall: a corner of two grazings)."""
    stack, tmat = np.empty((64, 2)), np.empty((2, 2))
    out = np.empty(2 + 3 * m)
    bk.all_tests(y, m, n, 1.0 / ib, d, ZETA, EPS, stack, tmat, out)
    conds = [("fold", out[0]), ("period_doubling", out[1])]
    x = np.concatenate((y, [ib, d]))
    prm = np.array([ZETA, EPS, 0.0, 0.0, 1.0])
    ax = np.array([bk.PRM_INV_BETA, bk.PRM_DELTA])
    for j in range(m):
        conds.append(("grazing", y[m + j]))
        top, place = bk.peak_of(bk.COND_MARGIN, j, -1.0, x, m, n, prm, ax)
        conds.append(("grazing", top))
        conds.append(("grazing", bk.peak_of(bk.COND_OTHER_PEAK, j, place, x, m, n, prm,
                                            ax)[0]))
        conds.append(("existence", out[2 + 2 * m + j]))
    return conds


@pytest.mark.parametrize("mn", TYPES)
def test_codimension_two_points_satisfy_both_conditions(curves, mn):
    m, n = mn
    res = curves[mn]
    assert res.codimension_two
    for p in res.codimension_two:
        ends = [(c, k) for c in res for k in (0, -1)
                if abs(c.inv_beta[k] - p.inv_beta) < 1e-12 and abs(c.delta[k] - p.delta) < 1e-12]
        assert ends, p
        c, k = ends[0]
        conds = _conditions(m, n, c.orbits[k], p.inv_beta, p.delta)
        zero = [kind for kind, v in conds if abs(v) <= 1e-9]
        a, b = p.kinds
        assert a in zero, (p, conds)
        if not p.other_orbit:
            zero.remove(a)
            assert b in zero, (p, conds)
        elif b != "fold":
            # the curve meets the edge of another stable orbit's domain: that orbit satisfies
            # its condition there (to the 1e-11 of the bisection times the slope); at a fold
            # the other orbit is born just past the point, so it is not there to check
            others = _raw_solutions(m, n, 1.0 / p.inv_beta, p.delta, ZETA, EPS)
            best = min(min(abs(v) for kind, v in _conditions(m, n, y, p.inv_beta, p.delta)
                           if kind == b) for y in others)
            assert best <= 1e-8, (p, best)


# ------------------------------------------------------------------------------------------
# the union of the curves reproduces the pixel edges; API

@pytest.mark.parametrize("mn", TYPES)
def test_every_seed_pixel_edge_is_within_a_cell_of_a_curve(seed, curves, mn):
    t = [tuple(x) for x in seed["types"]].index(mn)
    ib, dd = seed["inv_beta"], seed["delta"]
    cb, cd = ib[1] - ib[0], dd[1] - dd[0]
    pts = []
    for c in curves[mn]:
        p = np.c_[c.inv_beta, c.delta]
        for s in np.linspace(0, 1, 4, endpoint=False):
            pts.append(p[:-1] + s * (p[1:] - p[:-1]))
        pts.append(p[-1:])
    pts = np.concatenate(pts)
    segs = _seed_segments(seed["n_stable"][t] > 0, ib, dd)
    assert segs
    for ps, pu in segs:
        mid = 0.5 * (ps + pu)
        dist = np.min(np.hypot((pts[:, 0] - mid[0]) / cb, (pts[:, 1] - mid[1]) / cd))
        assert dist <= 1.0, (mn, mid)


@pytest.mark.parametrize("mn", TYPES)
def test_curves_are_ordered_fine_and_inside_the_box(curves, mn):
    diag = math.hypot(2.8, 4.5)
    for c in curves[mn]:
        assert c.kind in ("fold", "period_doubling", "grazing", "existence")
        assert (c.m, c.n) == mn and len(c) >= 2
        assert c.orbits.shape == (len(c), 2 * mn[0])
        steps = np.hypot(np.diff(c.inv_beta), np.diff(c.delta))
        assert np.all(steps <= diag / 200)
        assert np.all(c.inv_beta >= 0.2 - 1e-12) and np.all(c.inv_beta <= 3.0 + 1e-12)
        assert np.all(c.delta >= -1.5 - 1e-12) and np.all(c.delta <= 3.0 + 1e-12)
        assert np.all(c.error[1:-1] <= 1e-10) and np.all(c.error <= 1e-7)
        assert "lost" not in c.ends


def test_result_api(curves):
    res = curves[(1, 1)]
    assert isinstance(res, list) and isinstance(res, DomainBoundaries)
    c = res[0]
    assert isinstance(c, BoundaryCurve)
    assert c["kind"] == c.kind and c["inv_beta"] is c.inv_beta and c["delta"] is c.delta
    assert (c.m, c.n) == (1, 1)
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.kind = "fold"
    with pytest.raises(KeyError):
        c["nope"]
    for p in res.codimension_two:
        assert len(p.kinds) == 2 and all(k in ("fold", "period_doubling", "grazing",
                                                "existence") for k in p.kinds)
        assert p["inv_beta"] == p.inv_beta


# ------------------------------------------------------------------------------------------
# 5. bad input

@pytest.mark.parametrize("kwargs, name", [
    (dict(m=4), "m"), (dict(m=0), "m"), (dict(n=0), "n"), (dict(m=1.5), "m"),
    (dict(zeta=1.0), "zeta"), (dict(eps=2.0), "eps"), (dict(eps=0.0), "eps"),
    (dict(inv_beta=(1.0, 1.0)), "inv_beta"), (dict(inv_beta=(2.0, 1.0)), "inv_beta"),
    (dict(inv_beta=(-1.0, 1.0)), "inv_beta"), (dict(inv_beta=()), "inv_beta"),
    (dict(delta=(0.0, 0.0)), "delta"), (dict(delta=(1.0, float("nan"))), "delta"),
    (dict(resolution=(1, 10)), "resolution"), (dict(tol=0.0), "tol"),
    (dict(seed_map={"x": 1}), "seed_map"),
])
def test_bad_input_names_the_argument(kwargs, name):
    args = dict(m=1, n=1, zeta=ZETA, eps=EPS)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        domain_boundaries(**args)


def test_seed_map_without_the_type(seed):
    with pytest.raises(ValueError, match="seed_map"):
        domain_boundaries(1, 3, ZETA, EPS, seed_map=seed)


# ------------------------------------------------------------------------------------------
# slow: the whole default Fig. 16 (141 x 226 seeds, five types), against bisection

def _bisect_edge(mn, ib, lo, hi, iters=45):
    """The stability flip of the solver between delta = lo and hi at fixed 1/beta."""
    def stable(d):
        return any(o.stable for o in periodic_orbits(*mn, 1.0 / ib, d, ZETA, EPS))
    s_lo = stable(lo)
    assert stable(hi) != s_lo
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        if stable(mid) == s_lo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@pytest.mark.slow
def test_default_figure_16_all_types():
    types = [(1, 1), (2, 1), (1, 2), (1, 3), (3, 1)]
    mp = orbit_map(np.linspace(0.2, 3.0, 141), np.linspace(-1.5, 3.0, 226), types=types,
                   zeta=ZETA, eps=EPS)
    ib, dd = mp["inv_beta"], mp["delta"]
    for t, mn in enumerate(types):
        res = domain_boundaries(*mn, ZETA, EPS, **BOX, seed_map=mp)
        assert res
        pts = np.concatenate([np.c_[c.inv_beta, c.delta] for c in res])
        for ps, pu in _seed_segments(mp["n_stable"][t] > 0, ib, dd):
            mid = 0.5 * (ps + pu)
            dist = np.min(np.hypot((pts[:, 0] - mid[0]) / (ib[1] - ib[0]),
                                   (pts[:, 1] - mid[1]) / (dd[1] - dd[0])))
            assert dist <= 1.5, (mn, mid)        # points, not the polyline: half a step more
        for c in res:
            assert "lost" not in c.ends, (mn, c.kind, c.ends)
            slope = np.gradient(c.delta, c.inv_beta) if len(c) > 2 else np.zeros(len(c))
            for k in _flip_points(c, 2):
                if abs(slope[k]) > 20.0:
                    continue
                d_star = _bisect_edge(mn, c.inv_beta[k], c.delta[k] - 1e-6, c.delta[k] + 1e-6)
                assert abs(d_star - c.delta[k]) <= 1e-9, (mn, c.kind, c.inv_beta[k])


def test_own_seed_map_gives_the_same_curves(curves):
    """Without seed_map the function computes its own map (here a coarser one): the curves are
    exact, so their codimension-two points are the same."""
    res = domain_boundaries(1, 1, ZETA, EPS, **BOX, resolution=(36, 57))
    ref = curves[(1, 1)]
    assert sorted(c.kind for c in res) == sorted(c.kind for c in ref)
    for p in ref.codimension_two:
        assert any(math.hypot(p.inv_beta - o.inv_beta, p.delta - o.delta) < 1e-9
                   for o in res.codimension_two), p
