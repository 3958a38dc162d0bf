"""Import time of each kind of workflow job against the interpreter's floor, same run.

A job is a fresh interpreter: its start-up and imports are paid once per job, 70-odd times
in a build of the default config. For each script under ``workflow/scripts`` (and for
``import vibroimpact.plotting``) this times, in a fresh ``python -c``, the script's
module-level imports (``imports``) and those plus what its task imports inside the function
when it runs (``job``, the table `RUNS`); the best of ``--rounds`` wall times, and of CPU
times (user + system of the interpreter: what a busy machine inflates least), rounds
interleaved so that a load on the machine hits every row alike. The floors, timed the same
way: a bare interpreter, numpy + matplotlib (Agg, pyplot), numpy + xarray. Each row gives
the seconds, the ratios to the floors, and which heavy modules (numba, scipy, xarray,
matplotlib) the job loads. With ``--peer REV`` the same rows of another git revision
(a worktree, its own scripts on its own ``PYTHONPATH``) are timed in the same rounds.

    python benchmarks/imports.py --rounds 5 --peer ee3372a
"""
import argparse
import ast
import os
from pathlib import Path
import resource
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "scipy", "xarray", "matplotlib")

FLOORS = {
    "bare python": "pass",
    "numpy + matplotlib": "import numpy, matplotlib; matplotlib.use('Agg'); "
                          "import matplotlib.pyplot",
    "numpy + xarray": "import numpy, xarray",
}

#: What a script's task imports inside its function when it runs (`pipeline.tasks`): the
#: random study's events aggregation reads the noise spectrum and integrates the wall-free
#: response (`stats.theory`); a figure imports plotting (fig09's t quantile: scipy.special).
RUNS = {
    "draw_figure": ["vibroimpact.plotting"],
    "aggregate_events": ["vibroimpact.noise", "vibroimpact.stats.theory"],
    "aggregate_spectra": ["vibroimpact.noise"],
    "simulate_events": ["vibroimpact.pipeline.cells"],
    "simulate_map": ["vibroimpact.pipeline.cells"],
    "simulate_spectra": ["vibroimpact.pipeline.cells"],
    "simulate_trace": ["vibroimpact.pipeline.cells"],
    "generate_noise": ["vibroimpact.noise"],
    "solve_orbit_tile": ["numba", "vibroimpact.orbits"],
}

_REPORT = ("\nimport sys; print(' '.join(m for m in %r if m in sys.modules))" % (HEAVY,))


def script_imports(path):
    """The module-level import statements of a workflow script, as source."""
    tree = ast.parse(Path(path).read_text())
    return "\n".join(ast.unparse(node) for node in tree.body
                     if isinstance(node, (ast.Import, ast.ImportFrom)))


def rows(root):
    """``{row name: code}`` of the job kinds of the tree at ``root``."""
    out = {}
    for script in sorted((root / "workflow" / "scripts").glob("*.py")):
        code = script_imports(script)
        out[f"{script.stem} imports"] = code
        if script.stem in RUNS:
            out[f"{script.stem} job"] = "\n".join([code] + [f"import {m}"
                                                            for m in RUNS[script.stem]])
    out["vibroimpact.plotting"] = "import vibroimpact.plotting"
    return out


def _children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run(code, src=None):
    """Wall and CPU time (s) of a fresh ``python -c code``, and the heavy modules it loaded."""
    env = {**os.environ, "PYTHONPATH": str(src)} if src else dict(os.environ)
    env["MPLBACKEND"] = "Agg"
    cpu, start = _children_cpu(), time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code + _REPORT], env=env, capture_output=True,
                         text=True, cwd=ROOT)
    seconds, cpu = time.perf_counter() - start, _children_cpu() - cpu
    if out.returncode != 0:
        raise RuntimeError(f"{code!r} failed:\n{out.stderr[-2000:]}")
    return (seconds, cpu), out.stdout.split()


def measure(sides, rounds):
    """Best (wall, CPU) times and heavy modules of every row of every side, rounds
    interleaved."""
    jobs = [(None, name, code, None) for name, code in FLOORS.items()]
    for side, root in sides.items():
        jobs += [(side, name, code, root / "src") for name, code in rows(root).items()]
    best, heavy = {}, {}
    for _ in range(rounds):
        for side, name, code, src in jobs:
            times, loaded = run(code, src)
            old = best.get((side, name), (float("inf"),) * 2)
            best[side, name] = tuple(map(min, times, old))
            heavy[side, name] = loaded
    return best, heavy


def report(best, heavy, sides):
    for k, clock in enumerate(("wall", "CPU")):
        floors = {name: best[None, name][k] for name in FLOORS}
        print(f"\n{clock} time, floors: "
              + ", ".join(f"{name} {s:.3f} s" for name, s in floors.items()))
        names = list(rows(next(iter(sides.values()))))
        for side in sides:
            print(f"{side}")
            print(f"  {'row':32s} {'s':>6s} {'/bare':>6s} {'/np+mpl':>8s} {'/np+xr':>7s}  heavy")
            for name in names:
                if (side, name) not in best:
                    continue
                s = best[side, name][k]
                ratios = [s / floors[f] for f in FLOORS]
                print(f"  {name:32s} {s:6.3f} {ratios[0]:6.2f} {ratios[1]:8.2f} "
                      f"{ratios[2]:7.2f}  {' '.join(heavy[side, name]) or '-'}")
        mpl = floors["numpy + matplotlib"]
        for side in sides:
            s = best[side, "vibroimpact.plotting"][k]
            print(f"{side}: import vibroimpact.plotting {s:.3f} s {clock}, {s - mpl:+.3f} s over "
                  f"numpy + matplotlib (target: within 0.2 s)")
        if len(sides) == 2:
            now, peer = sides
            print(f"  {'row':32s} {now[:12]:>12s} {peer[:12]:>12s} {'ratio':>6s}")
            for name in names:
                if (now, name) in best and (peer, name) in best:
                    a, b = best[now, name][k], best[peer, name][k]
                    print(f"  {name:32s} {a:12.3f} {b:12.3f} {a / b:6.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--peer", help="a git revision to time in the same rounds")
    args = parser.parse_args()
    sides = {"this tree": ROOT}
    with tempfile.TemporaryDirectory() as tmp:
        if args.peer:
            where = Path(tmp) / "peer"
            subprocess.run(["git", "worktree", "add", "-f", "--detach", str(where), args.peer],
                           cwd=ROOT, check=True, capture_output=True)
            sides[f"peer {args.peer}"] = where
        try:
            best, heavy = measure(sides, args.rounds)
        finally:
            if args.peer:
                subprocess.run(["git", "worktree", "remove", "--force", str(where)], cwd=ROOT,
                               capture_output=True)
    print(f"python {sys.version.split()[0]}, best of {args.rounds} fresh interpreters, "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}")
    report(best, heavy, sides)


if __name__ == "__main__":
    main()
