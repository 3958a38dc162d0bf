"""Periodic (m/n) impact motions under the harmonic force alone (paper section 4, Fig. 16).

An (m/n) motion has period ``z = 2 pi n / beta`` and exactly m impacts per period. This module
finds every one of them at a parameter point (``periodic_orbits``) and classifies a whole
``(1/beta, delta)`` grid (``orbit_map``). Flights are closed form; the kernels live in
``vibroimpact.orbits.kernels``.

Method
------
- (1/n): the equations reduce to ``cos(psi_0 - chi) = kappa`` in the impact phase: both roots in
  closed form (``kernels.solve_m1``).
- (2/n), (3/n): for fixed intervals the equations are linear in the impact phase's
  ``(sin, cos)`` and the velocities; the solutions are the zeros of a smooth scalar circle
  condition over the intervals (a 1-D scan for m = 2, a 2-D one for m = 3;
  ``kernels.solve_general``). m >= 4 is not supported.
- m = 2: every sign change of the circle condition is solved to round-off in ``z_1`` and gives
  the solution directly; every dip toward zero between scan nodes is minimized first, so that
  the two orbits next to a fold (a near-double root, ~sqrt(distance) apart) are both bracketed.
  For even n the condition is taken in a symmetric form that stays regular at ``z_1 = z/2``,
  where the doubled (1/(n/2)) motion makes the plain linear system singular: the (2/n) motion
  born there at a period doubling is then a simple root, found to round-off.
- m = 3 (and any m = 2 root with a residual above tolerance): Newton on the full 2m-equation
  system with its analytic Jacobian, converged on the residual and the step; it stops at the
  round-off floor or when a step no longer cuts the residual, instead of drifting along the
  near-null direction where ``|mu - 1|`` is tiny.
- One orbit once: solutions closer than ``1e-7`` plus their uncertainty (round-off over the
  conditioning of the equations, ``kernels.uncertainty``) are one; a solution that is
  its own rotation within that tolerance is a shorter orbit traversed repeatedly (e.g. the
  doubled (1/1) motion among the (2/2) solutions; it is reported by the (1/1) call).
- Admissibility: the exact largest interior maximum of x on every flight, from the zeros of
  the velocity (``kernels.flight_max``).
- Stability: the analytic one-period Jacobian ``T = T_m ... T_1`` of the impact map, whose
  determinant is ``eps^(2m) exp(-2 zeta z)``.
- Map (``orbit_map``): rows of constant 1/beta run in parallel; along a row the solutions of
  the previous delta seed Newton (branch following). m = 2 also runs the global scan at every
  point; m = 3 runs it every ``kernels.MAP_SCAN_EVERY`` points, wherever a branch ends (and
  then at the points since the previous scan too, where the partner of a fold may have lived
  and died), and follows every branch a scan finds back to the previous scan.

Limits: for m = 3 the scan nodes keep a third of a step (~0.04 / max(beta, 1) in time) off the
edges of the interval triangle, so a (3/n) solution with a flight shorter than that (an orbit
at the edge of its existence, next to chatter) can be missed by a single call; the map may
still reach it by following its branch. In float64 the two orbits of a fold pair (m = 2) are
told apart down to ~1e-14 in delta from the fold (~1e-7 apart), and a (2/2k) motion whose
intervals differ by less than ~1e-7 of a forcing period (~1e-14 in delta from the period
doubling) counts as the doubled (1/k) motion.

eps = 0: every impact leaves the mass on the wall at rest; the motion is still a free flight
when the force pulls it off at once, and only then is it an orbit here (a flight whose
acceleration leaves the wall upward has an interior maximum above delta and is inadmissible;
impact-stick motions are not returned). The map is then rank one: ``T`` has a zero column,
``det T = 0``, one multiplier is 0 and ``lam = |tr T|^(1/m)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
import enum

import numba
import numpy as np

from vibroimpact import _checks
from vibroimpact._limits import MAX_M
from vibroimpact.model import Model
from vibroimpact.orbits import kernels as ok

__all__ = ["PeriodicOrbit", "periodic_orbits", "closed_form", "orbit_map", "Reason",
           "REASON_CODES"]

#: Rows per thread in one call of `orbit_map`'s kernel, between two reports of its progress:
#: Fig. 16's 141 x 226 map takes ~11 CPU-s, ~0.08 s a row, so a block is ~0.3 s on 2 idle
#: threads (~3 s under a load of 9 on 2 cores), well under the progress log's cadence. Each
#: block ends when its slower thread does; the rows are those the thread had in one call, so
#: that wait is the one call's imbalance spread over the blocks: measured (5 pairs, whole
#: process, benchmarks/progress_ab.py) main/blocks CPU 0.966 (0.94-0.99), wall 0.94
#: (0.65-1.30) on a machine loaded by other builds.
MAP_BLOCK_ROWS = 4


class Reason(enum.IntEnum):
    """Why a map point has no stable motion of a type (``orbit_map``'s ``reason``; Fig. 16).

    The values are those the kernels write (``kernels.REASON_*``) and the datasets store.
    """

    STABLE = ok.REASON_STABLE              #: a stable admissible solution exists
    NO_SOLUTION = ok.REASON_NO_SOLUTION    #: no solution of eqs. (10)-(11) (paper: D, V, X)
    INADMISSIBLE = ok.REASON_INADMISSIBLE  #: every solution's flight crosses the wall (eq. 13)
    UNSTABLE = ok.REASON_UNSTABLE          #: admissible solutions, none stable (eq. 22; paper: U)

    @property
    def description(self):
        return _REASON_TEXT[self]


_REASON_TEXT = {
    Reason.STABLE: "a stable admissible solution exists",
    Reason.NO_SOLUTION: "no solution of eqs. (10)-(11) with positive intervals and velocities",
    Reason.INADMISSIBLE: "solutions exist but none is admissible "
                         "(a flight crosses the wall, eq. 13)",
    Reason.UNSTABLE: "admissible solutions exist but none is stable (eq. 22)",
}
#: ``{code: description}`` of `Reason` (kept for the datasets' attributes and old callers).
REASON_CODES = {int(r): r.description for r in Reason}


@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """One (m/n) periodic impact motion under ``sin(beta tau)``.

    Attributes
    ----------
    m, n : int
        Impacts per period and forcing cycles per period.
    beta, delta, zeta, eps : float
        The parameter point.
    tau0 : float
        Instant of an impact reduced modulo ``2 pi / beta``; of the m impacts, the one with the
        smallest reduced phase.
    intervals : ndarray, shape (m,)
        Flight times ``z_1..z_m`` starting at ``tau0``; they sum to ``z = 2 pi n / beta``.
    velocities : ndarray, shape (m,)
        Approach velocities ``u_{j-0} > 0``; ``velocities[j]`` is at the impact that ends
        ``intervals[j]`` (so the impact at ``tau0`` has ``velocities[-1]``).
    multipliers : ndarray, complex, shape (2,)
        Eigenvalues ``mu`` of the one-period Jacobian, largest modulus first (eq. 19).
    jacobian : ndarray, shape (2, 2)
        The one-period Jacobian ``T`` of ``(tau, u) -> (tau, u)`` at the impact ``tau0``.
    lam : float
        ``max|mu|^(1/m)`` (eq. 20: ``mu = lambda^m``).
    S : float
        Degree of stability ``100 (1 - lam)`` in percent (eq. 24).
    stable : bool
        ``lam < 1`` (eq. 22).
    margin : float
        ``delta - max x`` over the interior local maxima of every flight (``inf`` if none);
        admissible orbits have ``margin >= 0`` (grazing is ``margin = 0``).
    admissible : bool
        No flight crosses the wall (eq. 13).
    """

    m: int
    n: int
    beta: float
    delta: float
    zeta: float
    eps: float
    tau0: float
    intervals: np.ndarray
    velocities: np.ndarray
    multipliers: np.ndarray
    jacobian: np.ndarray
    lam: float
    S: float
    stable: bool
    margin: float
    admissible: bool

    @property
    def period(self) -> float:
        """Period ``z = 2 pi n / beta`` of the motion."""
        return 2.0 * math.pi * self.n / self.beta

    @property
    def impact_times(self) -> np.ndarray:
        """Impact instants ``tau0, tau0 + z_1, ...`` over one period, shape (m,)."""
        return self.tau0 + np.concatenate(([0.0], np.cumsum(self.intervals)[:-1]))

    def state(self, tau):
        """Displacement and velocity ``(x, v)`` of the motion at the instants ``tau`` (any real).

        Just after an impact the velocity is the rebound ``-eps u``.
        """
        tau = np.asarray(tau, dtype=float)
        z = self.period
        starts = self.impact_times
        rel = np.mod(tau - self.tau0, z)
        j = np.searchsorted(np.cumsum(self.intervals), rel, side="right")
        j = np.minimum(j, self.m - 1)
        offset = rel - (starts[j] - self.tau0)
        flight_start = tau - offset            # the impact that began the current flight
        u_a = self.velocities[(j - 1) % self.m]
        wd, q, phi = ok.harmonic_constants(self.beta, self.zeta)
        x = np.empty_like(tau)
        v = np.empty_like(tau)
        for idx in np.ndindex(tau.shape):
            xs, vs = ok.flight(flight_start[idx], u_a[idx], offset[idx], self.beta, self.delta,
                               self.zeta, self.eps, wd, q, phi)[:2]
            x[idx] = xs
            v[idx] = vs
        return x, v


def _validate(m, n, beta, delta, zeta, eps):
    m = _checks.integer("m", m, low=1)
    n = _checks.integer("n", n, low=1)
    if m > MAX_M:
        raise NotImplementedError(f"m must be at most {MAX_M} (m = {m} is not supported)")
    beta = _checks.real("beta", beta, low=0.0, low_open=True)
    delta = _checks.real("delta", delta)
    return m, n, beta, delta, _checks.zeta(zeta), _checks.eps(eps)


def closed_form(model, solver="periodic_orbits"):
    """``(beta, delta, zeta, eps)`` of a `vibroimpact.Model` the closed form solves: one wall
    under Newton's law and the force ``sin(beta tau)`` (amplitude 1). Any other model is
    refused in one line that names the solver that takes it (`periodic_motions`)."""
    if not isinstance(model, Model):
        raise TypeError(f"model must be a vibroimpact.Model, got {type(model).__name__}")
    other = ([f"a second wall (gap {model.gap!r})"] if model.n_walls == 2 else []) + (
        [] if model.newton else ["a restitution that falls with the impact speed"]) + (
        [] if model.amplitude == 1.0 else [f"amplitude {model.amplitude!r}"])
    if other:
        raise ValueError(f"{solver} is the closed form of one wall under Newton's law and the "
                         f"force sin(beta tau); this model has {' and '.join(other)}: "
                         f"vibroimpact.periodic_motions(model, n) solves it")
    return model.beta, model.delta, model.zeta, model.eps


def _raw_solutions(m, n, beta, delta, zeta, eps):
    """Rows ``(tau_0..tau_{m-1}, u_0..u_{m-1})`` of every solution of eqs. (10)-(11)."""
    sols = np.empty((ok.MAX_SOLUTIONS, 2 * m + 1))     # the last column: uncertainty
    seeds = np.empty((1, 2 * m + 1))
    step = ok.SCAN_STEP_M2 if m == 2 else ok.SCAN_STEP_M3
    count = ok.solve_type(m, n, beta, delta, zeta, eps, seeds, 0, step, sols)
    return sols[:count, :2 * m]


def _make_orbit(y, m, n, beta, delta, zeta, eps):
    """Canonical ``PeriodicOrbit`` from a raw solution row (any first impact, any period)."""
    tf = 2.0 * math.pi / beta
    z = n * tf
    tau = np.asarray(y[:m], dtype=float)
    u = np.asarray(y[m:], dtype=float)
    phases = np.mod(tau, tf)
    phases[phases >= tf] = 0.0
    r = int(np.argmin(phases))
    order = (np.arange(m) + r) % m
    tau_c = tau[order] + np.where(order < r, z, 0.0)   # increasing instants from impact r
    u_c = u[order]
    tau0 = float(phases[r])
    tau_c = tau_c - tau_c[0] + tau0
    intervals = np.diff(np.append(tau_c, tau_c[0] + z))
    y_c = np.concatenate((tau_c, u_c))
    tmat = np.empty((2, 2))
    ok.monodromy(y_c, m, z, beta, delta, zeta, eps, tmat)
    mult = np.linalg.eigvals(tmat).astype(complex)
    mult = mult[np.argsort(-np.abs(mult), kind="stable")]
    lam = float(np.abs(mult[0]) ** (1.0 / m))
    stack = np.empty((ok.FLIGHT_STACK, 2))
    margin = float(ok.orbit_margin(y_c, m, z, beta, delta, zeta, eps, stack))
    return PeriodicOrbit(
        m=m, n=n, beta=beta, delta=delta, zeta=zeta, eps=eps, tau0=tau0,
        intervals=intervals, velocities=np.roll(u_c, -1), multipliers=mult, jacobian=tmat,
        lam=lam, S=100.0 * (1.0 - lam), stable=bool(lam < 1.0), margin=margin,
        admissible=bool(margin >= -ok.ADMISSIBLE_TOL),
    )


def periodic_orbits(m, n, beta=None, delta=None, zeta=None, eps=None, *, model=None,
                    include_inadmissible=False):
    """Every (m/n) periodic impact motion at one parameter point (paper section 4).

    Parameters
    ----------
    m, n : int
        Impacts per period and forcing cycles per period (m <= 3).
    beta : float
        Forcing frequency ratio (> 0); the force is ``sin(beta tau)``.
    delta : float
        Wall position (play), any finite value.
    zeta : float
        Damping ratio in (0, 1).
    eps : float
        Restitution coefficient in [0, 1].
    model : vibroimpact.Model, optional
        The parameter point as a model, in place of ``beta, delta, zeta, eps``: one wall under
        Newton's law, amplitude 1 (`closed_form`; any other is refused, naming
        `vibroimpact.periodic_motions`, which solves it).
    include_inadmissible : bool, optional
        Also return solutions whose flights cross the wall (``admissible=False``).

    Returns
    -------
    list of PeriodicOrbit
        Sorted by ``tau0``; no duplicates, no shorter orbit traversed repeatedly.

    Notes
    -----
    Eqs. (10)-(11) with positive intervals and velocities, filtered by eq. (13); stability by
    eqs. (14)-(24). See the module docstring for the method and for eps = 0.

    Examples
    --------
    The (1/1) motion at 1/beta = 1.1, delta = 0.5 (Fig. 16's point), and the determinant of
    its one-period Jacobian against eps^(2m) exp(-2 zeta z):

    >>> import numpy as np
    >>> from vibroimpact import periodic_orbits
    >>> (orbit,) = periodic_orbits(1, 1, 1 / 1.1, 0.5, 0.05, 0.5)
    >>> orbit.stable, round(orbit.lam, 4), round(float(orbit.velocities[0]), 4)
    (True, 0.3539, 2.1048)
    >>> bool(np.isclose(np.linalg.det(orbit.jacobian), 0.5**2 * np.exp(-2 * 0.05 * orbit.period)))
    True

    The same point as a model; a second wall is the shooting solver's:

    >>> from vibroimpact import Model
    >>> (same,) = periodic_orbits(1, 1, model=Model.paper(0.05, 0.5, 0.5, 1.0, 1 / 1.1))
    >>> (same.tau0, same.lam) == (orbit.tau0, orbit.lam)
    True
    >>> two_walls = Model.paper(0.05, 0.5, 0.5, 1.0, 1 / 1.1, gap=2.0)
    >>> periodic_orbits(1, 1, model=two_walls)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    ValueError: periodic_orbits is ... a second wall (gap 2.0): vibroimpact.periodic_motions(...
    """
    loose = dict(beta=beta, delta=delta, zeta=zeta, eps=eps)
    if model is not None:
        given = [k for k, v in loose.items() if v is not None]
        if given:
            raise TypeError(f"periodic_orbits takes a model or beta, delta, zeta, eps, not "
                            f"both (got model and {', '.join(given)})")
        beta, delta, zeta, eps = closed_form(model)
    elif any(v is None for v in loose.values()):
        missing = [k for k, v in loose.items() if v is None]
        raise TypeError(f"periodic_orbits needs beta, delta, zeta and eps (or model=): "
                        f"missing {', '.join(missing)}")
    m, n, beta, delta, zeta, eps = _validate(m, n, beta, delta, zeta, eps)
    orbits = [_make_orbit(y, m, n, beta, delta, zeta, eps)
              for y in _raw_solutions(m, n, beta, delta, zeta, eps)]
    if not include_inadmissible:
        orbits = [o for o in orbits if o.admissible]
    return sorted(orbits, key=lambda o: o.tau0)


def orbit_map(inv_beta, delta, types=((1, 1), (2, 1), (1, 2), (1, 3), (3, 1)), zeta=0.05,
              eps=0.5, *, progress=None):
    """Existence and stability of (m/n) motions over a ``(1/beta, delta)`` grid (Fig. 16).

    Parameters
    ----------
    inv_beta : array_like, shape (nb,)
        Values of ``1/beta`` (> 0).
    delta : array_like, shape (nd,)
        Values of the play ``delta``.
    types : sequence of (m, n)
        Motion types (m <= 3).
    zeta, eps : float
        Damping ratio and restitution coefficient.
    progress : callable, optional
        ``progress(k)`` after every block of rows solved (`MAP_BLOCK_ROWS` per thread), ``k``
        its cells: a job's progress log (`vibroimpact.pipeline.tasks.Progress.advance`).

    Returns
    -------
    dict of ndarray
        ``exists`` bool, ``n_solutions`` int (admissible), ``n_stable`` int, ``lam`` float
        (smallest ``lam`` among admissible solutions, NaN if none), ``S`` float
        (``100 (1 - lam)``), ``reason`` int8 (``REASON_CODES``), each of shape
        (n_types, nb, nd); and the coordinates ``inv_beta``, ``delta``, ``types`` (n_types, 2).

    Notes
    -----
    Each row of constant ``1/beta`` is one parallel task; along it the solutions of the previous
    ``delta`` seed Newton (branch following) in addition to the global interval scan, so a
    branch lost by the scan near a fold is still followed.

    Examples
    --------
    Stable (1/1) motions on a 2 x 3 grid (rows 1/beta, columns delta):

    >>> from vibroimpact import orbit_map
    >>> result = orbit_map([0.9, 1.1], [0.0, 0.5, 1.0], types=((1, 1),))
    >>> result["n_stable"][0].tolist()
    [[1, 1, 1], [0, 1, 1]]
    """
    inv_beta = np.ascontiguousarray(inv_beta, dtype=float).ravel()
    deltas = np.ascontiguousarray(delta, dtype=float).ravel()
    if inv_beta.size == 0 or not np.all(np.isfinite(inv_beta)) or np.any(inv_beta <= 0):
        raise ValueError("inv_beta must be a non-empty array of finite positive numbers")
    if deltas.size == 0 or not np.all(np.isfinite(deltas)):
        raise ValueError("delta must be a non-empty array of finite numbers")
    tarr = []
    if len(types) == 0:
        raise ValueError("types must hold at least one (m, n) pair")
    for t in types:
        if len(t) != 2:
            raise ValueError(f"types must be (m, n) pairs, got {t!r}")
        mm, nn, *_ = _validate(t[0], t[1], 1.0, 0.0, zeta, eps)
        tarr.append((mm, nn))
    _validate(1, 1, 1.0, 0.0, zeta, eps)
    tarr = np.array(tarr, dtype=np.int64).reshape(-1, 2)
    shape = (tarr.shape[0], inv_beta.size, deltas.size)
    exists = np.zeros(shape, dtype=np.bool_)
    n_sol = np.zeros(shape, dtype=np.int64)
    n_stab = np.zeros(shape, dtype=np.int64)
    lam = np.full(shape, np.nan)
    reason = np.zeros(shape, dtype=np.int8)
    threads = numba.get_num_threads()
    # rows interleaved over the threads (block lo.. runs row lo + t + k threads on thread t,
    # as one call over every row would): a block's rows are independent of the others, so
    # the blocks give the one call's numbers bit for bit, and each thread the same rows
    step = MAP_BLOCK_ROWS * threads
    for lo in range(0, inv_beta.size, step):
        block = np.arange(lo, min(lo + step, inv_beta.size))
        row_order = block[np.argsort((block - lo) % threads, kind="stable")]
        ok.map_kernel(inv_beta, deltas, tarr, float(zeta), float(eps), row_order, exists,
                      n_sol, n_stab, lam, reason)
        if progress is not None:
            progress(block.size * deltas.size)
    return {
        "exists": exists, "n_solutions": n_sol, "n_stable": n_stab, "lam": lam,
        "S": 100.0 * (1.0 - lam), "reason": reason,
        "inv_beta": inv_beta, "delta": deltas, "types": tarr,
    }
