"""Sample paths of the oscillator that can be stopped at any force sample, copied and continued.

A path advances sample step by sample step (the step ``dt`` of the noise spec) through the
exact simulator's kernel (:func:`vibroimpact.impact.kernels.run_steps`, the loop
:func:`vibroimpact.simulate` runs), :data:`CHUNK` samples a call. Its state at a sample, a
:class:`PathState`, is everything the future depends on: the kernel's exact state
(:class:`~vibroimpact.impact.simulate.SampleState`: position and velocity, the sample index and
so the harmonic force's phase, whether the mass rests on the wall) and the random force's
(:class:`~vibroimpact.rare.forcing.ForceState`: the sample there and the filter's memory).

The target set B is the wall: a wall stands at ``x = level`` and reaching B is the first
impact, whose instant the simulator finds exactly inside the step (the smallest root of
``x - level``, grazing double crossings included; docs/model.md, section 5). For a wall-free
problem (an up-crossing of ``level``) the wall's restitution is irrelevant, since the path stops
at its first impact; this is exact, where a test of ``x`` at the samples would miss the
crossings between them. The return to the start set A and the reaction coordinate are read at
the samples (``x, x'`` recorded there by the kernel, as ``simulate(record_every=1)`` does).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from vibroimpact import _checks
from vibroimpact.impact import kernels
from vibroimpact.impact.simulate import (SampleState, initial_vector, model_parameters)
from vibroimpact.model import Model
from vibroimpact.rare.forcing import ForceFilter, ForceState

#: Samples per kernel call. A path is stored with the kernel's state every CHUNK samples, so
#: a branch at sample j re-simulates at most CHUNK - 1 steps from the boundary before it.
CHUNK = 64
_BUFFER = 2 * kernels.STEP_HEADROOM

#: How a path ended.
RETURNED, REACHED, RUNNING = "A", "B", "running"


@dataclass(frozen=True)
class PathState:
    """The state a clone copies at a sample.

    Attributes
    ----------
    sample : SampleState
        The simulator's exact state: ``x - p_h, x' - p_h'``, the mode (free, resting on the
        wall), the sample index ``k`` (time ``k dt``, the harmonic force's phase).
    force : ForceState
        The random force at the sample and its filter's memory.
    """

    sample: SampleState
    force: ForceState


@dataclass
class Path:
    """One path of a splitting run, from its own start to its end.

    Attributes
    ----------
    start : PathState
        The state it started from (sample ``start.sample.k``).
    origin : int
        The sample where the excursion it belongs to began (its ancestors' start); its
        duration is counted from there.
    prefix_score : float
        The largest reaction coordinate of the ancestors' part before ``start``.
    dt : float
        Sample step.
    xi, x, v : ndarray of float64
        Reaction coordinate, displacement and velocity at the samples from the start to the
        end sample (inclusive). The coordinate at the end sample of a path back in A is
        ``-inf``: the path stopped there, no clone branches there.
    e, r : ndarray of float64
        The unit innovations after the start, and the force samples from the start.
    end : str
        ``"A"`` (returned to A at a sample), ``"B"`` (hit the wall) or ``"running"``.
    t_end : float
        The time it ended: the sample of its return to A, or the impact's instant.
    n_steps : int
        Sample steps simulated for it (those run past its end inside the last chunk included).
    """

    start: PathState
    origin: int
    prefix_score: float
    dt: float
    xi: np.ndarray = None
    x: np.ndarray = None
    v: np.ndarray = None
    e: np.ndarray = None
    r: np.ndarray = None
    end: str = RUNNING
    t_end: float = math.nan
    n_steps: int = 0
    boundaries: list = field(default_factory=list, repr=False)

    @property
    def score(self):
        """The path's level: +inf when it reached B, else the largest reaction coordinate at
        its samples (its ancestors' included)."""
        if self.end == REACHED:
            return math.inf
        return max(self.prefix_score, float(self.xi.max()))

    @property
    def duration(self):
        """Time from the excursion's start (``origin``) to the end (dimensionless)."""
        return self.t_end - self.origin * self.dt

    def first_above(self, z):
        """Index of the first sample whose reaction coordinate exceeds ``z``, or None."""
        above = np.flatnonzero(self.xi > z)
        return int(above[0]) if above.size else None


class Dynamics:
    """The oscillator, its random and harmonic force and its wall at ``level``: paths of it.

    Parameters
    ----------
    zeta : float
        Damping ratio, ``0 < zeta < 1``.
    noise : NoiseSpec
        The random force (its ``dt`` is the sample step).
    level : float
        Position of the wall (the target set B: the first impact), dimensionless displacement.
    coordinate : callable
        Reaction coordinate ``xi(x, v)``: arrays in, an array out (vectorized). One with an
        ``along_path(x, v, r, memory, e)`` method (:class:`~vibroimpact.rare.coordinates.
        Predicted`) reads the force too: the samples ``r``, the filter's memory at the path's
        start and the innovations ``e`` after it; its ``force`` must have this force's taps.
    start_set : callable
        The start set A: ``start_set(x, v)`` is a boolean array, true inside A.
    eps : float, optional
        The wall's restitution, ``0 <= eps <= 1``: irrelevant to paths stopped at B, it acts
        in the control run after a hit.
    amplitude, beta : float, optional
        Harmonic force ``amplitude sin(beta tau)``.
    phase : {"minimum", "linear"}, optional
        The FIR of a ``band_limited`` force (:class:`~vibroimpact.rare.forcing.ForceFilter`).
    """

    def __init__(self, zeta, noise, level, coordinate, start_set, *, eps=1.0, amplitude=0.0,
                 beta=1.0, phase="minimum"):
        zeta = _checks.zeta(zeta)
        level = _checks.real("level", level)
        if not (callable(coordinate) and callable(start_set)):
            raise ValueError("coordinate and start_set must be callables of (x, v) arrays")
        self.model = Model.paper(zeta, _checks.eps(eps), level, _checks.real("amplitude",
                                 amplitude), _checks.real("beta", beta, low=0.0, low_open=True))
        self.filter = ForceFilter(noise, phase)
        if hasattr(coordinate, "along_path"):
            theirs = getattr(coordinate, "force", None)
            if not (isinstance(theirs, ForceFilter) and theirs.kind == self.filter.kind
                    and theirs.spec == noise and (theirs.taps is None) == (self.filter.taps
                                                                         is None)
                    and (theirs.taps is None or np.array_equal(theirs.taps, self.filter.taps))):
                raise ValueError("the coordinate's force filter is not the paths' (same "
                                 "spec and phase needed)")
        self.dt = noise.dt
        self.level = level
        self.coordinate = coordinate
        self.start_set = start_set
        self.P = model_parameters(self.model, self.dt)
        self._imp = (np.empty(_BUFFER, np.int64), np.empty(_BUFFER), np.empty(_BUFFER))
        self._stk = (np.empty(_BUFFER, np.int64), np.empty(_BUFFER), np.empty(_BUFFER))
        self._cnt = np.zeros(kernels.N_COUNTERS, np.int64)
        self._ftot = np.zeros(kernels.N_FTOT)
        self._grid = np.empty(CHUNK + 1)
        self._grid_v = np.empty(CHUNK + 1)
        self._grid_n = np.zeros(1, np.int64)
        #: Sample steps simulated so far, by every path and every re-simulation to a branch.
        self.n_steps = 0

    def initial(self, rng, x0=0.0, v0=0.0, *, k=0, stuck=False):
        """A start at ``x0, v0`` (or resting on the wall) at sample ``k``, the random force in
        a draw of its stationary state from ``rng``."""
        x0 = _checks.real("x0", x0, high=self.level)
        v0 = _checks.real("v0", v0)
        vec = initial_vector(self.model, self.dt, x0, v0, _checks.integer("k", k, low=0),
                              bool(stuck))
        return PathState(SampleState.of_vector(k, vec), self.filter.stationary(rng))

    # -- stepping -------------------------------------------------------------------------
    def _steps(self, r, k0, vec, record):
        """Run the kernel over ``r`` (samples k0 ...) from ``vec`` (in and out).

        Returns the sample reached and the first impact's time (NaN: none); with ``record``
        the grid holds ``x, x'`` at the samples taken. Stops at a full event buffer, which
        only happens after an impact (B reached).
        """
        self._grid_n[0] = 0
        k1 = k0 + r.size - 1
        k = k0
        t_hit, step_hit = math.nan, -1
        while k < k1:
            self._cnt[:] = 0
            status, k = kernels.run_steps(r[k - k0:], k, k1, vec, self.P, *self._imp,
                                          *self._stk, self._cnt, self._ftot, self._grid,
                                          self._grid_v, 1 if record else 0, self._grid_n)
            if status not in (kernels.OK, kernels.BUFFER_FULL):
                raise RuntimeError(f"the simulator stopped with status {status} at sample "
                                   f"{k} (force samples {r[k - k0]!r}, {r[k - k0 + 1]!r})")
            if self._cnt[kernels.CNT_IMPACTS] > 0 and math.isnan(t_hit):
                step_hit = int(self._imp[0][0])
                t_hit = step_hit * self.dt + self._imp[1][0]
        return t_hit, step_hit

    def run(self, start, rng, *, origin=None, prefix_score=-math.inf, stop=True,
            max_steps=10**7):
        """Simulate a path from ``start`` with fresh innovations from ``rng``.

        Parameters
        ----------
        start : PathState
            Where it starts.
        rng : numpy.random.Generator
            Its innovations, CHUNK at a time.
        origin : int, optional
            The excursion's first sample (default: the start's).
        prefix_score : float, optional
            The ancestors' largest reaction coordinate before ``start``.
        stop : bool, optional
            Stop at the first return to A (a sample in A after the start) or at B; False
            runs ``max_steps`` samples whatever happens (a control run).
        max_steps : int, optional
            Steps after which a stopping path that has neither returned nor reached B is an
            error (A unreachable from where it wanders).

        Returns
        -------
        Path
        """
        k_start = start.sample.k
        path = Path(start, k_start if origin is None else origin, prefix_score, self.dt)
        vec = start.sample.vector()
        force = start.force
        k = k_start
        xs, vs, es, rs = [], [], [], [np.array([force.r])]
        while True:
            n = CHUNK if stop else min(CHUNK, k_start + max_steps - k)
            path.boundaries.append((vec.copy(), force if self.filter.kind == "lowpass2"
                                    else None))
            e = rng.standard_normal(n)
            r, force = self.filter.advance(force, e)
            t_hit, step_hit = self._steps(r, k, vec, record=True)
            n_rec = int(self._grid_n[0])
            path.n_steps += n
            self.n_steps += n
            x = self.level - self._grid[:n_rec]
            v = self._grid_v[:n_rec].copy()
            end_i, end, t_end = (self._stop(k, k == k_start, x, v, t_hit, step_hit) if stop
                                 else (None, None, math.nan))
            keep = n_rec if end is None else end_i + 1
            xs.append(x[:keep])
            vs.append(v[:keep])
            if end is not None:
                es.append(e[:end_i])
                rs.append(r[1:end_i + 1])
                path.end = end
                path.t_end = t_end
                break
            es.append(e)
            rs.append(r[1:])
            k += n
            if k - k_start >= max_steps:
                if stop:
                    raise RuntimeError(f"a path ran {max_steps} steps without returning to "
                                       f"the start set or reaching the wall: check start_set")
                # the end sample itself
                xe, ve = self.state_xv(vec, k)
                xs.append(np.array([xe]))
                vs.append(np.array([ve]))
                path.t_end = k * self.dt
                break
        path.x = np.concatenate(xs)
        path.v = np.concatenate(vs)
        path.e = np.concatenate(es) if es else np.empty(0)
        path.r = np.concatenate(rs)
        path.xi = self._coordinate_along(path)
        if path.end == RETURNED:
            # the sample back in A stops the path: no level is reached there and no clone
            # branches there (a coordinate need not be low on A)
            path.xi[-1] = -math.inf
        return path

    def _stop(self, k, first, x, v, t_hit, step_hit):
        """Where a stopping path ends inside a chunk: ``(i, end, t_end)``, ``i`` the index of
        its end sample in the chunk (samples ``k, k + 1, ...`` at ``x, v``), ``end`` RETURNED
        or REACHED and ``t_end`` its time, or ``(None, None, nan)`` to go on. ``first``: the
        chunk starts at the path's start, which does not count as a return. Here A is read
        at the samples and B is the first impact (``t_hit`` in step ``step_hit``)."""
        end_i, end, t_end = None, None, math.nan
        inside = self.start_set(x, v)
        if first:
            inside[0] = False       # the start itself does not count as a return
        ret = np.flatnonzero(inside)
        if ret.size:
            end_i, end, t_end = int(ret[0]), RETURNED, (k + int(ret[0])) * self.dt
        if not math.isnan(t_hit):
            step = step_hit - k
            if end_i is None or step < end_i:
                end_i, end, t_end = step, REACHED, t_hit
        return end_i, end, t_end

    def _coordinate_along(self, path):
        """The reaction coordinate at every sample of ``path`` (its ``x, v``, and for a
        coordinate with ``along_path`` its force)."""
        along = getattr(self.coordinate, "along_path", None)
        if along is None:
            return np.asarray(self.coordinate(path.x, path.v), dtype=float)
        return np.asarray(along(path.x, path.v, path.r, path.start.force.memory, path.e),
                          dtype=float)

    def state_xv(self, vec, k):
        """``x, x'`` at sample ``k`` from the kernel's state vector."""
        from vibroimpact.impact.simulate import state_at

        x, v, _ = state_at(vec, self.P, k)
        return float(x), float(v)

    def state_at(self, path, j):
        """The exact :class:`PathState` of ``path`` at its ``j``-th sample.

        The kernel's state is simulated again from the last stored boundary before ``j``
        through the path's own force samples: the same arithmetic as the first time, so the
        same bits. The force's memory is the path's innovations (FIR), or the filter state
        advanced from the boundary (lowpass2).
        """
        b = j // CHUNK
        vec, fb = path.boundaries[b]
        vec = vec.copy()
        k_start = path.start.sample.k
        i0 = b * CHUNK
        if j > i0:
            self._steps(np.ascontiguousarray(path.r[i0:j + 1]), k_start + i0, vec,
                        record=False)
        self.n_steps += j - i0
        return PathState(SampleState.of_vector(k_start + j, vec),
                         self._force_at(path, j, fb, i0))

    def _force_at(self, path, j, boundary, i0):
        r_j = float(path.r[j])
        kind = self.filter.kind
        if kind == "white":
            return ForceState(r_j, np.empty(0))
        if kind == "band_limited":
            m1 = self.filter.n_memory
            # the innovations e_{k-m+2} ... e_k: the start's memory, then the path's own
            if j < m1:
                buf = np.concatenate([path.start.force.memory[j:], path.e[:j]])
            else:
                buf = path.e[j - m1:j].copy()
            return ForceState(r_j, buf)
        _, end = self.filter.advance(boundary, path.e[i0:j])
        return ForceState(r_j, end.memory)
