"""Numba kernels of :func:`vibroimpact.attractors.attractor_map`: many starts of the
forced impact oscillator, each run by the simulator's own sample loop until it settles, with
its tangent dynamics along the way.

Every start is stepped by :func:`vibroimpact.impact.stepping.run_steps` on a zero noise record
with the harmonic force ``sin(beta tau)`` (exact between samples; impacts, chatter, sticking
and grazing touches exactly as :func:`vibroimpact.simulate` treats them), one forcing period
per call; after each call its new events go into a ring of recent impacts and sticking
events, the tangent vectors are carried across them, and the settling tests run
(:func:`_run_start`). The stable solver orbits of every cell come from
:func:`vibroimpact.orbits.solve.solve_type` (as :func:`vibroimpact.periodic_orbits` calls it),
filtered for admissibility and stability in :func:`cell_orbits`.

The numba cache of these kernels is stamped with the orbit solver's kernel modules and the
simulator's (their code is compiled into these kernels).
"""
import math

from numba import njit, prange
import numpy as np

from vibroimpact._kernel_cache import kernel_decorator, package_modules
from vibroimpact._law import rebound_derivative, rebound_ratio, rebound_velocity
from vibroimpact.impact.layout import (BUFFER_FULL, FREE, N_COUNTERS, N_FTOT, N_PARAMS,
                                       N_STATE, OK, P_AQ, P_BETA, P_BH_HI, P_BH_LO, P_DELTA,
                                       P_PHI, S_COS_PSI, S_MODE, S_SIN_PSI, S_W, S_WV, STICK_LO,
                                       STICK_ON, STUCK, STUCK_LO)
from vibroimpact.impact.motion import phase
from vibroimpact.impact.parameters import parameters
from vibroimpact.impact.stepping import run_steps
from vibroimpact.impact.tolerances import STEP_HEADROOM
from vibroimpact.orbits.flight import (flight_max, harmonic_constants, lam_of, monodromy,
                                      orbit_margin, propagator)
from vibroimpact.orbits.intervals import fill_interval_system, start_from_intervals
from vibroimpact.orbits.linalg import cofactors
from vibroimpact.orbits.newton import N_WORK
from vibroimpact.orbits.scan_m3 import bilinear_root
from vibroimpact.orbits.solve import solve_type
from vibroimpact.orbits.tolerances import (ADMISSIBLE_TOL, FLIGHT_STACK, M3_CIRCLE_NEAR,
                                           M3_MIN_NODES, M3_NODE_OFFSET, MAX_SOLUTIONS,
                                           SCAN_STEP_M2, SCAN_STEP_M3)

#: Stamped with this file and every kernel module of the orbit solver and the simulator that
#: these kernels inline (:mod:`vibroimpact._kernel_cache`): an edit of any recompiles them.
kernel = kernel_decorator(
    njit, __file__,
    ("kernels.py",) + package_modules("orbits", "impact"),
    error_model="numpy")

# --- constants ------------------------------------------------------------------------------
#: Stable solver orbits kept per type and cell (a cell has rarely more than two).
K_ORBITS = 8
#: Largest m of the solver (``vibroimpact._limits.MAX_M``).
M_COLS = 3
#: Returns over which a settled motion must repeat (or match its solver orbit): "persistently
#: over a few periods".
REPEATS = 3
#: Periods of the forcing a repeating motion may span (the k of a periodic motion m'/k).
MAX_PERIODS = 6
#: Impacts a period may hold (an impact-stick motion resolves ~15 rebounds per chatter).
MAX_PER_PERIOD = 256
#: Ring of recent impacts (>= (REPEATS + 1) MAX_PER_PERIOD) and of sticking events.
RING = 2048
STICK_RING = 512
#: A motion periodic within the tolerance but within LOOSE x tolerance of a stable solver orbit
#: is still converging to it: it is run on, not called "periodic_other".
LOOSE = 1e3
#: Samples per forcing period at least, and the largest sample step: the zero noise record only
#: sets where the exclusion test runs (the motion is exact whatever the step).
STEPS_PER_PERIOD = 16
MAX_STEP = 0.2
#: A start at t0 is moved on by whole forcing periods to at least this many nominal steps, so
#: that the step h = t0 / k0 (the start on a sample point) is within 6 % of the nominal one.
MIN_START_STEPS = 8
#: Benettin: the first quarter of the capped run is transient, the rest is cut into batches.
BENETTIN_FROM = 0.25
N_BATCHES = 8
#: An impact slot is compacted once this many are in the simulator's buffer.
COMPACT = 4096
#: Buffer capacity: run_steps wants STEP_HEADROOM free slots before every slow step.
CAPACITY = 2 * STEP_HEADROOM + COMPACT
#: "Chaotic": the largest exponent exceeds this many standard errors (batch means, 7 dof).
CHAOS_SIGMAS = 3.0

# classes (attractors.CLASSES); the wall-free response came last, so codes 0-4 kept their meaning
LISTED, PERIODIC_OTHER, STICKING, CHAOTIC, UNDECIDED, WALL_FREE = 0, 1, 2, 3, 4, 5
# per-start float results
# F_IMPACTS_LO: of F_IMPACTS, those at the lower wall (0 with one wall)
(F_SETTLE, F_LYAP1, F_LYAP2, F_STDERR, F_RATE, F_IMPACTS, F_WINDOW, F_STEP, F_T0,
 F_IMPACTS_LO) = range(10)
N_F = 10
# per-start integer results
I_MOTION, I_CLASS, I_STICK_M, I_STICK_P, I_STATUS, I_PERIOD_M, I_PERIOD_P = range(7)
N_I = 7


@kernel
def orbit_floor(y, m, z, beta, delta, zeta, eps, stack):
    """Lowest point ``min x`` over the flights of the solver orbit ``y`` (``inf`` if none has
    an interior minimum): :func:`vibroimpact.orbits.flight.flight_max` in the mirrored frame.

    ``-x`` is the flight of the same oscillator under ``sin(beta (tau + pi / beta))`` from
    the wall at ``-delta`` with approach velocity ``-u`` (Newton's law is odd in ``u``).
    """
    shift = math.pi / beta
    worst = -np.inf
    for j in range(1, m + 1):
        a = j - 1
        b = j % m
        tb = y[b] + (z if j == m else 0.0)
        worst = max(worst, flight_max(y[a] + shift, -y[m + a], tb - y[a], beta, -delta, zeta,
                                      eps, stack))
    return -worst


@kernel(parallel=True)
def cell_orbits(inv_beta, deltas, types, zeta, eps, n_stable, orb_ph, orb_u, orb_z, orb_lnmu,
                clearance, rows):
    """The stable admissible solver orbits of every cell and type, in parallel over the
    1/beta rows, taken in the order ``rows`` (the costliest first: the m = 3 scan grows with
    1/beta, so that the last rows to finish are the cheap ones).

    As :func:`vibroimpact.periodic_orbits`: ``solve_type`` with the same scan steps, admissible
    when ``orbit_margin >= -ADMISSIBLE_TOL``, stable when ``lam_of(T) < 1``; with a finite
    ``clearance``, also above the wall at ``delta - clearance`` (:func:`orbit_floor`), so
    that the orbit is one of the two-wall oscillator, with the same multipliers. Per orbit:
    ``orb_ph`` the impact phases ``(tau_j mod T_f) / T_f``, ``orb_u`` the approach velocities,
    ``orb_z`` the interval from impact j to j + 1, ``orb_lnmu`` ``ln max|mu|``.

    An m = 3 type is solved as ``solve_type`` does it (``_scan_m3``, no seeds) with the scan's
    node values that do not depend on delta (``det K`` and the null vector of K at fixed
    intervals) computed once per row (:func:`_m3_nodes`) and shared by its cells
    (:func:`_m3_cell`): the same operations on the same numbers, bit for bit.
    """
    nd = deltas.shape[0]
    for r in prange(rows.shape[0]):
        ib = rows[r]
        beta = 1.0 / inv_beta[ib]
        stack = np.empty((FLIGHT_STACK, 2))
        tmat = np.empty((2, 2))
        for t in range(types.shape[0]):
            m = types[t, 0]
            n = types[t, 1]
            sols = np.empty((MAX_SOLUTIONS, 2 * m + 1))
            seeds = np.empty((1, 2 * m + 1))
            step = SCAN_STEP_M2 if m == 2 else SCAN_STEP_M3
            if m == 3:
                wd = harmonic_constants(beta, zeta)[0]
                npt = max(M3_MIN_NODES,
                          int(math.ceil(2.0 * math.pi * n / beta * max(beta, wd) / step)))
                f1 = np.empty((npt + 1, npt + 1))
                hyp = np.empty((npt + 1, npt + 1))
                wt = np.empty((npt + 1, npt + 1))
                _m3_nodes(n, beta, zeta, eps, npt, f1, hyp, wt)
            else:
                f1 = hyp = wt = np.empty((0, 0))
            for idd in range(nd):
                delta = deltas[idd]
                if m == 3:
                    cnt = _m3_cell(n, beta, delta, zeta, eps, f1, hyp, wt, sols)
                else:
                    cnt = solve_type(m, n, beta, delta, zeta, eps, seeds, 0, step, sols)
                _keep_stable(cnt, sols, m, n, beta, delta, zeta, eps, clearance, stack, tmat,
                             t, ib, idd, n_stable, orb_ph, orb_u, orb_z, orb_lnmu)


@kernel
def _m3_nodes(n, beta, zeta, eps, npt, f1, hyp, wt):
    """The node values of ``vibroimpact.orbits.scan_m3._scan_m3`` that do not depend on
    delta, on its ``npt`` grid: ``f1`` (normalised ``det K``), and of the null vector ``w`` of
    rows 1-5, ``hyp = |w_SC|`` and ``wt = w_t`` (what its ``_circle_factors`` reads). The
    same statements as there (K does not involve delta: ``fill_interval_system`` ignores it).
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * math.pi * n / beta
    m = 3
    nn = 2 * m
    ncol = m + 3
    kmat = np.empty((nn, ncol))
    sub = np.empty((nn, ncol))
    nvec = np.empty(ncol)
    zs = np.empty(m)
    hz = z / npt
    for i in range(npt + 1):
        for k in range(npt + 1 - i):
            zs[0] = (i + M3_NODE_OFFSET) * hz
            zs[1] = (k + M3_NODE_OFFSET) * hz
            zs[2] = z - zs[0] - zs[1]
            fill_interval_system(zs, m, beta, 0.0, zeta, eps, wd, kmat)
            cofactors(kmat, 1, ncol, sub, nvec)
            det = 0.0
            cn = 0.0
            rn = 0.0
            for c in range(ncol):
                det += kmat[0, c] * nvec[c]
                cn += nvec[c] * nvec[c]
                rn += kmat[0, c] * kmat[0, c]
            norm = math.sqrt(cn * rn)
            f1[i, k] = det / norm if norm > 0.0 else 0.0
            hyp[i, k] = math.hypot(nvec[0], nvec[1])
            wt[i, k] = nvec[ncol - 1]


@kernel
def _circle_at(hyp, wt, delta, q):
    """``vibroimpact.orbits.intervals._circle_factors`` from ``|w_SC|`` and ``w_t``."""
    r = abs(delta) * hyp
    t = q * wt
    if delta < 0.0:
        r = -r
    norm = math.hypot(r, t)
    if norm == 0.0:
        return 0.0, 0.0
    return (t - r) / norm, (t + r) / norm


@kernel
def _m3_cell(n, beta, delta, zeta, eps, f1, hyp, wt, sols):
    """``solve_type(3, n, ...)`` without seeds (``_scan_m3``'s second pass) on the node
    values of :func:`_m3_nodes`; returns the count of solutions in ``sols``."""
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * math.pi * n / beta
    m = 3
    nn = 2 * m
    ncol = m + 3
    npt = f1.shape[0] - 1
    hz = z / npt
    count = 0
    work = np.empty((N_WORK, nn))
    jac = np.empty((nn, nn))
    y = np.empty(nn)
    kmat = np.empty((nn, ncol))
    sub = np.empty((nn, ncol))
    nvec = np.empty(ncol)
    zs = np.empty(m)
    f2 = np.empty((2, npt + 1, npt + 1))
    for i in range(npt + 1):
        for k in range(npt + 1 - i):
            f2[0, i, k], f2[1, i, k] = _circle_at(hyp[i, k], wt[i, k], delta, q)
    for i in range(npt):
        for k in range(npt - i):
            a00, a10, a01 = f1[i, k], f1[i + 1, k], f1[i, k + 1]
            a11 = f1[i + 1, k + 1] if i + k + 2 <= npt else a10 + a01 - a00
            if min(min(a00, a10), min(a01, a11)) > 0.0 or max(max(a00, a10), max(a01, a11)) < 0.0:
                continue
            for f in range(2):
                b00, b10, b01 = f2[f, i, k], f2[f, i + 1, k], f2[f, i, k + 1]
                b11 = f2[f, i + 1, k + 1] if i + k + 2 <= npt else b10 + b01 - b00
                lo2 = min(min(b00, b10), min(b01, b11))
                hi2 = max(max(b00, b10), max(b01, b11))
                if (lo2 > 0.0 or hi2 < 0.0) and min(abs(lo2), abs(hi2)) > M3_CIRCLE_NEAR:
                    continue
                ok_, si, ti = bilinear_root(a00, a10, a01, a11, b00, b10, b01, b11)
                if not ok_:
                    continue
                zs[0] = (i + M3_NODE_OFFSET + si) * hz
                zs[1] = (k + M3_NODE_OFFSET + ti) * hz
                zs[2] = z - zs[0] - zs[1]
                if zs[0] <= 0.0 or zs[1] <= 0.0 or zs[2] <= 0.0:
                    continue
                count = start_from_intervals(zs, m, n, beta, delta, zeta, eps,
                                              1.0 if f == 0 else -1.0, kmat, sub, nvec, y,
                                              sols, count, work, jac)
    return count


@kernel
def _keep_stable(cnt, sols, m, n, beta, delta, zeta, eps, clearance, stack, tmat, t, ib, idd,
                 n_stable, orb_ph, orb_u, orb_z, orb_lnmu):
    """The stable admissible ones of the ``cnt`` solutions of type ``t`` at cell ``(ib,
    idd)`` into the arrays of :func:`cell_orbits`."""
    tf = 2.0 * math.pi / beta
    z = n * tf
    ns = 0
    for s in range(cnt):
        y = sols[s, :2 * m]
        if orbit_margin(y, m, z, beta, delta, zeta, eps, stack) < -ADMISSIBLE_TOL:
            continue
        if clearance < np.inf and (orbit_floor(y, m, z, beta, delta, zeta, eps, stack)
                                   < delta - clearance + ADMISSIBLE_TOL):
            continue
        monodromy(y, m, z, beta, delta, zeta, eps, tmat)
        lam = lam_of(tmat, m)
        if not lam < 1.0:
            continue
        if ns < K_ORBITS:
            for j in range(m):
                ph = y[j] / tf
                orb_ph[ib, idd, t, ns, j] = ph - math.floor(ph)
                orb_u[ib, idd, t, ns, j] = y[m + j]
                nxt = y[j + 1] if j + 1 < m else y[0] + z
                orb_z[ib, idd, t, ns, j] = nxt - y[j]
            orb_lnmu[ib, idd, t, ns] = m * math.log(lam)
        ns += 1
    n_stable[t, ib, idd] = ns


@kernel
def start_step(beta, theta):
    """``(h, k0, t0)``: the sample step and the start's sample index, ``t0 = k0 h``, with
    ``sin(beta t0) = sin(theta)``: ``t0 = theta / beta`` moved on by whole forcing periods to
    at least MIN_START_STEPS nominal steps (``k0 = 0``, the nominal step, when theta = 0)."""
    tf = 2.0 * math.pi / beta
    h_nom = min(MAX_STEP, tf / STEPS_PER_PERIOD)
    t0 = theta / beta
    if t0 == 0.0:
        return h_nom, 0, 0.0
    floor_t = MIN_START_STEPS * h_nom
    if t0 < floor_t:
        t0 += math.ceil((floor_t - t0) / tf) * tf
    k0 = int(round(t0 / h_nom))
    return t0 / k0, k0, t0


@kernel
def _circ(a, b):
    d = abs(a - b) % 1.0
    return min(d, 1.0 - d)


@kernel
def _dt(rk, rs, i, j, h):
    """Time from impact j to impact i (ring slots), in the split form's precision."""
    return (rk[i % RING] - rk[j % RING]) * h + (rs[i % RING] - rs[j % RING])


@kernel
def _match_orbit(rk, rs, ru, rph, n_imp, h, tf, t_now_k, m, oph, ou, oz, tol, last_stick,
                 lower):
    """Whether the last REPEATS m impacts follow the solver orbit (``oph, ou, oz``) within
    ``tol``: phase / T_f, velocity relative to ``1 + |u|``, every interval / T_f; no sticking
    in between, and no impact missing at the end (``t_now`` is within one interval of the
    last impact). With ``lower`` the orbit is one of the wall below, solved in the mirrored
    frame ``x -> -x`` (:func:`vibroimpact.attractors.api.stable_orbits`): its impacts are
    met half a forcing period later (the force ``-sin(beta tau)`` of that frame is
    ``sin(beta (tau + T_f / 2))``) with the lab-frame velocity ``-u``."""
    L = REPEATS * m
    if n_imp < L or L > RING:
        return False
    shift = 0.5 if lower else 0.0
    sign = -1.0 if lower else 1.0
    i0 = n_imp - L
    t_first = rk[i0 % RING] * h + rs[i0 % RING]
    if last_stick >= t_first:
        return False
    for j0 in range(m):
        if _circ(rph[i0 % RING], oph[j0] + shift) > tol:
            continue
        if abs(ru[i0 % RING] - sign * ou[j0]) > tol * (1.0 + ou[j0]):
            continue
        ok = True
        for l in range(1, L):
            i = i0 + l
            j = (j0 + l) % m
            jp = (j0 + l - 1) % m
            if (_circ(rph[i % RING], oph[j] + shift) > tol
                    or abs(ru[i % RING] - sign * ou[j]) > tol * (1.0 + ou[j])
                    or abs(_dt(rk, rs, i, i - 1, h) - oz[jp]) > tol * tf):
                ok = False
                break
        if not ok:
            continue
        jl = (j0 + L - 1) % m
        i_last = n_imp - 1
        gap = (t_now_k - rk[i_last % RING]) * h - rs[i_last % RING]
        if gap <= oz[jl] + tol * tf:
            return True
    return False


@kernel
def _period_of(rk, rs, ru, n_imp, h, tf, t_now_k, p, tol):
    """m' > 0 when the last REPEATS + 1 returns of the impact sequence repeat with period
    ``p`` forcing periods and m' impacts (instants shifted by p T_f and velocities equal,
    within ``tol`` relative to ``1 + |u|``, at either wall), 0 otherwise."""
    if n_imp < 2:
        return 0
    last = n_imp - 1
    zp = p * tf
    mm = 0
    for back in range(1, min(MAX_PER_PERIOD, n_imp - 1) + 1):
        d = _dt(rk, rs, last, last - back, h)
        if abs(d - zp) <= tol * tf:
            mm = back
            break
        if d > zp + tol * tf:
            return 0
    if mm == 0:
        return 0
    L = REPEATS * mm
    if last - L - mm < 0 or L + mm >= RING or last - L - mm < n_imp - RING:
        return 0
    for i in range(last, last - L, -1):
        if abs(_dt(rk, rs, i, i - mm, h) - zp) > tol * tf:
            return 0
        if abs(ru[i % RING] - ru[(i - mm) % RING]) > tol * (1.0 + abs(ru[i % RING])):
            return 0
    gap = (t_now_k - rk[last % RING]) * h - rs[last % RING]
    if gap > _dt(rk, rs, last - mm + 1, last - mm, h) + tol * tf:
        return 0
    return mm


@kernel
def _is_onset(kind):
    """A sticking event's kind is an onset (at either wall), not a release."""
    return kind == STICK_ON or kind == STICK_ON + STICK_LO


@kernel
def _hop(ta, tb, beta, delta):
    """The flight ``[ta, tb]`` is pressed throughout by the push ``sin(beta tau) - delta``
    (amplitude 1, no random force): its minimum is -1 - delta where ``beta tau`` passes
    -pi/2 modulo 2 pi, else at an end (:func:`vibroimpact.stats.pressed_flights`)."""
    two_pi = 2.0 * math.pi
    n = math.ceil((beta * ta + 0.5 * math.pi) / two_pi)
    low = min(math.sin(beta * ta), math.sin(beta * tb))
    if -0.5 * math.pi + two_pi * n <= beta * tb:
        low = -1.0
    return low - delta > 0.0


@kernel
def _period_collisions(rk, rs, ru, n_imp, mm, h, zp, sk, ss, skind, n_stk, beta, delta,
                       lower):
    """Collisions per period of a periodic motion (period ``zp``, ``mm`` impacts): the
    grouping of :func:`vibroimpact.stats.group_collisions` (the physical rule: a run of hops,
    flights the push presses throughout, ending in sticking joins the impact that starts it)
    on three periods, counted in the middle one."""
    # three periods: the last two as recorded, the next one by periodicity, so that a
    # chatter run that the period's edge cuts is seen whole from the middle period
    L = 3 * mm
    t = np.empty(L + 1)
    u = np.empty(L + 1)
    base = n_imp - 2 * mm
    for j in range(2 * mm):
        i = base + j
        t[j] = rk[i % RING] * h + rs[i % RING]
        u[j] = ru[i % RING]
    for j in range(2 * mm, L + 1):
        t[j] = t[j - mm] + zp
        u[j] = u[j - mm]
    ends = np.zeros(L, np.bool_)
    for j in range(L):
        for e in range(max(0, n_stk - STICK_RING), n_stk):
            if _is_onset(skind[e % STICK_RING]):
                ts = sk[e % STICK_RING] * h + ss[e % STICK_RING]
                if ts < t[0] - zp:
                    continue            # before the verified periodic stretch
                # the onset, and its copies one and two periods on (the motion repeats)
                if ((t[j] <= ts < t[j + 1]) or (t[j] <= ts + zp < t[j + 1])
                        or (t[j] <= ts + 2.0 * zp < t[j + 1])):
                    ends[j] = True
                    break
    cont = np.zeros(L, np.bool_)
    for j in range(L):
        if u[j] > 0.0 or not lower > -np.inf:
            cont[j] = (not ends[j]) and _hop(t[j], t[j + 1], beta, delta)
        else:
            # a flight from the lower wall, pressed onto it: the mirrored frame's push
            # -sin(beta tau) + lower is sin(beta (tau + pi / beta)) - (-lower)
            sh = math.pi / beta
            cont[j] = (not ends[j]) and _hop(t[j] + sh, t[j + 1] + sh, beta, -lower)
    n_coll = 0
    for j in range(mm, 2 * mm):
        # impact j joins j - 1 when j - 1 lies on a shrinking run ending in sticking
        joins = False
        if not ends[j - 1]:
            for e in range(j - 1, L):
                if ends[e]:
                    joins = True
                    break
                if not cont[e]:
                    break
        if not joins:
            n_coll += 1
    return n_coll


@kernel
def _moduli(a11, a12, a21, a22, det):
    """Eigenvalue moduli ``(|mu_max|, |mu_min|)`` of a 2x2 matrix whose determinant ``det`` is
    known exactly (``eps^(2 m) exp(-2 zeta span)``: a product of saltations and
    propagators); the computed one loses every digit to cancellation when a grazing-slow
    impact (``1/u`` large) makes the entries huge."""
    tr = a11 + a22
    disc = tr * tr - 4.0 * det
    if disc >= 0.0:
        big = 0.5 * (abs(tr) + math.sqrt(disc))
        small = abs(det) / big if big > 0.0 else 0.0
    else:
        big = math.sqrt(abs(det))
        small = big
    return big, small


@kernel
def _tangent_product(rk, rs, ru, n_imp, mm, h, P, zeta, omega, eps, delta, eps_lower, lower):
    """Eigenvalue moduli ``(|mu_max|, |mu_min|)`` of the tangent map over the last ``mm``
    impacts: from just after impact ``n - mm - 1`` to just after impact ``n - 1``, the
    product of flight propagators ``P(s)`` and impact saltation matrices (at either wall:
    the sign of the recorded velocity says which)."""
    a11, a12, a21, a22 = 1.0, 0.0, 0.0, 1.0
    span = 0.0
    n_lo = 0
    for i in range(n_imp - mm, n_imp):
        s = _dt(rk, rs, i, i - 1, h)
        span += s
        f = math.sin(phase(rk[i % RING], rs[i % RING], P[P_BH_HI], P[P_BH_LO], P[P_BETA]))
        a11, a12, a21, a22 = _flight_impact(a11, a12, a21, a22, s, f, ru[i % RING], zeta,
                                            omega, eps, delta, eps_lower, lower)
        if ru[i % RING] < 0.0:
            n_lo += 1
    # det S = eps_w^2 at each impact (Newton's law); eps_lower^0 = 1 with one wall
    return _moduli(a11, a12, a21, a22, eps ** (2 * (mm - n_lo)) * eps_lower ** (2 * n_lo)
                   * math.exp(-2.0 * zeta * span))


@kernel
def wall_saltation(eps, u, f, delta, eps_lower, lower, zeta):
    """:func:`saltation` of an impact at either wall, told by the sign of the lab-frame
    velocity ``u`` (the simulator's ``imp_u``: > 0 at the wall at ``delta``, < 0 at the wall
    at ``lower``). The lower wall's is the upper wall's formula in the mirrored frame
    ``x -> -x`` (approach ``-u``, force ``-f``, wall at ``-lower``, its own law), and a
    saltation matrix is the same in both frames (the mirror is ``-I``)."""
    if u > 0.0:
        return saltation(eps, u, f, delta, zeta)
    return saltation(eps_lower, -u, -f, -lower, zeta)


@kernel
def _flight_impact(a11, a12, a21, a22, s, f, u, zeta, omega, eps, delta, eps_lower, lower):
    """``S P(s) A``: a flight of length ``s``, then the saltation of an impact with lab-frame
    velocity ``u`` (its sign the wall, :func:`wall_saltation`) where the force is ``f``."""
    p11, p12, p21, p22 = propagator(s, zeta, omega)
    b11 = p11 * a11 + p12 * a21
    b12 = p11 * a12 + p12 * a22
    b21 = p21 * a11 + p22 * a21
    b22 = p21 * a12 + p22 * a22
    s11, s21, s22 = wall_saltation(eps, u, f, delta, eps_lower, lower, zeta)
    return s11 * b11, s11 * b12, s21 * b11 + s22 * b21, s21 * b12 + s22 * b22


@kernel
def saltation(eps, u, f, delta, zeta):
    """Saltation matrix ``S = [[s11, 0], [s21, s22]]`` of an impact on the wall at ``x = delta``
    met at approach velocity ``u > 0`` where the force is ``f``: the tangent map from just
    before to just after the impact, ``S = Dg + (F_+ - Dg F_-) e_x^T / u`` with the reset
    ``g(x, v) = (x, rebound_velocity(eps, v))`` and the flows before and after.

    Notes
    -----
    ``s11 = v_+ / u``, ``s22 = d v_+ / du``, ``s21 = (a_+ - s22 a_-) / u`` with the
    accelerations ``a_-+ = f - 2 zeta v_-+ - delta``, written as
    ``((1 - s22) (f - delta) - 2 zeta (v_+ - s22 u)) / u`` for any law. Newton's law makes the
    last term exactly 0 (``v_+ = s22 u`` to the bit), leaving the classic ``(1 + eps) (f -
    delta) / u`` rounded exactly as before.
    """
    v_plus = rebound_velocity(eps, u)
    s22 = rebound_derivative(eps, u)
    s21 = ((1.0 - s22) * (f - delta) - 2.0 * zeta * (v_plus - s22 * u)) / u
    return rebound_ratio(eps, u), s21, s22


@kernel
def _orbit_tangent_product(oph, ou, oz, m, z, zeta, omega, eps, delta):
    """As :func:`_tangent_product`, over one period of the solver orbit itself (impact
    phases ``oph``, approach velocities ``ou``, intervals ``oz``): the limit the settled
    trajectory approaches, free of its remaining ``match_tol`` distance (which moves an
    eigenvalue by its square root where the multipliers are nearly double)."""
    a11, a12, a21, a22 = 1.0, 0.0, 0.0, 1.0
    for l in range(1, m + 1):
        j = l % m
        f = math.sin(2.0 * math.pi * oph[j])
        a11, a12, a21, a22 = _flight_impact(a11, a12, a21, a22, oz[(l - 1) % m], f, ou[j],
                                            zeta, omega, eps, delta, eps, -np.inf)
    return _moduli(a11, a12, a21, a22, eps ** (2 * m) * math.exp(-2.0 * zeta * z))


@kernel
def _qr(q, acc):
    """Gram-Schmidt of the 2x2 tangent matrix ``q`` (columns), logs of R's diagonal added to
    ``acc[0], acc[1]``."""
    r11 = math.hypot(q[0, 0], q[1, 0])
    if r11 == 0.0:
        acc[0] = -np.inf
        acc[1] = -np.inf
        return
    q[0, 0] /= r11
    q[1, 0] /= r11
    pr = q[0, 0] * q[0, 1] + q[1, 0] * q[1, 1]
    q[0, 1] -= pr * q[0, 0]
    q[1, 1] -= pr * q[1, 0]
    r22 = math.hypot(q[0, 1], q[1, 1])
    if r22 == 0.0:
        acc[0] += math.log(r11)
        acc[1] = -np.inf
        return
    q[0, 1] /= r22
    q[1, 1] /= r22
    acc[0] += math.log(r11)
    acc[1] += math.log(r22)


@kernel
def _flow(q, s, zeta, omega):
    p11, p12, p21, p22 = propagator(s, zeta, omega)
    for c in range(2):
        a = q[0, c]
        b = q[1, c]
        q[0, c] = p11 * a + p12 * b
        q[1, c] = p21 * a + p22 * b


@kernel
def _carry(q, acc, seg, t_to, t_b, zeta, omega):
    """Carry the tangent matrix over a flight of length ``seg`` ending at ``t_to``; a flight
    across the start ``t_b`` of Benettin's window is cut there and its part before ``t_b``
    renormalised without counting (so the window's logs cover exactly ``[t_b, ...]``)."""
    t_from = t_to - seg
    if t_from < t_b < t_to:
        _flow(q, t_b - t_from, zeta, omega)
        a0, a1 = acc[0], acc[1]
        _qr(q, acc)
        acc[0], acc[1] = a0, a1
        seg = t_to - t_b
    _flow(q, seg, zeta, omega)


@kernel
def _run_start(beta, delta, zeta, eps, clearance, eps_lower, theta, x0, v0, max_time, tol,
               types, n_upper, orb_n, oph, ou, oz, bufs_i, bufs_f, rk, rs, ru, rph, sk, ss, skind,
               outf, outi, trace_k, trace_s, trace_u):
    """One start until it settles or reaches ``max_time``; results into ``outf``/``outi``
    (slots ``F_*``, ``I_*``). ``trace_*`` (length > 0) receive its first impacts.

    A finite ``clearance`` adds the wall at ``lower = delta - clearance`` (restitution
    ``eps_lower``): the simulator follows both walls, impacts there are recorded with their
    lab-frame velocity ``< 0`` (``ru``, ``trace_u``) and the tangent crosses them by their own
    saltation (:func:`wall_saltation`). The orbit tables (``types``, ``orb_n``, ``oph``, ``ou``,
    ``oz``) then hold each listed type twice: rows ``< n_upper`` the orbits at the wall above,
    the rest those at the wall below (:func:`_match_orbit`); a start settled on one gets the
    type's index either way (``I_MOTION``) and its impacts at the wall below count in
    ``F_IMPACTS_LO``."""
    tf = 2.0 * math.pi / beta
    omega = math.sqrt(1.0 - zeta * zeta)
    lower = delta - clearance                   # -inf with one wall
    h, k0, t0 = start_step(beta, theta)
    # the C library's hypot in the harmonic gain, as these kernels have always had it
    # (vibroimpact.impact.parameters.parameters); Newton's law at both walls, force sin(beta tau)
    P = parameters(zeta, h, 1.0, beta, math.hypot(1.0 - beta * beta, 2.0 * zeta * beta), eps,
                   delta, 0.0, 2 if clearance < np.inf else 1, eps_lower, lower, 0.0)
    q = P[P_AQ]
    psi0 = phase(k0, 0.0, P[P_BH_HI], P[P_BH_LO], beta) - P[P_PHI]
    state = np.empty(N_STATE)
    state[S_W] = x0 - q * math.sin(psi0)
    state[S_WV] = v0 - q * beta * math.cos(psi0)
    state[S_MODE] = FREE
    state[S_SIN_PSI] = math.sin(psi0)
    state[S_COS_PSI] = math.cos(psi0)
    imp_step = bufs_i[0]
    stk_step = bufs_i[1]
    imp_off = bufs_f[0]
    imp_u = bufs_f[1]
    stk_off = bufs_f[2]
    stk_kind = bufs_f[3]
    cnt = np.zeros(N_COUNTERS, np.int64)
    ftot = np.zeros(N_FTOT)
    grid = np.empty(1)
    grid_n = np.zeros(1, np.int64)
    n_chunk = max(1, int(round(tf / h)))
    zeros = np.zeros(n_chunk + 2)
    k_cap = k0 + int(math.ceil(max_time / h))
    t_b = t0 + BENETTIN_FROM * max_time          # Benettin window [t_b, t0 + max_time]
    t_w = (1.0 - BENETTIN_FROM) * max_time
    qm = np.eye(2)
    acc = np.zeros(2)
    batch = np.zeros(N_BATCHES)
    tan_dead = False
    stick_in_win = False
    last_k, last_s = k0, 0.0                    # last tangent update
    n_imp = 0
    n_stk = 0
    n_imp_win = 0
    n_lo_win = 0
    n_coll_win = 0
    last_stick = -np.inf                        # instant of the last sticking event
    after_release = True
    u_prev = np.inf
    lo_prev = False
    z_prev = np.inf
    n_trace = 0
    ip = 0
    k = k0
    for c in range(N_F):
        outf[c] = np.nan
    for c in range(N_I):
        outi[c] = 0
    outf[F_STEP] = h
    outf[F_T0] = t0
    outi[I_MOTION] = -1
    outi[I_CLASS] = UNDECIDED
    loose = min(1e-2, LOOSE * tol)
    while k < k_cap:
        k1 = min(k + n_chunk, k_cap)
        while k < k1:
            if P.shape[0] > N_PARAMS:       # the second wall's tests compiled in
                status, k = run_steps(zeros, k, k1, state, P, imp_step, imp_off, imp_u,
                                      stk_step, stk_off, stk_kind, cnt, ftot, grid, grid, 0,
                                      grid_n, -P[N_PARAMS + P_DELTA])
            else:
                status, k = run_steps(zeros, k, k1, state, P, imp_step, imp_off, imp_u,
                                      stk_step, stk_off, stk_kind, cnt, ftot, grid, grid, 0,
                                      grid_n)
            if status != OK and status != BUFFER_FULL:
                outi[I_STATUS] = status
                outf[F_LYAP1] = np.nan
                outf[F_LYAP2] = np.nan
                return
            # the new events in time order: impacts ip.., sticking events 0..
            i_end = cnt[0]
            s_end = cnt[1]
            js = 0
            while ip < i_end or js < s_end:
                take_imp = ip < i_end and (js >= s_end or imp_step[ip] < stk_step[js] or (
                    imp_step[ip] == stk_step[js] and imp_off[ip] <= stk_off[js]))
                if take_imp:
                    ek, es = imp_step[ip], imp_off[ip]
                else:
                    ek, es = stk_step[js], stk_off[js]
                tau = ek * h + es
                if not tan_dead:
                    _carry(qm, acc, (ek - last_k) * h + (es - last_s), tau, t_b, zeta, omega)
                last_k, last_s = ek, es
                if take_imp:
                    u = imp_u[ip]
                    if not tan_dead:
                        f = math.sin(phase(ek, es, P[P_BH_HI], P[P_BH_LO], beta))
                        s11, s21, s22 = wall_saltation(eps, u, f, delta, eps_lower, lower,
                                                       zeta)
                        for cc in range(2):
                            a = qm[0, cc]
                            b = qm[1, cc]
                            qm[0, cc] = s11 * a
                            qm[1, cc] = s21 * a + s22 * b
                        before0, before1 = acc[0], acc[1]
                        _qr(qm, acc)
                        if tau >= t_b:
                            bi = min(N_BATCHES - 1, int((tau - t_b) / (t_w / N_BATCHES)))
                            batch[bi] += acc[0] - before0
                        else:
                            acc[0], acc[1] = before0, before1
                    ph = phase(ek, es, P[P_BH_HI], P[P_BH_LO], beta) / (2.0 * math.pi)
                    slot = n_imp % RING
                    rk[slot] = ek
                    rs[slot] = es
                    ru[slot] = u
                    rph[slot] = ph - math.floor(ph)
                    z_here = (ek - rk[(n_imp - 1) % RING]) * h + (
                        es - rs[(n_imp - 1) % RING]) if n_imp > 0 else np.inf
                    lo = u < 0.0
                    if tau >= t_b:
                        n_imp_win += 1
                        if lo:
                            n_lo_win += 1
                        # a new collision: after a release, at the other wall, or not
                        # shrinking (a chatter run's rebounds shrink in speed and interval)
                        if (after_release or lo != lo_prev or abs(u) >= abs(u_prev)
                                or z_here >= z_prev):
                            n_coll_win += 1
                    after_release = False
                    u_prev = u
                    lo_prev = lo
                    z_prev = z_here
                    if n_trace < trace_k.shape[0]:
                        trace_k[n_trace] = ek
                        trace_s[n_trace] = es
                        trace_u[n_trace] = u
                        n_trace += 1
                    n_imp += 1
                    ip += 1
                else:
                    kind = stk_kind[js]
                    slot = n_stk % STICK_RING
                    sk[slot] = ek
                    ss[slot] = es
                    skind[slot] = kind
                    n_stk += 1
                    last_stick = tau
                    if _is_onset(kind):
                        tan_dead = True
                        if tau >= t_b:
                            stick_in_win = True
                    else:
                        tan_dead = False
                        after_release = True
                        qm[0, 0], qm[0, 1], qm[1, 0], qm[1, 1] = 1.0, 0.0, 0.0, 1.0
                    js += 1
            cnt[1] = 0
            if cnt[0] > COMPACT:
                # keep the last impact where slow_step reads it (the chatter tail's flight)
                imp_step[0] = imp_step[cnt[0] - 1]
                imp_off[0] = imp_off[cnt[0] - 1]
                imp_u[0] = imp_u[cnt[0] - 1]
                cnt[0] = 1
                ip = 1
        # the tangent vectors to the end of the chunk
        t_now = k * h
        if not tan_dead:
            _carry(qm, acc, (k - last_k) * h - last_s, t_now, t_b, zeta, omega)
            before0, before1 = acc[0], acc[1]
            _qr(qm, acc)
            if t_now > t_b:
                bi = min(N_BATCHES - 1, int((t_now - t_b) / (t_w / N_BATCHES)))
                batch[bi] += acc[0] - before0
            else:
                acc[0], acc[1] = before0, before1
            last_k, last_s = k, 0.0
        mode = int(state[S_MODE])
        # (a) no impact ever again: the free response has decayed below the wall's margin
        # and the motion tends to the linear steady response q sin(beta tau - phi), q < delta
        # (and above the lower wall, q < -lower, when there is one)
        if mode == FREE:
            w = state[S_W]
            c2 = (state[S_WV] + zeta * w) / omega
            reach = q + math.sqrt(w * w + c2 * c2)
            if reach < delta - 1e-9 * (1.0 + abs(delta)) and (
                    not lower > -np.inf or -reach > lower + 1e-9 * (1.0 + abs(lower))):
                outf[F_SETTLE] = t_now - t0
                outf[F_LYAP1] = -zeta
                outf[F_LYAP2] = -zeta
                outf[F_RATE] = 0.0
                outi[I_CLASS] = WALL_FREE
                outi[I_PERIOD_P] = 1
                return
        # (b) resting or sliding on the wall for REPEATS + 1 periods without an impact
        t_last_imp = (rk[(n_imp - 1) % RING] * h + rs[(n_imp - 1) % RING]
                      if n_imp > 0 else t0)
        stuck = mode == STUCK or mode == STUCK_LO
        if t_now - t_last_imp > (REPEATS + 1) * tf and (
                stuck or last_stick > t_now - (REPEATS + 1) * tf):
            outf[F_SETTLE] = max(t_last_imp, t0) - t0
            outf[F_LYAP1] = -np.inf
            outf[F_LYAP2] = -np.inf
            outf[F_RATE] = 0.0
            outi[I_CLASS] = STICKING
            outi[I_PERIOD_P] = 1
            outi[I_STICK_P] = 1                # no collision per forcing period: (0/1)
            return
        # (c) on a stable solver orbit of a listed type, at the wall above (t < n_upper) or
        # below (the same types again, solved in the mirrored frame)
        for t in range(types.shape[0]):
            m = types[t, 0]
            at_lower = t >= n_upper
            for o in range(min(orb_n[t], K_ORBITS)):
                if _match_orbit(rk, rs, ru, rph, n_imp, h, tf, k, m, oph[t, o], ou[t, o],
                                oz[t, o], tol, last_stick, at_lower):
                    z = types[t, 1] * tf
                    # the mirrored frame's own wall: the product is that of the one-wall
                    # orbit the table holds, the same numbers as at a wall above
                    big, small = _orbit_tangent_product(
                        oph[t, o], ou[t, o], oz[t, o], m, z, zeta, omega,
                        eps_lower if at_lower else eps, -lower if at_lower else delta)
                    i0 = n_imp - REPEATS * m
                    outf[F_SETTLE] = rk[i0 % RING] * h + rs[i0 % RING] - t0
                    outf[F_LYAP1] = math.log(big) / z
                    outf[F_LYAP2] = math.log(small) / z
                    outf[F_RATE] = m / z
                    outf[F_IMPACTS] = m
                    outf[F_IMPACTS_LO] = m if at_lower else 0.0
                    outf[F_WINDOW] = z
                    outi[I_MOTION] = t - n_upper if at_lower else t
                    outi[I_CLASS] = LISTED
                    outi[I_PERIOD_M] = m
                    outi[I_PERIOD_P] = types[t, 1]
                    return
        # (d) some other periodic motion (with chatter and sticking, or of another type)
        for p in range(1, MAX_PERIODS + 1):
            mm = _period_of(rk, rs, ru, n_imp, h, tf, k, p, tol)
            if mm == 0:
                continue
            near = False
            for t in range(types.shape[0]):
                m = types[t, 0]
                for o in range(min(orb_n[t], K_ORBITS)):
                    if _match_orbit(rk, rs, ru, rph, n_imp, h, tf, k, m, oph[t, o], ou[t, o],
                                    oz[t, o], loose, last_stick, t >= n_upper):
                        near = True
            if near:
                break                   # still converging onto a listed orbit: run on
            zp = p * tf
            t_last = rk[(n_imp - 1) % RING] * h + rs[(n_imp - 1) % RING]
            i0 = n_imp - 1 - REPEATS * mm
            outf[F_SETTLE] = rk[i0 % RING] * h + rs[i0 % RING] - t0
            outi[I_PERIOD_M] = mm
            outi[I_PERIOD_P] = p
            if stuck or last_stick > t_last - zp:
                mc = _period_collisions(rk, rs, ru, n_imp, mm, h, zp, sk, ss, skind, n_stk,
                                        beta, delta, lower)
                outf[F_LYAP1] = -np.inf
                outf[F_LYAP2] = -np.inf
                outf[F_RATE] = mc / zp
                outi[I_CLASS] = STICKING
                outi[I_STICK_M] = mc
                outi[I_STICK_P] = p
                for t in range(n_upper):
                    if types[t, 0] == mc and types[t, 1] == p:
                        outi[I_MOTION] = -2 - t          # impact-stick variant of type t
                return
            big, small = _tangent_product(rk, rs, ru, n_imp, mm, h, P, zeta, omega, eps, delta,
                                          eps_lower, lower)
            outf[F_LYAP1] = math.log(big) / zp
            outf[F_LYAP2] = math.log(small) / zp
            outf[F_RATE] = mm / zp
            outf[F_IMPACTS] = mm
            n_lo = 0
            for i in range(n_imp - mm, n_imp):
                if ru[i % RING] < 0.0:
                    n_lo += 1
            outf[F_IMPACTS_LO] = n_lo
            outf[F_WINDOW] = zp
            outi[I_CLASS] = PERIODIC_OTHER
            return
    # not settled: Benettin over [t_b, t0 + max_time]
    t_end = k * h
    win = t_end - t_b
    outf[F_WINDOW] = win
    outf[F_IMPACTS] = n_imp_win
    outf[F_IMPACTS_LO] = n_lo_win
    outf[F_RATE] = (n_imp_win if not stick_in_win else n_coll_win) / win
    if stick_in_win or tan_dead:
        outf[F_LYAP1] = -np.inf
        outf[F_LYAP2] = -np.inf
        outi[I_CLASS] = STICKING
        return
    lam1 = acc[0] / win
    outf[F_LYAP1] = lam1
    outf[F_LYAP2] = acc[1] / win
    tb = t_w / N_BATCHES
    mean = 0.0
    for b in range(N_BATCHES):
        mean += batch[b] / tb
    mean /= N_BATCHES
    var = 0.0
    for b in range(N_BATCHES):
        var += (batch[b] / tb - mean) ** 2
    se = math.sqrt(var / (N_BATCHES - 1) / N_BATCHES)
    outf[F_STDERR] = se
    outi[I_CLASS] = CHAOTIC if lam1 > CHAOS_SIGMAS * se else UNDECIDED


@kernel
def _alloc_ring():
    return (np.empty(RING, np.int64), np.empty(RING), np.empty(RING), np.empty(RING),
            np.empty(STICK_RING, np.int64), np.empty(STICK_RING), np.empty(STICK_RING))


@kernel(parallel=True)
def run_starts(cell_beta, cell_delta, cell_of, theta, x0, v0, zeta, eps, clearance, eps_lower,
               max_time, tol, types, n_upper, orb_n, oph, ou, oz, n_blocks, outf, outi):
    """Every start ``i`` (cell ``cell_of[i]``) through :func:`_run_start`; ``n_blocks``
    parallel blocks, block ``b`` taking the starts ``b, b + n_blocks, ...`` (so that the cost,
    which varies across the plane, is shared evenly), each with its own buffers."""
    n = theta.shape[0]
    for b in prange(n_blocks):
        bufs_i = np.empty((2, CAPACITY), np.int64)
        bufs_f = np.empty((4, CAPACITY))
        rk, rs, ru, rph, sk, ss, skind = _alloc_ring()
        tr_k = np.empty(0, np.int64)
        tr_s = np.empty(0)
        for i in range(b, n, n_blocks):
            c = cell_of[i]
            _run_start(cell_beta[c], cell_delta[c], zeta, eps, clearance, eps_lower, theta[i],
                       x0[i], v0[i], max_time, tol, types, n_upper, orb_n[c], oph[c], ou[c],
                       oz[c], bufs_i, bufs_f, rk, rs, ru, rph, sk, ss, skind, outf[i], outi[i],
                       tr_k, tr_s, tr_s)


@kernel
def trace_start(beta, delta, zeta, eps, clearance, eps_lower, theta, x0, v0, max_time, tol,
                types, n_upper, orb_n, oph, ou, oz, outf, outi, trace_k, trace_s, trace_u):
    """One start, serially, recording its first impacts (tests)."""
    bufs_i = np.empty((2, CAPACITY), np.int64)
    bufs_f = np.empty((4, CAPACITY))
    rk, rs, ru, rph, sk, ss, skind = _alloc_ring()
    _run_start(beta, delta, zeta, eps, clearance, eps_lower, theta, x0, v0, max_time, tol,
               types, n_upper, orb_n, oph, ou, oz, bufs_i, bufs_f, rk, rs, ru, rph, sk, ss, skind,
               outf, outi, trace_k, trace_s, trace_u)
