"""One simulation job's kernel work, for timing numba's CPU target and its cache from outside.

numba's on-disk cache (``cache=True``) keys each compiled kernel by the CPU it was compiled
for (name and features): on a cluster of mixed CPUs, a node of another model than the one that
compiled finds no entry and compiles again, in every job. Compiled for a named target instead
(``NUMBA_CPU_NAME=generic``: baseline x86-64; ``x86-64-v3``: AVX2 and FMA, any x86 CPU since
2013-2015), the entry is the same on every node. This script is the command to time: it
imports the simulator, runs `vibroimpact.simulate` over ``--samples`` seeded Gaussian force
samples at delta = 0 (impacts) and 1, and prints its own kernel CPU time per sample step. With
a small record its process time is the start-up and the cache's load (or the compilation, on
an empty ``NUMBA_CACHE_DIR``); with a large one, the kernel's speed. What was measured, and
with which commands: README, "On a SLURM cluster".

    python benchmarks/numba_cpu_target.py --samples 20000000
"""
import argparse
import time

import numpy as np

from vibroimpact import simulate


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000)
    args = parser.parse_args(argv)
    noise = np.random.default_rng(1974).standard_normal(args.samples)
    total = 0.0
    for delta in (0.0, 1.0):
        start = time.process_time()
        simulate(0.05, 0.5, delta, noise, 0.1)
        total += time.process_time() - start
    print(f"{total / (2 * args.samples) * 1e9:.2f} CPU-ns a sample step over {args.samples:,} "
          f"samples x 2 plays")


if __name__ == "__main__":
    main()
