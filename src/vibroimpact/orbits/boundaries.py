"""Exact boundaries of the stable (m/n) domains of Fig. 16 over the ``(1/beta, delta)`` plane
(``domain_boundaries``) or any plane of the harmonic-force problem (``plane_boundaries``: the
two parameter unknowns below are then the plane's, e.g. ``(eps, delta)``).

``domain_boundaries`` replaces the pixel edges of ``orbit_map`` by curves traced by
pseudo-arclength continuation on the augmented system: the 2m orbit equations (paper eqs.
10-11, ``newton._residual_jacobian``) plus one boundary condition, in the 2m + 2 unknowns
``(tau_0..tau_{m-1}, u_0..u_{m-1}, 1/beta, delta)`` (kernels: ``boundaries_kernels``).

Kinds of boundary (a stable admissible orbit has every test function positive; an edge of the
stable domain is where one of them reaches 0 along the stable orbit):

- ``"fold"``: a real multiplier at +1, ``1 - tr T + det T = 0`` (the stable orbit merges with
  an unstable one and both disappear);
- ``"period_doubling"``: a multiplier at -1, ``1 + tr T + det T = 0``;
- ``"grazing"``: an interior maximum of a flight reaches the wall (margin -> 0 with v = 0
  there) or an impact velocity goes to 0;
- ``"existence"``: an interval ``z_j`` goes to 0 (two impacts merge).

There is no Neimark-Sacker (torus) edge: ``det T = eps^(2m) exp(-2 zeta z) < 1``, so complex
multipliers have ``|mu| = sqrt(det T) < 1`` and stability is lost only at mu = +1 or -1.

An impact velocity going to 0 (a grazing impact) is not an edge in practice: ``T`` has
``1 / u_j`` in it, so ``|tr T|`` diverges and the orbit loses stability (a fold or a period
doubling) before it grazes; the tracing finds whichever test function vanishes first. The fold
and period-doubling conditions are taken times ``prod u_j`` (regular there), so their curves
run into the grazing-impact point (for (1/n): ``delta = q``, the linear response touching the
wall) and end there as codimension-two points. In the default Fig. 16 box the edges are fold,
period-doubling and grazing (flight maximum) curves; no ``"existence"`` edge occurs.

Seeds: every pixel edge of the map's stable mask. Each stable orbit at the stable pixel is
followed (Newton) along the segment to its unstable neighbour until a test function vanishes
(or the branch ends: a fold); that point is solved exactly (1/beta or delta fixed) and the
curve through it is traced both ways. A seed is skipped when a curve already traced crosses
its segment.

Each curve ends where it leaves the box, where a second test function of its orbit vanishes
(a codimension-two point, e.g. a period-doubling curve meeting a grazing curve: beyond it the
orbit on the curve is no longer stable and admissible, so the curve no longer bounds the
stable domain; also a corner where two maxima of one flight both touch the wall), or where it
closes on itself. Where another stable (m/n) orbit coexists the point is inside the stable
domain, not on its edge: those parts are cut out, the cut located by bisection along the curve
(to 1e-11) and listed among the codimension-two points with ``other_orbit=True``.

Accuracy: every point is a Newton solution of the augmented system whose last correction (the
estimate ``J^-1 F`` of its distance to the exact root, so it includes the conditioning) is
below ``BOUNDARY_STEP_RTOL (1 + |x|)`` in every unknown. The curve's ``error`` is then
re-estimated independently at each point: the parameter part of the minimum-norm correction
``J^+ F`` of the (2m + 1) x (2m + 2) system (the distance to the exact curve, ~1e-15 in
practice; where the curve is not vertical, delta at fixed 1/beta is off by that over the cosine
of the slope). ``tol`` bounds it. The tests check it against the (1/n) closed forms (1e-12)
and against the solver's own stability verdict 2e-9 either side of the curve.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from vibroimpact import _checks
from vibroimpact._limits import MAX_M
from vibroimpact.orbits import boundaries_kernels as bk
from vibroimpact.orbits.api import _raw_solutions, orbit_map

__all__ = ["domain_boundaries", "plane_boundaries", "BoundaryCurve", "CodimTwoPoint",
           "DomainBoundaries", "PlaneCurve", "PlanePoint", "KINDS"]

#: The kinds of boundary, in the order of the kernels' test-function codes.
KINDS = ("fold", "period_doubling", "grazing", "existence")
_KIND_OF_CODE = {bk.COND_FOLD: "fold", bk.COND_PD: "period_doubling", bk.COND_U: "grazing",
                 bk.COND_MARGIN: "grazing", bk.COND_Z: "existence"}

#: Largest step between curve points: this fraction of the box's diagonal.
MAX_STEP_OF_DIAGONAL = 1.0 / 250.0
#: Largest turn of the curve's direction (radians, in the (1/beta, delta) plane) per step.
MAX_TURN = 0.1
#: A curve is given up (end "lost") when the step falls below this fraction of the diagonal.
MIN_STEP_OF_DIAGONAL = 1e-9
#: A stalled curve (step below the minimum) tries a codimension-two point with every other
#: test function below this at its last point.
LOST_NEAR_ZERO = 1e-3
#: The end points of a curve may be this many times less accurate than ``tol``: where a
#: flight's maximum merges with a grazing impact (u -> 0) the grazing curve and the curve
#: u = 0 are tangent, and their common point is determined only to ~sqrt(round-off): measured
#: 1e-9 .. 4e-8 at the (1/2) corners of the default box.
END_TOL_FACTOR = 1000.0
#: Near a cusp of the curve's projection on the plane (the orbit unknowns move, 1/beta and delta
#: hardly): the step in all unknowns is capped at this many times the largest plane step, and
#: the turn is not checked where the plane part of the unit tangent is below CUSP_SPEED.
CUSP_STEP_FACTOR = 10.0
CUSP_SPEED = 0.05
#: Coexistence cuts: bisection along the curve down to this distance in the plane.
CUT_TOL = 1e-11
#: Hard cap on the points of one curve (each direction).
MAX_POINTS = 20000
#: Seed walk from the stable cell to its unstable neighbour: first step (fraction of the
#: segment), and the length below which a crossing is solved for directly.
WALK_STEP = 1.0 / 8.0
WALK_RESOLVE = 1e-3
#: Two orbits are the same when their phases (mod the forcing period, over it) and velocities
#: (over 1 + max u) agree to this (the coexistence test; a fold's partner is ~1e-8 away).
OTHER_ORBIT_RTOL = 1e-5


@dataclass(frozen=True, eq=False)
class BoundaryCurve:
    """One boundary curve of the stable (m/n) domain.

    Attributes
    ----------
    kind : str
        ``"fold"``, ``"period_doubling"``, ``"grazing"`` or ``"existence"``.
    m, n : int
        The motion type.
    inv_beta, delta : ndarray
        Points along the curve, in order.
    orbits : ndarray, shape (len, 2m)
        The orbit on the curve at each point: ``(tau_0..tau_{m-1}, u_0..u_{m-1})``.
    error : ndarray
        Estimated distance of each point to the exact curve in the (1/beta, delta) plane: the
        parameter part of the minimum-norm Newton correction there.
    ends : tuple of str
        Why the curve ends at its first and last point: ``"box"``, ``"codim2"``, ``"closed"``,
        ``"coexist"`` (another stable orbit takes over), ``"lost"`` (continuation failed).
    """

    kind: str
    m: int
    n: int
    inv_beta: np.ndarray
    delta: np.ndarray
    orbits: np.ndarray = field(repr=False)
    error: np.ndarray = field(repr=False)
    ends: tuple = ("box", "box")

    def __getitem__(self, key):
        if not isinstance(key, str) or key not in self.__dataclass_fields__:
            raise KeyError(key)
        return getattr(self, key)

    def __len__(self):
        return int(self.inv_beta.size)


@dataclass(frozen=True)
class CodimTwoPoint:
    """A point where two boundary conditions hold at once (a curve's end).

    ``kinds``: the curve's own kind and the other condition's. ``other_orbit``: False when
    both hold for the curve's orbit (e.g. a period-doubling orbit that grazes); True where the
    curve meets the boundary of another stable (m/n) orbit, beyond which that orbit coexists
    and the curve is no longer an edge of the stable domain (the curve's end "coexist").
    """

    inv_beta: float
    delta: float
    kinds: tuple
    m: int
    n: int
    other_orbit: bool = False

    def __getitem__(self, key):
        if not isinstance(key, str) or key not in self.__dataclass_fields__:
            raise KeyError(key)
        return getattr(self, key)


class DomainBoundaries(list):
    """The boundary curves (a list of `BoundaryCurve`) and ``codimension_two`` points."""

    def __init__(self, curves=(), codimension_two=()):
        super().__init__(curves)
        self.codimension_two = list(codimension_two)


def _test_code(i, m):
    """Test-function code and index of entry ``i`` of ``all_tests``."""
    if i == 0:
        return bk.COND_FOLD, 0
    if i == 1:
        return bk.COND_PD, 0
    k = i - 2
    return (bk.COND_U, bk.COND_MARGIN, bk.COND_Z)[k // m], k % m


class _Tracer:
    """Seeds, continuation and filtering for one (m/n) type, over the plane whose parameters
    ``prm`` and axis slots ``ax`` describe (`boundaries_kernels.plane_point`): the last two
    unknowns of a point ``x`` are its plane coordinates (Fig. 16's: 1/beta, delta)."""

    def __init__(self, m, n, prm, ax, box):
        self.m, self.n = m, n
        self.prm = np.ascontiguousarray(prm, dtype=float)
        self.ax = np.ascontiguousarray(ax, dtype=np.int64)
        self.nn = 2 * m
        self.box = box                  # (x_lo, x_hi, y_lo, y_hi)
        diag = math.hypot(box[1] - box[0], box[3] - box[2])
        self.hmax = MAX_STEP_OF_DIAGONAL * diag
        self.hmin = MIN_STEP_OF_DIAGONAL * diag
        self.stack = np.empty((64, 2))
        self.tmat = np.empty((2, 2))
        self.fvec = np.empty(self.nn + 1)
        self.jac = np.empty((self.nn + 1, self.nn + 2))
        self.dummy = np.zeros(self.nn + 2)
        self.codim2 = []
        self.hint = -1.0        # grazing curves: time of the followed maximum in its flight

    # --- kernels' wrappers ---------------------------------------------------------------
    def point(self, p):
        """``(beta, delta, zeta, eps)`` of the unit-force problem at the plane point ``p``."""
        return bk.plane_point(np.asarray(p, dtype=float), 0, self.prm, self.ax)

    def tests(self, x):
        out = np.empty(2 + 3 * self.m)
        beta, delta, zeta, eps = self.point(x[-2:])
        bk.all_tests(x[:self.nn], self.m, self.n, beta, delta, zeta, eps, self.stack,
                     self.tmat, out)
        return out

    def peak(self, code, j, x, hint=None):
        hint = self.hint if hint is None else hint
        return bk.peak_of(code, j, hint, x, self.m, self.n, self.prm, self.ax)

    def side_tests(self, x, code, j, own):
        """Every test function; the own entry is the other maxima of the own flight (margin
        curves: a second maximum reaching the wall ends the curve) or +inf."""
        t = self.tests(x)
        t[own] = self.peak(bk.COND_OTHER_PEAK, j, x)[0] if code == bk.COND_MARGIN else np.inf
        return t

    def second(self, i, own, code, j, x):
        """Code, index and hint of side test ``i`` as a curve condition (at ``x``)."""
        if i == own:
            return bk.COND_MARGIN, j, self.peak(bk.COND_OTHER_PEAK, j, x)[1]
        return _test_code(int(i), self.m) + (-1.0,)

    def newton(self, x, code, j, mode=0, code2=0, j2=0, tvec=None, xref=None, idx=0, val=0.0,
               hint2=-1.0):
        x = np.array(x, dtype=float)
        it, _ = bk.newton_aug(x, self.m, self.n, self.prm, self.ax, code, j, self.hint, mode,
                              code2, j2, hint2, self.dummy if tvec is None else tvec,
                              self.dummy if xref is None else xref, idx, val)
        return (x, it) if it >= 0 else (None, it)

    def tangent(self, x, code, j):
        bk.aug_system(x, self.m, self.n, self.prm, self.ax, code, j, self.hint, self.fvec,
                      self.jac)
        t = np.linalg.svd(self.jac)[2][-1]
        return t / np.linalg.norm(t)

    def error_of(self, x, code, j, hint):
        """Distance of ``x`` to the exact curve in the (1/beta, delta) plane: the parameter
        part of the minimum-norm Newton correction ``J^+ F`` (the conditioning included)."""
        bk.aug_system(x, self.m, self.n, self.prm, self.ax, code, j, hint, self.fvec,
                      self.jac)
        dx = np.linalg.lstsq(self.jac, -self.fvec, rcond=None)[0]
        return float(np.hypot(dx[-2], dx[-1]))

    def inside(self, x):
        b = self.box
        return b[0] <= x[-2] <= b[1] and b[2] <= x[-1] <= b[3]

    # --- seeds ---------------------------------------------------------------------------
    def localize(self, ps, pu):
        """Boundary points on the segment from the stable grid point ``ps`` to its unstable
        neighbour ``pu``: each stable orbit at ``ps`` is followed along the segment until a
        test function vanishes (or the branch ends at a fold), then solved for exactly."""
        found = []
        rows = _raw_solutions(self.m, self.n, *self.point(ps))
        fix = self.nn if ps[0] == pu[0] else self.nn + 1
        for y in rows:
            x = np.concatenate((y, ps))
            if not np.all(self.tests(x) > 0.0):
                continue
            pt = self._walk(x, ps, pu, fix)
            if pt is not None:
                found.append(pt)
        return found

    def _at(self, x, p):
        y = x[:self.nn].copy()
        if not bk.follow_orbit(y, self.m, self.n, *self.point(p)):
            return None
        return np.concatenate((y, p))

    def _walk(self, x, ps, pu, fix):
        t, dt = 0.0, WALK_STEP
        tc = self.tests(x)
        while t < 1.0:
            t1 = min(1.0, t + dt)
            x1 = self._at(x, ps + t1 * (pu - ps))
            tests1 = None if x1 is None else self.tests(x1)
            if x1 is not None and np.all(tests1 > 0.0):
                t, x, tc = t1, x1, tests1
                dt = min(2.0 * dt, WALK_STEP)
                continue
            if t1 - t > WALK_RESOLVE:
                dt = 0.25 * (t1 - t)
                continue
            if x1 is None:
                order = [int(np.argmin(np.abs(tc[:2])))] + list(np.argsort(tc))
            else:
                neg = np.flatnonzero(~(tests1 > 0.0))
                with np.errstate(invalid="ignore", divide="ignore"):
                    frac = np.where(np.isfinite(tc[neg]), tc[neg] / (tc[neg] - tests1[neg]),
                                    0.5)
                order = list(neg[np.argsort(frac)])
                x = x + np.nan_to_num(np.min(frac), nan=0.5) * (x1 - x)
            for i in order:
                code, j = _test_code(int(i), self.m)
                self.hint = -1.0
                xs, it = self.newton(x, code, j, mode=1, idx=fix, val=ps[fix - self.nn])
                if xs is None:
                    continue
                seg = pu - ps
                tt = float(np.dot(xs[-2:] - ps, seg) / np.dot(seg, seg))
                if not (-1e-3 <= tt <= 1.0 + 1e-3):
                    continue
                hint = self.peak(bk.COND_MARGIN, j, xs)[1] if code == bk.COND_MARGIN else -1.0
                return xs, code, j, hint
            return None
        return None

    # --- continuation --------------------------------------------------------------------
    def trace(self, x0, code, j, hint):
        """Both directions from the boundary point ``x0``: ``(points, hints, ends)``."""
        self.hint = hint
        t0 = self.tangent(x0, code, j)
        fwd, hf, end_f = self._branch(x0, t0, code, j)
        if end_f == "closed":
            return fwd, hf, ("closed", "closed")
        self.hint = hint
        bwd, hb, end_b = self._branch(x0, -t0, code, j)
        return bwd[::-1] + fwd[1:], hb[::-1] + hf[1:], (end_b, end_f)

    def _branch(self, x0, t0, code, j):
        own = self._own_index(code, j)
        pts = [x0]
        hints = self._hints = [self.hint]
        x, t = x0, t0
        h = 0.5 * self.hmax
        tests_x = self.side_tests(x0, code, j, own)
        travelled = 0.0
        while len(pts) < MAX_POINTS:
            if h < self.hmin:
                return self._lost(pts, tests_x, own, code, j)
            tp = math.hypot(t[-2], t[-1])
            # the step along the curve in all unknowns: h in the (1/beta, delta) plane, capped
            # where the curve turns in the orbit unknowns only (a cusp of its projection)
            big = min(h / max(tp, 1e-12), CUSP_STEP_FACTOR * self.hmax)
            xp = x + big * t
            xn, it = self.newton(xp, code, j, mode=0, tvec=t, xref=xp)
            if xn is None or it > 8:
                h *= 0.5
                continue
            dp = math.hypot(xn[-2] - x[-2], xn[-1] - x[-1])
            tn = self.tangent(xn, code, j)
            if np.dot(tn, t) < 0.0:
                tn = -tn
            # the turn in the plane, unless the curve is near a cusp of its projection there
            turn = _angle(t[-2:], tn[-2:]) if min(tp, math.hypot(*tn[-2:])) > CUSP_SPEED else 0.0
            if (dp > 2.0 * h or np.dot(tn, t) < 0.9 or turn > MAX_TURN) and h > 4 * self.hmin:
                h *= 0.5
                continue
            tests_n = self.side_tests(xn, code, j, own)
            ok = tests_n > 0.0
            out = not self.inside(xn)
            if out and not (self.box[0] < x[-2] < self.box[1]
                            and self.box[2] < x[-1] < self.box[3]):
                return pts, hints, "box"  # started on the box's edge, going out
            if not np.all(ok) or out:
                end = self._finish(x, xn, tests_x, tests_n, ok, out, code, j, own)
                if end is None:           # could not solve the end point: smaller step
                    if h > 4 * self.hmin:
                        h *= 0.5
                        continue
                    return self._lost(pts, tests_x, own, code, j)
                xe, why = end
                pts.append(xe)
                hints.append(self.hint)
                return pts, hints, why
            travelled += dp
            if (travelled > 4 * self.hmax and len(pts) > 8
                    and math.hypot(xn[-2] - x0[-2], xn[-1] - x0[-1]) < 1.5 * h
                    and np.dot(tn, t0) > 0.0):
                pts.append(xn)
                pts.append(x0)
                hints.extend([self.hint, hints[0]])
                return pts, hints, "closed"
            if code == bk.COND_MARGIN:
                self.hint = self.peak(bk.COND_MARGIN, j, xn)[1]
            pts.append(xn)
            hints.append(self.hint)
            x, t, tests_x = xn, tn, tests_n
            if it <= 4 and turn < 0.3 * MAX_TURN:
                h = min(1.5 * h, self.hmax)
        return pts, hints, "lost"

    def _lost(self, pts, tests_x, own, code, j):
        """The continuation stalled: typically next to a point where a second test function
        vanishes degenerately (an impact velocity -> 0 as a flight's maximum reaches the
        impact). Try that codimension-two point from the last point; else end "lost"."""
        x = pts[-1]
        for i in np.argsort(np.abs(tests_x)):
            if not abs(tests_x[i]) < LOST_NEAR_ZERO:
                continue
            c2, j2, h2 = self.second(i, own, code, j, x)
            if i == own and h2 < 0.0:
                continue                  # no other maximum on the flight
            xs, _ = self.newton(x, code, j, mode=2, code2=c2, j2=j2, hint2=h2)
            if xs is not None and math.hypot(xs[-2] - x[-2], xs[-1] - x[-1]) < 10 * self.hmin:
                self.codim2.append(CodimTwoPoint(float(xs[-2]), float(xs[-1]),
                                                 (_KIND_OF_CODE[code], _KIND_OF_CODE[c2]),
                                                 self.m, self.n))
                self._hints.append(self.hint)
                return pts + [xs], self._hints, "codim2"
        return pts, self._hints, "lost"

    def crossing(self, x, code, kind):
        """Record where the curve meets the boundary of another stable orbit (coexistence)."""
        if kind is not None:
            self.codim2.append(CodimTwoPoint(float(x[-2]), float(x[-1]),
                                             (_KIND_OF_CODE[code], kind), self.m, self.n,
                                             other_orbit=True))

    def _own_index(self, code, j):
        m = self.m
        j = j % m
        return {bk.COND_FOLD: 0, bk.COND_PD: 1, bk.COND_U: 2 + j, bk.COND_MARGIN: 2 + m + j,
                bk.COND_Z: 2 + 2 * m + j}[code]

    def _finish(self, x, xn, tests_x, tests_n, ok, out, code, j, own):
        """The end point between ``x`` and ``xn``: a codimension-two point or the box edge."""
        cands = []
        for i in np.flatnonzero(~ok):
            a, b = tests_x[i], tests_n[i]
            f = a / (a - b) if np.isfinite(a) and np.isfinite(b) and a != b else 0.5
            cands.append((min(max(f, 0.0), 1.0), "codim2", int(i)))
        if out:
            b = self.box
            for col, lo, hi in ((-2, b[0], b[1]), (-1, b[2], b[3])):
                for edge in (lo, hi):
                    if (x[col] - edge) * (xn[col] - edge) < 0.0:
                        cands.append(((edge - x[col]) / (xn[col] - x[col]), "box", (col, edge)))
        cands.sort(key=lambda c: c[0])
        for f, why, what in cands:
            xi = x + f * (xn - x)
            if why == "box":
                col, edge = what
                xs, _ = self.newton(xi, code, j, mode=1, idx=self.nn + 2 + col, val=edge)
            else:
                c2, j2, h2 = self.second(what, own, code, j, xn)
                xs, _ = self.newton(xi, code, j, mode=2, code2=c2, j2=j2, hint2=h2)
            if xs is None or np.linalg.norm(xs[-2:] - xi[-2:]) > 2.0 * np.linalg.norm(
                    xn[-2:] - x[-2:]) + 1e-12:
                continue                    # not this end: the next candidate may hold
            if why == "codim2" and not self.inside(xs):
                # the second condition holds only outside the box: cut at the box's edge
                return self._finish(x, xs, tests_x, tests_x, np.ones_like(ok), True, code, j,
                                    own)
            if why == "codim2":
                self.codim2.append(CodimTwoPoint(
                    float(xs[-2]), float(xs[-1]),
                    (_KIND_OF_CODE[code], _KIND_OF_CODE[c2]),
                    self.m, self.n))
            return xs, why
        return None

    # --- coexistence ---------------------------------------------------------------------
    def other_stable(self, x):
        """A stable admissible (m/n) orbit other than ``x``'s at its point, or None."""
        m, nn = self.m, self.nn
        beta, delta, zeta, eps = self.point(x[-2:])
        tf = 2.0 * math.pi / beta
        rows = _raw_solutions(m, self.n, beta, delta, zeta, eps)
        ph0 = np.sort(np.mod(x[:m], tf))
        u0 = np.sort(x[m:nn])
        uscale = 1.0 + np.max(np.abs(u0))
        for y in rows:
            ph = np.sort(np.mod(y[:m], tf))
            dph = np.abs(ph - ph0) % tf
            dph = np.minimum(dph, tf - dph)
            if (np.max(dph) <= OTHER_ORBIT_RTOL * tf
                    and np.max(np.abs(np.sort(y[m:]) - u0)) <= OTHER_ORBIT_RTOL * uscale):
                continue
            if np.all(self.tests(np.concatenate((y, x[-2:]))) > 0.0):
                return y
        return None

    def cut(self, xg, xb, hint, code, j):
        """Where, between the curve points ``xg`` (an edge) and ``xb`` (another stable orbit
        coexists), the other orbit appears: bisection along the curve (each trial point
        corrected onto it) down to CUT_TOL in the plane. Returns the last edge point and the
        kind of the other orbit's condition that vanishes there (its smallest test)."""
        self.hint = hint
        d = xb - xg
        tvec = d / np.linalg.norm(d)
        lo, hi = 0.0, 1.0
        x_lo, y_hi, x_hi = xg, None, xb
        plane = math.hypot(d[-2], d[-1])
        while (hi - lo) * plane > CUT_TOL:
            mid = 0.5 * (lo + hi)
            xp = xg + mid * d
            xs, _ = self.newton(xp, code, j, mode=0, tvec=tvec, xref=xp)
            if xs is None:
                break
            y = self.other_stable(xs)
            if y is None:
                lo, x_lo = mid, xs
            else:
                hi, y_hi, x_hi = mid, y, xs
        if y_hi is None:
            y_hi = self.other_stable(x_hi)
        kind = None
        if y_hi is not None:
            t = self.tests(np.concatenate((y_hi, x_hi[-2:])))
            kind = _KIND_OF_CODE[_test_code(int(np.argmin(t)), self.m)[0]]
        return x_lo, kind


def _angle(a, b):
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na == 0.0 or nb == 0.0:
        return 0.0
    return math.acos(max(-1.0, min(1.0, float(np.dot(a, b) / (na * nb)))))


def _range(name, value):
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a (lo, hi) pair, got {value!r}") from None
    lo = _checks.real(f"{name}[0]", lo)
    hi = _checks.real(f"{name}[1]", hi)
    if not lo < hi:
        raise ValueError(f"{name} must be a non-empty range with lo < hi, got ({lo}, {hi})")
    return lo, hi


def _seed_stable(seed_map, m, n, inv_beta, delta, resolution, zeta, eps):
    """The stable mask (nb, nd) and the grid coordinates of the seeds."""
    if seed_map is None:
        nb, nd = resolution
        ib = np.linspace(inv_beta[0], inv_beta[1], nb)
        dd = np.linspace(delta[0], delta[1], nd)
        mp = orbit_map(ib, dd, types=[(m, n)], zeta=zeta, eps=eps)
        return mp["n_stable"][0] > 0, ib, dd
    try:
        types = np.asarray(seed_map["types"]).reshape(-1, 2)
        ib = np.asarray(seed_map["inv_beta"], dtype=float)
        dd = np.asarray(seed_map["delta"], dtype=float)
        n_stable = np.asarray(seed_map["n_stable"])
    except (KeyError, TypeError) as exc:
        raise ValueError(f"seed_map must be a dict as orbit_map returns ({exc})") from None
    hit = np.flatnonzero((types[:, 0] == m) & (types[:, 1] == n))
    if hit.size == 0:
        raise ValueError(f"seed_map has no ({m}/{n}) type (types {types.tolist()})")
    return n_stable[hit[0]] > 0, ib, dd


def _seed_segments(stable, ib, dd):
    """Pixel edges of the stable mask: ``(stable point, unstable neighbour)`` pairs."""
    segs = []
    a, b = stable[:, :-1], stable[:, 1:]
    for i, k in zip(*np.nonzero(a != b)):
        p, q = np.array([ib[i], dd[k]]), np.array([ib[i], dd[k + 1]])
        segs.append((p, q) if a[i, k] else (q, p))
    a, b = stable[:-1, :], stable[1:, :]
    for i, k in zip(*np.nonzero(a != b)):
        p, q = np.array([ib[i], dd[k]]), np.array([ib[i + 1], dd[k]])
        segs.append((p, q) if a[i, k] else (q, p))
    return segs


def _crosses(pts, segs):
    """Mask of the seed segments ``segs`` (k, 2, 2) crossed by the polyline ``pts`` (N, 2)."""
    if len(pts) < 2 or len(segs) == 0:
        return np.zeros(len(segs), dtype=bool)
    p1, p2 = pts[:-1][None], pts[1:][None]
    q1, q2 = segs[:, 0][:, None], segs[:, 1][:, None]

    def orient(a, b, c):
        return ((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
                - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    return np.any((d1 * d2 <= 0.0) & (d3 * d4 <= 0.0), axis=1)


def domain_boundaries(m, n, zeta, eps, inv_beta=(0.2, 3.0), delta=(-1.5, 3.0), *,
                      resolution=(141, 226), seed_map=None, tol=1e-10):
    """Exact boundary curves of the domain where a stable (m/n) motion exists (Fig. 16).

    Parameters
    ----------
    m, n : int
        Motion type (m <= 3).
    zeta, eps : float
        Damping ratio in (0, 1), restitution coefficient in (0, 1] (eps = 0, where every
        flight starts at rest on the wall with a degenerate maximum there, is not supported).
    inv_beta, delta : (lo, hi)
        The box of the ``(1/beta, delta)`` plane; curves are cut at its edges.
    resolution : (nb, nd)
        Grid of the seed map when ``seed_map`` is not given.
    seed_map : dict, optional
        An ``orbit_map`` result holding the (m, n) type (others are ignored); its pixel edges
        (``n_stable > 0`` against ``== 0``) seed the curves.
    tol : float
        Required accuracy of each point; a point whose estimated distance to the exact curve
        (``BoundaryCurve.error``) exceeds it raises RuntimeError. The two end points may be
        ``END_TOL_FACTOR`` (1000) times less accurate: a codimension-two point where a flight's
        maximum merges with a grazing impact is a tangency, found to ~1e-9 .. 4e-8 only.

    Returns
    -------
    DomainBoundaries
        A list of `BoundaryCurve` (``kind``, ``m``, ``n``, ``inv_beta``, ``delta``, ...), with
        ``codimension_two``: the `CodimTwoPoint` s where curves end on another condition.

    Notes
    -----
    Kinds: ``"fold"`` (a multiplier at +1), ``"period_doubling"`` (at -1), ``"grazing"`` (a
    flight's interior maximum reaches the wall, or an impact velocity reaches 0),
    ``"existence"`` (an interval reaches 0). There is no Neimark-Sacker edge: ``det T =
    eps^(2m) exp(-2 zeta z) < 1``, so complex multipliers are always inside the unit circle.
    See the module docstring for the method, the ends of a curve and the accuracy. Points are
    at most 1/250 of the box's diagonal apart and the direction turns by at most 0.1 rad
    between them (except across a cusp of the curve's projection).

    Examples
    --------
    The edges of the stable (1/1) domain over a small window of Fig. 16:

    >>> from vibroimpact import domain_boundaries
    >>> curves = domain_boundaries(1, 1, 0.05, 0.5, inv_beta=(0.8, 1.4), delta=(-0.5, 1.5),
    ...                            resolution=(13, 21))
    >>> sorted({curve.kind for curve in curves})
    ['grazing']
    """
    m = _checks.integer("m", m, low=1)
    n = _checks.integer("n", n, low=1)
    if m > MAX_M:
        raise ValueError(f"m must be at most {MAX_M}, got {m}")
    zeta = _checks.zeta(zeta)
    eps = _checks.eps(eps)
    if eps == 0.0:
        raise ValueError("eps must be > 0 for domain_boundaries, got 0.0 (with eps = 0 every "
                         "flight starts at rest on the wall, where its maximum is degenerate; "
                         "not supported)")
    inv_beta = _range("inv_beta", inv_beta)
    if inv_beta[0] <= 0.0:
        raise ValueError(f"inv_beta must be positive, got {inv_beta}")
    delta = _range("delta", delta)
    try:
        nb, nd = (int(r) for r in resolution)
    except (TypeError, ValueError):
        raise ValueError(f"resolution must be a pair of integers, got {resolution!r}") from None
    if nb < 2 or nd < 2:
        raise ValueError(f"resolution must be at least (2, 2), got {resolution!r}")
    tol = _checks.real("tol", tol, low=0.0, low_open=True)

    stable, ib_grid, d_grid = _seed_stable(seed_map, m, n, inv_beta, delta, (nb, nd), zeta,
                                           eps)
    box = (inv_beta[0], inv_beta[1], delta[0], delta[1])
    prm = np.array([zeta, eps, 0.0, 0.0, 1.0])
    ax = np.array([bk.PRM_INV_BETA, bk.PRM_DELTA])
    return _trace(m, n, prm, ax, box, stable, ib_grid, d_grid, tol)


def _trace(m, n, prm, ax, box, stable, x_grid, y_grid, tol):
    """The boundary curves of the (m/n) stable domain over the plane (``prm``, ``ax``: see
    `_Tracer`), seeded by the pixel edges of ``stable`` over ``(x_grid, y_grid)``, cut at
    ``box``. Coordinates ``x`` and ``y`` are in the fields ``inv_beta`` and ``delta`` of the
    `BoundaryCurve` and `CodimTwoPoint` objects (Fig. 16's plane; `plane_boundaries` renames
    them)."""
    tr = _Tracer(m, n, prm, ax, box)
    segs = [(ps, pu) for ps, pu in _seed_segments(stable, x_grid, y_grid)
            if tr.inside(ps) and tr.inside(pu)]    # a seed map may be larger than the box
    seg_arr = np.array(segs).reshape(-1, 2, 2)
    covered = np.zeros(len(segs), dtype=bool)
    raw = []                                   # (points (N, 2m+2), code, j, ends)
    for k, (ps, pu) in enumerate(segs):
        if covered[k]:
            continue
        covered[k] = True
        for x0, code, j, hint in tr.localize(ps, pu):
            if _near_known(raw, x0, code, tr.hmax):
                continue
            pts, hints, ends = tr.trace(x0, code, j, hint)
            pts = np.array(pts)
            raw.append((pts, code, j, ends, np.array(hints)))
            covered |= _crosses(pts[:, -2:], seg_arr)
    curves = []
    for pts, code, j, ends, hints in raw:
        for piece, phints, pends in _edge_pieces(tr, pts, hints, ends, code, j):
            err = np.array([tr.error_of(x, code, j, h) for x, h in zip(piece, phints)])
            # (not `> tol`: a NaN estimate is a failure too)
            if not (np.all(err[1:-1] <= tol) and np.all(err[[0, -1]] <= END_TOL_FACTOR * tol)):
                raise RuntimeError(f"boundary point not converged to tol={tol}: "
                                   f"max error estimate {np.nanmax(err):.3g}")
            curves.append(BoundaryCurve(
                kind=_KIND_OF_CODE[code], m=m, n=n, inv_beta=piece[:, -2].copy(),
                delta=piece[:, -1].copy(), orbits=piece[:, :2 * m].copy(), error=err,
                ends=pends))
    ends = [(c.inv_beta[k], c.delta[k]) for c in curves for k in (0, -1)]
    codim2 = _dedupe([p for p in tr.codim2
                      if any(abs(p.inv_beta - a) <= 1e-12 and abs(p.delta - b) <= 1e-12
                             for a, b in ends)])  # not those of parts cut out (coexistence)
    return DomainBoundaries(curves, codim2)


def _near_known(raw, x0, code, hmax):
    """Whether ``x0`` lies on a curve already traced with the same kind of condition."""
    return any(c == code and _chord_gap(pts, x0) <= 0.05 * hmax for pts, c, *_ in raw)


def _chord_gap(pts, x0):
    """Distance from ``x0`` to the polyline ``pts`` in the parameter plane."""
    p = pts[:, -2:]
    q = x0[-2:]
    if len(p) < 2:
        return float(np.hypot(*(p[0] - q)))
    a, b = p[:-1], p[1:]
    ab = b - a
    den = np.maximum(np.sum(ab * ab, axis=1), 1e-300)
    s = np.clip(np.sum((q - a) * ab, axis=1) / den, 0.0, 1.0)
    return float(np.min(np.hypot(*(a + s[:, None] * ab - q).T)))


def _edge_pieces(tr, pts, hints, ends, code, j):
    """Split a traced curve where another stable orbit coexists (not an edge there)."""
    inner = np.array([tr.other_stable(x) is not None for x in pts])
    runs = []
    start = None
    for i, bad in enumerate(inner):
        if not bad and start is None:
            start = i
        if (bad or i == len(pts) - 1) and start is not None:
            runs.append((start, i if bad else i + 1))
            start = None
    pieces = []
    for start, stop in runs:
        p, h = list(pts[start:stop]), list(hints[start:stop])
        e0 = ends[0] if start == 0 else "coexist"
        e1 = ends[1] if stop == len(pts) else "coexist"
        if start > 0:
            xe, kind = tr.cut(pts[start], pts[start - 1], hints[start], code, j)
            p.insert(0, xe)
            h.insert(0, hints[start])
            tr.crossing(xe, code, kind)
        if stop < len(pts):
            xe, kind = tr.cut(pts[stop - 1], pts[stop], hints[stop - 1], code, j)
            p.append(xe)
            h.append(hints[stop - 1])
            tr.crossing(xe, code, kind)
        if len(p) >= 2:
            pieces.append((np.array(p), np.array(h), (e0, e1)))
    return pieces


def _dedupe(points):
    out = []
    for p in points:
        if not any(abs(p.inv_beta - o.inv_beta) < 1e-6 and abs(p.delta - o.delta) < 1e-6
                   for o in out):
            out.append(p)
    return out


#: Slots of the plane's parameters in the kernels' parameter vector.
_SLOTS = {"zeta": bk.PRM_ZETA, "eps": bk.PRM_EPS, "inv_beta": bk.PRM_INV_BETA,
          "delta": bk.PRM_DELTA, "amplitude": bk.PRM_AMPLITUDE}


@dataclass(frozen=True, eq=False)
class PlaneCurve:
    """One boundary curve of the stable (m/n) domain over a plane (`plane_boundaries`).

    As `BoundaryCurve`, with the points' coordinates ``x``, ``y`` along the plane's
    ``axes`` (x first). ``orbits`` are those of the unit-force problem: with an amplitude
    A != 1 the velocities are over A (the orbit at A is A times the one at delta / A).
    """

    kind: str
    m: int
    n: int
    x: np.ndarray
    y: np.ndarray
    orbits: np.ndarray = field(repr=False)
    error: np.ndarray = field(repr=False)
    ends: tuple = ("box", "box")
    axes: tuple = ("inv_beta", "delta")

    def __len__(self):
        return int(self.x.size)


@dataclass(frozen=True)
class PlanePoint:
    """A codimension-two point (`CodimTwoPoint`) over a plane: coordinates ``x``, ``y``."""

    x: float
    y: float
    kinds: tuple
    m: int
    n: int
    other_orbit: bool = False
    axes: tuple = ("inv_beta", "delta")


def _plane_range(name, value):
    lo, hi = _range(name, value)
    if name == "eps" and not lo > 0.0:
        raise ValueError(f"the eps range must be > 0 for the boundaries, got {(lo, hi)} (with "
                         f"eps = 0 every flight starts at rest on the wall, where its maximum "
                         f"is degenerate; not supported)")
    for v in (lo, hi):
        _plane_check_value(name, v)
    return lo, hi


def _plane_check_value(name, value):
    from vibroimpact.orbits.plane import _check_value

    return _check_value(name, value)


def plane_boundaries(m, n, x_name, x_range, y_name, y_range, fixed, *, resolution=(41, 201),
                     seed_map=None, tol=1e-10):
    """Exact boundary curves of the stable (m/n) domain over any plane of the harmonic-force
    problem with one wall (Fig. 16 over that plane; `domain_boundaries` over (1/beta, delta)).

    Parameters
    ----------
    m, n : int
        Motion type (m <= 3).
    x_name, y_name : str
        The plane's axes, two of ``zeta``, ``eps``, ``delta``, ``inv_beta``, ``amplitude``
        (`vibroimpact.orbits.plane.orbit_plane`'s; a second wall or the noise's rms raises).
    x_range, y_range : (lo, hi)
        The box; curves are cut at its edges. An eps range must be > 0 (as `domain_boundaries`
        refuses eps = 0).
    fixed : dict
        Every other parameter, as `orbit_plane` takes it (``amplitude`` default 1).
    resolution : (nx, ny)
        Grid of the seed map when ``seed_map`` is not given (`orbit_plane` over the box).
    seed_map : xarray.Dataset, optional
        An `orbit_plane` result over this plane holding the (m/n) type; its pixel edges
        (``n_stable > 0`` against ``== 0``) seed the curves.
    tol : float
        As `domain_boundaries`.

    Returns
    -------
    DomainBoundaries
        A list of `PlaneCurve` (``x``, ``y`` along ``axes``) with ``codimension_two``, a list
        of `PlanePoint`.

    Notes
    -----
    The continuation of `domain_boundaries` with its two parameter unknowns the plane's: the
    kernels read the unit-force problem at each point (``beta``, ``delta / A``, ``zeta``,
    ``eps``; the amplitude scales out, `vibroimpact.orbits.plane`). Over ``(inv_beta,
    delta)`` with A = 1 the result is `domain_boundaries`' bit for bit. Step lengths and
    tolerances are in the plane's own units (its box's diagonal), as there.
    """
    from vibroimpact.orbits.plane import HARMONIC_PARAMETERS, check_plane

    m = _checks.integer("m", m, low=1)
    n = _checks.integer("n", n, low=1)
    if m > MAX_M:
        raise ValueError(f"m must be at most {MAX_M}, got {m}")
    if "gap" in (x_name, y_name) or (isinstance(fixed, dict) and "gap" in fixed):
        raise ValueError("the boundaries continue the one-wall closed-form (m/n) solutions: "
                         "a plane with a second wall (gap) has none; its edges are the map's "
                         "cell edges")
    x_range = _plane_range(x_name, x_range) if x_name in HARMONIC_PARAMETERS else x_range
    y_range = _plane_range(y_name, y_range) if y_name in HARMONIC_PARAMETERS else y_range
    fixed = check_plane(x_name, list(x_range), y_name, list(y_range), fixed, [(m, n)])[2]
    if "eps" in fixed and not fixed["eps"] > 0.0:
        raise ValueError(f"eps must be > 0 for the boundaries, got {fixed['eps']} (with eps = 0 "
                         f"every flight starts at rest on the wall; not supported)")
    try:
        nx, ny = (int(r) for r in resolution)
    except (TypeError, ValueError):
        raise ValueError(f"resolution must be a pair of integers, got {resolution!r}") from None
    if nx < 2 or ny < 2:
        raise ValueError(f"resolution must be at least (2, 2), got {resolution!r}")
    tol = _checks.real("tol", tol, low=0.0, low_open=True)
    label = f"{m}/{n}"
    if seed_map is None:
        from vibroimpact.orbits.plane import orbit_plane

        seed_map = orbit_plane(x_name, np.linspace(*x_range, nx), y_name,
                               np.linspace(*y_range, ny), fixed, types=[(m, n)])
    try:
        types = [str(t) for t in seed_map["type"].values]
        x_grid = np.asarray(seed_map[x_name].values, dtype=float)
        y_grid = np.asarray(seed_map[y_name].values, dtype=float)
    except (KeyError, TypeError, AttributeError) as exc:
        raise ValueError(f"seed_map must be an orbit_plane dataset over ({x_name}, {y_name}) "
                         f"({exc!r})") from None
    if label not in types:
        raise ValueError(f"seed_map has no ({label}) type (types {types})")
    stable = (seed_map["n_stable"].sel(type=label).transpose(x_name, y_name).values > 0)
    prm = np.zeros(5)
    for name, slot in _SLOTS.items():
        if name in fixed:
            prm[slot] = fixed[name]
    ax = np.array([_SLOTS[x_name], _SLOTS[y_name]])
    box = (x_range[0], x_range[1], y_range[0], y_range[1])
    found = _trace(m, n, prm, ax, box, stable, x_grid, y_grid, tol)
    axes = (x_name, y_name)
    curves = [PlaneCurve(kind=c.kind, m=c.m, n=c.n, x=c.inv_beta, y=c.delta, orbits=c.orbits,
                         error=c.error, ends=c.ends, axes=axes) for c in found]
    points = [PlanePoint(p.inv_beta, p.delta, p.kinds, p.m, p.n, p.other_orbit, axes)
              for p in found.codimension_two]
    return DomainBoundaries(curves, points)
