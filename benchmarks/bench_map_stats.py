"""The Fig. 15 map cell's statistics (everything but the simulator's kernel): CPU per cell of
this tree against the merge base with main, in one run, and the results compared.

Every ``--stride``-th cell of a built map (``--dataset``, default
``results/datasets/motion_map_map.nc``, over its noise record ``--noise``) runs
``vibroimpact.pipeline.cells.motion_map_cell`` in a fresh process per build (``git archive REV
src/vibroimpact`` for the peer, as `ab_no_impact.py`; NUMBA_NUM_THREADS = 1, each build its own
warmed numba cache). In that process the simulator's chunk generator
(``cells.simulate_chunks``) is wrapped so that the CPU spent inside it (the kernel: stepping,
impacts, chunk wrapping) is summed apart; the statistics are the rest of the cell's CPU: the
hop check, the three grouping rules, the motion statistics at every check, the residence
statistics. Builds run in turn, ``--rounds`` times, interleaved (this tree, peer, this tree,
...): the best round of each is printed, per cell and in total, with the ratio, and every
returned field of every cell is compared between the builds (bytes of the arrays: a changed
bit is a difference).

Also the job's start-up: a fresh interpreter importing what the map job imports before its
first cell (``vibroimpact.pipeline.tasks``, then ``vibroimpact.pipeline.cells``), best of the
rounds, per build.

Measured 2026-11-27 05:47-05:53 UTC (load average 22-24 on 2 cores: a shared machine), 325
cells (every 16th of the default map), best of 3 interleaved rounds, peer = main a13f0b3:

    build             stats CPU s  per cell ms  kernel CPU s  cell CPU s  stats share
    this tree               1.387        4.267         2.805       4.192        33.1%
    peer a13f0b3            2.927        9.007         2.803       5.731        51.1%
    statistics CPU, this tree / peer: 0.474; whole cell: 0.731
    results identical to the bit (every field of every cell): 325 of 325 cells

Start-up (import of tasks and cells, CPU) 0.80 s against 0.79 s. Of the 1.39 s left, the hop
check (``impact.hops``, compiled already) is about a third. Again after merging main 9347978
(its simulator changes in both builds), 06:07-06:14 UTC, load average 13-18:

    this tree               1.143        3.518         2.314       3.458        33.1%
    peer 9347978            2.488        7.655         2.357       4.845        51.4%
    statistics CPU, this tree / peer: 0.460; whole cell: 0.714; 325 of 325 cells identical

Issue 37 (m38), the cell's statistics at their floor: the lean forms of `vibroimpact.tally`
(``collision_firsts``, ``MotionTally``, ``rule_probabilities``, ``residence_statistics``) and
the hops' walk that skips the pushes it can bound; measured 2026-11-27 08:54-08:59 UTC (load
average 6.3-7.2 on 2 cores), 649 cells (every 8th), best of 3 interleaved rounds, peer = main
2ec7353 (the "kernel" column is all of ``simulate_chunks``, its driver included):

    build             stats CPU s  per cell ms  kernel CPU s  cell CPU s  stats share
    this tree               1.289        1.986         4.724       6.013        21.4%
    peer 2ec7353            2.480        3.821         4.718       7.198        34.5%
    statistics CPU, this tree / peer: 0.520; whole cell: 0.835
    results identical to the bit (every field of every cell): 649 of 649 cells

and every cell of the map (``--stride 1 --rounds 1``, 08:59-09:07 UTC, load average 7.1):

    this tree               9.740        1.878        37.059      46.799        20.8%
    peer 2ec7353           19.460        3.752        38.187      57.648        33.8%
    statistics CPU, this tree / peer: 0.501; whole cell: 0.812; 5187 of 5187 cells identical

Run it as

    python benchmarks/bench_map_stats.py --stride 8 --rounds 3 \\
        --dataset /work/check35c/results/datasets/motion_map_map.nc \\
        --noise /work/check35c/results/noise/harmonic_input.nc
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread, as the jobs

import argparse
import hashlib
import json
from pathlib import Path
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))


# ---------------------------------------------------------------------------- the worker
def worker(job):
    """Run the cells with the kernel's CPU counted apart (this process's ``vibroimpact``)."""
    from vibroimpact.pipeline import cells
    from vibroimpact.pipeline.io import read_noise

    from cell_calls import call

    kernel_cpu = [0.0]
    # the chunk generator the cells call: of a Model since they take one, loose before
    source = "simulate_model_chunks" if hasattr(cells, "simulate_model_chunks") else (
        "simulate_chunks")
    plain = getattr(cells, source)

    def timed(*args, **kwargs):
        gen = plain(*args, **kwargs)
        request = None
        try:
            while True:
                c0 = time.process_time()
                try:
                    chunk = gen.send(request) if request is not None else next(gen)
                finally:
                    kernel_cpu[0] += time.process_time() - c0
                request = yield chunk
        finally:
            gen.close()

    setattr(cells, source, timed)
    noise, dt, _ = read_noise(job["noise"])
    noise = np.asarray(noise[:], dtype=float)
    kw = dict(job["kwargs"])
    kw["motions"] = tuple(tuple(m) for m in kw["motions"])
    call(cells.motion_map_cell, noise, dt, 2.5, -1.0, **dict(kw, max_periods=50))
    total, kernel, digest = [], [], []
    for inv_beta, delta in job["cells"]:
        kernel_cpu[0] = 0.0
        c0 = time.process_time()
        out = call(cells.motion_map_cell, noise, dt, inv_beta, delta, **kw)
        total.append(time.process_time() - c0)
        kernel.append(kernel_cpu[0])
        h = hashlib.sha256()
        for name in sorted(out):
            value = np.asarray(out[name])
            h.update(name.encode() + str(value.dtype).encode() + value.tobytes())
        digest.append(h.hexdigest())
    return dict(total=total, kernel=kernel, digest=digest)


def startup(src, cache):
    """Wall and CPU seconds of a fresh interpreter importing the map job's modules."""
    code = ("import vibroimpact.pipeline.tasks, vibroimpact.pipeline.cells, "
            "vibroimpact.tally" if (Path(src) / "vibroimpact" / "tally").is_dir() else
            "import vibroimpact.pipeline.tasks, vibroimpact.pipeline.cells")
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS="1", NUMBA_CACHE_DIR=cache)
    r0 = os.times()
    w0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], env=env, check=True, cwd=cache)
    wall = time.perf_counter() - w0
    r1 = os.times()
    return wall, (r1.children_user - r0.children_user) + (r1.children_system - r0.children_system)


# ---------------------------------------------------------------------------- the driver
def run_build(src, cache, job):
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS="1", NUMBA_CACHE_DIR=cache)
    proc = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--worker"],
                          input=json.dumps(job), env=env, capture_output=True, text=True,
                          cwd=cache)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr)
        raise SystemExit(f"FAIL: the worker of {src} exited with {proc.returncode}")
    return json.loads(proc.stdout)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dataset", default=str(REPO / "results/datasets/motion_map_map.nc"))
    p.add_argument("--noise", default=str(REPO / "results/noise/harmonic_input.nc"))
    p.add_argument("--main", default="origin/main", help="the peer: the merge base with this")
    p.add_argument("--peer", default=None, help="a revision instead of the merge base")
    p.add_argument("--stride", type=int, default=8, help="every this-many-th cell (default 8)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.worker:
        json.dump(worker(json.load(sys.stdin)), sys.stdout)
        return
    from ab_no_impact import extract
    from bench_map import load_map

    peer = args.peer or subprocess.run(
        ["git", "-C", str(REPO), "merge-base", "HEAD", args.main], check=True,
        capture_output=True, text=True).stdout.strip()
    ds, kw, _ = load_map(args.dataset)
    cells = [(float(b), float(d)) for b in ds.inv_beta.values for d in ds.delta.values]
    cells = cells[:: args.stride]
    kw = {k: (list(map(list, v)) if k == "motions" else v) for k, v in kw.items()}
    job = dict(noise=str(Path(args.noise).resolve()), kwargs=kw, cells=cells)
    print(f"load average {os.getloadavg()} on {os.cpu_count()} CPUs; {len(cells)} cells "
          f"(every {args.stride}th of {args.dataset})")
    with tempfile.TemporaryDirectory() as tmp:
        builds = {"this tree": REPO / "src", f"peer {peer[:7]}": extract(peer, Path(tmp) / "p")}
        caches = {}
        for i, label in enumerate(builds):
            caches[label] = str(Path(tmp) / f"cache{i}")
            os.mkdir(caches[label])
            run_build(builds[label], caches[label], dict(job, cells=cells[:1]))   # compile
        best, starts = {}, {label: [] for label in builds}
        for r in range(args.rounds):
            for label, src in builds.items():
                res = run_build(src, caches[label], job)
                starts[label].append(startup(src, caches[label]))
                stats_cpu = np.subtract(res["total"], res["kernel"])
                if label not in best or stats_cpu.sum() < best[label]["stats"].sum():
                    best[label] = dict(stats=stats_cpu, kernel=np.array(res["kernel"]),
                                       total=np.array(res["total"]), digest=res["digest"])
            print(f"round {r + 1}: load average {os.getloadavg()[0]:.1f}")
    ref = best["this tree"]
    n = len(cells)
    print(f"\n{'build':<16} {'stats CPU s':>12} {'per cell ms':>12} {'kernel CPU s':>13} "
          f"{'cell CPU s':>11} {'stats share':>12} {'start-up s (wall/CPU)':>22}")
    for label, b in best.items():
        wall, cpu = min(s[0] for s in starts[label]), min(s[1] for s in starts[label])
        print(f"{label:<16} {b['stats'].sum():12.3f} {1e3 * b['stats'].sum() / n:12.3f} "
              f"{b['kernel'].sum():13.3f} {b['total'].sum():11.3f} "
              f"{b['stats'].sum() / b['total'].sum():12.1%} {wall:10.2f} / {cpu:.2f}")
    other = [label for label in best if label != "this tree"][0]
    ratio = ref["stats"].sum() / best[other]["stats"].sum()
    whole = ref["total"].sum() / best[other]["total"].sum()
    print(f"statistics CPU, this tree / peer: {ratio:.3f}; whole cell: {whole:.3f}")
    same = sum(a == b for a, b in zip(ref["digest"], best[other]["digest"]))
    print(f"results identical to the bit (every field of every cell): {same} of {n} cells")


if __name__ == "__main__":
    main()
