"""Every long job says in its log what it did and what is left (issue 46): the orbit,
attractor, boundary and escape jobs, in the simulation tiles' format (`tasks.Progress`); and
the blocks their kernels run in to report it give the numbers of one call, bit for bit."""
import copy
import re

import numba
import numpy as np
import pytest
import yaml

from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline import tasks
from vibroimpact.pipeline.study import ORBIT_JOB_KEYS, orbit_rows

from helpers import ROOT

TEST_CONFIG = yaml.safe_load((ROOT / "config" / "test.yaml").read_text())
#: A progress line: units done of total, the rate and the time left.
LINE = re.compile(r"progress (?P<what>.+): (?P<done>\d+) of (?P<total>\d+) (?P<unit>\w+), "
                  r"(.+ simulated, )?[0-9.e+-]+ (?P=unit)/s, ~\d+ s left$")


@pytest.fixture(scope="module")
def config():
    return configuration.load(copy.deepcopy(TEST_CONFIG), root=ROOT)[0]


def _orbit_block(config, kind):
    entry = config["orbits"]["harmonic"]
    return {k: entry[k] for k in ORBIT_JOB_KEYS[kind] if k in entry}


def _progress(log):
    """``(started, [(done, total)])`` of the progress lines of a job's log."""
    lines = [line.split(" INFO ", 1)[1] for line in log.read_text().splitlines()
             if " INFO progress " in line]
    started = [line for line in lines if line.endswith(", started")]
    counts = [LINE.search(line) for line in lines if not line.endswith(", started")]
    assert all(counts), lines
    return started, [(int(m["done"]), int(m["total"])) for m in counts]


def _run(job, log):
    with tasks.logged(str(log)):
        job()
    return _progress(log)


def _jobs(config, tmp_path):
    """One job of each kind (a callable each), in an order that feeds the boundaries."""
    orbits = tmp_path / "orbits.nc"
    block = _orbit_block(config, "orbits")
    study = config["studies"]["motion_map"]
    noise = {k: v for k, v in config["noises"][study["noise"]].items()
             if k in ("kind", "dt", "beta_c", "zeta_f", "seed")}
    return {
        "orbit": lambda: tasks.orbit_tile(block, 0, orbits),
        "attractor": lambda: tasks.attractor_tile(_orbit_block(config, "attractors"), 0,
                                                  tmp_path / "attractors.nc"),
        "boundaries": lambda: tasks.boundaries(_orbit_block(config, "boundaries"), orbits,
                                               tmp_path / "boundaries.nc"),
        "escape": lambda: tasks.escape_level("motion_map", study, noise, 0,
                                             tmp_path / "escape.nc"),
    }


def test_every_long_job_logs_its_start_its_progress_and_its_end(config, tmp_path):
    """A job of each kind: one ``0 of N ..., started`` line, then lines counting up to N of
    N, each with the rate and the time left (the simulation tiles' format)."""
    for name, job in _jobs(config, tmp_path).items():
        started, counts = _run(job, tmp_path / f"{name}.log")
        assert len(started) == 1, name
        total = int(re.search(r": 0 of (\d+) ", started[0])[1])
        assert total > 0 and counts and counts[-1] == (total, total), (name, counts)
        assert all(a[0] < b[0] for a, b in zip(counts, counts[1:])), (name, counts)


def test_a_long_job_logs_between_start_and_end_at_a_short_cadence(config, tmp_path,
                                                                   monkeypatch):
    """With the cadence at 0 s and one row (or cell) a block, the orbit and attractor tiles
    log each block: more lines than the start and the end."""
    from vibroimpact.attractors import api as attractors
    from vibroimpact.orbits import api as orbits

    monkeypatch.setattr(tasks, "PROGRESS_EVERY", 0.0)
    monkeypatch.setattr(orbits, "MAP_BLOCK_ROWS", 1)
    monkeypatch.setattr(attractors, "BLOCK_STARTS", 1)    # a cell's starts
    jobs = _jobs(config, tmp_path)
    threads = numba.get_num_threads()
    counts = {name: _run(jobs[name], tmp_path / f"{name}.log")[1]
              for name in ("orbit", "attractor")}
    rows, n_tiles = orbit_rows(_orbit_block(config, "orbits"))
    assert len(counts["orbit"]) == -(-rows[::n_tiles].size // threads)   # a line a block
    assert len(counts["attractor"]) > 2           # a line a cell
    for done in counts.values():                  # and the start: more than start and end
        assert len(done) >= 2 and done[-1][0] == done[-1][1]


def test_blocks_of_rows_or_starts_give_one_calls_numbers_bit_for_bit(monkeypatch):
    """`orbit_map` on one row a block per thread and `attractor_map` on one cell a block
    give what each gives in one block, every array bit for bit."""
    from vibroimpact.attractors import api as attractors
    from vibroimpact.orbits import api as orbits

    inv_beta, delta = np.linspace(0.4, 2.6, 7), np.linspace(-1.0, 2.0, 13)
    types = [(1, 1), (2, 1), (1, 2), (3, 1)]
    kw = dict(n_starts=8, max_time=600.0, types=[(1, 1), (2, 1)])
    whole = orbits.orbit_map(inv_beta, delta, types=types)
    basins = attractors.attractor_map(inv_beta[::2], delta[::3], 0.05, 0.5, **kw)
    monkeypatch.setattr(orbits, "MAP_BLOCK_ROWS", 1)
    monkeypatch.setattr(attractors, "BLOCK_STARTS", 1)
    done = []
    blocks = orbits.orbit_map(inv_beta, delta, types=types, progress=done.append)
    assert sum(done) == inv_beta.size * delta.size and len(done) > 1
    cells = []
    basins_blocks = attractors.attractor_map(inv_beta[::2], delta[::3], 0.05, 0.5, **kw,
                                             progress=cells.append)
    assert cells == [1] * (4 * 5)
    for key, value in whole.items():
        np.testing.assert_array_equal(blocks[key], value, err_msg=key)
    for key, value in basins.items():
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(basins_blocks[key], value, err_msg=key)
