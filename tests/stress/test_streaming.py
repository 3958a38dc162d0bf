"""Stress family ``streamed_record``: a long record streamed from disk with flat memory.

Checked by invariants, by bit-identity across chunk sizes and by replaying the flights after
a seeded sample of impacts in closed form (``vibroimpact.validation.streaming``, where every
tolerance is stated with its reason): A_TOL = 1e-12 on the grid, REPLAY_TOL = 1e-9 on the
replayed flights, 0 (bit-identical) across chunk sizes. Memory: the streaming process's growth
over its own baseline (imports + JIT) must stay below 25 % of the record's bytes, and its
whole peak below 50 % (a run that held the record, or a plain memmap of it, needs > 100 %).
"""
import shutil

import numpy as np
import pytest

from vibroimpact import simulate
from vibroimpact.validation import streaming as S
from vibroimpact.validation.campaign import SLOW_SEED


@pytest.mark.slow
def test_streamed_record_of_1e8_samples(tmp_path):
    """1e8 unit samples (763 MB) at zeta 0.05, eps 0.5, delta 1.5, dt 0.1, chunk sizes
    2**20, 999_983 and 2**22; ~1.4e5 impacts. About 20 s on 2 cores."""
    n = 100_000_000
    free = shutil.disk_usage(tmp_path).free
    if free < 2 * 8 * n:
        pytest.skip(f"{free / 2**30:.1f} GB free in {tmp_path}, the 1e8 record needs 0.8 GB")
    report = S.run_streamed_record(n, seed=SLOW_SEED, workdir=tmp_path)
    print("\n" + report.summary())
    assert report.ok, report.details()
    x = report.extra
    assert report.cases == 3 and report.exceptions == report.missed == report.spurious == 0
    assert x["n_impacts"] > 100_000 and report.compared == 2 * x["n_impacts"], report.details()
    assert x["replayed"] == 64, report.details()
    assert x["stream_rss_mb"] < 0.25 * x["record_mb"], report.details()
    assert x["peak_rss_mb"] < 0.5 * x["record_mb"], report.details()
    assert list(tmp_path.iterdir()) == []      # the record and the event files are gone


def test_streamed_record_small(tmp_path):
    """2e5 samples at delta = 0 (impacts, chatter sequences and sticking), chunks smaller than
    the record so that boundaries fall inside it; the grid at every sample. A few seconds."""
    report = S.run_streamed_record(200_000, seed=5, workdir=tmp_path, delta=0.0,
                                   chunk_sizes=(2**14, 9_973, 2**16), record_every=1,
                                   n_replay=32)
    print("\n" + report.summary())
    assert report.ok, report.details()
    x = report.extra
    assert x["n_impacts"] > 5_000 and x["n_sticks"] > 50, report.details()
    assert report.compared == 2 * x["n_impacts"] and x["replayed"] == 32
    assert x["rss_bound_mb"] is None          # 1.5 MB record: the bound is not enforced
    assert list(tmp_path.iterdir()) == []


def test_streamed_record_checks_can_fail(tmp_path):
    """The family's checks are not vacuous: the record on disk is the generator's sequence and
    streams like the array in memory; a wrong restitution in the replay, and an event shifted
    by one ulp, dropped or added, are all caught."""
    n, seed = 50_001, 3
    path = tmp_path / "r.npy"
    S.write_record(path, n, seed, block=4_096)
    r = np.random.default_rng(seed).standard_normal(n)
    assert np.array_equal(np.load(path), r)

    params = dict(zeta=0.05, eps=0.5, delta=0.3, dt=0.1, amplitude=0.0, beta=1.0)
    run = S.stream_run(path, 7_919, tmp_path / "run", params, record_every=1)
    mem = simulate(noise=r, record_every=1, **params)
    imp = np.fromfile(tmp_path / "run.impacts", S.IMPACT_DTYPE)
    assert run["n_impacts"] == mem.n_impacts > 200
    assert np.array_equal(imp["step"], mem.impact_step)
    assert np.array_equal(imp["offset"], mem.impact_offset)
    assert np.array_equal(imp["u"], mem.impact_velocity)
    sticks = np.fromfile(tmp_path / "run.sticks", S.STICK_DTYPE)

    good = S._replay_sample(r, imp, sticks, params, 8, seed, S.REPLAY_TOL)
    assert len(good) == 8 and all(c is None and e <= S.REPLAY_TOL for _, e, c in good)
    wrong = S._replay_sample(r, imp, sticks, dict(params, eps=0.45), 8, seed, S.REPLAY_TOL)
    assert all(c is not None or e > 1e3 * S.REPLAY_TOL for _, e, c in wrong), wrong

    same = S._compare_streams(imp, imp.copy(), 0.1, "impacts")
    assert same == dict(matched=len(imp), missed=0, spurious=0, worst=0.0, first=None)
    ulp = imp.copy()
    ulp["offset"][100] = np.nextafter(ulp["offset"][100], 1.0)
    c = S._compare_streams(imp, ulp, 0.1, "impacts")
    assert c["first"] is not None and c["worst"] > 0.0 and c["missed"] == c["spurious"] == 0
    c = S._compare_streams(imp, np.delete(imp, 150), 0.1, "impacts")
    assert (c["missed"], c["spurious"], c["matched"]) == (1, 0, len(imp) - 1)
    i = int(np.flatnonzero(np.diff(imp["step"]) > 2)[0])     # a flight of more than 2 steps
    extra = np.insert(imp, i + 1, (imp["step"][i] + 1, 0.05, 0.1))  # an impact inside it
    c = S._compare_streams(imp, extra, 0.1, "impacts")
    assert (c["missed"], c["spurious"]) == (0, 1)
