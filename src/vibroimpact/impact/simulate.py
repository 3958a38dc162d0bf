"""Public entry point of the exact simulator: :func:`simulate` and :func:`simulate_chunks`.

The numerics live in :mod:`vibroimpact.impact.kernels`; this module validates the input, builds
the kernel's parameter vector, streams the force record through the kernel in chunks
(bounded memory on records of any length) and wraps the events in a
:class:`SimulationResult`.
"""
from dataclasses import dataclass, field
from functools import cached_property
import math
import sys

import numpy as np

from vibroimpact import _checks
from vibroimpact.impact import kernels
from vibroimpact.impact.hops import pressed_flights
from vibroimpact.impact.parameters import parameters
from vibroimpact.model import Model
from vibroimpact.stats.collisions import (DEFAULT_REBOUND_FLOOR, MIN_REBOUND_FLOOR, Collisions,
                                          close_open_phase, group_collisions)

_BUFFER = 2 * kernels.STEP_HEADROOM


@dataclass(frozen=True)
class SampleState:
    """The simulator's exact state at a force sample: where a run can be stopped and continued.

    Attributes
    ----------
    k : int
        The sample index; the time is ``k * dt`` (dimensionless), which fixes the phase
        ``beta k dt`` of the harmonic force.
    w, wv : float
        ``x - p_h`` and ``x' - p_h'``: the displacement and velocity less the harmonic
        particular solution ``p_h = A q sin(beta tau - phi)`` (docs/model.md, section 5); with
        no harmonic force, ``x`` and ``x'`` themselves.
    mode : int
        The kernel's mode (:mod:`vibroimpact.impact.layout`): free, resting on a wall
        (``STUCK``, ``STUCK_LO``), or free exactly on a wall (``WALL``, ``WALL_LO``).
    sin_psi, cos_psi : float
        ``sin psi, cos psi`` with ``psi = beta k dt - phi``, as the kernel carries them
        (rotated step by step between its resynchronisations).

    Notes
    -----
    These are the kernel's own numbers, not ``(x, v)`` rebuilt from them: a run continued
    from the ``end_state`` of a run stopped at a sample takes, given the same force samples,
    bit for bit the steps of the run never stopped (tests/test_rare_events.py). Build one from
    a displacement and velocity with :func:`sample_state`.
    """

    k: int
    w: float
    wv: float
    mode: int
    sin_psi: float
    cos_psi: float

    def vector(self):
        """The kernel's state vector (float64, slots ``S_*``)."""
        state = np.empty(kernels.N_STATE)
        state[[kernels.S_W, kernels.S_WV, kernels.S_MODE, kernels.S_SIN_PSI,
               kernels.S_COS_PSI]] = (self.w, self.wv, self.mode, self.sin_psi, self.cos_psi)
        return state

    @classmethod
    def of_vector(cls, k, state):
        """The state at sample ``k`` from the kernel's state vector ``state``."""
        return cls(int(k), float(state[kernels.S_W]), float(state[kernels.S_WV]),
                   int(state[kernels.S_MODE]), float(state[kernels.S_SIN_PSI]),
                   float(state[kernels.S_COS_PSI]))


def initial_vector(model, dt, x0, v0, k=0, stuck=False):
    """The kernel's state vector at sample ``k`` for ``x = x0, x' = v0`` (free) or resting
    on the wall at ``x = delta`` (``stuck``)."""
    beta = model.beta
    amplitude = model.amplitude
    q = 1.0 / math.hypot(1.0 - beta * beta, 2.0 * model.zeta * beta)
    phi = math.atan2(2.0 * model.zeta * beta, 1.0 - beta * beta)
    Aq = amplitude * q
    if k == 0:
        sin_psi, cos_psi = -math.sin(phi), math.cos(phi)
    else:
        bh_hi, bh_lo = kernels.two_prod(beta, dt)
        psi = kernels.phase(k, 0.0, bh_hi, bh_lo, beta) - phi
        sin_psi, cos_psi = math.sin(psi), math.cos(psi)
    state = np.empty(kernels.N_STATE)
    if stuck:
        # as the kernel holds a resting mass: w = delta - p_h, w' = -p_h' (so x' = 0)
        state[[kernels.S_W, kernels.S_WV, kernels.S_MODE]] = (
            model.delta - Aq * sin_psi, -Aq * beta * cos_psi, kernels.STUCK)
    elif k == 0:
        # the expression of every run started at tau = 0 (its results unchanged bit for bit)
        state[[kernels.S_W, kernels.S_WV, kernels.S_MODE]] = (
            x0 + Aq * math.sin(phi), v0 - Aq * beta * math.cos(phi), kernels.FREE)
    else:
        state[[kernels.S_W, kernels.S_WV, kernels.S_MODE]] = (
            x0 - Aq * sin_psi, v0 - Aq * beta * cos_psi, kernels.FREE)
    state[[kernels.S_SIN_PSI, kernels.S_COS_PSI]] = sin_psi, cos_psi
    return state


def sample_state(zeta, delta, dt, x, v=0.0, *, k=0, stuck=False, amplitude=0.0, beta=1.0):
    """A :class:`SampleState` from a displacement and velocity at sample ``k``.

    Parameters
    ----------
    zeta : float
        Damping ratio, ``0 < zeta < 1``.
    delta : float
        The wall's position (the state must satisfy ``x <= delta``).
    dt : float
        Sample step (dimensionless time), ``> 0``.
    x, v : float
        Displacement and velocity at ``tau = k dt``; ignored (``x = delta``, ``v = 0``) when
        ``stuck``.
    k : int, keyword-only
        Sample index, ``>= 0``: the start time ``k dt`` and so the harmonic force's phase.
    stuck : bool, keyword-only
        Resting on the wall at ``x = delta`` (held there while ``f - delta > 0``).
    amplitude, beta : float, keyword-only
        The harmonic force ``amplitude sin(beta tau)`` of the run to be started.

    Returns
    -------
    SampleState
        For :func:`simulate`'s ``start`` (one wall, or the upper wall of two).
    """
    k = _checks.integer("k", k, low=0)
    model = Model.paper(_checks.zeta(zeta), 0.0, _checks.real("delta", delta),
                        _checks.real("amplitude", amplitude),
                        _checks.real("beta", beta, low=0.0, low_open=True))
    dt = _checks.real("dt", dt, low=0.0, low_open=True)
    x = _checks.real("x", x, high=delta)
    v = _checks.real("v", v)
    return SampleState.of_vector(k, initial_vector(model, dt, x, v, k, bool(stuck)))


@dataclass(frozen=True)
class SimulationResult:
    """Events and counters of one simulation (or one chunk of it).

    Attributes
    ----------
    impact_time : ndarray of float64, shape (n,)
        Impact instants tau_j (dimensionless time), increasing.
    impact_velocity : ndarray of float64, shape (n,)
        Approach velocities u_{j-0} > 0 (paper eq. 6); the velocity after impact is
        ``-eps * impact_velocity`` (eq. 7; ``-eps(u) u`` under a law whose restitution varies
        with the speed, :meth:`vibroimpact.model.Model.restitution`).
    impact_step, impact_offset : ndarray, shape (n,)
        ``impact_time = impact_step * dt + impact_offset`` with ``0 <= offset <= dt``: the
        full-precision form, for intervals on long records.
    stick_start, stick_end : ndarray of float64, shape (n_stick,)
        Intervals during which the mass rests on the wall (after a chatter sequence, a
        plastic impact, or a start at rest on the wall).
    grid_time, a, v : ndarray of float64
        ``a(tau) = delta - x(tau)`` (the paper's displacement from the wall) and the velocity
        ``x'(tau)`` every ``record_every`` samples; empty unless asked for. ``grid_time`` is
        built on first use from ``grid``.
    grid : ndarray or tuple
        The recorded samples' times: an array, or ``(first, stride, n, dt)``, the samples
        ``first, first + stride, ...`` (``n`` of them) at spacing ``dt`` (a chunk's: its
        times cost a pass over the chunk that a consumer reading only ``a`` and ``v``, an
        events cell, does not pay).
    n_steps, n_impacts, n_chatter : int
        Force sample steps taken, impacts, chatter sequences closed at their accumulation point.
    contact_time : float
        Total time spent resting on the wall.
    t_end, x_end, v_end : float
        Final time and state; ``stuck_end`` tells whether the mass rests on the wall there,
        and ``stuck_since`` since when (NaN when it does not). In a chunk of
        :func:`simulate_chunks` other than the last, a sticking phase still going on at the
        chunk's end is in ``stick_start``/``stick_end`` of the chunk where it ends.
    n_collisions : int
        Collisions: impacts grouped with the chatter sequence they start and the sticking
        that follows, up to the release (docs/figures.md, "Collisions, chatter and sticking";
        :mod:`vibroimpact.stats.collisions`). Unlike ``n_impacts``, which counts every
        rebound the kernel resolved before summing a chatter tail, it depends on no numerical
        tolerance; every impact statistic counts collisions.
    collision_time, collision_step, collision_offset : ndarray, shape (n_collisions,)
        Instant of each collision's first impact (and its split form, as for impacts).
    collision_velocity : ndarray of float64, shape (n_collisions,)
        Approach velocity of each collision's first impact; its velocity after impact (that
        of its first rebound) is ``eps * collision_velocity`` (``eps(u) u`` under a
        speed-dependent law).
    collision_rebounds : ndarray of int64, shape (n_collisions,)
        Rebounds of each collision leaving the wall at speed ``>= rebound_floor``.
    collision_stuck : ndarray of bool, shape (n_collisions,)
        Whether a sticking phase followed (before the next collision).
    collision_stick_time : ndarray of float64, shape (n_collisions,)
        Time resting on the wall in those phases.
    collision_duration : ndarray of float64, shape (n_collisions,)
        Time from its first impact to the release (stuck), or to its last impact.
    impact_collision : ndarray of int64, shape (n,)
        Index of the collision each impact belongs to.
    rebound_floor : float
        The velocity floor of ``collision_rebounds``.
    impact_wall : ndarray of int8, shape (n,)
        The wall each impact hit: 0 the wall at ``x = delta``, 1 the second wall at
        ``x = delta - gap`` (only with ``gap``; all zeros with one wall).
    stick_wall : ndarray of int8, shape (n_stick,)
        The wall each sticking interval rests on.
    model : vibroimpact.model.Model
        The oscillator, its walls and its harmonic force.
    end_state : SampleState or None
        The kernel's exact state at ``t_end`` when it falls on a sample (None otherwise):
        pass it as ``start`` to continue the run bit for bit.
    params : dict
        The physical inputs.
    force_record : array_like or None
        The random force samples simulated (a reference, not a copy; None: none), which the
        collisions read to tell chatter hops from free flights.

    The collision fields are computed on first access (``collisions`` holds them all). In a
    chunk of :func:`simulate_chunks` they are those of the chunk's own impacts (a collision
    across a chunk boundary is split); :func:`concatenate_results` groups the whole record
    again.
    """

    impact_time: np.ndarray
    impact_velocity: np.ndarray
    impact_step: np.ndarray
    impact_offset: np.ndarray
    stick_start: np.ndarray
    stick_end: np.ndarray
    grid: object
    a: np.ndarray
    v: np.ndarray
    n_steps: int
    n_impacts: int
    n_chatter: int
    contact_time: float
    t_end: float
    x_end: float
    v_end: float
    stuck_end: bool
    stuck_since: float
    params: dict = field(default_factory=dict)
    force_record: object = field(default=None, repr=False, compare=False)
    impact_wall: np.ndarray = None
    stick_wall: np.ndarray = None
    model: Model = field(default=None, compare=False)
    end_state: SampleState = None

    def __post_init__(self):
        # results built without walls (one wall): every event at the wall at delta
        for name, like in (("impact_wall", "impact_step"), ("stick_wall", "stick_start")):
            if getattr(self, name) is None:
                object.__setattr__(self, name,
                                   np.zeros(np.shape(getattr(self, like)), np.int8))

    @cached_property
    def grid_time(self) -> np.ndarray:
        """Times of the recorded samples (see ``grid``)."""
        if not isinstance(self.grid, tuple):
            return self.grid
        first, stride, n, dt = self.grid
        # k as exact floats, then one product each: (arange(n) * stride + first) * dt
        times = np.arange(first, first + n * stride, stride, dtype=np.float64)[:n]
        times *= dt
        return times

    # The collision fields are computed on first use (most streaming consumers group the
    # impacts of many chunks themselves) and cached; a frozen dataclass keeps a __dict__.
    @cached_property
    def collisions(self) -> Collisions:
        """The impacts grouped into collisions (:func:`vibroimpact.stats.group_collisions`);
        the ``collision_*`` attributes are its fields."""
        # a sticking phase still open at the end of a chunk ends there for its collisions
        return self.grouped()

    def grouped(self, rule="physical") -> Collisions:
        """The impacts grouped by ``rule`` (:data:`vibroimpact.stats.RULES`; the default,
        the physical rule, is :attr:`collisions`)."""
        p = self.params
        if "gap" not in p:
            start, end = close_open_phase(self.stick_start, self.stick_end, self.stuck_since,
                                          self.t_end)
            pressed = None
            if rule == "physical":
                pressed = pressed_flights(self.impact_step, self.impact_offset,
                                          self.force_record, p["dt"], delta=p["delta"],
                                          amplitude=p["amplitude"], beta=p["beta"])
            return group_collisions(self.impact_step, self.impact_offset,
                                    self.impact_velocity, start, end, dt=p["dt"],
                                    eps=self._restitution(), floor=p["rebound_floor"],
                                    pressed=pressed, rule=rule)
        # two walls: a rest still going on at the end is on the wall the mass ends on
        start, end, wall = close_open_phase(self.stick_start, self.stick_end, self.stuck_since,
                                            self.t_end, self.stick_wall,
                                            int(self.x_end != p["delta"]))
        pressed = None
        if rule == "physical":
            pressed = pressed_flights(self.impact_step, self.impact_offset, self.force_record,
                                      p["dt"], delta=p["delta"], amplitude=p["amplitude"],
                                      beta=p["beta"], wall=self.impact_wall, gap=p["gap"])
        return group_collisions(self.impact_step, self.impact_offset, self.impact_velocity,
                                start, end, dt=p["dt"], eps=self._restitution(),
                                floor=p["rebound_floor"], pressed=pressed, rule=rule,
                                wall=self.impact_wall, stick_wall=wall,
                                eps_lower=None if self._speed_law else p["eps_lower"])

    def _restitution(self):
        """The rebound speed's coefficient for the collisions: ``eps`` under Newton's law
        (``eps_lower`` then goes with it), else each impact's ``eps_w(u)`` by its wall's
        law (:meth:`vibroimpact.model.Model.restitution`)."""
        if not self._speed_law:
            return self.params["eps"]
        return self.model.restitution(self.impact_velocity, self.impact_wall)

    @property
    def _speed_law(self):
        """Whether a wall's restitution varies with the speed (not Newton's law)."""
        return self.model is not None and not self.model.newton

    n_collisions = property(lambda self: int(self.collisions.first.size))
    collision_time = property(lambda self: self.collisions.time)
    collision_step = property(lambda self: self.collisions.step)
    collision_offset = property(lambda self: self.collisions.offset)
    collision_velocity = property(lambda self: self.collisions.velocity)
    collision_rebounds = property(lambda self: self.collisions.rebounds)
    collision_stuck = property(lambda self: self.collisions.stuck)
    collision_stick_time = property(lambda self: self.collisions.stick_time)
    collision_duration = property(lambda self: self.collisions.duration)
    collision_wall = property(lambda self: self.collisions.wall)
    impact_collision = property(lambda self: self.collisions.impact_collision)
    rebound_floor = property(lambda self: self.params["rebound_floor"])


def _check_inputs(zeta, eps, delta, noise, dt, amplitude, beta, x0, v0, t_end, record_every,
                  chunk_size, gap=None, eps_lower=None, start=None, speed_scale=math.inf,
                  speed_scale_lower=None):
    zeta = _checks.zeta(zeta)
    eps = _checks.eps(eps)
    delta = _checks.real("delta", delta)
    amplitude = _checks.real("amplitude", amplitude)
    beta = _checks.real("beta", beta, low=0.0, low_open=True)
    model = Model.paper(zeta, eps, delta, amplitude, beta, gap=gap, eps_lower=eps_lower,
                        speed_scale=speed_scale, speed_scale_lower=speed_scale_lower)
    return (model,) + _check_run(model, noise, dt, x0, v0, t_end, record_every, chunk_size,
                                 start)


def _check_run(model, noise, dt, x0, v0, t_end, record_every, chunk_size, start=None):
    """The run's own arguments (everything but the model), checked against its walls."""
    delta, lower = model.delta, model.lower
    dt = _checks.real("dt", dt, low=0.0, low_open=True)
    k_start = 0
    if start is not None:
        if not isinstance(start, SampleState):
            raise ValueError(f"start must be a SampleState (a result's end_state, or "
                             f"sample_state(...)), got {type(start).__name__}")
        if x0 is not None or v0 != 0.0:
            raise ValueError(f"x0 and v0 must be left at their defaults (None, 0.0) with "
                             f"start, which holds the state; got x0={x0!r}, v0={v0!r}")
        k_start = start.k
    # the static position, on the nearer wall when the walls leave it out
    x0 = max(lower, min(0.0, delta)) if x0 is None else _checks.real("x0", x0)
    if x0 > delta:
        raise ValueError(f"x0 must satisfy x0 <= delta (the mass lives in x <= delta), "
                         f"got x0={x0!r} > delta={delta!r}")
    if x0 < lower:
        raise ValueError(f"x0 must satisfy x0 >= delta - gap (the mass lives between the "
                         f"walls), got x0={x0!r} < delta - gap={lower!r}")
    v0 = _checks.real("v0", v0)
    if noise is not None:
        if getattr(noise, "ndim", 1) != 1 or len(noise) < 2:
            raise ValueError("noise must be a 1-D array of at least 2 samples (or None)")
    if t_end is None:
        if noise is None:
            raise ValueError("t_end is required when noise is None")
        t_end = (k_start + len(noise) - 1) * dt
    t_end = _checks.real("t_end", t_end, low=k_start * dt, low_open=True)
    if noise is not None and t_end > (k_start + len(noise) - 1) * dt * (1.0 + 1e-12):
        raise ValueError(f"t_end must not exceed (start.k + len(noise) - 1) * dt = "
                         f"{(k_start + len(noise) - 1) * dt!r}, got {t_end!r}")
    record_every = _checks.integer("record_every", record_every, low=0)
    chunk_size = _checks.integer("chunk_size", chunk_size, low=1)
    return dt, x0, v0, t_end, record_every, chunk_size, start


def model_parameters(model, dt):
    """The parameter vector ``P`` the simulator's kernels read, for sample step ``dt``.

    One wall: the ``N_PARAMS`` slots of :mod:`vibroimpact.impact.layout`, exactly as
    before models existed. Two walls: twice as many; the second half is the lower wall
    seen in the mirrored frame ``x -> -x`` (force and harmonic amplitude negated, wall
    at ``-(delta - gap)`` hit from below, its own restitution), so that every search of
    :mod:`vibroimpact.impact.events` serves both walls unchanged. The vector is
    :func:`vibroimpact.impact.parameters.parameters` of the model's numbers, with CPython's
    ``math.hypot`` in the harmonic gain, as this vector has always had it (see there).
    """
    dt = _checks.real("dt", dt, low=0.0, low_open=True)
    zeta, beta = model.zeta, model.beta
    two = model.n_walls == 2
    lower = model.walls[1] if two else None
    return parameters(zeta, dt, model.amplitude, beta,
                      math.hypot(1.0 - beta * beta, 2.0 * zeta * beta), model.eps, model.delta,
                      model.walls[0].law.a, model.n_walls, lower.eps if two else 0.0,
                      lower.position if two else -math.inf, lower.law.a if two else 0.0)


def split_steps(t_end, dt):
    ratio = t_end / dt
    n_full = int(round(ratio))
    if abs(ratio - n_full) > 1e-9 * max(1.0, ratio):
        n_full = int(math.floor(ratio))
    n_full = max(n_full, 0)
    rem = t_end - n_full * dt
    if rem <= 1e-12 * dt:
        rem = 0.0
    return n_full, rem


#: Recording buffers handed over to chunks that `_Buffers.take_grid` keeps to record into
#: again once their chunks are let go: a consumer looping over the chunks still holds the
#: last one while the next is simulated, so the one before it is the first free.
HANDED_KEPT = 2


class _Buffers:
    def __init__(self, n_grid):
        self.imp_step = np.empty(_BUFFER, np.int64)
        self.imp_off = np.empty(_BUFFER)
        self.imp_u = np.empty(_BUFFER)
        self.stk_step = np.empty(_BUFFER, np.int64)
        self.stk_off = np.empty(_BUFFER)
        self.stk_kind = np.empty(_BUFFER)
        self.cnt = np.zeros(kernels.N_COUNTERS, np.int64)
        self.ftot = np.zeros(kernels.N_FTOT)      # the time in contact; a step that gave up
        self.grid = np.empty(max(n_grid, 1))
        self.grid_v = np.empty(max(n_grid, 1))
        self.grid_n = np.zeros(1, np.int64)
        self.handed = []        # the last buffers handed over (take_grid), oldest first

    def take_grid(self, n):
        """The recorded ``a`` and ``v`` (their first ``n`` values) as arrays of their own.

        A record filling at least half of the buffers takes the buffers themselves and the
        next chunk records into others: copying 16 bytes a sample cost an events cell
        (``record_every=1``) ~2 ns a step, a fifth of its simulation. A shorter one (a chunk
        asked short with ``send``, the last) is copied, so that a kept chunk never holds
        more than twice its record.

        The others are a pair handed over two chunks before (`HANDED_KEPT`) that nothing
        refers to any more (no view of it alive: its reference count is the list's and the
        call's alone), else new ones: a consumer that reads each chunk and lets it go (the
        events and spectra cells) records into memory already paged in (a new 8 MB array is
        zeroed by the system page by page, ~1 ns a step for the pair); one that keeps its
        chunks (`simulate`) gets new buffers every time."""
        if 2 * n < self.grid.size:
            return self.grid[:n].copy(), self.grid_v[:n].copy()
        a, v = self.grid[:n], self.grid_v[:n]
        self.handed.append((self.grid, self.grid_v))
        free = [i for i, pair in enumerate(self.handed[:-1])
                if sys.getrefcount(pair[0]) == 2 and sys.getrefcount(pair[1]) == 2]
        if free:
            self.grid, self.grid_v = self.handed.pop(free[0])
        else:
            self.grid, self.grid_v = np.empty(self.grid.size), np.empty(self.grid_v.size)
        del self.handed[:-HANDED_KEPT]
        return a, v

    def drain(self, parts):
        n, m = int(self.cnt[kernels.CNT_IMPACTS]), int(self.cnt[kernels.CNT_STICK_EVENTS])
        parts["imp_step"].append(self.imp_step[:n].copy())
        parts["imp_off"].append(self.imp_off[:n].copy())
        parts["imp_u"].append(self.imp_u[:n].copy())
        parts["stk_step"].append(self.stk_step[:m].copy())
        parts["stk_off"].append(self.stk_off[:m].copy())
        parts["stk_kind"].append(self.stk_kind[:m].copy())
        parts["n_chatter"] += int(self.cnt[kernels.CNT_CHATTER])
        self.cnt[:] = 0


def _raise_status(status, k, dt, r, k0, diag, P):
    if status == kernels.BAD_NOISE:
        bad = k + 1 if np.isfinite(r[k - k0]) else k
        raise ValueError(f"noise must be finite: noise[{bad}] = {float(r[bad - k0])!r}")
    if status == kernels.TOO_MANY_EVENTS:
        s, gap, v, mode, n_imp, n_stk = (float(d) for d in diag)    # layout.FT_FIELDS[1:]
        delta, A, beta = (float(p)
                          for p in (P[kernels.P_DELTA], P[kernels.P_A], P[kernels.P_BETA]))
        r0, r1 = float(r[k - k0]), float(r[k - k0 + 1])
        f0 = r0 + A * math.sin(beta * k * dt)
        f1 = r1 + A * math.sin(beta * (k + 1) * dt)
        raise RuntimeError(
            f"gave up in the force step [{k * dt!r}, {(k + 1) * dt!r}] (sample {k}) after "
            f"{kernels.STEP_HEADROOM - 2} events ({int(n_imp)} impacts, {int(n_stk)} sticking "
            f"starts and ends) without reaching its end: reached offset {s!r} with "
            f"x - delta = {gap!r}, x' = {v!r}, "
            f"{'resting on the wall' if mode == kernels.STUCK else 'free'}; "
            f"force samples r = ({r0!r}, {r1!r}), f - delta at the step's ends = "
            f"({f0 - delta!r}, {f1 - delta!r}). Please report these inputs as a bug.")


def simulate_chunks(zeta, eps, delta, noise=None, dt=0.1, amplitude=0.0, beta=1.0, x0=None,
                    v0=0.0, t_end=None, *, record_every=0, chunk_size=2**20,
                    rebound_floor=DEFAULT_REBOUND_FLOOR, gap=None, eps_lower=None,
                    start=None, speed_scale=math.inf, speed_scale_lower=None):
    """Simulate chunk by chunk; yield one :class:`SimulationResult` per chunk of samples.

    Same arguments as :func:`simulate`. Each chunk carries the events of its stretch of
    time; counters are per chunk; ``t_end, x_end, v_end, stuck_end`` are the chunk's last
    state. Memory is bounded by the chunk size whatever the record's length.

    The generator also accepts ``send(n)``: the next chunk then holds ``n`` samples instead
    of ``chunk_size`` (at most ``chunk_size`` when recording ``a(tau)``), so a caller that
    stops when a statistic is precise enough can step to its next check in one chunk and
    close the generator there. Chunk boundaries never change the motion: the samples are
    taken one by one by the same kernel whatever the chunking.

    Examples
    --------
    A record in chunks of 2000 samples gives the collisions of the whole record:

    >>> from vibroimpact import simulate, simulate_chunks
    >>> from vibroimpact.noise import NoiseSpec, generate_array
    >>> r = generate_array(NoiseSpec("white", rms=0.5, dt=0.1), 10001, seed=3)
    >>> sum(c.n_collisions for c in simulate_chunks(0.05, 0.5, 1.0, r, 0.1, chunk_size=2000))
    2
    """
    model, dt, x0, v0, t_end, record_every, chunk_size, start = _check_inputs(
        zeta, eps, delta, noise, dt, amplitude, beta, x0, v0, t_end, record_every, chunk_size,
        gap, eps_lower, start, speed_scale, speed_scale_lower)
    rebound_floor = _checks.real("rebound_floor", rebound_floor, low=MIN_REBOUND_FLOOR)
    yield from _simulate_model(model, noise, dt, x0, v0, t_end, record_every, chunk_size,
                               start, rebound_floor)


def _simulate_model(model, noise, dt, x0, v0, t_end, record_every, chunk_size, start,
                    rebound_floor):
    """:func:`simulate_chunks` once its arguments are checked and resolved into ``model``."""
    delta, beta = model.delta, model.beta
    P = model_parameters(model, dt)
    lower = (model.lower,) if model.n_walls == 2 else ()     # run_steps' second wall, if any
    params = dict(zeta=model.zeta, eps=model.eps, delta=delta, dt=dt,
                  amplitude=model.amplitude, beta=beta, x0=x0, v0=v0,
                  rebound_floor=rebound_floor)
    if model.n_walls == 2:
        params.update(gap=model.gap, eps_lower=model.eps_lower)
    params.update({k: v for k, v in model.params().items() if k.startswith("speed_scale")})
    k_start = 0 if start is None else start.k
    state = initial_vector(model, dt, x0, v0) if start is None else start.vector()
    n_full, rem = split_steps(t_end, dt)
    stride = int(record_every)
    zeros = None if noise is not None else np.zeros(min(chunk_size, n_full + 1) + 1)
    stick_open = [None, 0]  # start time and wall of an unfinished sticking interval
    if start is not None and start.mode in (kernels.STUCK, kernels.STUCK_LO):
        stick_open = [k_start * dt, int(start.mode == kernels.STUCK_LO)]
    buf = _Buffers(chunk_size // stride + 2 if stride else 0)   # reused by every chunk
    k0 = k_start
    size = chunk_size
    while True:
        k1 = min(k0 + size, n_full)
        if noise is None:
            r = zeros[: k1 - k0 + 1]
        else:
            r = np.ascontiguousarray(noise[k0 - k_start : k1 - k_start + 1], dtype=np.float64)
        final = k1 == n_full
        buf.grid_n[0] = 0
        buf.ftot[kernels.FT_CONTACT_TIME] = 0.0
        parts = dict(imp_step=[], imp_off=[], imp_u=[], stk_step=[], stk_off=[], stk_kind=[],
                     n_chatter=0)
        k = k0
        while k < k1:
            status, k = kernels.run_steps(r[k - k0 :], k, k1, state, P, buf.imp_step, buf.imp_off,
                                          buf.imp_u, buf.stk_step, buf.stk_off, buf.stk_kind,
                                          buf.cnt, buf.ftot, buf.grid, buf.grid_v, stride,
                                          buf.grid_n, *lower)
            if status == kernels.BUFFER_FULL:
                buf.drain(parts)
            else:
                _raise_status(status, k, dt, r, k0, buf.ftot[kernels.FT_DIAGNOSTICS], P)
        t_chunk = k1 * dt
        x, v, mode = state_at(state, P, k1)
        end_state = SampleState.of_vector(k1, state)
        if final and stride and n_full % stride == 0:
            buf.grid[buf.grid_n[0]] = delta - x
            buf.grid_v[buf.grid_n[0]] = v
            buf.grid_n[0] += 1
        if final and rem > 0.0:
            buf.drain(parts)       # the partial step may write up to STEP_HEADROOM events
            if noise is None:
                r_last = (0.0, 0.0)
            else:
                r_last = tuple(float(z)
                               for z in noise[n_full - k_start : n_full - k_start + 2])
                if not all(map(math.isfinite, r_last)):
                    raise ValueError(f"noise must be finite near sample {n_full}")
            b = (r_last[1] - r_last[0]) / dt
            if mode in (kernels.WALL, kernels.WALL_LO):
                mode = kernels.FREE     # x on the wall, v is x' itself
            step = kernels.slow_step if lower else kernels.slow_step_one   # as run_steps
            x, v, mode, status = step(
                n_full, rem, x, v, mode, r_last[0], b, P, buf.imp_step, buf.imp_off, buf.imp_u,
                buf.stk_step, buf.stk_off, buf.stk_kind, buf.cnt, buf.ftot)
            _raise_status(status, n_full, dt, r_last, n_full, buf.ftot[kernels.FT_DIAGNOSTICS],
                          P)
            t_chunk = t_end
            end_state = None
        buf.drain(parts)
        requested = yield _wrap(parts, buf, stride, dt, k0, k1, params, t_chunk, x, v, mode,
                                stick_open, final, noise, model, end_state)
        k0 = k1
        if final:
            return
        if requested is not None:
            size = _checks.integer("chunk size sent", requested, low=1,
                                   high=chunk_size if stride else None)


def state_at(state, P, k):
    """Displacement, velocity and mode at sample ``k`` from the kernel's state vector."""
    delta, beta, Aq = P[kernels.P_DELTA], P[kernels.P_BETA], P[kernels.P_AQ]
    mode = int(state[kernels.S_MODE])
    if mode == kernels.STUCK:
        return delta, 0.0, kernels.STUCK
    if mode == kernels.STUCK_LO:
        return -P[kernels.N_PARAMS + kernels.P_DELTA], 0.0, kernels.STUCK_LO
    if Aq == 0.0:
        x, v = state[kernels.S_W], state[kernels.S_WV]
    else:
        psi = (kernels.phase(k, 0.0, P[kernels.P_BH_HI], P[kernels.P_BH_LO], beta)
               - P[kernels.P_PHI])
        x = state[kernels.S_W] + Aq * math.sin(psi)
        v = state[kernels.S_WV] + Aq * beta * math.cos(psi)
    if mode == kernels.WALL:
        x = delta       # exactly on the wall, not through the round-off of w + p_h
    elif mode == kernels.WALL_LO:
        x = -P[kernels.N_PARAMS + kernels.P_DELTA]
    return x, v, mode


def _pair_sticking(time, kind, stick_open):
    """Sticking intervals and their walls from the kernel's onsets and releases in time
    order (kinds :data:`~vibroimpact.impact.layout.STICK_ON`/``STICK_OFF``, plus ``STICK_LO``
    at the lower wall); ``stick_open`` holds an onset whose release is still to come (its
    time, or None, and its wall). Returns arrays (float64, float64, int8): no Python float
    per event (a list of them cost ~1 % of a map cell)."""
    wall = (kind >= kernels.STICK_LO).astype(np.int8)
    onset = (kind - kernels.STICK_LO * wall) == kernels.STICK_ON
    first_open = stick_open[0] is not None
    # onsets and releases alternate, starting with an onset or, with one open, a release
    if onset.size and onset[first_open::2].all() and not onset[1 - first_open::2].any():
        on = np.concatenate([[stick_open[0]] if first_open else [], time[first_open::2]])
        on_wall = np.concatenate([[stick_open[1]] if first_open else [],
                                  wall[first_open::2]])
        off = time[1 - first_open::2].copy()     # contiguous, as the kernels take it
        stick_open[0] = float(on[-1]) if on.size > off.size else None
        stick_open[1] = int(on_wall[-1]) if on.size > off.size else 0
        return (on[:off.size].astype(np.float64), off,
                on_wall[:off.size].astype(np.int8))
    starts, ends, walls = [], [], []
    for t, k, w in zip(time, onset, wall):
        if k:
            stick_open[0], stick_open[1] = t, int(w)
        elif stick_open[0] is not None:
            starts.append(stick_open[0])
            ends.append(t)
            walls.append(stick_open[1])
            stick_open[0] = None
    return (np.asarray(starts, dtype=np.float64), np.asarray(ends, dtype=np.float64),
            np.asarray(walls, dtype=np.int8))


def _wrap(parts, buf, stride, dt, k0, k1, params, t_chunk, x, v, mode, stick_open, final,
          noise, model, end_state=None):
    def cat(key, dtype):
        """The chunk's events of one kind (one drain, the usual case: its copy as it is)."""
        got = parts[key]
        return got[0] if len(got) == 1 else np.concatenate(got) if got else np.empty(0, dtype)

    imp_step = cat("imp_step", np.int64)
    imp_off = cat("imp_off", np.float64)
    imp_u = cat("imp_u", np.float64)
    if model.n_walls == 2:
        # the kernel writes the lab-frame velocity: < 0 at the wall below the mass
        imp_wall = (imp_u < 0.0).astype(np.int8)
        imp_u = np.abs(imp_u)
    else:
        imp_wall = np.zeros(imp_u.size, np.int8)
    stk_time = cat("stk_step", np.int64) * dt + cat("stk_off", np.float64)
    stk_kind = cat("stk_kind", np.float64)
    starts, ends, walls = _pair_sticking(stk_time, stk_kind, stick_open)
    stuck = mode in (kernels.STUCK, kernels.STUCK_LO)
    stuck_since = stick_open[0] if stick_open[0] is not None else math.nan
    if final and stick_open[0] is not None:
        # still resting on the wall at the record's end
        starts = np.append(starts, np.float64(stick_open[0]))
        ends = np.append(ends, np.float64(t_chunk))
        walls = np.append(walls, np.int8(stick_open[1]))
        stick_open[0] = None
    n = int(buf.grid_n[0])
    grid = np.empty(0)
    if stride:      # the times of the samples recorded, built if read (SimulationResult.grid)
        grid = (((k0 + stride - 1) // stride) * stride, stride, n, dt)
    grid_a, grid_v = buf.take_grid(n)
    return SimulationResult(
        impact_time=imp_step * dt + imp_off,
        impact_velocity=imp_u,
        impact_step=imp_step,
        impact_offset=imp_off,
        stick_start=starts,
        stick_end=ends,
        grid=grid,
        a=grid_a,
        v=grid_v,
        n_steps=k1 - k0 + (1 if t_chunk > k1 * dt else 0),
        n_impacts=len(imp_step),
        n_chatter=parts["n_chatter"],
        contact_time=float(buf.ftot[kernels.FT_CONTACT_TIME]),
        t_end=t_chunk,
        x_end=float(x),
        v_end=float(v),
        stuck_end=bool(stuck),
        stuck_since=float(stuck_since),
        params=params,
        force_record=noise,
        impact_wall=imp_wall,
        stick_wall=walls,
        model=model,
        end_state=end_state,
    )


def simulate(zeta, eps, delta, noise=None, dt=0.1, amplitude=0.0, beta=1.0, x0=None, v0=0.0,
             t_end=None, *, record_every=0, chunk_size=2**20,
             rebound_floor=DEFAULT_REBOUND_FLOOR, gap=None, eps_lower=None, start=None,
             speed_scale=math.inf, speed_scale_lower=None):
    """Exact motion of the impact oscillator under a sampled random force plus a harmonic force.

    Parameters
    ----------
    zeta : float
        Damping ratio, ``0 < zeta < 1`` (paper eq. 2).
    eps : float
        Restitution coefficient, ``0 <= eps <= 1`` (eq. 7).
    delta : float
        Dimensionless play: the wall stands at ``x = delta``; negative values pre-load it.
    noise : array_like of float, shape (N,), or None
        ``noise[k]`` is the random force at ``tau = k * dt``; the force between samples is the
        straight line between them. Any sliceable 1-D array (an ``np.memmap`` or a netCDF
        variable works: it is read chunk by chunk). ``None``: no random force.
    dt : float
        Sample step of ``noise``; with ``noise=None`` the step of the internal grid and of
        the recorded ``a(tau)``.
    amplitude, beta : float
        Harmonic force ``amplitude * sin(beta * tau)``, treated exactly; ``beta > 0``.
    x0, v0 : float
        State at ``tau = 0``. ``x0=None`` starts at rest in the static position
        ``min(0, delta)``: pressed on the wall when the play is negative.
    t_end : float, optional
        Final time; default ``(len(noise) - 1) * dt``; required when ``noise`` is None.
    record_every : int, keyword-only
        Record ``a(tau) = delta - x(tau)`` every ``record_every`` samples (0: do not record).
    chunk_size : int, keyword-only
        Samples per chunk streamed through the kernel.
    rebound_floor : float, keyword-only
        Velocity floor (``>= 1e-4``: the kernel resolves every faster rebound) of
        ``collision_rebounds``: rebounds leaving the wall slower are not counted (default
        0.01, :data:`vibroimpact.stats.DEFAULT_REBOUND_FLOOR`).
    gap : float, keyword-only
        A second wall at ``x = delta - gap`` (``gap > 0``), hit from above: the mass then
        moves in the clearance ``delta - gap <= x <= delta`` (docs/model.md, "A clearance
        between two walls"). ``None`` (the default): the paper's one wall.
    eps_lower : float, keyword-only
        Restitution coefficient of the second wall, ``0 <= eps_lower <= 1`` (default ``eps``).
    speed_scale, speed_scale_lower : float, keyword-only
        The impact law of the wall at ``delta`` (and of the second wall, default
        ``speed_scale``): the restitution falls with the approach speed ``u`` as
        ``eps(u) = eps / (1 + u / speed_scale)`` (`vibroimpact.model.Restitution`;
        docs/model.md, "Impact laws"). ``inf`` (the default) is Newton's law, the paper's
        eq. 7: ``eps`` at every speed.
    start : SampleState, keyword-only
        Start from this exact state at sample ``start.k`` (time ``start.k * dt``, the harmonic
        force at its phase there) instead of ``x0, v0`` at ``tau = 0``: a previous run's
        ``end_state`` (the run then continues bit for bit as if never stopped, given the same
        force samples), or :func:`sample_state` (for instance resting on the wall).
        ``noise[0]`` is then the force at sample ``start.k``, and ``t_end`` (absolute time,
        ``> start.k * dt``) defaults to ``(start.k + len(noise) - 1) * dt``. Event times,
        steps and the recorded grid keep absolute sample indices. None (the default): start
        at ``tau = 0``.

    Returns
    -------
    SimulationResult

    Raises
    ------
    ValueError
        For non-finite or out-of-range input, naming the argument.

    Notes
    -----
    Between samples and impacts the motion is the closed-form solution (docs/model.md, section 5;
    the paper's eqs. 3-6); each impact is the smallest root of ``x - delta`` in its step, found
    by a rigorous exclusion bound and refined to round-off, so grazing double crossings
    inside a step are caught. A chatter sequence is followed impact by impact until its
    remaining geometric tail is summed in closed form to within ``CHATTER_TIME_TOL``
    (see :mod:`vibroimpact.impact.kernels`); the mass then sticks until ``f(tau) - delta`` turns
    negative (the release instant is an exact root). The ``collision_*`` fields group the
    impacts into collisions, the unit of every impact statistic: their values do not depend
    on where the kernel stops resolving a chatter sequence.

    Examples
    --------
    The paper's oscillator under the harmonic force alone, 1/beta_f = 1.1, the wall at the
    rest position (delta = 0): it settles on the (1/1) motion, one impact a forcing period.

    >>> from vibroimpact import simulate
    >>> res = simulate(0.05, 0.5, 0.0, amplitude=1.0, beta=1 / 1.1, t_end=300.0)
    >>> res.n_collisions
    86
    >>> round(float(res.collision_velocity[-1]), 4)       # the approach speed it settles to
    0.7781
    >>> bool(res.x_end <= 0.0)                           # never beyond the wall
    True

    Under a random force, from its samples (a record of `vibroimpact.noise`):

    >>> from vibroimpact.noise import NoiseSpec, generate_array
    >>> r = generate_array(NoiseSpec("white", rms=0.5, dt=0.1), 10001, seed=3)
    >>> simulate(0.05, 0.5, 1.0, r, 0.1).n_collisions
    2
    """
    chunks = list(simulate_chunks(zeta, eps, delta, noise=noise, dt=dt, amplitude=amplitude,
                                  beta=beta, x0=x0, v0=v0, t_end=t_end,
                                  record_every=record_every, chunk_size=chunk_size,
                                  rebound_floor=rebound_floor, gap=gap, eps_lower=eps_lower,
                                  start=start, speed_scale=speed_scale,
                                  speed_scale_lower=speed_scale_lower))
    return concatenate_results(chunks)


def simulate_model(model, noise=None, dt=0.1, x0=None, v0=0.0, t_end=None, *, record_every=0,
                   chunk_size=2**20, rebound_floor=DEFAULT_REBOUND_FLOOR, start=None):
    """:func:`simulate` of a :class:`vibroimpact.model.Model` (its walls placed exactly where
    the model puts them); the other arguments as for :func:`simulate`."""
    return concatenate_results(list(simulate_model_chunks(
        model, noise, dt, x0, v0, t_end, record_every=record_every, chunk_size=chunk_size,
        rebound_floor=rebound_floor, start=start)))


def simulate_model_chunks(model, noise=None, dt=0.1, x0=None, v0=0.0, t_end=None, *,
                          record_every=0, chunk_size=2**20, rebound_floor=DEFAULT_REBOUND_FLOOR,
                          start=None):
    """:func:`simulate_chunks` of a :class:`vibroimpact.model.Model`: the generator of chunks
    (``send(n)`` included) the pipeline's cells consume; the other arguments as for
    :func:`simulate`."""
    if not isinstance(model, Model):
        raise ValueError(f"model must be a vibroimpact.model.Model, got {type(model).__name__}")
    run = _check_run(model, noise, dt, x0, v0, t_end, record_every, chunk_size, start)
    rebound_floor = _checks.real("rebound_floor", rebound_floor, low=MIN_REBOUND_FLOOR)
    yield from _simulate_model(model, noise, *run, rebound_floor)


def concatenate_results(chunks):
    """Join consecutive chunk results into one :class:`SimulationResult`."""
    last = chunks[-1]
    cat = lambda name: np.concatenate([getattr(c, name) for c in chunks])
    return SimulationResult(
        impact_time=cat("impact_time"), impact_velocity=cat("impact_velocity"),
        impact_step=cat("impact_step"), impact_offset=cat("impact_offset"),
        stick_start=cat("stick_start"), stick_end=cat("stick_end"),
        grid=cat("grid_time"), a=cat("a"), v=cat("v"),
        n_steps=sum(c.n_steps for c in chunks), n_impacts=sum(c.n_impacts for c in chunks),
        n_chatter=sum(c.n_chatter for c in chunks),
        contact_time=float(sum(c.contact_time for c in chunks)),
        t_end=last.t_end, x_end=last.x_end, v_end=last.v_end, stuck_end=last.stuck_end,
        stuck_since=last.stuck_since, params=last.params, force_record=last.force_record,
        impact_wall=cat("impact_wall"), stick_wall=cat("stick_wall"), model=last.model,
        end_state=last.end_state,
    )
