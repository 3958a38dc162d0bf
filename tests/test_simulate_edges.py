"""Edge cases of the simulator found in use (regressions), each checked against physics."""
import numpy as np
import pytest

from vibroimpact import simulate, simulate_chunks


@pytest.mark.parametrize("r0", [-0.29, -1e-3, -1e-9])
def test_leaves_the_wall_from_rest_when_pulled(r0):
    """At rest on the wall (x0 = delta = 0) with f(0) - delta = r0 < 0 and sin(1.1 tau) on top.
    Before the fix the mass crept off in steps of 1e-15 and hit the per-step event limit.
    It must leave at once (no sticking at tau = 0) unless the pull reverses before any
    resolvable separation (r0 = -1e-9: f turns positive at tau ~ 1e-9), and never cross."""
    r = np.full(1001, r0)
    res = simulate(0.05, 0.5, 0.0, noise=r, dt=0.1, amplitude=1.0, beta=1.1, record_every=1)
    if r0 < -1e-6:
        assert res.stick_start.size == 0 or res.stick_start[0] > 0.0
        assert res.impact_time[0] > 0.0
    assert np.all(res.a >= -1e-12)
    assert res.n_impacts > 0


def test_negative_play_starts_pressed_and_stays_until_the_force_releases_it():
    """delta < 0 at rest in contact: stuck while f - delta > 0, released exactly at the root
    of the piecewise-linear force: f = 0 for tau <= 10, then falls by 0.01 per sample step
    (0.1 per unit time), so f - delta = 0 at tau = 10 + 0.5/0.1 = 15."""
    delta = -0.5
    r = np.concatenate([np.zeros(101), np.linspace(0.0, -1.0, 101)[1:]])
    res = simulate(0.05, 0.5, delta, noise=r, dt=0.1)
    assert res.stick_start[0] == 0.0
    assert res.stick_end[0] == pytest.approx(15.0, abs=1e-12)
    assert res.contact_time == pytest.approx(15.0, abs=1e-12)


def test_chunking_and_buffer_flushes_give_identical_results():
    """Streaming in chunks and flushing full event buffers mid-record (153k impacts, more than
    the 131k-event buffer) must not change a single bit, nor duplicate a recorded sample."""
    r = np.random.default_rng(0).standard_normal(300_001)
    a = simulate(0.05, 0.5, -0.5, noise=r, record_every=3)
    b = simulate(0.05, 0.5, -0.5, noise=r, record_every=3, chunk_size=999)
    assert a.n_impacts > 2 * 65536
    assert a.a.size == 100_001 and np.array_equal(a.grid_time, (np.arange(100_001) * 3) * 0.1)
    for name in ("impact_time", "impact_velocity", "stick_start", "stick_end", "a", "v",
                 "collision_time", "collision_stuck", "collision_stick_time",
                 "collision_rebounds"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name


def test_a_streamed_record_is_never_recorded_over():
    """The driver records each chunk into buffers handed over two chunks before once nothing
    refers to them (`_Buffers.take_grid`): the a and v a consumer keeps (a chunk, or only a
    view of its a) hold their values to the end, those it lets go are reused, and each
    chunk's record is the whole run's (simulate, which keeps every chunk)."""
    import gc

    r = np.random.default_rng(1).standard_normal(40_001)
    whole = simulate(0.05, 0.5, 0.3, noise=r, record_every=1)
    kept, views, reused, seen = [], [], set(), set()
    k0 = 0
    for j, chunk in enumerate(simulate_chunks(0.05, 0.5, 0.3, noise=r, record_every=1,
                                              chunk_size=3000)):
        base = chunk.a.base if chunk.a.base is not None else chunk.a
        reused.add(id(base) in seen)
        seen.add(id(base))
        n = chunk.a.size
        assert np.array_equal(chunk.a, whole.a[k0:k0 + n])
        assert np.array_equal(chunk.v, whole.v[k0:k0 + n])
        if j % 3 == 0:
            kept.append((k0, chunk))                   # the chunk kept
        elif j % 3 == 1:
            views.append((k0, chunk.a[1:-1]))          # a view of its a kept
        k0 += n
        gc.collect()
    assert k0 == whole.a.size and True in reused       # some buffers were recorded into again
    for k0, chunk in kept:
        assert np.array_equal(chunk.a, whole.a[k0:k0 + chunk.a.size])
        assert np.array_equal(chunk.v, whole.v[k0:k0 + chunk.v.size])
    for k0, a in views:
        assert np.array_equal(a, whole.a[k0 + 1:k0 + 1 + a.size])


def test_elastic_micro_bounces_end_in_contact():
    """eps = 1 pressed on the wall: bounces shrink only by damping (no finite-time accumulation);
    the run must end (micro-bounces below ELASTIC_MICRO_FLIGHT are resting contact)."""
    res = simulate(0.6, 1.0, -0.6, np.zeros(401), 0.1, x0=-1.5)
    assert res.stuck_end and res.stick_start.size == 1


RELEASE_NEAR_SAMPLE = [-0.13027803983693853, -0.11302993382683199, -0.12046318579457768,
                       -0.15342973887650074, -0.2093737715719887, -0.28278417717873827,
                       -0.3659625028322547, -0.45000001401856266, -0.52583421712982,
                       -0.5852593079118741, -0.621774855594811, -0.6312052781403946,
                       -0.612023088919565, -0.5653774225904354, -0.4948568488931359,
                       -0.40602611112508824]


@pytest.mark.parametrize("eps", [0.5, 0.8])
def test_release_just_before_a_sample_point(eps):
    """Regression (issue: a release from the wall near a sample point broke the simulator).
    The mass rests on the wall at delta = -0.45; f - delta crosses zero 1.7e-7 dt before the
    sample at tau = 0.7 (the sample misses delta by 1.4e-8). Before the fix the release left
    a zero-length rest of the step that was never consumed: 'more than 65536 events'.
    It must leave at the root of the linear force (to round-off) and match the 34-digit
    reference: no impact, final state to 1e-12."""
    from vibroimpact.validation.reference import reference_impacts
    r = np.array(RELEASE_NEAR_SAMPLE)
    res = simulate(zeta=0.02, eps=eps, delta=-0.45, noise=r, dt=0.1, x0=None, v0=0.0)
    ref = reference_impacts(0.02, eps, -0.45, r, 0.1)
    t_release = 0.6 + 0.1 * (r[6] + 0.45) / (r[6] - r[7])
    assert res.stick_start.tolist() == [0.0]
    assert res.stick_end[0] == pytest.approx(t_release, abs=1e-15)
    assert res.stick_end[0] == pytest.approx(float(ref["stick_end"][0]), abs=1e-15)
    assert res.n_impacts == len(ref["time"]) == 0
    assert res.x_end == pytest.approx(float(ref["x_end"]), abs=1e-12)
    assert res.v_end == pytest.approx(float(ref["v_end"]), abs=1e-12)


def test_gave_up_message_says_what_it_saw():
    """When the kernel gives up on a step, the message names the step, the state, the force
    at the step's ends and the counts, and guesses no cause."""
    from vibroimpact.impact import kernels
    from vibroimpact.impact.simulate import _raise_status
    diag = np.array([0.05, -1e-17, -2e-9, kernels.FREE, 40000, 25534])
    P = np.zeros(21)
    P[kernels.P_DELTA] = -0.45
    r = np.array([0.0, 0.1, 0.2, 0.3, -0.45, -0.5, 0.0, -0.45, -0.52])
    with pytest.raises(RuntimeError) as info:
        _raise_status(kernels.TOO_MANY_EVENTS, 7, 0.1, r, 0, diag, P)
    msg = str(info.value)
    for part in ("sample 7", "40000 impacts", "25534 sticking", "x - delta = -1e-17",
                 "x' = -2e-09", "free", "r = (-0.45, -0.52)",
                 "f - delta at the step's ends = (0.0, -0.07"):
        assert part in msg, (part, msg)
    assert "eps" not in msg


def test_every_event_array_of_a_chunk_is_contiguous():
    """The chunks' event arrays are C-contiguous, one wall and two: the compiled statistics
    and the self-audit take them as they are, and a strided view would compile a second
    specialisation of their kernels inside a job (numba types the layout)."""
    from vibroimpact import simulate_chunks

    noise = 0.5 * np.random.default_rng(3).standard_normal(20001)
    names = ("impact_step", "impact_offset", "impact_velocity", "impact_time", "stick_start",
             "stick_end", "impact_wall", "stick_wall")
    seen = 0
    for walls in ({}, {"gap": 0.8, "eps_lower": 0.6}):
        for chunk in simulate_chunks(0.05, 0.5, -0.3, noise=noise, dt=0.1, amplitude=1.0,
                                     beta=0.8, chunk_size=5000, **walls):
            for name in names:
                assert getattr(chunk, name).flags.c_contiguous, name
            seen += chunk.stick_start.size
    assert seen > 10
