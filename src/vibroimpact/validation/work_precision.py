"""Work-precision: run time against impact error, for the simulator and its peers, in one run.

:func:`work_precision` gives every method the same problem (zeta = 0.05, eps = 0.5, a record of
N(0, 1) force samples at dt = 0.1, linear in between, start at rest at min(0, delta)) on the
same machine in the same process, and measures two things per play delta:

- the **error**: over the first N comparable impacts (chatter tails excluded), the largest
  |impact time error| and |relative impact velocity error| against the mpmath reference
  (:mod:`vibroimpact.validation.reference`, 34 digits). N is cut where a float64-precision
  (53-bit) run of the reference stops agreeing with the 34-digit one to `TRUST_TOL`; that
  53-bit run's own error is the round-off level of the stretch;
- the **cost**: wall time per unit of simulated time, timed the same way for every method: the
  fastest of ``repeats`` runs (`TIMING_STATISTIC`). The compiled methods (the simulator, the
  numba RK4 schemes) run the long record; scipy's ``solve_ivp`` runs the first ``stretch``
  time units (its cost grows linearly with the record: one restart per sample), and, where the
  compared stretch is longer, the whole stretch once more, untimed, for its errors.

The compared stretch ends just past the ``impacts``-th impact, but not before ``stretch`` and
not after ``max_stretch``: at a play with rare impacts (delta = 1: one every ~14 time units)
fewer impacts are compared rather than the peers integrating hundreds of time units for them.
Every method is compared over the same stretch, so the errors depend on ``impacts``,
``stretch`` and ``max_stretch`` only, never on the timing (``repeats``, ``long_samples``).

The job should have the machine to itself (the workflow's rule holds every core); the load
average before and after the run is kept to show whether it had.

``solve_ivp`` is restarted at every force sample, because the force is piecewise linear (a step
across a kink loses the method's order), and after every impact: none of its steps exceeds
``dt``. A method accurate over one step of ``dt`` (DOP853, order 8) therefore errs about as much
at every tolerance; `RESTART_NOTE` says so in the dataset.

The peers are those of :mod:`vibroimpact.validation.peers`. Nothing here computes results of
the paper; the workflow stores the dataset as ``results/validation/work_precision.nc``.
"""
import functools
import logging
import math
import os
import platform
import time

import numpy as np
import xarray as xr

from vibroimpact.validation import peers

__all__ = ["work_precision", "impact_errors", "ZETA", "EPS", "DT", "SOLVERS", "SIMULATOR"]

log = logging.getLogger(__name__)

#: The problem (docs/model.md): damping ratio, restitution, sample step of the force.
ZETA, EPS, DT = 0.05, 0.5, 0.1
#: A 53-bit run of the reference must agree with the 34-digit one this closely on an impact
#: for the impact to be compared.
TRUST_TOL = 1e-10
#: Chatter-tail impacts slower than this are not compared one by one (each simulator closes a
#: chatter sequence with thresholds of its own; the reference sums it to its accumulation point).
U_TAIL = 1e-4
#: The scipy methods compared by default.
SOLVERS = ("RK45", "DOP853", "LSODA")
#: Label of this package's simulator in the dataset.
SIMULATOR = "simulate"
#: Labels of the fixed-step peers.
RK4_EVENT, RK4_CLAMP = "RK4 + event location", "RK4 clamp"
#: How the timed runs of every method are reduced to one time: the fastest (the least disturbed
#: by other work on the machine; timeit's advice).
TIMING_STATISTIC = "min"
#: Why a restarted solve_ivp method errs about equally at every tolerance (dataset attribute).
RESTART_NOTE = ("solve_ivp is restarted at every force sample (the force is piecewise linear) "
                "and after every impact, so no step of it exceeds dt; where one step of dt is "
                "already accurate (DOP853, order 8) its error hardly depends on rtol")

#: long_name and units of every variable of the dataset.
META = {
    "delta": ("play delta", "1"),
    "run": ("method and setting index", "1"),
    "method": ("method", "1"),
    "setting": ("setting of the method (tolerance or step)", "1"),
    "rtol": ("relative tolerance of solve_ivp (atol = rtol; NaN: not adaptive)", "1"),
    "steps_per_sample": ("fixed steps per force sample, h = dt / k (0: not fixed-step)", "1"),
    "timing_repeats": ("timed runs of the method, the fastest kept", "1"),
    "err_time": ("largest impact time error over the compared impacts", "1"),
    "err_velocity": ("largest relative impact velocity error over the compared impacts", "1"),
    "error": ("largest impact error: max(|time error|, |relative velocity error|)", "1"),
    "error_ratio": ("error / the simulator's error at the same delta", "1"),
    "n_found": ("impacts the method found in the compared stretch", "1"),
    "timed_span": ("simulated time of the timed run", "1"),
    "seconds": ("fastest wall time of the timed runs", "s"),
    "timing_spread": ("(slowest - fastest) / fastest wall time of the timed runs", "1"),
    "cost": ("run time per unit of simulated time", "s"),
    "cost_ratio": ("cost / the simulator's cost at the same delta", "1"),
    "t_stretch": ("end of the compared stretch (from rest at tau = 0)", "1"),
    "n_compared": ("impacts compared one by one with the reference", "1"),
    "n_reference": ("impacts of the reference in the compared stretch (chatter included)", "1"),
    "roundoff": ("error of a 53-bit run of the reference: the float64 round-off level", "1"),
    "reference_seconds": ("wall time of the 34-digit reference run", "s"),
    "compile_seconds": ("wall time of the first calls (numba compilation or cache load)", "s"),
    "build_seconds": ("wall time of the whole measurement (reference and compilation included)",
                      "s"),
    "build_cpu_seconds": ("CPU time of the process during the measurement (less than the wall "
                          "time when the machine is shared)", "s"),
}
#: Variables that measure this run (flagged ``run_measurement = 1``, as the workflow's timings):
#: everything else is bit-identical between runs of the same arguments.
RUN_MEASUREMENTS = ("seconds", "timing_spread", "cost", "cost_ratio", "reference_seconds",
                    "compile_seconds", "build_seconds", "build_cpu_seconds")


def timed_runs(fn, repeats):
    """Wall times (time.perf_counter) of ``repeats`` calls of fn(), and the last result.

    Returns
    -------
    seconds : ndarray of float64, shape (repeats,)
    out : object
        What the last call returned (every call computes the same).
    """
    seconds, out = np.empty(max(int(repeats), 1)), None
    for k in range(seconds.size):
        t0 = time.perf_counter()
        out = fn()
        seconds[k] = time.perf_counter() - t0
    return seconds, out


def split_time(time_, dt=DT):
    """Impact times as (sample index, offset in the sample), float64."""
    time_ = np.asarray(time_, dtype=np.float64)
    step = np.floor(time_ / dt).astype(np.int64)
    return step, time_ - step * dt


def reference_run(delta, noise, t_end, **kwargs):
    """The reference on ``noise`` up to ``t_end``: (run, (step, offset, velocity)).

    The arrays hold the comparable impacts (chatter tails removed); the offset in the sample is
    taken in multiprecision, so that the simulator's step + offset form is compared at full
    precision. ``kwargs`` go to `reference.reference_impacts` (``prec=53``: float64-like).
    """
    from mpmath import mp, mpf

    from vibroimpact.validation import reference

    run = reference.reference_impacts(ZETA, EPS, delta, noise, DT, t_end=t_end, **kwargs)
    tail = reference.chatter_tail_mask(run["time"], run["velocity"], run["stick_start"],
                                       run["stick_end"], U_TAIL)
    keep = [j for j, drop in enumerate(tail) if not drop]
    with mp.workdps(40):
        h = mpf(DT)
        step = [int(mp.floor(run["time"][j] / h)) for j in keep]
        offset = [float(run["time"][j] - s * h) for j, s in zip(keep, step)]
    velocity = [float(run["velocity"][j]) for j in keep]
    return run, (np.array(step, dtype=np.int64), np.array(offset), np.array(velocity))


def impact_errors(ref, step, offset, velocity, n_impacts, dt=DT):
    """``(err_time, err_velocity)`` over the first ``n_impacts`` reference impacts.

    Parameters
    ----------
    ref : tuple of ndarray
        ``(step, offset, velocity)`` of the reference's comparable impacts (`reference_run`).
    step, offset, velocity : ndarray
        A method's impacts in the same form (`split_time` for plain times).
    n_impacts : int
        Reference impacts compared.

    Returns
    -------
    err_time, err_velocity : float
        Largest |time difference| and |relative velocity difference|; inf when the method found
        no impact.

    Notes
    -----
    Each reference impact is paired with the method's impact nearest in time, so a missed or
    spurious impact shows as a large error, not as a shift of every later pair; the time
    difference is taken as (step difference) * dt + (offset difference), exact for equal steps.
    """
    ref_step, ref_offset, ref_velocity = (a[:n_impacts] for a in ref)
    if step.size == 0:
        return math.inf, math.inf
    ref_t = ref_step * dt + ref_offset
    t = step * dt + offset
    j = np.minimum(np.clip(np.searchsorted(t, ref_t), 1, max(t.size - 1, 1)), t.size - 1)
    left = np.maximum(j - 1, 0)
    j = np.where(np.abs(t[left] - ref_t) <= np.abs(t[j] - ref_t), left, j)
    d_time = (step[j] - ref_step) * dt + (offset[j] - ref_offset)
    d_velocity = (velocity[j] - ref_velocity) / ref_velocity
    return float(np.max(np.abs(d_time))), float(np.max(np.abs(d_velocity)))


def stretch_end(impact_time, impact_velocity, impacts, t_min, n_samples, t_max=math.inf):
    """End of the compared stretch: just past the ``impacts``-th impact faster than `U_TAIL`
    (a proxy for the reference's comparable impacts), at least ``t_min`` and at most ``t_max``,
    on the sample grid."""
    fast = impact_time[impact_velocity >= U_TAIL]
    t_n = fast[min(impacts, fast.size) - 1] if fast.size else t_min
    steps = int(math.ceil(max(1.05 * t_n + 2.0, t_min) / DT))
    if math.isfinite(t_max):
        steps = min(steps, max(int(math.floor(t_max / DT + 1e-9)), int(math.ceil(t_min / DT))))
    return min(steps, n_samples - 1) * DT


def _runs(solvers, rtol, rk4_steps, clamp_steps):
    """The (method, setting, rtol, steps per sample) of every run, the simulator first."""
    runs = [(SIMULATOR, "exact", math.nan, 0)]
    runs += [(f"solve_ivp {s}", f"rtol={r:.0e}", float(r), 0) for s in solvers for r in rtol]
    runs += [(RK4_EVENT, f"h=dt/{k}", math.nan, int(k)) for k in rk4_steps]
    runs += [(RK4_CLAMP, f"h=dt/{k}", math.nan, int(k)) for k in clamp_steps]
    return runs


def _check_arguments(delta, impacts, stretch, max_stretch, long_samples, rtol, solvers,
                     rk4_steps, clamp_steps, repeats):
    if len(delta) == 0 or not all(math.isfinite(float(d)) for d in delta):
        raise ValueError(f"delta must be a non-empty list of finite plays, got {delta!r}")
    if int(impacts) < 1:
        raise ValueError(f"impacts must be a positive integer, got {impacts!r}")
    if not float(stretch) > 0.0:
        raise ValueError(f"stretch must be positive, got {stretch!r}")
    if not float(max_stretch) >= float(stretch):
        raise ValueError(f"max_stretch must be at least stretch ({stretch!r}), "
                         f"got {max_stretch!r}")
    if int(long_samples) * DT < float(stretch) + 2.0 * DT:
        raise ValueError(f"long_samples = {long_samples} covers less than the stretch "
                         f"({stretch} time units at dt = {DT})")
    if not all(0.0 < float(r) < 1.0 for r in rtol):
        raise ValueError(f"rtol must lie in (0, 1), got {rtol!r}")
    unknown = set(solvers) - {"RK23", "RK45", "DOP853", "Radau", "BDF", "LSODA"}
    if unknown:
        raise ValueError(f"solvers: unknown solve_ivp methods {sorted(unknown)}")
    if not all(int(k) >= 1 for k in (*rk4_steps, *clamp_steps)):
        raise ValueError("rk4_steps and clamp_steps must be positive integers, got "
                         f"{rk4_steps!r}, {clamp_steps!r}")
    if int(repeats) < 1:
        raise ValueError(f"repeats must be a positive integer, got {repeats!r}")


def work_precision(delta=(1.0, 0.0, -0.5), *, impacts=40, stretch=100.0, max_stretch=math.inf,
                   long_samples=100_000, seed=19740072, rtol=(1e-3, 1e-6, 1e-9, 1e-12),
                   solvers=SOLVERS, rk4_steps=(1, 2, 4, 8, 16, 32, 64), clamp_steps=(),
                   repeats=3):
    """Run time against impact error of `vibroimpact.simulate` and its peers, one run.

    Parameters
    ----------
    delta : sequence of float
        Plays; one comparison each.
    impacts : int
        Impacts compared per play (fewer where the 53-bit reference stops agreeing, or where
        they take longer than ``max_stretch``).
    stretch : float
        Shortest compared stretch, in time units: solve_ivp is timed on its first ``stretch``
        time units.
    max_stretch : float
        Longest compared stretch, in time units (>= ``stretch``; default: no limit).
    long_samples : int
        Force samples of the record the compiled methods are timed on.
    seed : int
        Seed of the N(0, 1) force samples (`numpy.random.default_rng`).
    rtol : sequence of float
        Tolerances of every solve_ivp method (atol = rtol: the state is O(1)).
    solvers : sequence of str
        solve_ivp methods.
    rk4_steps, clamp_steps : sequence of int
        Steps per sample k (h = dt / k) of the RK4 scheme with event location, and of the RK4
        scheme that clamps x to the wall (none by default: it does not converge at impacts).
    repeats : int
        Timed runs of every method; the fastest is kept (`TIMING_STATISTIC`).

    Returns
    -------
    xarray.Dataset
        Dimensions ``delta`` and ``run`` (one method and setting each; coordinates
        ``method``, ``setting``, ``rtol``, ``steps_per_sample``, ``timing_repeats``).
        Per (delta, run): ``err_time``, ``err_velocity``, ``error``, ``error_ratio``,
        ``n_found``, ``timed_span``, ``seconds``, ``timing_spread``, ``cost``, ``cost_ratio``.
        Per delta: ``t_stretch``, ``n_compared``, ``n_reference``, ``roundoff``,
        ``reference_seconds``. Scalars ``compile_seconds`` and ``build_seconds``. Every variable
        has ``long_name`` and ``units``; the timings are flagged ``run_measurement = 1``. The
        attributes describe the problem, the record, how it was timed (``timing_statistic``,
        ``timing_repeats``, ``timing``), why the restarted solve_ivp hardly depends on its
        tolerance (``solve_ivp_restart``) and the machine (``load_average_start``,
        ``load_average_end``: 1-minute averages before and after the run).
    """
    start, cpu_start = time.perf_counter(), time.process_time()
    load_start = os.getloadavg()[0]
    delta = [float(d) for d in np.atleast_1d(delta)]
    _check_arguments(delta, impacts, stretch, max_stretch, long_samples, rtol, solvers,
                     rk4_steps, clamp_steps, repeats)
    runs = _runs(solvers, rtol, rk4_steps, clamp_steps)
    noise = np.random.default_rng(seed).standard_normal(int(long_samples) + 1)
    long_span = int(long_samples) * DT
    log.info("work-precision: %d plays x %d runs; long record %d samples (tau = 0 .. %g)",
             len(delta), len(runs), long_samples, long_span)

    compile_seconds = _warm_up(delta, noise, clamp_steps)
    shape = (len(delta), len(runs))
    out = {name: np.full(shape, math.nan) for name in ("err_time", "err_velocity", "seconds",
                                                        "timing_spread", "timed_span")}
    out["n_found"] = np.zeros(shape, dtype=np.int64)
    per_delta = {name: np.zeros(len(delta)) for name in ("t_stretch", "roundoff",
                                                         "reference_seconds")}
    per_delta.update(n_compared=np.zeros(len(delta), dtype=np.int64),
                     n_reference=np.zeros(len(delta), dtype=np.int64))
    repeats_of = np.full(len(runs), int(repeats))
    for i, d in enumerate(delta):
        _measure_delta(i, d, noise, runs, impacts, (float(stretch), float(max_stretch)),
                       int(repeats), out, per_delta)
        log.info("delta = %g done: %d impacts compared, %.1f s so far", d,
                 per_delta["n_compared"][i], time.perf_counter() - start)

    attrs = dict(zeta=ZETA, eps=EPS, dt=DT, amplitude=0.0, seed=int(seed),
                 force="N(0, 1) samples every dt, linear in between",
                 initial_state="from rest at min(0, delta)",
                 long_samples=int(long_samples), stretch_min=float(stretch),
                 stretch_max=float(max_stretch),
                 impacts_target=int(impacts), repeats=int(repeats), trust_tol=TRUST_TOL,
                 u_tail=U_TAIL,
                 reference="vibroimpact.validation.reference, 34 decimal digits (mpmath)",
                 simulator=SIMULATOR, timing_statistic=TIMING_STATISTIC,
                 timing_repeats=int(repeats),
                 timing=(f"wall clock (time.perf_counter), one process; each method timed "
                         f"in {int(repeats)} runs, the fastest kept; compiled methods on the "
                         f"long record ({int(long_samples)} samples), solve_ivp on the first "
                         f"{float(stretch):g} time units"),
                 solve_ivp_restart=RESTART_NOTE, load_average_start=float(load_start),
                 **_machine())
    ds = _dataset(delta, runs, repeats_of, out, per_delta, attrs)
    ds["compile_seconds"] = compile_seconds
    ds["build_seconds"] = time.perf_counter() - start
    ds["build_cpu_seconds"] = time.process_time() - cpu_start
    ds.attrs["load_average_end"] = float(os.getloadavg()[0])
    return _annotate(ds)


def _warm_up(delta, noise, clamp_steps):
    """Compile (or load from the cache) every numba kernel before any timing; its wall time."""
    from vibroimpact import simulate

    t0 = time.perf_counter()
    for d in delta:
        simulate(ZETA, EPS, d, noise[:2001], DT)
        peers.rk4_event_impacts(ZETA, EPS, d, noise[:101], DT, 2)
        if clamp_steps:
            peers.rk4_clamp_impacts(ZETA, EPS, d, noise[:101], DT, 2)
    return time.perf_counter() - t0


def _measure_delta(i, delta, noise, runs, impacts, stretches, repeats, out, per_delta):
    """Fill row ``i`` of ``out`` and ``per_delta`` for one play; ``stretches`` are the
    shortest and the longest compared stretch."""
    from vibroimpact import simulate
    from vibroimpact.validation.reference import agreeing_prefix

    long_span = (noise.size - 1) * DT
    sim_seconds, sim = timed_runs(lambda: simulate(ZETA, EPS, delta, noise, DT), repeats)
    stretch, max_stretch = stretches
    t_end = stretch_end(sim.impact_time, sim.impact_velocity, impacts, stretch, noise.size,
                        max_stretch)
    short = noise[: int(round(t_end / DT)) + 1]
    timed = noise[: int(round(stretch / DT)) + 1]
    t0 = time.perf_counter()
    run34, ref = reference_run(delta, short, t_end)
    per_delta["reference_seconds"][i] = time.perf_counter() - t0
    run53, ref53 = reference_run(delta, short, t_end, prec=53)
    n_trust = agreeing_prefix(run34, run53, tol=TRUST_TOL, u_tail=U_TAIL)
    n_cmp = min(int(impacts), n_trust, ref[0].size)
    per_delta["t_stretch"][i] = t_end
    per_delta["n_compared"][i] = n_cmp
    per_delta["n_reference"][i] = len(run34["time"])
    per_delta["roundoff"][i] = max(impact_errors(ref, *ref53, n_cmp))
    log.info("delta = %g: stretch tau = 0 .. %g, %d reference impacts, %d compared "
             "(53-bit agreement), round-off %.2e", delta, t_end, len(run34["time"]), n_cmp,
             per_delta["roundoff"][i])

    def record(j, seconds, span, step, offset, velocity):
        out["err_time"][i, j], out["err_velocity"][i, j] = impact_errors(ref, step, offset,
                                                                         velocity, n_cmp)
        out["seconds"][i, j], out["timed_span"][i, j] = seconds.min(), span
        out["timing_spread"][i, j] = (seconds.max() - seconds.min()) / seconds.min()
        out["n_found"][i, j] = int(np.sum(step * DT + offset <= t_end))

    for j, (method, setting, rtol, k) in enumerate(runs):
        if method == SIMULATOR:
            record(j, sim_seconds, long_span, sim.impact_step, sim.impact_offset,
                   sim.impact_velocity)
            continue
        if method.startswith("solve_ivp"):
            run = functools.partial(peers.solve_ivp_impacts, ZETA, EPS, delta, dt=DT,
                                    method=method.split()[1], rtol=rtol)
            seconds, (t_imp, u_imp) = timed_runs(lambda run=run: run(noise=timed), repeats)
            if short.size > timed.size:  # the errors are taken over the whole stretch
                t_imp, u_imp = run(noise=short)
            span = (timed.size - 1) * DT
        else:
            fn = peers.rk4_event_impacts if method == RK4_EVENT else peers.rk4_clamp_impacts
            seconds, (t_imp, u_imp) = timed_runs(
                lambda fn=fn, k=k: fn(ZETA, EPS, delta, noise, DT, k), repeats)
            span = long_span
        record(j, seconds, span, *split_time(t_imp), u_imp)
        log.info("delta = %g, %s %s: error %.2e, %.3g s per unit time (spread %.0f %%)", delta,
                 method, setting, max(out["err_time"][i, j], out["err_velocity"][i, j]),
                 seconds.min() / span, 100.0 * out["timing_spread"][i, j])


def _cpu_model():
    """The processor's name (Linux: /proc/cpuinfo), else the platform's machine type."""
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _machine():
    """Where the timings were taken (attributes of the dataset)."""
    import numba
    import scipy

    return dict(machine=_cpu_model(),
                cpu_count=os.cpu_count() or 0, platform=platform.platform(),
                python=platform.python_version(), numpy_version=np.__version__,
                scipy_version=scipy.__version__, numba_version=numba.__version__,
                numba_threads=int(numba.config.NUMBA_NUM_THREADS))


def _dataset(delta, runs, repeats_of, out, per_delta, attrs):
    method, setting, rtol, steps = zip(*runs)
    err = np.maximum(out["err_time"], out["err_velocity"])
    cost = out["seconds"] / out["timed_span"]
    sim = method.index(SIMULATOR)
    with np.errstate(divide="ignore", invalid="ignore"):
        error_ratio = err / err[:, sim:sim + 1]
    pair = ("delta", "run")
    data = dict(err_time=(pair, out["err_time"]), err_velocity=(pair, out["err_velocity"]),
                error=(pair, err), error_ratio=(pair, error_ratio),
                n_found=(pair, out["n_found"]), timed_span=(pair, out["timed_span"]),
                seconds=(pair, out["seconds"]), timing_spread=(pair, out["timing_spread"]),
                cost=(pair, cost),
                cost_ratio=(pair, cost / cost[:, sim:sim + 1]))
    data.update({name: ("delta", values) for name, values in per_delta.items()})
    coords = dict(delta=np.array(delta), run=np.arange(len(runs)),
                  method=("run", list(method)), setting=("run", list(setting)),
                  rtol=("run", np.array(rtol)), steps_per_sample=("run", np.array(steps)),
                  timing_repeats=("run", repeats_of))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _annotate(ds):
    for name in ds.variables:
        long_name, units = META[name]
        ds[name].attrs.update(long_name=long_name, units=units)
        if name in RUN_MEASUREMENTS:
            ds[name].attrs["run_measurement"] = 1
    return ds
