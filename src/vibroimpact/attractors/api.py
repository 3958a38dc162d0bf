"""Basins of attraction and the largest Lyapunov exponent under ``sin(beta tau)`` alone.

For every cell ``(1/beta, delta)`` of a grid, :func:`attractor_map` runs ``n_starts`` starting
states without noise until each settles on a periodic motion or reaches a time cap, and tells
which motion it settled on (a stable (m/n) orbit of :func:`vibroimpact.periodic_orbits`, an
impact-stick motion, another periodic impact motion, the wall-free linear response) together
with its Lyapunov exponents. Kernels:
:mod:`vibroimpact.attractors.kernels`.
"""
from __future__ import annotations

import math
import warnings

import numba
import numpy as np

from vibroimpact import _checks
from vibroimpact._limits import ATTRACTOR_MATCH_TOL, MAX_M, attractor_min_time
from vibroimpact.attractors import kernels as ak
from vibroimpact.stats.events import clopper_pearson

__all__ = ["attractor_map", "CLASSES", "DEFAULT_TYPES"]

#: The classes of a start (``class_count``, ``cell_class``, ``class_start``), by code 0-5:
#: a stable solver orbit of a listed type; another periodic impact motion; sticking (at rest
#: on the wall, or an impact-stick motion); chaotic; undecided; the wall-free response (the
#: linear steady response ``q sin(beta tau - phi)`` with ``q < delta``, no impact). The
#: wall-free class came last so that the codes 0-4 of datasets written before it keep their
#: meaning.
CLASSES = ("listed", "periodic_other", "sticking", "chaotic", "undecided", "wall_free")
DEFAULT_TYPES = ((1, 1), (2, 1), (1, 2), (1, 3), (3, 1))
#: Default cap on a start's run (dimensionless time): ~64 natural periods, 5.5 times the
#: time ln(1e6)/zeta = 276 that damping alone needs at zeta = 0.05 and match_tol = 1e-6.
DEFAULT_MAX_TIME = 1500.0
DEFAULT_MATCH_TOL = ATTRACTOR_MATCH_TOL
#: Two-sided level of the Clopper-Pearson interval of ``fraction``.
CONFIDENCE = 0.95
#: Starts (whole cells of them) in one call of the starts' kernel, between two reports of
#: `attractor_map`'s progress: ~55 CPU-us a start on Fig. 15's plane (64 starts a cell), so
#: a block is ~1 s on 2 threads, under the progress log's cadence, and holds 32 blocks a
#: thread whose last one to finish leaves the others idle ~1/64 of it, as one call over
#: every start does. Measured (5 pairs, whole process, benchmarks/progress_ab.py):
#: main/blocks CPU 0.98 (0.90-1.22), wall 1.05 (0.66-1.28) on a machine loaded by other builds.
BLOCK_STARTS = 2 ** 15


def _interval(name, value, low=None):
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (low, high) of finite numbers with "
                         f"low < high, got {value!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or not hi > lo:
        raise ValueError(f"{name} must be a pair (low, high) of finite numbers with low < high "
                         f"(a non-empty box), got {value!r}")
    if low is not None and lo < low:
        raise ValueError(f"{name} must have low >= {low:g} (a start beyond the wall: x0 = "
                         f"delta - gap must satisfy x0 <= delta), got {value!r}")
    return lo, hi


def _types(types):
    out = []
    if len(types) == 0:
        raise ValueError("types must hold at least one (m, n) pair")
    for t in types:
        if len(t) != 2:
            raise ValueError(f"types must be (m, n) pairs, got {t!r}")
        m = _checks.integer("m of types", t[0], low=1, high=MAX_M)
        n = _checks.integer("n of types", t[1], low=1)
        out.append((m, n))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def sobol_starts(n_starts, gap, velocity, seed):
    """The unit-cube points (scrambled Sobol, ``scipy.stats.qmc``, seeded) and the starts
    ``theta in [0, 2 pi)``, ``g in gap``, ``v0 in velocity`` they map to (same in every cell).
    """
    from scipy.stats import qmc

    sampler = qmc.Sobol(d=3, scramble=True, seed=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)     # n not a power of 2: still balanced
        u = sampler.random(n_starts)
    theta = 2.0 * math.pi * u[:, 0]
    g = gap[0] + (gap[1] - gap[0]) * u[:, 1]
    v0 = velocity[0] + (velocity[1] - velocity[0]) * u[:, 2]
    return u, theta, g, v0


def kernel_walls(clearance, eps, eps_lower):
    """The kernels' ``(clearance, eps_lower)`` (float): no second wall (``clearance`` None,
    the one spelling above the kernels) is a wall at infinite distance with ``eps``."""
    if clearance is None:
        return math.inf, float(eps)
    return float(clearance), float(eps if eps_lower is None else eps_lower)


def stable_orbits(inv_beta, delta, types, zeta, eps, clearance=None, eps_lower=None):
    """Stable admissible solver orbits per cell and type (arrays of
    :func:`kernels.cell_orbits`): ``n_stable (n_rows, nb, nd)``, and per cell, row and orbit
    the phases, approach velocities, intervals and ``ln max|mu|``. One wall (``clearance``
    None): a row per type. With a ``clearance``, the rows of the wall above (the orbits that
    stay above the wall below), then those of the wall below: the one-wall orbits of the
    mirrored frame ``x -> -x``, play ``clearance - delta`` and restitution ``eps_lower``, that
    stay below the wall above (the mirror image of a cell holds the same numbers the other way
    round)."""
    nb, nd, nt = inv_beta.size, delta.size, types.shape[0]
    kernel_clearance, kernel_eps_lower = kernel_walls(clearance, eps, eps_lower)
    walls = [(delta, eps)]
    if clearance is not None:
        walls.append((clearance - delta, kernel_eps_lower))
    shape = (nb, nd, len(walls) * nt, ak.K_ORBITS, ak.M_COLS)
    n_stable = np.zeros((len(walls) * nt, nb, nd), np.int64)
    oph, ou, oz = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    lnmu = np.full(shape[:4], np.nan)
    rows = np.argsort(-inv_beta, kind="stable")      # the costliest rows first
    for w, (plays, eps_w) in enumerate(walls):
        part = slice(w * nt, (w + 1) * nt)
        arrays = [np.zeros((nt, nb, nd), np.int64)] + [np.zeros(shape[:2] + (nt,) + shape[3:])
                                                       for _ in range(3)]
        lnmu_w = np.full(shape[:2] + (nt, ak.K_ORBITS), np.nan)
        with numba.parallel_chunksize(1):       # rows handed out as threads come free
            ak.cell_orbits(inv_beta, np.ascontiguousarray(plays), types, float(zeta),
                           float(eps_w), *arrays, lnmu_w, kernel_clearance, rows)
        n_stable[part] = arrays[0]
        for full, got in zip((oph, ou, oz, lnmu), arrays[1:] + [lnmu_w]):
            full[:, :, part] = got
    return n_stable, oph, ou, oz, lnmu


def _validate(inv_beta, delta, zeta, eps, types, n_starts, gap, velocity, max_time,
              match_tol, seed):
    inv_beta = np.ascontiguousarray(inv_beta, dtype=float).ravel()
    delta = np.ascontiguousarray(delta, dtype=float).ravel()
    if inv_beta.size == 0 or not np.all(np.isfinite(inv_beta)) or np.any(inv_beta <= 0):
        raise ValueError("inv_beta must be a non-empty array of finite numbers > 0")
    if delta.size == 0 or not np.all(np.isfinite(delta)):
        raise ValueError("delta must be a non-empty array of finite numbers")
    zeta = _checks.zeta(zeta)
    eps = _checks.eps(eps)
    types = _types(types)
    n_starts = _checks.integer("n_starts", n_starts, low=1)
    gap = _interval("gap", gap, low=0.0)
    velocity = _interval("velocity", velocity)
    match_tol = _checks.real("match_tol", match_tol, low=0.0, high=1e-2, low_open=True)
    need = attractor_min_time(zeta, match_tol)
    max_time = _checks.real("max_time", max_time, low=0.0, low_open=True)
    if max_time < need:
        raise ValueError(f"max_time must be >= ln(1/match_tol)/zeta = {need:.6g} (the time "
                         f"damping alone needs to bring a perturbation under the matching "
                         f"tolerance), got {max_time!r}")
    seed = _checks.integer("seed", seed, low=0)
    return (inv_beta, delta, zeta, eps, types, n_starts, gap, velocity, max_time, match_tol,
            seed)


def attractor_map(inv_beta, delta, zeta, eps, types=DEFAULT_TYPES, *, n_starts=64,
                  gap=(0.0, 4.0), velocity=(-4.0, 4.0), max_time=DEFAULT_MAX_TIME,
                  match_tol=DEFAULT_MATCH_TOL, seed=0, clearance=None, eps_lower=None,
                  progress=None):
    """Basins of the stable (m/n) motions and the largest Lyapunov exponent over a grid.

    Parameters
    ----------
    inv_beta, delta : array_like
        The grid's ``1/beta`` (> 0) and plays; force ``sin(beta tau)``, no noise.
    zeta, eps : float
        Damping ratio in (0, 1), restitution coefficient in [0, 1].
    types : sequence of (m, n)
        Motion types whose stable solver orbits are matched (m <= 3).
    n_starts : int, keyword-only
        Starts per cell (>= 1): the same scrambled Sobol points (``scipy.stats.qmc``,
        ``seed``) of the unit cube in every cell (common random numbers), mapped to the
        forcing phase ``theta in [0, 2 pi)`` at the start (the start is at
        ``tau = theta / beta``, moved on by whole forcing periods, so ``f = sin(theta)``
        there), the distance ``g`` from the wall (``x0 = delta - g``) and ``v0``.
    gap : (low, high), keyword-only
        Range of ``g``, ``0 <= low < high`` (no start beyond the wall).
    velocity : (low, high), keyword-only
        Range of ``v0``, ``low < high``.
    max_time : float, keyword-only
        Cap on a start's run; at least ``ln(1/match_tol)/zeta``, the time damping alone
        needs to bring a perturbation under the tolerance.
    match_tol : float, keyword-only
        In (0, 0.01]: phases over a forcing period ``T_f = 2 pi / beta``, intervals over
        ``T_f`` and velocities over ``1 + u`` must agree to it (default 1e-6).
    seed : int, keyword-only
        Seed of the Sobol scrambling.
    clearance : float, optional, keyword-only
        A second wall at ``x = delta - clearance`` (> 0), hit from above: the clearance
        between two stops (``simulate``'s ``gap``; here ``gap`` already names the starts'
        range, which must then lie within it: ``gap[1] <= clearance``). Default: one wall.
    eps_lower : float, optional, keyword-only
        Restitution coefficient of that wall, in [0, 1] (default ``eps``).
    progress : callable, optional, keyword-only
        ``progress(k)`` after every block of ``k`` cells whose starts have all run
        (`BLOCK_STARTS` starts a block): a job's progress log
        (`vibroimpact.pipeline.tasks.Progress.advance`).

    Returns
    -------
    dict of ndarray
        Coordinates ``inv_beta (nb,)``, ``delta (nd,)``, ``motions`` (names ``"m/n"`` of
        ``types``, then ``"other"``), ``classes`` (:data:`CLASSES`), and

        - ``count`` int (n_types + 1, nb, nd): starts settled on the stable solver orbits of
          each type (all stable orbits of a type pooled); the last row, "other", is the rest;
        - ``stick_count`` int (n_types, nb, nd): starts settled on a periodic impact-stick
          motion with m collisions per n forcing periods of a listed type (in "other");
        - ``fraction``, ``fraction_lo``, ``fraction_hi`` (n_types + 1, nb, nd): ``count /
          n_starts`` and its Clopper-Pearson 95 % interval;
        - ``n_stable`` int (n_types, nb, nd): stable admissible solver orbits (at either wall
          with a ``clearance``);
        - ``class_count`` int (6, nb, nd) and ``cell_class`` int8 (nb, nd), the most frequent
          class (the first of a tie);
        - ``lyapunov`` (nb, nd): the largest exponent over the cell's starts (``-inf`` when
          every start sticks); ``lyapunov_class`` int8 (nb, nd): the class of the start it
          belongs to (the first such start; -1 where no start has an exponent), which differs
          from ``cell_class`` where a minority attractor coexists with a larger exponent;
          ``lyapunov_start``, ``lyapunov_second_start`` (n_starts, nb,
          nd): both exponents of every start; ``lyapunov_stderr`` (nb, nd): the largest
          standard error among the unsettled starts (NaN where all settled);
        - ``impact_rate`` (nb, nd): mean collisions per unit time over the starts' final
          windows (a settled start's period, an unsettled one's Benettin window);
          ``impact_rate_lower`` (nb, nd): the mean rate of impacts at the lower wall
          (with a ``clearance``; 0 with one wall);
        - ``settle_time`` (n_starts, nb, nd), NaN if not settled; ``motion_start`` int
          (n_starts, nb, nd): index into ``motions``; ``class_start`` int8 (n_starts, nb,
          nd); ``period_start`` int (2, n_starts, nb, nd): (m', k) of a settled periodic
          motion (impacts and forcing periods; collisions for an impact-stick motion);
          ``impacts_lower_start`` int (n_starts, nb, nd): of a start settled on a periodic
          impact motion (listed or periodic_other), the m' impacts, those at the wall below
          (so the motion is ``(m' - that, that)/k`` in the two-wall names; 0 otherwise).

    Notes
    -----
    **Trajectories.** Each start is stepped by the simulator's own loop
    (``vibroimpact.impact.stepping.run_steps``) on a zero noise record with the harmonic
    force, so impacts, chatter, sticking and grazing touches are those of
    :func:`vibroimpact.simulate`; starts run in parallel (numba ``prange``). The start sits on
    a sample point: its instant ``t0 = theta / beta + j T_f`` and the step ``h = t0 / k0``,
    within 6 % of ``min(0.2, T_f / 16)``, are chosen per start (with zero noise the step only
    sets where the exclusion test runs).

    **Settling**, tested once per forcing period, in this order:

    1. no impact can happen again: the free response's amplitude plus the steady one, ``q``,
       is below ``delta`` (class "wall_free": the motion tends to the linear steady response
       ``q sin(beta tau - phi)``, which never reaches the wall; both exponents ``-zeta``,
       exactly, since the tangent map of a free flight is the damped propagator);
    2. on the wall (resting or sliding) for 4 forcing periods without an impact (class
       "sticking");
    3. the last 3 m impacts follow a stable admissible solver orbit of a listed (m/n) type
       within ``match_tol``, impact by impact (phase, velocity, interval), with no sticking in
       between (class "listed");
    4. the impact sequence repeats: the last 3 returns, with period k forcing periods
       (k <= 6) and m' impacts, agree within ``match_tol``, and no stable listed orbit is
       within ``1000 match_tol`` (then it is still converging onto that one). With sticking
       in its period it is an impact-stick motion, class "sticking", with m' collisions
       (impacts grouped as in :func:`vibroimpact.stats.group_collisions`) per k periods; if
       (m'/k) is a listed type it is counted in ``stick_count``. Otherwise class
       "periodic_other" (a periodic impact motion of another type).

    ``settle_time`` is the start of the window that proved it (the first impact of the
    3 returns). Unsettled at ``max_time``: "chaotic" or "undecided" (below), or "sticking"
    (``settle_time`` NaN) when it stuck within the Benettin window: sticking recurs, so such a
    start is periodic too, with a period beyond the 6 forcing periods (or 256 impacts)
    tested (0.2 % of the starts of the default plane, all at 1/beta <= 0.4).

    **Tangent dynamics.** The flight is linear, so its tangent map over a flight of length
    ``s`` is the free propagator ``P(s)`` of ``y'' + 2 zeta y' + y = 0``. At an impact at
    ``x = delta`` with approach velocity ``u`` (jump ``R(x, v) = (x, -eps v)``, surface normal
    ``n = (1, 0)``), the saltation matrix ``S = DR + (F+ - DR F-) n^T / (n . F-)``, with the
    vector fields ``F- = (u, a-)``, ``F+ = (-eps u, a+)``, ``a- = f - delta - 2 zeta u``,
    ``a+ = f - delta + 2 zeta eps u`` (f the force at the impact), is::

        S = [[-eps, 0], [(1 + eps) (f(tau_j) - delta) / u, -eps]],     det S = eps^2.

    So the sum of both exponents is ``-2 zeta + 2 nu ln eps`` (nu: impacts per unit time).
    At a grazing touch the simulator records no impact and the tangent passes unchanged (the
    ``1/u`` entry is never formed at ``u -> 0``). Sticking: the release instant is set by the
    force alone, so the state after a sticking interval does not depend on the state before:
    the tangent map is 0 and both exponents are ``-inf``.

    **Exponents.** A start settled on a periodic motion gets exactly ``ln|mu|/z`` of the
    eigenvalues of the tangent product (propagators and saltations) over one period ``z`` of
    its settled motion: the limit of Benettin's estimate as the window grows. On a listed
    orbit the product is taken along the solver orbit it matched (the trajectory is within
    ``match_tol`` of it, and where the two multipliers are nearly equal that distance moves
    them by its square root; along the solver orbit it agrees with the solver's multipliers,
    from the impact-map Jacobian, to round-off); on another periodic motion along the last
    period of the trajectory itself. The determinant of the product is used in its exact
    form ``eps^(2 m) exp(-2 zeta z)`` (computed, it is lost to cancellation after a slow
    impact), so for settled starts the two exponents sum to the contraction by
    construction.
    An unsettled start gets Benettin's estimate (both tangent vectors, Gram-Schmidt at every
    impact and at every forcing period) over ``[max_time / 4, max_time]`` of its run; its
    standard error is from 8 batch means (``std / sqrt 8``). It is "chaotic" when the
    largest exponent exceeds 3 standard errors, "undecided" otherwise (quasi-periodic, or
    slow to settle).

    **Fractions.** The Sobol starts are not independent draws (they are more evenly spread),
    so the binomial Clopper-Pearson interval is a conservative stand-in for the uncertainty
    of the basin fraction.

    ``impact_rate`` counts collisions; for an unsettled start whose window holds sticking it
    approximates them by counting every run of shrinking rebounds as one collision.

    **Two walls** (``clearance``). The simulator follows both walls (impacts, chatter,
    sticking at either); the tangent crosses an impact at the lower wall by the same saltation
    in the mirrored frame ``x -> -x`` (approach speed ``-x'``, force ``-f``, wall at
    ``-(delta - clearance)``, restitution ``eps_lower``), so the exponents' sum is
    ``-2 zeta + 2 sum_w nu_w ln eps_w`` over the walls. The closed-form solver knows one wall:
    its orbits whose flights stay above the wall below (``min x >= delta - clearance``) are
    orbits of the two-wall oscillator with the same multipliers, and so are, in the mirrored
    frame, its orbits at the play ``clearance - delta`` with restitution ``eps_lower`` that
    stay below the wall above: both are listed under their type (``n_stable`` counts both
    walls' orbits, ``impact_rate_lower`` tells the wall), so that a cell and its mirror image
    (walls swapped, starts mirrored) settle alike. A motion that meets both walls settles as
    "periodic_other", with its exponents from its own last period. An impact at the other
    wall always starts a new collision.

    Examples
    --------
    One cell of Fig. 16's plane, 8 starts: all of them settle on the (1/1) motion, whose
    largest Lyapunov exponent is negative:

    >>> from vibroimpact import attractor_map
    >>> result = attractor_map([1.1], [0.5], 0.05, 0.5, n_starts=8)
    >>> result["motions"][0], float(result["fraction"][0, 0, 0])
    ('1/1', 1.0)
    >>> bool(result["lyapunov"][0, 0] < 0)
    True
    """
    (inv_beta, delta, zeta, eps, types, n_starts, gap, velocity, max_time, match_tol,
     seed) = _validate(inv_beta, delta, zeta, eps, types, n_starts, gap, velocity, max_time,
                       match_tol, seed)
    clearance, eps_lower = _validate_walls(clearance, eps_lower, eps, gap)
    nb, nd, nt = inv_beta.size, delta.size, types.shape[0]
    raw = _simulate_starts(inv_beta, delta, zeta, eps, types, n_starts, gap, velocity,
                           max_time, match_tol, seed, clearance=clearance, eps_lower=eps_lower,
                           progress=progress)
    outf, outi = raw["outf"], raw["outi"]
    # per start, (n_starts, nb, nd)
    shape_s = (nb, nd, n_starts)
    to_s = lambda a: np.moveaxis(a.reshape(shape_s), -1, 0)
    motion_raw = to_s(outi[:, ak.I_MOTION])
    cls = to_s(outi[:, ak.I_CLASS]).astype(np.int8)
    motion = np.where(motion_raw >= 0, motion_raw, nt)
    count = np.stack([(motion == t).sum(axis=0) for t in range(nt + 1)])
    stick_count = np.stack([(motion_raw == -2 - t).sum(axis=0) for t in range(nt)])
    class_count = np.stack([(cls == c).sum(axis=0) for c in range(len(CLASSES))])
    frac = count / n_starts
    lo, hi = clopper_pearson(count, n_starts, CONFIDENCE)
    status = to_s(outi[:, ak.I_STATUS])
    if np.any(status != 0):
        # the simulator's kernel refused a step (as simulate() would raise): no result of
        # that start can be trusted, so none of the map's is written
        s, ib, d = (int(v[0]) for v in np.nonzero(status != 0))
        raise RuntimeError(f"attractor_map: the simulator's kernel stopped with status "
                           f"{int(status[s, ib, d])} on start {s} of the cell 1/beta = "
                           f"{inv_beta[ib]:g}, delta = {delta[d]:g} "
                           f"({int(np.count_nonzero(status))} starts in all)")
    lyap1 = to_s(outf[:, ak.F_LYAP1])
    ranked = np.where(np.isnan(lyap1), -np.inf, lyap1)
    owner = np.argmax(ranked, axis=0)           # first start holding the largest exponent
    lyap_class = np.where(np.isnan(lyap1).all(axis=0), -1,
                          np.take_along_axis(cls, owner[None], axis=0)[0]).astype(np.int8)
    lyap2 = to_s(outf[:, ak.F_LYAP2])
    stderr = to_s(outf[:, ak.F_STDERR])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        lyap = np.nanmax(lyap1, axis=0)      # -inf: every start sticks; NaN: no exponent
        unsettled = (cls == ak.CHAOTIC) | (cls == ak.UNDECIDED)
        lyap_se = np.nanmax(np.where(unsettled, stderr, np.nan), axis=0)
        rate = np.nanmean(to_s(outf[:, ak.F_RATE]), axis=0)
        rate_lo = np.nanmean(to_s(outf[:, ak.F_IMPACTS_LO] / outf[:, ak.F_WINDOW]), axis=0)
    return {
        "inv_beta": inv_beta, "delta": delta,
        "motions": [f"{m}/{n}" for m, n in types] + ["other"],
        "classes": list(CLASSES),
        "count": count, "stick_count": stick_count,
        "fraction": frac, "fraction_lo": lo, "fraction_hi": hi,
        "n_stable": raw["n_stable"],
        "class_count": class_count,
        "cell_class": np.argmax(class_count, axis=0).astype(np.int8),
        "lyapunov": lyap, "lyapunov_class": lyap_class, "lyapunov_start": lyap1,
        "lyapunov_second_start": lyap2,
        "lyapunov_stderr": lyap_se, "impact_rate": rate, "impact_rate_lower": rate_lo,
        "settle_time": to_s(outf[:, ak.F_SETTLE]),
        "motion_start": motion, "class_start": cls,
        "period_start": np.stack([to_s(outi[:, ak.I_PERIOD_M]), to_s(outi[:, ak.I_PERIOD_P])]),
        "impacts_lower_start": np.where(
            (cls == ak.LISTED) | (cls == ak.PERIODIC_OTHER),
            np.nan_to_num(to_s(outf[:, ak.F_IMPACTS_LO])), 0).astype(np.int64),
    }


def _validate_walls(clearance, eps_lower, eps, gap):
    """``(clearance, eps_lower)`` checked: ``(None, None)`` with one wall, ``eps_lower``
    defaulting to ``eps`` with two."""
    if clearance is None:
        if eps_lower is not None:
            raise ValueError("eps_lower needs a second wall: give clearance as well")
        return None, None
    clearance = _checks.real("clearance", clearance, low=0.0, low_open=True)
    eps_lower = eps if eps_lower is None else _checks.eps(eps_lower, "eps_lower")
    if gap[1] > clearance:
        raise ValueError(f"gap (the starts' distance below the wall at delta) must lie within "
                         f"the clearance: gap[1] <= clearance = {clearance!r}, got {gap!r}")
    return clearance, eps_lower


def _simulate_starts(inv_beta, delta, zeta, eps, types, n_starts, gap, velocity, max_time,
                     match_tol, seed, *, clearance=None, eps_lower=None, progress=None):
    """Every start of every cell (validated input); the kernels' raw per-start records
    ``outf (n, N_F)``, ``outi (n, N_I)`` (start ``i`` of cell ``c = ib nd + id`` at row
    ``c n_starts + i``), the starts, the solver orbits and the kernels' times."""
    import time

    nb, nd = inv_beta.size, delta.size
    t_a = time.perf_counter()
    n_stable, oph, ou, oz, lnmu = stable_orbits(inv_beta, delta, types, zeta, eps, clearance,
                                                eps_lower)
    t_b = time.perf_counter()
    u, theta, g, v0 = sobol_starts(n_starts, gap, velocity, seed)
    n_cells = nb * nd
    nt = types.shape[0]
    n_walls = n_stable.shape[0] // nt
    cell_beta = np.repeat(1.0 / inv_beta, nd)
    cell_delta = np.tile(delta, nb)
    cell_of = np.repeat(np.arange(n_cells), n_starts)
    th = np.tile(theta, n_cells)
    x0 = cell_delta[cell_of] - np.tile(g, n_cells)
    vv = np.tile(v0, n_cells)
    orb_n = np.moveaxis(n_stable, 0, -1).reshape(n_cells, -1)
    shape = (n_cells,) + oph.shape[2:]
    n = th.size
    outf = np.empty((n, ak.N_F))
    outi = np.empty((n, ak.N_I), np.int64)
    # the starts in blocks of whole cells, one kernel call each, between two reports of
    # progress: a start's numbers are its own (its buffers are reset, whatever ran before on
    # them), so the blocks give one call's numbers bit for bit
    per_block = max(1, BLOCK_STARTS // n_starts) * n_starts
    args = (float(zeta), float(eps), *kernel_walls(clearance, eps, eps_lower),
            float(max_time), float(match_tol),
            np.tile(types, (n_walls, 1)), nt, np.ascontiguousarray(orb_n),
            oph.reshape(shape), ou.reshape(shape), oz.reshape(shape))
    for lo in range(0, n, per_block):
        part = slice(lo, min(lo + per_block, n))
        size = part.stop - lo
        n_blocks = min(size, 32 * numba.get_num_threads())  # the last one to finish is short
        with numba.parallel_chunksize(1):       # blocks handed out as threads come free
            ak.run_starts(cell_beta, cell_delta, cell_of[part], th[part], x0[part], vv[part],
                          *args, n_blocks, outf[part], outi[part])
        if progress is not None:
            progress(size // n_starts)
    t_c = time.perf_counter()
    # a type's stable orbits at either wall, pooled
    n_stable = n_stable.reshape(n_walls, nt, nb, nd).sum(axis=0)
    return {"outf": outf, "outi": outi, "n_stable": n_stable, "lnmu": lnmu, "theta": th,
            "x0": x0, "v0": vv, "cell_of": cell_of, "unit": u,
            "seconds_orbits": t_b - t_a, "seconds_starts": t_c - t_b}


def _starts_at_cell(inv_beta, delta, zeta, eps, theta, x0, v0, types=DEFAULT_TYPES, *,
                    max_time=DEFAULT_MAX_TIME, match_tol=DEFAULT_MATCH_TOL, trace=0,
                    clearance=None, eps_lower=None):
    """Given starts ``(theta, x0, v0)`` (arrays) at one cell, through the same kernels as
    :func:`attractor_map`: the raw records ``outf (n, N_F)``, ``outi (n, N_I)`` (slots
    ``kernels.F_*, I_*``) and, with ``trace > 0``, the first ``trace`` impacts
    ``(step, offset, velocity)`` of the first start, run serially (tests, brute force)."""
    types = _types(types)
    clearance, eps_lower = _validate_walls(clearance, eps_lower, eps, (0.0, 0.0))
    walls = kernel_walls(clearance, eps, eps_lower)
    ib = np.array([float(inv_beta)])
    dd = np.array([float(delta)])
    n_stable, oph, ou, oz, _ = stable_orbits(ib, dd, types, zeta, eps, clearance, eps_lower)
    n_walls = n_stable.shape[0] // types.shape[0]
    rows = np.tile(types, (n_walls, 1))
    theta, x0, v0 = (np.ascontiguousarray(a, dtype=float).ravel() for a in (theta, x0, v0))
    n = theta.size
    outf = np.empty((n, ak.N_F))
    outi = np.empty((n, ak.N_I), np.int64)
    orb_n = np.ascontiguousarray(n_stable[:, 0, 0])
    if trace:
        tk, ts, tu = np.zeros(trace, np.int64), np.full(trace, np.nan), np.full(trace, np.nan)
        ak.trace_start(1.0 / ib[0], dd[0], float(zeta), float(eps), *walls,
                       theta[0], x0[0], v0[0],
                       float(max_time), float(match_tol), rows, types.shape[0], orb_n,
                       oph[0, 0], ou[0, 0], oz[0, 0], outf[0], outi[0], tk, ts, tu)
        return outf[:1], outi[:1], (tk, ts, tu)
    ak.run_starts(np.repeat(1.0 / ib, 1), dd, np.zeros(n, np.int64), theta, x0, v0,
                  float(zeta), float(eps), *walls, float(max_time),
                  float(match_tol), rows, types.shape[0],
                  orb_n[None, :], oph[0], ou[0], oz[0], min(n, 8 * numba.get_num_threads()),
                  outf, outi)
    return outf, outi, None
