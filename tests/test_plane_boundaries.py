"""Exact boundaries of the stable (m/n) domains over any plane (``plane_boundaries``, issue 36).

Independent references: the (1/beta, delta) tracer (``domain_boundaries``) on the line both
planes share, the solver's own stability verdict (``orbit_plane``) bisected across the curve,
and the amplitude's scaling law (the motions at (A, delta) are A times those at (1, delta/A):
over (A, delta) every edge is a ray delta = c A).
"""
import numpy as np
import pytest

from vibroimpact.orbits import boundaries_kernels as bk
from vibroimpact.orbits import domain_boundaries
from vibroimpact.orbits.boundaries import _KIND_OF_CODE, _Tracer, plane_boundaries
from vibroimpact.orbits.plane import orbit_plane

ZETA, EPS, IB = 0.05, 0.5, 1.1
DELTA = (-1.0, 3.0)
#: Distance allowed between the two tracers' crossings of a shared line: both are Newton
#: solutions of the same augmented equations to BOUNDARY_STEP_RTOL, measured <= 3e-15.
SAME_LINE_TOL = 1e-12
#: Bisection of the solver's verdict down to this bracket; the curve must lie in it (its
#: error estimate is ~1e-15, the solver's verdict exact to its Newton tolerance ~1e-13).
BISECT_TOL = 1e-10


def _tracer(m, n, prm, ax, box):
    return _Tracer(m, n, np.asarray(prm, dtype=float), np.asarray(ax), box)


def crossings(curves, tracer, x_line, xy):
    """Where each curve crosses x = x_line, solved exactly on the curve (Newton on its
    condition with x fixed): ``[(kind, y)]``."""
    out = []
    for c in curves:
        x, y = xy(c)
        s = np.sign(x - x_line)
        for k in np.flatnonzero(s[:-1] * s[1:] < 0):
            f = (x_line - x[k]) / (x[k + 1] - x[k])
            xi = np.concatenate((c.orbits[k] + f * (c.orbits[k + 1] - c.orbits[k]),
                                 [x_line, y[k] + f * (y[k + 1] - y[k])]))
            best = None
            for code, kind in _KIND_OF_CODE.items():
                if kind != c.kind:
                    continue
                for j in range(c.m):
                    tracer.hint = (tracer.peak(bk.COND_MARGIN, j, xi, hint=-1.0)[1]
                                   if code == bk.COND_MARGIN else -1.0)
                    xs, _ = tracer.newton(xi, code, j, mode=1, idx=tracer.nn, val=x_line)
                    if xs is not None and abs(xs[-1] - xi[-1]) < 1e-3 and (
                            best is None or abs(xs[-1] - xi[-1]) < abs(best - xi[-1])):
                        best = float(xs[-1])
            assert best is not None, f"no exact crossing of a {c.kind} curve at {x_line}"
            out.append((c.kind, best))
    return sorted(out, key=lambda t: t[1])


def eps_delta_crossings(m, n, eps):
    curves = plane_boundaries(m, n, "eps", (0.3, 0.7), "delta", DELTA,
                              {"zeta": ZETA, "inv_beta": IB}, resolution=(21, 201))
    assert all(c.axes == ("eps", "delta") for c in curves)
    tracer = _tracer(m, n, [ZETA, 0.0, IB, 0.0, 1.0], [bk.PRM_EPS, bk.PRM_DELTA],
                     (0.3, 0.7) + DELTA)
    return crossings(curves, tracer, eps, lambda c: (c.x, c.y))


def default_crossings(m, n, eps):
    curves = domain_boundaries(m, n, ZETA, eps, inv_beta=(1.0, 1.2), delta=DELTA,
                               resolution=(11, 201))
    tracer = _tracer(m, n, [ZETA, eps, 0.0, 0.0, 1.0], [bk.PRM_INV_BETA, bk.PRM_DELTA],
                     (1.0, 1.2) + DELTA)
    return crossings(curves, tracer, IB, lambda c: (c.inv_beta, c.delta))


def stable_at(m, n, eps, delta):
    ds = orbit_plane("eps", [eps], "delta", [delta], {"zeta": ZETA, "inv_beta": IB},
                     types=[(m, n)])
    return bool(ds["n_stable"].values[0, 0, 0] > 0)


def bisect(m, n, eps, lo, hi):
    s_lo, s_hi = stable_at(m, n, eps, lo), stable_at(m, n, eps, hi)
    assert s_lo != s_hi, f"the solver's verdict is {s_lo} at both {lo} and {hi}"
    while hi - lo > BISECT_TOL:
        mid = 0.5 * (lo + hi)
        if stable_at(m, n, eps, mid) == s_lo:
            lo = mid
        else:
            hi = mid
    return lo, hi


@pytest.mark.parametrize("mn, kinds", [((1, 1), ["grazing", "period_doubling"]),
                                        ((2, 1), ["grazing", "fold"])])
def test_eps_delta_edges_meet_the_default_tracer_on_the_shared_line(mn, kinds):
    """At eps = 0.5 the (eps, delta) curves cross where the (1/beta, delta) curves of eps = 0.5
    cross 1/beta = 1.1 (the plane's fixed 1/beta), and the solver's verdict flips there."""
    plane = eps_delta_crossings(*mn, EPS)
    default = default_crossings(*mn, EPS)
    assert [k for k, _ in plane] == kinds
    assert [k for k, _ in default] == kinds
    for (_, a), (_, b) in zip(plane, default):
        assert abs(a - b) <= SAME_LINE_TOL
    for _, y in plane:
        lo, hi = bisect(*mn, EPS, y - 1e-4, y + 3e-4)      # off-centre: y is no bisection point
        assert lo - 1e-13 <= y <= hi + 1e-13


@pytest.mark.slow
@pytest.mark.parametrize("eps", [0.35, 0.65])
@pytest.mark.parametrize("mn", [(1, 1), (2, 1), (1, 2)])
def test_eps_delta_edges_off_the_paper_eps(mn, eps):
    """The same away from the paper's eps: the default tracer run at that eps."""
    plane = eps_delta_crossings(*mn, eps)
    default = default_crossings(*mn, eps)
    assert plane and [k for k, _ in plane] == [k for k, _ in default]
    for (_, a), (_, b) in zip(plane, default):
        assert abs(a - b) <= SAME_LINE_TOL
    for _, y in plane:
        lo, hi = bisect(*mn, eps, y - 1e-4, y + 3e-4)
        assert lo - 1e-13 <= y <= hi + 1e-13


def test_amplitude_delta_edges_are_rays():
    """Over (A, delta) the (1/1) edges are delta = c A, c the unit force's edge at 1/beta =
    1.1: the amplitude scales out (orbits/plane.py), so the continuation in A must find it."""
    unit = dict(default_crossings(1, 1, EPS))
    curves = plane_boundaries(1, 1, "amplitude", (0.5, 2.0), "delta", (-1.0, 6.0),
                              {"zeta": ZETA, "eps": EPS, "inv_beta": IB},
                              resolution=(16, 141))
    kinds = sorted({c.kind for c in curves})
    assert kinds == ["grazing", "period_doubling"]
    for c in curves:
        ratio = c.y / c.x
        assert np.max(np.abs(ratio - unit[c.kind])) <= 1e-9


def test_plane_boundaries_refuse_what_they_cannot_trace():
    fixed = {"zeta": ZETA, "inv_beta": IB}
    with pytest.raises(ValueError, match="rms"):
        plane_boundaries(1, 1, "rms", (0.1, 0.5), "delta", DELTA, dict(fixed, eps=EPS))
    with pytest.raises(ValueError, match="second wall"):
        plane_boundaries(1, 1, "eps", (0.3, 0.7), "delta", DELTA, dict(fixed, gap=2.0))
    with pytest.raises(ValueError, match="eps range must be > 0"):
        plane_boundaries(1, 1, "eps", (0.0, 0.7), "delta", DELTA, fixed)
    with pytest.raises(ValueError, match="amplitude"):
        plane_boundaries(1, 1, "amplitude", (-1.0, 1.0), "delta", DELTA, dict(fixed, eps=EPS))


@pytest.mark.parametrize("mn", [(1, 1), (2, 1)])
def test_a_plane_without_delta_meets_a_plane_with_it(mn):
    """Over (zeta, eps) at delta = 0.2 (no delta axis: every seed solved per cell) the edge
    crosses zeta = 0.05 at the eps where the (delta, eps) edge at zeta = 0.05 crosses delta =
    0.2: one point of the (zeta, eps, delta) space reached along two planes (measured to
    5e-15)."""
    fixed = {"inv_beta": IB}
    across = plane_boundaries(*mn, "zeta", (0.02, 0.2), "eps", (0.2, 0.9),
                              dict(fixed, delta=0.2), resolution=(19, 36))
    tracer = _tracer(*mn, [0.0, 0.0, IB, 0.2, 1.0], [bk.PRM_ZETA, bk.PRM_EPS],
                     (0.02, 0.2, 0.2, 0.9))
    a = crossings(across, tracer, ZETA, lambda c: (c.x, c.y))
    along = plane_boundaries(*mn, "delta", (-0.5, 1.0), "eps", (0.2, 0.9),
                             dict(fixed, zeta=ZETA), resolution=(31, 36))
    tracer = _tracer(*mn, [ZETA, 0.0, IB, 0.0, 1.0], [bk.PRM_DELTA, bk.PRM_EPS],
                     (-0.5, 1.0, 0.2, 0.9))
    b = crossings(along, tracer, 0.2, lambda c: (c.x, c.y))
    assert [k for k, _ in a] == [k for k, _ in b] == ["grazing"]
    assert abs(a[0][1] - b[0][1]) <= SAME_LINE_TOL


def test_over_the_papers_plane_it_is_domain_boundaries_bit_for_bit():
    """plane_boundaries over (inv_beta, delta) at A = 1 is the (1/beta, delta) tracer: the
    kernels read the same numbers (1 / x, delta / 1) in the same order."""
    box = dict(inv_beta=(0.9, 1.3), delta=(-0.5, 2.5))
    old = domain_boundaries(1, 1, ZETA, EPS, **box, resolution=(9, 31))
    new = plane_boundaries(1, 1, "inv_beta", box["inv_beta"], "delta", box["delta"],
                           {"zeta": ZETA, "eps": EPS}, resolution=(9, 31))
    assert len(old) == len(new) > 0
    for a, b in zip(old, new):
        assert a.kind == b.kind and a.ends == b.ends
        for u, v in ((a.inv_beta, b.x), (a.delta, b.y), (a.orbits, b.orbits),
                     (a.error, b.error)):
            np.testing.assert_array_equal(u, v)
