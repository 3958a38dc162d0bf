"""The residence of a periodic impact motion under noise, by splitting on the exact simulator.

The oscillator with its wall and its harmonic force, ``x'' + 2 zeta x' + x = A sin(beta_f tau)
+ r(tau)``, ``x <= delta``, restitution ``eps`` (docs/model.md), stepped sample by sample by
:class:`~vibroimpact.rare.paths.Dynamics` (the harmonic phase is the sample index ``k`` of the
kernel's :class:`~vibroimpact.impact.simulate.SampleState`; impacts go on as in
:func:`vibroimpact.simulate`, they do not end a path).

The sets are read at *stroboscopic samples*, one per forcing period ``T = 2 pi / beta_f``: the
first sample at or after ``phi + j T`` (``phi`` the strobe phase, a time in ``[0, T)``), where
``j`` is any integer: ``k_j = ceil((phi + j T) / dt)``. There the state is compared with the
noiseless motion's own state at the same instant ``k_j dt`` (:class:`PeriodicMotion`: so the
strobe's jitter of up to one sample against the phase costs nothing), in the energy metric of
the unit-frequency oscillator,

    d = sqrt((x - x_p(k dt))^2 + (x' - x_p'(k dt))^2)

(minimised over the ``n`` shifts by whole periods of an ``(m/n)`` motion with ``n > 1``):

- A, "in the motion": ``d < radius_a`` at a strobe;
- B, "escaped": ``d >= radius_b`` at a strobe.

Both are functions of the state at a sample (its ``x, x'`` and its index), so the chain of
states at the samples is Markov with them and :func:`~vibroimpact.rare.ams.ams` stays unbiased
(Brehier et al. 2016). The brute-force residence of the workflow
(:func:`vibroimpact.pipeline.cells.escape_cell`) is defined otherwise: by the classifier of
the impact intervals (a stretch of collisions whose intervals lie within ``w`` forcing periods
of ``n / m``). The two are not the same quantity; :func:`brute_force_residence` measures the
one defined here by direct simulation, so that the splitting is checked like with like, and
the comparison with the classifier's values is a separate statement about ``radius_b``.

Measured (the (1/1) cell 1/beta_f = 1.1, delta = 1, zeta = 0.05, eps = 0.5, A = 1; the
band-limited force beta_c = 4, dt = 0.1; ``radius_a = 0.25``, ``radius_b = 0.9``; forcing
periods): brute force with these A and B gives 16.0 +- 0.35 (rms 0.29), 108 +- 4 (0.22) and
1094 +- 51 (0.18, 35e6 steps); the classifier's residence of the escape dataset is 22.4, 97
and 491 there: the two definitions differ by up to a factor 2 and do not scale alike with
the noise. Splitting with :class:`PredictedDeviation` gives 16.3 +- 0.6, 110 +- 6 and
1033 +- 234; with :class:`StrobeDistance` 17.2 +- 1.1, 114 +- 9 and 2033 +- 471 (the last 2
standard errors off: heavy-tailed). Why the coordinates at the strobes weaken as the noise
falls: the probability of reaching B before A from a strobe barely depends on its distance
(0.02 - 0.08 from ``d = 0.25`` to ``0.9`` at rms 0.22, brute force): the strobe map contracts
by ``|lambda| = 0.35`` a period and the escape is made by the noise inside the last period;
a clone branched at a strobe then seldom rises above its branch value, ties with its
siblings and dies with them (at rms 0.15, 6 of 20 runs extinct, the runs' ``p`` spread over
nine decades). :class:`Forecast`, read between the strobes, gives 103 +- 10 (0.22) and
1278 +- 386 (0.18), at about five times the steps a run; at rms 0.15, beyond brute force,
28200 +- 4900 (30 runs of 100 clones, 7.2e7 steps; the runs' ``p`` within 3.5 decades, none
extinct; the fit ``ln T`` linear in ``1 / rms^2`` through the three brute-force levels
extrapolates to ~24000), the cost brute force would need for the same interval (~35
residences of ~2e6 steps): no gain yet. At rms 0.12 it degrades too (7e7 +- 4e7 from 10
runs, 3 extinct, 4e7 steps).

:class:`ForecastMargin` is the coordinate for weak noise: the forecast's margin to B in units
of the noise the rest of the period can still add, so that readings at different phases
compare. With 100 clones and 10 runs (``python benchmarks/rare_motions.py ams RMS
--coordinate margin``), no run extinct at any level:

- 17.1 +- 0.6 (rms 0.29, the slow test's) and 114 +- 20 (0.22, 1.7e7 steps), against brute
  force's 16.0 +- 0.35 and 108 +- 4;
- 33300 +- 4300 (0.15, 2.4e7 steps, the runs' ``p`` within 0.7 decades), where brute force
  spends ~2.3e6 steps a residence, so ~1.4e8 for the same 13 % (59 residences);
- 5.6e6 +- 1.9e6 (0.12, 2.8e7 steps, the runs' ``p`` within 1.4 decades);
- 2.5e9 +- 1.8e9 (0.10, 3.0e7 steps): a relative error of 72 % from 10 runs, for one
  residence that brute force would need ~1.7e11 steps to see once.

From rms 0.15 to 0.10 the cost grows by 30 % while the residence grows by five decades.
``ln T`` against ``1 / rms^2`` has the slope 0.205 from rms 0.15 to 0.12 and 0.200 from 0.12
to 0.10 (0.25 from 0.18, brute force, to 0.15).

The other escape cells, with :class:`PredictedDeviation` (100 clones, 10 runs) against brute
force, ``radius_a = 0.25`` (forcing periods): the (2/1) motion at 1/beta_f = 1.1, delta =
0.1 (``radius_b = 0.9``) 54.0 +- 3.9 against 47.2 +- 5.5 (rms 0.29) and 234 +- 47 against
196 +- 14 (0.25); the (1/2) motion at 1/beta_f = 1.2, delta = 2.5 (``radius_b = 1.2``: its
deviations under noise are larger, and with 0.9 it lasts 9 periods at rms 0.29) 90 +- 8
against 82 +- 5 (0.25) and 213 +- 30 against 223 +- 21 (0.22). At these levels brute force
is the cheaper of the two (the (2/1) at rms 0.22: brute force 908 +- 170 from 1.4e6 steps,
splitting 553 +- 300 from 2.1e6). Lower down, with :class:`ForecastMargin` (``python
benchmarks/rare_motions.py ams RMS --motion M --coordinate margin``): the (1/2) motion
4.96e7 +- 2.2e7 at rms 0.10 (5.2e7 steps, no run extinct); the (2/1) motion at rms 0.13 lost
6 of 10 runs (1.4e10 +- 1.3e10 from 2.1e7 steps, not an estimate to use): for it the margin
is not yet the coordinate.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vibroimpact import _checks
from vibroimpact import noise as _noise
from vibroimpact.impact.simulate import initial_vector
from vibroimpact.rare.ams import _rng, ams, starting_exits
from vibroimpact.rare.paths import CHUNK, REACHED, RETURNED, Dynamics


class PeriodicMotion:
    """The noiseless periodic motion of the oscillator with its wall, as a function of time.

    Simulated by the exact simulator without random force from ``(x0, v0)`` at ``tau = 0``
    for ``settle`` forcing periods, then tabulated over the ``n`` periods of the motion at
    ``per_period`` points a period (a step dividing the period, so the table's phase is
    exact); between table points linear interpolation (error ~ ``(T / per_period)^2 / 8``
    times the acceleration: ~1e-6 for the default).

    Parameters
    ----------
    zeta, eps, delta, beta_f, amplitude : float
        The oscillator: damping ratio ``0 < zeta < 1``, restitution ``0 <= eps <= 1``, wall
        position ``delta`` (dimensionless displacement), forcing frequency ``beta_f > 0``
        (units of the natural frequency) and amplitude.
    motion : (int, int), optional
        ``(m, n)``: m impacts per n forcing periods, the motion expected.
    x0, v0 : float, optional
        The noiseless start at ``tau = 0`` (``x0 <= delta``); the default, rest at the
        origin, is the start of :func:`~vibroimpact.pipeline.cells.escape_cell`.
    settle : int, optional
        Forcing periods simulated before the table, ``>= 1``.
    per_period : int, optional
        Table points per forcing period, ``>= 16``.
    tol : float, optional
        The state after the ``n`` tabulated periods must return within ``tol`` (energy
        metric) of the first, ``> 0``.

    Attributes
    ----------
    period : float
        ``T = 2 pi / beta_f`` (dimensionless time).
    x, v : ndarray of float64, shape (n per_period + 1,)
        ``x_p, x_p'`` at ``tau = settle T + i n T / (n per_period)``: the motion at the time
        ``t`` is the table at ``t mod nT``.
    impacts : int
        Impacts in the tabulated ``n`` periods (``m`` checked).

    Raises
    ------
    ValueError
        If the settled motion is not periodic with ``n`` periods within ``tol`` or has not
        ``m`` impacts in them (another attractor from this start: change ``x0, v0``).
    """

    def __init__(self, zeta, eps, delta, beta_f, amplitude, motion=(1, 1), *, x0=0.0, v0=0.0,
                 settle=400, per_period=2000, tol=1e-6):
        m, n = (_checks.integer("motion[0]", motion[0], low=1),
                _checks.integer("motion[1]", motion[1], low=1))
        beta_f = _checks.real("beta_f", beta_f, low=0.0, low_open=True)
        settle = _checks.integer("settle", settle, low=1)
        per_period = _checks.integer("per_period", per_period, low=16)
        tol = _checks.real("tol", tol, low=0.0, low_open=True)
        self.motion, self.zeta, self.eps, self.delta = (m, n), zeta, eps, delta
        self.beta_f, self.amplitude = beta_f, amplitude
        self.period = 2.0 * math.pi / beta_f
        h = self.period / per_period
        dyn = Dynamics(zeta, _noise.NoiseSpec("white", 0.0, h), delta, _never, _never, eps=eps,
                       amplitude=amplitude, beta=beta_f)
        vec = initial_vector(dyn.model, h, _checks.real("x0", x0, high=delta),
                              _checks.real("v0", v0), 0, False)
        n_tab = n * per_period
        k0 = settle * per_period
        xs, vs = [], []
        k, first = 0, None
        while k < k0 + n_tab + 1:
            record = k + CHUNK > k0
            dyn._steps(np.zeros(CHUNK + 1), k, vec, record=record)
            if record:
                first = k if first is None else first
                got = int(dyn._grid_n[0])
                if got != CHUNK:
                    raise RuntimeError(f"the simulator recorded {got} of {CHUNK} samples")
                xs.append(delta - dyn._grid[:got])
                vs.append(dyn._grid_v[:got].copy())
            k += CHUNK
        x, v = np.concatenate(xs)[k0 - first:], np.concatenate(vs)[k0 - first:]
        self.x, self.v = x[:n_tab + 1].copy(), v[:n_tab + 1].copy()
        self.t0 = k0 * h
        self.h = h
        miss = math.hypot(self.x[-1] - self.x[0], self.v[-1] - self.v[0])
        if not miss <= tol:
            raise ValueError(f"the noiseless motion from x0={x0!r}, v0={v0!r} after settle="
                             f"{settle} periods does not repeat after n={n} periods: it "
                             f"misses by {miss:.3g} > tol={tol!r}")
        # an impact: the velocity turns from > 0 to < 0 between table points by a jump
        # (0.1: ~30 times what the smooth motion's acceleration gives in one table step)
        turn = (self.v[:-1] > 0.0) & (self.v[1:] < 0.0) & (self.v[:-1] - self.v[1:] > 0.1)
        self.impacts = int(np.count_nonzero(turn))
        if self.impacts != m:
            raise ValueError(f"the settled motion has {self.impacts} impacts in n={n} "
                             f"periods, not m={m}: not the ({m}/{n}) motion")

    def at(self, t, shift=0):
        """``x_p, x_p'`` at the times ``t`` (array), shifted by ``shift`` forcing periods."""
        n_tab = self.x.size - 1
        u = np.mod((np.asarray(t, dtype=float) - self.t0 + shift * self.period)
                   / self.h, n_tab)
        i = np.minimum(np.floor(u).astype(np.int64), n_tab - 1)
        f = u - i
        return ((1.0 - f) * self.x[i] + f * self.x[i + 1],
                (1.0 - f) * self.v[i] + f * self.v[i + 1])

    def far_phase(self):
        """The strobe phase (time in ``[0, T)``) where the motion is farthest from the wall
        (its smallest ``x`` over the first period): away from the impacts."""
        per = (self.x.size - 1) // self.motion[1]
        i = int(np.argmin(self.x[:per]))
        return float(np.mod(self.t0 + i * self.h, self.period))


def _never(x, v):
    return np.zeros(np.shape(x), dtype=bool)


@dataclass(frozen=True)
class StrobeDistance:
    """``xi = sqrt((dx / s_x)^2 + (dv / s_v)^2)``: the distance from the motion at a strobe,
    with its own scales (the default 1, 1 is the energy metric that defines A and B).

    Parameters
    ----------
    s_x, s_v : float, optional
        Scales of the displacement and velocity deviations, ``> 0``.
    """

    s_x: float = 1.0
    s_v: float = 1.0

    def __post_init__(self):
        _checks.real("s_x", self.s_x, low=0.0, low_open=True)
        _checks.real("s_v", self.s_v, low=0.0, low_open=True)

    def __call__(self, dx, dv):
        return np.hypot(np.asarray(dx, dtype=float) / self.s_x,
                        np.asarray(dv, dtype=float) / self.s_v)


class PredictedDeviation:
    """The deviation from the motion at a strobe with the random force's predictable part:
    :class:`~vibroimpact.rare.coordinates.Predicted` (unit scales) applied to ``(dx, dv)``.

    ``xi = exp(zeta H) |Phi_H (dx, dv) + (response over H to the force samples the filter's
    memory fixes)|``, ``Phi_H`` the wall-free linear flow: in the linear theory of the
    deviation (the harmonic force cancels in it) the force the memory already fixes is
    counted now, so clones branched at a strobe part at once (the reason for ``Predicted``
    in the wall-free problem). The wall is ignored in the prediction: it is a coordinate,
    and the estimate does not rely on it. Build it through ``MotionDynamics(...,
    coordinate="predicted")``, which gives it the paths' own filter.

    Parameters
    ----------
    zeta : float
        Damping ratio, ``0 < zeta < 1``.
    force : ForceFilter
        The paths' filter (``band_limited`` or ``white``).
    horizon : float, optional
        ``H`` (dimensionless time, ``> 0``).
    """

    def __init__(self, zeta, force, horizon=10.0):
        from vibroimpact.rare.coordinates import Predicted

        self.predicted = Predicted(zeta, force, 1.0, 1.0, horizon)

    def along_path(self, dx, dv, r, memory, e):
        """The coordinate at every sample (``dx, dv`` the deviations there, arguments as
        :meth:`~vibroimpact.rare.coordinates.Predicted.predict`)."""
        return self.predicted.along_path(dx, dv, r, memory, e)


@dataclass(frozen=True)
class Forecast:
    """The distance B tests at the next strobe, as the path's forecast without new noise: from
    the exact state at a sample, the exact simulator runs to the next strobe with the force
    its filter's memory already fixes (every later innovation zero), and ``xi`` is the
    energy-metric distance from the motion there. Read every ``every`` samples (``k = 0 mod
    every``) and at the strobes; costs up to one forcing period of steps a reading (counted
    in ``n_steps``).

    Why: the probability of reaching B before A from a strobe barely depends on the distance
    there (module docstring): the escape is made inside the last period, which a coordinate
    read at the strobes does not see; and read at every sample, the deviation from the motion
    jumps at the impacts. The forecast is nonlinear through the impacts and, with the force's
    predictable part, moves with each new innovation (as
    :class:`~vibroimpact.rare.coordinates.Predicted` does for the wall-free problem).

    Parameters
    ----------
    every : int, optional
        Samples between readings, ``>= 1``.
    """

    every: int = 8

    def __post_init__(self):
        _checks.integer("every", self.every, low=1)

    def __call__(self, dx, dv):
        raise TypeError("Forecast reads the path's exact state: MotionDynamics evaluates it")


@dataclass(frozen=True)
class ForecastMargin(Forecast):
    """The :class:`Forecast`'s margin to B in units of the noise the rest of the period can
    still add: ``xi = (d_f - radius_b) / sqrt(c(m))``, ``d_f`` the forecast distance at the
    next strobe, ``m`` the samples left to it and ``c(m)`` the energy-metric variance that the
    innovations of those ``m`` samples give the wall-free deviation (:func:`forecast_spread`).

    Why: a forecast short of B by 0.1 a period before the strobe is far likelier to reach it
    than the same forecast one sample before, where no noise is left to close the gap; ranked
    by the forecast alone the second outranks the first, clones branch where they cannot rise,
    tie with their siblings and die with them (the runs' ``p`` of :class:`Forecast` spread
    over 3.5 decades at rms 0.15). In the weak-noise, linear picture ``-xi^2 / 2`` is the log
    of the probability of closing the gap before the strobe, so the readings of different
    phases compare. The wall is ignored in ``c`` (it is a coordinate: the estimate does not
    rely on it). Read as :class:`Forecast` is (``every``), at the same cost.
    """

    def __call__(self, dx, dv):
        raise TypeError("ForecastMargin reads the path's exact state: MotionDynamics "
                        "evaluates it")


def forecast_spread(force, zeta, n):
    """``c(m)``, ``m = 0 .. n``: the energy-metric variance ``E[y_m^2 + y_m'^2]`` of the
    wall-free oscillator ``y'' + 2 zeta y' + y = r`` started at rest with the force that the
    innovations ``e_1 .. e_m`` after a sample add (the filter's memory zero; the force linear
    between samples, as the simulator steps it).

    By linearity ``y_m = sum_j g_{m-j} e_j`` with ``g_l`` the response at ``l`` samples to one
    innovation, so ``c(m) = sum_{l=1..m} |g_l|^2``; ``g`` is the exact response of the
    state-space oscillator to the filter's impulse response under first-order hold
    (``scipy.signal.lsim``).

    Parameters
    ----------
    force : ForceFilter
        The paths' filter (its taps carry the rms).
    zeta : float
        Damping ratio.
    n : int
        Largest ``m``, ``>= 1``.

    Returns
    -------
    ndarray of float64, shape (n + 1,)
    """
    import scipy.signal

    from vibroimpact.rare.forcing import ForceState

    n = _checks.integer("n", n, low=1)
    e = np.zeros(n)
    e[0] = 1.0
    r, _ = force.advance(ForceState(0.0, np.zeros(force.n_memory)), e)
    dt = force.spec.dt
    system = scipy.signal.StateSpace([[0.0, 1.0], [-1.0, -2.0 * zeta]], [[0.0], [1.0]],
                                     np.eye(2), np.zeros((2, 1)))
    _, _, g = scipy.signal.lsim(system, r, np.arange(n + 1) * dt, interp=True)
    return np.concatenate([[0.0], np.cumsum(np.sum(g[1:] ** 2, axis=1))])


class MotionDynamics(Dynamics):
    """Paths of the oscillator with its wall and harmonic force; A is the motion, B its escape.

    Parameters
    ----------
    zeta : float
        Damping ratio, ``0 < zeta < 1``.
    eps : float
        Restitution of the wall, ``0 <= eps <= 1``.
    delta : float
        Wall position (dimensionless displacement).
    beta_f : float
        Forcing frequency (units of the natural frequency), ``> 0``.
    amplitude : float
        Harmonic force ``amplitude sin(beta_f tau)``.
    noise : NoiseSpec
        The random force (its ``dt`` is the sample step).
    motion : (int, int) or PeriodicMotion, optional
        The ``(m/n)`` motion (computed by :class:`PeriodicMotion` from rest), or the motion
        itself (its parameters must be these).
    radius_a, radius_b : float
        A: ``d < radius_a`` at a strobe; B: ``d >= radius_b`` at a strobe; ``0 < radius_a <
        radius_b`` (energy metric, dimensionless; module docstring).
    coordinate : callable or str, optional
        Reaction coordinate ``xi(dx, dv)`` of the deviations from the motion at the strobes
        (arrays in, array out); default :class:`StrobeDistance` ``()``, ``d`` itself;
        ``"predicted"``: :class:`PredictedDeviation` on this force. It is ``-inf`` at the
        other samples: clones branch at strobes only. ``"forecast"`` (or a
        :class:`Forecast`): the noiseless forecast of the next strobe's distance, read between
        the strobes too; ``"margin"`` (or a :class:`ForecastMargin`): that forecast's margin
        to B in units of the noise left before the strobe (the coordinate for weak noise).
    strobe_phase : float, optional
        ``phi``, a time in ``[0, T)``; default the motion's farthest point from the wall
        (:meth:`PeriodicMotion.far_phase`).
    phase : {"minimum", "linear"}, optional
        The FIR of a band-limited force (:class:`~vibroimpact.rare.forcing.ForceFilter`).
    """

    def __init__(self, zeta, eps, delta, beta_f, amplitude, noise, motion=(1, 1), *,
                 radius_a, radius_b, coordinate=None, strobe_phase=None, phase="minimum"):
        super().__init__(zeta, noise, delta, _never, _never, eps=eps, amplitude=amplitude,
                         beta=beta_f, phase=phase)
        if not isinstance(motion, PeriodicMotion):
            motion = PeriodicMotion(zeta, eps, delta, beta_f, amplitude, motion)
        elif (motion.zeta, motion.eps, motion.delta, motion.beta_f, motion.amplitude) != (
                zeta, eps, delta, beta_f, amplitude):
            raise ValueError("motion must be computed with this zeta, eps, delta, beta_f and "
                             "amplitude")
        self.orbit = motion
        self.period = motion.period
        self.radius_a = _checks.real("radius_a", radius_a, low=0.0, low_open=True)
        self.radius_b = _checks.real("radius_b", radius_b, low=self.radius_a, low_open=True)
        if coordinate is None:
            coordinate = StrobeDistance()
        elif isinstance(coordinate, str) and coordinate == "predicted":
            coordinate = PredictedDeviation(zeta, self.filter)
        elif isinstance(coordinate, str) and coordinate == "forecast":
            coordinate = Forecast()
        elif isinstance(coordinate, str) and coordinate == "margin":
            coordinate = ForecastMargin()
        elif not callable(coordinate):
            raise ValueError(f"coordinate must be a callable of (dx, dv) arrays, 'predicted', "
                             f"'forecast' or 'margin', got {coordinate!r}")
        self.coordinate = coordinate
        # ForecastMargin's c(m), up to the samples of a period and the strobe's jitter
        self._spread = (forecast_spread(self.filter, zeta,
                                        int(math.ceil(self.period / self.dt)) + 2)
                        if isinstance(coordinate, ForecastMargin) else None)
        phi = motion.far_phase() if strobe_phase is None else strobe_phase
        self.strobe_phase = _checks.real("strobe_phase", phi, low=0.0, high=self.period)
        self.start_set = self._in_a

    # -- the strobes and the sets ---------------------------------------------------------
    def strobes(self, k0, k1):
        """The stroboscopic samples ``k_j = ceil((phi + j T) / dt)`` in ``[k0, k1]`` (int64)."""
        t_p, dt = self.period, self.dt
        j0 = math.floor((k0 * dt - self.strobe_phase) / t_p) - 1
        j1 = math.ceil((k1 * dt - self.strobe_phase) / t_p) + 1
        kj = np.ceil((self.strobe_phase + np.arange(j0, j1 + 1) * t_p) / dt).astype(np.int64)
        return kj[(kj >= k0) & (kj <= k1)]

    def deviation(self, x, v, k):
        """``dx, dv`` from the motion at the samples ``k`` (the closest of its ``n`` shifts in
        the energy metric)."""
        t = np.asarray(k, dtype=float) * self.dt
        best = None
        for s in range(self.orbit.motion[1]):
            xp, vp = self.orbit.at(t, s)
            dx, dv = np.asarray(x) - xp, np.asarray(v) - vp
            if best is None:
                best = (dx, dv)
            else:
                closer = np.hypot(dx, dv) < np.hypot(*best)
                best = (np.where(closer, dx, best[0]), np.where(closer, dv, best[1]))
        return best

    def distance(self, x, v, k):
        """``d``, the energy-metric distance from the motion at the samples ``k``."""
        return np.hypot(*self.deviation(x, v, k))

    def _in_a(self, x, v, k=None):
        raise TypeError("A is read at the strobes: use MotionDynamics.strobe_sets")

    def strobe_sets(self, path):
        """The strobes of ``path`` (indices into its samples) and whether each is in A, in B."""
        k0 = path.start.sample.k
        i = self.strobes(k0, k0 + path.x.size - 1) - k0
        d = self.distance(path.x[i], path.v[i], k0 + i)
        return i, d < self.radius_a, d >= self.radius_b

    def _stop(self, k, first, x, v, t_hit, step_hit):
        """A return to A or a hit of B at a strobe of the chunk (the start may be in B, not a
        return); impacts do not stop a path."""
        i = self.strobes(k, k + x.size - 1) - k
        if i.size == 0:
            return None, None, math.nan
        d = self.distance(x[i], v[i], k + i)
        in_a = d < self.radius_a
        if first:
            in_a &= i > 0
        hit = np.flatnonzero(in_a | (d >= self.radius_b))
        if hit.size == 0:
            return None, None, math.nan
        j = int(i[hit[0]])
        return j, REACHED if d[hit[0]] >= self.radius_b else RETURNED, (k + j) * self.dt

    def _coordinate_along(self, path):
        k0 = path.start.sample.k
        xi = np.full(path.x.size, -math.inf)
        if isinstance(self.coordinate, Forecast):
            return self._forecast_along(path, xi)
        i = self.strobes(k0, k0 + path.x.size - 1) - k0
        dx, dv = self.deviation(path.x[i], path.v[i], k0 + i)
        if isinstance(self.coordinate, PredictedDeviation):
            full_x, full_v = np.zeros(path.x.size), np.zeros(path.x.size)
            full_x[i], full_v[i] = dx, dv
            xi[i] = self.coordinate.along_path(full_x, full_v, path.r, path.start.force.memory,
                                               path.e)[i]
        else:
            xi[i] = np.asarray(self.coordinate(dx, dv), dtype=float)
        return xi

    def _forecast_along(self, path, xi):
        """:class:`Forecast` at the path's samples ``k = 0 mod every`` and its strobes."""
        k0, n = path.start.sample.k, path.x.size
        every = self.coordinate.every
        ks = np.union1d(self.strobes(k0, k0 + n - 1),
                        np.arange(-(-k0 // every) * every, k0 + n, every))
        ks = ks[ks < k0 + n]
        if path.end == RETURNED:
            ks = ks[ks < k0 + n - 1]                # the return itself is -inf anyway
        for k in ks:
            state = self.state_at(path, int(k - k0))
            k_next = int(self.strobes(int(k) + 1, int(k) + int(self.period / self.dt) + 2)[0])
            vec = state.sample.vector()
            r, _ = self.filter.advance(state.force, np.zeros(k_next - int(k)))
            self._steps(r, int(k), vec, record=False)
            self.n_steps += k_next - int(k)
            x, v = self.state_xv(vec, k_next)
            d = float(self.distance(np.array([x]), np.array([v]), np.array([k_next]))[0])
            if self._spread is not None:
                spread = self._spread[k_next - int(k)]
                d = ((d - self.radius_b) / math.sqrt(spread) if spread > 0.0
                     else (-math.inf if d < self.radius_b else math.inf))
            xi[k - k0] = d
        return xi

    def on_motion(self, rng, period=0):
        """A start on the noiseless motion at the first strobe of forcing period ``period``
        (``>= 0``), the random force in a draw of its stationary state."""
        lo = int(math.ceil(_checks.integer("period", period, low=0) * self.period / self.dt))
        k = int(self.strobes(lo, lo + int(math.ceil(self.period / self.dt)) + 1)[0])
        xp, vp = self.orbit.at(np.array([k * self.dt]))
        return self.initial(rng, float(xp[0]), float(vp[0]), k=k)


@dataclass(frozen=True)
class Residence:
    """Mean residence time in a motion (from an entry into A to B), in forcing periods.

    Attributes
    ----------
    time, time_se : float
        The mean residence and its standard error (forcing periods).
    probability, probability_se : float
        ``p``: P(reach B before A from an exit of A), its mean over the runs and standard
        error.
    sojourn : float
        Mean time in A from an entry to the next exit (forcing periods).
    cycle : float
        Mean time between exits of A (forcing periods).
    success : float
        Mean duration of an excursion that reaches B (forcing periods).
    runs : tuple of SplittingRun
    n_steps : int
        Sample steps simulated in all (control runs and re-simulations included).
    """

    time: float
    time_se: float
    probability: float
    probability_se: float
    sojourn: float
    cycle: float
    success: float
    runs: tuple
    n_steps: int


def residence_time(dynamics, *, n_clones, n_runs, seed, burn_in=20.0, spacing=5.0, k=1):
    """Mean residence time in the motion by splitting and renewal (forcing periods).

    Parameters
    ----------
    dynamics : MotionDynamics
    n_clones : int
        Paths per splitting run, ``>= 2``.
    n_runs : int
        Independent runs ``>= 2``, each with its control run.
    seed : int or numpy.random.SeedSequence
        Root of the seed tree (:mod:`vibroimpact.rare.ams`).
    burn_in : float, optional
        Forcing periods of each control run, from the noiseless motion's point, before its
        exits are used (``>= 0``): the transient of the start.
    spacing : float, optional
        Mean forcing periods between two exits taken as starts, ``> 0``.
    k : int, optional
        Killed per iteration at least.

    Returns
    -------
    Residence

    Notes
    -----
    The renewal decomposition of :func:`~vibroimpact.rare.ams.first_passage`, from an entry
    into A instead of a fixed initial state: after an entry the path stays in A (the
    sojourn), leaves it, and either returns to A (a failed cycle, exit to exit) or reaches B,

        T = E[sojourn] + E[cycle] (1 - p) / p + E[successful excursion],

    ``p`` by :func:`~vibroimpact.rare.ams.ams` from the control run's exits (every ``s``-th
    after the burn-in, as ``first_passage``), the sojourn by the control run and the cycle by
    its cycles whose excursion returned to A before B (``E[cycle | fail]``: where brute force
    still reaches, ``p`` is not small, and the unconditioned mean of ``first_passage`` was
    measured 20 % high at ``p ~ 0.3``). The approximations left: consecutive exits are close
    to independent, and the sojourn after an entry from B is taken to be that after a failed
    excursion.
    """
    if not isinstance(dynamics, MotionDynamics):
        raise ValueError(f"dynamics must be a MotionDynamics, got {type(dynamics).__name__}")
    n_clones = _checks.integer("n_clones", n_clones, low=2)
    n_runs = _checks.integer("n_runs", n_runs, low=2)
    burn_in = _checks.real("burn_in", burn_in, low=0.0)
    spacing = _checks.real("spacing", spacing, low=0.0, low_open=True)
    t_p, dt = dynamics.period, dynamics.dt
    burn, gap = int(math.ceil(burn_in * t_p / dt)), max(1, int(math.ceil(spacing * t_p / dt)))
    steps0 = dynamics.n_steps
    runs, p, cycle, sojourn, succ = [], [], [], [], []
    for r in range(n_runs):
        rng = _rng(seed, r, 0)
        start = dynamics.on_motion(rng)
        control = dynamics.run(start, rng, stop=False, max_steps=burn + 2 * (n_clones + 1) * gap)
        i, in_a, in_b = dynamics.strobe_sets(control)
        exits = i[1:][in_a[:-1] & ~in_a[1:]]
        entries = i[1:][~in_a[:-1] & in_a[1:]]
        used, _, picks = starting_exits(exits, burn, gap, n_clones, control.x.size - 1,
                                        "radius_a")
        # sojourns: each entry after the burn-in to the next exit
        ent = entries[entries >= burn]
        nxt = np.searchsorted(exits, ent)
        ok = nxt < exits.size
        sojourn.append(float(np.mean(exits[nxt[ok]] - ent[ok])) * dt / t_p if ok.any()
                       else math.nan)
        cycle.append(_failed_cycle(i, in_a, in_b, used) * dt / t_p)
        starts = [dynamics.state_at(control, int(j)) for j in picks[:n_clones]]
        run = ams(dynamics, starts, seed, run=r, k=k)
        runs.append(run)
        p.append(run.probability)
        succ.extend(run.durations / t_p)
    p, cycle = np.array(p), np.array(cycle)
    p_mean, p_se = float(p.mean()), float(p.std(ddof=1) / math.sqrt(n_runs))
    c_mean, c_se = float(cycle.mean()), float(cycle.std(ddof=1) / math.sqrt(n_runs))
    s_mean = float(np.nanmean(sojourn))
    success = float(np.mean(succ)) if succ else math.nan
    if p_mean > 0.0:
        time = s_mean + c_mean * (1.0 - p_mean) / p_mean + success
        time_se = math.hypot(c_mean / p_mean**2 * p_se, (1.0 - p_mean) / p_mean * c_se)
    else:
        time, time_se = math.inf, math.nan
    return Residence(time=time, time_se=time_se, probability=p_mean, probability_se=p_se,
                     sojourn=s_mean, cycle=c_mean, success=success, runs=tuple(runs),
                     n_steps=dynamics.n_steps - steps0)


def _failed_cycle(i, in_a, in_b, exits):
    """Mean samples from an exit of A to the next, over the exits whose excursion returns to
    A before B (strobes ``i`` with their sets): ``E[cycle | fail]``."""
    pos = np.searchsorted(i, exits)
    gaps = []
    for a, b in zip(pos[:-1], pos[1:]):
        seg_a, seg_b = np.flatnonzero(in_a[a:b]), np.flatnonzero(in_b[a:b])
        if seg_a.size and (seg_b.size == 0 or seg_a[0] < seg_b[0]):
            gaps.append(i[b] - i[a])
    if not gaps:
        raise RuntimeError("no excursion of the control run returned to A before B: "
                           "check radius_a, radius_b")
    return float(np.mean(gaps))


def brute_force_residence(dynamics, *, n_periods, seed, burn_in=20.0):
    """Residence times in the motion with the same A and B, by one long direct simulation.

    From the noiseless motion's point, ``burn_in`` forcing periods discarded, then each
    residence is the time from an entry into A (the first strobe in A after the start or
    after a hit of B) to the next strobe in B.

    Parameters
    ----------
    dynamics : MotionDynamics
    n_periods : float
        Forcing periods simulated after the burn-in, ``> 0``.
    seed : int
        Seed of the run.
    burn_in : float, optional
        Forcing periods discarded, ``>= 0``.

    Returns
    -------
    times : ndarray of float64
        The complete residences (forcing periods).
    n_steps : int
        Sample steps simulated.
    """
    n_periods = _checks.real("n_periods", n_periods, low=0.0, low_open=True)
    burn_in = _checks.real("burn_in", burn_in, low=0.0)
    t_p, dt = dynamics.period, dynamics.dt
    rng = _rng(seed, 0)
    steps0 = dynamics.n_steps
    path = dynamics.run(dynamics.on_motion(rng), rng, stop=False,
                        max_steps=int(math.ceil((burn_in + n_periods) * t_p / dt)))
    i, in_a, in_b = dynamics.strobe_sets(path)
    keep = i >= int(math.ceil(burn_in * t_p / dt))
    return _residences(i[keep], in_a[keep], in_b[keep]) * dt / t_p, dynamics.n_steps - steps0


def _residences(i, in_a, in_b):
    """Sample counts from each entry into A (after the start or a B) to the next B."""
    out, entry = [], None
    for j, a, b in zip(i, in_a, in_b):
        if entry is None:
            if a:
                entry = j
        elif b:
            out.append(j - entry)
            entry = None
    return np.array(out, dtype=float)


__all__ = ["PeriodicMotion", "StrobeDistance", "PredictedDeviation", "Forecast",
           "ForecastMargin", "forecast_spread", "MotionDynamics",
           "Residence", "residence_time", "brute_force_residence",
           "RETURNED", "REACHED"]
