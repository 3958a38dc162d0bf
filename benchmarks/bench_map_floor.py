"""The Fig. 15 map job at its floor (issue 37): this tree against named revisions, in one run.

Two measurements, nothing asserted:

1. The map job: every cell of a built map (``--dataset``, default
   ``results/datasets/motion_map_map.nc``) over its noise record (``--noise``), split over
   ``--procs`` processes (default 2, as the workflow runs the map's tiles), each process running
   ``benchmarks/map_cells_cpu.py`` (fresh interpreter, NUMBA_NUM_THREADS = 1, the build's own
   NUMBA_CACHE_DIR, one warm-up cell, then its share of the cells). Builds: this tree's ``src``,
   the merge base with ``--main`` (default ``origin/main``) and the peer ``--peer`` (default
   3091f6a, the revision the issue measured at 36 s), each ``git archive REV src/vibroimpact``
   as ``benchmarks/ab_kernels.py`` does. Printed per build: the wall time of the whole job
   (start-up, compile or cache load, warm-up, cells), the summed CPU time of the cells
   (time.process_time, less disturbed by the neighbours on a shared machine), the ratios to
   this tree, and the largest difference of the stored probabilities to this tree's.
2. The step without impact: ``vibroimpact.simulate`` at delta = 100 (no impact) over a seeded
   N(0,1) record against a closed-form prototype, a minimal numba loop (the 2x2 propagator plus
   the two force terms of a linearly interpolated force per step, nothing else), in turn in one
   process (``--rounds`` alternations, best of each): ns per step and their ratio.

Measured 2026-11-27 01:42-01:48 UTC (load average 5 on 2 cores, shared machine), all 5187
cells of the default build's map, this tree = the merge base f02e60b (no kernel change yet):
this tree 133.6 s wall / 71.0 s cell CPU; merge base 136.6 / 72.8; peer 3091f6a 75.1 / 49.4
(0.69 x the CPU: the issue-33 hop check and two extra grouping rules per cell cost +44 %);
max |dP| to the peer 0.037 (the physical collision rule of issue 33, expected). Step without
impact: simulator 3.97 ns, prototype 4.33 ns (0.92 x; an earlier 2e6-step run gave 1.23 x:
noisy at this load).

0. (``--split STRIDE``) Where a tile's CPU time goes: every STRIDE-th cell in one process under
   cProfile: the kernel, the simulator's driver, the pressed-flight kernel and the per-cell
   statistics; the kernel's time per step without impact and per resolved impact.

Measured 2026-11-27 05:41-05:51 UTC on branch k37 (load average 22-27 on 2 cores: CPU times
inflated by the neighbours, walls meaningless), the default build's map (/work/check35c):

- ``--split 8`` (649 cells, one process): cells 12.99 CPU-s, of which the kernel (run_steps
  and slow_step) 4.65 s = 35.9 %, the rest of the simulator's driver 0.83 s = 6.4 %, the
  pressed-flight kernel of the collision rule 0.82 s = 6.3 %, the per-cell Python/numpy
  statistics 6.66 s = 51.4 %. Kernel: 1.76e8 steps, of which the impact-free part at the
  measured 3.83 ns/step is 0.68 s; the other 3.98 s are the events: 9.88e6 resolved impacts
  in 1.96e6 collisions (5.04 per collision), 403 ns per resolved impact, 2030 ns per
  collision. So a kernel at no cost at all leaves 64 % of the map (about 38 of 60 CPU-s idle,
  19 s wall on 2 cores): the <= 10 s target needs the statistics cut by ~4x as well.
- What a closed-form chatter tail could still save (every 16th cell simulated alone to its
  record_end, fresh compilations with the tolerances of impact.tolerances scaled, best of
  two alternations): RESOLVED_REBOUND x 1e4 alone removes 1.6-4.3 % of the impacts (four
  harmonic cells, 4e5 steps each: it does not bind; the tail is summed once chatter_tail's
  first-order bracket is within CHATTER_TIME_TOL = 1e-7, and by estimate T_hi - T_lo ~
  500 w^2 at F ~ 0.5, so w ~ 1e-5); with
  CHATTER_TIME_TOL x 1e4 too, 5.01e6 -> 3.04e6 impacts (-39 %) saved 2.51 -> 2.11 CPU-s of
  the kernel (-13..-16 %, about 180 ns per rebound not resolved): resolving only the first
  rebound of each of the 3.0e5 chatter sequences (the sample's ~1e6 collisions keeping ~1.3e6
  of its 5.0e6 impacts) would save ~3.7e6 x 180 ns, about 27 % of the kernel and 10 % of the
  map (an estimate: the marginal cost measured on the slowest rebounds), and needs a bracket
  on the onset of order w^5 (a perturbation series of the chatter in w with a proved
  remainder), not the first-order one.
- Where the 2030 ns per collision go (the same 325 cells through a throw-away copy of the
  kernel with counters added to slow_step_one, not kept: counters in the loop cost time):
  for its ~0.99e6 collisions (5.0e6 impacts, 3.0e5 chatter tails, 8.96e7 steps) 3.68e6
  calls of slow_step (4.1 % of the steps), of which 1.10e6 are flights that meet nothing
  (steps within the exclusion bound's reach of the wall) and 3.0e5 start on the wall
  (releases; only 3 170 stay stuck through the step: the cheap stay test of run_steps takes
  the rest), 9.29e6 events walked (segment + search each), 4.64e6 chatter_tail calls. A
  sharper exclusion test would skip some near misses, but a step taken by the recurrence
  instead of segment rounds differently: not bit for bit.
- the map, ``--stride 4 --no-main --peer a13f0b3`` (1297 cells, 2 processes): this tree
  22.16 cell CPU-s, main a13f0b3 22.70 (0.98 x; slow_step_one), max |dP| 0 (bit for bit).
- ``--only-step`` part of the same run: simulator 4.41 ns, prototype 4.45 ns per step (0.99 x).
- the same command again at 05:59-06:03 UTC (load 23-31), the sticking intervals now kept as
  arrays in the driver: this tree 22.91 cell CPU-s, main a13f0b3 23.44 (0.98 x), max |dP| 0;
  the step without impact 4.38 against 5.22 ns (0.84 x: at this load the ratio moves by
  +-0.15 between runs).

3. (``--kernel STRIDE``) The kernel alone: every STRIDE-th cell simulated alone to its
   ``record_end`` (what the map job's kernel computes for it, bit for bit), this tree against
   ``--peer``, one fresh process per build, in turn over ``--rounds`` rounds: the CPU time of
   ``run_steps``, per resolved impact and per collision, and a SHA-256 of every event array
   and end state (equal digests: the two builds agree bit for bit on the map's workload).

Issue 37, session 38 (branch k38): where the kernel's time per collision goes, and what was cut.

- Profile: ``perf record`` on a process that, after the cells, writes ``/tmp/perf-PID.map``
  from the JIT's symbol addresses (``library._get_compiled_object()`` of every overload,
  ``nm -S`` for the sizes, the engine's ``get_function_address``; it needs a fresh
  NUMBA_CACHE_DIR, a library loaded from the cache keeps no object code). It showed that
  LLVM's inliner leaves as calls ``seg_eval`` (9 call sites), ``first_contact``, ``_polish``,
  ``safe_step``, ``_hermite_guess``, ``release_time``, ``chatter_tail`` and the one-wall step
  itself, each passing the 17-slot segment tuple by value; and that the phase of the sample
  point and its libm ``sin``/``cos`` were computed three times per slow step (after the
  previous slow step for ``w``, in run_steps' path to the slow step for ``x``, and in the
  step's first segment). Share of the kernel's samples (649 cells, before): run_steps 29 %
  (the impact-free steps about half of it), seg_eval 20 %, libm sincos 13 %, the one-wall
  step (with segment inlined) 11 %, first_contact 10 %, _polish 8 %, safe_step 3 %,
  _hermite_guess 3 %, release_time 2 %, chatter_tail 1.5 %.
- Cut, bit for bit (``kernel_identity.py`` IDENTICAL against 2ec7353; the event digests of
  ``--kernel`` equal): a slow step at a sample point takes the phase and the libm sin/cos
  that run_steps already holds there (``_slow_step_one``'s ``exact``: one ``phase`` and one
  sincos pair less per slow step, two when slow steps follow each other); ``first_contact``
  inlined into the one-wall step (a twin compiled with numba's ``inline="always"``, the
  generic two-wall step keeps the call) and ``_polish`` into its two callers. Inlining
  ``seg_eval`` and ``safe_step`` as well gained nothing measurable and cost compile time
  (simulate's first call 6.6 -> 8.7 s); the one-wall step compiled with a literal ``exact``
  (two specializations) doubled its compile time: the flag is a run-time bool.
- What one piece costs (a numba loop over 2e6 calls, throughput, best of 5, load 4):
  seg_eval 17.9 ns, segment (with its libm sin+cos) 13.5 ns, phase 5.8 ns, libm sin+cos
  8.0 ns, phase + libm sin/cos 26.0 ns. Per resolved impact (counted in pure Python,
  NUMBA_DISABLE_JIT, on five cells of 2e4 steps: 1/beta, delta = 0.5, 0; 1, -0.5; 2, 0.5;
  2.5, -1; 0.2, -0.9): 1.0-1.2 segments, 3.4-7.1 seg_evals (a safe step from the wall, then
  Halley from a proved bracket; more where flights approach the wall over several steps),
  1.4-6.1 square roots of the safe steps, one polish, 1.4-2.1 phases (before the
  cut): 100-200 ns of arithmetic at throughput, more at the latency of the search's dependent
  chain, plus the bookkeeping; measured 336-349 ns per resolved impact after the cut.
- Why ~300 ns a collision is out of reach bit for bit: with 5.04 resolved impacts per
  collision, 300 ns is 60 ns a rebound, less than the three seg_evals any proved root of this
  search needs. It needs the rebounds not resolved, i.e. the chatter tail summed after the
  first rebound: a bracket on the accumulation point of order w^5 (chatter_tail's is first
  order, ~500 w^2, so the tail waits for w ~ 1e-5 under CHATTER_TIME_TOL = 1e-7; see k37's
  notes above), which moves bits of every later event. Not attempted in this session (no
  proved bracket), so the map's floor stays ~1 impact at ~340 ns + 4 rebounds at ~340 ns.
- Measured 2026-11-27 08:40-09:00 UTC on branch k38 against 2ec7353 (shared machine, load
  average 2.9-7 on 2 cores; other helpers' jobs and this branch's tests running):
  ``--kernel 1 --rounds 1 --peer 2ec7353`` (all 5187 cells, 1.42e9 steps, 7.95e7 resolved
  impacts, 1.59e7 collisions): run_steps 31.10 CPU-s against 34.51 (0.90 x), 391 against
  434 ns per resolved impact, 1960 against 2175 ns per collision (free steps included),
  the event digests equal (bit for bit on the whole map). ``--kernel 8 --rounds 3``: best
  3.905 against 4.286 CPU-s (0.91 x), medians 3.964 / 4.429, digests equal; again after
  merging main at 09:12 UTC (load 8): 3.826 against 4.190 (0.91 x), digests equal.
  ``--split 8`` (one process, this tree and 2ec7353 in turn, twice, load 3.8): kernel 3.92 and
  4.02 s against 4.41 and 4.36 s; less the free steps 336 / 349 ns per resolved impact
  against 390 / 381, 1692 / 1761 ns per collision against 1965 / 1924; the whole cells 7.48 /
  7.55 CPU-s against 8.02 / 7.87 (the statistics, 2.3 s, and hops' pressed flights, 0.75 s,
  unchanged). ``--stride 4 --no-main --peer 2ec7353`` (1297 cells, 2 processes, load 2.9-3.9):
  cell CPU 13.66 against 14.08 s (0.97 x), walls 39.78 / 37.45 s (fresh caches: compilation
  included), max |dP| 0; the step without impact 3.96 ns against the prototype's 4.48
  (0.88 x). ``ab_kernels.py --base 2ec7353 --quick`` (load 3.9-5.6): simulate at delta = -0.5
  (random force only: the inlining, not the phase reuse) 0.947 x CPU best, 0.949 x median;
  delta = +0.5 0.974 / 0.988; periodic_orbits 1.009 / 0.970 (not touched).
- The generic step (two walls: the clearance map and studies) got the same hand-over, and one
  sin/cos pair per event now serves both walls' frames (the lower half of ``P`` shares the
  harmonic phase): 20 two-wall simulate calls (gaps 0.6-2, random, harmonic plus random,
  plastic, partial last step; 3.95e5 impacts), two alternations at 09:03 UTC (load 6):
  0.54 / 0.54 CPU-s against 0.57 / 0.58 for 2ec7353, event digests equal;
  ``kernel_identity.py`` now holds three two-wall cases too (IDENTICAL against 2ec7353).

Usage::

    python benchmarks/bench_map_floor.py --noise results/noise/harmonic_input.nc
    python benchmarks/bench_map_floor.py --stride 4 --no-main     # a quarter of the cells
    python benchmarks/bench_map_floor.py --only-step
    python benchmarks/bench_map_floor.py --split 8 --dataset ... --noise ...
    python benchmarks/bench_map_floor.py --kernel 8 --peer 2ec7353 --rounds 3 --dataset ...
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread, as the jobs

import argparse
import json
from pathlib import Path
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
from ab_no_impact import extract  # noqa: E402  (git archive REV src/vibroimpact)

ZETA, EPS, DT, SEED = 0.05, 0.5, 0.1, 19740072  # as benchmarks/ab_kernels.py


# ---------------------------------------------------------------------------- 1. the map job
def map_job(dataset, noise_path, stride):
    """The cells and the motion_map_cell keywords of a built map (as bench_map.py reads them)."""
    from bench_map import load_map
    ds, kw, _ = load_map(dataset)
    cells = [(float(b), float(d)) for b in ds.inv_beta.values for d in ds.delta.values]
    kw = {k: (list(map(list, v)) if k == "motions" else v) for k, v in kw.items()}
    return cells[::stride], kw


def run_build(label, src, cells, kw, noise_path, procs, tmp):
    """All cells on ``procs`` concurrent processes; returns wall, CPU and probabilities."""
    cache = Path(tmp) / f"cache-{label}"
    cache.mkdir(exist_ok=True)
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS="1",
               NUMBA_CACHE_DIR=str(cache))
    script = str(REPO / "benchmarks" / "map_cells_cpu.py")
    shares = [list(range(i, len(cells), procs)) for i in range(procs)]
    start = time.perf_counter()
    running = []
    for share in shares:
        job = json.dumps(dict(noise=str(noise_path), kwargs=kw, cells=[cells[i] for i in share]))
        p = subprocess.Popen([sys.executable, script], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                             cwd=tmp)
        running.append((share, p, job))
    outs = [(share, p.communicate(job)) + (p.returncode,) for share, p, job in running]
    wall = time.perf_counter() - start
    cpu = np.zeros(len(cells))
    prob = [None] * len(cells)
    for share, (out, err), code in outs:
        if code != 0:
            sys.stderr.write(err)
            raise SystemExit(f"FAIL: build {label} exited with {code}")
        res = json.loads(out)
        for k, i in enumerate(share):
            cpu[i] = res["cpu"][k]
            prob[i] = res["probability"][k]
    return dict(wall=wall, cpu=cpu, prob=np.array(prob, dtype=float))


def merge_base(main):
    return subprocess.run(["git", "-C", str(REPO), "merge-base", "HEAD", main], check=True,
                          capture_output=True, text=True).stdout.strip()


# ---------------------------------------------------------------------------- 0. the split
def split(dataset, noise_path, stride, n_free):
    """Where a tile's CPU time goes: every ``stride``-th cell in this process under cProfile
    (timer time.process_time), the time split between the kernel (``run_steps``, which calls
    ``slow_step`` inside numba), the rest of the simulator's driver (``simulate_chunks`` less
    the kernel), the pressed-flight kernel of the collision rule (``hops._pressed``) and the
    per-cell statistics (everything else); the kernel's own time split between the steps
    without impact (the steps taken, at the ns per step of ``simulate`` at delta = 100,
    measured here) and the events (the rest), per resolved impact and per collision."""
    import cProfile
    import pstats
    from vibroimpact import simulate
    from vibroimpact.pipeline.cells import motion_map_cell
    from vibroimpact.pipeline.io import read_noise

    from cell_calls import call
    cells, kw = map_job(dataset, noise_path, stride)
    noise, dt, _ = read_noise(noise_path)
    noise = np.asarray(noise[:], dtype=float)
    call(motion_map_cell, noise, dt, 2.5, -1.0, **dict(kw, max_periods=50))
    free = noise[: n_free + 1]
    simulate(kw["zeta"], kw["eps"], 100.0, free[:1001], dt)
    ns_free = np.inf
    for _ in range(3):
        c0 = time.process_time()
        simulate(kw["zeta"], kw["eps"], 100.0, free, dt)
        ns_free = min(ns_free, (time.process_time() - c0) / n_free * 1e9)
    prof = cProfile.Profile(time.process_time)
    steps = impacts = collisions = 0
    c0 = time.process_time()
    prof.enable()
    for inv_beta, delta in cells:
        cell = call(motion_map_cell, noise, dt, inv_beta, delta, **kw)
        steps += round(float(cell["simulated_time"]) / dt)
        impacts += int(cell["n_impacts_resolved"])
        collisions += int(cell["n_collisions"])
    prof.disable()
    total = time.process_time() - c0
    st = pstats.Stats(prof).stats      # {(file, line, name): (cc, nc, tottime, cumtime, ...)}

    def cum(name, file_end):
        return sum(v[3] for k, v in st.items() if k[2] == name and k[0].endswith(file_end))
    prof_total = cum("motion_map_cell", "cells.py")
    kernel = cum("run_steps", "stepping.py")
    driver = cum("simulate_chunks", "simulate.py") - kernel
    pressed = cum("_pressed", "hops.py")
    stats_ = prof_total - kernel - driver - pressed
    print(f"\n== 0. Split of {len(cells)} cells (every {stride}th of {dataset}), one process, "
          f"cProfile on CPU time ==")
    print(f"cells CPU {total:.2f} s (under the profiler: {prof_total:.2f} s)")
    for name, t in (("kernel run_steps/slow_step", kernel), ("driver (simulate_chunks)", driver),
                    ("pressed flights (hops)", pressed), ("statistics (Python/numpy)", stats_)):
        print(f"{name:<28} {t:7.2f} s  {t / prof_total:6.1%}")
    free_s = steps * ns_free * 1e-9
    print(f"steps {steps:.3e} (without impact at {ns_free:.2f} ns: {free_s:.2f} s), resolved "
          f"impacts {impacts:.3e}, collisions {collisions:.3e} ({impacts / collisions:.2f} "
          f"impacts per collision)")
    ev = kernel - free_s
    print(f"kernel less the free steps: {ev:.2f} s = {ev / impacts * 1e9:.0f} ns per resolved "
          f"impact, {ev / collisions * 1e9:.0f} ns per collision")


# ---------------------------------------------------------------------------- 3. the kernel
def kernel_child(dataset, noise_path, stride):
    """In a child (the build on PYTHONPATH): every ``stride``-th cell of the map simulated
    alone to its ``record_end`` (what the map job's kernel computes for it, bit for bit), with
    the CPU time of ``run_steps`` (the driver's calls of it, timed around each) and of the
    whole ``simulate`` call, the counts, and a SHA-256 of every event array and end state."""
    import hashlib
    import xarray as xr
    from vibroimpact import simulate
    from vibroimpact.impact import kernels
    from vibroimpact.pipeline.io import read_noise
    ds = xr.open_dataset(dataset).load()
    noise, dt, _ = read_noise(noise_path)
    noise = np.asarray(noise[:], dtype=float)
    zeta, eps, amp = (float(ds.attrs[k]) for k in ("zeta", "eps", "amplitude"))
    cells = [(float(b), float(d), float(ds.record_end.sel(inv_beta=b, delta=d)))
             for b in ds.inv_beta.values for d in ds.delta.values][::stride]
    run_steps, spent = kernels.run_steps, [0.0]

    def timed(*a):
        c0 = time.process_time()
        out = run_steps(*a)
        spent[0] += time.process_time() - c0
        return out
    kernels.run_steps = timed                # the driver calls kernels.run_steps
    simulate(zeta, eps, -1.0, noise=noise[:20001], dt=dt, amplitude=amp, beta=0.4)  # warm
    spent[0] = 0.0
    digest, cpu, impacts, collisions, steps = hashlib.sha256(), 0.0, 0, 0, 0
    for inv_beta, delta, t_end in cells:
        c0 = time.process_time()
        res = simulate(zeta, eps, delta, noise=noise, dt=dt, amplitude=amp, beta=1.0 / inv_beta,
                       t_end=t_end)
        cpu += time.process_time() - c0
        for f in ("impact_step", "impact_offset", "impact_velocity", "stick_start",
                  "stick_end"):
            digest.update(np.ascontiguousarray(getattr(res, f)).tobytes())
        digest.update(np.array([res.x_end, res.v_end, res.contact_time, res.n_chatter]).tobytes())
        impacts += int(res.n_impacts)
        collisions += int(res.n_collisions)
        steps += int(res.n_steps)
    json.dump(dict(cells=len(cells), cpu=cpu, kernel=spent[0], impacts=impacts,
                   collisions=collisions, steps=steps, digest=digest.hexdigest()[:16]),
              sys.stdout)


def kernel_ab(dataset, noise_path, stride, peer, rounds):
    """The kernel alone, this tree against ``peer``, one fresh process per build and round,
    in turn (each build's own NUMBA_CACHE_DIR, compiled before the first round)."""
    with tempfile.TemporaryDirectory() as tmp:
        builds = [("this tree", REPO / "src"), (f"peer {peer}", extract(peer, Path(tmp) / "p"))]
        out = {label: [] for label, _ in builds}
        for r in range(rounds + 1):
            for label, src in (builds if r % 2 == 0 else builds[::-1]):
                env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS="1",
                           NUMBA_CACHE_DIR=str(Path(tmp) / f"cache-{label[:4]}"))
                args = [sys.executable, __file__, "--kernel-child",
                        str(stride if r > 0 else 10**9), "--dataset", dataset, "--noise",
                        noise_path]               # round 0: one cell, to compile
                p = subprocess.run(args, env=env, capture_output=True, text=True)
                if p.returncode != 0:
                    sys.stderr.write(p.stderr)
                    raise SystemExit(f"FAIL: build {label} exited with {p.returncode}")
                if r > 0:                    # round 0 compiles: not timed
                    out[label].append(json.loads(p.stdout))
    ref = out["this tree"][0]
    print(f"\n== 3. The kernel alone: {ref['cells']} cells (every {stride}th) simulated to "
          f"their record_end, {rounds} rounds in turn, one process each ==")
    print(f"{ref['steps']:.3e} steps, {ref['impacts']:.3e} resolved impacts, "
          f"{ref['collisions']:.3e} collisions")
    print(f"{'build':<16} {'run_steps CPU s (best, median)':>31} {'ns/impact':>10} "
          f"{'ns/collision':>13} {'/this':>6}  events digest")
    best_ref = min(o["kernel"] for o in out["this tree"])
    for label, runs in out.items():
        k = sorted(o["kernel"] for o in runs)
        o = runs[0]
        same = all(x["digest"] == ref["digest"] for x in runs)
        print(f"{label:<16} {k[0]:15.3f} {np.median(k):15.3f} "
              f"{k[0] / o['impacts'] * 1e9:10.0f} {k[0] / o['collisions'] * 1e9:13.0f} "
              f"{k[0] / best_ref:6.3f}  {o['digest']}{'' if same else ' (varies!)'}")
    print("bit for bit on these cells" if all(
        o["digest"] == ref["digest"] for runs in out.values() for o in runs)
        else "DIFFERENT events")


# ---------------------------------------------------------------------------- 2. the step
def prototype_kernel():
    """A minimal numba loop: x_{k+1} = A x_k + g0 f_k + g1 f_{k+1}, nothing else."""
    import numba

    @numba.njit(cache=False)
    def run(a, g0, g1, f):
        x, v = 0.0, 0.0
        acc = 0.0
        for k in range(f.size - 1):
            x, v = (a[0, 0] * x + a[0, 1] * v + g0[0] * f[k] + g1[0] * f[k + 1],
                    a[1, 0] * x + a[1, 1] * v + g0[1] * f[k] + g1[1] * f[k + 1])
            acc += x
        return acc
    return run


def propagator(zeta, dt):
    """A and the force vectors of x'' + 2 zeta x' + x = f(t), f linear over a step: the
    exponential of the augmented matrix (state, f, f')."""
    from scipy.linalg import expm
    m = np.zeros((4, 4))
    m[0, 1], m[1, 0], m[1, 1], m[1, 2], m[2, 3] = 1.0, -1.0, -2.0 * zeta, 1.0, 1.0 / dt
    e = expm(m * dt)
    a = e[:2, :2].copy()
    g1 = e[:2, 3].copy()                  # response to the ramp f_{k+1} - f_k
    g0 = e[:2, 2].copy() - g1             # response to f_k (constant minus ramp)
    return a, g0, g1


def step_ratio(n_steps, rounds):
    from vibroimpact import simulate
    noise = np.random.default_rng(SEED).standard_normal(n_steps + 1)
    a, g0, g1 = propagator(ZETA, DT)
    proto = prototype_kernel()
    proto(a, g0, g1, noise[:100])
    simulate(ZETA, EPS, 100.0, noise[:1001], DT)
    best = dict(simulator=np.inf, prototype=np.inf)
    for _ in range(rounds):
        for name, fn in (("simulator", lambda: simulate(ZETA, EPS, 100.0, noise, DT)),
                         ("prototype", lambda: proto(a, g0, g1, noise))):
            c0 = time.process_time()
            fn()
            best[name] = min(best[name], time.process_time() - c0)
    ns = {k: v / n_steps * 1e9 for k, v in best.items()}
    print(f"\n== 2. Step without impact, delta = 100, {n_steps:.0e} steps, best of {rounds} "
          f"alternations (CPU) ==")
    for k, v in ns.items():
        print(f"{k:<10} {v:6.2f} ns/step")
    print(f"ratio simulator / prototype: {ns['simulator'] / ns['prototype']:.2f}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dataset", default=str(REPO / "results/datasets/motion_map_map.nc"))
    p.add_argument("--noise", default=str(REPO / "results/noise/harmonic_input.nc"))
    p.add_argument("--peer", default="3091f6a")
    p.add_argument("--main", default="origin/main")
    p.add_argument("--no-main", action="store_true", help="skip the merge base")
    p.add_argument("--procs", type=int, default=2)
    p.add_argument("--stride", type=int, default=1, help="every this-many-th cell (default all)")
    p.add_argument("--steps", type=float, default=2e7)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--only-step", action="store_true")
    p.add_argument("--split", type=int, default=0, metavar="STRIDE",
                   help="only the split of a tile's time, over every STRIDE-th cell")
    p.add_argument("--kernel", type=int, default=0, metavar="STRIDE",
                   help="only the kernel alone on every STRIDE-th cell, this tree vs --peer")
    p.add_argument("--kernel-child", type=int, default=0, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.kernel_child:
        kernel_child(args.dataset, args.noise, args.kernel_child)
        return
    print(f"load average {os.getloadavg()} on {os.cpu_count()} CPUs")
    if args.kernel:
        kernel_ab(args.dataset, args.noise, args.kernel, args.peer, args.rounds)
        print(f"load average {os.getloadavg()} at the end")
        return
    if args.split:
        split(args.dataset, args.noise, args.split, int(2e6))
        return
    if not args.only_step:
        cells, kw = map_job(args.dataset, args.noise, args.stride)
        print(f"\n== 1. The map job: {len(cells)} cells of {args.dataset} on {args.procs} "
              f"processes ==")
        with tempfile.TemporaryDirectory() as tmp:
            builds = [("this tree", REPO / "src")]
            if not args.no_main:
                base = merge_base(args.main)
                builds.append((f"merge base {base[:7]}",
                               extract(base, Path(tmp) / "base")))
            builds.append((f"peer {args.peer}", extract(args.peer, Path(tmp) / "peer")))
            res = {label: run_build(f"b{i}", src, cells, kw, args.noise, args.procs, tmp)
                   for i, (label, src) in enumerate(builds)}
        ref = res["this tree"]
        print(f"{'build':<22} {'wall s':>8} {'cell CPU s':>11} {'wall/this':>10} "
              f"{'CPU/this':>9} {'max |dP| vs this':>17}")
        for label, r in res.items():
            dp = np.nanmax(np.abs(r["prob"] - ref["prob"]))
            print(f"{label:<22} {r['wall']:8.2f} {r['cpu'].sum():11.2f} "
                  f"{r['wall'] / ref['wall']:10.2f} {r['cpu'].sum() / ref['cpu'].sum():9.2f} "
                  f"{dp:17.3g}")
    step_ratio(int(args.steps), args.rounds)


if __name__ == "__main__":
    main()
