"""The default build's figures drawn three ways, in turn, in one run: CPU and wall of each.

1. ``fresh``: one fresh Python process a figure, as a ``script:`` job (Snakemake's preamble
   imports, then ``workflow/scripts/draw_figure.py``'s imports and its drawing);
2. ``forks``: one process that warms up once and forks for each figure
   (`vibroimpact.pipeline.forked.run_script`: what the figure server in Snakemake's process
   does for each figure job, without the job's client, ~0.1 CPU-s), its warm-up counted;
3. ``owner``: one process per owner (study or orbits entry) drawing all its figures in turn
   (a batched rule; loses the one-figure rebuild scope, measured for comparison only).

The figures, their inputs and options are read from the job logs of a built default tree
(``--root``, default this one); the figures are drawn into a scratch folder and, for
``forks``, compared byte for byte with the tree's own. Sequential, one figure at a time: the
CPU sums are the steady figures, wall on a shared machine measures the machine.

    python benchmarks/figure_start.py --rounds 3
"""
import argparse
import ast
import os
from pathlib import Path
import re
import resource
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
OWNERS = ("random", "harmonic", "motion_map", "orbits/harmonic")
PREAMBLE = ("from snakemake.logging import logger\n"
            "from snakemake.iocontainers import Snakemake\n")


def figures(root):
    """``{owner: [(fig, inputs, options), ...]}`` from the draw_figure job logs."""
    found = {}
    logs = root / "results" / "logs" / "draw_figure"
    for log in sorted(logs.rglob("*.log")):
        owner = log.parent.relative_to(logs).as_posix()
        match = re.search(r"drawing (\S+) from (\[.*?\]) with (\{.*\})", log.read_text())
        if owner in OWNERS and match:
            found.setdefault(owner, []).append(
                (match.group(1), ast.literal_eval(match.group(2)),
                 ast.literal_eval(match.group(3))))
    return found


def _draw(items, out):
    return "".join(f"tasks.figure({fig!r}, {inputs!r}, {str(out / owner / fig) + '.png'!r}, "
                   f"{options!r})\n" for owner, fig, inputs, options in items)


def commands(found, out):
    """The three ways, each a list of commands run one after another."""
    items = [(owner, *f) for owner, figs in found.items() for f in figs]
    head = PREAMBLE + "from vibroimpact.pipeline import tasks\n"
    fresh = [[sys.executable, "-c", head + _draw([item], out / "fresh")] for item in items]
    owner = [[sys.executable, "-c", head + _draw([i for i in items if i[0] == o], out / "owner")]
             for o in found]
    jobs = []
    for o, fig, inputs, options in items:
        png = out / "forks" / o / f"{fig}.png"
        jobs.append((str(png), fig, inputs, options))
    forks = [[sys.executable, "-c", PREAMBLE + (
        "import tempfile\n"
        "from pathlib import Path\n"
        "from types import SimpleNamespace as N\n"
        "from vibroimpact.pipeline import forked\n"
        f"script = Path({str(ROOT / 'workflow' / 'scripts' / 'draw_figure.py')!r})\n"
        "log = tempfile.mktemp(suffix='.log')\n"
        f"for png, fig, inputs, options in {jobs!r}:\n"
        "    Path(png).parent.mkdir(parents=True, exist_ok=True)\n"
        "    forked.run_script(script, N(input=inputs, output=N(png=png), log=[log],\n"
        "        params=N(options=options), wildcards=N(fig=fig)))\n")]]
    return {"fresh": fresh, "forks": forks, "owner": owner}


def run(cmds, cwd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    for cmd in cmds:
        subprocess.run(cmd, cwd=cwd, check=True, capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (time.perf_counter() - start,
            after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", type=Path, default=ROOT, help="a built default tree")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args(argv)
    found = figures(args.root)
    n = sum(map(len, found.values()))
    if not n:
        raise SystemExit(f"no draw_figure logs under {args.root}/results/logs: build first")
    with tempfile.TemporaryDirectory(prefix="figure_start-") as tmp:
        ways = commands(found, Path(tmp))
        print(f"{n} figures of {len(found)} owners; {os.getloadavg()[0]:.1f} load")
        times = {way: [] for way in ways}
        for r in range(args.rounds):
            order = list(ways) if r % 2 == 0 else list(reversed(ways))
            for way in order:
                times[way].append(run(ways[way], args.root))
                wall, cpu = times[way][-1]
                print(f"round {r + 1} {way:6s} wall {wall:6.1f} s  CPU {cpu:6.1f} s  "
                      f"(load {os.getloadavg()[0]:.1f})", flush=True)
        differ = [str(p.relative_to(Path(tmp) / "forks")) for p in (Path(tmp) / "forks").rglob(
            "*.p[nd][gf]") if p.read_bytes() != (args.root / "results" / "figures" / p.relative_to(
                Path(tmp) / "forks")).read_bytes()]
    print("median of the rounds, per figure:")
    for way, rows in times.items():
        wall = sorted(w for w, _ in rows)[len(rows) // 2]
        cpu = sorted(c for _, c in rows)[len(rows) // 2]
        print(f"  {way:6s} wall {wall:6.1f} s  CPU {cpu:6.1f} s  ({cpu / n:.2f} CPU-s a figure)")
    print(f"forks' figures identical to the tree's: {2 * n - len(differ)} of {2 * n}"
          + (f"; differ: {differ}" if differ else ""))


if __name__ == "__main__":
    main()
