"""A/B of the no-impact sample step: a git revision of `vibroimpact` against the working tree.

Measures, for two builds of the package in the same run, the cost of `vibroimpact.simulate`
per sample step with no impact reachable, as in benchmarks/bench_simulate.py: one seeded
record of N(0,1) force samples (default 1e7), dt = 0.1, zeta = 0.05, eps = 0.5, delta = 1e6;
and the same with a harmonic term (amplitude = 1, beta = 1.1), since the fast path has a
harmonic branch.

- A = a git revision (--base, default HEAD): `git archive REV src/vibroimpact | tar -x` into
  a temporary directory;
- B = the working tree's src/vibroimpact, uncommitted edits included.

Every measurement runs in a fresh subprocess with PYTHONPATH = the build's `src` (it is
checked there that every `vibroimpact` module comes from that directory, ahead of the
editable install's path), NUMBA_NUM_THREADS = 1, and a NUMBA_CACHE_DIR of its own per build.
The child compiles and warms up with one full call, then times `repeats` calls
(time.perf_counter; time.process_time alongside). Only the public `simulate` is called, so
the harness works whatever the kernels' internal signatures are.

Rounds are interleaved A B, B A, A B, ... to cancel drift on a shared machine. Printed: per
case the median and best ns per step of each build, the ratios B/A, the min-max spread of
each build's per-round medians, the paired per-round ratios, and a verdict; nothing about
time is asserted. The run-to-run spread on this 2-core machine is about 7 %.

Usage::

    python benchmarks/ab_no_impact.py                    # full size, HEAD vs working tree
    python benchmarks/ab_no_impact.py --quick            # 1e6 samples, 2 rounds
    python benchmarks/ab_no_impact.py --base HEAD~3 --rounds 10
"""
import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ZETA, EPS, DT = 0.05, 0.5, 0.1
DELTA_FREE = 1e6  # far beyond any excursion of the response: no impact reachable
SEED = 19740072  # as benchmarks/bench_simulate.py
CASES = {  # name: extra keyword arguments of simulate
    "no impact": {},
    "no impact + harmonic": {"amplitude": 1.0, "beta": 1.1},
}
REPO = Path(__file__).resolve().parent.parent


# ---------------------------------------------------------------------------- child
def child(src, n_samples, repeats, seed):
    """Runs in the subprocess: check the build, time simulate(), print one JSON line."""
    src = Path(src).resolve()
    pkg_dir = src / "vibroimpact"
    t0 = time.perf_counter()
    import numpy as np
    import vibroimpact
    t_import = time.perf_counter() - t0

    def under(path):
        try:
            Path(path).resolve().relative_to(pkg_dir)
            return True
        except ValueError:
            return False

    if not under(vibroimpact.__file__):
        raise SystemExit(f"FAIL: vibroimpact loaded from {vibroimpact.__file__}, expected under "
                         f"{pkg_dir}; sys.path = {sys.path}")
    # other sys.path entries holding a vibroimpact package (e.g. the editable install's src):
    # PYTHONPATH must come first among them
    holders = [p for p in sys.path if (Path(p or ".") / "vibroimpact" / "__init__.py").is_file()]
    if not holders or Path(holders[0] or ".").resolve() != src:
        raise SystemExit(f"FAIL: the first sys.path entry with a vibroimpact package is "
                         f"{holders[:1]}, expected {src}; sys.path = {sys.path}")
    simulate = vibroimpact.simulate
    stray = [f"{name}: {mod.__file__}" for name, mod in sorted(sys.modules.items())
             if name.split(".")[0] == "vibroimpact" and getattr(mod, "__file__", None)
             and not under(mod.__file__)]
    if stray:
        raise SystemExit("FAIL: vibroimpact modules from elsewhere: " + "; ".join(stray))

    import numba
    noise = np.random.default_rng(seed).standard_normal(n_samples + 1)
    shadowed = sorted({str(Path(p or ".").resolve()) for p in holders} - {str(src)})
    out = dict(file=vibroimpact.__file__, shadowed=shadowed,
               numba=numba.__version__, numpy=np.__version__,
               threads=numba.config.NUMBA_NUM_THREADS, import_s=t_import, cases={})
    for name, extra in CASES.items():
        t0 = time.perf_counter()
        res = simulate(zeta=ZETA, eps=EPS, delta=DELTA_FREE, noise=noise, dt=DT, **extra)
        warm = time.perf_counter() - t0
        if res.n_impacts:
            raise SystemExit(f"FAIL: {res.n_impacts} impacts in case {name!r}: not impact-free")
        # the kernels' modules are loaded now
        stray = [f"{n}: {m.__file__}" for n, m in sorted(sys.modules.items())
                 if n.split(".")[0] == "vibroimpact" and getattr(m, "__file__", None)
                 and not under(m.__file__)]
        if stray:
            raise SystemExit("FAIL: vibroimpact modules from elsewhere: " + "; ".join(stray))
        wall, cpu = [], []
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            simulate(zeta=ZETA, eps=EPS, delta=DELTA_FREE, noise=noise, dt=DT, **extra)
            wall.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
        out["cases"][name] = dict(warmup_s=warm, wall=wall, cpu=cpu)
    print(json.dumps(out))


# ---------------------------------------------------------------------------- parent
def git(*args):
    return subprocess.run(["git", "-C", str(REPO), *args], check=True, capture_output=True,
                          text=True).stdout.strip()


def extract(rev, dest):
    """git archive REV src/vibroimpact | tar -x -C dest; returns dest/src."""
    dest.mkdir(parents=True)
    archive = subprocess.Popen(["git", "-C", str(REPO), "archive", "--format=tar", rev,
                                "src/vibroimpact"], stdout=subprocess.PIPE)
    untar = subprocess.run(["tar", "-x", "-C", str(dest)], stdin=archive.stdout)
    archive.stdout.close()
    if archive.wait() != 0 or untar.returncode != 0:
        raise SystemExit(f"FAIL: could not extract src/vibroimpact of {rev!r}")
    src = dest / "src"
    if not (src / "vibroimpact" / "__init__.py").is_file():
        raise SystemExit(f"FAIL: {rev!r} has no src/vibroimpact/__init__.py")
    return src


def run_child(build, n_samples, repeats, seed):
    env = dict(os.environ)
    env.update(PYTHONPATH=str(build["src"]), NUMBA_NUM_THREADS="1",
               NUMBA_CACHE_DIR=str(build["cache"]), PYTHONPYCACHEPREFIX=str(build["pycache"]))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", str(build["src"]),
           "--samples", str(n_samples), "--repeats", str(repeats), "--seed", str(seed)]
    # cwd = the temporary directory: nothing importable as vibroimpact there
    proc = subprocess.run(cmd, env=env, cwd=build["cache"].parent, capture_output=True,
                          text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        raise SystemExit(f"FAIL: child for build {build['label']} exited with "
                         f"{proc.returncode}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def file_hashes(pkg_dir):
    """{relative path: sha1} of the package's files, bytecode excluded: tells whether the
    working tree changed while the A/B ran (the kernel may be edited at the same time)."""
    return {str(f.relative_to(pkg_dir)): hashlib.sha1(f.read_bytes()).hexdigest()
            for f in sorted(Path(pkg_dir).rglob("*"))
            if f.is_file() and "__pycache__" not in f.parts}


def fingerprint(hashes):
    """Short hash of a file_hashes() dict."""
    return hashlib.sha1(json.dumps(hashes, sort_keys=True).encode()).hexdigest()[:12]


def pct(x):
    return f"{100.0 * x:+.1f} %"


def summarize(runs, name, n_steps):
    """Per build: median and best ns/step over all timings, per-round medians."""
    wall = [t for r in runs for t in r["cases"][name]["wall"]]
    cpu = [t for r in runs for t in r["cases"][name]["cpu"]]
    per_round = [statistics.median(r["cases"][name]["wall"]) for r in runs]
    ns = 1e9 / n_steps
    med = statistics.median(wall) * ns
    lo, hi = min(per_round) * ns, max(per_round) * ns
    return dict(median=med, best=min(wall) * ns, lo=lo, hi=hi, spread=(hi - lo) / med,
                cpu_median=statistics.median(cpu) * ns, per_round=[t * ns for t in per_round])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default="HEAD", help="git revision of build A (default HEAD)")
    parser.add_argument("--rounds", type=int, default=None,
                        help="rounds of one A and one B child each (default 6, quick 2)")
    parser.add_argument("--samples", type=float, default=None,
                        help="force samples in the record (default 1e7, quick 1e6)")
    parser.add_argument("--repeats", type=int, default=3, help="timed calls per child")
    parser.add_argument("--quick", action="store_true", help="1e6 samples, 2 rounds")
    parser.add_argument("--seed", type=int, default=SEED, help="seed of the force record")
    parser.add_argument("--child", metavar="SRC", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)

    n_samples = int(args.samples if args.samples is not None
                    else (1e6 if args.quick else 1e7))
    if args.child:
        child(args.child, n_samples, args.repeats, args.seed)
        return
    rounds = args.rounds if args.rounds is not None else (2 if args.quick else 6)
    if rounds < 1 or args.repeats < 1 or n_samples < 1:
        parser.error("--rounds, --repeats and --samples must be positive")

    base_hash = git("rev-parse", "--verify", f"{args.base}^{{commit}}")
    base_desc = git("log", "-1", "--format=%h %s", base_hash)
    head_hash = git("rev-parse", "HEAD")
    dirty = git("status", "--porcelain", "--", "src/vibroimpact").splitlines()
    diff_base = git("diff", "--shortstat", base_hash, "--", "src/vibroimpact")
    b_label = (f"working tree (HEAD {head_hash[:10]}"
               + (f" +dirty: {len(dirty)} path(s) changed or untracked under src/vibroimpact)"
                  if dirty else ", clean)"))
    t_start = time.perf_counter()
    load0 = os.getloadavg()[0]
    print(f"A/B of simulate() with no impact reachable: {n_samples:.3g} N(0,1) samples "
          f"(seed {args.seed}), dt = {DT}, zeta = {ZETA}, eps = {EPS}, delta = {DELTA_FREE:g}; "
          f"{rounds} rounds x {args.repeats} timed calls per build and case, after one warm-up "
          f"call; NUMBA_NUM_THREADS = 1; load average {load0:.1f} on {os.cpu_count()} CPUs")
    print(f"A = {args.base} = {base_hash} ({base_desc})")
    print(f"B = {b_label}")
    print(f"src/vibroimpact, A -> working tree: {diff_base or 'no tracked changes'}"
          + (f"; untracked: {sum(line.startswith('??') for line in dirty)}" if dirty else ""))

    with tempfile.TemporaryDirectory(prefix="ab_no_impact-") as tmp:
        tmp = Path(tmp)
        builds = {}
        for key, src in (("A", None), ("B", REPO / "src")):
            root = tmp / key
            if src is None:
                src = extract(base_hash, root)
            else:
                root.mkdir()
            builds[key] = dict(label=key, src=src, cache=root / "numba_cache",
                               pycache=root / "pycache")
            builds[key]["cache"].mkdir()
        runs = {"A": [], "B": []}
        prints = {"A": [], "B": []}  # fingerprint of each child's build, taken before it ran
        order = []
        for i in range(rounds):
            order += ["A", "B"] if i % 2 == 0 else ["B", "A"]
        for j, key in enumerate(order):
            t0 = time.perf_counter()
            prints[key].append(file_hashes(builds[key]["src"] / "vibroimpact"))
            out = run_child(builds[key], n_samples, args.repeats, args.seed)
            runs[key].append(out)
            if len(runs[key]) == 1:
                print(f"build {key}: vibroimpact from {out['file']}"
                      + (f" (ahead of {', '.join(out['shadowed'])} on sys.path)"
                         if out["shadowed"] else "")
                      + f"; numba {out['numba']}, numpy {out['numpy']}, "
                      f"{out['threads']} numba thread(s); files {fingerprint(prints[key][-1])}")
            meds = ", ".join(f"{statistics.median(c['wall']) * 1e9 / n_samples:.2f}"
                             for c in out["cases"].values())
            warm = max(c["warmup_s"] for c in out["cases"].values())
            print(f"  round {j // 2 + 1} {key}: median ns/step {meds} "
                  f"(import {out['import_s']:.1f} s, slowest warm-up call {warm:.1f} s, "
                  f"child {time.perf_counter() - t0:.1f} s)", flush=True)
        prints["B"].append(file_hashes(builds["B"]["src"] / "vibroimpact"))
    # the temporary directory (build A, both numba caches, bytecode) is removed here
    first, last = prints["B"][0], prints["B"][-1]
    changed = sorted(f for f in first.keys() | last.keys() if first.get(f) != last.get(f))
    if changed:
        print(f"WARNING: the working tree's src/vibroimpact changed during the run (files "
              f"{fingerprint(first)} -> {fingerprint(last)}: {', '.join(changed)}): the B "
              "rounds may not all have measured the same code; run again when the edits have "
              "settled")

    print(f"\n== ns per sample step ({n_samples:.3g} steps; median and best over "
          f"{rounds} x {args.repeats} timed calls; spread = min-max of the per-round medians) ==")
    print(f"{'case':<22} {'A median':>9} {'A best':>7} {'A spread':>20} {'B median':>9} "
          f"{'B best':>7} {'B spread':>20} {'B/A med':>8} {'B/A best':>8}")
    verdicts = []
    for name in CASES:
        a = summarize(runs["A"], name, n_samples)
        b = summarize(runs["B"], name, n_samples)
        r_med, r_best = b["median"] / a["median"], b["best"] / a["best"]
        print(f"{name:<22} {a['median']:>9.2f} {a['best']:>7.2f} "
              f"{a['lo']:>6.2f}-{a['hi']:<6.2f}({a['spread'] * 100:4.1f}%) "
              f"{b['median']:>9.2f} {b['best']:>7.2f} "
              f"{b['lo']:>6.2f}-{b['hi']:<6.2f}({b['spread'] * 100:4.1f}%) "
              f"{r_med:>8.3f} {r_best:>8.3f}")
        paired = [pb / pa for pa, pb in zip(a["per_round"], b["per_round"])]
        noise = max(a["spread"], b["spread"])
        slower = f"B slower in {sum(p > 1.0 for p in paired)} of {len(paired)} paired rounds"
        if r_med - 1.0 <= noise:
            text = ("B no slower than A within the measured spread "
                    f"(B/A medians {r_med:.3f}, {pct(r_med - 1)}; spread {noise * 100:.1f} %; "
                    f"{slower})")
        else:
            text = (f"B slower by {(r_med - 1) * 100:.1f} % (B/A medians {r_med:.3f}, beyond the "
                    f"measured spread {noise * 100:.1f} %; {slower})")
        verdicts.append((name, text, paired, a, b, r_best))
    print("spread (%) = (max - min) / median of the per-round medians; B/A best = ratio of the "
          "fastest single calls")
    print()
    for name, _text, paired, a, b, _r_best in verdicts:
        print(f"{name}: paired per-round B/A {min(paired):.3f} .. {max(paired):.3f} "
              f"(median {statistics.median(paired):.3f}); cpu-time medians "
              f"B/A {b['cpu_median'] / a['cpu_median']:.3f}")
    print("\n== Verdict (B/A of the medians against the larger of the two spreads; nothing "
          "asserted) ==")
    for name, text, *_ in verdicts:
        print(f"{name}: {text}")
    if rounds < 4:
        print(f"({rounds} rounds: the spread is a rough estimate; the full run has 6)")
    if changed:
        print("(B changed during the run: see the WARNING above)")
    print(f"\nA = {base_hash[:10]} ({args.base}), files {fingerprint(prints['A'][0])}; "
          f"B = {b_label}, files {fingerprint(last)}"
          + (" (changed during the run)" if changed else ""))
    print(f"total {time.perf_counter() - t_start:.0f} s; load average {load0:.1f} at start, "
          f"{os.getloadavg()[0]:.1f} at end")


if __name__ == "__main__":
    main()
