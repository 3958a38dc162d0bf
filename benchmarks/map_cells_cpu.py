"""CPU time of `motion_map_cell` on given cells of a map, for the revision on ``PYTHONPATH``.

A helper of ``bench_map.py --peer REV``: the same script runs once with this tree's package
and once with a peer revision's (a git worktree put first on ``PYTHONPATH``), so both sides
time the same cells with the same arguments in the same run. It uses only what every revision
since the map's introduction has: ``vibroimpact.pipeline.cells.motion_map_cell`` and
``vibroimpact.pipeline.io.read_noise``.

Usage (reads the cells as JSON on stdin, writes JSON to stdout)::

    echo '{"noise": "...nc", "kwargs": {...}, "cells": [[inv_beta, delta], ...]}' |
        PYTHONPATH=<src> python benchmarks/map_cells_cpu.py
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread, as the jobs

import json
import sys
import time

import numpy as np

import vibroimpact
from vibroimpact.pipeline.cells import motion_map_cell
from vibroimpact.pipeline.io import read_noise

from cell_calls import call


def main():
    job = json.load(sys.stdin)
    noise, dt, _ = read_noise(job["noise"])
    noise = np.asarray(noise[:], dtype=float)
    kw = dict(job["kwargs"])
    # compile and warm the kernels on a busy cell before any timing
    call(motion_map_cell, noise, dt, 2.5, -1.0, **dict(kw, max_periods=50))
    cpu, probability, record_end = [], [], []
    for inv_beta, delta in job["cells"]:
        start = time.process_time()
        cell = call(motion_map_cell, noise, dt, inv_beta, delta, **kw)
        cpu.append(time.process_time() - start)
        probability.append([float(p) for p in cell["probability"]])
        record_end.append(float(cell["record_end"]))
    json.dump(dict(package=os.path.dirname(vibroimpact.__file__), cpu=cpu,
                   probability=probability, record_end=record_end), sys.stdout)


if __name__ == "__main__":
    main()
