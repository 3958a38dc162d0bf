"""The events cells' self-audit compiled: :func:`vibroimpact.stats.flight_moments` in one pass.

The same integrals of v^2, x^2, f v, x f and of the wall's push over every force step, cut at
impacts and sticking phases (docs/model.md, section 7.1), walked step by step in numba
instead of gathered into arrays: the numpy function stays the reference (the tests hold this
one to it) and the statement of the rules; this is the one the events cells run.

With a second wall (``gap``) the events carry their wall: an impact at the lower wall leaves
``x = delta - gap`` at ``+eps_lower V``, a piece resting there adds its push
``(delta - gap) - f`` and its tails to the rows of ``stats.identities.MOMENTS_LOWER``.

Its kernels use no simulator kernel and no constant of another module (the Gauss-Legendre
rule, the tail threshold and the whole-step forms come in as arguments) but the impact law,
so their numba cache is stamped with this file and the law's (`vibroimpact._law`), and an
edit here recompiles nothing of the simulator.
"""
import math

import numpy as np
from numba import njit

from vibroimpact._kernel_cache import kernel_decorator
from vibroimpact._law import LAW_MODULES, rebound_velocity
from vibroimpact.model import law_rates
from vibroimpact.stats.identities import (GAUSS_NODES, TAIL_REBOUND, moment_rows, step_forms,
                                         wall_arrays)

kernel = kernel_decorator(njit, __file__, ("audit.py",) + tuple(f"../{m}" for m in LAW_MODULES),
                          error_model="numpy")

#: Whole free steps summed together before joining their batch's sum (round-off of the
#: running sums ~ (BLOCK + steps / BLOCK) ulp rather than steps ulp).
BLOCK = 1024

_XI, _W = np.polynomial.legendre.leggauss(GAUSS_NODES)

# the kinds of pieces: a sample, an impact, a sticking onset (a release is 3), in the order
# they sort at equal times (as stats.flight_moments)
_SAMPLE, _IMPACT, _ONSET = 0, 1, 2


def audit_moments(k_first, a, v, r, dt, *, zeta, eps, delta, amplitude=0.0, beta_f=1.0,
                  impact_time=(), impact_velocity=(), stick_start=(), stick_end=(),
                  batch_bounds=None, gap=None, eps_lower=None, impact_wall=None,
                  stick_wall=None, speed_scale=math.inf, speed_scale_lower=None):
    """:func:`vibroimpact.stats.flight_moments` of the simulator's record ``a = delta - x``.

    Parameters
    ----------
    k_first : int
        Sample index of the first step.
    a, v : array_like, shape (n,)
        ``a = delta - x`` and the velocity at samples ``k_first .. k_first + n - 1`` (a
        chunk's ``a`` and ``v`` with ``record_every=1``).
    r : array_like, shape (n + 1,)
        Random force samples ``k_first .. k_first + n``.
    dt, zeta, eps, delta, amplitude, beta_f, impact_time, impact_velocity, stick_start,
    stick_end
        As :func:`vibroimpact.stats.flight_moments`; the impacts and the sticking phases
        increasing, as the simulator gives them.
    batch_bounds : array_like of int, shape (B + 1,), optional
        Contiguous batches: batch ``j`` holds the steps from sample ``batch_bounds[j]`` up to
        ``batch_bounds[j + 1]`` (nondecreasing, covering the steps). Default: one batch.
    gap, eps_lower, impact_wall, stick_wall
        A second wall, as :func:`vibroimpact.stats.flight_moments` (all or none).
    speed_scale, speed_scale_lower
        The walls' impact laws (:class:`vibroimpact.model.Restitution`; ``inf``, the
        default, Newton's): the velocity leaving each impact is its wall's
        ``rebound_velocity``.

    Returns
    -------
    ndarray, shape (len(MOMENTS), B), or (len(MOMENTS + MOMENTS_LOWER), B) with two walls
        The per-batch sums of :func:`vibroimpact.stats.flight_moments` with ``batch`` the
        batch of each step, equal to round-off (the order of the sums differs;
        tests/test_audit_kernel.py).
    """
    a = np.ascontiguousarray(a, dtype=float)
    v = np.ascontiguousarray(v, dtype=float)
    r = np.ascontiguousarray(r, dtype=float)
    n = a.size
    if v.size != n or r.size != n + 1:
        raise ValueError(f"need a, v of n samples and r of n + 1, got {n}, {v.size}, {r.size}")
    bounds = np.ascontiguousarray([k_first, k_first + n] if batch_bounds is None
                                  else batch_bounds, dtype=np.int64)
    if (bounds.size < 2 or np.any(np.diff(bounds) < 0) or bounds[0] > k_first
            or bounds[-1] < k_first + n):
        raise ValueError(f"batch_bounds must be nondecreasing sample indices from at most "
                         f"{k_first} to at least {k_first + n}, got {bounds}")
    as_f = lambda e: np.ascontiguousarray(e, dtype=float).reshape(-1)
    t_imp, s0 = as_f(impact_time), as_f(stick_start)
    walls = wall_arrays(gap, eps_lower, delta, impact_wall, stick_wall, t_imp.size, s0.size)
    out = np.zeros((len(moment_rows(walls is not None)), bounds.size - 1))
    if walls is None:    # one wall: every event at the wall at delta
        walls = (0.0, 0.0, np.zeros(t_imp.size, np.int8), np.zeros(s0.size, np.int8))
    x_lower, e_lower, iw, sw = walls
    law_a, law_a_lower = law_rates(speed_scale, speed_scale_lower)
    if n:
        _moments(int(k_first), a, v, r, float(dt), float(zeta), float(eps), float(delta),
                 float(amplitude), float(beta_f), t_imp, as_f(impact_velocity),
                 s0, as_f(stick_end), bounds,
                 np.ascontiguousarray(step_forms(dt, zeta, amplitude, beta_f)), _XI, _W,
                 TAIL_REBOUND, float(x_lower), float(e_lower), np.ascontiguousarray(iw),
                 np.ascontiguousarray(sw), law_a, law_a_lower, out)
    return out


@kernel
def _step_of(t, k_first, n, dt):
    """The step of an instant: the last sample at or before it (``searchsorted`` right - 1
    over the samples' times ``(k_first + i) * dt``), within ``0 .. n - 1``."""
    i = min(max(int(math.floor(t / dt)) - k_first, 0), n - 1)
    while i > 0 and (k_first + i) * dt > t:
        i -= 1
    while i < n - 1 and (k_first + i + 1) * dt <= t:
        i += 1
    return i


@kernel
def _events(k_first, n, dt, eps, t_imp, u_imp, s0, s1, delta, x_lower, eps_lower, iw, sw,
            law_a, law_a_lower):
    """Impacts, sticking onsets and releases inside the steps, sorted by (time, kind).

    Returns the times, kinds, velocities leaving them (the wall's law: ``-eps V``, 0, 0 at
    the upper wall under Newton's law; ``+eps_lower V`` after an impact at the lower one),
    positions (the event's wall) and steps."""
    t_lo, t_hi = k_first * dt, (k_first + n) * dt
    lists = (t_imp, s0, s1)
    firsts = np.zeros(3, np.int64)
    stops = np.zeros(3, np.int64)
    for kind in range(3):
        times = lists[kind]
        j = 0
        while j < times.size and not times[j] >= t_lo:
            j += 1
        firsts[kind] = j
        while j < times.size and times[j] <= t_hi:
            j += 1
        stops[kind] = j
    m = int(np.sum(stops - firsts))
    ev_t = np.empty(m)
    ev_kind = np.empty(m, np.int64)
    ev_v = np.zeros(m)
    ev_x = np.full(m, delta)
    ev_step = np.empty(m, np.int64)
    heads = firsts.copy()
    for e in range(m):
        best, best_t = -1, 0.0
        for kind in range(3):           # the earliest head; at equal times the lower kind
            if heads[kind] < stops[kind]:
                t = lists[kind][heads[kind]]
                if best < 0 or t < best_t:
                    best, best_t = kind, t
        at_lower = (iw[heads[0]] if best == 0 else sw[heads[best]]) == 1
        if best == 0:
            u = u_imp[heads[0]]
            ev_v[e] = (-rebound_velocity(eps_lower, u, law_a_lower) if at_lower
                       else rebound_velocity(eps, u, law_a))
        if at_lower:
            ev_x[e] = x_lower
        ev_t[e] = best_t
        ev_kind[e] = best + 1
        ev_step[e] = _step_of(best_t, k_first, n, dt)
        heads[best] += 1
    return ev_t, ev_kind, ev_v, ev_x, ev_step


@kernel
def _phase_after(t, s0, p):
    """``searchsorted(s0, t, side="right")`` from a guess ``p``: the sticking phases begun at
    or before ``t`` (instants met in increasing order move ``p`` by a step or two)."""
    while p < s0.size and s0[p] <= t:
        p += 1
    while p > 0 and s0[p - 1] > t:
        p -= 1
    return p


@kernel
def _add_resting(out, b, s_a, L, k, r0, r1, dt, delta, A, beta, lower):
    """Integrals of x^2, x f and the push f - delta over a piece resting on the wall at
    ``delta`` (offset ``s_a`` in step ``k``, length ``L``), added to batch ``b``; ``lower``:
    the wall is the lower one, at ``delta``, and its push ``delta - f`` goes to its row."""
    slope = (r1 - r0) / dt
    f_int = L * (r0 + slope * (s_a + 0.5 * L))
    if A != 0.0:
        tau = k * dt + s_a
        f_int = f_int + A / beta * (math.cos(beta * tau) - math.cos(beta * (tau + L)))
    out[1, b] += delta * delta * L
    out[3, b] += delta * f_int
    if lower:
        out[7, b] += delta * L - f_int
    else:
        out[4, b] += f_int - delta * L


@kernel
def _resting_run(out, b, i, stop, k_first, r, dt, wall, A, beta, lower, end, next_onset):
    """:func:`_add_resting` of the whole steps from ``i`` (resting) up to ``stop`` while
    their midpoints lie before ``end`` and ``next_onset``; returns the first step left.
    The same calls in the same order as one step at a time (the same bits), without the
    main loop's tests between them."""
    j = i
    while True:
        k = k_first + j
        _add_resting(out, b, 0.0, dt, k, r[j], r[j + 1], dt, wall, A, beta, lower)
        j += 1
        if j >= stop:
            return j
        t_mid = (k_first + j) * dt + 0.5 * dt
        if not (t_mid < end and t_mid < next_onset):
            return j


@kernel
def _node(sig, wt, c, sn, cb, sb, r0, slope, s_a, zeta, y0, yv0, A, q, beta, sin_psi, cos_psi,
          sin_pp, cos_pp):
    """The weighted v^2, x^2, f v and x f at a node ``sig`` of a free piece, given
    ``c + i wd sn = exp((-zeta + i wd) sig)`` and ``cb + i sb = exp(i beta sig)``."""
    f = r0 + slope * (s_a + sig)
    p = f - 2.0 * zeta * slope
    dp = slope
    if A != 0.0:
        f = f + A * (sin_psi * cb + cos_psi * sb)
        p = p + q * (sin_pp * cb + cos_pp * sb)
        dp = dp + q * beta * (cos_pp * cb - sin_pp * sb)
    xs = p + (c + zeta * sn) * y0 + sn * yv0
    vs = dp - sn * y0 + (c - zeta * sn) * yv0
    return wt * (vs * vs), wt * (xs * xs), wt * (f * vs), wt * (xs * f)


@kernel
def _add_free(out, b, s_a, L, k, x0, v0, r0, r1, dt, zeta, A, beta, xi, wi):
    """Integrals of v^2, x^2, f v and x f over a free piece from ``(x0, v0)`` (offset ``s_a``
    in step ``k``, length ``L``), by Gauss-Legendre quadrature, added to batch ``b``.

    The rule's nodes lie in pairs about the piece's middle ``h = L / 2``, so the exponentials
    at ``h +- d`` are those at ``h`` times those at ``+-d``: three calls of each of exp, cos
    and sin for five nodes rather than five (at ``h`` and at the two pairs' ``d``; the middle
    node's ``d`` is 0)."""
    wd = math.sqrt(1.0 - zeta * zeta)
    slope = (r1 - r0) / dt
    p_a = r0 + slope * s_a - 2.0 * zeta * slope
    dp_a = slope
    q = phi = sin_psi = cos_psi = sin_pp = cos_pp = 0.0
    if A != 0.0:
        q = A / math.hypot(1.0 - beta * beta, 2.0 * zeta * beta)
        phi = math.atan2(2.0 * zeta * beta, 1.0 - beta * beta)
        psi = beta * (k * dt + s_a)                      # phase of the force at the start
        sin_psi, cos_psi = math.sin(psi), math.cos(psi)
        sin_pp, cos_pp = math.sin(psi - phi), math.cos(psi - phi)
        p_a = p_a + q * sin_pp
        dp_a = dp_a + q * beta * cos_pp
    y0, yv0 = x0 - p_a, v0 - dp_a
    h = 0.5 * L
    eh = math.exp(-zeta * h)
    ch, sh = math.cos(wd * h), math.sin(wd * h)
    cbh = sbh = cbd = sbd = 0.0
    if A != 0.0:
        cbh, sbh = math.cos(beta * h), math.sin(beta * h)
    v2 = x2 = fv = xf = 0.0
    n = xi.size
    for j in range((n + 1) // 2):
        hi = n - 1 - j
        d = h * xi[hi]                                   # >= 0: nodes h - d (j), h + d (hi)
        if d == 0.0:
            # the middle node (xi = +0 exactly): what exp, cos and sin give at +-0, without
            # their calls (a quarter of a piece's; the same bits)
            ed, cd, sd = 1.0, 1.0, 0.0
            if A != 0.0:
                cbd, sbd = 1.0, 0.0
        else:
            ed = math.exp(-zeta * d)
            cd, sd = math.cos(wd * d), math.sin(wd * d)
            if A != 0.0:
                cbd, sbd = math.cos(beta * d), math.sin(beta * d)
        for sign in (1.0, -1.0):
            node = hi if sign > 0.0 else j
            e = eh * ed if sign > 0.0 else eh / ed
            c = e * (ch * cd - sign * sh * sd)
            sn = e * (sh * cd + sign * ch * sd) / wd
            cb = cbh * cbd - sign * sbh * sbd
            sb = sbh * cbd + sign * cbh * sbd
            dv2, dx2, dfv, dxf = _node(0.5 * L * (1.0 + xi[node]), 0.5 * L * wi[node], c, sn,
                                       cb, sb, r0, slope, s_a, zeta, y0, yv0, A, q, beta,
                                       sin_psi, cos_psi, sin_pp, cos_pp)
            v2 += dv2
            x2 += dx2
            fv += dfv
            xf += dxf
            if j == hi:
                break                                    # the middle node: once
    out[0, b] += v2
    out[1, b] += x2
    out[2, b] += fv
    out[3, b] += xf


@kernel
def _busy_step(out, i, e, p, ev_t, ev_kind, ev_v, ev_x, ev_step, k_first, a, v, r, b, dt,
               zeta, delta, A, beta, s0, s1, xi, wi, tail_rebound, x_lower, sw):
    """The pieces of step ``i``, whose events start at ``e``; returns the next step's first
    event and :func:`_phase_after` of its last piece (from ``p``). As stats.flight_moments:
    a piece resting at its midpoint, or running from a last chatter rebound slower than
    ``tail_rebound`` to a sticking onset, is resting (at its phase's wall; a tail at its
    impact's)."""
    k = k_first + i
    t_a, kind, x0, v0 = k * dt, _SAMPLE, delta - a[i], v[i]
    while True:
        same = e < ev_t.size and ev_step[e] == i
        end = ev_t[e] if same else (k + 1) * dt
        length = max(end - t_a, 0.0)
        t_mid = t_a + 0.5 * length
        p = _phase_after(t_mid, s0, p)
        stuck = p > 0 and t_mid < s1[p - 1]
        lower = stuck and sw[p - 1] == 1
        if kind == _IMPACT and same and ev_kind[e] == _ONSET:
            # a rebound leaves the upper wall downwards (v0 <= 0), the lower one upwards
            at_lower = x0 != delta
            w = v0 if at_lower else -v0
            if w < tail_rebound:
                stuck, lower = True, at_lower
                row = 8 if lower else 5
                out[row, b] += w
                out[row + 1, b] += w * w
        offset = t_a - k * dt
        if stuck:
            _add_resting(out, b, offset, length, k, r[i], r[i + 1], dt,
                         x_lower if lower else delta, A, beta, lower)
        else:
            _add_free(out, b, offset, length, k, x0, v0, r[i], r[i + 1], dt, zeta, A, beta, xi,
                      wi)
        if not same:
            return e, p
        t_a, kind, x0, v0 = ev_t[e], ev_kind[e], ev_x[e], ev_v[e]
        e += 1


@kernel
def _before_onset(i, stop, onset, k_first, dt):
    """The end of a run of free steps from ``i`` (at most ``stop``) before a sticking onset:
    the first ``j > i`` whose midpoint ``(k_first + j) dt + dt / 2`` is not before ``onset``,
    found from its estimate and a step or two of the same test, which is what testing each
    step in turn from ``i + 1`` gives (the midpoints increase with ``j``) at a fraction of its
    cost (a float product a free step: ~5 % of the audit at large delta)."""
    estimate = (onset - 0.5 * dt) / dt - k_first
    if not estimate < stop:         # beyond the run (or no onset: inf)
        estimate = stop
    j = min(max(int(math.ceil(estimate)), i + 1), stop)
    while j > i + 1 and (k_first + j - 1) * dt + 0.5 * dt >= onset:
        j -= 1
    while j < stop and (k_first + j) * dt + 0.5 * dt < onset:
        j += 1
    return j


@kernel
def _free_run_unforced(a, v, r, i0, i1, dt, zeta, delta, z, total):
    """:func:`_free_run` without a harmonic force (``z = (r0, b, y0, y0')``), in two passes:
    ``b, y0, y0'`` of every step into ``z`` (rows 1-3; elementwise, which the compiler
    vectorizes), then the sums of their products in step order, as the one-pass loop adds
    them (same values, same order: the same bits). ``z`` holds at least ``i1 - i0`` columns
    (a run is at most BLOCK steps)."""
    two_zeta = 2.0 * zeta
    n = i1 - i0
    rb, y0b, y1b = z[0], z[1], z[2]
    for j in range(n):
        i = i0 + j
        b = (r[i + 1] - r[i]) / dt
        rb[j] = b
        y0b[j] = delta - a[i] - r[i] + two_zeta * b
        y1b[j] = v[i] - b
    s00 = s01 = s02 = s03 = s11 = s12 = s13 = s22 = s23 = s33 = 0.0
    for j in range(n):
        r0 = r[i0 + j]
        b = rb[j]
        y0 = y0b[j]
        y1 = y1b[j]
        s00 += r0 * r0
        s01 += r0 * b
        s02 += r0 * y0
        s03 += r0 * y1
        s11 += b * b
        s12 += b * y0
        s13 += b * y1
        s22 += y0 * y0
        s23 += y0 * y1
        s33 += y1 * y1
    total[0, 0] += s00
    total[0, 1] += s01
    total[0, 2] += s02
    total[0, 3] += s03
    total[1, 1] += s11
    total[1, 2] += s12
    total[1, 3] += s13
    total[2, 2] += s22
    total[2, 3] += s23
    total[3, 3] += s33


@kernel
def _free_run(a, v, r, i0, i1, k_first, dt, zeta, delta, A, beta, q, cos_phi, sin_phi, total):
    """Add ``z z^T`` of the whole free steps ``i0 .. i1 - 1`` to ``total`` (its upper
    triangle), ``z = (r0, b, y0, y0', sin psi, cos psi)`` as stats.identities.step_forms;
    ``q, phi``: amplitude ratio and phase lag of the response to ``A sin(beta tau)``."""
    harmonic = A != 0.0
    s00 = s01 = s02 = s03 = s04 = s05 = s11 = s12 = s13 = s14 = s15 = 0.0
    s22 = s23 = s24 = s25 = s33 = s34 = s35 = s44 = s45 = s55 = 0.0
    two_zeta = 2.0 * zeta
    for i in range(i0, i1):
        r0 = r[i]
        b = (r[i + 1] - r0) / dt
        x0 = delta - a[i]
        if harmonic:
            psi = beta * ((k_first + i) * dt)
            sp, cp = math.sin(psi), math.cos(psi)
            sin_pa = sp * cos_phi - cp * sin_phi
            cos_pa = cp * cos_phi + sp * sin_phi
            y0 = x0 - (r0 - two_zeta * b + q * sin_pa)
            y1 = v[i] - (b + q * beta * cos_pa)
            s04 += r0 * sp
            s05 += r0 * cp
            s14 += b * sp
            s15 += b * cp
            s24 += y0 * sp
            s25 += y0 * cp
            s34 += y1 * sp
            s35 += y1 * cp
            s44 += sp * sp
            s45 += sp * cp
            s55 += cp * cp
        else:
            y0 = x0 - r0 + two_zeta * b
            y1 = v[i] - b
        s00 += r0 * r0
        s01 += r0 * b
        s02 += r0 * y0
        s03 += r0 * y1
        s11 += b * b
        s12 += b * y0
        s13 += b * y1
        s22 += y0 * y0
        s23 += y0 * y1
        s33 += y1 * y1
    total[0, 0] += s00
    total[0, 1] += s01
    total[0, 2] += s02
    total[0, 3] += s03
    total[1, 1] += s11
    total[1, 2] += s12
    total[1, 3] += s13
    total[2, 2] += s22
    total[2, 3] += s23
    total[3, 3] += s33
    if harmonic:
        total[0, 4] += s04
        total[0, 5] += s05
        total[1, 4] += s14
        total[1, 5] += s15
        total[2, 4] += s24
        total[2, 5] += s25
        total[3, 4] += s34
        total[3, 5] += s35
        total[4, 4] += s44
        total[4, 5] += s45
        total[5, 5] += s55


@kernel
def _moments(k_first, a, v, r, dt, zeta, eps, delta, A, beta, t_imp, u_imp, s0, s1, bounds,
             M, xi, wi, tail_rebound, x_lower, eps_lower, iw, sw, law_a, law_a_lower, out):
    """Add the moments of the steps ``k_first .. k_first + n - 1`` to ``out`` (see
    :func:`audit_moments`); ``M``: the whole-step forms of ``stats.identities.step_forms``;
    ``iw``, ``sw``: the wall of each impact and sticking phase (1: the lower wall, at
    ``x_lower``, restitution ``eps_lower``); ``law_a``, ``law_a_lower``: the walls' laws
    (``1 / speed_scale``, 0 for Newton's)."""
    n = a.size
    m = M.shape[1]
    ev_t, ev_kind, ev_v, ev_x, ev_step = _events(k_first, n, dt, eps, t_imp, u_imp, s0, s1,
                                                 delta, x_lower, eps_lower, iw, sw, law_a,
                                                 law_a_lower)
    q = phi = 0.0
    if A != 0.0:
        q = A / math.hypot(1.0 - beta * beta, 2.0 * zeta * beta)
        phi = math.atan2(2.0 * zeta * beta, 1.0 - beta * beta)
    cos_phi, sin_phi = math.cos(phi), math.sin(phi)
    total = np.zeros((out.shape[1], 6, 6))   # per batch, sum of z z^T over whole free steps
    z = np.empty((3, BLOCK))                 # b, y0, y0' of a run's steps (no harmonic force)
    e = p = b = 0
    i = 0
    while i < n:
        while k_first + i >= bounds[b + 1]:
            b += 1
        if e < ev_t.size and ev_step[e] == i:
            e, p = _busy_step(out, i, e, p, ev_t, ev_kind, ev_v, ev_x, ev_step, k_first, a, v,
                              r, b, dt, zeta, delta, A, beta, s0, s1, xi, wi, tail_rebound,
                              x_lower, sw)
            i += 1
            continue
        k = k_first + i
        t_mid = k * dt + 0.5 * dt
        p = _phase_after(t_mid, s0, p)
        if p > 0 and t_mid < s1[p - 1]:
            # a run of whole steps resting in phase p - 1: up to the next event's step, the
            # batch's end, the phase's end or the next phase's start (where _phase_after
            # would move on)
            stop = min(n, bounds[b + 1] - k_first)
            if e < ev_t.size:
                stop = min(stop, ev_step[e])
            lower = sw[p - 1] == 1
            i = _resting_run(out, b, i, stop, k_first, r, dt, x_lower if lower else delta, A,
                             beta, lower, s1[p - 1], s0[p] if p < s0.size else math.inf)
            continue
        # a run of free steps: up to the next event's step, the next sticking phase's
        # first step, the batch's end or BLOCK steps
        stop = min(n, i + BLOCK, bounds[b + 1] - k_first)
        if e < ev_t.size:
            stop = min(stop, ev_step[e])
        if p < s0.size:
            stop = _before_onset(i, stop, s0[p], k_first, dt)
        if A == 0.0:
            _free_run_unforced(a, v, r, i, stop, dt, zeta, delta, z, total[b])
        else:
            _free_run(a, v, r, i, stop, k_first, dt, zeta, delta, A, beta, q, cos_phi,
                      sin_phi, total[b])
        i = stop
    for bb in range(out.shape[1]):
        for row in range(4):
            acc = 0.0
            for s in range(m):
                acc += M[row, s, s] * total[bb, s, s]
                for t in range(s + 1, m):
                    acc += (M[row, s, t] + M[row, t, s]) * total[bb, s, t]
            out[row, bb] += acc
