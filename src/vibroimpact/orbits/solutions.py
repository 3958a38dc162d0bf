"""One orbit once: the set of solutions at a parameter point, with duplicates (within
their uncertainty) and shorter orbits traversed repeatedly left out.
"""
from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.newton import WORK_DY, WORK_RES, WORK_TRY, newton, uncertainty
from vibroimpact.orbits.tolerances import SAME_ORBIT_RTOL


@kernel
def _circ_dist(a, b, period):
    d = abs(a - b) % period
    return min(d, period - d)


@kernel
def _same_orbit(ya, yb, m, shift, tf, uscale, tol):
    """True when ``yb`` rotated by ``shift`` impacts is ``ya`` within ``tol`` (phases mod T_f
    over T_f, velocities over ``uscale``)."""
    for j in range(m):
        k = (j + shift) % m
        if _circ_dist(ya[j], yb[k], tf) > tol * tf:
            return False
        if abs(ya[m + j] - yb[m + k]) > tol * uscale:
            return False
    return True


@kernel
def _valid(y, m, z):
    """Positive approach velocities and increasing impact instants within one period."""
    for j in range(m):
        if not (y[m + j] > 0.0):
            return False
    for j in range(1, m):
        if not (y[j] - y[j - 1] > 0.0):
            return False
    return y[0] + z - y[m - 1] > 0.0


@kernel
def _accept(y, rho, rep_rho, m, z, tf, uscale, sols, count):
    """Append ``y`` (uncertainty ``rho``) to ``sols`` unless invalid, a duplicate, or a
    repeated shorter orbit; returns the new count.

    Rows of ``sols`` are ``(tau.., u.., rho)``. Two solutions are one orbit when they agree
    within ``SAME_ORBIT_RTOL + rho_a + rho_b`` (the uncertainty of a Newton solution grows like
    noise / |mu - 1| next to a fold or a period doubling); the better-conditioned copy is kept.
    ``y`` is a shorter orbit traversed repeatedly (e.g. the doubled (1/1) motion among the
    (2/2) solutions) when it is its own rotation within ``SAME_ORBIT_RTOL + 2 rep_rho``: pass
    ``rep_rho = rho`` for a Newton solution, 0 for one whose intervals are exact (the m = 2
    scan's, whose circle condition stays regular at the doubled motion).
    """
    if not _valid(y, m, z):
        return count
    nn = 2 * m
    for r in range(1, m):
        if _same_orbit(y, y, m, r, tf, uscale, SAME_ORBIT_RTOL + 2.0 * rep_rho):
            return count                       # a shorter orbit traversed m/r times
    for i in range(count):
        tol = SAME_ORBIT_RTOL + rho + sols[i, nn]
        for r in range(m):
            if _same_orbit(sols[i], y, m, r, tf, uscale, tol):
                if rho < sols[i, nn]:
                    for c in range(nn):
                        sols[i, c] = y[c]
                    sols[i, nn] = rho
                return count
    if count >= sols.shape[0]:
        return count
    for c in range(nn):
        sols[count, c] = y[c]
    sols[count, nn] = rho
    return count + 1


@kernel
def _try_start(y, m, z, beta, delta, zeta, eps, scale, tf, uscale, sols, count, work, jac):
    """Newton from ``y``; a converged, valid solution goes to ``_accept``."""
    res = work[WORK_RES]
    dy = work[WORK_DY]
    ytry = work[WORK_TRY]
    conv, _ = newton(y, m, z, beta, delta, zeta, eps, scale, res, jac, dy, ytry)
    if conv and _valid(y, m, z):
        rho = uncertainty(y, m, z, beta, delta, zeta, eps, scale, tf, uscale)
        count = _accept(y, rho, rho, m, z, tf, uscale, sols, count)
    return count
