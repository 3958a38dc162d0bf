"""Constructed stress families of the simulator, each around one singular configuration.

Every family draws its cases at random over its ranges (seeded: ``numpy.random.default_rng``),
runs :func:`vibroimpact.simulate` on each, and compares it event by event with the independent
34-digit reference (:mod:`~vibroimpact.validation.reference`) over a short record, except
``extreme``, whose longest inputs are checked by invariants too. The singular point of a case
is placed on or within round-off of a sample point, where the force's slope changes and the
kernel's step ends:

``release``
    Rest on the wall, released by a force crossing ``delta`` at ``1e-15 .. 1e-2`` (in units
    of ``dt``) before or after a sample point; the force linear, kinked there, or V-shaped
    (pushing the mass back at once).
``release_touch``
    The same, but the force touches ``delta`` at the sample point without crossing it
    (``f - delta = +1e-15 .. 1e-2`` times the slope): the mass must stay.
``start_pulled``
    Start at rest on the wall with ``f - delta`` negative (``-1e-15 .. -1``) or exactly zero.
``force_equals_delta``
    The force is exactly ``delta`` over one or more whole steps, then falls or rises; the mass
    rests on the wall, or flies and returns to it.
``stick_onset``
    Chatter under a constant push whose accumulation point (computed by the reference) lies
    ``1e-15 .. 1e-2`` steps before or after a sample point, where the force starts to ramp.
``grazing``
    Flights whose highest point lies ``1e-14 .. 1e-2`` above or below the wall, inside a step
    or at a sample point, with and without the harmonic term.
``extreme``
    ``zeta 1e-4 .. 0.99``, ``eps`` in ``{0, 1}``, noise rms ``1e-8 .. 1e4``, ``dt 1e-4 .. 1``,
    harmonic amplitude up to ``1e3`` and ``beta`` up to 50.

:func:`run_family` returns a :class:`~vibroimpact.validation.report.FamilyReport`.
"""
import dataclasses
import functools
import math
import time

import numpy as np

from vibroimpact.impact import simulate
from vibroimpact.impact.simulate import simulate_model
from vibroimpact.model import ABOVE, BELOW, Model, Restitution, Wall
from vibroimpact.validation import compare
from vibroimpact.validation.reference import linear_peak, reference_impacts
from vibroimpact.validation.report import FamilyReport

EPS_RELEASE = (0.0, 0.5, 0.8, 0.95, 0.99)
#: eps of the chatter families: 0.99 costs the reference ~2500 impacts per sequence
EPS_CHATTER = (0.3, 0.5, 0.8, 0.95, 0.99)
#: Impacts after which the reference stops (eps = 1 pressed on the wall bounces forever).
MAX_REF_IMPACTS = 400
#: Grid tolerance of ``x <= delta``, per unit of the problem's scale: the round-off of a
#: sample that lies on the wall (a release or touch exactly at a sample point).
GRID_TOL = 1e-12
#: The walls a family's singular configuration is built at: ``upper``, the paper's wall at
#: delta; ``lower``, the second wall of a clearance (the case mirrored, x -> -x, onto the
#: wall at -delta below the mass, the wall above kept out of reach at FAR_WALL x the case's
#: scale: its response stays below ~1 / (2 zeta) x the force, < 500 x).
WALLS = ("upper", "lower")
FAR_WALL = 1e4


def _log_uniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _common(rng, eps_choices=EPS_RELEASE, zeta=(1e-3, 0.9), dt=(1e-3, 0.5)):
    return dict(zeta=_log_uniform(rng, *zeta), eps=float(rng.choice(eps_choices)),
                dt=_log_uniform(rng, *dt))


def _tail(rng, F_last, slope, n, dt):
    """``n`` more values of ``f - delta`` after ``F_last``: a smooth random walk of the slope,
    so that the consequences of the singular point (flight, impacts, sticking) follow."""
    out = []
    F = F_last
    for _ in range(n):
        slope = slope + rng.normal(0.0, 0.5 * abs(slope) + 0.2)
        F = F + slope * dt
        out.append(F)
    return out


# --- case generators: each returns simulate's keyword arguments plus a "note" ----------------

def draw_release(rng):
    """Rest on the wall; ``f - delta`` crosses zero ``o * dt`` before or after sample ``K``,
    where its slope changes (``kink``), reverses (``V``: the mass is pushed back) or not."""
    p = _common(rng)
    dt = p["dt"]
    delta = rng.uniform(-1.0, 1.0)
    o = _log_uniform(rng, 1e-15, 1e-2)
    side = rng.choice(["before", "after"])
    shape = rng.choice(["linear", "kink", "V"])
    g = _log_uniform(rng, 0.05, 5.0)            # slope of f - delta before sample K is -g
    fac = _log_uniform(rng, 0.01, 100.0)
    K = int(rng.integers(3, 8))
    if side == "before":
        # crossing in step K - 1; the slope changes at sample K, just after it
        F = [g * dt * (K - k - o) for k in range(K + 1)]
        slope = {"linear": -g, "kink": -g * fac, "V": g * fac}[shape]
        F.append(F[K] + slope * dt)
    else:
        # the slope changes at sample K; the crossing follows in step K
        slope = -g if shape == "linear" else -g * fac
        F_K = -slope * dt * o
        F = [F_K + g * dt * (K - k) for k in range(K + 1)]
        F.append(F_K + slope * dt)
        if shape == "V":
            slope = g * _log_uniform(rng, 0.1, 10.0)
            F.append(F[-1] + slope * dt)
    F += _tail(rng, F[-1], slope, 12, dt)
    return dict(p, delta=delta, noise=np.array(F) + delta, x0=delta, v0=0.0,
                note=f"{shape} release {side} sample {K} by {o:.1e} dt")


def draw_release_touch(rng):
    """Rest on the wall; ``f - delta`` falls to ``+o * g * dt`` at sample ``K`` and rises."""
    p = _common(rng)
    dt = p["dt"]
    delta = rng.uniform(-1.0, 1.0)
    o = _log_uniform(rng, 1e-15, 1e-2)
    g = _log_uniform(rng, 0.05, 5.0)
    K = int(rng.integers(3, 8))
    F = [g * dt * (K - k + o) for k in range(K + 1)]
    up = g * _log_uniform(rng, 0.1, 10.0)
    F.append(F[K] + up * dt)
    F += _tail(rng, F[-1], up, 12, dt)
    return dict(p, delta=delta, noise=np.array(F) + delta, x0=delta, v0=0.0,
                note=f"touch at sample {K}, f - delta = {o:.1e} g dt")


def draw_start_pulled(rng):
    """At rest on the wall at tau = 0 with ``f - delta`` pulling away (or exactly zero)."""
    p = _common(rng)
    dt = p["dt"]
    delta = rng.uniform(-1.0, 1.0)
    F0 = 0.0 if rng.random() < 0.15 else -_log_uniform(rng, 1e-15, 1.0)
    slope = rng.normal(0.0, 2.0)
    F = [F0] + _tail(rng, F0, slope, 15, dt)
    return dict(p, delta=delta, noise=np.array(F) + delta, x0=delta, v0=0.0,
                note=f"start on the wall, f - delta = {F0:.1e}, slope {slope:.2f}")


def draw_force_equals_delta(rng):
    """The force is exactly ``delta`` from sample ``K`` to ``K + m``, then falls or rises."""
    p = _common(rng)
    dt = p["dt"]
    delta = float(rng.uniform(-1.0, 1.0))
    K, m = int(rng.integers(2, 6)), int(rng.integers(1, 4))
    g = _log_uniform(rng, 0.05, 5.0)
    noise = [delta + g * dt * (K - k) for k in range(K)] + [delta] * (m + 1)
    out_slope = g * rng.choice([-1.0, 1.0]) * _log_uniform(rng, 0.1, 10.0)
    F = _tail(rng, 0.0, out_slope, 10, dt)
    noise = np.array(noise + [delta + v for v in F])
    on_wall = rng.random() < 0.7
    x0 = delta if on_wall else delta - _log_uniform(rng, 1e-3, 0.5)
    return dict(p, delta=delta, noise=noise, x0=x0, v0=0.0,
                note=f"f = delta on samples {K}..{K + m}, then slope {out_slope:.2f}, "
                     f"{'on the wall' if on_wall else 'free'} at start")


def draw_stick_onset(rng):
    """Chatter under a constant push ``F``; its accumulation point (from the reference) lies
    ``o * dt`` before or after sample ``K``, from which the force ramps up or down."""
    zeta = _log_uniform(rng, 1e-3, 0.5)
    eps = float(rng.choice(EPS_CHATTER, p=[0.25, 0.3, 0.25, 0.15, 0.05]))
    delta = float(rng.uniform(-1.0, 1.0))
    F = _log_uniform(rng, 0.05, 2.0)
    w = _log_uniform(rng, 1e-3, 0.3)          # speed leaving the wall at tau = 0
    # the accumulation point does not depend on dt while the force is constant
    T = 4.0 * w / (F * (1 - eps)) + 1.0
    probe = reference_impacts(zeta, eps, delta, np.full(int(T) + 2, F + delta), 1.0,
                              x0=delta, v0=-w, t_end=T)
    if not probe["stick_start"]:
        return None
    t_acc = float(probe["stick_start"][0])
    o = _log_uniform(rng, 1e-15, 1e-2)
    side = rng.choice(["before", "after"])
    K = int(rng.integers(1, 6))
    dt = t_acc / (K + o if side == "before" else K - o)
    ramp = rng.choice([-1.0, 1.0]) * _log_uniform(rng, 0.1, 10.0) * F
    after = _tail(rng, F, ramp, 10, dt)
    noise = np.array([F + delta] * (K + 1) + [delta + v for v in after])
    return dict(zeta=zeta, eps=eps, delta=delta, dt=dt, noise=noise, x0=delta, v0=-w,
                note=f"accumulation {side} sample {K} by {o:.1e} dt, ramp {ramp:.2f}")


def draw_grazing(rng):
    """From rest at ``c``: ``x = c + lam x1(tau)``, ``x1`` the response to a fixed pulse (and
    harmonic term) from rest at 0, ``lam`` set so that the highest top is ``delta + overshoot``.
    ``at_sample``: one pulse sample is first adjusted so that ``x1' = 0`` at a sample point."""
    zeta = _log_uniform(rng, 1e-3, 0.5)
    eps = float(rng.choice(EPS_RELEASE[1:]))
    dt = _log_uniform(rng, 0.02, 0.5)
    kind = rng.choice(["noise", "harmonic", "both"])
    at_sample = bool(rng.random() < 0.5)
    n = int(math.ceil(6.0 / dt)) + 1
    A1, beta = 0.0, 1.0
    pulse = np.zeros(n)
    if kind != "harmonic":
        width = max(1, int(round(rng.uniform(0.5, 2.0) / dt)))
        start = 1 + int(rng.integers(0, max(1, int(0.5 / dt))))
        for j in range(-width, width + 1):
            if 0 <= start + width + j < n:
                pulse[start + width + j] = 1.0 - abs(j) / (width + 1)
    if kind != "noise":
        A1, beta = float(rng.uniform(0.3, 1.0)), _log_uniform(rng, 0.5, 3.0)
    t_end = (n - 1) * dt
    peak = linear_peak(zeta, pulse, dt, amplitude=A1, beta=beta, x0=0.0, t_end=t_end)
    if peak is None or float(peak["x"]) <= 0.0:
        return None
    if at_sample:
        K = int(round(float(peak["t"]) / dt))
        j = max(0, min(K - 2, n - 1))
        pulse = _zero_velocity_at(zeta, pulse, dt, A1, beta, K, j)
        if pulse is None:
            return None
        peak = linear_peak(zeta, pulse, dt, amplitude=A1, beta=beta, x0=0.0, t_end=t_end)
        if peak is None or float(peak["x"]) <= 0.0 or abs(float(peak["t"]) - K * dt) > 1e-9:
            return None
    X1 = float(peak["x"])
    if float(peak["x_second"]) > 0.9 * X1:
        return None                      # a second top close to the wall: not one graze
    c = float(rng.uniform(-0.5, 0.0))
    delta = c + _log_uniform(rng, 0.2, 2.0)
    overshoot = float(rng.choice([-1.0, 1.0])) * _log_uniform(rng, 1e-14, 1e-2)
    lam = (delta - c + overshoot) / X1
    return dict(zeta=zeta, eps=eps, delta=delta, dt=dt, noise=c + lam * pulse, x0=c, v0=0.0,
                amplitude=lam * A1, beta=beta,
                note=f"{kind} graze {'at a sample point' if at_sample else 'inside a step'}, "
                     f"top {overshoot:+.1e} from the wall")


def _zero_velocity_at(zeta, pulse, dt, A1, beta, K, j):
    """``pulse`` with sample ``j`` changed so that the linear response has ``x' = 0`` at
    sample ``K`` (``x'`` is affine in each sample: two reference runs fix it)."""
    def v_at(value):
        trial = pulse.copy()
        trial[j] = value
        lin = reference_impacts(zeta, 0.0, 1e300, trial, dt, amplitude=A1, beta=beta, x0=0.0,
                                t_end=K * dt, record=True)
        return float(lin["v"][K])
    v0, v1 = v_at(pulse[j]), v_at(pulse[j] + 1.0)
    if v1 == v0:
        return None
    out = pulse.copy()
    out[j] = pulse[j] - v0 / (v1 - v0)
    return out


def draw_extreme(rng):
    """Parameters at the ends of the admissible ranges; short record."""
    zeta = _log_uniform(rng, 1e-4, 0.99)
    eps = float(rng.choice([0.0, 1.0]))
    dt = _log_uniform(rng, 1e-4, 1.0)
    rms = _log_uniform(rng, 1e-8, 1e4)
    A = 0.0 if rng.random() < 0.4 else _log_uniform(rng, 1e-3, 1e3)
    beta = _log_uniform(rng, 0.1, 50.0)
    size = max(rms, A)
    delta = float(size * rng.uniform(-1.5, 1.5))
    n = int(rng.integers(20, 60))
    noise = rms * rng.standard_normal(n)
    x0 = min(0.0, delta) if rng.random() < 0.5 else delta - size * abs(rng.normal())
    return dict(zeta=zeta, eps=eps, delta=delta, dt=dt, noise=noise, amplitude=A, beta=beta,
                x0=x0, v0=float(size * rng.normal()),
                note=f"extreme: rms {rms:.1e}, A {A:.1e}, beta {beta:.2f}")


#: Cases per family at full size (the full campaign, vibroimpact.validation.campaign; the
#: slow suite runs the first third of each). stick_onset's cases are the dearest: mpmath
#: chatter sequences of up to ~2500 impacts at eps = 0.99.
FULL_CASES = {"release": 1000, "release_touch": 500, "start_pulled": 500,
              "force_equals_delta": 500, "stick_onset": 150, "grazing": 400, "extreme": 600}

FAMILIES = {
    "release": draw_release,
    "release_touch": draw_release_touch,
    "start_pulled": draw_start_pulled,
    "force_equals_delta": draw_force_equals_delta,
    "stick_onset": draw_stick_onset,
    "grazing": draw_grazing,
    "extreme": draw_extreme,
}


def _scales(case):
    noise = case["noise"]
    force = float(np.max(np.abs(noise))) if noise is not None else 0.0
    force += abs(case.get("amplitude", 0.0))
    scale = 1.0 + abs(case["delta"]) + force + abs(case.get("x0", 0.0))
    u_scale = 1.0 + abs(case.get("v0", 0.0)) + force * max(1.0, case.get("beta", 1.0))
    return scale, u_scale


def force_of(case):
    """``f(tau)`` of a case: the samples' piecewise-linear interpolant plus the harmonic term."""
    noise, dt = case["noise"], case["dt"]
    A, beta = case.get("amplitude", 0.0), case.get("beta", 1.0)

    def force(tau):
        tau = np.asarray(tau, float)
        r = 0.0 if noise is None else np.interp(tau / dt, np.arange(len(noise)), noise)
        return r + A * np.sin(beta * tau)

    def slopes(tau):
        """``f'`` just before and just after ``tau`` (the sample slopes on either side)."""
        harmonic = A * beta * math.cos(beta * tau)
        if noise is None:
            return harmonic, harmonic
        k = tau / dt
        n = round(k)
        left, right = (n - 1, n) if abs(k - n) <= 1e-9 * max(1.0, k) else (math.floor(k),) * 2
        last = len(noise) - 2
        left, right = (min(max(j, 0), last) for j in (left, right))
        return tuple((noise[j + 1] - noise[j]) / dt + harmonic for j in (left, right))
    force.slopes = slopes
    return force


def _run_at_lower_wall(kw, scale):
    """The case mirrored onto the lower wall of a clearance, and its result seen back in the
    case's frame (the lower wall's impacts and rests as the case's own; ``a`` and ``v`` of the
    mirrored grid, ``x_end``), with the far wall's rounding in the grid's tolerance."""
    far = FAR_WALL * scale
    eps, delta = kw["eps"], kw["delta"]
    model = Model(kw["zeta"], (Wall(far, ABOVE, Restitution(eps)),
                               Wall(-delta, BELOW, Restitution(eps))),
                  -kw.get("amplitude", 0.0), kw.get("beta", 1.0))
    noise = kw["noise"]
    x0 = kw.get("x0")
    res = simulate_model(model, noise=None if noise is None else -np.asarray(noise),
                         dt=kw["dt"], x0=None if x0 is None else -x0, v0=-kw.get("v0", 0.0),
                         t_end=kw.get("t_end"), record_every=1)
    if np.any(res.impact_wall == 0):
        raise RuntimeError(f"the far wall at {far!r} was reached: the lower-wall run is not "
                           f"the case's")
    x = far - res.a
    view = dataclasses.replace(res, a=delta + x, v=-res.v, x_end=-res.x_end,
                               params={**res.params, "delta": delta,
                                       "amplitude": kw.get("amplitude", 0.0),
                                       "x0": -res.params["x0"], "v0": -res.params["v0"]})
    return view, 4.0 * np.spacing(far)


def run_case(case, report, wall="upper"):
    """Simulate one case, compare it with the reference and record the outcome in ``report``;
    ``wall="lower"`` builds the case at the lower wall of a clearance (:data:`WALLS`)."""
    kw = {k: v for k, v in case.items() if k != "note"}
    show = dict(case, noise=None if case["noise"] is None else case["noise"].tolist(),
                wall=wall)
    report.cases += 1
    scale, u_scale = _scales(case)
    grid_tol = GRID_TOL * scale
    try:
        if wall == "lower":
            res, rounding = _run_at_lower_wall(kw, scale)
            grid_tol += rounding
        else:
            res = simulate(**kw, record_every=1)
    except Exception as err:        # any exception is a finding
        report.exceptions += 1
        report.fail(show, f"{type(err).__name__}: {err}")
        return
    problems = compare.invariant_problems(res, case["delta"], case["eps"], grid_tol)
    ref = reference_impacts(**kw, max_impacts=MAX_REF_IMPACTS, record=True)
    force = force_of(case)
    cmp = compare.compare_events(res, ref, force, scale=scale, u_scale=u_scale)
    if cmp.failed:
        # a long sequence of slow impacts amplifies round-off: compare only as far as a
        # 53-bit run of the reference follows the 34-digit one (a horizon only removes events,
        # so a case that passes without it passes with it)
        horizon = compare.trusted_horizon(
            ref, reference_impacts(**kw, max_impacts=MAX_REF_IMPACTS, prec=53))
        cmp = compare.compare_events(res, ref, force, scale=scale, u_scale=u_scale,
                                     horizon=horizon)
        report.extra["horizon_cut"] = report.extra.get("horizon_cut", 0) + 1
    report.missed += cmp.missed
    report.spurious += cmp.spurious
    report.approximated += cmp.approximated
    report.extra["ambiguous"] = report.extra.get("ambiguous", 0) + cmp.ambiguous
    if cmp.compared:
        report.add_error(cmp.worst, show, cmp.compared)
    if problems or cmp.failed:
        report.fail(show, "; ".join(problems + ([cmp.first_problem] if cmp.first_problem else [])))


@functools.lru_cache(maxsize=len(FAMILIES))
def draw_cases(name, n_cases, seed):
    """The ``n_cases`` cases of family ``name`` drawn from ``seed`` (a draw that cannot build
    its singular configuration is drawn again), as a tuple of dicts not to be modified.

    Kept per process: several families' draws call the 34-digit reference (``stick_onset``
    finds its accumulation point with it), and :func:`run_family` and
    :func:`mirror_mismatches` run the same cases.
    """
    if name not in FAMILIES:
        raise ValueError(f"family must be one of {sorted(FAMILIES)}, got {name!r}")
    draw = FAMILIES[name]
    rng = np.random.default_rng([seed, sum(map(ord, name))])
    cases = []
    while len(cases) < n_cases:
        case = draw(rng)
        if case is not None:
            cases.append(case)
    return tuple(cases)


def run_family(name, n_cases, seed, wall="upper"):
    """Run ``n_cases`` seeded random cases of one family; return its :class:`FamilyReport`.

    Parameters
    ----------
    name : str
        A key of :data:`FAMILIES`.
    n_cases : int
        Cases to run (:func:`draw_cases`).
    seed : int
        Seed of ``numpy.random.default_rng``: the same seed gives the same cases.
    wall : {"upper", "lower"}
        The wall the cases are built at (:data:`WALLS`): the same cases either way.

    The report's ``seconds`` count the runs and comparisons, and the draws when this process
    has not drawn them yet.
    """
    if wall not in WALLS:
        raise ValueError(f"wall must be one of {WALLS}, got {wall!r}")
    report = FamilyReport(family=name, tolerance=1.0, measure=compare.MEASURE)
    start = time.perf_counter()
    for case in draw_cases(name, n_cases, seed):
        run_case(case, report, wall)
    report.seconds = time.perf_counter() - start
    return report


def mirror_mismatches(name, n_cases, seed):
    """The cases of a family (the same draws as :func:`run_family`) whose run at the lower
    wall of a clearance is not the upper-wall run bit for bit.

    The lower wall is searched in the mirrored frame with the upper wall's code, each flight
    in the frame of the nearer wall, and IEEE arithmetic commutes with negation: so the
    mirrored case must reproduce every impact (step, offset, speed), every rest and the
    sampled velocity exactly. With that identity, the upper wall's comparison with the
    34-digit reference (:func:`run_family`) holds at the lower wall for every case, at the
    cost of the simulations alone. Returns ``(cases, [(case, what differs), ...])``.
    """
    bad, cases = [], 0
    for case in draw_cases(name, n_cases, seed):
        cases += 1
        kw = {k: v for k, v in case.items() if k != "note"}
        one = simulate(**kw, record_every=1)
        two, _ = _run_at_lower_wall(kw, _scales(case)[0])
        differ = [f for f in ("impact_step", "impact_offset", "impact_velocity", "stick_start",
                              "stick_end", "v")
                  if not np.array_equal(getattr(one, f), getattr(two, f))]
        if (one.x_end, one.v_end, one.stuck_end) != (two.x_end, -two.v_end, two.stuck_end):
            differ.append("end state")
        if differ:
            bad.append((case.get("note", ""), differ))
    return cases, bad

