"""The two exact identities of a stationary record: power balance and virial (self-audit).

For the oscillator ``x'' + 2 zeta x' + x = f - N`` with the wall at ``x = delta``
(docs/model.md, section 7.1), time averages over a record of length T satisfy, up to
boundary terms that fall as 1/T and for any delta and eps,

    power:   <f v> = 2 zeta <v^2> + (1 - eps^2) / (2 T) sum_j V_j^2
    virial:  <v^2> - <x^2> + <x f> = delta [(1 + eps) / T sum_j V_j + <(f - delta) 1_stuck>]

with ``V_j`` the approach velocity of every impact (every rebound of a chatter sequence,
not only a collision's first) and ``1_stuck`` the time resting on the wall.

With a second wall at ``x_L = delta - gap`` (restitution ``eps_L``, hit moving down) each
wall has its own impact term (docs/model.md, section 7.1, "Two walls"):

    power:   ... + (1 - eps_L^2) / (2 T) sum_{j at L} V_j^2
    virial:  ... - x_L [(1 + eps_L) / T sum_{j at L} V_j + <(x_L - f) 1_stuck at L>]

the wall's position times the rate of momentum it gives the mass, with the lower wall's
sign (it pushes up, the upper wall down). A chatter tail
the simulator summed in closed form adds, per tail, ``w^2 / 2`` to the power's loss and
``-w`` to the virial's impulse, ``w`` its last resolved rebound (:func:`flight_moments`).
The averages of the motion are exact integrals of the closed-form motion between events,
so the residuals test the impact record against the motion. Under an impact law whose
restitution varies with the speed (`vibroimpact.model.Restitution`) the sums carry it:
``sum_j (1 - eps(V_j)^2) V_j^2`` and ``sum_j (1 + eps(V_j)) V_j`` (:func:`identity_residuals`).

Pure numpy: no simulation; :mod:`vibroimpact.pipeline.cells` feeds it chunk by chunk.
"""
import math
from typing import NamedTuple

import numpy as np

from vibroimpact import _checks
from vibroimpact.model import law_rates, rebound_velocity

#: Gauss-Legendre nodes per piece of motion between events. A piece is at most one force
#: step long (h = 0.1 in the studies); its integrands are x, v, f and their products, entire
#: functions of time whose rates (1, beta_f) are far below 1/h, so 5 nodes integrate them to
#: round-off (error ~ (h/2)^10 / 10! of the 10th derivative).
GAUSS_NODES = 5
#: Pieces evaluated at once (bounds the memory of a chunk of 2**20 steps).
BLOCK = 2**16

#: A rebound slower than this, followed by a sticking onset with no event between, ends a
#: chatter sequence whose tail the simulator summed in closed form (its rebounds are slower
#: than ``impact.tolerances.RESOLVED_REBOUND = 5e-5``): see :func:`flight_moments`.
TAIL_REBOUND = 1e-4

#: Names of the per-batch sums returned by :func:`flight_moments`, in order: integrals of
#: v^2, x^2, f v, x f, of the wall's reaction f - delta while resting, and the sums of the
#: speeds w and of w^2 of the last rebounds of chatter tails.
MOMENTS = ("v2", "x2", "fv", "xf", "push", "tail", "tail2")
#: With a second wall, the rows that follow `MOMENTS`: the lower wall's reaction
#: ``(delta - gap) - f`` while resting on it, and its chatter tails' ``w`` and ``w^2``
#: (`push`, `tail`, `tail2` are then the upper wall's).
MOMENTS_LOWER = ("push_lower", "tail_lower", "tail2_lower")


def moment_rows(two_walls: bool) -> tuple:
    """The names of the rows of :func:`flight_moments` for one wall or for two."""
    return MOMENTS + MOMENTS_LOWER if two_walls else MOMENTS


def wall_arrays(gap, eps_lower, delta, impact_wall, stick_wall, n_impacts, n_phases):
    """None with one wall; else ``(lower, eps_lower, impact_wall, stick_wall)`` checked
    (positions ``delta - gap``; int8 walls of the impacts and of the sticking phases)."""
    if gap is None:
        if eps_lower is not None or impact_wall is not None or stick_wall is not None:
            raise ValueError("eps_lower, impact_wall and stick_wall need a second wall: give "
                             "gap as well")
        return None
    gap = _checks.real("gap", gap, low=0.0, low_open=True)
    eps_lower = _checks.eps(eps_lower, "eps_lower")
    out = []
    for name, wall, n in (("impact_wall", impact_wall, n_impacts),
                          ("stick_wall", stick_wall, n_phases)):
        wall = np.zeros(n, np.int8) if wall is None and n == 0 else np.asarray(wall)
        if wall.shape != (n,) or not np.all((wall == 0) | (wall == 1)):
            raise ValueError(f"{name} must hold one value per event, each 0 (the wall at "
                             f"delta) or 1 (the wall at delta - gap), shape ({n},), got "
                             f"{np.shape(wall)}")
        out.append(wall.astype(np.int8))
    return float(delta) - gap, eps_lower, out[0], out[1]

_XI, _W = np.polynomial.legendre.leggauss(GAUSS_NODES)


def flight_moments(k_first, x, v, r, dt, *, zeta, eps, delta, amplitude=0.0, beta_f=1.0,
                   impact_time=(), impact_velocity=(), stick_start=(), stick_end=(),
                   batch=None, n_batches=1, gap=None, eps_lower=None, impact_wall=None,
                   stick_wall=None, speed_scale=math.inf, speed_scale_lower=None):
    """Exact integrals of v^2, x^2, f v, x f and the wall's push over force steps.

    Parameters
    ----------
    k_first : int
        Sample index of the first step.
    x, v : array_like, shape (n,)
        Displacement and velocity at samples ``k_first .. k_first + n - 1`` (the simulator's
        state there, ``record_every=1``); the steps integrated are those that start there.
    r : array_like, shape (n + 1,)
        Random force samples ``k_first .. k_first + n``.
    dt : float
        Sample step h.
    zeta, eps, delta, amplitude, beta_f : float
        Physical parameters; the force is ``r(tau) + amplitude sin(beta_f tau)`` with ``r``
        the straight line between samples.
    impact_time, impact_velocity : array_like
        Impacts inside the steps (approach velocities ``V > 0``); the mass leaves at
        ``-eps V``.
    stick_start, stick_end : array_like
        Sticking phases (sorted, disjoint); they may reach beyond the steps.
    batch : array_like of int, shape (n,), optional
        Batch of each step (default: all in batch 0).
    n_batches : int
        Number of batches of the output.
    gap, eps_lower : float, optional
        A second wall at ``delta - gap`` with restitution ``eps_lower`` (both or neither).
    impact_wall, stick_wall : array_like of int, optional
        With a second wall: the wall of each impact and of each sticking phase (0: at
        delta, 1: at delta - gap; the simulator's ``impact_wall``, ``stick_wall``). An
        impact at the lower wall leaves at ``+eps_lower V``.
    speed_scale, speed_scale_lower : float, optional
        The walls' impact laws (`vibroimpact.model.Restitution`; ``inf``, the default,
        Newton's): an impact leaves at its wall's ``rebound_velocity``.

    Returns
    -------
    ndarray, shape (len(MOMENTS), n_batches), or (len(MOMENTS + MOMENTS_LOWER), n_batches)
        Per batch (rows in the order of :data:`MOMENTS`): the integrals over its steps of
        ``v^2``, ``x^2``, ``f v``, ``x f`` and of the push ``f - delta`` while resting on the
        wall (the wall's reaction there), and the sums of ``w`` and ``w^2`` over the chatter
        tails that begin in it. With a second wall these three are the upper wall's and
        the rows of :data:`MOMENTS_LOWER` follow: the push ``(delta - gap) - f`` while
        resting on the lower wall, its tails' ``w`` and ``w^2``.

    Notes
    -----
    The steps are cut at every impact and every start and end of a sticking phase. On a
    piece resting on the wall ``x = delta, v = 0``. A free piece starts from the sampled
    state, from ``(delta, -eps V)`` after an impact or from ``(delta, 0)`` after a release,
    and follows the closed form of docs/model.md, section 5; its integrals are taken by
    Gauss-Legendre quadrature with :data:`GAUSS_NODES` nodes, exact to round-off.

    A chatter sequence whose tail the simulator summed in closed form shows as a last
    resolved rebound of speed ``w < TAIL_REBOUND`` followed by a sticking onset. From that
    rebound on the piece is taken as resting, the rebound's momentum ``w`` and energy
    ``w^2 / 2`` absorbed by the wall (rows ``tail``, ``tail2``): the tail's wall impulse is
    then ``(f - delta)`` over its duration minus ``w``, its energy loss ``w^2 / 2``, as for
    the unresolved rebounds, to within ``O(w^2)``.
    """
    x = np.asarray(x, dtype=float)
    v = np.asarray(v, dtype=float)
    r = np.asarray(r, dtype=float)
    n = x.size
    if v.size != n or r.size != n + 1:
        raise ValueError(f"need x, v of n samples and r of n + 1, got {n}, {v.size}, {r.size}")
    batch = np.zeros(n, np.int64) if batch is None else np.asarray(batch, dtype=np.int64)
    k = k_first + np.arange(n)
    tk = k * dt
    t_imp = np.asarray(impact_time, dtype=float)
    u_imp = np.asarray(impact_velocity, dtype=float)
    s0 = np.asarray(stick_start, dtype=float)
    s1 = np.asarray(stick_end, dtype=float)
    walls = wall_arrays(gap, eps_lower, delta, impact_wall, stick_wall, t_imp.size, s0.size)
    t_lo, t_hi = tk[0] if n else 0.0, (k_first + n) * dt
    hit = (t_imp >= t_lo) & (t_imp <= t_hi)
    on_mask = (s0 >= t_lo) & (s0 <= t_hi)
    off_mask = (s1 >= t_lo) & (s1 <= t_hi)
    on, off = s0[on_mask], s1[off_mask]
    # events: impacts (kind 1), sticking onsets (2) and releases (3), each in the step of the
    # last sample at or before it; at equal times the sample comes first, so an event at a
    # sample sets the state after it
    ev_t = np.concatenate([t_imp[hit], on, off])
    ev_kind = np.repeat([1.0, 2.0, 3.0], [np.count_nonzero(hit), on.size, off.size])
    law_a, law_a_lower = law_rates(speed_scale, speed_scale_lower)
    # the velocity leaving each impact, by its wall's law (Newton's: -eps V, to the bit)
    ev_v = np.concatenate([rebound_velocity(eps, u_imp[hit], law_a),
                           np.zeros(on.size + off.size)])
    ev_x = np.full(ev_t.size, delta)
    if walls is not None:
        # the lower wall's events: at x_L, leaving an impact upwards at eps_L V
        x_lower, e_lower, iw, sw = walls
        ev_lower = np.concatenate([iw[hit], sw[on_mask], sw[off_mask]]) == 1
        ev_x[ev_lower] = x_lower
        i_lower = np.flatnonzero(ev_lower[:np.count_nonzero(hit)])
        ev_v[i_lower] = -rebound_velocity(e_lower, u_imp[hit][i_lower], law_a_lower)
    ev_step = np.searchsorted(tk, ev_t, side="right") - 1
    busy = np.zeros(n, bool)
    busy[ev_step] = True
    held = _resting(tk + 0.5 * dt, s0, s1)
    out = np.zeros((len(moment_rows(walls is not None)), int(n_batches)))

    def add(rows, st, values):                  # per-step values into their batches
        for row, value in zip(rows, values):
            out[row] += np.bincount(batch[st], weights=value, minlength=out.shape[1])

    # steps without events, free: quadratic forms z^T M z of the state at their start, summed
    # per batch as <M, sum z z^T> over each run of steps of one batch
    free = ~busy & ~held
    i = np.flatnonzero(free)
    if i.size:
        pick = slice(None) if i.size == n else i          # most chunks: every step, no copy
        M, z = _whole_step_forms(k[pick], x[pick], v[pick], r[:-1][pick], r[1:][pick], dt, zeta,
                                 amplitude, beta_f)
        cuts = np.flatnonzero(np.diff(batch[i])) + 1
        for lo, hi in zip(np.concatenate([[0], cuts]), np.concatenate([cuts, [i.size]])):
            zs = z[:, lo:hi]
            out[:4, batch[i[lo]]] += np.einsum("mij,ij->m", M, zs @ zs.T)
    # steps without events, resting on the wall: x = delta, v = 0
    st = np.flatnonzero(~busy & held)
    if walls is None:
        add((1, 3, 4), st, _resting_integrals(np.zeros(st.size), dt, st, r, k_first, dt,
                                              delta, amplitude, beta_f))
    else:
        lower = walls[3][_phase_of(tk[st] + 0.5 * dt, s0)] == 1
        _add_resting_walls(add, lower, np.zeros(st.size), np.full(st.size, dt), st, r,
                           k_first, dt, delta, walls[0], amplitude, beta_f)
    # steps with events: cut into pieces at every event
    bs = np.flatnonzero(busy)
    times = np.concatenate([tk[bs], ev_t])
    kind = np.concatenate([np.zeros(bs.size), ev_kind])
    step = np.concatenate([bs, ev_step])
    x0 = np.concatenate([x[bs], ev_x])
    v0 = np.concatenate([v[bs], ev_v])
    order = np.lexsort((kind, times, step))
    times, kind, step, x0, v0 = times[order], kind[order], step[order], x0[order], v0[order]
    same = np.append(step[1:] == step[:-1], False)           # the next piece is in the step
    end = np.where(same, np.append(times[1:], 0.0), (step + k_first + 1) * dt)
    length = np.maximum(end - times, 0.0)
    stuck = _resting(times + 0.5 * length, s0, s1)
    # the closed-form end of a chatter sequence: from its last resolved rebound to the onset
    # (a rebound leaves the upper wall downwards, the lower one upwards: w = |v0|)
    tail = (kind == 1) & same & (np.append(kind[1:], 0) == 2) & (np.abs(v0) < TAIL_REBOUND)
    stuck |= tail
    w = np.abs(v0[tail])
    offset = times - (step + k_first) * dt
    j = np.flatnonzero(stuck)
    if walls is None:
        add((5, 6), step[tail], (w, w * w))
        add((1, 3, 4), step[j], _resting_integrals(offset[j], length[j], step[j], r, k_first,
                                                   dt, delta, amplitude, beta_f))
    else:
        # a tail rests at its impact's wall; any other resting piece at its phase's
        tail_lower = x0[tail] != delta
        add((5, 6), step[tail][~tail_lower], (w[~tail_lower], w[~tail_lower] ** 2))
        add((8, 9), step[tail][tail_lower], (w[tail_lower], w[tail_lower] ** 2))
        lower = np.where(tail[j], x0[j] != delta,
                         walls[3][_phase_of(times[j] + 0.5 * length[j], s0)] == 1)
        _add_resting_walls(add, lower, offset[j], length[j], step[j], r, k_first, dt, delta,
                           walls[0], amplitude, beta_f)
    j = np.flatnonzero(~stuck)
    for lo in range(0, j.size, BLOCK):
        sl = j[lo:lo + BLOCK]
        st = step[sl]
        add(range(4), st, _piece_integrals(offset[sl], length[sl], st + k_first, x0[sl],
                                           v0[sl], r[st], r[st + 1], dt, zeta, amplitude,
                                           beta_f))
    return out


def _resting_integrals(s_a, L, st, r, k_first, dt, delta, A, beta):
    """Integrals of x^2, x f and the push f - delta over pieces resting on the wall."""
    slope = (r[st + 1] - r[st]) / dt
    f_int = L * (r[st] + slope * (s_a + 0.5 * L))
    if A != 0.0:
        tau = (st + k_first) * dt + s_a
        f_int = f_int + A / beta * (np.cos(beta * tau) - np.cos(beta * (tau + L)))
    return np.broadcast_to(delta * delta * L, f_int.shape), delta * f_int, f_int - delta * L


def _add_resting_walls(add, lower, s_a, L, st, r, k_first, dt, delta, x_lower, A, beta):
    """The resting integrals of pieces at the upper wall (rows x2, xf, push) and at the
    lower one (rows x2, xf, push_lower, whose push is ``x_lower - f``)."""
    for at, x_w, rows, sign in ((~lower, delta, (1, 3, 4), 1.0),
                                (lower, x_lower, (1, 3, 7), -1.0)):
        x2, xf, push = _resting_integrals(s_a[at], L[at], st[at], r, k_first, dt, x_w, A, beta)
        add(rows, st[at], (x2, xf, sign * push))


def _phase_of(t, s0):
    """The sticking phase begun last at or before each instant ``t`` (0 if none)."""
    return np.maximum(np.searchsorted(s0, t, side="right") - 1, 0)


def _resting(t, s0, s1):
    """Whether the instants ``t`` lie inside a sticking phase ``[s0, s1)`` (sorted)."""
    if not s0.size:
        return np.zeros(t.size, bool)
    j = np.searchsorted(s0, t, side="right") - 1
    return (j >= 0) & (t < s1[np.maximum(j, 0)])


def step_forms(dt, zeta, amplitude=0.0, beta_f=1.0):
    """The matrices of the integrals of v^2, x^2, f v, x f over a whole free step.

    On a whole step x, v and f at the fixed nodes are linear in
    ``z = (r0, b, y0, y0', sin psi, cos psi)`` (``r0`` the force sample at the step's start,
    ``b`` the slope, ``y`` the free response, ``psi = beta_f k h``), so each integral is
    ``z^T M z`` with M the same for every step.

    Returns
    -------
    ndarray, shape (4, m, m)
        The symmetric matrices, in the order v^2, x^2, f v, x f; ``m = 6``, or 4 without a
        harmonic force (no ``sin psi, cos psi``).
    """
    A, beta = amplitude, beta_f
    wd = np.sqrt(1.0 - zeta * zeta)
    sig = 0.5 * dt * (1.0 + _XI)
    w = 0.5 * dt * _W
    q = A / np.hypot(1.0 - beta * beta, 2.0 * zeta * beta)
    phi = np.arctan2(2.0 * zeta * beta, 1.0 - beta * beta)
    E = np.exp(-zeta * sig) * np.cos(wd * sig)
    S = np.exp(-zeta * sig) * np.sin(wd * sig) / wd
    cp, sp = np.cos(beta * sig - phi), np.sin(beta * sig - phi)
    one, zero = np.ones_like(sig), np.zeros_like(sig)
    a = np.array([one, sig - 2.0 * zeta, E + zeta * S, S, q * cp, q * sp])      # x at nodes
    b = np.array([zero, one, -S, E - zeta * S, -q * beta * sp, q * beta * cp])  # v
    c = np.array([one, sig, zero, zero, A * np.cos(beta * sig), A * np.sin(beta * sig)])  # f
    form = lambda g, h: 0.5 * ((g * w) @ h.T + (h * w) @ g.T)
    M = np.stack([form(b, b), form(a, a), form(c, b), form(a, c)])
    return M if A != 0.0 else M[:, :4, :4]


def _whole_step_forms(k, x0, v0, r0, r1, dt, zeta, A, beta):
    """The matrices of :func:`step_forms` and the vectors ``z``, shape (m, n), of whole steps."""
    M = step_forms(dt, zeta, A, beta)
    slope = (r1 - r0) / dt
    if A == 0.0:
        return M, np.array([r0, slope, x0 - r0 + 2.0 * zeta * slope, v0 - slope])
    q = A / np.hypot(1.0 - beta * beta, 2.0 * zeta * beta)
    phi = np.arctan2(2.0 * zeta * beta, 1.0 - beta * beta)
    psi = beta * (k * dt)
    sin_psi, cos_psi = np.sin(psi), np.cos(psi)
    sin_pa = sin_psi * np.cos(phi) - cos_psi * np.sin(phi)
    cos_pa = cos_psi * np.cos(phi) + sin_psi * np.sin(phi)
    y0 = x0 - (r0 - 2.0 * zeta * slope + q * sin_pa)
    yv0 = v0 - (slope + q * beta * cos_pa)
    return M, np.array([r0, slope, y0, yv0, sin_psi, cos_psi])


def _piece_integrals(s_a, L, k, x0, v0, r0, r1, dt, zeta, A, beta):
    """Integrals of v^2, x^2, f v and x f over free pieces.

    A piece starts at offset ``s_a`` of step ``k`` and lasts ``L``.
    """
    wd = np.sqrt(1.0 - zeta * zeta)
    slope = (r1 - r0) / dt
    s_a = np.asarray(s_a, dtype=float)
    L = np.asarray(L, dtype=float)[:, None]
    sig = 0.5 * L * (1.0 + _XI)                          # nodes, from the piece's start
    wts = 0.5 * L * _W
    s = s_a[:, None] + sig                               # offsets in the step
    f = r0[:, None] + slope[:, None] * s
    p = f - (2.0 * zeta * slope)[:, None]                # particular solution, linear force
    dp = np.broadcast_to(slope[:, None], f.shape)
    p_a = r0 + slope * s_a - 2.0 * zeta * slope
    dp_a = slope
    if A != 0.0:
        q = A / np.hypot(1.0 - beta * beta, 2.0 * zeta * beta)
        phi = np.arctan2(2.0 * zeta * beta, 1.0 - beta * beta)
        psi = beta * (k * dt + s_a)                      # phase of the force at the start
        cb, sb = np.cos(beta * sig), np.sin(beta * sig)
        sin_f = (np.sin(psi)[:, None] * cb + np.cos(psi)[:, None] * sb)
        sin_p = (np.sin(psi - phi)[:, None] * cb + np.cos(psi - phi)[:, None] * sb)
        cos_p = (np.cos(psi - phi)[:, None] * cb - np.sin(psi - phi)[:, None] * sb)
        f = f + A * sin_f
        p, dp = p + q * sin_p, dp + q * beta * cos_p
        p_a = p_a + q * np.sin(psi - phi)
        dp_a = dp_a + q * beta * np.cos(psi - phi)
    y0, yv0 = (x0 - p_a)[:, None], (v0 - dp_a)[:, None]
    e = np.exp(-zeta * sig)
    c, sn = e * np.cos(wd * sig), e * np.sin(wd * sig) / wd
    xs = p + (c + zeta * sn) * y0 + sn * yv0
    vs = dp - sn * y0 + (c - zeta * sn) * yv0
    integ = lambda g: np.sum(wts * g, axis=1)
    return integ(vs * vs), integ(xs * xs), integ(f * vs), integ(xs * f)


class IdentityResiduals(NamedTuple):
    """Residuals of the power balance and of the virial, with batch-means errors."""

    power: float            #: <f v> - 2 zeta <v^2> - (1 - eps^2) nu <V^2> / 2
    power_stderr: float     #: batch-means standard error of `power`
    power_input: float      #: <f v>, the power the force feeds in (the scale of `power`)
    virial: float           #: <v^2> - <x^2> + <x f> - delta [(1 + eps) nu <V> + <push>]
    virial_stderr: float    #: batch-means standard error of `virial`
    virial_scale: float     #: <v^2> (the scale of `virial`)
    n_batches: int          #: batches B


def identity_residuals(moments, impact_sum, impact_sum2, durations, *, zeta, eps, delta,
                       gap=None, eps_lower=None):
    """Residuals of the two exact identities and their batch-means standard errors.

    Parameters
    ----------
    moments : array_like, shape (len(MOMENTS), B)
        Per-batch integrals from :func:`flight_moments` (summed over a record's chunks).
    impact_sum, impact_sum2 : array_like, shape (B,)
        Per batch, the sum of the approach velocities ``V_j`` and of ``V_j^2`` of every
        impact (every rebound) in the batch. Under an impact law whose restitution varies
        with the speed: the sums of ``(1 + eps(V_j)) V_j`` (the momentum each impact
        exchanges) and ``(1 - eps(V_j)^2) V_j^2`` (twice the energy it takes), with ``eps``
        and ``eps_lower`` 0, which leaves them as they are.
    durations : array_like, shape (B,)
        Length of each batch (contiguous stretches of the record).
    zeta, eps, delta : float
        Physical parameters.
    gap, eps_lower : float, optional
        A second wall at ``delta - gap`` with restitution ``eps_lower``: ``moments`` then
        has the rows of ``MOMENTS + MOMENTS_LOWER`` and ``impact_sum``, ``impact_sum2`` have
        shape (2, B), the upper wall's sums first.

    Returns
    -------
    IdentityResiduals
        Residuals over the whole record (integrals over its length) and
        ``std(batch residuals, ddof=1) / sqrt(B)``. Each identity holds on every record up
        to a boundary term (``[E]/T`` and ``[x v + zeta x^2]/T``), so an exact record has
        residuals well within their standard errors, which bound those boundary terms.
    """
    m = np.asarray(moments, dtype=float)
    su, su2 = np.asarray(impact_sum, dtype=float), np.asarray(impact_sum2, dtype=float)
    T = np.asarray(durations, dtype=float)
    two = gap is not None
    if two != (eps_lower is not None):
        raise ValueError("gap and eps_lower go together: give both for a second wall")
    rows = moment_rows(two)
    if m.shape[0] != len(rows) or su.shape != su2.shape or su.shape != (
            (2,) if two else ()) + T.shape:
        raise ValueError(f"moments must have the rows {rows} and the impact sums shape "
                         f"{'(2, B)' if two else '(B,)'} with B = {T.size}, got "
                         f"{m.shape}, {su.shape} and {su2.shape}")
    v2, x2, fv, xf, push, tail, tail2 = m[:len(MOMENTS)]
    if two:
        su, su_lower = su
        su2, su2_lower = su2
    power = fv - 2.0 * zeta * v2 - 0.5 * (1.0 - eps * eps) * su2 - 0.5 * tail2
    virial = v2 - x2 + xf - delta * ((1.0 + eps) * su - tail + push)
    if two:
        # the lower wall: its loss, and its position times the momentum it gives (upwards)
        x_lower = delta - gap
        push_lower, tail_lower, tail2_lower = m[len(MOMENTS):]
        power = (power - 0.5 * (1.0 - eps_lower * eps_lower) * su2_lower
                 - 0.5 * tail2_lower)
        virial = virial + x_lower * ((1.0 + eps_lower) * su_lower - tail_lower + push_lower)
    total = T.sum()
    B = T.size
    err = lambda a: float(np.std(a / T, ddof=1) / np.sqrt(B)) if B >= 2 else np.nan
    return IdentityResiduals(float(power.sum() / total), err(power), float(fv.sum() / total),
                             float(virial.sum() / total), err(virial), float(v2.sum() / total),
                             B)
