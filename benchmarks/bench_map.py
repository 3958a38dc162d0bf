"""Cost of the Fig. 15 probability map: where its CPU time goes, and against a peer in the same
run.

Reads a built map (``results/datasets/motion_map_map.nc``, rule ``simulate_map``) and the
noise record its cells ran over, then prints:

1. the map's bookkeeping: share of cells that reached the target standard error, share with
   few switches, totals and quantiles (10, 50, 90 %, max) of simulated time and CPU time per
   cell (the CPU times are the ones the workflow jobs stored);
2. a coarse text map of the median CPU time and simulated time per cell over the
   (1/beta_f, delta) plane (the grid cut into about 7 x 9 blocks);
3. a cost model fitted to the stored CPU times by non-negative least squares:
   cpu_time ~ a * steps + b * n_impacts, steps = record_end / dt;
4. the peer, measured in this run on a stratified random sample of cells (half from the top
   quartile of n_impacts): the plain simulator ``vibroimpact.simulate`` over the same fixed
   record length as the cell, against ``motion_map_cell`` (the adaptive, statistics-reducing
   cell of the map) with the map's parameters; per-step and per-impact costs of both (same
   fit on the sample) and the ratio of their total times. Also checks that the rerun cells
   reproduce the stored ones (n_impacts, record_end, probabilities);
5. a linear scaling check: every cell of a box of the plane at the map's resolution and at
   twice it in both directions (grid steps halved), CPU totals and their ratio;
6. with ``--peer-rev REV``: the map's cells (every ``--peer-stride``-th) timed with this tree
   and with revision REV (a git worktree), same arguments, each side in a fresh warmed
   process (``benchmarks/map_cells_cpu.py``): the CPU ratio on the same cells.

Timings are CPU times (time.process_time), numba compiled and warmed before any timing;
nothing is asserted.

Usage::

    python benchmarks/bench_map.py --dataset results/datasets/motion_map_map.nc \\
        --noise results/noise/harmonic_input.nc
    python benchmarks/bench_map.py ... --cells 20 --scaling-box 1.0,1.2,0,0.5
    python benchmarks/bench_map.py ... --no-scaling
    python benchmarks/bench_map.py ... --peer-rev 7b5ef46 --only-peer-rev
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread, as the jobs

import argparse
import math
import sys
import time

import numpy as np
import xarray as xr
from scipy.optimize import nnls

from vibroimpact import simulate
from vibroimpact import stats
from vibroimpact.pipeline.cells import motion_map_cell
from vibroimpact.pipeline.io import read_noise

from cell_calls import call

SEED = 19741015
DEFAULT_BOX = (1.0, 1.5, -0.5, 0.5)  # inv_beta lo, hi, delta lo, hi
BLOCKS = (7, 9)  # blocks along inv_beta, delta
GRID_TOL = 1e-9  # slack when selecting grid values inside a box


# ---------------------------------------------------------------------------------------------
# dataset


def _impacts(ds):
    """Impacts the kernel resolved per cell (``n_impacts_resolved``; ``n_impacts`` in maps
    built before collisions became the unit of the statistics): the cost driver."""
    return ds["n_impacts_resolved"] if "n_impacts_resolved" in ds else ds["n_impacts"]


def load_map(path):
    """The map dataset (loaded) and the keyword arguments of motion_map_cell from its attrs."""
    ds = xr.open_dataset(path).load()
    attrs = ds.attrs
    if "motion" in ds.coords:
        motions = tuple(tuple(int(p) for p in str(m).split("/")) for m in ds["motion"].values)
        motions_from = "motion coordinate"
    else:
        motions, motions_from = tuple(stats.DEFAULT_MOTIONS), "default"
    if "n_batches" in attrs:
        n_batches, batches_from = int(attrs["n_batches"]), "attrs"
    else:
        n_batches, batches_from = int(stats.DEFAULT_N_BATCHES), "not stored: package default"
    kwargs = dict(zeta=float(attrs["zeta"]), eps=float(attrs["eps"]),
                  amplitude=float(attrs.get("amplitude", 1.0)),
                  transient=float(attrs["transient"]), motions=motions,
                  window=float(attrs["motion_window"]), n_batches=n_batches,
                  target_stderr=float(attrs["target_stderr"]), min_time=float(attrs["min_time"]),
                  max_periods=int(attrs["max_periods"]), min_switches=int(attrs["min_switches"]))
    sources = dict(motions=motions_from, n_batches=batches_from)
    return ds, kwargs, sources


def quantile_row(name, values, unit, scale=1.0):
    v = np.asarray(values, dtype=float).ravel() * scale
    q10, q50, q90 = np.quantile(v, (0.1, 0.5, 0.9))
    print(f"{name:<22} {v.sum():>12.4g} {v.mean():>10.4g} {q10:>10.4g} {q50:>10.4g} "
          f"{q90:>10.4g} {v.max():>10.4g}  {unit}")


def summary(ds):
    n = ds["reached"].size
    print(f"\n== 1. The map: {ds.sizes['inv_beta']} x {ds.sizes['delta']} = {n} cells "
          f"(inv_beta {float(ds.inv_beta[0]):g} .. {float(ds.inv_beta[-1]):g}, delta "
          f"{float(ds.delta[0]):g} .. {float(ds.delta[-1]):g}) ==")
    reached = int(ds["reached"].sum())
    few = int(ds["few_switches"].sum())
    capped = ds["reached"] == 0
    print(f"reached == 1 (every stderr <= {float(ds.attrs['target_stderr']):g}): {reached} cells, "
          f"{reached / n:.2%}")
    print(f"few_switches (1 .. {int(ds.attrs['min_switches']) - 1} switches): {few} cells, "
          f"{few / n:.2%}")
    print(f"both (capped and few switches): {int((capped & (ds['few_switches'] == 1)).sum())} "
          f"cells; n_checks per cell: median {float(ds['n_checks'].median()):g}, "
          f"max {int(ds['n_checks'].max())}")
    print(f"{'per cell':<22} {'total':>12} {'mean':>10} {'q10':>10} {'median':>10} {'q90':>10} "
          f"{'max':>10}")
    quantile_row("simulated_time", ds["simulated_time"], "time units (after the transient)")
    quantile_row("cpu_time", ds["cpu_time"], "s")
    quantile_row("n_impacts", _impacts(ds), "impacts (after the transient)")
    if capped.any():
        sim_share = (float(ds['simulated_time'].where(capped).sum())
                     / float(ds['simulated_time'].sum()))
        print(f"the {int(capped.sum())} capped cells (reached == 0) hold "
              f"{float(ds['cpu_time'].where(capped).sum()) / float(ds['cpu_time'].sum()):.1%} of "
              f"the CPU time and {sim_share:.1%} of the simulated time")


def _blocks(n, k):
    return np.array_split(np.arange(n), min(k, n))


def block_table(ds, var, title, scale, fmt):
    rows, cols = _blocks(ds.sizes["inv_beta"], BLOCKS[0]), _blocks(ds.sizes["delta"], BLOCKS[1])
    ib, de = ds["inv_beta"].values, ds["delta"].values
    values = ds[var].transpose("inv_beta", "delta").values * scale
    labels = [f"{de[c[0]]:g}..{de[c[-1]]:g}" for c in cols]
    width = max(9, max(len(s) for s in labels) + 1)
    print(f"\n{title}")
    print(f"{'inv_beta | delta':<16}" + "".join(f"{s:>{width}}" for s in labels))
    for r in rows:
        cells = [np.median(values[np.ix_(r, c)]) for c in cols]
        print(f"{f'{ib[r[0]]:g}..{ib[r[-1]]:g}':<16}"
              + "".join(f"{v:>{width}{fmt}}" for v in cells))


def fit_cost(seconds, steps, impacts):
    """NNLS fit seconds ~ a * steps + b * impacts; (a, b) in ns, R^2 and median |rel. residual|."""
    seconds = np.asarray(seconds, dtype=float)
    design = np.column_stack([np.asarray(steps, dtype=float), np.asarray(impacts, dtype=float)])
    coef, _ = nnls(design, seconds)
    model = design @ coef
    ss_res = float(np.sum((seconds - model) ** 2))
    ss_tot = float(np.sum((seconds - seconds.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else math.nan
    rel = np.median(np.abs(seconds - model) / seconds)
    share_impacts = float(np.sum(design[:, 1] * coef[1]) / np.sum(model))
    return dict(a=coef[0] * 1e9, b=coef[1] * 1e9, r2=r2, rel=float(rel),
                share_impacts=share_impacts)


def print_fit(name, fit):
    print(f"{name:<34} {fit['a']:>10.2f} {fit['b']:>11.1f} {fit['r2']:>7.3f} "
          f"{fit['rel']:>13.1%} {fit['share_impacts']:>16.1%}")


def print_fit_header():
    print(f"{'':<34} {'a ns/step':>10} {'b ns/impact':>11} {'R^2':>7} "
          f"{'median |res|':>13} {'impact share':>16}")


def cost_model(ds, dt):
    steps = (ds["record_end"].values / dt).ravel()
    impacts = _impacts(ds).values.ravel()
    cpu = ds["cpu_time"].values.ravel()
    fit = fit_cost(cpu, steps, impacts)
    print(f"\n== 3. Cost model of the stored CPU times, all {cpu.size} cells: cpu_time ~ a * "
          f"steps + b * n_impacts (NNLS), steps = record_end / dt (dt = {dt:g}; transient "
          f"included), n_impacts after the transient ==")
    print_fit_header()
    print_fit("map jobs (stored cpu_time)", fit)
    print(f"total: {steps.sum():.4g} steps, {impacts.sum():.4g} impacts, "
          f"{cpu.sum():.4g} s; impact share = b * impacts / model total")
    return fit


# ---------------------------------------------------------------------------------------------
# timing in this run


def cpu_best(fn, repeats):
    """Best CPU time (time.process_time) of `repeats` calls of fn(), and the last result."""
    best, out = math.inf, None
    for _ in range(repeats):
        c0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - c0)
    return best, out


def warm_up(samples, dt, kw):
    """Compile and warm numba: one short call of each timed function."""
    c0 = time.process_time()
    simulate(kw["zeta"], kw["eps"], 0.0, noise=samples[:2001], dt=dt, amplitude=kw["amplitude"],
             beta=1.0, t_end=200.0)
    short = dict(kw, transient=10.0, min_time=100.0, max_periods=20)
    call(motion_map_cell, samples, dt, 1.0, 0.0, **short)
    return time.process_time() - c0


def sample_cells(ds, n, rng):
    """n cells, half from the top quartile of n_impacts, half from the rest (fixed seed)."""
    impacts = _impacts(ds).transpose("inv_beta", "delta").values.ravel()
    q75 = np.quantile(impacts, 0.75)
    busy = np.flatnonzero(impacts >= q75)
    rest = np.flatnonzero(impacts < q75)
    n_busy = min(n // 2 + n % 2, busy.size)
    pick = np.concatenate([rng.choice(busy, n_busy, replace=False),
                           rng.choice(rest, min(n - n_busy, rest.size), replace=False)])
    return np.sort(pick), q75


def peer(ds, samples, dt, kw, n_cells, repeats, seed):
    flat = ds.transpose("inv_beta", "delta", "motion", ...)
    n_delta = ds.sizes["delta"]
    pick, q75 = sample_cells(ds, n_cells, np.random.default_rng(seed))
    print(f"\n== 4. Peer in this run: {pick.size} cells (seed {seed}; "
          f"{int(np.sum(_impacts(flat).values.ravel()[pick] >= q75))} from the top quartile, "
          f"n_impacts >= {q75:.0f}), best of {repeats} CPU timings each ==")
    print("simulate = vibroimpact.simulate(zeta, eps, delta, noise, dt, amplitude, beta = "
          "1/inv_beta, t_end = record_end): the plain simulator over the cell's fixed length; "
          "map cell = motion_map_cell with the map's parameters (adaptive length, statistics)")
    rows = []
    for idx in pick:
        i, j = divmod(int(idx), n_delta)
        inv_beta, delta = float(ds.inv_beta[i]), float(ds.delta[j])
        stored = flat.isel(inv_beta=i, delta=j)
        t_end = float(stored["record_end"])
        t_sim, res = cpu_best(lambda: simulate(kw["zeta"], kw["eps"], delta, noise=samples, dt=dt,
                                               amplitude=kw["amplitude"], beta=1.0 / inv_beta,
                                               t_end=t_end), repeats)
        t_map, cell = cpu_best(lambda: call(motion_map_cell, samples, dt, inv_beta, delta, **kw),
                               repeats)
        after = int(np.sum(res.impact_time >= kw["transient"]))
        rows.append(dict(
            inv_beta=inv_beta, delta=delta, steps=t_end / dt, impacts_all=int(res.n_impacts),
            impacts_after=int(cell["n_impacts_resolved"]), sim=t_sim, map=t_map,
            stored_cpu=float(stored["cpu_time"]),
            same_end=cell["record_end"] == t_end,
            same_impacts=cell["n_impacts_resolved"] == int(_impacts(stored)),
            same_prob=bool(np.array_equal(cell["probability"], stored["probability"].values)),
            sim_matches_cell=after == cell["n_impacts_resolved"]))

    steps = np.array([r["steps"] for r in rows])
    imp = np.array([r["impacts_all"] for r in rows])
    sim = np.array([r["sim"] for r in rows])
    cmap = np.array([r["map"] for r in rows])
    stored = np.array([r["stored_cpu"] for r in rows])
    print(f"\n{'inv_beta':>8} {'delta':>6} {'steps':>9} {'impacts':>8} {'simulate ms':>12} "
          f"{'map cell ms':>12} {'map/sim':>8} {'stored ms':>10}")
    order = np.argsort(-imp)
    show = order if order.size <= 12 else np.concatenate([order[:6], order[-6:]])
    for k in show:
        r = rows[k]
        print(f"{r['inv_beta']:>8g} {r['delta']:>6g} {r['steps']:>9.0f} {r['impacts_all']:>8d} "
              f"{r['sim'] * 1e3:>12.2f} {r['map'] * 1e3:>12.2f} {r['map'] / r['sim']:>8.2f} "
              f"{r['stored_cpu'] * 1e3:>10.2f}")
    if order.size > 12:
        print(f"(the 6 busiest and the 6 quietest of the {order.size} sampled cells; impacts = "
              "all impacts of the run, transient included)")

    print("\nCost model on the sample: seconds ~ a * steps + b * impacts (NNLS), steps = "
          "record_end / dt, impacts = all impacts of the run (same regressors for both)")
    print_fit_header()
    fit_sim = fit_cost(sim, steps, imp)
    fit_map = fit_cost(cmap, steps, imp)
    fit_stored = fit_cost(stored, steps, imp)
    print_fit("simulate (plain, fixed length)", fit_sim)
    print_fit("motion_map_cell (this run)", fit_map)
    print_fit("motion_map_cell (stored cpu_time)", fit_stored)
    print(f"total CPU on the sample: simulate {sim.sum():.3f} s, motion_map_cell "
          f"{cmap.sum():.3f} s: ratio map cell / simulate = {cmap.sum() / sim.sum():.3f}; "
          f"median per-cell ratio {np.median(cmap / sim):.3f}")
    print(f"this run's motion_map_cell vs the stored cpu_time of the same cells: "
          f"{cmap.sum():.3f} s / {stored.sum():.3f} s = {cmap.sum() / stored.sum():.3f}")
    n = len(rows)
    print(f"reproduction: rerun cells with the stored record_end "
          f"{sum(r['same_end'] for r in rows)}/{n}, stored n_impacts "
          f"{sum(r['same_impacts'] for r in rows)}/{n}, stored probabilities bit for bit "
          f"{sum(r['same_prob'] for r in rows)}/{n}; simulate's impacts after the transient == "
          f"the cell's n_impacts {sum(r['sim_matches_cell'] for r in rows)}/{n}")
    return fit_sim, fit_map


def peer_revision(ds, noise_path, kw, rev, stride):
    """Section 6: every ``stride``-th cell of the map with this tree and with revision ``rev``
    (a git worktree), each in a fresh process running benchmarks/map_cells_cpu.py."""
    import json
    import subprocess
    import tempfile
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    flat = ds.transpose("inv_beta", "delta", "motion", ...)
    cells = [(float(b), float(d)) for b in flat.inv_beta.values for d in flat.delta.values]
    cells = cells[::stride]
    job = json.dumps(dict(noise=str(noise_path), cells=cells,
                          kwargs={k: (list(map(list, v)) if k == "motions" else v)
                                  for k, v in kw.items()}))
    print(f"\n== 6. This tree against revision {rev} on {len(cells)} cells (every {stride}-th "
          f"cell of the map), the same motion_map_cell arguments, one process each, warmed ==")
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp) / "peer"
        subprocess.run(["git", "worktree", "add", "-f", "--detach", str(where), rev], cwd=root,
                       check=True, capture_output=True)
        try:
            for name, src in (("this tree", root / "src"), (f"revision {rev}", where / "src")):
                env = dict(os.environ, PYTHONPATH=str(src))
                script = str(root / "benchmarks" / "map_cells_cpu.py")
                out = subprocess.run([sys.executable, script], input=job,
                                     capture_output=True, text=True, env=env, check=True)
                results[name] = json.loads(out.stdout)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(where)], cwd=root,
                           check=False, capture_output=True)
    now, base = results["this tree"], results[f"revision {rev}"]
    cpu_now, cpu_base = np.array(now["cpu"]), np.array(base["cpu"])
    print(f"{'':<22} {'CPU total s':>12} {'median ms':>10} {'q90 ms':>8} {'max ms':>8}  package")
    for name, r in results.items():
        c = np.array(r["cpu"])
        print(f"{name:<22} {c.sum():>12.2f} {np.median(c) * 1e3:>10.2f} "
              f"{np.quantile(c, 0.9) * 1e3:>8.2f} {c.max() * 1e3:>8.2f}  {r['package']}")
    print(f"ratio revision {rev} / this tree: {cpu_base.sum() / cpu_now.sum():.2f} x the CPU "
          f"(median per cell {np.median(cpu_base / np.maximum(cpu_now, 1e-9)):.2f})")
    busy = cpu_base >= np.quantile(cpu_base, 0.9)
    print(f"on the busiest tenth of the cells for {rev}: {cpu_base[busy].sum():.2f} s against "
          f"{cpu_now[busy].sum():.2f} s ({cpu_base[busy].sum() / cpu_now[busy].sum():.2f} x)")


def box_grid(ds, box):
    lo_b, hi_b, lo_d, hi_d = box
    ib = ds["inv_beta"].values
    de = ds["delta"].values
    ib = ib[(ib >= lo_b - GRID_TOL) & (ib <= hi_b + GRID_TOL)]
    de = de[(de >= lo_d - GRID_TOL) & (de <= hi_d + GRID_TOL)]
    if ib.size == 0 or de.size == 0:
        raise SystemExit(f"--scaling-box {box}: no grid value of the map inside it")
    return ib, de


def refine(values):
    """The grid with its steps halved: the old values and the midpoints between them."""
    if values.size == 1:
        return values.copy()
    return np.linspace(values[0], values[-1], 2 * (values.size - 1) + 1)


def run_grid(samples, dt, kw, inv_betas, deltas):
    c0 = time.process_time()
    impacts = 0
    for ib in inv_betas:
        for d in deltas:
            impacts += call(motion_map_cell, samples, dt, float(ib), float(d),
                            **kw)["n_impacts"]
    return time.process_time() - c0, impacts


def scaling(ds, samples, dt, kw, box):
    ib, de = box_grid(ds, box)
    ib2, de2 = refine(ib), refine(de)
    stored = ds["cpu_time"].sel(inv_beta=ib, delta=de)
    n1, n2 = ib.size * de.size, ib2.size * de2.size
    print(f"\n== 5. Linear scaling: box inv_beta {ib[0]:g} .. {ib[-1]:g}, delta {de[0]:g} .. "
          f"{de[-1]:g}; grid steps halved in both directions ==")
    print(f"stored cpu_time of the box's {n1} cells: {float(stored.sum()):.3f} s (the refined run "
          f"should take about {n2 / n1:.2f} x that)")
    cpu1, imp1 = run_grid(samples, dt, kw, ib, de)
    cpu2, imp2 = run_grid(samples, dt, kw, ib2, de2)
    print(f"{'grid':<26} {'cells':>7} {'CPU s':>9} {'ms/cell':>9} {'impacts':>11}")
    print(f"{f'map resolution {ib.size} x {de.size}':<26} {n1:>7d} {cpu1:>9.3f} "
          f"{cpu1 / n1 * 1e3:>9.3f} {imp1:>11d}")
    print(f"{f'steps halved {ib2.size} x {de2.size}':<26} {n2:>7d} {cpu2:>9.3f} "
          f"{cpu2 / n2 * 1e3:>9.3f} {imp2:>11d}")
    print(f"CPU ratio refined / map resolution: {cpu2 / cpu1:.3f} (ideal 4.0 for 4x cells; this "
          f"box has {n2 / n1:.3f}x cells, since halving the steps of a closed grid of n points "
          f"gives 2n - 1); CPU per cell ratio {(cpu2 / n2) / (cpu1 / n1):.3f} (ideal 1.0)")


def parse_box(text):
    try:
        box = tuple(float(v) for v in text.split(","))
    except ValueError:
        box = ()
    if len(box) != 4 or box[0] > box[1] or box[2] > box[3]:
        raise argparse.ArgumentTypeError(
            f"expected inv_beta_lo,inv_beta_hi,delta_lo,delta_hi (lo <= hi), got {text!r}")
    return box


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dataset", required=True, help="the built map (motion_map_map.nc)")
    parser.add_argument("--noise", required=True, help="the noise record its cells ran over")
    parser.add_argument("--cells", type=int, default=40,
                        help="cells timed against the peer (default 40)")
    parser.add_argument("--repeats", type=int, default=3,
                        help="best of this many CPU timings per sampled cell (default 3)")
    parser.add_argument("--seed", type=int, default=SEED, help="seed of the cell sample")
    parser.add_argument("--scaling-box", type=parse_box, default=DEFAULT_BOX,
                        metavar="IB_LO,IB_HI,D_LO,D_HI",
                        help="box of the scaling check (default 1.0,1.5,-0.5,0.5)")
    parser.add_argument("--no-scaling", action="store_true", help="skip the scaling check")
    parser.add_argument("--peer-rev", metavar="REV",
                        help="also time the map's cells with this git revision (section 6)")
    parser.add_argument("--peer-stride", type=int, default=1,
                        help="with --peer-rev: every this-many-th cell (default 1: all)")
    parser.add_argument("--only-peer-rev", action="store_true",
                        help="with --peer-rev: skip sections 4 and 5")
    args = parser.parse_args(argv)

    start = time.perf_counter(), time.process_time()
    ds, kw, sources = load_map(args.dataset)
    samples, dt, noise_attrs = read_noise(args.noise)
    if "dt" in ds.attrs and float(ds.attrs["dt"]) != dt:
        raise SystemExit(f"the map was built at dt = {ds.attrs['dt']}, the noise record has {dt}")
    if "seed" in ds.attrs and "seed" in noise_attrs and ds.attrs["seed"] != noise_attrs["seed"]:
        print(f"WARNING: map seed {ds.attrs['seed']} != noise seed {noise_attrs['seed']}")
    print(f"map: {args.dataset} (git {str(ds.attrs.get('git_commit', '?'))[:7]}); noise: "
          f"{args.noise}, {samples.size} samples at dt = {dt:g}")
    print("motion_map_cell parameters: " + ", ".join(f"{k} = {v}" for k, v in kw.items())
          + f" (motions: {sources['motions']}; n_batches: {sources['n_batches']})")
    print(f"NUMBA_NUM_THREADS = {os.environ['NUMBA_NUM_THREADS']}; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs; CPU times: time.process_time")

    summary(ds)
    print("\n== 2. Coarse map: block medians per cell (rows inv_beta, columns delta) ==")
    block_table(ds, "cpu_time", "cpu_time per cell [ms]", 1e3, ".2f")
    block_table(ds, "simulated_time", "simulated_time per cell [1e3 time units]", 1e-3, ".1f")
    cost_model(ds, dt)

    print(f"\nwarm-up (numba compile, one short call of each): "
          f"{warm_up(samples, dt, kw):.2f} s CPU")
    if not args.only_peer_rev:
        peer(ds, samples, dt, kw, args.cells, args.repeats, args.seed)
        if not args.no_scaling:
            scaling(ds, samples, dt, kw, args.scaling_box)
    if args.peer_rev:
        peer_revision(ds, args.noise, kw, args.peer_rev, args.peer_stride)
    print(f"\ntotal: {time.perf_counter() - start[0]:.1f} s wall, "
          f"{time.process_time() - start[1]:.1f} s CPU")


if __name__ == "__main__":
    main()
