"""A/B of the validation jobs' sizes: the old sizes against the new, same code, same run.

Issue 37 asks the work-precision and stress deliverables at a fraction of their cost with the
same conclusions. This script runs this tree's `vibroimpact.validation.work_precision.
work_precision` and `vibroimpact.validation.campaign.stress_sample` at

- old sizes: the default config before issue 37 (work precision: impacts 20, stretch 100, no
  longest stretch, long_samples 1e5, repeats 3; stress: size ``quick``);
- new sizes: ``config/config.yaml``'s ``validation`` block as it is now,

each in a fresh subprocess (the job's own import and numba cache load included), alternating
old new, new old, ... (``--rounds``; ``--new-repeats`` extra runs of the new sizes, the dear old
work-precision run once a round). Each child prints its wall time and its CPU time (its own
and its children's: the streamed record's runs are processes).

Then it checks the conclusions the figures and reports draw, on every run, and prints them:

- work precision, per play: the errors are the same in every repeat (they are deterministic)
  and, where the same impacts are compared (``n_compared`` equal), bit-identical to the old
  sizes'; the simulator's error is below every peer's; the most accurate peer is the same
  method; each method's most accurate setting; the simulator is the cheapest run; the
  methods' order by their cheapest run's cost; each run's cost over the simulator's against
  the old sizes' (the ratio of the two, its range over the runs);
- stress: the same families, no failure, no missed or spurious event, no exception, and each
  family's worst error / allowance, which cannot exceed the quick sample's (the sample's cases
  are the first of the quick sample's).

Usage::

    python benchmarks/ab_validation_sizes.py                     # 1 round, 2 extra new runs
    python benchmarks/ab_validation_sizes.py --rounds 2 --new-repeats 0
    python benchmarks/ab_validation_sizes.py --only wp           # work precision only
"""
import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile

import numpy as np
import xarray as xr
import yaml

ROOT = Path(__file__).resolve().parent.parent

#: The default config's validation sizes before issue 37.
OLD_WP = dict(delta=[1.0, 0.0, -0.5], impacts=20, stretch=100.0, long_samples=100_000,
              seed=19740072, rtol=[1e-3, 1e-6, 1e-9, 1e-12], solvers=["RK45", "DOP853", "LSODA"],
              rk4_steps=[1, 2, 4, 8, 16, 32, 64], repeats=3)
OLD_STRESS = dict(seed=20261122, size="quick")

CHILD = r"""
import json, os, resource, sys, time
t0, c0 = time.perf_counter(), time.process_time()
kind, args, out = sys.argv[1], json.loads(sys.argv[2]), sys.argv[3]
if kind == "wp":
    from vibroimpact.validation.work_precision import work_precision
    ds = work_precision(**args)
else:
    from vibroimpact.validation.campaign import stress_sample
    ds = stress_sample(args["seed"], size=args["size"])
ds.to_netcdf(out)
ch = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps(dict(wall=time.perf_counter() - t0, cpu=time.process_time() - c0,
                      children_cpu=ch.ru_utime + ch.ru_stime, load=os.getloadavg()[0])))
"""


def new_sizes():
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["validation"]
    return dict(config["work_precision"]), dict(config["stress"])


def run_child(kind, args, out):
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    proc = subprocess.run([sys.executable, "-c", CHILD, kind, json.dumps(args), str(out)],
                          capture_output=True, text=True, env=env, cwd=ROOT, check=True)
    stats = json.loads(proc.stdout.strip().splitlines()[-1])
    stats["total_cpu"] = stats["cpu"] + stats["children_cpu"]
    return stats


def _best(ds, method):
    runs = np.flatnonzero(ds.method.values == method)
    return runs[int(np.nanargmin(ds.error.values[runs]))]


def wp_conclusions(old, news):
    """Print the work-precision checks; return the number that failed."""
    failed = 0

    def check(ok, text):
        nonlocal failed
        failed += not ok
        print(f"  [{'ok' if ok else 'FAILED'}] {text}")

    first = news[0]
    for other in news[1:]:
        same = all(np.array_equal(first[v].values, other[v].values, equal_nan=True)
                   for v in ("error", "n_compared", "roundoff", "n_found", "t_stretch"))
        check(same, "errors identical in every repeat of the new sizes")
    methods = list(dict.fromkeys(first.method.values))
    for d in first.delta.values:
        o, n = old.sel(delta=d), first.sel(delta=d)
        print(f" delta = {d:g}: impacts compared old {int(o.n_compared)} (tau <= "
              f"{float(o.t_stretch):g}), new {int(n.n_compared)} (tau <= {float(n.t_stretch):g})")
        if int(o.n_compared) == int(n.n_compared):
            check(np.array_equal(o.error.values, n.error.values, equal_nan=True),
                  "same impacts compared: every error bit-identical to the old sizes'")
        sim = int(np.flatnonzero(first.method.values == "simulate")[0])
        for name, ds in (("old", o), ("new", n)):
            peers, own = np.delete(ds.error.values, sim), float(ds.error[sim])
            check(bool(np.all(own < peers)),
                  f"{name}: simulator's error {own:.2g} below every peer's "
                  f"(smallest {np.nanmin(peers):.2g}, x{np.nanmin(peers) / own:.3g})")
        top = [str(ds.method.values[np.nanargmin(np.where(ds.method.values == "simulate",
                                                          np.inf, ds.error.values))])
               for ds in (o, n)]
        check(top[0] == top[1], f"most accurate peer: old {top[0]}, new {top[1]}")
        for method in methods[1:]:
            b_old, b_new = _best(o, method), _best(n, method)
            print(f"    {method:22s} most accurate: old {o.setting.values[b_old]} "
                  f"({float(o.error[b_old]):.2g}), new {n.setting.values[b_new]} "
                  f"({float(n.error[b_new]):.2g})")
        # costs: every new repeat against the old run
        for k, ds in enumerate(news):
            dn = ds.sel(delta=d)
            check(int(np.nanargmin(dn.cost.values)) == sim,
                  f"new run {k}: the simulator is the cheapest run")
        order_old = sorted(methods, key=lambda m: np.nanmin(o.cost.values[o.method.values == m]))
        for k, ds in enumerate(news):
            dn = ds.sel(delta=d)
            order = sorted(methods, key=lambda m: np.nanmin(dn.cost.values[dn.method.values == m]))
            check(order[0] == order_old[0] and order[1] == order_old[1]
                  and set(order[2:]) == set(order_old[2:]),
                  f"new run {k}: methods by cost {' < '.join(order)} (old "
                  f"{' < '.join(order_old)}; the solve_ivp methods within a factor 2.5)")
        ratio = np.stack([ds.sel(delta=d).cost_ratio.values / o.cost_ratio.values
                          for ds in news])[:, 1:]
        print(f"    cost over the simulator's, new / old sizes: {np.nanmin(ratio):.2f} .. "
              f"{np.nanmax(ratio):.2f} (median {np.nanmedian(ratio):.2f}) over "
              f"{ratio.size} runs; old range x{np.nanmin(o.cost_ratio.values[1:]):.3g} .. "
              f"x{np.nanmax(o.cost_ratio.values[1:]):.3g}")
    return failed


def stress_conclusions(old, news):
    failed = 0

    def check(ok, text):
        nonlocal failed
        failed += not ok
        print(f"  [{'ok' if ok else 'FAILED'}] {text}")

    for k, ds in enumerate(news):
        check(list(ds.family.values) == list(old.family.values),
              f"new run {k}: the same {ds.sizes['family']} families")
        bad = {v: int(ds[v].values.sum()) for v in ("failed", "missed", "spurious", "exceptions")}
        check(not any(bad.values()), f"new run {k}: {bad}")
        check(np.array_equal(ds.worst_error.values, news[0].worst_error.values),
              f"new run {k}: worst errors identical to the first run's")
    worst_old = old.worst_error.values / old.tolerance.values
    worst_new = news[0].worst_error.values / news[0].tolerance.values
    for f, c_o, c_n, w_o, w_n in zip(old.family.values, old.cases.values, news[0].cases.values,
                                     worst_old, worst_new):
        print(f"    {f:22s} cases {c_o:3d} -> {c_n:3d}   worst / allowance {w_o:.3g} -> {w_n:.3g}")
    check(bool(np.all(worst_new <= worst_old)), "no family's worst error above the quick sample's")
    print(f"    largest worst / allowance: old {worst_old.max():.3g}, new {worst_new.max():.3g}; "
          f"cases {int(old.cases.sum())} -> {int(news[0].cases.sum())}, events compared "
          f"{int(old.compared.sum())} -> {int(news[0].compared.sum())}")
    return failed


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=1, help="old/new pairs (alternating)")
    parser.add_argument("--new-repeats", type=int, default=2,
                        help="extra runs of the new sizes after the rounds")
    parser.add_argument("--only", choices=("wp", "stress"), default=None)
    args = parser.parse_args(argv)
    new_wp, new_stress = new_sizes()
    print(f"load average at start {os.getloadavg()}")
    print(f"old sizes: work precision {OLD_WP}; stress {OLD_STRESS}")
    print(f"new sizes: work precision {new_wp}; stress {new_stress}")
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for kind, old_args, new_args, judge in (("wp", OLD_WP, new_wp, wp_conclusions),
                                                ("stress", OLD_STRESS, new_stress,
                                                 stress_conclusions)):
            if args.only not in (None, kind):
                continue
            runs = {"old": [], "new": []}
            plan = [(("old", "new") if r % 2 == 0 else ("new", "old")) for r in
                    range(args.rounds)]
            plan = [s for pair in plan for s in pair] + ["new"] * args.new_repeats
            for k, size in enumerate(plan):
                out = Path(tmp) / f"{kind}_{size}_{k}.nc"
                stats = run_child(kind, old_args if size == "old" else new_args, out)
                runs[size].append((stats, xr.load_dataset(out)))
                print(f"{kind} {size:3s}: wall {stats['wall']:6.2f} s, CPU {stats['cpu']:6.2f} s "
                      f"+ children {stats['children_cpu']:5.2f} s, load {stats['load']:.1f}",
                      flush=True)
            for size in ("old", "new"):
                cpu = [s["total_cpu"] for s, _ in runs[size]]
                wall = [s["wall"] for s, _ in runs[size]]
                print(f"{kind} {size}: CPU {min(cpu):.2f} .. {max(cpu):.2f} s, wall "
                      f"{min(wall):.2f} .. {max(wall):.2f} s over {len(cpu)} runs")
            cpu_ratio = (min(s["total_cpu"] for s, _ in runs["new"])
                         / min(s["total_cpu"] for s, _ in runs["old"]))
            print(f"{kind}: new / old CPU (fastest of each) {cpu_ratio:.3f}")
            failed += judge(runs["old"][0][1], [ds for _, ds in runs["new"]])
    print(f"load average at end {os.getloadavg()}; {failed} check(s) failed")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
