"""Peers of the simulator: general-purpose integrators given the same problem.

Every peer integrates the oscillator of docs/model.md (x'' + 2 zeta x' + x = r(tau), wall at
x = delta, restitution eps) under a piecewise-linear random force r(tau) sampled every `dt`
(no harmonic part), and returns the impacts it found as ``(impact_time, impact_velocity)``
float64 arrays, impact_velocity being the approach velocity u_{j-0} > 0. They are what a user
without this package would reach for, set up with care so that the comparison measures the
methods (`vibroimpact.validation.work_precision` times them against the simulator):

- `solve_ivp_impacts`: scipy.integrate.solve_ivp (RK45, DOP853, LSODA, ...) restarted at every
  force sample (so no step ever straddles a kink of r) and after every impact (a terminal
  event on x - delta).
- `rk4_event_impacts`: classical fixed-step RK4 at h = dt / k with event location: the impact
  is the first upward zero of the step's cubic Hermite interpolant, and the integration
  restarts there with the rebound. Compiled by numba, since it runs per step.
- `rk4_clamp_impacts`: fixed-step RK4 with the wall imposed by clamping (no event location:
  the naive scheme, first order at best in the impact time).

Also here: the bare recurrence that bounds any exact simulator from below
(`linear_propagator`, `linear_recurrence`).

Nothing here is used to compute results: the package's own simulator is
`vibroimpact.simulate`.
"""
import math

import numpy as np
import scipy.integrate
import scipy.linalg
from numba import njit

from vibroimpact import _law
from vibroimpact._kernel_cache import kernel_decorator
from vibroimpact.model import rebound_velocity

#: ``njit(cache=True)`` stamped with this file and the impact law (the event peers rebound by
#: it: :mod:`vibroimpact._law`), so that an edit of the law recompiles them.
_kernel = kernel_decorator(njit, __file__,
                           ("peers.py",) + tuple(f"../{m}" for m in _law.LAW_MODULES))

V_STICK = 1e-7
"""Rebound speed below which the event-locating peers leave the mass at rest on the wall.

The rest of the sequence (~2 V_STICK / ((1 - eps) (r - delta)) of time) is skipped: its impacts
are slower still, in the chatter tail that the comparison does not take impact by impact."""


def _check_problem(zeta, eps, delta, noise, dt):
    if not 0.0 < zeta < 1.0:
        raise ValueError(f"zeta must lie in (0, 1), got {zeta!r}")
    if not 0.0 <= eps <= 1.0:
        raise ValueError(f"eps must lie in [0, 1], got {eps!r}")
    if not math.isfinite(delta):
        raise ValueError(f"delta must be a finite number, got {delta!r}")
    if not dt > 0.0:
        raise ValueError(f"dt must be positive, got {dt!r}")
    noise = np.ascontiguousarray(noise, dtype=np.float64)
    if noise.ndim != 1 or noise.size < 2:
        raise ValueError(f"noise must be a 1-D array of at least 2 samples, "
                         f"got shape {noise.shape}")
    return noise


def _n_intervals(noise, dt, t_end):
    """Number of sample intervals to integrate, and the end time."""
    if t_end is None:
        t_end = (noise.size - 1) * dt
    n = int(math.ceil(t_end / dt - 1e-9))
    if n > noise.size - 1:
        raise ValueError(f"t_end={t_end} lies beyond the last noise sample at "
                         f"{(noise.size - 1) * dt}")
    return n, t_end


# ---------------------------------------------------------------------------------------------
# scipy.integrate.solve_ivp with per-sample restarts and terminal impact events
# ---------------------------------------------------------------------------------------------

def _make_rhs(zeta, t_a, r0, b):
    """Right-hand side on one sample interval, where r(tau) = r0 + b (tau - t_a)."""
    two_zeta = 2.0 * zeta

    def rhs(t, y):
        return np.array([y[1], r0 + b * (t - t_a) - y[0] - two_zeta * y[1]])

    return rhs


def _make_wall_event(delta, t_quiet):
    """Terminal event x - delta = 0 crossed upwards, ignored up to time t_quiet.

    The integration restarts on the wall after every impact (g = 0 there); scipy would report
    that starting point as a root as soon as a first step jumps over a short flight, so g is
    -1 until t_quiet (at least the start): the only sign change left is a real arrival."""

    def wall(t, y):
        return y[0] - delta if t > t_quiet else -1.0

    wall.terminal = True
    wall.direction = 1.0
    return wall


def solve_ivp_impacts(zeta, eps, delta, noise, dt, method="DOP853", rtol=1e-10, atol=None,
                      x0=None, v0=0.0, t_end=None, v_stick=V_STICK):
    """Impacts found by `scipy.integrate.solve_ivp` restarted at every force sample.

    Parameters
    ----------
    zeta, eps, delta : float
        Damping ratio, restitution coefficient, wall position (docs/model.md).
    noise : ndarray of float64, shape (n,)
        r[k] = r(k dt); r is linear in between.
    dt : float
        Sample step, < pi.
    method : {"RK45", "DOP853", "LSODA", ...}
        Passed to `solve_ivp`.
    rtol, atol : float
        Tolerances; atol defaults to rtol (the state is O(1)).
    x0, v0 : float
        Initial state; x0=None means min(0, delta), the static rest position.
    t_end : float, optional
        End time; default (n - 1) dt.
    v_stick : float
        A rebound slower than this leaves the mass at rest on the wall (the end of a chatter
        sequence): it sticks while r - delta > 0 and leaves where r - delta turns negative (an
        exact linear root).

    Returns
    -------
    impact_time, impact_velocity : ndarray of float64
        Impact instants and approach velocities u_{j-0} > 0.

    Notes
    -----
    One `solve_ivp` call per sample interval (or per flight within it): a step across a kink of
    r would lose the method's order there. The impact map is eq. 7 of the paper.

    A mass leaving the wall from rest cannot come back while r < delta: y = delta - x obeys
    y'' + 2 zeta y' + y = delta - r > 0 from y = y' = 0, and the impulse response is positive
    for a half period pi / omega_d > dt. Wall events are therefore ignored until r returns to
    delta or the sample ends; otherwise a loose solver drifting across the wall right after a
    release would register endless spurious contacts.
    """
    noise = _check_problem(zeta, eps, delta, noise, dt)
    if dt >= math.pi:
        raise ValueError(f"dt must be < pi for the release rule, got {dt!r}")
    n, t_end = _n_intervals(noise, dt, t_end)
    atol = rtol if atol is None else atol
    x = min(0.0, delta) if x0 is None else float(x0)
    v = float(v0)
    resting = x == delta and v == 0.0
    stuck = False
    times, velocities = [], []
    for k in range(n):
        t_a = k * dt
        t_b = min((k + 1) * dt, t_end)
        r0 = noise[k]
        b = (noise[k + 1] - r0) / dt
        rhs = _make_rhs(zeta, t_a, r0, b)
        t = t_a
        t_quiet = t_a
        while t < t_b:
            if resting:
                push = r0 + b * (t - t_a) - delta
                resting = False
                stuck = push > 0.0 or (push == 0.0 and b > 0.0)
                if not stuck:  # leaves at once; quiet until r comes back to delta
                    t_quiet = t_b if b <= 0.0 else min(t_b, t_a + (delta - r0) / b)
            if stuck:
                if r0 + b * (t_b - t_a) - delta >= 0.0:
                    break
                t = max(t, t_a + (delta - r0) / b)
                stuck = False
                x, v = delta, 0.0
                t_quiet = t_b
                continue
            sol = scipy.integrate.solve_ivp(rhs, (t, t_b), [x, v], method=method, rtol=rtol,
                                            atol=atol,
                                            events=_make_wall_event(delta, max(t, t_quiet)))
            if sol.status != 1:
                if sol.status != 0:
                    raise RuntimeError(f"solve_ivp failed at tau={t}: {sol.message}")
                x, v = sol.y[0, -1], sol.y[1, -1]
                break
            t = sol.t_events[0][0]
            u = sol.y_events[0][0][1]
            times.append(t)
            velocities.append(u)
            x = delta
            v = rebound_velocity(eps, u)
            if -v < v_stick:
                v = 0.0
                resting = True
    return np.array(times), np.array(velocities)


# ---------------------------------------------------------------------------------------------
# Fixed-step RK4 with event location (cubic Hermite interpolant) and restart at the impact
# ---------------------------------------------------------------------------------------------

@_kernel
def _rk4_step(x, v, s, f0, b, two_zeta):
    """One classical RK4 step of length s from (x, v); the force is f0 + b * (elapsed time)."""
    f_half = f0 + 0.5 * b * s
    f_end = f0 + b * s
    k1x = v
    k1v = f0 - x - two_zeta * v
    xa = x + 0.5 * s * k1x
    va = v + 0.5 * s * k1v
    k2x = va
    k2v = f_half - xa - two_zeta * va
    xb = x + 0.5 * s * k2x
    vb = v + 0.5 * s * k2v
    k3x = vb
    k3v = f_half - xb - two_zeta * vb
    xc = x + s * k3x
    vc = v + s * k3v
    k4x = vc
    k4v = f_end - xc - two_zeta * vc
    return (x + s / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x),
            v + s / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v))


@_kernel
def _cubic(c0, c1, c2, c3, theta):
    return c0 + theta * (c1 + theta * (c2 + theta * c3))


@_kernel
def _upcrossing(c0, c1, c2, c3, a, b):
    """Zero of the cubic on [a, b] if it is <= 0 at a and > 0 at b (bisection to the last bit,
    the cubic being monotone there), else -1."""
    if not (_cubic(c0, c1, c2, c3, a) <= 0.0 < _cubic(c0, c1, c2, c3, b)):
        return -1.0
    for _ in range(200):
        mid = 0.5 * (a + b)
        if mid <= a or mid >= b:
            break
        if _cubic(c0, c1, c2, c3, mid) > 0.0:
            b = mid
        else:
            a = mid
    return b


@_kernel
def _first_upcrossing(p0, m0, p1, m1, lo):
    """First upward zero in [lo, 1] of the cubic Hermite interpolant of a step, or -1.

    p0, p1 are x - delta at the step's ends, m0, m1 the velocities times the step length, and
    theta in [0, 1] the fraction of the step. The cubic's critical points split [lo, 1] into
    monotone pieces; the first piece that rises through zero holds the event. A flight that
    leaves the wall and comes back within one step (both ends below it) is caught too.
    """
    c1 = m0
    c2 = -3.0 * p0 - 2.0 * m0 + 3.0 * p1 - m1
    c3 = 2.0 * p0 + m0 - 2.0 * p1 + m1
    # critical points: roots of c1 + 2 c2 theta + 3 c3 theta^2 (stable quadratic formula)
    qa, qb = 3.0 * c3, 2.0 * c2
    e1 = e2 = lo
    if qa == 0.0:
        if qb != 0.0:
            e1 = e2 = -c1 / qb
    else:
        disc = qb * qb - 4.0 * qa * c1
        if disc >= 0.0:
            q = -0.5 * (qb + math.copysign(math.sqrt(disc), qb))
            r1 = q / qa
            r2 = c1 / q if q != 0.0 else r1
            e1, e2 = min(r1, r2), max(r1, r2)
    e1 = min(max(e1, lo), 1.0)
    e2 = min(max(e2, lo), 1.0)
    for a, b in ((lo, e1), (e1, e2), (e2, 1.0)):
        if b > a:
            theta = _upcrossing(p0, c1, c2, c3, a, b)
            if theta >= 0.0:
                return theta
    return -1.0


@_kernel
def _rk4_event_kernel(noise, dt, m, n_intervals, t_end, zeta, eps, delta, x0, v0, v_stick,
                      impact_time, impact_velocity):
    """RK4 with m steps per sample, impacts located on the step's cubic Hermite interpolant.

    Mirrors the sample loop of `solve_ivp_impacts` (same resting, sticking and release rules);
    only the integrator differs. Returns the number of impacts (those beyond the buffers'
    capacity are counted, not stored).
    """
    h = dt / m
    two_zeta = 2.0 * zeta
    x = x0
    v = v0
    resting = x == delta and v == 0.0
    stuck = False
    n_impacts = 0
    capacity = impact_time.size
    for k in range(n_intervals):
        t_a = k * dt
        t_b = min((k + 1) * dt, t_end)
        r0 = noise[k]
        b = (noise[k + 1] - r0) / dt
        t = t_a
        t_quiet = t_a
        node = 1  # next grid point t_a + node * h
        while t < t_b:
            if resting:
                push = r0 + b * (t - t_a) - delta
                resting = False
                stuck = push > 0.0 or (push == 0.0 and b > 0.0)
                if not stuck:  # leaves at once; quiet until r comes back to delta
                    t_quiet = t_b if b <= 0.0 else min(t_b, t_a + (delta - r0) / b)
            if stuck:
                if r0 + b * (t_b - t_a) - delta >= 0.0:
                    break
                t = max(t, t_a + (delta - r0) / b)
                stuck = False
                x = delta
                v = 0.0
                t_quiet = t_b
                continue
            t_node = t_b if node >= m else min(t_a + node * h, t_b)
            if t_node <= t:
                node += 1
                continue
            s = t_node - t
            f0 = r0 + b * (t - t_a)
            x1, v1 = _rk4_step(x, v, s, f0, b, two_zeta)
            lo = max(0.0, (t_quiet - t) / s)
            theta = -1.0
            if lo < 1.0:
                theta = _first_upcrossing(x - delta, s * v, x1 - delta, s * v1, lo)
            if theta < 0.0:
                # the wall is impenetrable: an end point beyond it is the scheme's own error
                x = min(x1, delta)
                v = v1
                t = t_node
                node += 1
                continue
            # the state at the event: a fresh RK4 step to it (the interpolant's derivative
            # would cost an order in the impact velocity)
            s_impact = theta * s
            _, u = _rk4_step(x, v, s_impact, f0, b, two_zeta)
            u = max(u, 0.0)
            t = t + s_impact
            if n_impacts < capacity:
                impact_time[n_impacts] = t
                impact_velocity[n_impacts] = u
            n_impacts += 1
            x = delta
            v = _law.rebound_velocity(eps, u)
            if -v < v_stick:
                v = 0.0
                resting = True
    return n_impacts


def rk4_event_impacts(zeta, eps, delta, noise, dt, steps_per_sample=1, x0=None, v0=0.0,
                      t_end=None, v_stick=V_STICK):
    """Impacts found by fixed-step RK4 with event location and restart at every impact.

    The fixed-step scheme a careful user would write: classical RK4 at h = dt / k (so every
    stage sees the force's own linear piece), the impact located inside the step as the first
    upward zero of the step's cubic Hermite interpolant of x - delta (end values and
    velocities), the state at the impact recomputed by an RK4 step from the step's start to
    the impact, and the integration restarted there with the rebound -eps u. It runs per step,
    so it is compiled by numba (`cache=True`): the comparison with `vibroimpact.simulate`
    measures the method, not the interpreter.

    Parameters
    ----------
    zeta, eps, delta, noise, dt, x0, v0, t_end, v_stick
        As in `solve_ivp_impacts` (same resting, sticking and release rules).
    steps_per_sample : int
        k: RK4 steps per sample interval, h = dt / k.

    Returns
    -------
    impact_time, impact_velocity : ndarray of float64
        Impact instants and approach velocities u_{j-0} >= 0.

    Notes
    -----
    Both the step and the interpolant are fourth order, so impact times and velocities
    converge as h^4 (measured in tests/test_validation_targets.py) while no impact is
    grazing. After a rebound the interpolant matches the step's start exactly (x = delta and
    the rebound velocity), so even a flight much shorter than h is located to a relative
    error of O(h^2). Steps restart from the impact and rejoin the grid t_a + j h at the next
    grid point. The impact map is eq. 7 of the paper.
    """
    noise = _check_problem(zeta, eps, delta, noise, dt)
    if dt >= math.pi:
        raise ValueError(f"dt must be < pi for the release rule, got {dt!r}")
    n, t_end = _n_intervals(noise, dt, t_end)
    m = int(steps_per_sample)
    if m < 1:
        raise ValueError(f"steps_per_sample must be a positive integer, got {steps_per_sample!r}")
    x = min(0.0, delta) if x0 is None else float(x0)
    if x > delta:
        raise ValueError(f"x0 must be <= delta, got {x0!r}")
    capacity = 4 * n + 16
    while True:
        impact_time = np.empty(capacity)
        impact_velocity = np.empty(capacity)
        n_impacts = _rk4_event_kernel(noise, dt, m, n, float(t_end), zeta, eps, delta, x,
                                      float(v0), float(v_stick), impact_time, impact_velocity)
        if n_impacts <= capacity:
            return impact_time[:n_impacts], impact_velocity[:n_impacts]
        capacity = 2 * n_impacts


# ---------------------------------------------------------------------------------------------
# Fixed-step RK4 with clamping at the wall
# ---------------------------------------------------------------------------------------------

@_kernel
def _rk4_clamp_kernel(noise, dt, m, n_intervals, zeta, eps, delta, x0, v0,
                      impact_time, impact_velocity):
    """RK4 with m steps per sample; x > delta is clamped to delta, and v > 0 there reversed."""
    h = dt / m
    two_zeta = 2.0 * zeta
    x = x0
    v = v0
    n_impacts = 0
    capacity = impact_time.size
    for k in range(n_intervals):
        r0 = noise[k]
        b = (noise[k + 1] - r0) / dt
        for j in range(m):
            s = j * h
            x, v = _rk4_step(x, v, h, r0 + b * s, b, two_zeta)
            if x > delta:
                x = delta
                if v > 0.0:
                    if n_impacts < capacity:
                        impact_time[n_impacts] = k * dt + s + h
                        impact_velocity[n_impacts] = v
                    n_impacts += 1
                    v = _law.rebound_velocity(eps, v)
    return n_impacts, x, v


def rk4_clamp_impacts(zeta, eps, delta, noise, dt, steps_per_sample=1, x0=None, v0=0.0,
                      t_end=None):
    """Impacts found by fixed-step RK4 with the wall imposed by clamping.

    Parameters
    ----------
    zeta, eps, delta, noise, dt, x0, v0, t_end
        As in `solve_ivp_impacts`.
    steps_per_sample : int
        RK4 steps per sample interval (step h = dt / steps_per_sample; every stage then sees the
        force's own linear piece, so the only inexactness is RK4's and the wall's).

    Returns
    -------
    impact_time, impact_velocity : ndarray of float64
        Impact time = end of the step that crossed the wall (an O(h) error); velocity = the
        step's end velocity before reversal.
    """
    noise = _check_problem(zeta, eps, delta, noise, dt)
    n, t_end = _n_intervals(noise, dt, t_end)
    m = int(steps_per_sample)
    if m < 1:
        raise ValueError(f"steps_per_sample must be a positive integer, got {steps_per_sample!r}")
    x = min(0.0, delta) if x0 is None else float(x0)
    capacity = max(16, n // 8)
    while True:
        impact_time = np.empty(capacity)
        impact_velocity = np.empty(capacity)
        n_impacts, _, _ = _rk4_clamp_kernel(noise, dt, m, n, zeta, eps, delta, x, float(v0),
                                            impact_time, impact_velocity)
        if n_impacts <= capacity:
            return impact_time[:n_impacts], impact_velocity[:n_impacts]
        capacity = n_impacts


# ---------------------------------------------------------------------------------------------
# The floor: the bare dependent recurrence, no wall
# ---------------------------------------------------------------------------------------------

def linear_propagator(zeta, dt):
    """Exact one-sample propagator of the free oscillator under a linear force.

    Returns ``(phi, g0, g1)``: y_{k+1} = phi @ y_k + g0 r_k + g1 r_{k+1} for y = (x, v), from the
    matrix exponential of the system augmented with (r, r')."""
    a = np.zeros((4, 4))
    a[0, 1] = 1.0
    a[1, 0] = -1.0
    a[1, 1] = -2.0 * zeta
    a[1, 2] = 1.0
    a[2, 3] = 1.0
    e = scipy.linalg.expm(a * dt)
    phi = np.ascontiguousarray(e[:2, :2])
    g1 = e[:2, 3] / dt
    g0 = e[:2, 2] - g1
    return phi, np.ascontiguousarray(g0), np.ascontiguousarray(g1)


@_kernel
def _recurrence_kernel(noise, p00, p01, p10, p11, g00, g01, g10, g11, x, v):
    for k in range(noise.size - 1):
        r0 = noise[k]
        r1 = noise[k + 1]
        x, v = (p00 * x + p01 * v + g00 * r0 + g10 * r1,
                p10 * x + p11 * v + g01 * r0 + g11 * r1)
    return x, v


def linear_recurrence(noise, propagator, x0=0.0, v0=0.0):
    """Run the bare recurrence y_{k+1} = phi y_k + g0 r_k + g1 r_{k+1} over the whole record.

    Every step depends on the last, so this chain of multiply-adds is the least work per sample
    step that any exact simulator of this model can do: the floor of the benchmark.

    Parameters
    ----------
    noise : ndarray of float64, shape (n,)
        Force samples.
    propagator : tuple
        ``(phi, g0, g1)`` from `linear_propagator` (computed outside the timing).
    x0, v0 : float
        Initial state.

    Returns
    -------
    x, v : float
        The state at the last sample.
    """
    phi, g0, g1 = propagator
    return _recurrence_kernel(noise, phi[0, 0], phi[0, 1], phi[1, 0], phi[1, 1],
                              g0[0], g0[1], g1[0], g1[1], float(x0), float(v0))
