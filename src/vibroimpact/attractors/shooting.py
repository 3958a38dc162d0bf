"""Periodic motions of any wall layout: Newton shooting on the exact flow.

The closed-form solver (:func:`vibroimpact.periodic_orbits`) knows one wall and a given
number of impacts. This one knows neither limit: it solves ``Phi_n(X) = X`` for the state
``X = (x, v)`` at a fixed phase of the force, where ``Phi_n`` is the exact flow over ``n``
forcing periods with impacts at either wall, and reads the motion's impact sequence off the
converged orbit. Seeds come from settled starts (:func:`vibroimpact.simulate`), so a cell's
stable motions are found whatever their type (docs/model.md, section 8.8).

Method
------
- Flight: the particular harmonic solution plus the damped free response fitted to the state
  at the flight's start (closed form; as :mod:`vibroimpact.orbits.flight` for one wall).
- First contact with either wall, rigorously: the critical points of ``x`` (zeros of ``x'``)
  are found left to right on brackets that a bound on the next derivative proves to hold no
  zero of ``x'`` or a single one (otherwise the bracket is bisected; the proof of
  ``orbits.flight.flight_max``, with a bound of the derivatives that stays tight near
  resonance: ``_bound``). Between two critical points ``x`` is monotone, so a wall is
  crossed there exactly when the piece ends beyond it, and the crossing is then the only root
  of ``x - wall`` on the piece (safeguarded Newton). A flight that rises towards a wall and
  turns back without a sign change at the samples (grazing, double crossing) is therefore
  never jumped over: its maximum is a critical point, computed, and compared with the wall.
- Impact at wall ``w`` (approach velocity ``u``): ``v -> R_w(u) = -eps_w(u) u``, the wall's
  impact law (:mod:`vibroimpact.model`; ``eps_w`` constant under Newton's law).
- Jacobian of ``Phi_n``: the product of the free propagators ``P(s)`` of the flights and the
  impacts' saltation matrices ``S = [[R / u, 0], [(a_+ - R' a_-) / u, R']]`` (``a_-+`` the
  accelerations just before and after the impact, ``R' = dR/du``; Newton's law:
  ``[[-eps, 0], [(a_+ + eps a_-) / u, -eps]]``); ``det = prod (R R' / u) exp(-2 zeta z)``,
  ``prod eps_w^2 exp(-2 zeta z)`` under Newton's law.
- Newton on ``Phi_n(X) - X`` at a phase ``theta`` chosen in the middle of the largest gap
  between the impacts' phases (so no impact sits on the section while Newton moves the orbit),
  with halving of steps that do not reduce the residual; converged when the residual is below
  ``NEWTON_TOL`` (relative to ``1 + |X|``), then polished while a step halves it.
- Seeds: a grid of starts run by the simulator in rounds until each repeats after one of the
  asked n (``RETURN_TOL``); Newton runs from it for those n, unless it has settled onto a motion
  found already. A stable motion is found when its basin meets the grid of starts.
- Not handled: chatter and sticking (an impact slower than ``CHATTER_SPEED`` or more than
  ``MAX_IMPACTS_PER_PERIOD`` impacts in a forcing period); such seeds are reported in
  ``skipped`` with kind ``"chatter"`` (Newton never runs through sticking), as are settled
  starts resting on a wall (``"sticking"``) or repeating after none of the n
  (``"not_periodic"``), starts Newton does not converge from
  (``"not_converged"``) and motions of a shorter period than asked (``"shorter_period"``:
  they are the motions of that shorter ``n``).
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from numba import njit
import numpy as np

from vibroimpact import _checks
from vibroimpact._kernel_cache import kernel_decorator
from vibroimpact._law import (LAW_MODULES, rebound_derivative, rebound_ratio,
                              rebound_velocity)
from vibroimpact.impact.layout import (N_PARAMS, P_A, P_AQ, P_BETA, P_DELTA, P_EPS, P_LAW_A,
                                       P_OMEGA, P_PHI, P_ZETA)
from vibroimpact.impact.parameters import parameters
from vibroimpact.model import Model

__all__ = ["PeriodicMotion", "SkippedSeed", "MotionSet", "periodic_motions"]

#: Stamped with the simulator's layout too: the kernels read its slot constants.
kernel = kernel_decorator(njit, __file__, ("shooting.py", "../impact/layout.py")
                          + tuple(f"../{m}" for m in LAW_MODULES), error_model="numpy")

# --- thresholds, each with its reason ---------------------------------------------------------
#: Critical-point search: initial bracket in radians of the fastest of beta and wd (x' has
#: at most a few zeros per radian), at least MIN_BRACKETS of them per flight; bisection stops
#: at MIN_STEP (relative to max(1, flight)): there x' and x'' vanish together and x is flat to
#: ~|x'''| h^3 ~ 1e-27, so the sliver is taken as one critical point at its middle.
PHASE_STEP = 0.5
MIN_BRACKETS = 4
MIN_STEP = 1e-9
STACK = 64               # bisection levels: ~30 reach MIN_STEP from a 0.5 rad bracket
#: Root of x - wall on a monotone piece: a few ulps of the instant.
ROOT_XTOL = 4e-16
ROOT_MAXIT = 100
#: An impact slower than this starts chatter (the velocities then shrink geometrically to an
#: accumulation point and sticking), which shooting does not follow.
CHATTER_SPEED = 1e-7
#: More impacts than this in one forcing period: chatter (eps near 1 shrinks slowly).
MAX_IMPACTS_PER_PERIOD = 64
#: Newton: residual tolerance relative to 1 + |X| (the brief's ~1e-12), iterations, halvings.
NEWTON_TOL = 1e-12
NEWTON_MAXIT = 40
NEWTON_HALVINGS = 10
NEWTON_POLISH = 0.5      # polish steps continue while they cut the residual by this factor
#: Two motions are one when a phase-0 state of one is this close (relative to 1 + |X|) to a
#: phase-0 state of the other; a motion whose state returns this close after a proper divisor
#: of n periods has that shorter period. Far above the Newton tolerance over |1 - mu|, far below
#: the distance between distinct coexisting orbits.
SAME_TOL = 1e-7
#: Admissibility: the margin to the walls of every interior extremum of every flight must be
#: >= -ADMISSIBLE_TOL (the closed-form solver's value); within GRAZING_TOL of a wall a flight
#: grazes it (the edge of an existence domain; the motion is reported with ``grazing=True``).
ADMISSIBLE_TOL = 1e-12
GRAZING_TOL = 1e-9
#: Settling: forcing-cycle grid of the simulator (samples per forcing period; exact at any
#: step, it only sets where the samples fall) and the periods simulated before Newton.
SETTLE_SAMPLES = 64
SETTLE_PERIODS = 50
#: A settled start seeds Newton for the n after which it returns within RETURN_TOL (relative
#: to 1 + |X|): well inside Newton's basin, and far above the distance to a stable motion
#: left by SETTLE_PERIODS (multiplier^50 ~ 1e-3 even at |mu| = 0.87). A start that returns
#: after none of the n is run again, SETTLE_ROUNDS rounds at most (slowly settling motions,
#: |mu| near 1), then reported "not_periodic" (chaos, or a period not among the n).
RETURN_TOL = 1e-2
SETTLE_ROUNDS = 4
#: A settled state this close (relative to 1 + |X|) to a phase-0 state of a motion found
#: already (or to a seed that failed already) is on it: Newton from it is not run again.
SETTLED_TOL = 1e-3
#: Default starts: a DEFAULT_STARTS x DEFAULT_STARTS grid. On the Fig. 16 grid stable motions
#: coexist with basins of ~2% of the start box (a (1/1) beside a (2/1) at 1/beta = 1.2,
#: delta = 0.44; a (3/1) beside a (4/1) at delta = -0.16): 5 x 5 and 8 x 8 miss the first,
#: 12 x 12 finds both (and 1967 of the 1969 stable closed-form motions of 6554 cells of the
#: Fig. 16 grid; the two missed graze, with basins below 0.1% of the box: docs/model.md 8.8).
DEFAULT_STARTS = 12

# status codes of the flow kernel
OK, CHATTER = 0, 1
# The kernels read the simulator's parameter vector (vibroimpact.impact.layout), always with
# both halves (_Flow): the wall above the mass in the first N_PARAMS slots, the wall below in
# the next, mirrored (x -> -x), so that its position is -P[N_PARAMS + P_DELTA] (-inf with one
# wall) and its restitution and law are P[N_PARAMS + P_EPS], P[N_PARAMS + P_LAW_A]; the
# kernels work in the lab frame and read the force (P_A, P_AQ) from the first half.


# --- kernels ----------------------------------------------------------------------------------
@kernel
def _fit(t0, x0, v0, P):
    """Phase of the particular solution at ``t0`` and the free response's ``(c1, c2)``."""
    zeta, wd, aq, beta = P[P_ZETA], P[P_OMEGA], P[P_AQ], P[P_BETA]
    th0 = beta * t0 - P[P_PHI]
    c1 = x0 - aq * math.sin(th0)
    c2 = (v0 - aq * beta * math.cos(th0) + zeta * c1) / wd
    return th0, c1, c2


@kernel
def _eval(s, th0, c1, c2, P):
    """``x, x', x'', x'''`` at ``s`` after the flight's start."""
    zeta, wd, aq, beta = P[P_ZETA], P[P_OMEGA], P[P_AQ], P[P_BETA]
    e = math.exp(-zeta * s)
    cw = math.cos(wd * s)
    sw = math.sin(wd * s)
    th = th0 + beta * s
    sn = math.sin(th)
    cs = math.cos(th)
    # each derivative of the free part rotates (c1, c2) with unit gain (zeta^2 + wd^2 = 1)
    b1 = -zeta * c1 + wd * c2
    d1 = -zeta * c2 - wd * c1
    b2 = -zeta * b1 + wd * d1
    d2 = -zeta * d1 - wd * b1
    b3 = -zeta * b2 + wd * d2
    d3 = -zeta * d2 - wd * b2
    x = aq * sn + e * (c1 * cw + c2 * sw)
    v = aq * beta * cs + e * (b1 * cw + d1 * sw)
    a = -aq * beta * beta * sn + e * (b2 * cw + d2 * sw)
    j = -aq * beta ** 3 * cs + e * (b3 * cw + d3 * sw)
    return x, v, a, j


@kernel
def _root(lo, hi, wall, sgn, th0, c1, c2, P):
    """The one root of ``x - wall`` in ``[lo, hi]``, where ``sgn (x - wall)`` rises from < 0."""
    s = 0.5 * (lo + hi)
    for _ in range(ROOT_MAXIT):
        x, v, a, j = _eval(s, th0, c1, c2, P)
        g = sgn * (x - wall)
        if g < 0.0:
            lo = s
        else:
            hi = s
        sn = s - (x - wall) / v if v != 0.0 else 0.5 * (lo + hi)
        if not lo < sn < hi:
            sn = 0.5 * (lo + hi)
        if abs(sn - s) <= ROOT_XTOL * (1.0 + abs(s)) or hi - lo <= ROOT_XTOL * (1.0 + hi):
            return sn
        s = sn
    return s


@kernel
def _piece(s_prev, x_prev, s_c, x_c, th0, c1, c2, P):
    """Contact on the monotone piece ``[s_prev, s_c]``: ``(s, wall)`` or ``(s_c, -1)``."""
    upper, lower = P[P_DELTA], -P[N_PARAMS + P_DELTA]
    if x_c > x_prev and x_c >= upper:
        if x_prev >= upper:
            return s_prev, 0
        return _root(s_prev, s_c, upper, 1.0, th0, c1, c2, P), 0
    if x_c < x_prev and x_c <= lower:
        if x_prev <= lower:
            return s_prev, 1
        return _root(s_prev, s_c, lower, -1.0, th0, c1, c2, P), 1
    return s_c, -1


@kernel
def _bound(k, lo, h, th0, gamma0, amp, P):
    """Bound of ``|x^(k)|`` on ``[lo, lo + h]`` of the flight fitted by ``_fit``.

    ``x^(k) = Im(e^{i wd s} C(s))`` with ``C(s) = aq beta^k e^{i(th0 + k pi/2 + (beta - wd) s)}
    + amp e^{-zeta s} e^{i(gamma0 + k rho)}`` (``e^{i rho} = -zeta + i wd``: each derivative of
    the free part turns it by ``rho`` with unit gain). ``|C(lo)|`` is exact, and ``C`` moves by
    at most ``(|aq| beta^k |beta - wd| + zeta amp e^{-zeta lo}) h`` on the bracket. Near
    resonance the forced and free parts nearly cancel, and this bound stays near ``|x^(k)|``
    where the sum of their amplitudes would be many times larger.
    """
    zeta, wd, aq, beta = P[P_ZETA], P[P_OMEGA], P[P_AQ], P[P_BETA]
    f = aq * beta ** k
    g = amp * math.exp(-zeta * lo)
    rho = math.atan2(wd, -zeta)
    delta = (th0 + beta * lo + 0.5 * k * math.pi) - (gamma0 + wd * lo + k * rho)
    c_lo = math.sqrt(max(f * f + g * g + 2.0 * f * g * math.cos(delta), 0.0))
    return c_lo + (abs(f) * abs(beta - wd) + zeta * g) * h


@kernel
def _first_contact(t0, x0, v0, length, P, stack, res):
    """First contact in ``(0, length]`` of the flight from ``(t0, x0, v0)`` with either wall.

    Writes ``res = (s, wall, margin)``: the flight time to the contact (``length`` if none),
    the wall (0 upper, 1 lower, -1 none) and the smallest distance to the wall it faces of an
    interior extremum before the contact (``inf`` if none). See the module docstring.
    """
    th0, c1, c2 = _fit(t0, x0, v0, P)
    wd, beta = P[P_OMEGA], P[P_BETA]
    upper, lower = P[P_DELTA], -P[N_PARAMS + P_DELTA]
    amp = math.hypot(c1, c2)              # amplitude of every derivative of the free part
    gamma0 = math.atan2(c1, c2)           # free part: amp e^{-zeta s} sin(wd s + gamma0)
    n0 = max(MIN_BRACKETS, int(math.ceil(length * max(beta, wd) / PHASE_STEP)))
    min_h = MIN_STEP * max(1.0, length)
    s_prev, x_prev = 0.0, x0
    margin = np.inf
    for k in range(n0):
        stack[0, 0] = length * k / n0
        stack[0, 1] = length * (k + 1) / n0 if k + 1 < n0 else length
        top = 1
        while top > 0:
            top -= 1
            lo = stack[top, 0]
            hi = stack[top, 1]
            h = hi - lo
            xl, vl, al, jl = _eval(lo, th0, c1, c2, P)
            xh, vh, ah, jh = _eval(hi, th0, c1, c2, P)
            m2 = _bound(2, lo, h, th0, gamma0, amp, P)    # of |x''| on [lo, hi]
            m3 = _bound(3, lo, h, th0, gamma0, amp, P)    # of |x'''| on [lo, hi]
            if vl * vh > 0.0 and abs(vl) + abs(vh) > m2 * h:
                continue                          # x' keeps its sign: no critical point
            sliver = False
            if al * ah > 0.0 and abs(al) + abs(ah) > m3 * h:
                # x' monotone: one zero in (lo, hi] exactly when it changes sign there (a zero
                # at lo is the previous bracket's, or the flight's start)
                if not (vl * vh < 0.0 or (vh == 0.0 and vl != 0.0)):
                    continue
                a_, b_ = lo, hi
                s_c = 0.5 * (lo + hi)
                for _ in range(ROOT_MAXIT):
                    xs, vs, as_, js = _eval(s_c, th0, c1, c2, P)
                    if vs * vl > 0.0:
                        a_ = s_c
                    else:
                        b_ = s_c
                    sn = s_c - vs / as_ if as_ != 0.0 else 0.5 * (a_ + b_)
                    if not a_ < sn < b_:
                        sn = 0.5 * (a_ + b_)
                    if (abs(sn - s_c) <= ROOT_XTOL * (1.0 + abs(s_c))
                            or b_ - a_ <= ROOT_XTOL * (1.0 + b_)):
                        s_c = sn
                        break
                    s_c = sn
            elif h <= min_h or top + 2 > stack.shape[0]:
                s_c = 0.5 * (lo + hi)             # flat sliver: one critical point
                sliver = True
            else:
                mid = 0.5 * (lo + hi)
                stack[top, 0] = mid
                stack[top, 1] = hi
                stack[top + 1, 0] = lo
                stack[top + 1, 1] = mid
                top += 2
                continue
            if s_prev == 0.0 and s_c <= min_h:
                # a zero of x' at the flight's start made of round-off (x' = -0 after a
                # plastic impact): x has not moved, the next piece decides
                continue
            x_c, v_c, a_c, j_c = _eval(s_c, th0, c1, c2, P)
            s_hit, wall = _piece(s_prev, x_prev, s_c, x_c, th0, c1, c2, P)
            if wall >= 0:
                res[0] = s_hit
                res[1] = wall
                res[2] = margin
                return
            if sliver:
                margin = min(margin, upper - x_c, x_c - lower)
            elif a_c < 0.0:
                margin = min(margin, upper - x_c)
            else:
                margin = min(margin, x_c - lower)
            s_prev, x_prev = s_c, x_c
    x_end = _eval(length, th0, c1, c2, P)[0]
    s_hit, wall = _piece(s_prev, x_prev, length, x_end, th0, c1, c2, P)
    res[0] = s_hit
    res[1] = wall
    res[2] = margin


@kernel
def _propagate(M, s, zeta, wd):
    """``M <- P(s) M`` with ``P(s)`` the free propagator of ``y'' + 2 zeta y' + y = 0``."""
    e = math.exp(-zeta * s)
    c = math.cos(wd * s)
    sn = math.sin(wd * s) / wd
    p11, p12, p21, p22 = e * (c + zeta * sn), e * sn, -e * sn, e * (c - zeta * sn)
    m11, m12, m21, m22 = M[0, 0], M[0, 1], M[1, 0], M[1, 1]
    M[0, 0] = p11 * m11 + p12 * m21
    M[0, 1] = p11 * m12 + p12 * m22
    M[1, 0] = p21 * m11 + p22 * m21
    M[1, 1] = p21 * m12 + p22 * m22


@kernel
def advance(t0, t1, x, v, P, M, ev_t, ev_w, ev_u, stack, out):
    """The exact flow from ``(t0, x, v)`` to ``t1`` with impacts at either wall.

    ``M`` (2x2) is multiplied in place by the flow's Jacobian (flight propagators and impact
    saltations). Impacts go to ``ev_t`` (instant), ``ev_w`` (wall), ``ev_u`` (approach
    velocity, lab frame). ``out = (x, v, margin, n_impacts, status)``; status ``CHATTER`` when
    an impact is slower than ``CHATTER_SPEED`` or the buffers are full.
    """
    zeta, wd, amp, beta = P[P_ZETA], P[P_OMEGA], P[P_A], P[P_BETA]
    res = np.empty(3)
    t = t0
    n_ev = 0
    margin = np.inf
    status = OK
    while True:
        length = t1 - t
        if length <= 0.0:
            break
        _first_contact(t, x, v, length, P, stack, res)
        s = res[0]
        wall = int(res[1])
        margin = min(margin, res[2])
        th0, c1, c2 = _fit(t, x, v, P)
        xs, u, a_s, j_s = _eval(s, th0, c1, c2, P)
        _propagate(M, s, zeta, wd)
        if wall < 0:
            x, v = xs, u
            break
        if abs(u) < CHATTER_SPEED or n_ev >= ev_t.size:
            status = CHATTER
            break
        half = 0 if wall == 0 else N_PARAMS
        eps = P[half + P_EPS]
        law_a = P[half + P_LAW_A]
        pos = P[P_DELTA] if wall == 0 else -P[N_PARAMS + P_DELTA]
        t = t + s
        f = amp * math.sin(beta * t)
        a_minus = f - 2.0 * zeta * u - pos
        v_plus = rebound_velocity(eps, u, law_a)      # the impact law (vibroimpact.model)
        a_plus = f - 2.0 * zeta * v_plus - pos
        # the saltation matrix [[R / u, 0], [(a_+ - R' a_-) / u, R']] times M (Newton's law:
        # R / u = R' = -eps, the same bits as -eps written in place)
        ratio = rebound_ratio(eps, u, law_a)
        slope = rebound_derivative(eps, u, law_a)
        c21 = (a_plus - slope * a_minus) / u
        m11, m12 = M[0, 0], M[0, 1]
        M[1, 0] = c21 * m11 + slope * M[1, 0]
        M[1, 1] = c21 * m12 + slope * M[1, 1]
        M[0, 0] = ratio * m11
        M[0, 1] = ratio * m12
        ev_t[n_ev] = t
        ev_w[n_ev] = wall
        ev_u[n_ev] = u
        n_ev += 1
        x = pos
        v = v_plus
    out[0] = x
    out[1] = v
    out[2] = margin
    out[3] = n_ev
    out[4] = status


# --- Python layer ------------------------------------------------------------------------------
class _Flow:
    """The exact flow of one model over whole forcing periods, with its buffers."""

    def __init__(self, model, n):
        zeta, beta = model.zeta, model.beta
        two = model.n_walls == 2
        # The simulator's vector, with both halves whatever the walls (one wall: the wall below
        # at -inf with restitution and law 0, which no flight reaches); CPython's math.hypot in
        # the harmonic gain, as this solver has always had it (see parameters). The step is 1:
        # the flow is exact between impacts and samples no force record, so the slots of the
        # step (P_DT, P_INV_DT, P_BH_*, P_M*, P_COS_BH, P_SIN_BH) are filled but never read,
        # and a unit step keeps them finite.
        self.P = parameters(zeta, 1.0, model.amplitude, beta,
                            math.hypot(1.0 - beta * beta, 2.0 * zeta * beta), model.eps,
                            model.delta, model.walls[0].law.a, 2,
                            model.eps_lower if two else 0.0, model.lower,
                            model.walls[1].law.a if two else 0.0)
        self.upper, self.lower = model.delta, model.lower
        self.tf = 2.0 * math.pi / model.beta
        cap = MAX_IMPACTS_PER_PERIOD * n
        self.ev_t = np.empty(cap)
        self.ev_w = np.empty(cap, dtype=np.int64)
        self.ev_u = np.empty(cap)
        self.stack = np.empty((STACK, 2))
        self.out = np.empty(5)

    def run(self, t0, t1, X):
        """``(X(t1), M, margin, impacts (t, wall, u), status)`` from ``X`` at ``t0``."""
        M = np.eye(2)
        advance(t0, t1, float(X[0]), float(X[1]), self.P, M, self.ev_t, self.ev_w, self.ev_u,
                self.stack, self.out)
        k = int(self.out[3])
        events = (self.ev_t[:k].copy(), self.ev_w[:k].copy(), self.ev_u[:k].copy())
        return self.out[:2].copy(), M, float(self.out[2]), events, int(self.out[4])


@dataclass(frozen=True, eq=False)
class PeriodicMotion:
    """One periodic motion of period ``n`` forcing cycles under ``amplitude sin(beta tau)``.

    Attributes
    ----------
    model : vibroimpact.model.Model
        The oscillator, its walls and its force.
    n : int
        Forcing cycles per period (the smallest: a motion of a shorter period is not an n one).
    state : ndarray, shape (2,)
        ``(x, x')`` at phase 0 (``tau = 0``, right-continuous: after an impact at that
        instant), of the rotation whose earliest impact phase falls in its first cycle (the
        closed-form solver's ``tau0`` convention).
    phase0_states : ndarray, shape (n, 2)
        ``(x, x')`` at ``tau = k 2 pi / beta``, ``k = 0 .. n-1`` (``phase0_states[0] = state``).
    impact_time : ndarray, shape (m,)
        Instants of the impacts of one period, ``0 <= tau < 2 pi n / beta``, increasing.
    impact_wall : ndarray of int8, shape (m,)
        Wall of each impact: 0 the wall at ``delta``, 1 the wall at ``delta - gap``.
    impact_velocity : ndarray, shape (m,)
        Speed of approach ``|x'(tau_j-)| > 0`` of each impact.
    counts : tuple of int
        ``(m_upper, m_lower)``: impacts per period on each wall.
    monodromy : ndarray, shape (2, 2)
        Jacobian of the flow over one period from phase 0.
    multipliers : ndarray, complex, shape (2,)
        Floquet multipliers (its eigenvalues), largest modulus first.
    lam, S : float
        ``max|mu|^(1/m)`` (the paper's lambda, eq. 20; ``max|mu|`` without impacts) and the
        degree of stability ``100 (1 - lam)`` in percent (eq. 24).
    stable : bool
        ``max|mu| < 1``.
    margin : float
        Smallest distance to the wall it faces of an interior extremum of any flight (``inf``
        if none).
    admissible, grazing : bool
        ``margin >= -ADMISSIBLE_TOL`` (no flight crosses a wall); ``|margin| <= GRAZING_TOL``
        (a flight touches a wall tangentially: the edge of the motion's existence domain).
    residual : float
        ``|Phi_n(X) - X|`` (max norm) at the Newton section when Newton stopped.
    """

    model: Model
    n: int
    state: np.ndarray
    phase0_states: np.ndarray
    impact_time: np.ndarray
    impact_wall: np.ndarray
    impact_velocity: np.ndarray
    monodromy: np.ndarray
    multipliers: np.ndarray
    lam: float
    S: float
    stable: bool
    margin: float
    admissible: bool
    grazing: bool
    residual: float

    @property
    def counts(self):
        """``(m_upper, m_lower)``: impacts per period on each wall."""
        return (int(np.sum(self.impact_wall == 0)), int(np.sum(self.impact_wall == 1)))

    @property
    def m(self):
        """Impacts per period on all walls."""
        return int(self.impact_wall.size)

    @property
    def name(self):
        """``"(m_upper,m_lower)/n"``, e.g. ``"(1,1)/1"``."""
        mu, ml = self.counts
        return f"({mu},{ml})/{self.n}"

    @property
    def period(self):
        return 2.0 * math.pi * self.n / self.model.beta

    def state_at(self, tau):
        """``(x, x')`` of the motion at the instants ``tau`` (any reals; right-continuous:
        just after an impact at that instant), shape ``tau.shape + (2,)``."""
        tau = np.asarray(tau, dtype=float)
        flow = _Flow(self.model, self.n)
        out = np.empty(tau.shape + (2,))
        for idx in np.ndindex(tau.shape):
            out[idx] = flow.run(0.0, float(np.mod(tau[idx], self.period)), self.state)[0]
        return out

    @property
    def impact_phase(self):
        """Phase ``beta tau mod 2 pi`` of each impact (radians)."""
        return np.mod(self.model.beta * self.impact_time, 2.0 * math.pi)


@dataclass(frozen=True)
class SkippedSeed:
    """A seed that gave no motion: ``kind`` is ``"sticking"`` (the settled start rests on a
    wall), ``"chatter"`` (the flow from it chatters: not followed), ``"not_periodic"`` (the
    settled start repeats after none of the n), ``"not_converged"`` or ``"shorter_period"``;
    ``reason`` says more; ``n`` is None when the seed was dropped for every n."""

    seed: tuple
    n: int
    kind: str
    reason: str


@dataclass(frozen=True)
class MotionSet:
    """The motions found (sorted by name, then state) and the seeds that gave none.

    Iterating, ``len`` and indexing go over ``motions``.
    """

    motions: tuple
    skipped: tuple

    def __iter__(self):
        return iter(self.motions)

    def __len__(self):
        return len(self.motions)

    def __getitem__(self, i):
        return self.motions[i]


def _scale(X):
    return 1.0 + float(np.max(np.abs(X)))


def _section(events, tf):
    """A phase in the middle of the largest gap between the impacts' phases (0 if none)."""
    if events[0].size == 0:
        return 0.0
    ph = np.sort(np.mod(events[0], tf))
    gaps = np.diff(np.append(ph, ph[0] + tf))
    k = int(np.argmax(gaps))
    return float(np.mod(ph[k] + 0.5 * gaps[k], tf))


def _newton(flow, X0, n):
    """Newton on ``Phi_n(X) - X`` at the section ``theta``: ``(theta, X_theta, residual, None,
    "")``, or ``(None, None, nan, kind, why)`` (kinds of `SkippedSeed`)."""
    z = n * flow.tf
    _, _, _, events, status = flow.run(0.0, z, X0)
    if status != OK:
        return None, None, np.nan, "chatter", "the flow from the seed chatters"
    theta = _section(events, flow.tf)
    X, _, _, _, status = flow.run(0.0, theta, X0)
    if status != OK:
        return None, None, np.nan, "chatter", "the flow from the seed chatters"
    converged = False
    X_prev, res_prev = X, np.inf
    for _ in range(NEWTON_MAXIT):
        Y, M, _, _, status = flow.run(theta, theta + z, X)
        if status != OK:
            return None, None, np.nan, "chatter", "Newton reached a chattering flow"
        F = Y - X
        res = float(np.max(np.abs(F)))
        if converged and (res >= NEWTON_POLISH * res_prev or res == 0.0):
            if res < res_prev:
                return theta, X, res, None, ""
            return theta, X_prev, res_prev, None, ""
        if res <= NEWTON_TOL * _scale(X):
            converged = True
        try:
            dX = np.linalg.solve(M - np.eye(2), -F)
        except np.linalg.LinAlgError:
            return None, None, np.nan, "not_converged", "singular Jacobian (a multiplier 1)"
        X_prev, res_prev = X, res
        if converged:
            X = X + dX
            continue
        step = 1.0
        for _h in range(NEWTON_HALVINGS):
            Xn = X + step * dX
            Yn, _, _, _, st = flow.run(theta, theta + z, Xn)
            inside = flow.lower <= Xn[0] <= flow.upper
            if inside and st == OK and float(np.max(np.abs(Yn - Xn))) < res:
                break
            step *= 0.5
        else:
            return None, None, np.nan, "not_converged", "no step reduces the residual"
        X = Xn
    if converged:
        return theta, X_prev, res_prev, None, ""
    return None, None, np.nan, "not_converged", f"no convergence in {NEWTON_MAXIT} iterations"


def _motion(flow, model, n, theta, X_theta, residual):
    """``(motion, None, "")`` at phase 0 in its canonical rotation, or ``(None, kind, why)``."""
    tf = flow.tf
    z = n * tf
    # the phase-0 states after the section, and the period's impacts
    states = []
    X = X_theta
    t = theta
    for k in range(1, n + 1):
        X, _, _, _, _ = flow.run(t, k * tf, X)
        t = k * tf
        states.append(X)
    states = np.array(states)
    for d in range(1, n):
        if n % d == 0 and np.max(np.abs(states[d] - states[0])) <= SAME_TOL * _scale(states[0]):
            return None, "shorter_period", f"the motion has period {d}"
    X0 = states[0]
    _, _, _, events, _ = flow.run(0.0, z, X0)
    if events[0].size:
        first = int(np.argmin(np.mod(events[0], tf)))
        rot = int(events[0][first] // tf)
    else:
        rot = 0
    X0 = states[rot]
    Y, M, margin, events, status = flow.run(0.0, z, X0)
    if status != OK:
        return None, "chatter", "the motion chatters"
    mult = np.linalg.eigvals(M).astype(complex)
    mult = mult[np.argsort(-np.abs(mult), kind="stable")]
    m = events[0].size
    big = float(np.abs(mult[0]))
    lam = big ** (1.0 / m) if m else big
    return PeriodicMotion(
        model=model, n=n, state=X0, phase0_states=np.roll(states, -rot, axis=0),
        impact_time=events[0], impact_wall=events[1].astype(np.int8),
        impact_velocity=np.abs(events[2]), monodromy=M, multipliers=mult, lam=lam,
        S=100.0 * (1.0 - lam), stable=bool(big < 1.0), margin=margin,
        admissible=bool(margin >= -ADMISSIBLE_TOL), grazing=bool(abs(margin) <= GRAZING_TOL),
        residual=residual), None, ""


def default_starts(model, k=DEFAULT_STARTS, speed=4.0, reach=4.0):
    """A ``k x k`` grid of starts: ``x`` inside the walls (at most ``reach`` below the upper
    wall), ``x'`` in ``[-speed, speed]``."""
    low = max(model.lower, model.delta - reach)
    xs = low + (model.delta - low) * (np.arange(k) + 0.5) / k
    vs = np.linspace(-speed, speed, k)
    return np.array([(x, v) for x in xs for v in vs])


def settle(model, starts, periods=SETTLE_PERIODS):
    """Run each start for ``periods`` forcing periods with the exact simulator
    (:func:`vibroimpact.impact.simulate.simulate_model`: chatter and sticking included);
    ``(states at phase 0, resting)`` with ``resting`` true where the mass rests on a wall in
    the last period."""
    from vibroimpact.impact.simulate import simulate_model

    tf = 2.0 * math.pi / model.beta
    t_end = periods * tf
    out = np.empty((len(starts), 2))
    resting = np.zeros(len(starts), dtype=bool)
    for i, (x0, v0) in enumerate(starts):
        r = simulate_model(model, None, dt=tf / SETTLE_SAMPLES, x0=float(x0), v0=float(v0),
                           t_end=t_end)
        out[i] = r.x_end, r.v_end
        resting[i] = bool(r.stuck_end) or bool(np.any(r.stick_end > t_end - tf))
    return out, resting


def _returns(model, X, n_max):
    """``|X_p - X|`` (max norm) after ``p = 1 .. n_max`` periods of the exact flow from the
    phase-0 state ``X`` (``inf`` from a chatter on)."""
    flow = _Flow(model, 1)
    out = np.full(n_max, np.inf)
    Y = X
    for p in range(n_max):
        Y, _, _, _, status = flow.run(0.0, flow.tf, Y)
        if status != OK:
            break
        out[p] = np.max(np.abs(Y - X))
    return out


def _settled_seeds(model, starts, periods, ns, skipped):
    """Newton seeds from ``starts``: each run by the simulator until it repeats after one of
    the ``ns`` periods (within ``RETURN_TOL``), in rounds of ``periods`` forcing periods, at
    most ``SETTLE_ROUNDS``. Returns the seeds and, for each, the set of ``n`` it repeats
    after; appends to ``skipped`` the starts that rest on a wall, chatter or never repeat."""
    X = np.asarray(starts, dtype=float)
    pending = np.arange(len(X))
    seeds, periods_of = [], []
    for rnd in range(SETTLE_ROUNDS):
        X_p, resting = settle(model, X[pending], periods)
        X[pending] = X_p
        still = []
        for i, rest in zip(pending, resting):
            seed = (float(X[i, 0]), float(X[i, 1]))
            if rest:
                skipped.append(SkippedSeed(seed, None, "sticking",
                                           "the settled start rests on a wall"))
                continue
            r = _returns(model, X[i], max(ns))
            if not np.isfinite(r[-1]):
                skipped.append(SkippedSeed(seed, None, "chatter",
                                           "the flow from the settled start chatters"))
                continue
            ok = {k for k in ns if r[k - 1] <= RETURN_TOL * _scale(X[i])}
            if ok:
                seeds.append(X[i].copy())
                periods_of.append(ok)
            elif rnd + 1 < SETTLE_ROUNDS:
                still.append(i)
            else:
                skipped.append(SkippedSeed(seed, None, "not_periodic",
                                           f"no return within {RETURN_TOL} after n = {ns} "
                                           f"periods in {SETTLE_ROUNDS * periods} periods"))
        pending = np.array(still, dtype=int)
        if pending.size == 0:
            break
    return seeds, periods_of


def _known(X, n, found):
    """Whether the settled state ``X`` lies on a motion found already whose period divides
    ``n`` (within ``SETTLED_TOL``)."""
    tol = SETTLED_TOL * _scale(X)
    return any(n % mo.n == 0 and np.min(np.max(np.abs(mo.phase0_states - X), axis=1)) <= tol
               for mo in found)


def _near(X, states):
    tol = SETTLED_TOL * _scale(X)
    return any(np.max(np.abs(Y - X)) <= tol for Y in states)


def _same(a, b):
    if a.n != b.n:
        return False
    tol = SAME_TOL * _scale(a.state)
    return bool(np.any(np.max(np.abs(b.phase0_states - a.state), axis=1) <= tol))


def periodic_motions(model, n, seeds=None, *, starts=None, settle_periods=SETTLE_PERIODS):
    """Every periodic motion of period ``n`` forcing cycles reached from the seeds.

    Parameters
    ----------
    model : vibroimpact.model.Model
        One or two walls, force ``amplitude sin(beta tau)`` (no noise).
    n : int or sequence of int
        Forcing cycles per period (each >= 1); a sequence solves for each.
    seeds : array_like, shape (k, 2), optional
        States ``(x, x')`` at phase 0 to start Newton from. Default: settled starts.
    starts : array_like, shape (k, 2), optional
        Starts at phase 0 run by the exact simulator (chatter and sticking included) whose
        settled states seed Newton, when ``seeds`` is None. Default :func:`default_starts`.
    settle_periods : int
        Forcing periods of a settling round (>= 1): a start seeds Newton for the n after
        which it repeats (within ``RETURN_TOL``), else it runs another round (at most
        ``SETTLE_ROUNDS``).

    Returns
    -------
    MotionSet
        ``motions``: `PeriodicMotion` s, each once (sorted by n, name, state); ``skipped``:
        a `SkippedSeed` for each seed that gave none (chatter and sticking are not handled:
        see the module docstring).

    Notes
    -----
    docs/model.md, section 8.8: the flow, the saltation matrix, the Newton section and the
    determinant ``prod eps_w^2 exp(-2 zeta z)`` of the monodromy (Newton's law; the module
    docstring gives it for any law).

    Examples
    --------
    A clearance: the paper's oscillator with a second wall 2 below the first, under
    sin(tau / 1.1); the motions of one forcing period reached from the settled seeds:

    >>> from vibroimpact import periodic_motions
    >>> from vibroimpact.model import Model
    >>> found = periodic_motions(Model.paper(0.05, 0.5, 1.0, 1.0, 1 / 1.1, gap=2.0), n=1)
    >>> [(motion.name, motion.stable) for motion in found]
    [('(1,1)/1', True)]
    """
    if not isinstance(model, Model):
        raise ValueError(f"model must be a vibroimpact.model.Model, got {type(model).__name__}")
    ns = [n] if np.ndim(n) == 0 else list(n)
    if not ns:
        raise ValueError("n must be a positive integer or a non-empty sequence of them")
    ns = [_checks.integer("n", k, low=1) for k in ns]
    settle_periods = _checks.integer("settle_periods", settle_periods, low=1)
    found, skipped = [], []
    if seeds is None:
        starts = default_starts(model) if starts is None else _states("starts", starts, model)
        seeds, periods_of = _settled_seeds(model, starts, settle_periods, ns, skipped)
    else:
        seeds = _states("seeds", seeds, model)
        periods_of = [set(ns)] * len(seeds)
    for nn in sorted(set(ns)):
        flow = _Flow(model, nn)
        failed = []
        for X0, periods in zip(seeds, periods_of):
            if nn not in periods or _known(X0, nn, found) or _near(X0, failed):
                continue             # not repeating after nn periods, or tried already
            theta, X, res, kind, why = _newton(flow, X0, nn)
            if kind is None:
                motion, kind, why = _motion(flow, model, nn, theta, X, res)
            if kind is not None:
                skipped.append(SkippedSeed((float(X0[0]), float(X0[1])), nn, kind, why))
                failed.append(X0)
            elif not any(_same(motion, other) for other in found):
                found.append(motion)
    found.sort(key=lambda mo: (mo.n, mo.name, tuple(mo.state)))
    return MotionSet(tuple(found), tuple(skipped))


def _states(name, value, model):
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] == 0 or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a non-empty array of finite (x, x') pairs, "
                         f"shape (k, 2), got shape {arr.shape}")
    outside = (arr[:, 0] > model.delta) | (arr[:, 0] < model.lower)
    if np.any(outside):
        raise ValueError(f"{name} must lie between the walls ({model.lower} <= x <= "
                         f"{model.delta}), got x = {arr[outside, 0][0]!r}")
    return arr
