"""The orbit map and the attractor map of the default build, timed in one process: the A/B
of their progress reports (the kernels called on blocks of rows or starts, issue 46).

Runs `vibroimpact.orbit_map` over ``orbits.harmonic``'s grid (141 x 226, Fig. 16) or
`vibroimpact.attractor_map` over its ``attractors`` grid (57 x 91, 64 starts a cell) of
config/config.yaml, as rules ``solve_orbit_tile`` and ``solve_attractor_tile`` do, with the
same call under any version of the package (no ``progress`` argument: a version without
blocks runs it as one call). Prints the wall time of the call and a digest of the result,
so two versions are compared on time and on numbers alike::

    PYTHONPATH=src python benchmarks/progress_ab.py orbits [--threads 2]

Time it from outside against the other version (its own interpreter and ``src``), runs
interleaved; the digests must be equal.
"""
import argparse
import hashlib
from pathlib import Path
import time

import numba
import numpy as np
import yaml

from vibroimpact.pipeline.study import grid_values

CONFIG = Path(__file__).resolve().parents[1] / "config" / "config.yaml"


def digest(result):
    h = hashlib.sha256()
    for key in sorted(result):
        value = result[key]
        if isinstance(value, np.ndarray):
            h.update(key.encode())
            h.update(np.ascontiguousarray(value).tobytes())
    return h.hexdigest()[:16]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("orbits", "attractors"))
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    numba.set_num_threads(args.threads)
    entry = yaml.safe_load(CONFIG.read_text())["orbits"]["harmonic"]
    types = [tuple(t) for t in entry["types"]]
    start = time.perf_counter()
    if args.what == "orbits":
        from vibroimpact.orbits import orbit_map

        result = orbit_map(grid_values(entry["inv_beta"]), grid_values(entry["delta"]),
                           types=types, zeta=float(entry["zeta"]), eps=float(entry["eps"]))
    else:
        from vibroimpact.attractors import attractor_map

        block = entry["attractors"]
        result = attractor_map(grid_values(block["inv_beta"]), grid_values(block["delta"]),
                               float(entry["zeta"]), float(entry["eps"]), types=types,
                               n_starts=int(block["n_starts"]),
                               gap=tuple(block["gap"]), velocity=tuple(block["velocity"]),
                               max_time=float(block["max_time"]), seed=int(block["seed"]))
    wall = time.perf_counter() - start
    print(f"{args.what}: {wall:.3f} s wall on {args.threads} threads, result {digest(result)}")


if __name__ == "__main__":
    main()
