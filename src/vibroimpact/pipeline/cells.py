"""Statistics of one parameter cell, computed while the simulation streams.

Each function takes the cell's resolved :class:`vibroimpact.model.Model` (the oscillator, its
walls and their impact laws, its harmonic force; `study_model` builds it from a study), runs
the simulator over a force record and reduces what the figures need on the fly: impact events
for densities and means (no a(tau) recorded), Welch spectra of a(tau) accumulated segment by
segment (no long series kept), or a short sampled trace. Inputs are arrays or sliceable
records; outputs are dicts of numpy values.
"""
import logging
import math
from typing import NamedTuple

import numpy as np

from vibroimpact import stats
from vibroimpact.impact.audit import audit_moments
from vibroimpact.impact.hops import pressed_flights
from vibroimpact.impact.simulate import simulate_model_chunks, split_steps
from vibroimpact.model import Model
from vibroimpact.pipeline.study import escape_samples, map_cap_steps

log = logging.getLogger("vibroimpact")

#: Relative slack when comparing ``t_end`` with the record's length, so that a ``t_end``
#: written as ``(n - 1) * dt`` in decimal is not refused for its last bit.
RECORD_END_RTOL = 1e-12


def _record_end(noise, dt, t_end):
    """End of the simulated stretch: ``t_end``, or the whole record when it is None.

    Raises
    ------
    ValueError
        If ``t_end`` lies beyond the last sample of the record (no silent truncation).
    """
    full = (len(noise) - 1) * dt
    if t_end is None:
        return full
    t_end = float(t_end)
    if t_end > full * (1.0 + RECORD_END_RTOL):
        raise ValueError(f"t_end = {t_end!r} is longer than the noise record: {len(noise)} "
                         f"samples at dt = {dt!r} end at tau = {full!r}")
    return min(t_end, full)


def _lag1_check(name, result, cell):
    """Warn when the batch means of `name` are correlated (batches too short for the error)."""
    if result is None or result.n_batches < 2 or not np.isfinite(result.lag1):
        return
    limit = 2.0 / math.sqrt(result.n_batches)
    if result.lag1 > limit:
        log.warning("%s: lag-1 correlation of the batch means of %s is %.3g > 2/sqrt(B) = %.3g "
                    "(B = %d): the batches are too short and its standard errors too small",
                    cell, name, result.lag1, limit, result.n_batches)


#: The walls of a two-wall dataset, in the order of its ``wall`` dimension (the simulator's
#: ``impact_wall``: 0 the wall at delta, 1 the wall at delta - gap).
WALLS = ("upper", "lower")


def study_model(study, cell):
    """The resolved :class:`vibroimpact.model.Model` of one cell of ``study``
    (`pipeline.study.Study`): its oscillator and walls at the cell's play, forced by
    ``amplitude sin(tau / inv_beta)``; a cell of a study's ``plane`` with the plane's two
    parameters at the cell's values (`Study.parameters`; the rms is the record's, not the
    model's: `pipeline.tasks.map_tile` scales the record). Here, beside the simulator, not
    on `Study`: reading a config or drawing a figure loads no kernel (the import contracts,
    pyproject.toml)."""
    if study.plane is None:
        return Model.paper(study.zeta, study.eps, cell.delta, study.amplitude,
                           1.0 / cell.inv_beta, **study.walls())
    p = study.parameters(cell)      # a plane's cell: the fixed values with its axes in
    walls = {} if study.gap is None else dict(gap=p["gap"], eps_lower=p["eps_lower"])
    return Model.paper(p["zeta"], p["eps"], p["delta"], p["amplitude"], 1.0 / p["inv_beta"],
                       **walls, **study.laws())


def cell_model(params):
    """The `Model` of a cell given as the config spells it: ``{zeta, eps, delta, amplitude,
    inv_beta}`` with, optionally, ``gap, eps_lower, speed_scale, speed_scale_lower`` (an
    escape cell, a plane study's trace: `pipeline.tasks.escape_cells`)."""
    p = dict(params)
    return Model.paper(p.pop("zeta"), p.pop("eps"), p.pop("delta"), p.pop("amplitude", 0.0),
                       1.0 / p.pop("inv_beta"), **p)


def _model(model):
    """``model`` itself, once it is a `Model`: the cells take the cell's resolved model
    (`study_model`, `cell_model`, or `Model.paper` of its parameters)."""
    if not isinstance(model, Model):
        raise ValueError(f"model must be a vibroimpact.model.Model (e.g. Model.paper(zeta, "
                         f"eps, delta, amplitude, beta_f)), got {type(model).__name__}")
    return model


def _loose(model):
    """The model as the keywords of `audit_moments` (``beta_f`` its forcing frequency)."""
    params = model.params()
    params["beta_f"] = params.pop("beta")
    return params


def _v_after(model, col):
    """Speed after each collision's first impact: its wall's law at its approach speed
    (Newton's law: ``eps_w u``, to the bit)."""
    return model.restitution(col.velocity, col.wall) * col.velocity


def event_statistics(noise, dt, model, *, transient=0.0, t_end=None, bins,
                     n_batches=stats.DEFAULT_N_BATCHES, motion_window=stats.DEFAULT_MOTION_WINDOW,
                     motions=stats.DEFAULT_MOTIONS, rebound_floor=stats.DEFAULT_REBOUND_FLOOR,
                     chunk_size=2**20):
    """Collision statistics of one cell (Figs. 7-9, 13, 14).

    Every statistic counts collisions (:mod:`vibroimpact.stats.collisions`): an impact after
    a free flight with the chatter and sticking it starts. The velocity after impact is that
    of a collision's first rebound, the interval runs from one collision's first impact to
    the next's; none depends on a tolerance of the simulator.

    Parameters
    ----------
    noise : array_like, shape (N,)
        Random force samples at spacing ``dt``.
    model : vibroimpact.model.Model
        The oscillator, its wall at ``delta`` (and a second wall at ``delta - gap``), their
        impact laws and the harmonic force ``amplitude sin(beta tau)`` (``beta``: the
        frequency ratio beta_f; unused when ``amplitude == 0``). Every statistic of a
        rebound (the velocity after impact, the rebound counts, the self-audit's impact
        sums) takes it from the wall's law.
    transient : float
        Time discarded before statistics (collisions that begin before it are dropped).
    t_end : float, optional
        End of the record used (default: the whole noise record); longer than the record
        raises ValueError.
    bins : dict
        ``{"v_after": edges, "interval": edges, "ratio": edges}`` histogram bin edges
        (``"ratio"`` only read for a harmonic force).
    n_batches : int
        Batches B of the batch-means standard errors of the means and the densities.
    motion_window : float
        Half-width w of the impact-motion classification (docs/figures.md, fig15).
    motions : sequence of (m, n)
        Motions whose probabilities are reported (harmonic force only).
    rebound_floor : float
        Velocity floor of the rebound counts (``rebounds_mean``, the per-rebound view).

    Returns
    -------
    dict
        Scalars ``n_collisions, collision_rate, simulated_time, n_batches, v_after_mean,
        v_after_stderr, v_after_mean_lo, v_after_mean_hi, v_after_lag1, interval_mean,
        interval_stderr, interval_mean_lo, interval_mean_hi, count_dispersion, interval_lag1,
        contact_fraction, stuck_fraction, stick_time_mean, rebounds_mean, n_rebounds,
        rebound_v_after_mean, v_after_beyond, interval_beyond``, the self-audit
        ``power_residual(_stderr), power_input, virial_residual(_stderr), virial_scale``
        (:func:`vibroimpact.stats.identity_residuals`, over the samples from
        ``ceil(transient / dt)`` to ``floor(t_end / dt)``) and arrays
        ``v_after_density(_stderr), interval_density(_stderr)`` (on the bins). With a
        harmonic force (``amplitude != 0``) also ``ratio_density(_stderr)``, ``ratio_beyond``,
        ``motion_probability`` (one value per motion of ``motions``, with free flights) and
        ``motion_stick_probability`` (their impact-stick variants, whose collisions stick);
        without one there is no forcing period, so these are absent. The per-rebound view
        (``n_rebounds``, ``rebound_v_after_mean``) counts every rebound leaving the wall at speed
        ``>= rebound_floor``. The weight of the grouping rule: ``rule_n_events,
        rule_collision_rate, rule_v_after_mean, rule_interval_mean`` (one value per rule of
        `stats.RULES`: physical, impacts-only, per rebound) and, with a harmonic force,
        ``rule_motion_probability, rule_motion_stick_probability`` (rules x motions); the
        physical row equals the statistics above.

        With two walls the statistics above are over the collisions at either wall
        (a velocity after impact is ``eps_w u`` with its wall's restitution), the motions
        are classified with the collisions' walls (two-wall motions ``(m_upper, m_lower,
        n)``, `stats.motions`), the per-wall statistics of `stats.wall_statistics` are added
        (arrays over `WALLS`) and the self-audit has a term per wall.

    Notes
    -----
    The mean interval is ``T / N`` (record length after the transient over the collisions in
    it), the reciprocal of the rate (`stats.event_rate`): the mean of the N - 1 gaps between
    the first and the last collision would leave the two end gaps out and be biased low where
    collisions are few. Its interval (``interval_mean_lo``, ``interval_mean_hi``) is Garwood's
    for the count, widened where the counts in B equal stretches of time are overdispersed
    (``count_dispersion`` > 1: collisions in bursts). The mean velocity after impact and its
    interval are batched in time too (`stats.mark_mean`), so a burst stays in one batch and a
    few collisions give a wide interval. The lag-1 correlations are those of batch means of
    equal numbers of values (`stats.batch_means`), a check of the sequences' memory.
    Density errors are batch-means standard errors per bin (`stats.density` with
    ``n_batches``). A lag-1 correlation of the batch means above ``2/sqrt(B)`` is logged as
    a warning on the ``vibroimpact`` logger: the batches are then too short for an honest
    error.
    """
    model = _model(model)
    t_end = _record_end(noise, dt, t_end)
    if not 0.0 <= transient < t_end:
        raise ValueError(f"transient must lie in [0, t_end = {t_end!r}), got {transient!r}")
    n_batches = int(n_batches)
    harmonic, beta_f = model.amplitude != 0.0, model.beta
    events = _EventRecord(dt, noise, model)
    audit = _IdentityRecord(noise, dt, transient, t_end, n_batches, model)
    for chunk in simulate_model_chunks(model, noise, dt, t_end=t_end, record_every=1,
                                       chunk_size=chunk_size):
        events.add(chunk)
        audit.add(chunk)
    col = events.collisions(rebound_floor, transient)
    contact = _clipped_contact(*events.sticking()[:2], transient)
    duration = t_end - transient
    two = model.n_walls == 2
    wall = events.collision_walls(col) if two else None
    v_after = _v_after(model, col)
    z = col.intervals
    cell = (f"cell delta={model.delta:g}" + (f", beta_f={beta_f:g}" if harmonic else ""))
    v_stats = stats.batch_means(v_after, n_batches) if v_after.size else None
    z_stats = stats.batch_means(z, n_batches) if z.size else None
    rate = stats.event_rate(col.time, transient, t_end, n_batches)
    v_mean = stats.mark_mean(v_after, col.time, transient, t_end, n_batches)
    _lag1_check("the velocity after impact", v_stats, cell)
    _lag1_check("the interval", z_stats, cell)
    v_dens = stats.density(v_after, bins["v_after"], total=v_after.size, n_batches=n_batches)
    z_dens = stats.density(z, bins["interval"], total=z.size, n_batches=n_batches)
    rebound_v = events.rebound_speeds(rebound_floor, transient)
    nan = math.nan
    motion_walls = {} if not two else dict(walls=wall)
    mean = lambda a: float(a.mean()) if a.size else nan
    out = dict(
        n_collisions=int(v_after.size),
        collision_rate=v_after.size / duration,
        simulated_time=duration,
        n_batches=n_batches,
        v_after_mean=v_mean.mean,
        v_after_stderr=v_mean.stderr,
        v_after_mean_lo=v_mean.lo,
        v_after_mean_hi=v_mean.hi,
        v_after_lag1=v_stats.lag1 if v_stats else nan,
        interval_mean=rate.mean_interval,
        interval_stderr=rate.mean_interval_stderr,
        interval_mean_lo=rate.mean_interval_bounds[0],
        interval_mean_hi=rate.mean_interval_bounds[1],
        count_dispersion=rate.dispersion,
        interval_lag1=z_stats.lag1 if z_stats else nan,
        contact_fraction=contact / duration,
        stuck_fraction=mean(col.stuck.astype(float)),
        stick_time_mean=mean(col.stick_time),
        rebounds_mean=mean(col.rebounds.astype(float)),
        n_rebounds=int(rebound_v.size),
        rebound_v_after_mean=mean(rebound_v),
        v_after_density=v_dens.density, v_after_density_stderr=v_dens.stderr,
        v_after_beyond=v_dens.beyond,
        interval_density=z_dens.density, interval_density_stderr=z_dens.stderr,
        interval_beyond=z_dens.beyond,
    )
    out.update(audit.result())
    if two:
        laws = [w.law for w in model.walls]
        out.update(stats.wall_statistics(col, transient, t_end, eps=laws[0], eps_lower=laws[1],
                                         bins=bins, n_batches=n_batches,
                                         beta_f=beta_f if harmonic else None))
    out.update(_rule_statistics(events, col, floor=rebound_floor, transient=transient,
                                duration=duration, n_batches=n_batches,
                                beta_f=beta_f if harmonic else None,
                                motion_window=motion_window, motions=motions))
    if harmonic:
        ratio_dens = stats.density(stats.interval_ratio(z, beta_f), bins["ratio"], total=z.size,
                                   n_batches=n_batches)
        if two:
            motion_walls["walls"] = wall[:-1]
        motion = list(stats.impact_motion_probabilities(
            z, beta_f, motion_window, total_time=duration, motions=motions,
            stuck=col.stuck[:-1], **motion_walls).values())   # the motions, then stick variants
        out.update(ratio_density=ratio_dens.density, ratio_density_stderr=ratio_dens.stderr,
                   ratio_beyond=ratio_dens.beyond,
                   motion_probability=np.array(motion[:len(motions)]),
                   motion_stick_probability=np.array(motion[len(motions):]))
    return out


def _rule_statistics(events, col, *, floor, transient, duration, n_batches, beta_f,
                     motion_window, motions):
    """The statistics a figure draws under each grouping rule (`stats.RULES`: physical,
    impacts-only, per rebound above ``floor``), stacked along the rules: ``rule_n_events,
    rule_collision_rate, rule_v_after_mean, rule_interval_mean`` and, with a forcing period
    (``beta_f`` not None), ``rule_motion_probability, rule_motion_stick_probability`` (rules
    x motions). The physical row is the cell's own statistics; the others show what the
    choice of rule weighs (the reports' sensitivity table)."""
    rows = []
    for rule in stats.RULES:
        c = col if rule == "physical" else events.collisions(floor, transient, rule=rule)
        z = c.intervals
        walls = {} if not events.walls else dict(walls=events.collision_walls(c)[:-1])
        v_after = _v_after(events.model, c)
        # the same estimators as the cell's own: T/N and the mean of every value
        row = dict(rule_n_events=c.time.size, rule_collision_rate=c.time.size / duration,
                   rule_v_after_mean=stats.mark_mean(
                       v_after, c.time, transient, transient + duration, n_batches).mean,
                   rule_interval_mean=stats.event_rate(
                       c.time, transient, transient + duration, n_batches).mean_interval)
        if beta_f is not None:
            p = list(stats.impact_motion_probabilities(
                z, beta_f, motion_window, total_time=duration, motions=motions,
                stuck=c.stuck[:-1], **walls).values())
            row.update(rule_motion_probability=np.array(p[:len(motions)]),
                       rule_motion_stick_probability=np.array(p[len(motions):]))
        rows.append(row)
    return {name: np.array([row[name] for row in rows]) for name in rows[0]}


class _Joined:
    """One kind of event of an `_EventRecord` (``steps``, ``u``, ...): the list of its
    chunks' arrays, joined into one when read. Joining at every chunk instead copied the
    whole record each time (O(chunks^2): ~10 ms a chunk at 2e6 impacts), which an events
    cell, reading it once at the end, never needed; a map cell reads it at each check."""

    def __set_name__(self, owner, name):
        self.name = "_" + name

    def __get__(self, record, owner=None):
        if record is None:
            return self
        parts = getattr(record, self.name)
        if len(parts) > 1:
            parts[:] = [np.concatenate(parts)]
        return parts


class _EventRecord:
    """The impacts and sticking phases of a streamed record, gathered chunk by chunk.

    Collisions are grouped on the whole record at the end (a chatter sequence may cross a
    chunk boundary). Impacts are kept from the start of the record, so that a collision that
    begins before the transient is grouped as it happened and then dropped. The physical rule
    reads the force (``noise`` and the ``model``'s harmonic force) along each flight; the
    rebounds' speeds are the model's walls' laws. With a second wall the walls of the impacts
    and of the sticking phases are gathered too, and the grouping is per wall
    (`stats.group_collisions` with ``wall``: a collision never spans the two walls, a hop is
    pressed onto the wall it is at).
    """

    steps, offsets, u, starts, ends = _Joined(), _Joined(), _Joined(), _Joined(), _Joined()
    wall, stick_wall = _Joined(), _Joined()

    def __init__(self, dt, noise, model):
        from vibroimpact import tally     # compiled: the jobs that group collisions load it

        self._tally = tally
        self._sticking = None       # `sticking` of the record as it stands
        self.dt = dt
        self.model = model
        self.force = dict(noise=noise, delta=model.delta, amplitude=model.amplitude,
                          beta=model.beta)
        #: whether the model has a second wall
        self.walls = model.n_walls == 2
        self._pressed, self._n_pressed = np.zeros(0, bool), 0   # flights of the first impacts
        self.stuck_since = math.nan
        self.stuck_wall = 0      # the wall of a rest still going on at the last chunk's end
        # each kind's arrays, chunk by chunk (read through the _Joined attributes)
        self._steps, self._offsets, self._u, self._starts, self._ends = [], [], [], [], []
        self._wall, self._stick_wall = [], []
        self.t_end = 0.0

    def add(self, chunk):
        self._steps.append(chunk.impact_step)
        self._offsets.append(chunk.impact_offset)
        self._u.append(chunk.impact_velocity)
        self._starts.append(chunk.stick_start)
        self._ends.append(chunk.stick_end)
        if self.walls:
            self._wall.append(np.asarray(chunk.impact_wall, dtype=np.int8))
            self._stick_wall.append(np.asarray(chunk.stick_wall, dtype=np.int8))
            self.stuck_wall = int(chunk.x_end != self.force["delta"])
        self.t_end = chunk.t_end
        self.stuck_since = chunk.stuck_since
        self._sticking = None

    def collision_walls(self, col):
        """The wall of each collision of ``col`` (int8, 0: at delta, 1: at delta - gap)."""
        return np.asarray(col.wall, dtype=np.int8)

    def sticking(self):
        """Sticking phases so far; one still open ends at the last chunk's end. With two
        walls ``(start, end, wall)``, the open one on the wall the mass rests on (kept until
        the next chunk: the checks and the rules read it several times)."""
        if self._sticking is None:
            self._sticking = (
                stats.close_open_phase(self.starts[0], self.ends[0], self.stuck_since,
                                       self.t_end) if not self.walls else
                stats.close_open_phase(self.starts[0], self.ends[0], self.stuck_since,
                                       self.t_end, stick_wall=self.stick_wall[0],
                                       stuck_wall=self.stuck_wall))
        return self._sticking

    def restitution(self):
        """The restitution of each impact of the record so far, by its wall's law at its
        speed, for the grouping: ``{eps, eps_lower}`` of the walls (floats) under Newton's
        law, ``{eps: one per impact, eps_lower: None}`` otherwise."""
        if self.model.newton:
            return dict(eps=self.model.eps,
                        eps_lower=self.model.eps_lower if self.walls else self.model.eps)
        wall = self.wall[0] if self.walls else None
        return dict(eps=self.model.restitution(self.u[0], wall), eps_lower=None)

    def rebound_speeds(self, floor, transient):
        """Speeds ``eps_w(u) u`` (each rebound by its wall's law) of the rebounds at or
        after ``transient`` that reach ``floor``."""
        t = self.steps[0] * self.dt + self.offsets[0]
        keep = t >= transient
        u = self.u[0][keep]
        v = self.model.restitution(u, self.wall[0][keep] if self.walls else None) * u
        return v[v >= floor]

    def pressed(self):
        """The flights between the record's impacts that the push presses throughout
        (`stats.pressed_flights`, compiled: `vibroimpact.impact.hops`; with two walls, onto
        the wall the flight is at); those of earlier checks are kept, only new ones
        computed."""
        n = self.steps[0].size if self.steps else 0
        if n > self._n_pressed:
            i = max(self._n_pressed - 1, 0)          # from the last impact already seen
            f = self.force
            step, offset = self.steps[0][i:], self.offsets[0][i:]
            t = step * self.dt + offset
            # a flight with a sticking phase is no hop: left out (it would cost its samples)
            free = self._tally.ends_in_sticking(t, self.sticking()[0])[:-1]
            walls = {} if not self.walls else dict(wall=self.wall[0][i:], gap=self.model.gap)
            new = pressed_flights(step, offset, f["noise"], self.dt, delta=f["delta"],
                                  amplitude=f["amplitude"], beta=f["beta"], flights=~free,
                                  **walls)
            self._pressed, self._n_pressed = np.concatenate((self._pressed, new)), n
        return self._pressed

    def collisions(self, floor, transient, rule="physical"):
        """Collisions of the record so far that begin at or after ``transient``, grouped by
        ``rule`` (:data:`vibroimpact.stats.RULES`)."""
        from vibroimpact import tally     # compiled: the jobs that group collisions load it

        pressed = self.pressed() if rule == "physical" else None
        law = self.restitution()
        if not self.walls:
            start, end = self.sticking()
            return tally.group_collisions(self.steps[0], self.offsets[0], self.u[0], start,
                                          end, dt=self.dt, eps=law["eps"], floor=floor,
                                          pressed=pressed, rule=rule, after=transient)
        start, end, wall = self.sticking()
        return tally.group_collisions(self.steps[0], self.offsets[0], self.u[0], start, end,
                                      dt=self.dt, eps=law["eps"], floor=floor, pressed=pressed,
                                      rule=rule, wall=self.wall[0], stick_wall=wall,
                                      eps_lower=law["eps_lower"], after=transient)

    def firsts(self, floor, transient, rule="physical"):
        """`collisions` reduced to what a map cell reads: the `_Firsts` of each collision's
        first impact (the same values as the `Collisions` fields of those names), grouped by
        one compiled call without the per-impact fields or the arguments' checks (the
        simulator's own arrays)."""
        step, offset, u = (self.steps[0], self.offsets[0], self.u[0]) if self.steps else (
            np.zeros(0, np.int64), np.zeros(0), np.zeros(0))
        wall = self.wall[0] if self.walls else np.zeros(step.size, np.int8)
        if step.size == 0:
            return _Firsts(np.zeros(0), step, offset, u, wall, np.zeros(0, bool))
        pressed = self.pressed() if rule == "physical" else np.zeros(0, bool)
        _, *fields = self._tally.collision_firsts(
            step, offset, u, self.sticking()[0], dt=self.dt, **self.restitution(),
            floor=floor, pressed=pressed, rule=rule, wall=wall, after=transient)
        return _Firsts(*fields)

    def rule_probabilities(self, tallied, floor, transient, rules, duration):
        """``[(probability, stick_probability)]`` of the collisions at or after
        ``transient`` of each rule of ``rules`` (not the physical one), as ``tallied``
        (`tally.MotionTally`) gives them for `firsts` of that rule: one compiled call for
        them all (`tally.rule_probabilities`)."""
        wall = self.wall[0] if self.walls else np.zeros(self.steps[0].size, np.int8)
        return self._tally.rule_probabilities(
            tallied, self.steps[0], self.offsets[0], self.u[0], self.sticking()[0], dt=self.dt,
            **self.restitution(), floor=floor, rules=rules, wall=wall, after=transient,
            duration=duration)


class _Firsts(NamedTuple):
    """A record's collisions as a map cell reads them (`_EventRecord.firsts`): of each one's
    first impact its instant, split instant, approach velocity and wall, and whether it
    sticks; the `stats.Collisions` fields of those names."""

    time: np.ndarray
    step: np.ndarray
    offset: np.ndarray
    velocity: np.ndarray
    wall: np.ndarray
    stuck: np.ndarray


class _IdentityRecord:
    """Per-batch integrals of the power balance and the virial, gathered chunk by chunk.

    The window runs over whole force steps, from sample ``ceil(transient / dt)`` to sample
    ``floor(t_end / dt)``, cut into ``n_batches`` contiguous batches of steps. The chunks,
    added in order, are those of one run from sample 0; each brings the state at its
    samples (``record_every=1``) and its impacts and sticking phases;
    :func:`vibroimpact.impact.audit.audit_moments` (the compiled
    :func:`vibroimpact.stats.flight_moments`) integrates its steps exactly. With a second
    wall in the ``model`` the identities have a term per wall (docs/model.md, "Two walls"):
    the impact sums are kept per wall. A law whose restitution varies with the speed puts its
    factors into the impact sums (`stats.identity_residuals`).
    """

    def __init__(self, noise, dt, transient, t_end, n_batches, model):
        self.noise, self.dt, self.model = noise, dt, model
        self.params = _loose(model)         # `audit_moments`' keywords
        self.two = model.n_walls == 2
        self.k_start = int(math.ceil(transient / dt - 1e-9))
        self.k_stop = max(int(math.floor(t_end / dt + 1e-9)), self.k_start)
        self.n_batches = n_batches
        n = self.k_stop - self.k_start
        # the first sample of each batch of _batch, and the window's end
        self.bounds = self.k_start + (np.arange(n_batches + 1) * n + n_batches - 1) // n_batches
        self.steps = np.diff(self.bounds)
        rows = len(stats.moment_rows(True)) if self.two else len(stats.identities.MOMENTS)
        self.moments = np.zeros((rows, n_batches))
        shape = (2, n_batches) if self.two else n_batches
        self.sum_u = np.zeros(shape)
        self.sum_u2 = np.zeros(shape)
        self.k_next = 0     # the first sample of the next chunk

    def _batch(self, k):
        n = self.k_stop - self.k_start
        return ((k - self.k_start) * self.n_batches) // max(n, 1)

    def add(self, chunk):
        # the chunks of one run from sample 0 with every sample recorded (record_every=1):
        # this one's first is the one after the last chunk's (its times, chunk.grid_time, are
        # never built)
        k0 = self.k_next
        self.k_next += chunk.a.size
        lo = max(self.k_start, k0)
        hi = min(self.k_stop, k0 + chunk.a.size)
        if hi > lo:
            keep = slice(lo - k0, hi - k0)
            r = np.asarray(self.noise[lo : hi + 1], dtype=float)
            if not self.two:
                start, end = stats.close_open_phase(chunk.stick_start, chunk.stick_end,
                                                    chunk.stuck_since, chunk.t_end)
                walls = {}
            else:   # a rest open at the chunk's end: on the wall the mass rests on
                start, end, stick_wall = stats.close_open_phase(
                    chunk.stick_start, chunk.stick_end, chunk.stuck_since, chunk.t_end,
                    stick_wall=chunk.stick_wall,
                    stuck_wall=int(chunk.x_end != self.model.delta))
                walls = dict(impact_wall=chunk.impact_wall, stick_wall=stick_wall)
            self.moments += audit_moments(
                lo, chunk.a[keep], chunk.v[keep], r, self.dt,
                **self.params, impact_time=chunk.impact_time,
                impact_velocity=chunk.impact_velocity, stick_start=start, stick_end=end,
                batch_bounds=self.bounds, **walls)
        step = chunk.impact_step
        hit = (step >= self.k_start) & (step < self.k_stop)
        u, b = chunk.impact_velocity[hit], self._batch(step[hit])
        u2 = u * u
        if not self.model.newton:
            e = self.model.restitution(u, np.asarray(chunk.impact_wall)[hit] if self.two
                                       else None)
            u, u2 = (1.0 + e) * u, (1.0 - e * e) * u2
        if not self.two:
            self.sum_u += np.bincount(b, weights=u, minlength=self.n_batches)
            self.sum_u2 += np.bincount(b, weights=u2, minlength=self.n_batches)
            return
        wall = np.asarray(chunk.impact_wall)[hit]
        for w in (0, 1):
            at = wall == w
            self.sum_u[w] += np.bincount(b[at], weights=u[at], minlength=self.n_batches)
            self.sum_u2[w] += np.bincount(b[at], weights=u2[at], minlength=self.n_batches)

    def result(self):
        """The residuals and their errors, as ``event_statistics`` keys (NaN: no batches)."""
        m = self.model
        if self.n_batches < 2 or np.any(self.steps == 0):
            nan = math.nan
            return dict(power_residual=nan, power_residual_stderr=nan, power_input=nan,
                        virial_residual=nan, virial_residual_stderr=nan, virial_scale=nan)
        eps, eps_lower = m.eps, m.eps_lower
        if not m.newton:       # the sums carry the laws' factors
            eps, eps_lower = 0.0, 0.0 if self.two else None
        walls = {} if not self.two else dict(gap=m.gap, eps_lower=eps_lower)
        res = stats.identity_residuals(self.moments, self.sum_u, self.sum_u2,
                                       self.steps * self.dt, zeta=m.zeta, eps=eps,
                                       delta=m.delta, **walls)
        return dict(power_residual=res.power, power_residual_stderr=res.power_stderr,
                    power_input=res.power_input, virial_residual=res.virial,
                    virial_residual_stderr=res.virial_stderr, virial_scale=res.virial_scale)


def _clipped_contact(start, end, transient):
    """Time resting on the wall after ``transient``."""
    return float(np.sum(np.clip(end, transient, None) - np.clip(start, transient, None)))


def spectra_statistics(noise, dt, model, *, transient=0.0, t_end=None, nperseg=4096,
                       chunk_size=2**20, n_batches=None):
    """Welch PSDs of a(tau) and of the random input r(tau) for one cell (Figs. 6, 11, 12).

    a(tau) is recorded at every sample and fed segment by segment to a
    :class:`vibroimpact.stats.WelchAccumulator`; nothing longer than a chunk is kept.

    Returns
    -------
    dict
        ``beta`` (>= 0), ``S_a`` and ``S_f`` (paper's two-sided angular convention, eq. 9),
        ``n_segments``; with ``n_batches``, also ``S_a_batch`` (n_batches, beta): the
        estimate of a(tau) over each of ``n_batches`` consecutive stretches of the record
        (fewer when the record holds fewer Welch segments: one each)
        (`WelchAccumulator`'s ``batches``; their spread is the estimate's sampling error).
        ``S_f`` is the random part r(tau) of the input only: the harmonic
        part ``amplitude sin(beta_f tau)`` is a spectral line of power ``amplitude**2 / 2``,
        which a Welch estimate would smear over its window's main lobe (Fig. 11 draws it as
        the line it is). ``model`` as in `event_statistics`; a(tau) is measured from the
        wall at delta whatever the walls.
    """
    model = _model(model)
    t_end = _record_end(noise, dt, t_end)
    skip = int(math.ceil(transient / dt - 1e-9))
    batches = None
    if n_batches is not None:
        # the samples fed: the grid's k = skip .. n_steps (a(tau) at every step from 0)
        n_samples = split_steps(t_end, dt)[0] + 1 - skip
        step = nperseg - nperseg // 2
        n_segments = max((n_samples - nperseg) // step + 1, 0)
        if n_segments:      # none: `result` says so; a batch holds at least one segment
            batches = (min(int(n_batches), n_segments), n_segments)
    acc_a = stats.WelchAccumulator(dt, nperseg, batches=batches)
    acc_f = stats.WelchAccumulator(dt, nperseg)
    for chunk in simulate_model_chunks(model, noise, dt, t_end=t_end, record_every=1,
                                       chunk_size=chunk_size):
        k = np.rint(chunk.grid_time / dt).astype(np.int64)
        keep = k >= skip
        if not keep.any():
            continue
        k = k[keep]
        acc_a.feed(chunk.a[keep])
        acc_f.feed(np.asarray(noise[k[0] : k[-1] + 1], dtype=float))
    beta, S_a = acc_a.result()
    _, S_f = acc_f.result()
    out = dict(beta=beta, S_a=S_a, S_f=S_f, n_segments=acc_a.n_segments)
    if batches is not None:
        out["S_a_batch"] = acc_a.result_batches()
    return out


def trace(noise, dt, model, *, t_end):
    """A short sampled record from rest (Figs. 3 and 10) of ``model`` (`event_statistics`):
    force, a(tau), impacts and the collision of each impact; with a second wall also the wall
    of each impact (``impact_wall``).

    ``t_end`` longer than the noise record raises ValueError.
    """
    model = _model(model)
    t_end = _record_end(noise, dt, t_end)
    res = next(iter(simulate_model_chunks(model, noise, dt, t_end=t_end, record_every=1,
                                          chunk_size=int(math.ceil(t_end / dt)) + 1)))
    k = np.rint(res.grid_time / dt).astype(np.int64)
    r = np.asarray(noise[k[0] : k[-1] + 1], dtype=float)
    f = r + model.amplitude * np.sin(model.beta * res.grid_time)
    out = dict(tau=res.grid_time, r=r, f=f, a=res.a, x=model.delta - res.a,
               impact_time=res.impact_time, impact_velocity=res.impact_velocity,
               impact_collision=res.impact_collision)
    if model.n_walls == 2:
        out["impact_wall"] = np.asarray(res.impact_wall, dtype=np.int8)
    return out


def motion_map_cell(noise, dt, model, *, transient, motions=stats.DEFAULT_MOTIONS,
                    window=stats.DEFAULT_MOTION_WINDOW, n_batches=stats.DEFAULT_N_BATCHES,
                    target_stderr=0.01, min_time=2000.0, max_periods=8000, min_switches=10,
                    approach=0.8, approach_unswitched=1.1, min_growth=1.1):
    """Probabilities of the (m/n) motions of one cell of the Fig. 15 map, to a target precision.

    The cell is simulated from rest over the common record ``noise`` (every cell of a map
    reads the same one). After ``transient``, the record is extended until every
    probability's batch-means standard error is at most ``target_stderr`` and the record
    either stayed in one motion or switched at least ``min_switches`` times between motions,
    or until ``max_periods`` forcing periods (the cap).

    Parameters
    ----------
    noise : array_like, shape (N,)
        Random force samples at spacing ``dt``; long enough for ``transient`` plus the cap.
    model : vibroimpact.model.Model
        The cell's oscillator, walls and laws (`event_statistics`); the force is
        ``amplitude sin(beta_f tau) + r(tau)`` with ``beta_f = model.beta``. With a second
        wall the collisions' walls classify the two-wall motions ``(m_upper, m_lower, n)`` of
        ``motions``, and ``wall_n_collisions, wall_collision_rate, wall_v_after_mean`` (over
        `WALLS`) are added.
    transient : float
        Time discarded before statistics.
    motions, window, n_batches
        Motions classified, half-width w and batches B (`stats.motion_statistics`).
    target_stderr : float
        Standard error every probability must reach (a fraction: 0.01 is 1 percentage point).
    min_time : float
        Shortest record after the transient, so that a few quiet forcing periods cannot
        pass for a precise zero.
    max_periods : int
        Cap on the record after the transient, in forcing periods ``2 pi / beta_f``.
    min_switches : int
        Switches between motions that make a mixed record trustworthy.
    approach, approach_unswitched, min_growth : float
        The schedule of the checks. A check short of the target predicts the length where
        the worst error reaches it (the error falls as 1/sqrt(time)); the next check comes
        at ``approach`` times that length (``approach_unswitched`` times while the record
        has not switched between motions), but at least ``min_growth`` times the current
        one. With ``approach < 1`` a switching record approaches its stopping length from
        below and stops at the first check that meets the target: the standard error
        estimated from ``n_batches`` batches varies by about 1/sqrt(2 (n_batches - 1)) (16 %
        for 20), so a check aimed at the predicted length itself or beyond it mostly lands
        well below the target, simulating past the precision asked for. A record that has
        not switched is aimed past the prediction: its error says nothing of a motion it
        has not visited yet, and stopping it early turned rare episodes of a second motion
        into zero probabilities. `benchmarks/bench_map_stop.py` measures the schedules on
        a built map.

    Returns
    -------
    dict
        ``probability, stderr`` (per motion, on the intervals between collisions, motions
        with free flights), ``stick_probability, stick_stderr`` (their impact-stick
        variants: a collision of the group ends sticking),
        ``rule_probability, rule_stick_probability`` (rules of `stats.RULES` x motions: the
        probabilities under each grouping rule on the record as it stopped; the physical row
        is ``probability, stick_probability``),
        ``n_switches, n_collisions, collision_rate, v_after_mean`` (of collisions),
        ``n_impacts_resolved`` (every rebound the kernel resolved: a numerical count, for cost
        models only), ``simulated_time, record_end`` (the last simulated instant: simulating
        the cell alone to ``t_end = record_end`` reproduces it bit for bit), ``reached``
        (every stderr at target), ``few_switches`` (1 to ``min_switches - 1`` switches: the
        probabilities say where the record started), ``n_checks``. Over the states (the
        motions, then "none": time in no listed motion, as the probabilities count it):
        ``residence_time, residence_time_stderr`` (mean length of the complete stretches of
        the motion, merged over its free and impact-stick variants, in forcing periods),
        ``n_stretches, n_censored`` (complete stretches, and those cut by the record's ends,
        left out of the mean), ``switch_rate`` (S, S: switches from motion i to j per forcing
        period spent in i, NaN rows for motions never seen) and ``switch_count``; see
        `stats.residence_statistics`. They read the same labelled record as the
        probabilities: no further simulation.

    Raises
    ------
    ValueError
        If the record is shorter than ``transient`` plus the cap.
    """
    from vibroimpact import tally     # compiled: the jobs that group collisions load it

    beta_f = _model(model).beta
    n_cap = map_cap_steps(len(noise), dt, transient, max_periods, beta_f)
    n_next = min(n_cap, int(math.ceil((transient + min_time) / dt - 1e-9)))
    two = model.n_walls == 2
    gen = simulate_model_chunks(model, noise, dt, t_end=n_cap * dt, chunk_size=n_next)
    events = _EventRecord(dt, noise, model)
    # the motion statistics of every check and rule, their arguments checked once
    tallied = tally.MotionTally(beta_f, window=window, motions=motions, n_batches=n_batches,
                                walls=two)
    floor = stats.DEFAULT_REBOUND_FLOOR

    k, n_checks, request = 0, 0, None
    try:
        while True:
            chunk = gen.send(request) if request is not None else next(gen)
            events.add(chunk)
            k += chunk.n_steps
            n_checks += 1
            col = events.firsts(floor, transient)
            res = tallied.statistics(col.time, col.step, col.offset, dt, col.stuck, transient,
                                     k * dt, walls=col.wall)
            worst = float(max(res.stderr.max(), res.stick_stderr.max()))
            reached = worst <= target_stderr
            mixed_ok = res.n_switches == 0 or res.n_switches >= min_switches
            if (reached and mixed_ok) or k >= n_cap:
                break
            length = k * dt - transient
            aim = approach if res.n_switches else approach_unswitched
            predicted = length * (worst / target_stderr) ** 2 * aim if not reached else 0.0
            wanted = max(predicted, 2.0 * length if not mixed_ok else 0.0, min_growth * length)
            n_next = min(n_cap, int(math.ceil((transient + wanted) / dt)))
            request = n_next - k
    finally:
        gen.close()
    duration = k * dt - transient
    n_resolved = int(np.count_nonzero(events.steps[0] * dt + events.offsets[0] >= transient))
    stays = _residence(col.time, res.labels, transient, k * dt, len(motions), beta_f)
    by_rule = [(res.probability, res.stick_probability)] + events.rule_probabilities(
        tallied, floor, transient, stats.RULES[1:], duration)
    v_after = _v_after(model, col)
    per_wall = {}
    if two:
        wall = col.wall
        n_w = np.array([np.count_nonzero(wall == w) for w in range(len(WALLS))])
        per_wall = dict(
            wall_n_collisions=n_w, wall_collision_rate=n_w / duration,
            wall_v_after_mean=np.array([float(v_after[wall == w].mean()) if n_w[w]
                                        else math.nan for w in range(len(WALLS))]))
    return dict(probability=res.probability, stderr=res.stderr,
                rule_probability=np.stack([p for p, _ in by_rule]),
                rule_stick_probability=np.stack([q for _, q in by_rule]),
                stick_probability=res.stick_probability, stick_stderr=res.stick_stderr,
                n_switches=res.n_switches,
                n_collisions=int(col.time.size), collision_rate=col.time.size / duration,
                n_impacts_resolved=n_resolved,
                # Newton's law: eps times the mean speed, rounded as it always was
                v_after_mean=(float(model.eps * col.velocity.mean()) if model.newton
                              else float(v_after.mean())) if col.time.size else math.nan,
                simulated_time=duration, record_end=k * dt, reached=bool(reached),
                few_switches=bool(0 < res.n_switches < min_switches), n_checks=n_checks,
                **stays, **per_wall)


def _residence(impact_time, labels, t_start, t_stop, n_motions, beta_f):
    """Residence times and switching rates of a map cell's labelled record, in forcing
    periods (`stats.residence_statistics`; the states are the motions, then "none")."""
    period = 2.0 * math.pi / beta_f
    from vibroimpact import tally     # compiled: the jobs that group collisions load it

    edges, states = stats.label_pieces(impact_time, labels, t_start, t_stop, n_motions)
    r = tally.residence_statistics(edges, states, n_motions + 1)
    complete = np.where(r.n_stretches > 0, r.mean * r.n_stretches, 0.0)
    return dict(residence_time=r.mean / period, residence_time_stderr=r.stderr / period,
                n_stretches=r.n_stretches, n_censored=r.n_censored,
                censored_time=np.maximum(r.time - complete, 0.0) / period,
                switch_rate=r.rate * period, switch_count=r.count)


def escape_cell(noise, dt, model, *, transient, record_length, motions=stats.DEFAULT_MOTIONS,
                window=stats.DEFAULT_MOTION_WINDOW):
    """Residence times of one cell on a record of fixed length (escape against noise level).

    The labelling of `motion_map_cell` (the same collisions, classification and
    `stats.residence_statistics`), on a record whose length is set in advance instead of
    extended to a precision: from rest at tau = 0, ``transient`` discarded, then
    ``record_length`` (rounded up to a whole sample step).

    Parameters
    ----------
    noise : array_like, shape (N,)
        Random force samples at spacing ``dt``; at least
        ``study.escape_samples(transient, record_length, dt)`` of them.
    model : vibroimpact.model.Model
        The cell's oscillator, walls and laws; the force is ``amplitude sin(beta_f tau) +
        r(tau)``, ``beta_f = model.beta``.
    transient, record_length : float
        Time discarded, and the record after it.
    motions, window
        Motions classified and the half-width w, as `motion_map_cell`.

    Returns
    -------
    dict
        Over the states (the motions, then "none"): ``residence_time,
        residence_time_stderr`` (forcing periods), ``n_stretches, n_censored`` as
        `motion_map_cell`'s, ``censored_time`` (forcing periods: the total length of the
        cut stretches, ``stats.censored_bound``), and ``probability`` (fraction of the
        record after the transient: a motion's free and impact-stick variants together,
        "none" the rest);
        ``n_collisions``, ``simulated_time``, ``record_end``.

    Notes
    -----
    `motion_map_cell` with ``min_time = record_length`` and a target it reaches at once
    (``target_stderr = 0.5``, ``min_switches = 1``) stops at the same sample and returns the
    same residence times, bit for bit (``tests/test_escape.py``).
    """
    from vibroimpact import tally     # compiled: the jobs that group collisions load it

    n_end = escape_samples(transient, record_length, dt) - 1
    if n_end > len(noise) - 1:
        raise ValueError(f"record_length = {record_length!r} after the transient "
                         f"{transient!r} needs {n_end + 1} samples at dt = {dt!r}, the record "
                         f"holds {len(noise)}")
    beta_f = _model(model).beta
    events = _EventRecord(dt, noise, model)
    two = model.n_walls == 2
    k = 0
    for chunk in simulate_model_chunks(model, noise, dt, t_end=n_end * dt):
        events.add(chunk)
        k += chunk.n_steps
    col = events.firsts(stats.DEFAULT_REBOUND_FLOOR, transient)
    res = tally.MotionTally(beta_f, window=window, motions=motions, walls=two).statistics(
        col.time, col.step, col.offset, dt, col.stuck, transient, k * dt, walls=col.wall)
    share = res.probability + res.stick_probability
    stays = _residence(col.time, res.labels, transient, k * dt, len(motions), beta_f)
    return dict(probability=np.append(share, max(0.0, 1.0 - float(share.sum()))),
                n_collisions=int(col.time.size), simulated_time=k * dt - transient,
                record_end=k * dt, residence_time=stays["residence_time"],
                residence_time_stderr=stays["residence_time_stderr"],
                n_stretches=stays["n_stretches"], n_censored=stays["n_censored"],
                censored_time=stays["censored_time"])
