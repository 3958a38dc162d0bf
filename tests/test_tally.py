"""The compiled cell statistics (`vibroimpact.tally`) are the numpy references of
`vibroimpact.stats`, bit for bit: the collision grouping under every rule and the motion
statistics, on simulated records (one wall, two walls, with and without sticking) and on
hand-made ones that reach the rules' corners."""
import numpy as np
import pytest

from vibroimpact import simulate, stats, tally
from vibroimpact.impact import hops

DT = 0.1


def _same(a, b):
    """Two results equal to the bit: every field of the same dtype and the same bytes."""
    for name in a._fields:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape, (name, x.dtype, y.dtype)
            assert x.tobytes() == y.tobytes(), name
        else:
            assert type(x) is type(y) and x == y, name


def _records():
    """Simulated records: one wall (chatter and sticking, free flights, 2/1 motions) and a
    clearance, under a harmonic plus a random force."""
    rng = np.random.default_rng(1974)
    noise = 0.4 * rng.standard_normal(40001)
    out = []
    for inv_beta, delta, walls in ((2.5, -0.5, {}), (1.1, 0.0, {}), (1.6, 0.3, {}),
                                   (0.8, -1.0, {}), (1.2, 0.2, dict(gap=0.6, eps_lower=0.7))):
        res = simulate(0.05, 0.5, delta, noise=noise, dt=DT, amplitude=1.0,
                       beta=1.0 / inv_beta, **walls)
        wall = {} if not walls else dict(wall=res.impact_wall, gap=walls["gap"])
        pressed = hops.pressed_flights(res.impact_step, res.impact_offset, noise, DT,
                                       delta=delta, amplitude=1.0, beta=1.0 / inv_beta, **wall)
        out.append((res, pressed, walls, 1.0 / inv_beta))
    return out


RECORDS = None


def records():
    global RECORDS
    if RECORDS is None:
        RECORDS = _records()
    return RECORDS


@pytest.mark.parametrize("rule", stats.RULES)
def test_the_compiled_grouping_is_the_numpy_reference(rule):
    """`tally.group_collisions(..., after=t0)` is `stats.group_collisions(...).after(t0)`."""
    n_checked = 0
    for res, pressed, walls, _ in records():
        kw = dict(dt=DT, eps=0.5, floor=0.01, pressed=pressed, rule=rule)
        if walls:
            kw.update(wall=res.impact_wall, stick_wall=res.stick_wall,
                      eps_lower=walls["eps_lower"])
        args = (res.impact_step, res.impact_offset, res.impact_velocity, res.stick_start,
                res.stick_end)
        for t0 in (None, 0.0, 200.0, 2000.0, 1e9):
            ref = stats.group_collisions(*args, **kw)
            ref = ref if t0 is None else ref.after(t0)
            _same(tally.group_collisions(*args, **kw, after=t0), ref)
        n_checked += int(stats.group_collisions(*args, **kw).stuck.sum() > 0)
    assert n_checked >= 2          # records that stick: the rules' chatter branches ran


def test_the_compiled_grouping_on_hand_made_records():
    """Corners: no impact, one, every rebound below the floor (rule 'rebounds': none), a
    sticking phase before the first impact and one open at the end, equal velocities."""
    rng = np.random.default_rng(7)
    cases = [(np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0)),
             (np.array([1.0]), np.array([0.3]), np.zeros(0), np.zeros(0)),
             (np.array([1.0, 1.5]), np.array([0.001, 0.001]), np.zeros(0), np.zeros(0)),
             (np.array([1.0, 1.2, 1.3, 5.0]), np.array([0.5, 0.5, 0.2, 0.4]),
              np.array([0.5, 1.35]), np.array([0.9, 4.0]))]
    for _ in range(40):
        n = int(rng.integers(2, 300))
        t = np.sort(rng.uniform(0.0, 100.0, n))
        u = rng.choice([0.005, 0.05, 0.3, 1.0], n) * rng.uniform(0.5, 1.5, n)
        s = np.sort(rng.uniform(-1.0, 101.0, int(rng.integers(0, 40))))
        e = np.minimum(s + rng.uniform(0.0, 0.5, s.size), np.append(s[1:], np.inf))
        cases.append((t, u, s, e))
    for t, u, s, e in cases:
        step = np.floor(t / DT).astype(np.int64)
        pressed = rng.random(max(t.size - 1, 0)) < 0.7
        for rule in stats.RULES:
            kw = dict(dt=DT, eps=0.6, floor=0.01, pressed=pressed, rule=rule)
            args = (step, t - step * DT, u, s, e)
            for t0 in (None, 0.0, 30.0):
                ref = stats.group_collisions(*args, **kw)
                _same(tally.group_collisions(*args, **kw, after=t0),
                      ref if t0 is None else ref.after(t0))


def test_the_compiled_grouping_refuses_what_the_reference_refuses():
    with pytest.raises(ValueError, match="pressed"):
        tally.group_collisions([1], [0.0], [1.0], [], [], dt=DT, eps=0.5)
    with pytest.raises(ValueError, match="rule"):
        tally.group_collisions([1], [0.0], [1.0], [], [], dt=DT, eps=0.5, rule="other")


def _reference_collisions(res, pressed, walls):
    """The numpy reference's collisions of a simulated record after t = 200."""
    kw = dict(dt=DT, eps=0.5, pressed=pressed)
    if walls:
        kw.update(wall=res.impact_wall, stick_wall=res.stick_wall, eps_lower=walls["eps_lower"])
    return stats.group_collisions(res.impact_step, res.impact_offset, res.impact_velocity,
                                  res.stick_start, res.stick_end, **kw).after(200.0)


@pytest.mark.parametrize("motions", [stats.DEFAULT_MOTIONS, ((2, 1), (1, 1), (3, 2), (1, 3))])
def test_the_compiled_motion_statistics_are_the_numpy_reference(motions):
    """`tally.motion_statistics` is `stats.motion_statistics` on each record's collisions,
    with and without the impact-stick refinement, and with the two-wall motions."""
    for res, pressed, walls, beta in records():
        col = _reference_collisions(res, pressed, walls)
        t_stop = res.params["t_end"] if "t_end" in res.params else (40000 * DT)
        for stuck in (None, col.stuck):
            for m, w in ((motions, None), (motions + ((1, 1, 1),), col.wall)):
                if w is None and len(m) > len(motions):
                    continue
                if w is not None and not walls:
                    continue
                a = dict(window=0.1, motions=m, n_batches=20, stuck=stuck, walls=w)
                _same(tally.motion_statistics(col.time, col.intervals, beta, 200.0, t_stop, **a),
                      stats.motion_statistics(col.time, col.intervals, beta, 200.0, t_stop, **a))


def test_the_compiled_labels_on_overlapping_candidates():
    """Runs of short intervals (overlapping (2/1) candidates), near-ties at the window's
    edge, and no interval at all."""
    rng = np.random.default_rng(3)
    beta = 1.0
    period = 2.0 * np.pi / beta
    for _ in range(30):
        n = int(rng.integers(0, 400))
        r = rng.choice([0.5, 0.45, 1.0, 2.0, 0.3, 1.5, 0.9, 1.1], n) + rng.normal(0, 0.04, n)
        z = np.abs(r) * period + 1e-9
        t = 300.0 + np.concatenate([[0.0], np.cumsum(z)])
        stuck = rng.random(n + 1) < 0.2
        for m in (stats.DEFAULT_MOTIONS, ((1, 2), (2, 1), (3, 1), (1, 1))):
            a = dict(window=0.1, motions=m, n_batches=7, stuck=stuck)
            t_stop = t[-1] + 5.0
            _same(tally.motion_statistics(t if n else t[:0], z, beta, 300.0, t_stop, **a),
                  stats.motion_statistics(t if n else t[:0], z, beta, 300.0, t_stop, **a))


def _batch_stderr_as_built(t, z, classes, n_classes, t_start, duration, n_batches):
    """`stats.motions._batch_stderr` as the stored maps were built (15acb54), verbatim: the
    layout of its arrays sets the order of the sums in its standard deviation."""
    onehot = classes[None, :] == np.arange(n_classes)[:, None]
    cover = np.concatenate([np.zeros((n_classes, 1)), np.cumsum(z * onehot, axis=1)], axis=1)
    edges = t_start + duration * np.arange(n_batches + 1) / n_batches
    j = np.clip(np.searchsorted(t, edges, side="right") - 1, 0, t.size - 1)
    inside = (edges > t[0]) & (j < z.size)
    jj = np.minimum(j, z.size - 1)
    extra = np.where(inside[None, :] & onehot[:, jj], np.minimum(edges - t[j], z[jj])[None, :],
                     0.0)
    at_edges = np.where(edges[None, :] > t[0], cover[:, j] + extra, 0.0)
    batches = np.diff(at_edges, axis=1) * (n_batches / duration)
    return batches.std(axis=1, ddof=1) / np.sqrt(n_batches)


def test_the_batch_errors_are_those_the_maps_were_built_with():
    """Both paths' standard errors (the numpy covered times and the compiled ones) equal, to
    the bit, the formula the stored maps were built with, whose sums run in the order of its
    arrays' (Fortran) layout; a C-ordered intermediate changes the last bits."""
    from vibroimpact.stats import motions

    rng = np.random.default_rng(5)
    for n, n_classes, n_batches in ((1, 3, 2), (50, 6, 20), (4000, 6, 20), (900, 4, 33)):
        z = rng.uniform(0.1, 3.0, n)
        t = 10.0 + np.concatenate([[0.0], np.cumsum(z)])
        classes = rng.integers(-1, n_classes, n)
        args = (t, z, classes, n_classes, 9.0, t[-1] + 2.0 - 9.0, n_batches)
        ref = _batch_stderr_as_built(*args)
        assert motions._batch_stderr(*args).tobytes() == ref.tobytes()
        assert motions._batch_stderr(*args, at_edges=tally._at_edges).tobytes() == ref.tobytes()


def test_the_compiled_grouping_at_two_walls_by_hand():
    """Impacts alternating between the walls, every rebound below the floor ('rebounds': no
    event at all, although the walls change) and random walls and restitutions."""
    rng = np.random.default_rng(11)
    cases = [(np.array([1.0, 2.0, 3.0]), np.array([0.001, 0.001, 0.001]),
              np.array([0, 1, 0], np.int8))]
    for _ in range(30):
        n = int(rng.integers(2, 200))
        cases.append((np.sort(rng.uniform(0.0, 50.0, n)), rng.uniform(0.001, 1.0, n),
                      rng.integers(0, 2, n).astype(np.int8)))
    for t, u, wall in cases:
        step = np.floor(t / DT).astype(np.int64)
        pressed = rng.random(t.size - 1) < 0.6
        for rule in stats.RULES:
            kw = dict(dt=DT, eps=0.6, floor=0.01, pressed=pressed, rule=rule, wall=wall,
                      eps_lower=0.3)
            args = (step, t - step * DT, u, [], [])
            for t0 in (None, 10.0):
                ref = stats.group_collisions(*args, **kw)
                _same(tally.group_collisions(*args, **kw, after=t0),
                      ref if t0 is None else ref.after(t0))


def test_the_defaults_are_the_references():
    """The compiled functions' defaults (written out: importing `tally` loads no statistics
    module) are those of the references."""
    assert tally.DEFAULT_REBOUND_FLOOR == stats.DEFAULT_REBOUND_FLOOR
    assert tally.DEFAULT_MOTION_WINDOW == stats.DEFAULT_MOTION_WINDOW
    assert tally.DEFAULT_MOTIONS == tuple(stats.DEFAULT_MOTIONS)


@pytest.mark.parametrize("rule", stats.RULES)
def test_the_collision_firsts_are_the_groupings_fields(rule):
    """`tally.collision_firsts` (what the map's cell groups with) returns the fields of
    `stats.group_collisions(...).after(t0)` it names, to the bit, with one wall and two,
    and on a record whose rebounds all fall below the floor at two walls (rule 'rebounds':
    no event, though the walls change)."""
    names = ("first", "time", "step", "offset", "velocity", "wall", "stuck")
    slow = np.array([0.001, 0.001, 0.001])
    step, wall = np.array([10, 20, 30]), np.array([0, 1, 0], np.int8)
    got = tally.collision_firsts(step, np.zeros(3), slow, np.zeros(0), dt=DT, eps=0.5,
                                 eps_lower=0.5, floor=0.01, pressed=np.ones(2, bool),
                                 rule=rule, wall=wall, after=0.0)
    ref = stats.group_collisions(step, np.zeros(3), slow, [], [], dt=DT, eps=0.5,
                                 pressed=np.ones(2, bool), rule=rule, wall=wall)
    assert [g.tobytes() for g in got] == [getattr(ref, k).tobytes() for k in names]
    for res, pressed, walls, _ in records():
        kw = dict(dt=DT, eps=0.5, floor=0.01, pressed=pressed, rule=rule)
        wall = np.zeros(res.impact_step.size, np.int8)
        eps_lower = 0.5
        if walls:
            kw.update(wall=res.impact_wall, stick_wall=res.stick_wall,
                      eps_lower=walls["eps_lower"])
            wall, eps_lower = res.impact_wall, walls["eps_lower"]
        for t0 in (0.0, 200.0, 1e9):
            ref = stats.group_collisions(res.impact_step, res.impact_offset,
                                         res.impact_velocity, res.stick_start, res.stick_end,
                                         **kw).after(t0)
            got = tally.collision_firsts(
                res.impact_step, res.impact_offset, res.impact_velocity, res.stick_start,
                dt=DT, eps=0.5, eps_lower=eps_lower, floor=0.01,
                pressed=pressed if rule == "physical" else np.zeros(0, bool), rule=rule,
                wall=wall, after=t0)
            for name, value in zip(names, got):
                expected = getattr(ref, name)
                assert value.dtype == expected.dtype, name
                assert value.tobytes() == expected.tobytes(), name


@pytest.mark.parametrize("motions", [stats.DEFAULT_MOTIONS, ((2, 1), (1, 1), (3, 2), (1, 3))])
def test_the_motion_tally_is_the_numpy_reference(motions):
    """`tally.MotionTally` (the map cell's motion statistics, checked once) returns
    `stats.motion_statistics` with ``stuck`` to the bit, and its `probabilities` the same
    probabilities; on simulated records (one wall, two) and on none, one or two
    collisions."""
    cases = []
    for res, pressed, walls, beta in records():
        col = _reference_collisions(res, pressed, walls)
        cases += [(col, beta, bool(walls))] + [(col._select(np.arange(col.time.size) < k),
                                                 beta, False) for k in (0, 1, 2)]
    for col, beta, two in cases:
        for m, w in ((motions, None), (motions + ((1, 1, 1),), col.wall)):
            if w is not None and not two:
                continue
            kw = dict(window=0.1, motions=m, n_batches=20)
            ref = stats.motion_statistics(col.time, col.intervals, beta, 200.0, 4000.0,
                                          stuck=col.stuck, walls=w, **kw)
            fast = tally.MotionTally(beta, walls=w is not None, **kw)
            _same(fast.statistics(col.time, col.step, col.offset, DT, col.stuck, 200.0,
                                  4000.0, walls=w), ref)
            p, q = fast.probabilities(col.time, col.step, col.offset, DT, col.stuck, 3800.0,
                                      walls=w)
            assert p.tobytes() == ref.probability.tobytes()
            assert q.tobytes() == ref.stick_probability.tobytes()


def test_the_compiled_residence_statistics_are_the_numpy_reference():
    """`tally.residence_statistics` is `stats.residence_statistics` to the bit: random
    labelled records (one stretch, two, many; states never seen) and its refusals."""
    rng = np.random.default_rng(17)
    for n in (0, 1, 2, 3, 10, 500, 5000):
        for n_states in (1, 4):
            edges = np.concatenate([[5.0], 5.0 + np.cumsum(rng.uniform(0.0, 3.0, n + 1))])
            states = np.minimum(rng.geometric(0.3, n + 1) - 1, n_states - 1)
            states = np.repeat(states, rng.integers(1, 4, n + 1))[: n + 1]
            edges = edges[: states.size + 1]
            _same(tally.residence_statistics(edges, states, n_states),
                  stats.residence_statistics(edges, states, n_states))
    with pytest.raises(ValueError, match="edges"):
        tally.residence_statistics([0.0, 1.0], [0, 0], 2)
    with pytest.raises(ValueError, match="states"):
        tally.residence_statistics([0.0, 1.0], [2], 2)
    with pytest.raises(ValueError, match="non-decreasing"):
        tally.residence_statistics([0.0, 2.0, 1.0], [0, 1], 2)


def test_the_rule_probabilities_are_the_motion_tallys():
    """`tally.rule_probabilities` (one call for the rules a map cell reports besides the
    physical one) gives, rule by rule, `MotionTally.probabilities` of `collision_firsts`."""
    for res, _, walls, beta in records():
        wall = res.impact_wall if walls else np.zeros(res.impact_step.size, np.int8)
        eps_lower = walls["eps_lower"] if walls else 0.5
        motions = stats.DEFAULT_MOTIONS + (((1, 1, 1),) if walls else ())
        fast = tally.MotionTally(beta, motions=motions, walls=bool(walls))
        kw = dict(dt=DT, eps=0.5, eps_lower=eps_lower, floor=0.01, wall=wall, after=200.0)
        args = (res.impact_step, res.impact_offset, res.impact_velocity, res.stick_start)
        rules = stats.RULES[1:]
        got = tally.rule_probabilities(fast, *args, rules=rules, duration=3800.0, **kw)
        for rule, (p, q) in zip(rules, got):
            _, time, step, offset, _, c_wall, stuck = tally.collision_firsts(
                *args, pressed=np.zeros(0, bool), rule=rule, **kw)
            ref = fast.probabilities(time, step, offset, DT, stuck, 3800.0, walls=c_wall)
            assert p.tobytes() == ref[0].tobytes() and q.tobytes() == ref[1].tobytes()
