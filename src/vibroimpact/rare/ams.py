"""Adaptive multilevel splitting on the exact simulator: the probability of reaching B before
returning to A, and the mean first-passage time to B.

The algorithm (Cerou & Guyader 2007, "Adaptive multilevel splitting for rare event
analysis", Stoch. Anal. Appl. 25; in the unbiased form of Brehier, Gazeau, Goudenege,
Lelievre & Rousset 2016, "Unbiasedness of some generalized adaptive multilevel splitting
algorithms", Ann. Appl. Probab. 26):

1. ``n`` paths start from ``n`` states (:mod:`vibroimpact.rare.paths`) and run until they
   return to A or reach B. The score of a path is the largest reaction coordinate at its
   samples (its ancestors' included), ``+inf`` if it reached B.
2. Iteration ``j``: ``Z_j`` is the ``k``-th smallest score. If ``Z_j >= z_max`` stop. Every
   path whose score is ``<= Z_j`` is killed (ties all killed: ``K_j >= k`` of them); if all
   ``n`` would be, the estimate is 0 (extinction). Each killed path is replaced by a clone
   of a survivor drawn uniformly (with replacement): the survivor's exact state at its
   first sample with coordinate ``> Z_j`` (:meth:`~vibroimpact.rare.paths.Dynamics.state_at`),
   continued with fresh innovations until A or B.
3. ``p_hat = prod_j (1 - K_j / n) * (number of final paths in B) / n``.

``E[p_hat] = p`` exactly, for any ``n >= 2``, ``k``, reaction coordinate and ``z_max``
(Brehier et al. 2016, Theorem 4.1, for a Markov chain in discrete time: here the chain of the
states at the samples, with "reached B inside the step" part of the state); the coordinate
and ``z_max`` change only the variance. With the coordinate ``x / sigma_x`` and ``z_max`` the
level, the algorithm stops once ``n - k + 1`` paths reached B; with a coordinate that can
exceed ``z_max`` outside B (an energy), paths above ``z_max`` that end in A count 0.

The variance is the whole matter at high levels. The estimate is heavy-tailed when the
coordinate has inertia: with the energy coordinate and the smooth band-limited force, the
clones of a path branched at its first sample above a level nearly repeat its coming peak
(the force's next samples are fixed by its memory), tie with it and are killed with it; at
``L = 7`` five runs (n = 200) all underestimated ``p`` 20 to 200 times. The coordinate
:class:`~vibroimpact.rare.coordinates.Predicted` counts the force's predictable part (a
martingale in the linear theory: clones part at once) and the same runs cover the known
answer (tests/test_rare_events.py).

Randomness: one seed is the root of a recorded tree of ``numpy.random.SeedSequence``,
``SeedSequence(seed, spawn_key=key)`` with ``key = (run, 0)`` the control run, ``(run, 1,
i)`` the ``i``-th initial path, ``(run, 2, j)`` the choice of parents at iteration ``j``,
``(run, 3, j, c)`` the ``c``-th clone of iteration ``j``: a whole estimate is a function of
the seed, bit for bit.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vibroimpact import _checks
from vibroimpact.rare.paths import REACHED, Dynamics


def _rng(seed, *key):
    """The generator at ``key`` in the seed tree of ``seed`` (an int or a SeedSequence)."""
    root = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    sequence = np.random.SeedSequence(root.entropy, spawn_key=tuple(root.spawn_key) + key)
    return np.random.Generator(np.random.PCG64(sequence))


@dataclass(frozen=True)
class SplittingRun:
    """One run of adaptive multilevel splitting.

    Attributes
    ----------
    probability : float
        ``p_hat``, the unbiased estimate of P(reach B before A) from the starts' law.
    killed : ndarray of int64
        ``K_j``, paths killed at each iteration.
    levels : ndarray of float64
        ``Z_j``, the killing levels (reaction coordinate).
    n_reached : int
        Final paths in B.
    durations : ndarray of float64
        Time from its excursion's start to B of each final path in B (dimensionless).
    n_steps : int
        Sample steps simulated (every path, and every re-simulation to a branch point).
    extinct : bool
        All paths were killed at once (``p_hat = 0``).
    """

    probability: float
    killed: np.ndarray
    levels: np.ndarray
    n_reached: int
    durations: np.ndarray
    n_steps: int
    extinct: bool

    @property
    def n_iterations(self):
        """Iterations (killing levels) taken."""
        return int(self.killed.size)


def ams(dynamics, starts, seed, *, z_max=math.inf, run=0, k=1, max_iterations=10**6):
    """Adaptive multilevel splitting from the given starting states.

    Parameters
    ----------
    dynamics : Dynamics
        The oscillator, its force, B (its wall), A and the reaction coordinate.
    starts : sequence of PathState
        The ``n >= 2`` initial states (one path each), distributed as the law the
        probability is conditioned on.
    seed : int or numpy.random.SeedSequence
        Root of the seed tree (module docstring).
    z_max : float, optional
        Stop when the ``k``-th smallest score reaches ``z_max`` (reaction coordinate units;
        finite, or ``inf``, the default: stop once ``n - k + 1`` paths reached B, each of
        the others killed on its way, the choice for a coordinate that can exceed the level
        outside B).
    run : int, optional
        The run's index in the tree, ``>= 0``.
    k : int, optional
        Paths killed per iteration at least, ``1 <= k < n``.
    max_iterations : int, optional
        Iterations after which the run is an error.

    Returns
    -------
    SplittingRun
    """
    if not isinstance(dynamics, Dynamics):
        raise ValueError(f"dynamics must be a Dynamics, got {type(dynamics).__name__}")
    n = len(starts)
    if n < 2:
        raise ValueError(f"starts must hold at least 2 states, got {n}")
    k = _checks.integer("k", k, low=1, high=n - 1)
    if isinstance(z_max, (int, float)) and z_max == math.inf:
        z_max = math.inf
    else:
        z_max = _checks.real("z_max", z_max)
    steps0 = dynamics.n_steps
    paths = [dynamics.run(s, _rng(seed, run, 1, i)) for i, s in enumerate(starts)]
    scores = np.array([p.score for p in paths])
    factor, killed, levels, extinct = 1.0, [], [], False
    for j in range(max_iterations + 1):
        z = float(np.partition(scores, k - 1)[k - 1])
        if z >= z_max:
            break
        if j == max_iterations:
            raise RuntimeError(f"ams took more than max_iterations={max_iterations} "
                               f"iterations (level {z!r} of z_max={z_max!r})")
        dead = np.flatnonzero(scores <= z)
        killed.append(dead.size)
        levels.append(z)
        if dead.size == n:
            factor, extinct = 0.0, True
            break
        factor *= 1.0 - dead.size / n
        alive = np.flatnonzero(scores > z)
        parents = alive[_rng(seed, run, 2, j).integers(alive.size, size=dead.size)]
        for c, (i, parent) in enumerate(zip(dead, parents)):
            paths[i] = _clone(dynamics, paths[parent], z, _rng(seed, run, 3, j, c))
            scores[i] = paths[i].score
    reached = [p for p in paths if p.end == REACHED]
    return SplittingRun(
        probability=factor * len(reached) / n, killed=np.array(killed, np.int64),
        levels=np.array(levels), n_reached=len(reached),
        durations=np.array([p.duration for p in reached]), n_steps=dynamics.n_steps - steps0,
        extinct=extinct)


def _clone(dynamics, parent, z, rng):
    """A new path: ``parent`` up to its first sample above ``z``, then fresh innovations."""
    j = parent.first_above(z)
    if j is None:
        # a path in B whose samples all stay <= z: it crossed inside its last step, and its
        # copy reaches B there too (the chain's state after that step is "in B")
        return parent
    prefix = max(parent.prefix_score, float(parent.xi[:j].max()) if j else -math.inf)
    return dynamics.run(dynamics.state_at(parent, j), rng, origin=parent.origin,
                        prefix_score=prefix)


@dataclass(frozen=True)
class FirstPassage:
    """Mean first-passage time to B and the probability behind it, over independent runs.

    Attributes
    ----------
    probability, probability_se : float
        Mean over the runs of ``p_hat`` (P(reach B before returning to A), from A's exit
        law) and its standard error ``std / sqrt(R)``.
    time, time_se : float
        The mean first-passage time to B from the initial state (dimensionless time) and
        its standard error (delta method on the run means).
    cycle : float
        Mean time from one exit of A to the next (control runs).
    first_exit : float
        Mean time from the initial state to its first exit of A.
    success : float
        Mean duration of a successful excursion (exit of A to B).
    runs : tuple of SplittingRun
        The runs.
    n_steps : int
        Sample steps simulated in all (control runs included).
    """

    probability: float
    probability_se: float
    time: float
    time_se: float
    cycle: float
    first_exit: float
    success: float
    runs: tuple
    n_steps: int


def starting_exits(exits, burn, gap, n_clones, n_steps, sets):
    """The exits of A a control run gives as starting states: ``(used, mean gap, picks)``.

    ``exits`` (sample indices of the control run's exits of A, ``n_steps`` long) after
    ``burn``; every stride-th, so spaced by ``gap`` samples on average, and not the first exit
    after a fixed delay, which would favour the exits that end long cycles (length bias).
    ``used``: the exits after ``burn``; the mean gap between them is in samples. Too few
    exits raise a RuntimeError naming ``sets``, the argument that defines A."""
    used = exits[exits >= burn]
    if used.size < 2:
        raise RuntimeError(f"the control run of {n_steps} steps left A {exits.size} times: "
                           f"check {sets}")
    mean_gap = (used[-1] - used[0]) / (used.size - 1)
    picks = used[::max(1, math.ceil(gap / mean_gap))]
    if picks.size < n_clones:
        raise RuntimeError(f"the control run of {n_steps} steps gave {picks.size} starting "
                           f"exits, fewer than n_clones={n_clones}; check {sets} or shorten "
                           f"spacing")
    return used, mean_gap, picks


def first_passage(dynamics, *, n_clones, n_runs, seed, x0=0.0, v0=0.0, burn_in, spacing,
                  z_max=math.inf, k=1):
    """Mean first-passage time to B from ``(x0, v0)`` by splitting and renewal.

    Parameters
    ----------
    dynamics : Dynamics
        The oscillator, B (its wall), A (``start_set``) and the reaction coordinate.
    n_clones : int
        Paths per splitting run, ``>= 2``.
    n_runs : int
        Independent runs ``R >= 2``, each with its own control run and seeds.
    seed : int or numpy.random.SeedSequence
        Root of the seed tree.
    z_max : float, optional
        The splitting's final level (see :func:`ams`).
    x0, v0 : float, optional
        The initial state at ``tau = 0`` (inside A); the random force starts in a draw of
        its stationary state.
    burn_in : float
        Time (dimensionless, ``>= 0``) of the control run before its exits are used.
    spacing : float
        Mean time between two exits taken as starting states (``> 0``): every ``s``-th exit
        of the control run, ``s`` the spacing over the mean cycle rounded up; a few
        correlation times ``1 / zeta`` keep them close to independent.
    k : int, optional
        Killed per iteration at least.

    Returns
    -------
    FirstPassage

    Notes
    -----
    The renewal decomposition. From the initial state the path first leaves A at ``t_1``;
    after that its history is a sequence of cycles, each from an exit of A to the next,
    until the excursion (the part of a cycle outside A) that reaches B. If the exit states
    were independent draws of one law ``mu``, the number of failed cycles would be geometric,
    ``E[N] = (1 - p) / p`` with ``p = P_mu(reach B before A)``, and exactly

        T = E[t_1] + E[cycle | fail] (1 - p) / p + E[duration of a successful excursion].

    Each run estimates ``mu`` by the exits of a control run from ``(x0, v0)`` (after
    ``burn_in``, every ``s``-th: the stationary exit law of the dynamics; taking instead the
    first exit after a fixed delay would favour exits after long cycles and bias ``p``),
    ``E[t_1]`` and the mean cycle by the same control run, ``p`` by :func:`ams` from those
    exits (unbiased for ``P_mu``), and the successful duration by the final paths in B (from
    their excursion's start). The runs are independent; ``T`` is evaluated at the means over
    the runs (``p`` enters as ``1 / mean p``, not ``mean (1 / p)``, which a run with few
    successes would bias). Consistent as ``R, n`` and the control runs grow, up to the
    approximations named: consecutive exits are not independent (correlation time ``~
    1 / zeta``, short against the ``1 / p`` cycles to B), the control run's cycles are not
    conditioned on failing (an error ``O(p)`` relative), and the first cycles from a start
    at rest are not yet stationary (an error of the order of the transient ``1 / (2 zeta)``
    against ``T``).
    """
    n_clones = _checks.integer("n_clones", n_clones, low=2)
    n_runs = _checks.integer("n_runs", n_runs, low=2)
    burn_in = _checks.real("burn_in", burn_in, low=0.0)
    spacing = _checks.real("spacing", spacing, low=0.0, low_open=True)
    dt = dynamics.dt
    if not bool(np.asarray(dynamics.start_set(np.array([x0]), np.array([v0])))[0]):
        raise ValueError(f"x0, v0 must lie in the start set A, got x0={x0!r}, v0={v0!r}")
    burn, gap = int(math.ceil(burn_in / dt)), max(1, int(math.ceil(spacing / dt)))
    steps0 = dynamics.n_steps
    runs, p, cycle, first, succ = [], [], [], [], []
    for r in range(n_runs):
        rng = _rng(seed, r, 0)
        control = dynamics.run(dynamics.initial(rng, x0, v0), rng, stop=False,
                               max_steps=burn + 2 * (n_clones + 1) * gap)
        inside = np.asarray(dynamics.start_set(control.x, control.v), dtype=bool)
        exits = np.flatnonzero(inside[:-1] & ~inside[1:]) + 1
        _, mean_gap, picks = starting_exits(exits, burn, gap, n_clones, control.xi.size - 1,
                                         "start_set")
        cycle.append(mean_gap * dt)
        first.append(exits[0] * dt)
        starts = [dynamics.state_at(control, int(i)) for i in picks[:n_clones]]
        run = ams(dynamics, starts, seed, z_max=z_max, run=r, k=k)
        runs.append(run)
        p.append(run.probability)
        succ.extend(run.durations)
    p, cycle = np.array(p), np.array(cycle)
    p_mean, p_se = float(p.mean()), float(p.std(ddof=1) / math.sqrt(n_runs))
    c_mean, c_se = float(cycle.mean()), float(cycle.std(ddof=1) / math.sqrt(n_runs))
    success = float(np.mean(succ)) if succ else math.nan
    if p_mean > 0.0:
        time = float(np.mean(first)) + c_mean * (1.0 - p_mean) / p_mean + success
        time_se = math.hypot(c_mean / p_mean**2 * p_se, (1.0 - p_mean) / p_mean * c_se)
    else:
        time, time_se = math.inf, math.nan
    return FirstPassage(probability=p_mean, probability_se=p_se, time=time, time_se=time_se,
                        cycle=c_mean, first_exit=float(np.mean(first)), success=success,
                        runs=tuple(runs), n_steps=dynamics.n_steps - steps0)

