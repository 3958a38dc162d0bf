"""Cost of the escape study (figure escape_vs_noise), against peers measured in the same run.

1. In this process, for every noise level of the config's escape block: the CPU time of
   generating its record (`noise.generate_array`) and of each cell (`cells.escape_cell`),
   against two peers on the same record and cell: ``motion_map_cell`` stopped at the same
   sample (the Fig. 15 cell; the residence times are checked equal) and the bare simulator
   ``vibroimpact.simulate`` (no statistics). Ratios escape / peer.
2. With ``--workflow``: the wall time of the Snakemake build of
   ``results/datasets/<study>_escape.nc`` and the figure in a scratch copy of the workflow
   with ``--cores 2`` (the target: under 60 s for the default 3 cells x 5 levels), against
   the same build with ``--cores 1`` in the same run (the ratio is the parallel speed-up).

CPU times are ``time.process_time``, numba compiled and warmed first; nothing is asserted.

Usage::

    python benchmarks/bench_escape.py                  # the paper's config
    python benchmarks/bench_escape.py --workflow       # plus the two builds
    python benchmarks/bench_escape.py --config config/test.yaml --workflow
"""
import os

os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba loads: one thread, as the jobs

import argparse
from pathlib import Path
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from vibroimpact import simulate  # noqa: E402 (after the thread setting)
from vibroimpact.noise import generate_array  # noqa: E402
from vibroimpact.pipeline import config as configuration  # noqa: E402
from vibroimpact.pipeline.cells import escape_cell, motion_map_cell  # noqa: E402
from vibroimpact.pipeline.study import escape_samples, escape_seed  # noqa: E402
from vibroimpact.pipeline.tasks import noise_spec  # noqa: E402

from cell_calls import call  # noqa: E402


def _cpu(func, *args, **kwargs):
    start = time.process_time()
    out = func(*args, **kwargs)
    return time.process_time() - start, out


def in_process(config, study):
    entry = config["studies"][study]
    noise = config["noises"][entry["noise"]]
    block = entry["escape"]
    system = dict(zeta=float(entry["zeta"]), eps=float(entry["eps"]),
                  amplitude=float(entry["amplitude"]))
    transient, length = float(entry["transient"]), float(block["record_length"])
    warm = generate_array(noise_spec(dict(noise, rms=0.3)), 20001, 0)
    call(escape_cell, warm, float(noise["dt"]), 1.0, 1.0, **system, transient=100.0,
         record_length=1000.0)
    print(f"studies.{study}.escape: {len(block['cells'])} cells x {len(block['rms'])} levels, "
          f"record {length:g} after the transient {transient:g}")
    print(f"{'rms':>6} {'cell':>12} {'gen s':>7} {'escape s':>9} {'map s':>7} {'sim s':>7} "
          f"{'ns/step':>8} {'esc/map':>8} {'esc/sim':>8}")
    totals = np.zeros(4)
    for k, rms in enumerate(block["rms"]):
        spec = noise_spec(dict(noise, rms=float(rms)))
        n = escape_samples(transient, length, spec.dt)
        # a forcing period more than the job's record: room for the peer's cap (a prefix of
        # the stream is the job's record)
        extra = int(np.ceil(2 * np.pi * max(c[0] for c in block["cells"]) / spec.dt)) + 1
        t_gen, r = _cpu(generate_array, spec, n + extra, escape_seed(noise["seed"], k))
        totals[0] += t_gen
        for inv_beta, delta in block["cells"]:
            beta_f = 1.0 / float(inv_beta)
            cell = dict(system, inv_beta=float(inv_beta), delta=float(delta),
                        transient=transient)
            t_esc, got = _cpu(call, escape_cell, r, spec.dt, **cell, record_length=length)
            t_map, ref = _cpu(call, motion_map_cell, r, spec.dt, **cell, target_stderr=0.5,
                              min_time=length, min_switches=1,
                              max_periods=int(length * beta_f / (2 * np.pi)) + 1)
            same = np.array_equal(got["residence_time"], ref["residence_time"], equal_nan=True)
            t_sim, _ = _cpu(simulate, system["zeta"], system["eps"], float(delta), noise=r,
                            dt=spec.dt, amplitude=system["amplitude"], beta=beta_f,
                            t_end=got["record_end"])
            totals[1:] += (t_esc, t_map, t_sim)
            print(f"{rms:>6g} {f'({inv_beta:g}, {delta:g})':>12} {t_gen:>7.2f} {t_esc:>9.3f} "
                  f"{t_map:>7.3f} {t_sim:>7.3f} {1e9 * t_esc / (n - 1):>8.1f} "
                  f"{t_esc / t_map:>8.2f} {t_esc / t_sim:>8.2f}"
                  + ("" if same else "  RESIDENCE TIMES DIFFER"))
    print(f"total CPU: generation {totals[0]:.2f} s, escape cells {totals[1]:.2f} s; peers: "
          f"motion_map_cell {totals[2]:.2f} s (ratio {totals[1] / totals[2]:.2f}), bare "
          f"simulate {totals[3]:.2f} s (ratio {totals[1] / totals[3]:.2f})")


def workflow(config_file, study):
    from helpers import make_workdir

    target = [f"results/datasets/{study}_escape.nc", "results/figures/escape_vs_noise.png"]
    walls = {}
    for cores in (2, 1):
        with tempfile.TemporaryDirectory() as tmp:
            work = make_workdir(Path(tmp) / "wf")
            cmd = [sys.executable, "-m", "snakemake", *target, "--cores", str(cores),
                   "--quiet", "--configfile", str(config_file)]
            start = time.perf_counter()
            out = subprocess.run(cmd, cwd=work, capture_output=True, text=True,
                                 env=dict(os.environ, PYTHONPATH=str(ROOT / "src")))
            walls[cores] = time.perf_counter() - start
            if out.returncode != 0:
                print(out.stdout[-2000:], out.stderr[-2000:])
                raise SystemExit(f"the build with --cores {cores} failed")
        print(f"workflow (escape jobs, aggregation, figure) with --cores {cores}: "
              f"{walls[cores]:.1f} s wall")
    print(f"wall --cores 2 / --cores 1: {walls[2] / walls[1]:.2f} (target: --cores 2 under 60 s)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", default=None, help="a --configfile (default: the paper's)")
    parser.add_argument("--study", default="motion_map")
    parser.add_argument("--workflow", action="store_true", help="also time the builds")
    parser.add_argument("--only-workflow", action="store_true", help="time the builds only")
    args = parser.parse_args()
    files = [Path(args.config)] if args.config else []
    config, _ = configuration.load(root=ROOT, user_files=files)
    if not args.only_workflow:
        in_process(config, args.study)
    if args.workflow or args.only_workflow:
        workflow(Path(args.config).resolve() if args.config else ROOT / "config" / "config.yaml",
                 args.study)


if __name__ == "__main__":
    main()
