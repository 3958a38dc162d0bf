"""Job costs: the test config's job kinds against a peer, the default build's report and figure
jobs against a peer (issue 37: none above 5 s), and the plan's per-rule CPU against measured
benchmark files (issue 37: within 25 %).

1. Default (no mode flag): one job of each kind on the test config, ``snakemake --force
   <target>`` minus the same dry run (DAG building), median of ``--rounds``, this tree against
   ``--peer`` in the same run::

       python benchmarks/job_costs.py --peer 33a035a --rounds 3

2. ``--jobs``: the default config's report and figure jobs (every ``report``, ``draw_figure``
   and ``draw_validation_figure`` benchmark file of ``--results``, a built default tree), each
   forced alone (``snakemake --cores 1 --force --rerun-triggers mtime <target>``) in this
   tree's copy and in a ``git worktree`` of ``--peer``, both holding a copy of ``--results``;
   the sides alternate job by job (peer first in odd rounds). Per job the best of the rounds
   of the job's own benchmark file (``s``: wall, ``cpu_time``), this/peer, and the jobs above
   ``--limit`` (5 s). A report job (a ``shell:`` rule) runs its shell command by itself
   instead, taken from a dry run: its wall time and the CPU of every process it waited for
   (the notebook's kernel too; Snakemake's sampled ``cpu_time`` misses a short-lived
   child)::

       python benchmarks/job_costs.py --jobs --peer 15acb54 --results /work/check35c/results
       python benchmarks/job_costs.py --jobs --only report --rounds 2 ...

3. ``--plan``: the plan (``make plan``'s cost model, `Plan.rule_costs`) of the default config
   per rule, jobs and CPU seconds, against the benchmark files of a built tree (``--results``,
   default ``results``): the summed ``cpu_time`` of the rule's jobs (the whole machine's
   ``s`` for the validation rules, which hold every core), their ratio, and whether it is
   within ``--tolerance`` (25 %). Exit status 1 when a rule is outside::

       python benchmarks/job_costs.py --plan --results /work/check35c/results --cold-cache

   ``--cold-cache``: the build's jobs compiled numba's kernels (15acb54's did; since 15572b0
   `make` compiles them when it installs), and the plan adds `costs.COMPILE_S`.
"""
import argparse
import csv
from collections import defaultdict
import os
import resource
from pathlib import Path
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = Path(__file__).resolve().parents[1]
# the tests' copy of the working tree (one function for both); a script, so not on the path
sys.path.insert(0, str(ROOT / "tests"))
from helpers import SNAKEMAKE, copy_tree  # noqa: E402

# kind -> target (fig16's path depends on the revision)
JOBS = {
    "figure (fig07)": "results/figures/random/fig07.png",
    "figure (fig16)": "{fig16}",
    "aggregate events": "results/datasets/random_events.nc",
    "simulate events tile": "results/cells/random/events/0.nc",
}
#: The rules whose jobs issue 37 holds under 5 s wall (`--jobs`).
SHORT_RULES = ("report", "draw_figure", "draw_validation_figure", "map_predictors")


def _checkout(rev, where):
    subprocess.run(["git", "worktree", "add", "-f", "--detach", str(where), rev], cwd=ROOT,
                   check=True, capture_output=True)


def _run(workdir, *args, config="config/test.yaml", cores=1):
    env = {**os.environ, "PYTHONPATH": str(workdir / "src")}
    start = time.perf_counter()
    configs = ["--configfile", config] if config else []     # None: the default config
    out = subprocess.run([SNAKEMAKE, "--cores", str(cores), *configs, "-q",
                          "--rerun-triggers", "mtime", *args], cwd=workdir, env=env,
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stdout[-2000:] + out.stderr[-2000:])
    return time.perf_counter() - start


def job_cost(workdir, target):
    full = _run(workdir, "--force", target)
    dry = _run(workdir, "-n", target)
    return full - dry


def _uptime():
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


# --- benchmark files ------------------------------------------------------------------------

def benchmark_rows(results):
    """``{relative path: (s, cpu_time)}`` of every benchmark file under ``results/benchmarks``
    (its last row: a file holds one row a run)."""
    rows = {}
    base = Path(results) / "benchmarks"
    for path in sorted(base.rglob("*.tsv")):
        with path.open() as f:
            last = list(csv.DictReader(f, delimiter="\t"))[-1]
        cpu = last.get("cpu_time", "NA")
        rows[str(path.relative_to(base))] = (float(last["s"]), float(cpu) if cpu not in
                                             ("", "NA", "-") else float("nan"))
    return rows


def rule_of(relpath):
    """The rule of a benchmark file: its first folder (``benchmarks/<rule>.tsv``: the name)."""
    parts = Path(relpath).parts
    return parts[0] if len(parts) > 1 else Path(relpath).stem


def target_of(relpath):
    """The output a report or figure job's benchmark file stands for (``--jobs``)."""
    parts = Path(relpath).with_suffix("").parts
    rule, rest = parts[0], parts[1:]
    if rule == "draw_figure":
        return "results/figures/" + "/".join(rest) + ".png"
    if rule == "draw_validation_figure":
        return f"results/figures/{rest[0]}.png"
    if rule == "map_predictors":
        return f"results/datasets/{rest[0]}_predictors.nc"
    if rule == "report" and rest[0] == "orbits":
        return f"results/reports/orbits/{rest[1]}/periodic_motions.html"
    if rule == "report":
        return "results/reports/" + "/".join(rest) + ".html"
    raise ValueError(f"{relpath}: not a report or figure job")


# --- mode 2: the default build's report and figure jobs, this tree against a peer ------------

def _forced(workdir, target):
    """``(s, cpu_time)`` of the job making ``target``, forced alone, from its benchmark file."""
    bench = workdir / "results" / "benchmarks"
    before = benchmark_rows(workdir / "results")
    _run(workdir, "--force", target, config=None)
    after = benchmark_rows(workdir / "results")
    changed = [k for k in after if k not in before or after[k] != before[k]]
    if len(changed) != 1:
        raise RuntimeError(f"{target}: {len(changed)} benchmark files changed under {bench}")
    return after[changed[0]]


def _shell_command(workdir, target):
    """The shell command of the job making ``target`` (a ``shell:`` rule), from a dry run."""
    env = {**os.environ, "PYTHONPATH": str(workdir / "src")}
    out = subprocess.run([SNAKEMAKE, "--cores", "1", "-n", "-p", "--force", "--rerun-triggers",
                          "mtime", "--", target], cwd=workdir, env=env, capture_output=True,
                         text=True)
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("Shell command: ")]
    if out.returncode or len(lines) != 1:
        raise RuntimeError(f"{target}: no single shell command\n{out.stdout[-2000:]}")
    return lines[0][len("Shell command: "):]


def _direct(workdir, command):
    """``(wall s, CPU s)`` of a job's shell command run by itself (no Snakemake around it):
    the CPU of every process it waited for (``RUSAGE_CHILDREN``: the report's kernel too)."""
    env = {**os.environ, "PYTHONPATH": str(workdir / "src")}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(["bash", "-c", command], cwd=workdir, env=env, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _has_rule(workdir, rule):
    """Whether the workflow of ``workdir`` has rule ``rule`` (a peer from before it has
    not; a report is one of three rules, all benchmarked under ``report``)."""
    if rule == "report":
        return True
    return any(f"rule {rule}:" in p.read_text()
               for p in (workdir / "workflow" / "rules").glob("*.smk"))


def _complete(workdir, jobs):
    """Build, by modification times only, what the jobs' targets miss in ``workdir``'s copy
    of ``--results`` (a dataset of a rule the built tree's revision had not, such as
    ``map_predictors``' for this tree's reports against a tree built before it)."""
    wanted = [target_of(job) for job in jobs if _has_rule(workdir, rule_of(job))]
    _run(workdir, "--", *wanted, config=None, cores=2)


def jobs_mode(args):
    reference = benchmark_rows(args.results)
    only = tuple(args.only.split(",")) if args.only else SHORT_RULES
    jobs = sorted(k for k in reference if rule_of(k) in only)
    tmp = Path(tempfile.mkdtemp(prefix="job_costs-"))
    sides = {"this": tmp / "this", "peer": tmp / "peer"}
    try:
        copy_tree(sides["this"])
        _checkout(args.peer, sides["peer"])
        for workdir in sides.values():
            shutil.copytree(args.results, workdir / "results", symlinks=True)
            _complete(workdir, jobs)
        print(f"job_costs --jobs: {len(jobs)} jobs of {args.results}, this tree against peer "
              f"{args.peer}, {args.rounds} round(s); {_uptime()}", flush=True)
        best = {side: {} for side in sides}
        commands = {}
        for i in range(args.rounds):
            for job in jobs:
                for side in (sides if i % 2 else reversed(list(sides))):
                    if not _has_rule(sides[side], rule_of(job)):     # a peer before it
                        best[side][job] = (float("nan"), float("nan"))
                        continue
                    if rule_of(job) == "report":      # a shell: rule, run by itself
                        key = (side, job)
                        if key not in commands:
                            commands[key] = _shell_command(sides[side], target_of(job))
                        s, cpu = _direct(sides[side], commands[key])
                    else:
                        s, cpu = _forced(sides[side], target_of(job))
                    old = best[side].get(job, (float("inf"), float("inf")))
                    best[side][job] = (min(old[0], s), min(old[1], cpu))
        print(f"done; {_uptime()}")
        print(f"{'job (benchmark file)':52s} {'this s':>7s} {'cpu':>6s} {'peer s':>7s} "
              f"{'cpu':>6s} {'s ratio':>7s}")
        for job in jobs:
            (s, c), (ps, pc) = best["this"][job], best["peer"][job]
            flag = f"  > {args.limit:g} s" if s > args.limit else ""
            if ps != ps:                                # NaN: the peer has no such rule
                print(f"{job:52s} {s:7.2f} {c:6.2f} {'-':>7s} {'-':>6s} {'-':>7s}{flag}")
                continue
            print(f"{job:52s} {s:7.2f} {c:6.2f} {ps:7.2f} {pc:6.2f} {s / ps:7.2f}{flag}")
        for side in sides:
            ran = {k: v for k, v in best[side].items() if v[0] == v[0]}
            if not ran:
                print(f"{side}: none of these jobs (no such rule)")
                continue
            worst = max(ran.items(), key=lambda kv: kv[1][0])
            print(f"{side}: {len(ran)} jobs, {sum(v[0] for v in ran.values()):.1f} s wall "
                  f"({sum(v[1] for v in ran.values()):.1f} CPU-s) in all, the dearest "
                  f"{worst[0]} {worst[1][0]:.2f} s; "
                  f"{sum(v[0] > args.limit for v in ran.values())} above {args.limit:g} s")
    finally:
        subprocess.run(["git", "worktree", "remove", "--force", str(sides["peer"])], cwd=ROOT,
                       capture_output=True)
        shutil.rmtree(tmp, ignore_errors=True)


# --- mode 3: the plan against benchmark files ------------------------------------------------

def plan_comparison(results, configfile="config/config.yaml", cold_cache=False):
    """``[(rule, planned jobs, measured jobs, planned CPU-s, measured CPU-s)]`` per rule of the
    plan of ``configfile`` against the benchmark files under ``results`` (``cold_cache``: a
    build whose jobs compiled numba's kernels, `Plan.rule_costs`)."""
    from vibroimpact.pipeline import config
    from vibroimpact.pipeline.config.plan import WHOLE_MACHINE_RULES

    user = [] if Path(configfile) == Path("config/config.yaml") else [configfile]
    _, plan = config.load(root=ROOT, user_files=user)
    measured = defaultdict(lambda: [0, 0.0])
    for path, (s, cpu) in benchmark_rows(results).items():
        rule = rule_of(path)
        measured[rule][0] += 1
        # cpu_time, sampled by Snakemake, reads 0 for a job shorter than its first sample:
        # then its wall time; wall time too for the rules that hold every core
        whole = rule in WHOLE_MACHINE_RULES or not cpu > 0.1
        measured[rule][1] += s if whole else cpu
    planned = plan.rule_costs(cold_cache=cold_cache)
    return [(rule, planned.get(rule, (0, 0.0))[0], measured[rule][0],
             planned.get(rule, (0, 0.0))[1], measured[rule][1])
            for rule in sorted(set(planned) | set(measured))]


def plan_mode(args):
    rows = plan_comparison(args.results, args.configfile, args.cold_cache)
    print(f"plan ({args.configfile}) against the benchmark files of {args.results}: CPU "
          f"seconds per rule (cpu_time summed; wall s for the rules holding every core and "
          f"for a job whose cpu_time reads 0)")
    print(f"{'rule':26s} {'jobs plan':>9s} {'measured':>8s} {'CPU-s plan':>10s} "
          f"{'measured':>9s} {'plan/meas.':>10s}")
    outside = 0
    for rule, pj, mj, pc, mc in rows:
        if not mj and not pc:           # a local rule's copies: no benchmark file, no cost
            print(f"{rule:26s} {pj:9d} {'-':>8s} {pc:10.1f} {'-':>9s} {'-':>10s}  "
                  f"(no benchmark files)")
            continue
        ratio = pc / mc if mc else float("inf")
        ok = abs(ratio - 1.0) <= args.tolerance and pj == mj
        outside += not ok
        print(f"{rule:26s} {pj:9d} {mj:8d} {pc:10.1f} {mc:9.1f} {ratio:10.2f}"
              + ("" if ok else "  OUTSIDE"))
    total_p, total_m = sum(r[3] for r in rows), sum(r[4] for r in rows)
    print(f"{'total':26s} {sum(r[1] for r in rows):9d} {sum(r[2] for r in rows):8d} "
          f"{total_p:10.1f} {total_m:9.1f} {total_p / total_m:10.2f}")
    print(f"{len(rows) - outside} of {len(rows)} rules within {100 * args.tolerance:g} % "
          f"(and the same number of jobs)")
    return 1 if outside else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--peer", default="33a035a", help="git revision to compare against")
    parser.add_argument("--rounds", type=int, default=3)
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--jobs", action="store_true", help="the default build's report and "
                      "figure jobs, this tree against --peer")
    mode.add_argument("--plan", action="store_true", help="the plan's per-rule CPU against "
                      "the benchmark files of --results")
    parser.add_argument("--results", default=str(ROOT / "results"),
                        help="a built default tree's results folder")
    parser.add_argument("--configfile", default="config/config.yaml")
    parser.add_argument("--only", help="--jobs: comma-separated rules (default: "
                        + ",".join(SHORT_RULES) + ")")
    parser.add_argument("--limit", type=float, default=5.0, help="--jobs: flag jobs above")
    parser.add_argument("--cold-cache", action="store_true", help="--plan: the build's jobs "
                        "compiled numba's kernels (before 15572b0, or a cache emptied "
                        "after installation)")
    parser.add_argument("--tolerance", type=float, default=0.25, help="--plan: allowed "
                        "relative error")
    args = parser.parse_args()
    if args.plan:
        sys.exit(plan_mode(args))
    if args.jobs:
        return jobs_mode(args)
    with tempfile.TemporaryDirectory() as tmp:
        sides = {"this tree": Path(tmp) / "now", f"peer {args.peer}": Path(tmp) / "peer"}
        copy_tree(sides["this tree"])     # results never land in the repository
        _checkout(args.peer, sides[f"peer {args.peer}"])
        try:
            for workdir in sides.values():
                _run(workdir)                       # full build of the test config
            fig16 = {"this tree": "results/figures/orbits/harmonic/fig16.png",
                     f"peer {args.peer}": "results/figures/harmonic/fig16.png"}
            print(f"{'job':24s} {'this tree [s]':>14s} {'peer [s]':>10s} {'ratio':>7s}")
            for kind, target in JOBS.items():
                cost = {}
                for side, workdir in sides.items():
                    t = target.format(fig16=fig16[side])
                    cost[side] = statistics.median(job_cost(workdir, t)
                                                   for _ in range(args.rounds))
                now, peer = cost.values()
                print(f"{kind:24s} {now:14.2f} {peer:10.2f} {now / peer:7.2f}")
        finally:
            subprocess.run(["git", "worktree", "remove", "--force",
                            str(sides[f"peer {args.peer}"])], cwd=ROOT, capture_output=True)


if __name__ == "__main__":
    main()
