"""Collisions, the unit of every impact statistic (docs/figures.md, "Collisions, chatter and
sticking"): the grouping on hand-made event records, on the public `simulate`, and the
statistics' independence of every event tolerance of the kernel."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from vibroimpact import simulate, stats
from vibroimpact.reports.notebook import AUDIT_FLOOR
from vibroimpact.stats import group_collisions

DT = 0.1


def _group(times, u, stick_start=(), stick_end=(), eps=0.5, floor=0.01, rule="impacts",
           pressed=None):
    """Group hand-made events (by default with the earlier, impacts-only rule)."""
    times = np.asarray(times, dtype=float)
    step = np.floor(times / DT).astype(np.int64)
    return group_collisions(step, times - step * DT, u, stick_start, stick_end, dt=DT, eps=eps,
                            floor=floor, rule=rule, pressed=pressed)


def _regroup(res, eps=0.5, rule="physical"):
    """``res``'s impacts grouped again by `group_collisions` (the flights pressed from the
    force it was simulated with)."""
    p = res.params
    pressed = stats.pressed_flights(res.impact_step, res.impact_offset, res.force_record,
                                    p["dt"], delta=p["delta"], amplitude=p["amplitude"],
                                    beta=p["beta"])
    return group_collisions(res.impact_step, res.impact_offset, res.impact_velocity,
                            res.stick_start, res.stick_end, dt=p["dt"], eps=eps,
                            pressed=pressed, rule=rule)


def test_free_impacts_are_collisions_of_their_own():
    c = _group([1.0, 4.0, 6.5, 7.0], [1.0, 0.8, 0.6, 0.4])
    assert list(c.first) == [0, 1, 2, 3]
    assert np.allclose(c.intervals, [3.0, 2.5, 0.5])
    assert not c.stuck.any() and np.all(c.duration == 0.0) and np.all(c.stick_time == 0.0)


def test_a_chatter_sequence_ending_in_sticking_is_one_collision():
    # a free impact, then an impact whose rebounds shrink (flights 1.0, 0.5, 0.25, 0.125) and
    # stick at 12.0 until the release at 15.0; then a free impact
    t = [5.0, 10.0, 11.0, 11.5, 11.75, 11.875, 17.0]
    u = [0.5, 0.9, 0.45, 0.22, 0.11, 0.05, 0.7]
    c = _group(t, u, [12.0], [15.0])
    assert list(c.first) == [0, 1, 6]
    assert list(c.impact_collision) == [0, 1, 1, 1, 1, 1, 2]
    assert np.allclose(c.time, [5.0, 10.0, 17.0]) and np.allclose(c.velocity, [0.5, 0.9, 0.7])
    assert list(c.stuck) == [False, True, False]
    assert np.allclose(c.stick_time, [0.0, 3.0, 0.0])
    assert np.allclose(c.duration, [0.0, 5.0, 0.0])
    # rebounds leaving at eps u >= the floor
    assert list(c.rebounds) == [1, 5, 1]
    assert list(_group(t, u, [12.0], [15.0], floor=0.1).rebounds) == [1, 3, 1]


def test_the_chatter_sequence_starts_where_rebounds_and_flights_stop_shrinking():
    u = [0.8, 0.6, 0.3, 0.15, 0.07]
    # flights 2.0, 3.0, 1.0, 0.5, then sticking: the run starts after the 2.0 flight
    c = _group([0.0, 2.0, 5.0, 6.0, 6.5], u, [6.7], [8.0])
    assert list(c.first) == [0, 1]
    # a faster impact after a free flight starts the collision, however long that flight was
    c = _group([0.0, 5.0, 6.0, 6.5], [0.1, 0.9, 0.4, 0.2], [6.7], [8.0])
    assert list(c.first) == [0, 1]
    # flights that do not shrink all the way to the sticking are separate collisions
    c = _group([0.0, 1.0, 1.5, 2.5, 2.75], u, [2.9], [4.0])
    assert list(c.first) == [0, 1, 2]
    # a shrinking run that never sticks (the push turned before the accumulation point) is not
    # chatter: its impacts are collisions of their own
    c = _group([0.0, 1.0, 1.5, 1.75], u[:4])
    assert list(c.first) == [0, 1, 2, 3]


def test_plastic_impacts_and_records_ending_on_the_wall():
    # eps = 0: each impact sticks at once (onset at the impact instant)
    c = _group([1.0, 3.0], [1.0, 2.0], [1.0, 3.0], [2.0, 3.5], eps=0.0)
    assert list(c.first) == [0, 1] and c.stuck.all() and np.allclose(c.stick_time, [1.0, 0.5])
    assert list(c.rebounds) == [0, 0]            # nothing rebounds
    # sticking before the first impact (a pre-loaded start) belongs to no collision
    c = _group([3.0, 3.5], [0.4, 0.2], [0.0, 3.7], [2.0, 9.0])
    assert list(c.first) == [0] and np.allclose(c.stick_time, [5.3])
    assert np.allclose(c.duration, [6.0])
    assert _group([], []).first.size == 0


def test_simulate_reports_collisions_beside_its_impacts():
    rng = np.random.default_rng(5)
    noise = 0.5 * rng.standard_normal(30_001)
    res = simulate(0.05, 0.5, -0.5, noise=noise, dt=DT)
    assert res.n_collisions == res.collision_time.size < res.n_impacts
    again = _regroup(res)
    assert np.array_equal(again.time, res.collision_time)
    assert np.array_equal(res.impact_velocity[again.first], res.collision_velocity)
    assert np.array_equal(np.unique(res.impact_collision), np.arange(res.n_collisions))
    # every collision that sticks is a chatter sequence closed at its accumulation point or
    # a touch-down; every sticking phase after the first impact lies in a collision
    assert res.collision_stuck.sum() <= res.stick_start.size
    first_impact = res.impact_time[0]
    assert np.isclose(res.collision_stick_time.sum(),
                      np.sum((res.stick_end - res.stick_start)[res.stick_start >= first_impact]))
    # chunking never changes the grouping
    chunked = simulate(0.05, 0.5, -0.5, noise=noise, dt=DT, chunk_size=977)
    for name in ("collision_time", "collision_velocity", "collision_rebounds",
                 "collision_stuck", "collision_stick_time", "collision_duration"):
        assert np.array_equal(getattr(res, name), getattr(chunked, name)), name
    # the floor is the caller's
    high = simulate(0.05, 0.5, -0.5, noise=noise, dt=DT, rebound_floor=0.2)
    assert high.rebound_floor == 0.2 and np.all(high.collision_rebounds <= res.collision_rebounds)
    with pytest.raises(ValueError, match="rebound_floor"):
        simulate(0.05, 0.5, -0.5, noise=noise, dt=DT, rebound_floor=5e-5)


@pytest.mark.parametrize("inv_beta, delta", [(2.0, -0.5), (3.0, -0.5), (2.5, -0.7)])
def test_an_impact_chatter_stick_cycle_is_a_1_1_motion_with_sticking_never_2_1(inv_beta, delta):
    """Under sin(beta tau) alone on a pre-loaded wall the mass hits once per period, chatters,
    sticks and is released: one collision per period, never a (2/1) pair (the old count of
    rebounds paired the long interval with the first rebound's flight). periodic_orbits has
    no admissible (1/1) motion there: it is the impact-stick variant of (1/1)."""
    from vibroimpact import periodic_orbits

    beta = 1.0 / inv_beta
    z = 2.0 * np.pi / beta
    res = simulate(0.05, 0.5, delta, noise=None, dt=DT, amplitude=1.0, beta=beta, t_end=40 * z)
    t0 = 20 * z
    c = _regroup(res).after(t0)
    assert np.allclose(c.intervals / z, 1.0, atol=1e-9)
    assert c.stuck[:-1].all() and np.all(c.rebounds[:-1] > 2)
    m = stats.motion_statistics(c.time, c.intervals, beta, t0, res.t_end, stuck=c.stuck)
    assert m.probability[1] == 0.0 and m.stick_probability[1] == 0.0     # no (2/1)
    assert m.probability[0] == 0.0 and m.stick_probability[0] > 0.9     # (1/1) with sticking
    # the rebound count did classify it (2/1): the test bites
    t = res.impact_time[res.impact_time >= t0]
    assert stats.motion_statistics(t, np.diff(t), beta, t0, res.t_end).probability[1] > 0.5
    assert periodic_orbits(1, 1, beta, delta, 0.05, 0.5) == []


def test_the_2_1_motion_with_free_flights_stays_2_1():
    """At 1/beta = 1.1, delta = 0 the harmonic force has a stable (2/1) motion (Fig. 16): two
    free impacts per period are two collisions."""
    beta = 1.0 / 1.1
    z = 2.0 * np.pi / beta
    res = simulate(0.05, 0.5, 0.0, noise=None, dt=DT, amplitude=1.0, beta=beta, t_end=80 * z)
    t0 = 40 * z
    c = _regroup(res).after(t0)
    m = stats.motion_statistics(c.time, c.intervals, beta, t0, res.t_end, stuck=c.stuck)
    assert m.probability[1] > 0.95 and m.stick_probability.sum() == 0.0


RUNNER = Path(__file__).with_name("tolerance_run.py")
#: Every event tolerance of the kernel (vibroimpact.impact.kernels), scaled by 1000 both ways
#: where it can be: the round-off multiples (*_ULPS) only up (below ~1 ulp they are not
#: tolerances but noise).
LOOSE = {"CHATTER_TIME_TOL": 1e3, "CHATTER_ESTIMATE_TOL": 1e3, "MICRO_HEIGHT": 1e3,
         "ELASTIC_MICRO_FLIGHT": 1e3,
         "TOUCH_ULPS": 1e3, "WALL_ULPS": 1e3, "GAP_ULPS": 1e3, "FORCE_ULPS": 1e3}
TIGHT = {"CHATTER_TIME_TOL": 1e-3, "CHATTER_ESTIMATE_TOL": 1e-3, "MICRO_HEIGHT": 1e-3,
         "ELASTIC_MICRO_FLIGHT": 1e-3}


#: The events cell's self-audit, each with the scale of its residual.
AUDIT = {"power_residual": "power_input", "power_residual_stderr": "power_input",
         "power_input": "power_input", "virial_residual": "virial_scale",
         "virial_residual_stderr": "virial_scale", "virial_scale": "virial_scale"}


def _run(factors, tmp_path, tag):
    """The runner's results with the kernel's tolerances scaled, its kernels compiled afresh
    in memory (tests/tolerance_run.py); unscaled (no factors), with the kernels every other
    test uses, from the package's numba cache."""
    out = tmp_path / f"{tag}.npz"
    subprocess.run([sys.executable, str(RUNNER), json.dumps(factors), str(out)], check=True,
                   timeout=600)
    with np.load(out) as data:
        return {k: data[k] for k in data.files}


@pytest.mark.slow
def test_no_collision_statistic_depends_on_an_event_tolerance(tmp_path):
    """The tolerances scaled by 1e3 and 1e-3: every statistic a figure or finding uses is
    bit-identical, but the self-audit's residuals (within the reports' numerical floor) and
    the time on the wall, whose sticking onsets (chatter accumulation
    points) are exact to CHATTER_TIME_TOL: it moves by at most that bound per collision. The
    number of impacts the kernel resolved does move (in the chatter cells by 2-10 % looser,
    16-33 % tighter): the tolerances did take effect."""
    from vibroimpact.impact import kernels

    base = _run({}, tmp_path, "base")
    for tag, factors in (("loose", LOOSE), ("tight", TIGHT)):
        other = _run(factors, tmp_path, tag)
        expected = [getattr(kernels, n) * f for n, f in sorted(factors.items())]
        assert np.allclose(other["applied"], expected, rtol=1e-12), tag
        bound = max(kernels.CHATTER_TIME_TOL,
                    kernels.CHATTER_TIME_TOL * factors["CHATTER_TIME_TOL"])
        for key, value in base.items():
            if key == "applied" or key.endswith("n_impacts_resolved"):
                continue
            case, name = key.split("/")
            if name == "stick_time_mean":
                assert abs(other[key] - value) <= bound, (tag, key)
            elif name == "contact_fraction":       # <= bound per collision over the record
                assert abs(other[key] - value) <= bound * base[f"{case}/collision_rate"], \
                    (tag, key)
            elif name in AUDIT:
                # the self-audit sums every resolved rebound, whose number the tolerances set
                # (and the chatter tails to O(w^2)): it moves within the reports' numerical
                # floor, AUDIT_FLOOR of its scale (docs/model.md, section 7.1)
                scale = abs(float(base[f"{case}/{AUDIT[name]}"]))
                assert abs(other[key] - value) <= AUDIT_FLOOR * scale, (tag, key)
            else:
                assert np.array_equal(other[key], value, equal_nan=True), (tag, key)
        # the tolerances took effect: the chatter cells resolved other numbers of impacts
        # (looser, fewer: RESOLVED_REBOUND keeps every rebound faster than 5e-5)
        chatter = [k for k in base if k.endswith("n_impacts_resolved") and "_m" in k]
        assert all(other[k] != base[k] for k in chatter), tag


# --- the physical rule: chatter hops are the flights the push presses throughout ---------

def _pressed(times, noise, delta=0.0, amplitude=0.0, beta=1.0):
    times = np.asarray(times, dtype=float)
    step = np.floor(times / DT).astype(np.int64)
    return stats.pressed_flights(step, times - step * DT, noise, DT, delta=delta,
                                 amplitude=amplitude, beta=beta)


def test_pressed_flights_read_the_straight_line_between_samples():
    noise = np.ones(101)                   # push f - delta = 1 - delta
    t = [1.05, 2.0, 2.55]
    assert list(_pressed(t, noise)) == [True, True]
    assert list(_pressed(t, noise, delta=1.0)) == [False, False]       # push 0: not pressed
    noise[15] = -0.2                       # one sample below the wall's push inside flight 0
    assert list(_pressed(t, noise)) == [False, True]
    # the straight line between samples: a dip between the impact and the next sample
    noise = np.ones(101)
    noise[21] = -1.0                       # push 1 at tau = 2.0, -1 at 2.1: zero at 2.05
    assert list(_pressed([2.0, 2.04], noise)) == [True]
    assert list(_pressed([2.0, 2.06], noise)) == [False]   # the later impact itself is pulled
    assert _pressed([2.0], noise).size == 0 and _pressed([], noise).size == 0


def test_pressed_flights_find_the_harmonic_minimum_inside_a_step():
    """sin(tau) has its minimum -1 at 3 pi / 2 = 4.712, between the samples 4.7 and 4.8 where
    it is above -1 + 7e-5: with delta = -1 + 1e-6 every sample is pressed and the flight is
    not (pulled by 1e-6 for about 3e-3 time units)."""
    t = [4.65, 4.85]
    assert list(_pressed(t, None, delta=-1.0 + 1e-6, amplitude=1.0)) == [False]
    assert list(_pressed(t, None, delta=-1.0 - 1e-6, amplitude=1.0)) == [True]
    # a negative amplitude: the minimum at pi / 2
    t = [1.52, 1.62]
    assert list(_pressed(t, None, delta=-1.0 + 1e-6, amplitude=-1.0)) == [False]


def test_pressed_flights_match_a_dense_sampling():
    """Random plus harmonic force, random flights: the exact flag agrees with the push sampled
    10^4 times a step wherever the sampled minimum is clear of zero (by 1e-6: the sampled
    minimum of a smooth step misses the true one by at most |f''| h^2 / 8 < 1e-8)."""
    rng = np.random.default_rng(3)
    noise = 0.5 * rng.standard_normal(401)
    A, beta, delta = 0.8, 1.7, -0.6
    t = np.sort(rng.uniform(0.0, 39.9, 120))
    exact = _pressed(t, noise, delta=delta, amplitude=A, beta=beta)
    checked = 0
    for j in range(t.size - 1):
        tau = np.linspace(t[j], t[j + 1], max(2, int((t[j + 1] - t[j]) / DT * 1e4)))
        k = np.minimum(np.floor(tau / DT).astype(int), noise.size - 2)
        r = noise[k] + (noise[k + 1] - noise[k]) * (tau / DT - k)
        low = np.min(r + A * np.sin(beta * tau) - delta)
        if abs(low) > 1e-6:
            assert exact[j] == (low > 0.0), j
            checked += 1
    assert checked > 100 and 10 < exact.sum() < checked - 10    # both kinds of flight tested


def test_a_force_that_reverses_during_a_long_hop_splits_the_collision():
    # an impact, a long flight of 3.0, then a chatter sequence sticking at 5.0 (release 6.0)
    t = [1.0, 4.0, 4.5, 4.75, 4.875]
    u = [0.9, 0.6, 0.3, 0.15, 0.07]
    noise = np.ones(101)                              # pressed throughout: one collision
    c = _group(t, u, [5.0], [6.0], rule="physical", pressed=_pressed(t, noise))
    assert list(c.first) == [0] and list(c.stuck) == [True]
    noise[25] = -0.3                                  # pulled at tau = 2.5: two collisions
    c = _group(t, u, [5.0], [6.0], rule="physical", pressed=_pressed(t, noise))
    assert list(c.first) == [0, 1] and list(c.stuck) == [False, True]
    # the impacts-only rule cannot tell the two apart
    assert list(_group(t, u, [5.0], [6.0]).first) == [0]


def test_a_force_that_presses_throughout_keeps_a_long_first_rebound():
    """A long first rebound that comes back faster than the next flight would suggest (the
    impacts-only rule reads a free flight there) stays in the collision while the push
    presses throughout; a run of hops that never sticks is no chatter (its impacts stay
    collisions of their own)."""
    t = [1.0, 4.0, 4.5, 4.75, 4.875]
    u = [0.5, 0.9, 0.3, 0.15, 0.07]                   # the second impact faster than the first
    pressed = _pressed(t, np.ones(101))
    assert list(_group(t, u, [5.0], [6.0], rule="physical", pressed=pressed).first) == [0]
    assert list(_group(t, u, [5.0], [6.0]).first) == [0, 1]
    assert list(_group(t, u, rule="physical", pressed=pressed).first) == [0, 1, 2, 3, 4]
    # sticking between two impacts always separates them (a release is a free flight)
    c = _group([1.0, 1.5, 3.0], [0.5, 0.2, 0.4], [1.8], [2.5], rule="physical",
               pressed=[True, True])
    assert list(c.first) == [0, 2]
    with pytest.raises(ValueError, match="pressed"):
        _group(t, u, rule="physical")
    with pytest.raises(ValueError, match="rule"):
        _group(t, u, rule="other")


def test_the_paper_fig3_free_flight_is_no_chatter():
    """Fig. 3 (delta = 0, the random study's record from rest): the impact at tau = 42.57
    follows a flight of 3.6 from 38.94 during which the force pulls; the flight 42.57 -> 44.52
    is pulled too, and the chatter that sticks at 44.85 starts at 44.52. The impacts-only rule
    folded 38.94 and 42.57 into it."""
    from vibroimpact import noise

    spec = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)
    record = noise.generate_array(spec, 701, seed=19740914)
    res = simulate(0.05, 0.5, 0.0, noise=record, dt=DT, t_end=60.0)
    t = res.impact_time
    i = int(np.argmin(abs(t - 38.936)))
    assert np.allclose(t[i : i + 3], [38.936, 42.574, 44.523], atol=1e-3)
    assert np.all(np.diff(res.impact_collision[i : i + 3]) == 1)      # three collisions
    chatter = res.impact_collision == res.impact_collision[i + 2]
    assert chatter.sum() > 5 and res.collision_stuck[res.impact_collision[i + 2]]
    assert np.isclose(res.stick_start[0], 44.849, atol=1e-3)
    old = res.grouped("impacts")
    assert old.impact_collision[i] == old.impact_collision[i + 1] == old.impact_collision[i + 2]


def test_the_per_rebound_view_counts_each_rebound_above_the_floor():
    t = [1.0, 4.0, 4.5, 4.75, 4.875]
    u = [0.9, 0.6, 0.3, 0.15, 0.01]                   # eps u = 0.005 < 0.01 for the last
    c = _group(t, u, [5.0], [6.0], rule="rebounds")
    assert list(c.first) == [0, 1, 2, 3] and list(c.impact_collision) == [0, 1, 2, 3, 3]
    assert list(c.rebounds) == [1, 1, 1, 1] and list(c.stuck) == [False, False, False, True]
    assert _group([1.0], [0.01], rule="rebounds").first.size == 0


def test_the_attractor_kernels_hop_is_pressed_flights_without_noise():
    """The attractor classifier (sin(beta tau) alone, amplitude 1) tells hops by the same
    rule as `stats.pressed_flights`, in closed form."""
    from vibroimpact.attractors.kernels import _hop

    rng = np.random.default_rng(11)
    for _ in range(300):
        beta, delta = rng.uniform(0.3, 3.0), rng.uniform(-1.5, 1.0)
        t = np.sort(rng.uniform(0.0, 50.0, 2))
        t[1] = t[0] + rng.choice([rng.uniform(0, 0.3), rng.uniform(0, 10)])
        exact = _pressed(t, None, delta=delta, amplitude=1.0, beta=beta)[0]
        assert _hop(t[0], t[1], beta, delta) == exact, (beta, delta, t)


@pytest.mark.parametrize("amplitude", [0.0, 0.8, -1.2])
def test_the_compiled_hops_are_the_numpy_reference(amplitude):
    """`impact.hops.pressed_flights` (what simulate and the cells run) equals
    `stats.pressed_flights` (the statement of the rule) on a random force with and without a
    harmonic part, with and without a mask of the flights to examine, and on a real record."""
    from vibroimpact.impact import hops

    rng = np.random.default_rng(12)
    noise = 0.5 * rng.standard_normal(2001)
    for delta in (-0.8, -0.3, 0.0, 0.4):
        t = np.sort(rng.uniform(0.0, 199.9, 400))
        step = np.floor(t / DT).astype(np.int64)
        kw = dict(delta=delta, amplitude=amplitude, beta=1.3)
        ref = stats.pressed_flights(step, t - step * DT, noise, DT, **kw)
        assert np.array_equal(hops.pressed_flights(step, t - step * DT, noise, DT, **kw), ref)
        mask = rng.random(t.size - 1) < 0.5
        assert np.array_equal(hops.pressed_flights(step, t - step * DT, noise, DT, **kw,
                                                   flights=mask), ref & mask)
        assert 0 < ref.sum() < ref.size or delta > 0.0
    res = simulate(0.05, 0.5, -0.5, noise=noise, dt=DT, amplitude=amplitude, beta=1.3)
    kw = dict(delta=-0.5, amplitude=amplitude, beta=1.3)
    assert np.array_equal(
        hops.pressed_flights(res.impact_step, res.impact_offset, noise, DT, **kw),
        stats.pressed_flights(res.impact_step, res.impact_offset, noise, DT, **kw))


def test_the_compiled_hops_shortcuts_keep_grazing_pushes():
    """The compiled walk's shortcuts (pushes bounded from the last sine, interior minima
    skipped under a curvature bound) skip only pushes that are clearly > 0: on a force
    whose push grazes 0 (the harmonic part, ``delta`` at its minimum -+ 1e-13 .. 1e-3, and
    a faint random part) and on flights of every length, the compiled hops are the
    numpy reference's."""
    from vibroimpact.impact import hops

    rng = np.random.default_rng(21)
    beta = 0.7
    mixed = 0
    for scale in (0.0, 1e-9, 1e-3):
        noise = scale * rng.standard_normal(40001)
        for gap in (1e-13, -1e-13, 1e-10, -1e-10, 1e-6, -1e-6, 1e-3):
            t = np.sort(rng.uniform(0.0, 3999.0, 3000))
            t[::7] = t[::7] - np.mod(t[::7], 0.3)          # short flights among long ones
            t = np.unique(t)
            step = np.floor(t / DT).astype(np.int64)
            kw = dict(delta=-1.0 - gap, amplitude=1.0, beta=beta)
            ref = stats.pressed_flights(step, t - step * DT, noise, DT, **kw)
            assert np.array_equal(hops.pressed_flights(step, t - step * DT, noise, DT, **kw),
                                  ref)
            mixed += bool(ref.any() and not ref.all())
    assert mixed >= 5
