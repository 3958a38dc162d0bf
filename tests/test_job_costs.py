"""Issue 37's job costs: the predictors' shared bootstrap gives what independent correlations
give, bit for bit; the plan's per-kind account (`Plan.rule_costs`) adds up to the plan and
names kinds of job the workflow benchmarks; `benchmarks/job_costs.py --plan` reads a build's
benchmark files as documented."""
import importlib.util
from pathlib import Path
import re

import numpy as np

from vibroimpact.pipeline import config as configuration
from vibroimpact.reports import predictors

ROOT = Path(__file__).resolve().parents[1]


def _job_costs():
    spec = importlib.util.spec_from_file_location("job_costs",
                                                  ROOT / "benchmarks" / "job_costs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_shared_bootstrap_is_each_correlation_alone_bit_for_bit():
    """A motion's four predictors share P's resampled ranks and the resampled cells; the
    results equal fresh `rank_correlation` calls exactly (ties, -inf and NaN cells included),
    whatever order the pairs come in, and a bootstrap of another seed is refused."""
    rng = np.random.default_rng(3)
    n = 300
    p = np.round(rng.random(n), 2)
    xs = [rng.normal(size=n), np.round(rng.normal(size=n), 1), np.where(rng.random(n) < 0.1,
                                                                       -np.inf, p ** 2)]
    xs[1][::17] = np.nan                                # a different set of cells kept
    shared = predictors._Bootstrap(predictors.SEED, 200)
    for x in xs + xs[::-1]:
        alone = predictors.rank_correlation(x, p, n_resamples=200)
        assert predictors.rank_correlation(x, p, n_resamples=200, _shared=shared) == alone
    try:
        predictors.rank_correlation(xs[0], p, seed=1, n_resamples=200, _shared=shared)
    except ValueError as error:
        assert "seed" in str(error)
    else:
        raise AssertionError("a bootstrap of another seed was used")


def test_the_plans_kinds_of_job_add_up_and_are_the_workflows():
    """`Plan.rule_costs` sums to the plan's jobs and CPU, and every kind it names is a
    benchmark folder of a rule (or the paper figures' local copies, which have none)."""
    _, plan = configuration.load(root=ROOT)
    kinds = plan.rule_costs()
    assert sum(n for n, _ in kinds.values()) == plan.jobs
    assert np.isclose(sum(c for _, c in kinds.values()), plan.cpu_s, rtol=1e-12)
    rules = "".join(p.read_text() for p in (ROOT / "workflow" / "rules").glob("*.smk"))
    folders = set(re.findall(r"results/benchmarks/([a-z_]+?)(?:/|\.tsv)", rules))
    assert set(kinds) - folders == {"copy_paper_figure"}
    assert kinds["report"][0] == 6 and kinds["draw_figure"][0] == 19


def test_job_costs_reads_benchmark_files_per_kind(tmp_path):
    """The comparison sums each kind's benchmark files: cpu_time, or the wall time where
    cpu_time reads 0 (a job shorter than Snakemake's first sample) and for the runs that hold
    every core."""
    job_costs = _job_costs()
    header = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
    files = {"draw_figure/random/fig07.tsv": "2.0\t0\t1\t1\t1\t1\t0\t0\t0\t1.5\n",
             "draw_figure/random/fig08.tsv": "1.0\t0\t1\t1\t1\t1\t0\t0\t0\t0.00\n",
             "sample_stress_families.tsv": "30.0\t0\t1\t1\t1\t1\t0\t0\t0\t10.0\n"}
    for name, row in files.items():
        path = tmp_path / "benchmarks" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(header + row)
    rows = {r[0]: r for r in job_costs.plan_comparison(tmp_path)}
    assert rows["draw_figure"][2:] == (2, rows["draw_figure"][3], 2.5)
    assert rows["sample_stress_families"][4] == 30.0
    assert rows["report"][2] == 0 and rows["report"][1] == 6      # planned, none measured
    assert job_costs.target_of("report/orbits/harmonic.tsv") == (
        "results/reports/orbits/harmonic/periodic_motions.html")
    assert job_costs.target_of("draw_validation_figure/stress.tsv") == (
        "results/figures/stress.png")
