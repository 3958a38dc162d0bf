"""Newton on the full 2m-equation system of an (m/n) motion (paper eqs. 10-11), with
its analytic Jacobian, and the uncertainty of a solution from the conditioning there.

The Jacobian's ``d/du_a`` columns carry the impact law's ``rebound_derivative``; its
``d/tau_a`` columns write the start's shift with ``-rebound_ratio(eps, ua) * ua`` for the
velocity ``-v_+`` (as :func:`vibroimpact.orbits.flight.impact_map_jacobian`), so they hold for
any law of :mod:`vibroimpact.model`.
"""
from math import sin

import numpy as np

from vibroimpact._law import rebound_derivative, rebound_ratio
from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import flight, harmonic_constants
from vibroimpact.orbits.linalg import _norm, _solve_inplace
from vibroimpact.orbits.tolerances import (NEWTON_GIVE_UP_IT, NEWTON_GIVE_UP_RTOL,
                                           NEWTON_LINE_SEARCH, NEWTON_MAXIT,
                                           NEWTON_POLISH_DECREASE, NEWTON_RTOL, NEWTON_STEP_RTOL,
                                           RESIDUAL_NOISE_RTOL, UNCERTAINTY_CAP,
                                           UNCERTAINTY_SAFETY)

#: Rows of the solvers' scratch ``work`` (shape ``(N_WORK, 2m)``): the residual, the Newton
#: step and the trial point of :func:`newton`.
WORK_RES, WORK_DY, WORK_TRY = range(3)
N_WORK = 3


@kernel
def _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac):
    """Residual of eqs. (10)-(11) for ``y = (tau_0..tau_{m-1}, u_0..u_{m-1})`` and its Jacobian."""
    nn = 2 * m
    for i in range(nn):
        for c in range(nn):
            jac[i, c] = 0.0
    for j in range(1, m + 1):
        a = j - 1
        b = j % m
        ta = y[a]
        ua = y[m + a]
        tb = y[b] + (z if j == m else 0.0)
        x, v, acc, p11, p12, p21, p22 = flight(ta, ua, tb - ta, beta, delta, zeta, eps,
                                               wd, q, phi)
        r1 = 2 * (j - 1)
        r2 = r1 + 1
        res[r1] = x - delta
        res[r2] = v - y[m + b]
        e_a = -rebound_ratio(eps, ua)                 # -v_+ = e_a ua
        g_a = delta - sin(beta * ta) - 2.0 * zeta * e_a * ua
        jac[r1, a] += p11 * e_a * ua + p12 * g_a
        jac[r2, a] += p21 * e_a * ua + p22 * g_a
        jac[r1, m + a] += rebound_derivative(eps, ua) * p12
        jac[r2, m + a] += rebound_derivative(eps, ua) * p22
        jac[r1, b] += v
        jac[r2, b] += acc
        jac[r2, m + b] += -1.0


@kernel
def newton(y, m, z, beta, delta, zeta, eps, scale, res, jac, dy, ytry):
    """Damped Newton with the analytic Jacobian, in place on ``y``.

    Returns ``(converged, residual norm at y)``. Converged means a residual <= NEWTON_RTOL
    times ``scale`` *and* a settled position: Newton goes on below that tolerance while full
    steps keep cutting the residual (by NEWTON_POLISH_DECREASE at least) and stops on a step
    of a few ulps, at the round-off floor (RESIDUAL_NOISE_RTOL) or when a step no longer
    helps; a step that does not help is not taken (near a singular Jacobian it would only
    carry the solution along the near-null direction, by noise / |mu - 1|).
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    nn = 2 * m
    tol = NEWTON_RTOL * scale
    floor_ = RESIDUAL_NOISE_RTOL * scale
    _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
    nr = _norm(res, nn)
    for it in range(NEWTON_MAXIT):
        if not np.isfinite(nr) or (it >= NEWTON_GIVE_UP_IT and nr > NEWTON_GIVE_UP_RTOL * scale):
            return False, nr
        if nr <= floor_:
            return True, nr
        for i in range(nn):
            dy[i] = -res[i]
        if not _solve_inplace(jac, dy, nn):
            return nr <= tol, nr
        polishing = nr <= tol
        step = 1.0
        accepted = False
        nt = nr
        for _ in range(1 if polishing else NEWTON_LINE_SEARCH):
            for i in range(nn):
                ytry[i] = y[i] + step * dy[i]
            _residual_jacobian(ytry, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
            nt = _norm(res, nn)
            if polishing:
                accepted = nt <= NEWTON_POLISH_DECREASE * nr
                break
            if nt < nr:
                accepted = True
                break
            step *= 0.5
        if not accepted:
            return nr <= tol, nr               # y unchanged (res, jac: the rejected trial)
        small = True
        for i in range(nn):
            if abs(ytry[i] - y[i]) > NEWTON_STEP_RTOL * (1.0 + abs(y[i])):
                small = False
            y[i] = ytry[i]
        nr = nt
        if small and nr <= tol:
            return True, nr
    return nr <= tol, nr


@kernel
def uncertainty(y, m, z, beta, delta, zeta, eps, scale, tf, uscale):
    """Error bound of the solution ``y`` in the units of SAME_ORBIT_RTOL (phase / T_f,
    velocity / uscale), from the conditioning of eqs. (10)-(11) there.

    ``UNCERTAINTY_SAFETY * max_i sum_j |J^-1_ij| (|res| + noise)`` over the phases (over
    ``tf``) and the velocities (over ``uscale``), capped at UNCERTAINTY_CAP. Next to a fold or
    a period doubling (|mu - 1| small) round-off alone leaves a Newton solution this far off.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    nn = 2 * m
    res = np.empty(nn)
    jac = np.empty((nn, nn))
    a = np.empty((nn, nn))
    col = np.empty(nn)
    rows = np.zeros(nn)
    _residual_jacobian(y, m, z, beta, delta, zeta, eps, wd, q, phi, res, jac)
    err = _norm(res, nn) + RESIDUAL_NOISE_RTOL * scale
    for c in range(nn):
        for i in range(nn):
            for k in range(nn):
                a[i, k] = jac[i, k]
            col[i] = 0.0
        col[c] = 1.0
        if not _solve_inplace(a, col, nn):
            return UNCERTAINTY_CAP
        for i in range(nn):
            rows[i] += abs(col[i])
    worst = 0.0
    for i in range(m):
        worst = max(worst, rows[i] / tf, rows[m + i] / uscale)
    bound = UNCERTAINTY_SAFETY * worst * err
    if not bound < UNCERTAINTY_CAP:             # also NaN
        return UNCERTAINTY_CAP
    return bound
