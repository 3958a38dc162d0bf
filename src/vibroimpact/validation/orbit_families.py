"""Stress families of periodic impact motions near singular configurations.

Three families of parameter points are constructed next to the places where the orbit solver
(:func:`vibroimpact.periodic_orbits`) is hardest to get right, and its answer at each point is
compared orbit by orbit with an independent solver written here:

``orbit_fold``
    A saddle-node (fold, ``mu -> +1``) of (1/1), (1/2) or (2/1) motions: two orbits are born at
    the fold and are ``~ sqrt(distance)`` apart next to it. Points at log-uniform distances
    ``1e-10 .. 1e-2`` in ``delta`` from the fold, on the side where the pair exists.
``orbit_period_doubling``
    A (1/1) motion whose multiplier crosses ``mu = -1``: points at the same distances on both
    sides. On one side a (2/2) motion is born from the doubled (1/1) one (intervals
    ``z/2 +- O(sqrt(distance))``); the (2/2) sets are compared too.
``orbit_grazing``
    A (1/1) (sometimes (1/2)) motion whose flight touches the wall tangentially (the edge of its
    admissibility, paper eq. 13): just on the admissible side it must be returned, just on the
    other side it must not be.

The independent solver shares no code with ``vibroimpact.orbits`` or
``vibroimpact.orbits.kernels`` (nothing of the package is imported but the function under test
and the impact law, :func:`vibroimpact.model.rebound_velocity`, the physics both solve):

- flight: the textbook closed form ``x = q sin(beta tau - phi) + exp(-zeta s)(c1 cos wd s +
  c2 sin wd s)``;
- (1/n) motions: with ``z = 2 pi n / beta`` the forced part returns to itself and eqs. (10)-(11)
  reduce to ``sin(psi_0 + theta) = kappa`` in the impact phase ``psi_0 = beta tau_0 - phi``,
  solved in closed form in extended precision (``numpy.longdouble``, 64-bit mantissa on x86);
  the folds are ``|kappa| = 1``, i.e. ``delta = +- R/|K|`` in closed form;
- (2/n) motions: for a fixed first interval ``z_1`` the four equations are linear in
  ``(sin psi_0, cos psi_0, u_0, u_1)`` with right-hand side proportional to ``delta``; their
  solution ``delta w(z_1)`` lies on the unit circle when ``|delta| = D(z_1) = 1/|w_SC(z_1)|``.
  So every (2/n) motion at ``delta`` is a root of the scalar function ``D(z_1) - |delta|`` on
  ``0 < z_1 <= z/2`` (each motion once: its shorter-first rotation), found exactly between the
  critical points of ``D`` (where it is monotone); the folds in ``delta`` are the local extrema
  of ``D``, and for even n the removable singularity of ``w`` at ``z_1 = z/2`` is where a
  (2/2) motion branches off the doubled (1/1) motion (``D(z/2)`` is the period-doubling
  ``delta``). The package instead scans ``z_1`` at fixed ``delta`` and polishes by Newton;
  near a fold its scan function has a double root;
- multipliers: the one-period Jacobian ``T`` by complex-step differentiation of the impact map
  (Newton on the landing time in complex longdouble arithmetic), not by an analytic formula;
- admissibility: dense sampling of every flight, each velocity sign change refined by
  ``scipy.optimize.brentq``;
- second methods for any disagreement, whose findings go into the failure message: scipy's
  DOP853 with a wall-crossing event from the disputed orbit's first impact (does it repeat?),
  and a 40-digit mpmath Newton from the disputed orbit (where does it converge to, and what
  are the multipliers there?).

Comparison: orbits are paired by an optimal assignment on their impacts; an admissible
reference orbit without a partner is *missed*, a returned orbit without one is *spurious*, a
paired orbit's multipliers must agree to a tolerance that grows like ``1/sqrt(d)`` at distance
``d`` from the fold or period doubling (see :func:`mu_tolerance` and the comment above it), and
``det T = eps^(2m) exp(-2 zeta z)`` must hold to 1e-10 for every returned orbit.

A failure of the independent solver (no singular point found in the draws, a self-check of its
own orbit failing, a returned orbit that mpmath confirms and the reference lacks) is not a
failure of the package: the case is skipped and counted in ``report.extra["skipped"]``.
Every failing case is kept as a dict that :func:`check_case` re-runs.

The extended precision needs a 64-bit-mantissa ``numpy.longdouble`` (x86-64 Linux); where
``longdouble`` is plain float64 the reference loses ~3 digits next to the singular points.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, linear_sum_assignment, minimize_scalar

from vibroimpact.model import rebound_velocity
from vibroimpact.validation.report import FamilyReport

__all__ = ["FAMILIES", "run_orbit_family", "check_case", "reference_orbits", "RefOrbit",
           "fold_points", "period_doubling_points", "grazing_points", "fold_deltas_m1",
           "compare_orbits", "Outcome", "mu_tolerance", "displacement_scale", "mp_orbit",
           "dop853_return", "flight_state"]

FAMILIES = ("orbit_fold", "orbit_period_doubling", "orbit_grazing")

_L = np.longdouble
_PI_L = _L("3.14159265358979323846264338327950288")

# Parameter ranges of the draws.
ZETA_RANGE = (0.01, 0.2)
EPS_RANGE = (0.3, 0.9)
INV_BETA_RANGE = (0.3, 3.0)
DISTANCE_RANGE = (1e-10, 1e-2)     # log-uniform distance in delta from the singular point

# Tolerance on the multipliers. The error of one orbit is |mu - mu_ind| / max(1, |mu_ind|) (the
# relative error of the large multipliers of strongly unstable orbits, the absolute one of those
# near the unit circle). The report records it divided by the orbit's tolerance, so that the
# family's tolerance is 1:
#     tol = MU_TOL_FLOOR + MU_TOL_RESIDUAL S / (sqrt(d) min(1, u_min))   (fold, period doubling)
#     tol = MU_TOL_FLOOR                                                (grazing)
# with d the distance in delta from the singular point, u_min the orbit's slowest impact and
# S = 1 + |delta| + q (1 + beta) the displacement scale (wall offset, forced amplitude and
# velocity amplitude: 2 .. 100 here, large next to resonance with small zeta).
# Why this form:
# - an orbit that is a simple root of well-conditioned equations is found by both solvers to
#   round-off (measured: <= 5e-14 over the grazing family, where nothing degenerates; the
#   reference works with a 64-bit mantissa and agrees with 40-digit mpmath to ~1e-11 or better);
# - at a fold at distance d the two orbits are a double root: a residual r left in the
#   equations moves an orbit by ~ r/|mu - 1| ~ r/sqrt(d) along its branch (the closed form's
#   d(arcsin kappa)/d kappa = 1/sqrt(1 - kappa^2)), and mu follows at a rate ~1/u_min (the
#   impact map's derivatives carry 1/u of the arrival velocity, so a slow impact makes it stiff);
# - next to a period doubling the (2/2) motion is a pitchfork branch e ~ sqrt(d) from the
#   doubled (1/1) one with |mu - 1| ~ d: the residual moves it by ~ r/d, but mu varies along the
#   branch only like e (the second derivative of the twice-iterated map vanishes at the
#   bifurcation), so again |dmu| ~ r/sqrt(d), times the 1/u_min stiffness;
# - r: float64 round-off for a closed form (the package's (1/n) motions), but for a Newton polish
#   the residual at which it stops, 1e-12 S in the package (its documented Newton tolerance).
#   That is MU_TOL_RESIDUAL S: errors within it are the stated accuracy of the solver, not a bug.
# Measured over ~3000 orbits, err sqrt(d) min(1, u_min) / S <= 1e-15 for the (1/n) closed form
# (e.g. err = 1.2e-7 at d = 1.5e-10 with u_min = 3e-5: float64 round-off, the reference there
# agrees with mpmath to 2e-11), <= 1e-15 at (2/1) folds and <= 4e-13 for the (2/2) motions next
# to a period doubling, where the package's Newton stops with the orbit up to 1.6e-5 off (a
# 1e-12 residual over |mu - 1| ~ 1e-7; see MATCH_TOL).
# A wrong branch, a duplicate or a mis-polished orbit next to a fold is off by ~ sqrt(d)/u_min in
# mu (the pair's multipliers straddle +1 by that much), >= ~100 times this tolerance.
MU_TOL_FLOOR = 1e-9
MU_TOL_RESIDUAL = 1e-12
# det T = eps^(2m) exp(-2 zeta z) (phase-space contraction), relative.
DET_RTOL = 1e-10
# Two orbits are paired when their impacts (phase mod 2 pi/beta over the period, velocity over
# the velocity scale) are this close, by an optimal assignment. Positions next to a fold are
# sqrt(d) >= 1e-5 apart while their errors are ~1e-11, and the package's (2/2) orbit next to a
# period doubling is up to ~1.5e-5 off (see above): 1e-4 pairs the right orbits and the
# assignment keeps two orbits of a fold pair from sharing one partner.
MATCH_TOL = 1e-4
# Grazing: an orbit whose independent margin is within this band of zero may be returned or
# not (the package's documented admissibility tolerance is 1e-12; the reference margin is exact
# to ~1e-15); outside the band its presence must agree.
GRAZING_BAND = 1e-11
# Complex-step size for the multipliers (no subtraction, so it can be tiny).
_CS_H = 1e-30


# ------------------------------------------------------------------------------------------
# the independent solver

@dataclass(frozen=True)
class RefOrbit:
    """One periodic motion found by the independent solver.

    Attributes
    ----------
    m, n : int
        Impacts per period and forcing cycles per period.
    taus : ndarray, shape (m,)
        Impact instants over one period, increasing, ``taus[0]`` in ``[0, 2 pi/beta)``.
    us : ndarray, shape (m,)
        Approach velocities ``u_j > 0``: ``us[j]`` at the impact ``taus[j]``.
    intervals : ndarray, shape (m,)
        Flight times from ``taus[j]`` to the next impact; they sum to ``z = 2 pi n/beta``.
    mu : ndarray, complex, shape (2,)
        Multipliers of the one-period Jacobian (complex step), largest modulus first.
    det : float
        ``det T`` of that Jacobian.
    margin : float
        ``delta - max x`` over the interior maxima of every flight (``inf`` if none).
    """

    m: int
    n: int
    taus: np.ndarray
    us: np.ndarray
    intervals: np.ndarray
    mu: np.ndarray
    det: float
    margin: float


def _consts(beta, zeta, dtype=float):
    """``(q, phi, wd)`` of the steady response ``q sin(beta tau - phi)``, in ``dtype``."""
    b, zt = dtype(beta), dtype(zeta)
    one = dtype(1)
    q = one / np.sqrt((one - b * b) ** 2 + (2 * zt * b) ** 2)
    phi = np.arctan2(2 * zt * b, one - b * b)
    return q, phi, np.sqrt(one - zt * zt)


def _free(s, zeta, wd):
    """Entries ``(p11, p12, p21, p22)`` of the damped free response over a time ``s``.

    ``y(s) = exp(-zeta s) [y0 cos wd s + (v0 + zeta y0)/wd sin wd s]``, differentiated.
    """
    e, c, sn = np.exp(-zeta * s), np.cos(wd * s), np.sin(wd * s) / wd
    return e * (c + zeta * sn), e * sn, -e * sn, e * (c - zeta * sn)


def flight_state(tau_a, u_a, s, beta, delta, zeta, eps, extended=False):
    """``(x, v)`` at ``tau_a + s`` of the flight leaving the wall at ``tau_a`` with ``-eps u_a``.

    Numpy ufuncs only, so it broadcasts and works on complex arguments (complex step);
    ``extended`` evaluates in longdouble (pass longdouble or clongdouble arguments).
    """
    dtype = _L if extended else float
    q, phi, wd = _consts(beta, zeta, dtype)
    beta, delta, zeta, eps = dtype(beta), dtype(delta), dtype(zeta), dtype(eps)
    psi = beta * tau_a - phi
    y0 = delta - q * np.sin(psi)                      # free part of the start state
    v0 = rebound_velocity(eps, u_a) - q * beta * np.cos(psi)
    e, c, sn = np.exp(-zeta * s), np.cos(wd * s), np.sin(wd * s)
    th = psi + beta * s
    x = q * np.sin(th) + e * (y0 * c + (v0 + zeta * y0) / wd * sn)
    v = q * beta * np.cos(th) + e * (v0 * c - (y0 + zeta * v0) / wd * sn)
    return x, v


def _flight_margin(tau_a, u_a, s_end, beta, delta, zeta, eps):
    """``delta - max x`` over the interior local maxima of one flight (``inf`` if none).

    Dense sampling (20 points per radian of the fastest of beta and wd) finds every sign change
    of the velocity from + to -; each is refined by brentq. The flight leaves the wall downward
    and lands upward, so every maximum is interior.
    """
    fast = max(beta, 1.0)
    npt = int(math.ceil(s_end * fast * 20.0)) + 16
    s = np.linspace(0.0, s_end, npt + 1)
    _, v = flight_state(tau_a, u_a, s, beta, delta, zeta, eps)
    best = -math.inf
    for k in np.flatnonzero((v[:-1] > 0.0) & (v[1:] <= 0.0)):
        if v[k + 1] == 0.0:
            sk = s[k + 1]
        else:
            sk = brentq(lambda t: flight_state(tau_a, u_a, t, beta, delta, zeta, eps)[1],
                        s[k], s[k + 1], xtol=1e-15, rtol=8.9e-16)
        if 0.0 < sk < s_end:
            best = max(best, float(flight_state(tau_a, u_a, sk, beta, delta, zeta, eps)[0]))
    return delta - best


def _monodromy(taus, us, intervals, beta, delta, zeta, eps):
    """One-period Jacobian ``T = T_m ... T_1`` of ``(tau, u) -> (tau, u)`` by complex step.

    Each factor ``T_j`` differentiates one flight's impact map at the orbit's own impact
    ``(taus[j], us[j])`` (longdouble): perturb ``tau_j`` (or ``u_j``) by ``i h`` and solve the
    landing time ``x(s) = delta`` by Newton in complex longdouble arithmetic from the real
    one; ``Im(result)/h`` is the derivative to round-off (no difference is taken). Factors are
    taken at the stored impacts, and in extended precision, because after a low-velocity
    impact ``u`` the landing (and with it ``T``) is sensitive like ``1/u``: a float64 landing
    re-solved from a rounded start biased ``T`` by ~1e-10 relative at ``u = 0.006``.
    """
    c_l = np.clongdouble
    h = _L(_CS_H)
    tmat = np.eye(2, dtype=_L)
    for j in range(len(taus)):
        tj = np.empty((2, 2), dtype=_L)
        for col, (dt, du) in enumerate(((1, 0), (0, 1))):
            t = c_l(taus[j]) + c_l(1j) * (dt * h)
            u = c_l(us[j]) + c_l(1j) * (du * h)
            s = c_l(intervals[j])
            for _ in range(12):
                x, v = flight_state(t, u, s, beta, delta, zeta, eps, extended=True)
                step = (x - _L(delta)) / v
                s = s - step
                if abs(step.real) < 1e-18 * (1 + abs(s.real)) and (
                        abs(step.imag) <= 1e-17 * abs(s.imag) or s.imag == 0):
                    break
            _, v = flight_state(t, u, s, beta, delta, zeta, eps, extended=True)
            tj[0, col] = (t + s).imag / h
            tj[1, col] = v.imag / h
        tmat = tj @ tmat
    return tmat.astype(float)


def _make_ref(m, n, taus, us, beta, delta, zeta, eps):
    """A :class:`RefOrbit` from impact instants and approach velocities (longdouble).

    Returns None when the orbit fails its own self-check (the flights must land on the wall
    at the stated instants with the stated velocities to 1e-9 of the scale): then the
    independent solver, not the package, is in doubt.
    """
    taus_l = np.asarray(taus, dtype=_L)
    us_l = np.asarray(us, dtype=_L)
    z = 2 * _PI_L * n / _L(beta)
    ints_l = np.diff(np.append(taus_l, taus_l[0] + z))
    taus, us, intervals = taus_l.astype(float), us_l.astype(float), ints_l.astype(float)
    scale = 1.0 + abs(delta) + float(np.max(us))
    for j in range(m):
        x, v = flight_state(taus[j], us[j], intervals[j], beta, delta, zeta, eps)
        if abs(x - delta) > 1e-9 * scale or abs(v - us[(j + 1) % m]) > 1e-9 * scale:
            return None
    tmat = _monodromy(taus_l, us_l, ints_l, beta, delta, zeta, eps)
    mu = np.linalg.eigvals(tmat).astype(complex)
    mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    margin = min(_flight_margin(taus[j], us[j], intervals[j], beta, delta, zeta, eps)
                 for j in range(m))
    return RefOrbit(m=m, n=n, taus=taus, us=us, intervals=intervals, mu=mu,
                    det=float(np.linalg.det(tmat)), margin=margin)


# --- (1/n): closed form in extended precision ----------------------------------------------

def _m1_coefficients(n, beta, zeta, eps):
    """``(K, a, b, z)`` of ``a sin psi_0 + b cos psi_0 = K delta`` (longdouble).

    With ``z = 2 pi n/beta`` the forced part repeats, so the free part must map the start
    state ``(delta - q S, -eps u - q beta C)`` (``S, C = sin, cos psi_0``) to
    ``(delta - q S, u - q beta C)``. The position row gives ``eps u`` in terms of ``(S, C)``;
    the velocity row then leaves ``K (delta - q S) + (1 + eps) p12 q beta C = 0`` with
    ``K = (1 - p11) + eps (p22 - det P)``.
    """
    q, _, wd = _consts(beta, zeta, _L)
    b_, zt, ep = _L(beta), _L(zeta), _L(eps)
    z = 2 * _PI_L * n / b_
    p11, p12, _, p22 = _free(z, zt, wd)
    kk = (1 - p11) + ep * (p22 - np.exp(-2 * zt * z))
    return kk, kk * q, -(1 + ep) * p12 * q * b_, z


def fold_deltas_m1(n, beta, zeta, eps):
    """``delta*`` (float) such that (1/n) solutions exist for ``|delta| <= delta*`` only.

    At ``delta = +- delta*``, ``|kappa| = 1``: the two roots merge (a fold, mu = +1).
    """
    kk, a, b, _ = _m1_coefficients(n, beta, zeta, eps)
    return float(np.hypot(a, b) / abs(kk))


def _m1_solution(n, beta, delta, zeta, eps, branch):
    """The (1/n) solution on ``branch`` (0: ``asin kappa``, 1: ``pi - asin kappa``).

    Returns ``(tau_0, u)`` (longdouble), or None when ``|kappa| > 1``. ``u`` may be <= 0.
    """
    q, phi, wd = _consts(beta, zeta, _L)
    kk, a, b, z = _m1_coefficients(n, beta, zeta, eps)
    r = np.hypot(a, b)
    kappa = kk * _L(delta) / r
    if abs(kappa) > 1:
        return None
    theta = np.arctan2(b, a)                       # a S + b C = r sin(psi + theta)
    asn = np.arcsin(kappa)
    psi = -theta + (asn if branch == 0 else _PI_L - asn)
    b_, zt, ep, d_ = _L(beta), _L(zeta), _L(eps), _L(delta)
    p11, p12, p21, p22 = _free(z, zt, wd)
    y0 = d_ - q * np.sin(psi)
    vq = q * b_ * np.cos(psi)
    # u from whichever row depends on it more strongly (they agree on the solution)
    if abs(ep * p12) >= abs(1 + ep * p22):
        u = -((1 - p11) * y0 + p12 * vq) / (ep * p12)      # position row
    else:
        u = (p21 * y0 + (1 - p22) * vq) / (1 + ep * p22)   # velocity row
    tf = 2 * _PI_L / b_
    tau0 = (psi + phi) / b_
    tau0 = tau0 - tf * np.floor(tau0 / tf)
    return tau0, u


def _solutions_m1(n, beta, delta, zeta, eps):
    out = []
    for branch in (0, 1):
        sol = _m1_solution(n, beta, delta, zeta, eps, branch)
        if sol is None or not sol[1] > 0:
            continue
        ref = _make_ref(1, n, [sol[0]], [sol[1]], beta, delta, zeta, eps)
        if ref is None:
            raise _ReferenceFailure(f"(1/{n}) closed-form orbit fails its self-check")
        out.append(ref)
    return _dedupe(out, beta)


# --- (2/n): D(z_1) parametrization ---------------------------------------------------------

def _m2_w(z1, n, beta, zeta, eps):
    """``w(z_1)``, shape (N, 4), longdouble: ``(S, C, u_0, u_1) = delta w`` solves the (2/n)
    equations with first interval ``z_1`` (any ``delta``).

    The four rows (position and velocity at the end of each flight) are linear in
    ``(S, C, u_0, u_1, delta)``; their matrix is assembled column by column from the residual
    and solved by Gaussian elimination with partial pivoting in longdouble (vectorized over
    ``z_1``). Singular matrices give inf/nan entries (callers treat them as no solution).
    """
    q, _, wd = _consts(beta, zeta, _L)
    b_, zt, ep = _L(beta), _L(zeta), _L(eps)
    z1 = np.atleast_1d(np.asarray(z1, dtype=_L))
    z = 2 * _PI_L * n / b_
    z2 = z - z1
    ca, sa = np.cos(b_ * z1), np.sin(b_ * z1)
    f1 = _free(z1, zt, wd)
    f2 = _free(z2, zt, wd)

    def resid(s_, c_, u0, u1, d_):
        xp0, vp0 = q * s_, q * b_ * c_                           # forced part at tau_0 (+z)
        xp1 = q * (s_ * ca + c_ * sa)                            # ... and at tau_1
        vp1 = q * b_ * (c_ * ca - s_ * sa)
        y0, w0 = d_ - xp0, -ep * u0 - vp0                        # free part leaving tau_0
        y1, w1 = d_ - xp1, -ep * u1 - vp1                        # free part leaving tau_1
        return np.stack([f1[0] * y0 + f1[1] * w0 - (d_ - xp1),
                         f1[2] * y0 + f1[3] * w0 - (u1 - vp1),
                         f2[0] * y1 + f2[1] * w1 - (d_ - xp0),
                         f2[2] * y1 + f2[3] * w1 - (u0 - vp0)], axis=-1)

    zero, one = np.zeros_like(z1), np.ones_like(z1)
    amat = np.stack([resid(one, zero, zero, zero, zero), resid(zero, one, zero, zero, zero),
                     resid(zero, zero, one, zero, zero), resid(zero, zero, zero, one, zero)],
                    axis=-1)                                     # amat[:, row, col]
    rhs = -resid(zero, zero, zero, zero, one)
    return _batched_solve(amat, rhs)


def _batched_solve(amat, rhs):
    """Solve ``amat[k] x = rhs[k]`` for every k (partial pivoting, any float dtype)."""
    a = amat.copy()
    b = rhs.copy()
    nb, nn = b.shape
    idx = np.arange(nb)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for k in range(nn):
            p = k + np.argmax(np.abs(a[:, k:, k]), axis=1)
            rows_k, rows_p = a[idx, k, :].copy(), a[idx, p, :].copy()
            a[idx, k, :], a[idx, p, :] = rows_p, rows_k
            bk, bp = b[idx, k].copy(), b[idx, p].copy()
            b[idx, k], b[idx, p] = bp, bk
            for i in range(k + 1, nn):
                f = a[:, i, k] / a[:, k, k]
                a[:, i, k:] -= f[:, None] * a[:, k, k:]
                b[:, i] -= f * b[:, k]
        x = np.empty_like(b)
        for k in range(nn - 1, -1, -1):
            acc = b[:, k] - np.sum(a[:, k, k + 1:] * x[:, k + 1:], axis=1)
            x[:, k] = acc / a[:, k, k]
    return x


def _m2_d(z1, n, beta, zeta, eps):
    """``D(z_1) = 1/|w_SC|`` (longdouble) and the sign s of ``delta`` that makes both
    velocities positive (0 when ``w_u0``, ``w_u1`` differ in sign or are not finite)."""
    w = _m2_w(z1, n, beta, zeta, eps)
    with np.errstate(invalid="ignore", divide="ignore"):
        dd = 1 / np.hypot(w[:, 0], w[:, 1])
        sgn = np.where((np.sign(w[:, 2]) == np.sign(w[:, 3])) & np.isfinite(w[:, 2])
                       & np.isfinite(w[:, 3]), np.sign(w[:, 2]), 0)
    dd = np.where(np.isfinite(dd), dd, _L(0))
    return dd, sgn.astype(int)


#: The (2/n) search stops this far (relative to z/2) from z_1 = z/2. For even n, w(z_1) has a
#: removable singularity there (the doubled (1/n) motion); D is then evaluated with an error
#: growing like ~1e-27/offset^2 (measured: 3e-13 at 1e-7, 7e-11 at 1e-10) and its value differs
#: from D(z/2) by ~D'' offset^2 ~ 1e-14. At 1e-7 both stay far below the smallest distance
#: (1e-10) at which a (2/2) motion is looked for next to a period doubling.
HALF_GUARD = 1e-7


def _m2_grid(n, beta, zeta):
    """Nodes on ``(0, z/2)``: uniform (0.01 rad of the fastest of beta, wd) plus geometric
    towards ``z_1 -> 0`` (a very short flight, next to chatter) and towards ``z/2``."""
    z = 2.0 * math.pi * n / beta
    half = 0.5 * z
    fast = max(beta, math.sqrt(1.0 - zeta * zeta))
    npt = max(400, int(math.ceil(half * fast / 0.01)))
    uni = half * (np.arange(npt) + 0.5) / npt
    geo0 = half * 10.0 ** -np.arange(3.0, 10.0)
    geo1 = half * 10.0 ** -np.arange(3.0, -math.log10(HALF_GUARD) + 0.5)
    return np.unique(np.concatenate((geo0, uni, half - geo1)))


def _m2_critical(n, beta, zeta, eps):
    """Critical points of ``D`` on ``(0, z/2)``: ``[(z_1*, D*, kind, sign)]`` with kind
    +1 (local maximum) or -1 (local minimum), refined by a bounded Brent search, plus the
    grid and its values (used to bracket the roots)."""
    nodes = _m2_grid(n, beta, zeta)
    dd, sgn = _m2_d(nodes, n, beta, zeta, eps)
    crit = []
    for k in range(1, nodes.size - 1):
        for kind in (1, -1):
            c = kind * dd[k]
            if c >= kind * dd[k - 1] and c > kind * dd[k + 1]:
                lo, hi = nodes[k - 1], nodes[k + 1]
                ref = dd[k]

                def obj(t, kind=kind, ref=ref):
                    # the difference is taken in longdouble before rounding, so the bracketing
                    # search resolves D to ~1e-19 near its extremum
                    val = _m2_d(np.array([t]), n, beta, zeta, eps)[0][0]
                    return -float(kind * (val - ref)) * 1e6

                res = minimize_scalar(obj, bounds=(lo, hi), method="bounded",
                                      options={"xatol": 1e-13 * (1.0 + hi)})
                t = float(res.x) if obj(res.x) <= obj(nodes[k]) else float(nodes[k])
                dval, s = _m2_d(np.array([t]), n, beta, zeta, eps)
                crit.append((t, dval[0], kind, int(s[0])))
    return crit, nodes, dd


def _solutions_m2(n, beta, delta, zeta, eps):
    """Every (2/n) solution at ``delta`` (u > 0, admissible or not), each orbit once."""
    crit, nodes, _ = _m2_critical(n, beta, zeta, eps)
    target = _L(abs(delta))
    ends = sorted([nodes[0], nodes[-1]] + [c[0] for c in crit])

    def f(t):
        return float(_m2_d(np.array([t]), n, beta, zeta, eps)[0][0] - target)

    out = []
    for lo, hi in zip(ends[:-1], ends[1:]):
        flo, fhi = f(lo), f(hi)
        if not (flo * fhi < 0.0):
            continue
        z1 = brentq(f, lo, hi, xtol=1e-16, rtol=8.9e-16, maxiter=200)
        w = _m2_w(np.array([z1]), n, beta, zeta, eps)[0]
        x = _L(delta) * w
        if not (x[2] > 0 and x[3] > 0):
            continue
        nrm = np.hypot(x[0], x[1])                # = 1 up to the root's accuracy
        _, phi, _ = _consts(beta, zeta, _L)
        psi = np.arctan2(x[0] / nrm, x[1] / nrm)
        tau0 = ((psi + phi) / _L(beta)) % (2 * _PI_L / _L(beta))
        ref = _make_ref(2, n, [tau0, tau0 + _L(z1)], [x[2], x[3]], beta, delta, zeta, eps)
        if ref is None:
            raise _ReferenceFailure(f"(2/{n}) orbit at z1 = {z1!r} fails its self-check")
        out.append(ref)
    return _dedupe(out, beta)


class _ReferenceFailure(RuntimeError):
    """The independent solver could not vouch for its own answer (not a package failure)."""


def _dedupe(orbits, beta):
    keep = []
    for o in orbits:
        if not any(_orbit_distance(o.taus, o.us, k.taus, k.us, beta) < 1e-9 for k in keep):
            keep.append(o)
    return keep


def reference_orbits(m, n, beta, delta, zeta, eps, include_inadmissible=False):
    """Every (m/n) periodic motion at one parameter point, by the independent solver.

    Parameters
    ----------
    m : {1, 2}
        Impacts per period.
    n : int
        Forcing cycles per period.
    beta, delta, zeta, eps : float
        Parameter point (``delta != 0``).
    include_inadmissible : bool, optional
        Also return solutions whose flights cross the wall (``margin < 0``).

    Returns
    -------
    list of RefOrbit
    """
    if m == 1:
        orbits = _solutions_m1(n, beta, delta, zeta, eps)
    elif m == 2:
        orbits = _solutions_m2(n, beta, delta, zeta, eps)
    else:
        raise NotImplementedError("the independent solver handles m = 1, 2")
    if not include_inadmissible:
        orbits = [o for o in orbits if o.margin >= 0.0]
    return orbits


# ------------------------------------------------------------------------------------------
# second method: DOP853 with a wall event

def dop853_return(taus, us, m, n, beta, delta, zeta, eps, max_step=None):
    """Largest deviation of m DOP853 impact-map steps from the orbit's own impacts.

    From the first impact ``(taus[0], us[0])``, integrate ``x'' + 2 zeta x' + x =
    sin(beta tau)`` (rtol = atol = 1e-12) to the first upward crossing of ``delta``, apply the
    rebound, and repeat m times. Returns the largest ``|dtau|, |du|`` against the orbit
    (``inf`` if an impact is missing): ~1e-10 for a genuine admissible orbit, O(1) if a flight
    crosses the wall early or the orbit does not exist. ``max_step`` (default
    ``min(0.01, u_min/2)``) keeps a short excursion above the wall, which lasts ~2u/|x''| after
    an arrival at velocity u, from slipping between two steps unseen by the event.
    """
    if max_step is None:
        max_step = min(0.01, 0.5 * float(np.min(us)))
    z = 2.0 * math.pi * n / beta

    def rhs(t, y):
        return [y[1], math.sin(beta * t) - 2.0 * zeta * y[1] - y[0]]

    def hit(t, y):
        return y[0] - delta
    hit.terminal, hit.direction = True, 1.0
    t, u = float(taus[0]), float(us[0])
    worst = 0.0
    for j in range(m):
        sol = solve_ivp(rhs, (t, t + 1.5 * z), [delta, rebound_velocity(eps, u)],
                        method="DOP853", rtol=1e-12, atol=1e-12, events=hit, max_step=max_step,
                        first_step=1e-6)
        if sol.t_events[0].size == 0:
            return math.inf
        t, u = float(sol.t_events[0][0]), float(sol.y_events[0][0][1])
        want_t = taus[j + 1] if j + 1 < m else taus[0] + z
        worst = max(worst, abs(t - want_t), abs(u - us[(j + 1) % m]))
    return worst


# ------------------------------------------------------------------------------------------
# comparison

def _orbit_distance(ta, ua, tb, ub, beta):
    """Rotation-invariant distance of two orbits' impacts: phases mod ``2 pi/beta`` (in units
    of it) and velocities (in units of ``max(1, u)``); inf for different impact counts."""
    if len(ta) != len(tb):
        return math.inf
    tf = 2.0 * math.pi / beta
    scale = max(1.0, float(np.max(ua)), float(np.max(ub)))
    pa, pb = np.mod(ta, tf), np.mod(tb, tf)
    best = math.inf
    for r in range(len(ta)):
        pr, ur = np.roll(pb, -r), np.roll(ub, -r)
        dp = np.abs(pa - pr) % tf
        dp = np.minimum(dp, tf - dp) / tf
        best = min(best, float(max(np.max(dp), np.max(np.abs(ua - ur)) / scale)))
    return best


def _mu_error(mu_pkg, mu_ref):
    """``max |mu - mu_ind| / max(1, |mu_ind|)`` over the better of the two pairings."""
    mu_pkg, mu_ref = np.asarray(mu_pkg, complex), np.asarray(mu_ref, complex)
    errs = []
    for perm in ((0, 1), (1, 0)):
        e = [abs(mu_pkg[i] - mu_ref[j]) / max(1.0, abs(mu_ref[j])) for i, j in zip((0, 1), perm)]
        errs.append(max(e))
    return min(errs)


def displacement_scale(beta, delta, zeta):
    """``S = 1 + |delta| + q (1 + beta)``: wall offset plus forced amplitude and velocity."""
    q = 1.0 / math.hypot(1.0 - beta * beta, 2.0 * zeta * beta)
    return 1.0 + abs(delta) + q * (1.0 + beta)


def mu_tolerance(family, distance, u_min=1.0, scale=1.0):
    """Tolerance on ``|mu - mu_ind| / max(1, |mu_ind|)`` for an orbit with slowest impact
    ``u_min`` at a distance ``d`` from the singular configuration, displacement scale
    ``scale`` (see the comment at ``MU_TOL_RESIDUAL`` for why)."""
    if family == "orbit_grazing":
        return MU_TOL_FLOOR
    return MU_TOL_FLOOR + MU_TOL_RESIDUAL * scale / (math.sqrt(distance) * min(1.0, u_min))


def _pkg_impacts(o):
    """Impact instants and the approach velocity at each, from a ``PeriodicOrbit``."""
    return np.asarray(o.impact_times, float), np.roll(np.asarray(o.velocities, float), 1)


def mp_orbit(m, n, taus, us, beta, delta, zeta, eps, dps=40):
    """Polish an (m/n) orbit in mpmath (``dps`` digits): an arbiter for disagreements.

    Newton (``mpmath.findroot``) on the 2m equations "flight j lands on the wall at
    ``taus[j+1]`` with velocity ``us[j+1]``" from the given impacts, then ``T`` from central
    differences of the mp impact map (step ``10^(-dps/2)``). Independent of both the package
    and the float/longdouble reference.

    Returns
    -------
    (taus, us, mu) as float arrays, or None when Newton does not converge.
    """
    import mpmath

    ctx = mpmath.mp.clone()
    ctx.dps = dps
    b, d, zt, ep = (ctx.mpf(v) for v in (beta, delta, zeta, eps))
    q = 1 / ctx.sqrt((1 - b * b) ** 2 + (2 * zt * b) ** 2)
    phi = ctx.atan2(2 * zt * b, 1 - b * b)
    wd = ctx.sqrt(1 - zt * zt)
    z = 2 * ctx.pi * n / b

    def fl(ta, ua, s):
        psi = b * ta - phi
        y0, v0 = d - q * ctx.sin(psi), -ep * ua - q * b * ctx.cos(psi)
        e, c, sn = ctx.exp(-zt * s), ctx.cos(wd * s), ctx.sin(wd * s)
        return (q * ctx.sin(psi + b * s) + e * (y0 * c + (v0 + zt * y0) / wd * sn),
                q * b * ctx.cos(psi + b * s) + e * (v0 * c - (y0 + zt * v0) / wd * sn))

    def eqs(*y):
        out = []
        for j in range(m):
            tn = y[j + 1] if j + 1 < m else y[0] + z
            x, v = fl(y[j], y[m + j], tn - y[j])
            out += [x - d, v - y[m + (j + 1) % m]]
        return out

    try:
        sol = ctx.findroot(eqs, [ctx.mpf(float(v)) for v in list(taus) + list(us)],
                           tol=ctx.mpf(10) ** (-2 * dps + 10), maxsteps=60)
    except (ValueError, ZeroDivisionError):
        return None
    t = [sol[j] for j in range(m)]
    u = [sol[m + j] for j in range(m)]

    def land(ta, ua, s0):
        s = ctx.findroot(lambda s: fl(ta, ua, s)[0] - d, s0)
        return ta + s, fl(ta, ua, s)[1]

    h = ctx.mpf(10) ** (-dps // 2)
    tm = ctx.eye(2)
    for j in range(m):
        s0 = (t[j + 1] if j + 1 < m else t[0] + z) - t[j]
        tj = ctx.matrix(2, 2)
        for col, (a, c) in enumerate(((1, 0), (0, 1))):
            p1 = land(t[j] + a * h, u[j] + c * h, s0)
            p0 = land(t[j] - a * h, u[j] - c * h, s0)
            tj[0, col], tj[1, col] = (p1[0] - p0[0]) / (2 * h), (p1[1] - p0[1]) / (2 * h)
        tm = tj * tm
    mu = np.array([complex(v) for v in ctx.eig(tm)[0]])
    return (np.array([float(v) for v in t]), np.array([float(v) for v in u]),
            mu[np.argsort(-np.abs(mu), kind="stable")])


def _arbitrate(m, n, taus, us, beta, delta, zeta, eps, ref, shorter):
    """Where mpmath Newton from a disputed returned orbit lands.

    Returns ``(text, genuine_new)``: a description for the failure message, and True when it
    lands (within 1e-9) on an admissible orbit that is neither a reference orbit nor a doubled
    shorter one, i.e. on an orbit the reference lacks.
    """
    res = mp_orbit(m, n, taus, us, beta, delta, zeta, eps)
    if res is None:
        return "mpmath Newton does not converge from it", False
    t, u, mu = res
    moved = _orbit_distance(t, u, taus, us, beta)
    text = f"mpmath Newton from it moves {moved:.1e} to an orbit with mu={mu}"
    for label, group in (("a reference orbit", ref), ("a doubled shorter orbit", shorter)):
        if any(_orbit_distance(t, u, r.taus, r.us, beta) < 1e-9 for r in group):
            return f"{text}, which is {label}", False
    genuine = False
    if moved < 1e-9 and np.all(u > 0.0) and np.all(np.diff(t) > 0.0):
        polished = _make_ref(m, n, t, u, beta, delta, zeta, eps)
        genuine = polished is not None and polished.margin >= 0.0
    return f"{text}, which the reference lacks", genuine


@dataclass
class Outcome:
    """What one comparison (one motion type at one point) found.

    Attributes
    ----------
    errors : list of (float, float)
        ``(|mu - mu_ind| / max(1, |mu_ind|), tolerance)`` of every paired orbit.
    missed, spurious, exceptions : int
        Counts for the report.
    det_rel : float
        Worst ``|det T / (eps^(2m) exp(-2 zeta z)) - 1|`` over the returned orbits.
    messages : list of str
        What failed.
    """

    errors: list = field(default_factory=list)
    missed: int = 0
    spurious: int = 0
    exceptions: int = 0
    det_rel: float = 0.0
    messages: list = field(default_factory=list)


def compare_orbits(pkg, ref, beta, delta, zeta, eps, m, n, mu_tol, band=None):
    """Compare the package's orbits with the reference's at one point.

    Parameters
    ----------
    pkg : list of PeriodicOrbit
        The package's admissible (m/n) orbits.
    ref : list of RefOrbit
        The reference's (m/n) orbits, admissible or not (``margin`` decides).
    beta, delta, zeta, eps : float
        The parameter point.
    m, n : int
        The motion type.
    mu_tol : callable
        ``mu_tol(ref_orbit)``: tolerance on ``|mu - mu_ind| / max(1, |mu_ind|)``.
    band : float or None
        Reference orbits with ``|margin| <= band`` may be present or absent (grazing).

    Returns
    -------
    Outcome

    Raises
    ------
    _ReferenceFailure
        When a returned orbit that the reference lacks is confirmed by mpmath as a genuine
        admissible orbit (neither a duplicate nor a doubled shorter orbit): the reference is
        incomplete there, and the case says nothing about the package.

    Notes
    -----
    Orbits are paired by an optimal assignment on the rotation-invariant impact distance
    (pairs farther than :data:`MATCH_TOL` are not pairs). A paired orbit's multipliers must
    agree to ``mu_tol``; an unpaired admissible reference orbit is a miss, an unpaired
    returned orbit is spurious. Every disagreement is re-examined by second methods (DOP853
    return deviation; mpmath Newton from the disputed orbit), whose findings go into the
    message. Every returned orbit also has ``det T`` checked (:data:`DET_RTOL`).
    """
    out = Outcome()
    must = [o for o in ref if o.margin >= 0.0 and not (band and abs(o.margin) <= band)]
    may = [o for o in ref if band and abs(o.margin) <= band]
    pool = must + may
    shorter = []
    if m == 2 and n % 2 == 0:            # a doubled (1/(n/2)) motion solves the (2/n) equations
        shorter = [RefOrbit(m=2, n=n, taus=np.array([o.taus[0], o.taus[0] + o.intervals[0]]),
                            us=np.array([o.us[0], o.us[0]]), intervals=np.r_[o.intervals] * 1,
                            mu=o.mu, det=o.det, margin=o.margin)
                   for o in reference_orbits(1, n // 2, beta, delta, zeta, eps, True)]
    cost = np.full((len(pool), len(pkg)), math.inf)
    for i, r in enumerate(pool):
        for k, o in enumerate(pkg):
            cost[i, k] = _orbit_distance(r.taus, r.us, *_pkg_impacts(o), beta)
    paired_ref, paired_pkg = set(), set()
    if cost.size:
        rows, cols = linear_sum_assignment(np.where(np.isfinite(cost), cost, 1e300))
        for i, k in zip(rows, cols):
            if cost[i, k] > MATCH_TOL:
                continue
            paired_ref.add(i)
            paired_pkg.add(k)
            err = _mu_error(pkg[k].multipliers, pool[i].mu)
            tol = mu_tol(pool[i])
            out.errors.append((err, tol))
            if not err <= tol:
                arb = mp_orbit(m, n, pool[i].taus, pool[i].us, beta, delta, zeta, eps)
                verdict = "" if arb is None else (
                    f"; mpmath: mu={arb[2]}, reference off by "
                    f"{_mu_error(pool[i].mu, arb[2]):.1e}, package off by "
                    f"{_mu_error(pkg[k].multipliers, arb[2]):.1e}, package orbit off by "
                    f"{_orbit_distance(arb[0], arb[1], *_pkg_impacts(pkg[k]), beta):.1e}")
                out.messages.append(f"({m}/{n}) multipliers {pkg[k].multipliers} vs "
                                    f"independent {pool[i].mu}: error {err:.2e} > tolerance "
                                    f"{tol:.1e}{verdict}")
    for k, o in enumerate(pkg):
        if k in paired_pkg:
            continue
        t, u = _pkg_impacts(o)
        dist_ref = min((_orbit_distance(r.taus, r.us, t, u, beta) for r in ref),
                       default=math.inf)
        what = [f"nearest reference orbit {dist_ref:.1e} away"]
        near = [r for r in ref if _orbit_distance(r.taus, r.us, t, u, beta) <= MATCH_TOL]
        if near:
            what.append(f"(its margin {max(r.margin for r in near):.3e})")
        dup = min((_orbit_distance(*_pkg_impacts(pkg[j]), t, u, beta) for j in paired_pkg),
                  default=math.inf)
        if dup <= MATCH_TOL:
            what.append(f"a duplicate: {dup:.1e} from another returned orbit")
        dshort = min((_orbit_distance(r.taus, r.us, t, u, beta) for r in shorter),
                     default=math.inf)
        if dshort <= MATCH_TOL:
            what.append(f"{dshort:.1e} from a doubled (1/{n // 2}) motion")
        arb, genuine = _arbitrate(m, n, t, u, beta, delta, zeta, eps, ref, shorter)
        if genuine and dup > MATCH_TOL:
            raise _ReferenceFailure(f"the package's ({m}/{n}) orbit tau0={o.tau0!r} is "
                                    f"genuine but the reference lacks it: {arb}")
        check = dop853_return(t, u, m, n, beta, delta, zeta, eps)
        out.spurious += 1
        out.messages.append(f"spurious ({m}/{n}) orbit tau0={o.tau0!r} "
                            f"velocities={o.velocities.tolist()} margin={o.margin:.3e}: "
                            f"{' '.join(what)}; DOP853 return deviation {check:.1e}; {arb}")
    for i, r in enumerate(must):
        if i in paired_ref:
            continue
        out.missed += 1
        check = dop853_return(r.taus, r.us, m, n, beta, delta, zeta, eps)
        arb = mp_orbit(m, n, r.taus, r.us, beta, delta, zeta, eps)
        verdict = ("mpmath Newton does not converge from it" if arb is None else
                   f"mpmath Newton from it moves "
                   f"{_orbit_distance(arb[0], arb[1], r.taus, r.us, beta):.1e}")
        out.messages.append(f"missed ({m}/{n}) orbit taus={r.taus.tolist()} "
                            f"us={r.us.tolist()} margin={r.margin:.3e} mu={r.mu}; "
                            f"DOP853 return deviation {check:.1e}; {verdict}")
    z = 2.0 * math.pi * n / beta
    expected = eps ** (2 * m) * math.exp(-2.0 * zeta * z)
    for o in pkg:
        det = np.linalg.det(o.jacobian)
        rel = abs(det - expected) / expected
        out.det_rel = max(out.det_rel, rel)
        if not rel <= DET_RTOL:
            out.messages.append(f"({m}/{n}) det T = {det!r}, expected {expected!r} "
                                f"(rel. {rel:.1e})")
    return out


# ------------------------------------------------------------------------------------------
# the singular configurations, located by the independent solver

def _merged_m1(n, beta, delta_f, zeta, eps):
    """The (1/n) orbit at a fold ``delta_f`` (the two roots coincide), or None."""
    sol = _m1_solution(n, beta, delta_f * (1.0 - 1e-14), zeta, eps, 0)
    if sol is None or not sol[1] > 0:
        return None
    return _make_ref(1, n, [sol[0]], [sol[1]], beta, delta_f, zeta, eps)


def fold_points(m, n, beta, zeta, eps):
    """Folds in ``delta`` (at fixed ``beta``) where a pair of admissible (m/n) motions is born.

    Parameters
    ----------
    m : {1, 2}
    n : int
    beta, zeta, eps : float

    Returns
    -------
    list of (delta_f, side, merged)
        The fold's ``delta``, the direction (+1/-1) of ``delta`` in which the pair exists, and
        the merged orbit at the fold (a :class:`RefOrbit`, admissible with ``u > 0``).

    Notes
    -----
    (1/n): ``|kappa| = 1`` at ``delta = +- delta*`` (closed form), the pair exists for
    ``|delta| < delta*``. (2/n): the interior local extrema of ``D(z_1)`` below ``z/2``; at a
    maximum the pair exists for ``|delta| < D*``, at a minimum for ``|delta| > D*``.
    """
    out = []
    if m == 1:
        dstar = fold_deltas_m1(n, beta, zeta, eps)
        for sgn in (1.0, -1.0):
            merged = _merged_m1(n, beta, sgn * dstar, zeta, eps)
            if merged is not None and merged.margin > 0.0:
                out.append((sgn * dstar, -sgn, merged))
        return out
    half = math.pi * n / beta
    crit, _, _ = _m2_critical(n, beta, zeta, eps)
    for z1, dval, kind, sgn in crit:
        # D -> 0 where the linear system is singular: a kink, not a fold
        if sgn == 0 or dval < 1e-3 or not 1e-6 * half < z1 < half * (1.0 - 1e-6):
            continue
        delta_f = float(sgn * dval)
        w = _m2_w(np.array([z1]), n, beta, zeta, eps)[0]
        x = _L(delta_f) * w
        if not (x[2] > 0 and x[3] > 0):
            continue
        _, phi, _ = _consts(beta, zeta, _L)
        nrm = np.hypot(x[0], x[1])
        tau0 = ((np.arctan2(x[0] / nrm, x[1] / nrm) + phi) / _L(beta)) % (2 * _PI_L / _L(beta))
        merged = _make_ref(2, n, [tau0, tau0 + _L(z1)], [x[2], x[3]], beta, delta_f, zeta,
                           eps)
        if merged is not None and merged.margin > 0.0:
            out.append((delta_f, -sgn if kind == 1 else sgn, merged))
    return out


def _pd_function(n, beta, delta, zeta, eps, branch):
    """``p(-1) = 1 + tr T + det T`` of the (1/n) orbit on ``branch`` (zero at mu = -1)."""
    sol = _m1_solution(n, beta, delta, zeta, eps, branch)
    if sol is None or not sol[1] > 0:
        return math.nan
    z = 2 * _PI_L * n / _L(beta)
    tmat = _monodromy([sol[0]], [sol[1]], [z], beta, delta, zeta, eps)
    return 1.0 + np.trace(tmat) + np.linalg.det(tmat)


def period_doubling_points(beta, zeta, eps, n=1, grid=120):
    """Values of ``delta`` (at fixed ``beta``) where an admissible (1/n) motion has mu = -1.

    Returns
    -------
    list of (delta_pd, branch, orbit)
        ``branch`` as in the closed form; ``orbit`` the (1/n) motion at ``delta_pd``.

    Notes
    -----
    ``p(-1) = 1 + tr T + det T`` changes sign along each closed-form branch where a real
    multiplier crosses -1 (complex multipliers keep ``p(-1) > 0``); sign changes on a grid of
    ``delta`` are refined by brentq.
    """
    dstar = fold_deltas_m1(n, beta, zeta, eps)
    deltas = np.linspace(-dstar, dstar, grid + 2)[1:-1]
    out = []
    for branch in (0, 1):
        vals = np.array([_pd_function(n, beta, d, zeta, eps, branch) for d in deltas])
        for k in np.flatnonzero(vals[:-1] * vals[1:] < 0.0):
            d_pd = brentq(lambda d, branch=branch: _pd_function(n, beta, d, zeta, eps, branch),
                          deltas[k], deltas[k + 1], xtol=1e-15, rtol=8.9e-16)
            if not abs(_pd_function(n, beta, d_pd, zeta, eps, branch)) < 1e-9:
                continue                  # the bracket held a gap of the branch, not a root
            sol = _m1_solution(n, beta, d_pd, zeta, eps, branch)
            if sol is None or not sol[1] > 0:
                continue
            orbit = _make_ref(1, n, [sol[0]], [sol[1]], beta, d_pd, zeta, eps)
            if orbit is not None and orbit.margin > 0.0:
                out.append((d_pd, branch, orbit))
    return out


def _margin_m1(n, beta, delta, zeta, eps, branch):
    sol = _m1_solution(n, beta, delta, zeta, eps, branch)
    if sol is None or not sol[1] > 0:
        return math.nan
    z = 2.0 * math.pi * n / beta
    return _flight_margin(float(sol[0]), float(sol[1]), z, beta, delta, zeta, eps)


def grazing_points(n, beta, zeta, eps, grid=100):
    """Values of ``delta`` (at fixed ``beta``) where a (1/n) flight touches the wall.

    Returns
    -------
    list of (delta_g, branch, side)
        ``side`` (+1/-1): the direction of ``delta`` in which the orbit is admissible.

    Notes
    -----
    The admissibility margin ``delta - max x`` of each closed-form branch is sampled on a grid
    of ``delta``; a sign change between two finite values (an interior maximum crossing the
    wall, not one appearing at a flight's end) is refined by brentq.
    """
    dstar = fold_deltas_m1(n, beta, zeta, eps)
    deltas = np.linspace(-dstar, dstar, grid + 2)[1:-1]
    out = []
    for branch in (0, 1):
        vals = np.array([_margin_m1(n, beta, d, zeta, eps, branch) for d in deltas])
        fin = np.isfinite(vals[:-1]) & np.isfinite(vals[1:])
        for k in np.flatnonzero(fin & (vals[:-1] * vals[1:] < 0.0)):
            try:
                d_g = brentq(lambda d, branch=branch: _margin_m1(n, beta, d, zeta, eps, branch),
                             deltas[k], deltas[k + 1], xtol=1e-15, rtol=8.9e-16)
            except ValueError:           # the margin jumped (a maximum appeared): no tangency
                continue
            out.append((d_g, branch, 1 if vals[k + 1] > 0.0 else -1))
    return out


# ------------------------------------------------------------------------------------------
# the families

#: Motion types near whose folds the fold family draws its points, with their weights.
FOLD_TYPES = ((1, 1), (1, 2), (2, 1))
FOLD_WEIGHTS = (0.45, 0.25, 0.30)
#: Draws of (beta, zeta, eps) tried per case before the case is skipped (most draws have a
#: suitable singular point: ~40-100% depending on the family).
MAX_DRAWS = 60


def _draw_parameters(rng):
    """``(beta, zeta, eps)``: ``1/beta``, ``zeta``, ``eps`` uniform in their ranges."""
    zeta = float(rng.uniform(*ZETA_RANGE))
    eps = float(rng.uniform(*EPS_RANGE))
    beta = 1.0 / float(rng.uniform(*INV_BETA_RANGE))
    return beta, zeta, eps


def _draw_distance(rng):
    lo, hi = np.log10(DISTANCE_RANGE)
    return float(10.0 ** rng.uniform(lo, hi))


def _package(m, n, beta, delta, zeta, eps):
    """The package's admissible (m/n) orbits, or an Outcome with its exception if it raised."""
    from vibroimpact import periodic_orbits
    try:
        return periodic_orbits(m, n, beta, delta, zeta, eps)
    except Exception as exc:          # any raise is a package failure; keep going
        return Outcome(exceptions=1, messages=[
            f"periodic_orbits({m}, {n}, ...) raised {type(exc).__name__}: {exc}"])


def _compare_type(case, family, m, n, ref, band=None):
    """Call the package for one motion type at the case's point and compare."""
    beta, delta, zeta, eps = (case[k] for k in ("beta", "delta", "zeta", "eps"))
    pkg = _package(m, n, beta, delta, zeta, eps)
    if isinstance(pkg, Outcome):
        return pkg
    scale = displacement_scale(beta, delta, zeta)
    return compare_orbits(
        pkg, ref, beta, delta, zeta, eps, m, n,
        lambda r: mu_tolerance(family, case["distance"], float(np.min(r.us)), scale), band=band)


def _fold_pair(ref, merged, beta):
    """The pair born at a fold among the reference orbits, or None.

    The two admissible orbits nearest the merged one (closer than 0.5 in the impact distance)
    whose real multipliers nearest +1 lie on opposite sides of it (a saddle and a node).
    """
    adm = sorted((o for o in ref if o.margin >= 0.0),
                 key=lambda o: _orbit_distance(o.taus, o.us, merged.taus, merged.us, beta))
    if len(adm) < 2 or _orbit_distance(adm[1].taus, adm[1].us, merged.taus, merged.us,
                                       beta) > 0.5:
        return None
    near_one = [o.mu[np.argmin(np.abs(o.mu - 1.0))] for o in adm[:2]]
    if any(abs(mu.imag) > 0.0 for mu in near_one):
        return None
    if (near_one[0].real - 1.0) * (near_one[1].real - 1.0) >= 0.0:
        return None
    return adm[:2]


def _case_fold(rng, report):
    """One point next to a fold, on the side where the pair exists, or None (skip).

    A drawn distance at which the reference does not see the pair (one of its orbits has
    already lost a positive impact velocity or its admissibility: this happens within
    ~u_min^2 of a fold whose merged orbit has a slow impact u_min) is divided by 100 until it
    does (down to 1e-10).
    """
    lo = DISTANCE_RANGE[0]
    for _ in range(MAX_DRAWS):
        m, n = FOLD_TYPES[rng.choice(len(FOLD_TYPES), p=FOLD_WEIGHTS)]
        beta, zeta, eps = _draw_parameters(rng)
        folds = fold_points(m, n, beta, zeta, eps)
        if not folds:
            continue
        delta_f, side, merged = folds[rng.integers(len(folds))]
        d = _draw_distance(rng)
        while True:
            delta = delta_f + side * d
            ref = reference_orbits(m, n, beta, delta, zeta, eps, include_inadmissible=True)
            pair = _fold_pair(ref, merged, beta)
            if pair is not None or d <= lo:
                break
            d = max(lo, d * 1e-2)
        if pair is None:
            report.extra["pair_not_seen"] = report.extra.get("pair_not_seen", 0) + 1
            continue
        case = dict(kind="fold", m=m, n=n, beta=beta, delta=delta, zeta=zeta, eps=eps,
                    distance=d, side=int(side), delta_singular=delta_f,
                    mu_pair=[complex(o.mu[np.argmin(np.abs(o.mu - 1.0))]) for o in pair])
        return case, ref
    return None


def _case_period_doubling(rng, report):
    for _ in range(MAX_DRAWS):
        beta, zeta, eps = _draw_parameters(rng)
        points = period_doubling_points(beta, zeta, eps)
        if not points:
            continue
        delta_pd, branch, orbit = points[rng.integers(len(points))]
        d = _draw_distance(rng)
        side = 1 if rng.random() < 0.5 else -1
        # a second, independent location of the period doubling: D(z/2) of the (2/2)
        # parametrization (the (2/2) branch leaves the doubled (1/1) motion there) against
        # mu = -1 of the (1/1) closed form; recorded (agrees to ~1e-12)
        half = 2.0 * math.pi / beta
        dd, sgn = _m2_d(np.array([half * (1.0 - HALF_GUARD)]), 2, beta, zeta, eps)
        cross = abs(float(sgn[0] * dd[0]) - delta_pd) / max(1.0, abs(delta_pd))
        report.extra["pd_crosscheck"] = max(report.extra.get("pd_crosscheck", 0.0), cross)
        case = dict(kind="period_doubling", m=1, n=1, beta=beta, delta=delta_pd + side * d,
                    zeta=zeta, eps=eps, distance=d, side=side, delta_singular=delta_pd)
        return case, orbit
    return None


def _case_grazing(rng, report):
    for _ in range(MAX_DRAWS):
        n = 1 if rng.random() < 0.7 else 2
        beta, zeta, eps = _draw_parameters(rng)
        points = grazing_points(n, beta, zeta, eps)
        if not points:
            continue
        delta_g, branch, adm_side = points[rng.integers(len(points))]
        if abs(_margin_m1(n, beta, delta_g, zeta, eps, branch)) > 1e-12:
            continue                      # brentq stopped on a jump, not a tangency
        d = _draw_distance(rng)
        side = 1 if rng.random() < 0.5 else -1
        case = dict(kind="grazing", m=1, n=n, beta=beta, delta=delta_g + side * d, zeta=zeta,
                    eps=eps, distance=d, side=side, delta_singular=delta_g,
                    admissible_side=side == adm_side)
        key = "just_admissible" if side == adm_side else "just_inadmissible"
        report.extra[key] = report.extra.get(key, 0) + 1
        return case, branch
    return None


def _check_fold(case, ref):
    """Outcomes at a point next to a fold (the reference was computed by the draw)."""
    return [_compare_type(case, "orbit_fold", case["m"], case["n"], ref)]


def _check_period_doubling(case, orbit):
    """Outcomes of the (1/1) and (2/2) motions at a point next to a period doubling."""
    beta, delta, zeta, eps = (case[k] for k in ("beta", "delta", "zeta", "eps"))
    ref11 = reference_orbits(1, 1, beta, delta, zeta, eps, include_inadmissible=True)
    ref22 = reference_orbits(2, 2, beta, delta, zeta, eps, include_inadmissible=True)
    case["n_22"] = len([o for o in ref22 if o.margin >= 0.0])
    return [_compare_type(case, "orbit_period_doubling", 1, 1, ref11),
            _compare_type(case, "orbit_period_doubling", 2, 2, ref22)]


def _check_grazing(case, branch):
    """Outcome of the (1/n) motions at a point next to a grazing one."""
    m, n, beta, delta, zeta, eps = (case[k] for k in ("m", "n", "beta", "delta", "zeta", "eps"))
    ref = reference_orbits(m, n, beta, delta, zeta, eps, include_inadmissible=True)
    # self-check of the construction: the orbit with the smallest |margin| is the grazing one,
    # and its margin has the sign of the side it was put on
    graze = min(ref, key=lambda o: abs(o.margin), default=None)
    if graze is None or ((graze.margin >= 0.0) != case["admissible_side"]
                         and abs(graze.margin) > GRAZING_BAND):
        raise _ReferenceFailure("the grazing orbit is not where it was constructed")
    case["margin"] = graze.margin
    return [_compare_type(case, "orbit_grazing", m, n, ref, band=GRAZING_BAND)]


def check_case(case):
    """Re-run the comparison of one case, e.g. one copied from a failure message.

    Parameters
    ----------
    case : dict
        With ``kind`` (``"fold"``, ``"period_doubling"`` or ``"grazing"``), ``m``, ``n``,
        ``beta``, ``delta``, ``zeta``, ``eps`` and ``distance`` (other keys are ignored).

    Returns
    -------
    list of str
        What failed (empty when the package agrees with the reference there).
    """
    beta, delta, zeta, eps = (case[k] for k in ("beta", "delta", "zeta", "eps"))
    family = "orbit_" + case["kind"]
    types = ((1, 1), (2, 2)) if case["kind"] == "period_doubling" else ((case["m"], case["n"]),)
    band = GRAZING_BAND if case["kind"] == "grazing" else None
    messages = []
    for m, n in types:
        ref = reference_orbits(m, n, beta, delta, zeta, eps, include_inadmissible=True)
        messages += _compare_type(dict(case), family, m, n, ref, band=band).messages
    return messages


_FAMILY_TABLE = {
    "orbit_fold": (_case_fold, _check_fold),
    "orbit_period_doubling": (_case_period_doubling, _check_period_doubling),
    "orbit_grazing": (_case_grazing, _check_grazing),
}


def run_orbit_family(name: str, n_cases: int, seed: int) -> FamilyReport:
    """Run one stress family of periodic orbits against the independent solver.

    Parameters
    ----------
    name : str
        One of :data:`FAMILIES`: ``"orbit_fold"``, ``"orbit_period_doubling"``,
        ``"orbit_grazing"``.
    n_cases : int
        Parameter points to construct and compare.
    seed : int
        Seed of ``numpy.random.default_rng``; the same seed gives the same cases.

    Returns
    -------
    FamilyReport
        ``compared`` counts orbits paired with a reference orbit; ``worst_error`` is the
        largest ``|mu - mu_ind| / max(1, |mu_ind|)`` over them divided by the case's tolerance
        (:func:`mu_tolerance`; so the family's tolerance is 1; the raw worst is in
        ``extra["worst_mu_error"]``);
        ``missed``/``spurious`` count reference orbits the package did not return and returned
        orbits without an admissible reference counterpart; every returned orbit also has
        ``det T`` checked against ``eps^(2m) exp(-2 zeta z)`` (relative :data:`DET_RTOL`,
        worst in ``extra["worst_det_rel"]``). ``extra["skipped"]`` counts cases in which the
        independent solver could not vouch for its own answer (not package failures).

    Notes
    -----
    Each case draws ``zeta`` in [0.01, 0.2], ``eps`` in [0.3, 0.9], ``1/beta`` in [0.3, 3],
    locates a singular configuration along ``delta`` with the independent solver (redrawing
    when the draw has none), and puts the point at a log-uniform distance 1e-10 .. 1e-2 in
    ``delta`` from it: on the side where the fold pair exists, or on a random side for period
    doubling and grazing. Every case is reproducible from the dict kept with a failure.
    """
    if name not in _FAMILY_TABLE:
        raise ValueError(f"unknown orbit family {name!r}; expected one of {FAMILIES}")
    draw, check = _FAMILY_TABLE[name]
    report = FamilyReport(family=name, tolerance=1.0,
                          measure="|mu-mu_ind|/max(1,|mu_ind|) over tol(d)")
    report.extra["skipped"] = 0
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    for _ in range(n_cases):
        report.cases += 1
        case = None
        try:
            drawn = draw(rng, report)
            if drawn is None:
                raise _ReferenceFailure(f"no suitable singular point in {MAX_DRAWS} draws")
            case, context = drawn
            outcomes = check(case, context)
        except _ReferenceFailure as exc:
            report.extra["skipped"] += 1
            reasons = report.extra.setdefault("skip_reasons", [])
            if len(reasons) < 2:
                reasons.append(f"{exc}; case: {case!r}")
            continue
        if abs(case.get("margin", math.inf)) <= GRAZING_BAND:
            report.extra["in_band"] = report.extra.get("in_band", 0) + 1
        messages = []
        for out in outcomes:
            for err, tol in out.errors:
                report.add_error(err / tol, case)
                report.extra["worst_mu_error"] = max(report.extra.get("worst_mu_error", 0.0),
                                                     err)
            report.missed += out.missed
            report.spurious += out.spurious
            report.exceptions += out.exceptions
            report.extra["worst_det_rel"] = max(report.extra.get("worst_det_rel", 0.0),
                                                out.det_rel)
            messages += out.messages
        if messages:
            report.fail(case, "; ".join(messages))
    for key in ("worst_mu_error", "worst_det_rel", "pd_crosscheck"):
        if key in report.extra:
            report.extra[key] = float(f"{report.extra[key]:.3g}")
    report.seconds = time.perf_counter() - start
    return report
