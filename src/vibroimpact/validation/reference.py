"""Independent high-precision reference simulator of the vibro-impact oscillator (mpmath).

Written from the closed form of docs/model.md (section 5), without importing the package's
numerics, so that its float64 simulator can be tested against it. It takes one thing from the
package: the impact law, :func:`vibroimpact.model.rebound_velocity`, which is the physics being
simulated rather than a method of simulating it (a new law is then checked by the same
reference; its chatter tail below assumes Newton's law, ``0 < eps < 1``).

Between impacts, on a stretch where the random force is linear, ``r(s) = r0 + b s``::

    x(s) = r0 + b s - 2 zeta b + A q sin(beta (t0 + s) - phi)            (particular part)
           + exp(-zeta s) [c1 cos(omega_d s) + c2 sin(omega_d s)]        (free response)

with ``q = 1/sqrt((1 - beta^2)^2 + (2 zeta beta)^2)`` and ``phi = atan2(2 zeta beta, 1 - beta^2)``.

The smallest root of ``g(s) = x(s) - delta`` in a stretch is located by a certified recursive
subdivision: an interval is discarded only if a rigorous bound proves ``g < 0`` on it (linear
interpolation plus ``max|g''| h^2/8``; certified monotonicity; certified convexity; or certified
concavity with the interior maximum of ``g``, found from ``g' = 0``, below zero). The bounds use
``|d^n/ds^n exp(-zeta s)(c1 cos + c2 sin)| <= sqrt(c1^2 + c2^2)`` (the characteristic roots have
modulus 1), so grazing double crossings inside one step are found, not skipped. Roots are then
polished by bracketed Newton to the working precision.

``g`` and ``x'`` are evaluated relative to the state at the start of the stretch
(``g(s) = g(0) + [p(s) - p(0)] + c1 (e^{-zeta s} cos - 1) + c2 e^{-zeta s} sin``), which keeps
their relative accuracy for the very short flights of a chatter sequence.
"""
from __future__ import annotations

import math

from mpmath import mp, mpf

from vibroimpact.model import rebound_velocity

__all__ = ["reference_impacts", "linear_peak", "agreeing_prefix", "comparable_impacts",
           "chatter_tail_mask"]

# Rebound velocity below which a chatter sequence is summed in closed form (flight times are
# geometric with ratio eps to O(velocity), so the neglected error is O(velocity^2) ~ 1e-24).
CHATTER_VELOCITY = 1e-12

# Safety cap on the number of certified bisections of one interval (only reached at an exact
# tangency, where the answer is decided by the sign of g at working precision).
_MAX_DEPTH_EXTRA = 24


class _Params:
    """Model constants converted exactly to mp numbers at the working precision."""

    def __init__(self, zeta, eps, delta, amplitude, beta, speed_scale=math.inf):
        self.zeta = mpf(zeta)
        self.eps = mpf(eps)
        # the impact law's 1 / speed_scale (0: Newton's law), as the model compiles it
        self.law_a = mpf(0) if math.isinf(speed_scale) else 1 / mpf(speed_scale)
        self.delta = mpf(delta)
        self.A = mpf(amplitude)
        self.beta = mpf(beta)
        self.wd = mp.sqrt(1 - self.zeta ** 2)
        one_m_b2 = 1 - self.beta ** 2
        two_zb = 2 * self.zeta * self.beta
        self.q = 1 / mp.sqrt(one_m_b2 ** 2 + two_zb ** 2)
        self.phi = mp.atan2(two_zb, one_m_b2)
        self.cos_phi, self.sin_phi = mp.cos_sin(self.phi)
        self.Aq = self.A * self.q
        # max |d^n/ds^n of the harmonic particular part| and of the harmonic force, n = 0..4
        self.harm_bound = [abs(self.Aq) * self.beta ** n for n in range(5)]
        self.force_bound = [abs(self.A) * self.beta ** n for n in range(5)]


class _Flight:
    """Closed-form free flight from state (x0, v0) at absolute time t0, force r(t0)+b s.

    ``eval(s)`` returns ``(g, g', g'')`` with ``g = x - delta``.
    """

    def __init__(self, P: _Params, t0, x0, v0, r0, b):
        self.P, self.t0, self.x0, self.v0, self.r0, self.b = P, t0, x0, v0, r0, b
        theta0 = P.beta * t0 - P.phi
        self.theta0 = theta0
        c0, s0 = mp.cos_sin(theta0)
        p0 = r0 - 2 * P.zeta * b + P.Aq * s0
        dp0 = b + P.Aq * P.beta * c0
        self.c1 = x0 - p0
        self.c2 = (v0 - dp0 + P.zeta * self.c1) / P.wd
        # coefficients of the free response's derivative: h' = e^{-zeta s}(d1 cos + d2 sin)
        self.d1 = v0 - dp0
        self.d2 = -P.zeta * self.c2 - P.wd * self.c1
        C = mp.sqrt(self.c1 ** 2 + self.c2 ** 2)
        self.M = [P.harm_bound[n] + C + (abs(b) if n == 1 else 0) for n in range(5)]

    def _increments(self, s):
        """x(s) - x(0), x'(s) and f(t0 + s); x - x(0) and x' without cancellation of O(1)
        terms (half-angle and sinh forms of cos - 1 and exp - 1)."""
        P = self.P
        y = -P.zeta * s / 2
        eh = mp.exp(y)
        e = eh * eh
        ch_w, sh_w = mp.cos_sin(P.wd * s / 2)
        c = 1 - 2 * sh_w * sh_w
        sn = 2 * sh_w * ch_w
        em1 = 2 * mp.sinh(y) * eh * c - 2 * sh_w * sh_w  # e^{-zeta s} cos(omega_d s) - 1
        dx = self.b * s + self.c1 * em1 + self.c2 * e * sn
        v = self.v0 + self.d1 * em1 + self.d2 * e * sn
        f = self.r0 + self.b * s
        if P.A != 0:
            ch, sh = mp.cos_sin(P.beta * s / 2)
            cmid, smid = mp.cos_sin(self.theta0 + P.beta * s / 2)
            # p(s) - p(0) and p'(s) - p'(0) of the harmonic part, by sum-to-product
            dx += 2 * P.Aq * cmid * sh
            v -= 2 * P.Aq * P.beta * smid * sh
            sin_th = smid * ch + cmid * sh  # theta = beta (t0 + s) - phi
            cos_th = cmid * ch - smid * sh
            f += P.A * (sin_th * P.cos_phi + cos_th * P.sin_phi)
        return dx, v, f

    def eval(self, s):
        dx, v, f = self._increments(s)
        x = self.x0 + dx
        return (self.x0 - self.P.delta) + dx, v, f - 2 * self.P.zeta * v - x

    def force(self, s):
        P = self.P
        return P.A * mp.sin(P.beta * (self.t0 + s)) + self.r0 + self.b * s

    def dforce(self, s):
        P = self.P
        return P.A * P.beta * mp.cos(P.beta * (self.t0 + s)) + self.b

    def state(self, s):
        dx, v, _ = self._increments(s)
        return self.x0 + dx, v


class _Release:
    """G(s) = delta - f(t0 + s): a mass stuck on the wall leaves where G turns positive."""

    def __init__(self, P: _Params, t0, r0, b):
        self.P, self.t0, self.r0, self.b = P, t0, r0, b
        self.M = [P.force_bound[n] + (abs(b) if n == 1 else 0) for n in range(5)]

    def eval(self, s):
        P = self.P
        sn, cs = mp.sin(P.beta * (self.t0 + s)), mp.cos(P.beta * (self.t0 + s))
        G = P.delta - (P.A * sn + self.r0 + self.b * s)
        return G, -(P.A * P.beta * cs + self.b), P.A * P.beta ** 2 * sn


def _polish(fn, lo, hi, flo, fhi, dlo, dhi):
    """Root of a function increasing on [lo, hi] with flo < 0 <= fhi.

    ``fn(s)`` returns ``(f, f', ...)``; dlo, dhi are f' at the ends. Newton safeguarded by
    bisection (Numerical Recipes' rtsafe): bisect whenever a Newton step would leave the
    bracket or fails to halve the step before last.
    """
    tol = 4 * mp.eps
    s, fs, ds = (lo, flo, dlo) if abs(flo) < abs(fhi) else (hi, fhi, dhi)
    step_old = step = hi - lo
    for _ in range(4 * mp.prec):
        if ds > 0 and lo < s - fs / ds < hi and abs(2 * fs) <= abs(step_old * ds):
            step_old, step = step, fs / ds
            s = s - step
        else:
            step_old, step = step, (hi - lo) / 2
            s = lo + step
        if abs(step) <= tol * abs(s) or hi - lo <= tol * max(abs(lo), abs(hi)):
            return s
        fs, ds = fn(s)[:2]
        if fs == 0:
            return s
        if fs < 0:
            lo = s
        else:
            hi = s
    return hi


def _smallest_root(fn, M, a, b):
    """Smallest s in [a, b] with fn(s)[0] >= 0, given fn(a)[0] < 0; None if there is none.

    fn(s) -> (g, g', g''); M[n] bounds |g^(n)| on [a, b]. Rigorous up to round-off.
    The interval is cut at a, 4a, 16a, ... (a > 0) so that the short return flights of a
    chatter sequence, which end a few times a after their start, cost a few evaluations.
    """
    max_depth = mp.prec + _MAX_DEPTH_EXTRA
    cuts = [a]
    while a > 0 and cuts[-1] * 4 < b / 2:
        cuts.append(cuts[-1] * 4)
    cuts.append(b)
    L = (a,) + tuple(fn(a))
    for right in cuts[1:]:
        R = (right,) + tuple(fn(right))
        root = _first_root(fn, M, L, R, max_depth)
        if root is not None:
            return root
        L = R
    return None


def _first_root(fn, M, L, R, max_depth):
    """Depth-first, left-to-right certified search of [L, R]: the first root found is the
    smallest."""
    stack = [(L, R, 0)]
    while stack:
        L, R, depth = stack.pop()
        root = _examine(fn, M, L, R, depth, max_depth)
        if root is None:
            continue
        if isinstance(root, tuple):  # subdivide: push right half first so left is examined first
            Mid = root
            stack.append((Mid, R, depth + 1))
            stack.append((L, Mid, depth + 1))
            continue
        return root
    return None


def _examine(fn, M, L, R, depth, max_depth):
    """Decide one interval: None (no root), a root (mpf), or the midpoint triple to split at."""
    a, ga, g1a, g2a = L
    b, gb, g1b, g2b = R
    h = b - a
    if gb >= 0:
        if min(g1a, g1b) - M[2] * h / 2 > 0:  # certified increasing: unique root
            return _polish(fn, a, b, ga, gb, g1a, g1b)
        if depth >= max_depth:
            return b
    else:
        if max(ga, gb) + M[2] * h * h / 8 < 0:
            return None
        if min(g1a, g1b) - M[2] * h / 2 >= 0 or max(g1a, g1b) + M[2] * h / 2 <= 0:
            return None  # monotone between two negative values
        if min(g2a, g2b) - M[3] * h / 2 >= 0:
            return None  # convex: maximum at an end
        if max(g2a, g2b) + M[3] * h / 2 <= 0:  # concave: one interior maximum at most
            if g1a <= 0 or g1b >= 0:
                return None
            # g' decreasing on [a, b]: its zero is the maximum of g
            neg = lambda s: tuple(-w for w in fn(s)[1:])  # -g', -g''
            c = _polish(neg, a, b, -g1a, -g1b, -g2a, -g2b)
            gc, g1c = fn(c)[:2]
            if gc < 0:
                return None
            if gc == 0:
                return c
            return _polish(fn, a, c, ga, gc, g1a, max(g1c, mpf(0)))
        if depth >= max_depth:
            return None
    m = (a + b) / 2
    return (m,) + tuple(fn(m))


def _safe_start(fl: _Flight, after_release: bool):
    """Length of an initial interval on which a flight leaving the wall stays below it.

    At s = 0 the mass is on the wall (g = 0) with g'(0) <= 0. Taylor bounds with the
    remainder bounded by M[n] give an interval (0, s*) with g < 0; half of it is returned.
    """
    g, g1, g2 = fl.eval(mpf(0))
    g3 = fl.dforce(mpf(0)) - 2 * fl.P.zeta * g2 - g1
    scale = 1 + abs(fl.P.delta) + abs(fl.r0) + abs(fl.P.A)
    if after_release or abs(g2) <= 64 * mp.eps * scale:
        g2 = min(g2, mpf(0))  # at a release point f = delta exactly; g'' is round-off
    cands = []
    if g1 < 0:
        cands.append(2 * -g1 / fl.M[2])
    if g1 <= 0 and g2 < 0:
        cands.append(3 * -g2 / fl.M[3])
    if g1 <= 0 and g2 <= 0 and g3 < 0:
        cands.append(4 * -g3 / fl.M[4])
    if not cands:
        return None
    return max(cands) / 2


def _release_time(rel: _Release, L):
    """First s in [0, L] at which a mass stuck on the wall leaves (f - delta turns negative),
    None if it stays. Consistent with _classify_rest: at f = delta (to round-off) it leaves
    only if f is decreasing."""
    G0, G1, G2 = rel.eval(mpf(0))
    scale = 1 + abs(rel.P.delta) + abs(rel.r0) + abs(rel.P.A)
    if abs(G0) <= 64 * mp.eps * scale:
        if G1 > 0 or (G1 == 0 and G2 > 0):
            return mpf(0)
        # G <= G1 s + G2 s^2/2 + M3 s^3/6 < 0 just after 0: start the search there
        if G1 < 0:
            start = -G1 / rel.M[2] if rel.M[2] > 0 else mp.inf  # M2 = 0: G is linear
        elif G2 < 0:
            start = -G2 / rel.M[3] if rel.M[3] > 0 else mp.inf
        else:
            return None
        if start >= L:
            return None
        return _smallest_root(rel.eval, rel.M, start, L)
    if G0 > 0:
        return mpf(0)
    return _smallest_root(rel.eval, rel.M, mpf(0), L)


def _classify_rest(fl: _Flight):
    """Mass on the wall at rest: True if the force holds it there (stick), False if it leaves."""
    f = fl.force(mpf(0)) - fl.P.delta
    scale = 1 + abs(fl.P.delta) + abs(fl.r0) + abs(fl.P.A)
    if abs(f) > 64 * mp.eps * scale:
        return f > 0
    return fl.dforce(mpf(0)) >= 0


def reference_impacts(zeta, eps, delta, noise, dt, amplitude=0.0, beta=1.0, x0=None, v0=0.0,
                      t_end=None, max_impacts=None, dps=34, record=False,
                      chatter_velocity=CHATTER_VELOCITY, prec=None, speed_scale=math.inf):
    """Simulate the vibro-impact oscillator in multiprecision arithmetic.

    Parameters
    ----------
    zeta, eps, delta : float
        Damping ratio, restitution coefficient, play (wall at x = delta).
    noise : sequence of float or None
        Force samples r[k] at tau = k*dt, linear in between; None means r = 0.
    dt : float
        Sample step (also the stepping grid when ``noise`` is None).
    amplitude, beta : float
        Harmonic force amplitude * sin(beta * tau), treated exactly.
    x0, v0 : float
        Initial state; x0 = None means min(0, delta).
    t_end : float, optional
        End time; default (len(noise) - 1) * dt.
    max_impacts : int, optional
        Stop after this many impacts.
    dps : int
        Decimal digits of working precision (16 is close to float64: 56 bits).
    prec : int, optional
        Working precision in bits, overriding ``dps`` (53 imitates float64 exactly).
    record : bool
        Also return x at every sample time.
    chatter_velocity : float
        Rebound velocity below which a chatter sequence is summed to its accumulation point.
    speed_scale : float
        The impact law's speed scale, ``eps(u) = eps / (1 + |u| / speed_scale)``
        (`vibroimpact.model.Restitution`); ``inf`` (the default) is Newton's law.

    Returns
    -------
    dict
        ``time``, ``velocity`` (approach velocities u_{j-0} > 0), ``acceleration`` (x'' just
        before each impact) as lists of mpf;
        ``stick_start``, ``stick_end`` (lists of mpf); ``sticking_reached`` (bool, a chatter
        sequence was summed); ``chatter_end`` (accumulation times); ``truncated`` (stopped
        by ``max_impacts``, possibly inside a chatter sequence); with ``record``,
        ``grid_time``, ``x`` and ``v`` at every sample; ``t_end``, ``x_end``, ``v_end``,
        ``stuck_end``.
    """
    with (mp.workprec(prec) if prec is not None else mp.workdps(dps)):
        return _run(zeta, eps, delta, noise, dt, amplitude, beta, x0, v0, t_end, max_impacts,
                    record, mpf(chatter_velocity), speed_scale)


def _run(zeta, eps, delta, noise, dt, amplitude, beta, x0, v0, t_end, max_impacts, record,
         chatter_velocity, speed_scale):
    if not 0 < zeta < 1:
        raise ValueError(f"zeta must be in (0, 1), got {zeta!r}")
    if not 0 <= eps <= 1:
        raise ValueError(f"eps must be in [0, 1], got {eps!r}")
    if not (dt > 0 and math.isfinite(dt)):
        raise ValueError(f"dt must be positive, got {dt!r}")
    P = _Params(zeta, eps, delta, amplitude, beta, speed_scale)
    h = mpf(dt)
    if noise is None:
        if t_end is None:
            raise ValueError("t_end is required when noise is None")
        r = None
    else:
        r = [mpf(float(v)) for v in noise]
        if t_end is None:
            t_end = (len(r) - 1) * dt
    T = mpf(t_end)
    n_steps = max(int(mp.ceil(T / h - mpf(1e-9))), 0)
    if abs(T - n_steps * h) <= mpf(1e-12) * max(T, 1):  # t_end on the grid up to float rounding
        T = n_steps * h
    if r is not None and n_steps > len(r) - 1:
        raise ValueError("noise is shorter than t_end / dt + 1 samples")
    x = mpf(min(0.0, delta) if x0 is None else x0)
    v = mpf(v0)
    if x > P.delta:
        raise ValueError(f"x0 must be <= delta, got {x0!r}")

    out = dict(time=[], velocity=[], acceleration=[], stick_start=[], stick_end=[], chatter_end=[],
               sticking_reached=False)
    grid_t, grid_x, grid_v = [], [], []
    t = mpf(0)
    stuck = False
    released = False  # the flight starts at a release point (f = delta)
    k = 0
    done = False

    def r_at(kk):
        return mpf(0) if r is None else r[kk]

    if x == P.delta and v > 0:  # starts on the wall moving into it: impact at tau = 0
        out["time"].append(t)
        out["velocity"].append(v)
        out["acceleration"].append(_Flight(P, t, x, v, r_at(0), mpf(0)).eval(mpf(0))[2])
        v = rebound_velocity(P.eps, v, P.law_a)
    while k < n_steps and not done:
        tk = k * h
        tk1 = min((k + 1) * h, T)
        if record and t == tk:
            grid_t.append(tk)
            grid_x.append(x)
            grid_v.append(v)
        b = (r_at(k + 1) - r_at(k)) / h if r is not None else mpf(0)
        guard = 0
        while t < tk1 and not done:
            guard += 1
            if guard > 100000:
                raise RuntimeError(f"no progress in step {k} at t={t}")
            r0 = r_at(k) + b * (t - tk)
            if stuck:
                rel = _Release(P, t, r0, b)
                s = _release_time(rel, tk1 - t)
                if s is None:
                    t = tk1
                    break
                t = t + s
                out["stick_end"].append(t)
                stuck, released = False, True
                x, v = P.delta, mpf(0)
                continue
            fl = _Flight(P, t, x, v, r0, b)
            L = tk1 - t
            start = mpf(0)
            if x == P.delta:
                if v == 0 and not released and _classify_rest(fl):
                    stuck = True
                    out["stick_start"].append(t)
                    continue
                start = _safe_start(fl, released)
                if start is None:  # degenerate tangential contact: hold it on the wall
                    stuck = True
                    out["stick_start"].append(t)
                    continue
            released = False
            if start >= L:
                x, v = fl.state(L)
                t = tk1
                break
            s = _smallest_root(fl.eval, fl.M, start, L)
            if s is None:
                x, v = fl.state(L)
                t = tk1
                break
            g, u, xdd = fl.eval(s)
            t = t + s
            out["time"].append(t)
            out["velocity"].append(u)
            out["acceleration"].append(xdd)
            if max_impacts is not None and len(out["time"]) >= max_impacts:
                done = True
                break
            x, v = P.delta, rebound_velocity(P.eps, u, P.law_a)
            f_wall = fl.force(s) - P.delta
            if 0 < P.eps < 1 and -v < chatter_velocity and f_wall > 0:
                # remaining flights ~ 2 w / (f - delta) * eps^k, k >= 0: geometric tail (a
                # speed-dependent law's eps(u) = eps (1 - O(u)) adds O(u^2) ~ 1e-24 too)
                tail = 2 * (-v) / f_wall / (1 - P.eps)
                t_acc = t + tail
                out["chatter_end"].append(t_acc)
                out["sticking_reached"] = True
                out["stick_start"].append(t_acc)
                stuck, x, v = True, P.delta, mpf(0)
                if t_acc >= tk1:  # the tail crosses into the next step (not expected)
                    t = tk1
                    break
                t = t_acc
        k += 1
        if t < tk1 and not done:
            t = tk1
    if record and not done and t == T:
        grid_t.append(T)
        grid_x.append(x)
        grid_v.append(v)
    out.update(t_end=t, x_end=x, v_end=v, stuck_end=stuck, truncated=done)
    if record:
        out.update(grid_time=grid_t, x=grid_x, v=grid_v)
    return out


def chatter_tail_mask(time, velocity, stick_start, stick_end, u_tail=1e-4, open_end=False):
    """Boolean mask of the impacts that close a chatter sequence.

    Walking back from each sticking start (and from the end of the record if ``open_end``,
    i.e. a run cut inside a chatter sequence), the impacts whose speeds grow backwards
    (geometric chatter) while staying below ``u_tail`` are tail impacts. Simulators close a
    chatter sequence in closed form below thresholds of their own, so these impacts are not
    comparable one by one; the sequence's accumulation point (the sticking start) is.
    """
    time = [float(t) for t in time]
    velocity = [float(u) for u in velocity]
    starts = [float(s) for s in stick_start] + ([math.inf] if open_end else [])
    ends = [float(e) for e in stick_end]
    tail = [False] * len(time)
    j_max = -1
    for i, s in enumerate(starts):
        floor = ends[i - 1] if 0 < i <= len(ends) else -math.inf
        while j_max + 1 < len(time) and time[j_max + 1] <= s:
            j_max += 1
        j = j_max
        while j >= 0 and time[j] >= floor and velocity[j] < u_tail and (
                j == j_max or velocity[j] > velocity[j + 1]):
            tail[j] = True
            j -= 1
    return tail


def comparable_impacts(ref, u_tail=1e-4):
    """(times, velocities, accelerations) of a reference run as float lists, chatter-tail
    impacts (see chatter_tail_mask) removed."""
    tail = chatter_tail_mask(ref["time"], ref["velocity"], ref["stick_start"],
                             ref["stick_end"], u_tail, open_end=ref["truncated"])
    rows = [(float(t), float(u), float(a)) for t, u, a, drop in
            zip(ref["time"], ref["velocity"], ref["acceleration"], tail) if not drop]
    return tuple([row[i] for row in rows] for i in range(3))


def agreeing_prefix(ref_a, ref_b, tol=1e-9, u_tail=1e-4):
    """Number of leading comparable impacts on which two reference runs agree:
    |time difference| <= tol and |relative velocity difference| <= tol."""
    ta, ua, _ = comparable_impacts(ref_a, u_tail)
    tb, ub, _ = comparable_impacts(ref_b, u_tail)
    n = 0
    for t1, u1, t2, u2 in zip(ta, ua, tb, ub):
        if abs(t1 - t2) > tol or abs(u1 - u2) > tol * abs(u2):
            break
        n += 1
    return n


def linear_peak(zeta, noise, dt, amplitude=0.0, beta=1.0, x0=0.0, v0=0.0, t_end=None, dps=34):
    """Highest local maximum of the impact-free (linear) response x(tau).

    Returns a dict of mpf: ``t`` (time of the maximum), ``x`` (its value), ``xdd`` (x'' there),
    ``step`` (int, index k of the sample step [k dt, (k+1) dt] holding it), ``x_ends`` (x at
    that step's two ends), ``x_second`` (the next highest local maximum, -inf if none).
    Local maxima are the zeros of x' where it turns from + to - between two samples
    (polished by bracketed Newton).
    """
    with mp.workdps(dps):
        lin = reference_impacts(zeta, 0.0, 1e300, noise, dt, amplitude=amplitude, beta=beta,
                                x0=x0, v0=v0, t_end=t_end, record=True, dps=dps)
        P = _Params(zeta, 0.0, 1e300, amplitude, beta)
        h = mpf(dt)
        best, second = None, -mp.inf
        for k in range(len(lin["x"]) - 1):
            if not (lin["v"][k] > 0 >= lin["v"][k + 1]):
                continue
            r0 = mpf(0) if noise is None else mpf(float(noise[k]))
            b = mpf(0) if noise is None else (mpf(float(noise[k + 1])) - r0) / h
            fl = _Flight(P, k * h, lin["x"][k], lin["v"][k], r0, b)
            neg = lambda s, fl=fl: tuple(-w for w in fl.eval(s)[1:])
            xdd0, xdd1 = fl.eval(mpf(0))[2], fl.eval(h)[2]
            s = _polish(neg, mpf(0), h, -lin["v"][k], -lin["v"][k + 1], -xdd0, -xdd1)
            x, _ = fl.state(s)
            xdd = fl.eval(s)[2]
            if best is None or x > best["x"]:
                if best is not None:
                    second = max(second, best["x"])
                best = dict(t=k * h + s, x=x, xdd=xdd, step=k,
                            x_ends=(lin["x"][k], lin["x"][k + 1]))
            else:
                second = max(second, x)
        if best is not None:
            best["x_second"] = second
        return best
