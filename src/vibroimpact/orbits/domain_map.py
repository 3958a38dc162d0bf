"""The domain map (Fig. 16): rows of constant 1/beta in parallel, branches followed
along delta, each point classified (stable, unstable, inadmissible, no solution).
"""
from math import pi

import numpy as np
from numba import prange

from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import harmonic_constants, lam_of, monodromy, orbit_margin
from vibroimpact.orbits.newton import (N_WORK, WORK_DY, WORK_RES, WORK_TRY, newton,
                                        uncertainty)
from vibroimpact.orbits.solutions import _accept, _valid
from vibroimpact.orbits.solve import solve_type
from vibroimpact.orbits.tolerances import (ADMISSIBLE_TOL, FLIGHT_STACK, MAP_SCAN_EVERY,
                                           MAP_SCAN_STEP_M2, MAP_SCAN_STEP_M3, MAX_SOLUTIONS,
                                           REASON_INADMISSIBLE, REASON_NO_SOLUTION, REASON_STABLE,
                                           REASON_UNSTABLE)


@kernel
def _follow_back(y0, m, n, beta, deltas, d_from, d_stop, zeta, eps, sols, counts, work, jac):
    """Continue the solution ``y0`` (at ``deltas[d_from]``) down to ``d_stop``, adding it where
    it is missing; stops when Newton fails or the branch is already known there."""
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    tf = 2.0 * pi / beta
    nn = 2 * m
    y = np.empty(nn)
    for c in range(nn):
        y[c] = y0[c]
    for dd in range(d_from - 1, d_stop - 1, -1):
        delta = deltas[dd]
        scale = 1.0 + abs(delta) + q * (1.0 + beta)
        conv, _ = newton(y, m, z, beta, delta, zeta, eps, scale, work[WORK_RES], jac,
                         work[WORK_DY], work[WORK_TRY])
        if not conv or not _valid(y, m, z):
            return
        rho = uncertainty(y, m, z, beta, delta, zeta, eps, scale, tf, scale)
        before = counts[dd]
        counts[dd] = _accept(y, rho, rho, m, z, tf, scale, sols[dd], before)
        if counts[dd] == before:
            return


@kernel
def _map_row(ib, beta, deltas, types, zeta, eps, exists, n_sol, n_stab, lam_best, reason):
    """One row of the map: all types at ``beta`` for every delta.

    For m = 2 the global interval scan runs at every point, as in ``periodic_orbits``. For
    m = 3 it runs every ``MAP_SCAN_EVERY`` points of delta (and at the last, and wherever a
    branch ends); in between, the solutions of the previous point seed Newton (branch following
    upward in delta), and every solution found by a scan is followed back down to the previous
    scan, so a branch born between two scans is filled in as well. Where a branch ends between
    two scans, the points since the last scan are scanned too: the partner of a fold that was
    born and died between two scans (next to a zero impact velocity) is found there.
    """
    nd = deltas.shape[0]
    stack = np.empty((FLIGHT_STACK, 2))
    tmat = np.empty((2, 2))
    for t in range(types.shape[0]):
        m = types[t, 0]
        n = types[t, 1]
        nn = 2 * m
        z = 2.0 * pi * n / beta
        sols = np.empty((nd, MAX_SOLUTIONS, nn + 1))   # rows (tau.., u.., uncertainty)
        seeds = np.empty((MAX_SOLUTIONS, nn + 1))
        counts = np.zeros(nd, dtype=np.int64)
        work = np.empty((N_WORK, nn))
        jac = np.empty((nn, nn))
        scan_step = MAP_SCAN_STEP_M2 if m == 2 else MAP_SCAN_STEP_M3
        last_scan = 0
        for d in range(nd):
            prev = d - 1 if d > 0 else 0
            nseed = counts[prev] if d > 0 else 0
            scan = m == 2 or d % MAP_SCAN_EVERY == 0 or d == nd - 1
            if m == 2:
                counts[d] = solve_type(m, n, beta, deltas[d], zeta, eps, sols[prev], nseed,
                                       scan_step, sols[d])
            else:
                counts[d] = solve_type(m, n, beta, deltas[d], zeta, eps, sols[prev], nseed,
                                       0.0, sols[d])
            # m = 3: a branch of the previous point not continued (a fold or an impact
            # velocity reaching zero) ends here, whether or not another starts
            ended = m > 2 and counts[d] < nseed
            if m > 2 and (scan or ended):
                scan = True
                counts[d] = solve_type(m, n, beta, deltas[d], zeta, eps, sols[prev], nseed,
                                       scan_step, sols[d])
            if ended:
                # at a fold its partner ended with it: born between the last scan and d (at
                # a zero impact velocity, say) it was never seen. Scan the points in between,
                # each seeded with what it holds, and follow what they find back.
                for dd in range(d - 1, last_scan, -1):
                    held = counts[dd]
                    for s in range(held):
                        for c in range(nn + 1):
                            seeds[s, c] = sols[dd, s, c]
                    counts[dd] = solve_type(m, n, beta, deltas[dd], zeta, eps, seeds, held,
                                            scan_step, sols[dd])
                    for s in range(counts[dd]):
                        _follow_back(sols[dd, s], m, n, beta, deltas, dd, last_scan + 1,
                                     zeta, eps, sols, counts, work, jac)
            if scan and m > 1 and d > 0:
                d_stop = max(0, last_scan)
                last_scan = d
                for s in range(counts[d]):
                    _follow_back(sols[d, s], m, n, beta, deltas, d, d_stop, zeta, eps, sols,
                                 counts, work, jac)
        for d in range(nd):
            delta = deltas[d]
            n_adm = 0
            n_st = 0
            best = np.inf
            for s in range(counts[d]):
                y = sols[d, s]
                if orbit_margin(y, m, z, beta, delta, zeta, eps, stack) < -ADMISSIBLE_TOL:
                    continue
                n_adm += 1
                monodromy(y, m, z, beta, delta, zeta, eps, tmat)
                lam = lam_of(tmat, m)
                if lam < 1.0:
                    n_st += 1
                best = min(best, lam)
            exists[t, ib, d] = n_adm > 0
            n_sol[t, ib, d] = n_adm
            n_stab[t, ib, d] = n_st
            lam_best[t, ib, d] = best if n_adm > 0 else np.nan
            if n_st > 0:
                reason[t, ib, d] = REASON_STABLE
            elif counts[d] == 0:
                reason[t, ib, d] = REASON_NO_SOLUTION
            elif n_adm == 0:
                reason[t, ib, d] = REASON_INADMISSIBLE
            else:
                reason[t, ib, d] = REASON_UNSTABLE


@kernel(parallel=True)
def map_kernel(inv_beta, deltas, types, zeta, eps, row_order, exists, n_sol, n_stab, lam_best,
               reason):
    """Fill the domain-map arrays, one row of ``inv_beta`` per task, continuing along delta.

    ``row_order`` is a permutation of the rows: the cost of a row grows with 1/beta, so
    interleaving the rows balances the threads' contiguous chunks.
    """
    for k in prange(row_order.shape[0]):
        ib = row_order[k]
        _map_row(ib, 1.0 / inv_beta[ib], deltas, types, zeta, eps, exists, n_sol, n_stab,
                 lam_best, reason)
