"""A report's "Run" section (`vibroimpact.reports.run`): the versions each dataset recorded
beside the report's own environment, and the costs of the jobs behind it from Snakemake's
benchmark files."""
import json

import pytest
import xarray as xr

from vibroimpact._release import SOFTWARE, software
from vibroimpact.pipeline.provenance import provenance
from vibroimpact.reports import run

HEADER = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


def _benchmarks(folder, jobs):
    """Benchmark files under ``folder`` in Snakemake's columns: ``{path: (wall s, max_rss,
    cpu_time)}``, the other columns 0."""
    for rel, (wall, rss, cpu) in jobs.items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text(HEADER + f"{wall}\t0:00:00\t{rss}\t0\t0\t0\t0\t0\t90\t{cpu}\n")


def test_every_dataset_records_the_software_that_computed_it():
    attrs = provenance({"zeta": 0.05})
    recorded = json.loads(attrs["software"])
    assert set(SOFTWARE) <= set(recorded) and {"Python", "CPU"} <= set(recorded)
    assert recorded == software()


def test_versions_show_each_record_beside_this_environment():
    now = xr.Dataset(attrs=dict(provenance({"a": 1}), package_version="1.0"))
    old = xr.Dataset(attrs={"package_version": "0.9", "git_commit": "abc", "git_dirty": 0,
                            "software": json.dumps({"numpy": "1.26.0"})})
    table = run.versions(events=now, spectra=now, map=old)
    assert list(table.columns) == ["events, spectra", "map", "this report"]
    assert table.loc["numpy", "map"] == "1.26.0"
    assert table.loc["numba", "map"] == "not recorded"
    assert table.loc["numpy", "this report"] == software()["numpy"]


def test_job_costs_read_the_jobs_of_the_owners_and_skip_the_report(tmp_path):
    bench = tmp_path / "benchmarks"
    files = {"simulate_events/mine/0.tsv": (7.5, 480, 7.0),
             "aggregate_events/mine.tsv": (1.5, 180, 1.4),
             "generate_noise/my_noise.tsv": (2.6, 390, 2.5),
             "draw_figure/orbits/mine/fig16.tsv": (1, 200, 0.9),
             "simulate_events/other/0.tsv": (9, 999, 9.0),
             "report/mine/harmonic_random.tsv": (20, 900, 19)}
    _benchmarks(bench, files)
    costs = run.job_costs(["mine", "noise/my_noise", "orbits/mine"], bench)
    assert list(costs.rule) == ["aggregate_events", "draw_figure", "generate_noise",
                                "simulate_events"]
    assert costs["CPU s"].sum() == 7.0 + 1.4 + 2.5 + 0.9
    assert costs["peak memory MB"].max() == 480
    assert run.job_costs(["mine"], tmp_path / "none").empty
    _benchmarks(bench, {"measure_work_precision.tsv": files["aggregate_events/mine.tsv"]})
    one = run.job_costs(["measure_work_precision"], bench)     # a rule of one job
    assert one[["rule", "job"]].values.tolist() == [["measure_work_precision", ""]]


def test_a_study_and_an_orbits_entry_of_one_name_own_their_own_jobs(tmp_path):
    """config.yaml names a study and an orbits entry ``harmonic``: the orbits report counts
    the entry's jobs and the map it reads, not the study's simulations; the study's report
    not the entry's tiles. A value Snakemake could not measure ("-") is no number."""
    bench = tmp_path / "benchmarks"
    files = {"simulate_events/harmonic/0.tsv": (7, 480, 7.0),
             "draw_figure/harmonic/fig11.tsv": (1, 200, 0.9),
             "solve_orbit_tile/harmonic/0.tsv": (9, 300, 9.0),
             "aggregate_attractors/harmonic.tsv": (1, "-", 0.5),
             "draw_figure/orbits/harmonic/fig16.tsv": (2, 250, 1.9),
             "simulate_map/motion_map/0.tsv": (30, 500, 29),
             "simulate_escape/motion_map/0.tsv": (5, 400, 4.9),
             "generate_noise/harmonic.tsv": (2, 390, 2.0)}
    _benchmarks(bench, files)
    jobs = {owners: [str(p.relative_to(bench)) for p in run.owner_jobs(owners, bench)]
            for owners in [("orbits/harmonic", "map/motion_map"), ("harmonic",)]}
    assert jobs[("orbits/harmonic", "map/motion_map")] == [
        "aggregate_attractors/harmonic.tsv", "draw_figure/orbits/harmonic/fig16.tsv",
        "simulate_map/motion_map/0.tsv", "solve_orbit_tile/harmonic/0.tsv"]
    assert jobs[("harmonic",)] == ["draw_figure/harmonic/fig11.tsv",
                                   "simulate_events/harmonic/0.tsv"]
    costs = run.job_costs(["orbits/harmonic"], bench)
    assert costs["peak memory MB"].isna().sum() == 1 and costs["CPU s"].sum() == 0.5 + 1.9 + 9.0


def test_rule_costs_sum_every_job_of_the_build_by_rule_beside_the_plan(tmp_path):
    """Snakemake's report's table (rule ``job_costs``): the owners of a build
    (`run.build_owners`) take every job, the reports too (an orbits entry's under
    ``report/orbits/``), none of another config; the sums by rule and the total row are the
    files' own; the plan's jobs and CPU stand beside them."""
    bench = tmp_path / "benchmarks"
    files = {"simulate_events/mine/0.tsv": (7.5, 480, 7.0),
             "simulate_events/mine/1.tsv": (6.5, 500, 6.0),
             "aggregate_events/mine.tsv": (1.5, 180, 1.4),
             "generate_noise/my_noise.tsv": (2.6, 390, 2.5),
             "solve_orbit_tile/mine/0.tsv": (9, 300, 8.5),
             "draw_figure/orbits/mine/fig16.tsv": (1, 200, 0.9),
             "report/mine/harmonic_random.tsv": (20, 900, 19),
             "report/orbits/mine.tsv": (4, 250, 3.5),
             "draw_sweep/my_sweep.tsv": (2, 210, 1.8),
             "measure_work_precision.tsv": (10, 260, 10.5),
             "simulate_events/other/0.tsv": (9, 999, 9.0)}      # another config's study
    _benchmarks(bench, files)
    build = {"studies": {"mine": {"events"}}, "orbits": {"mine": {"orbits"}},
             "noises": {"my_noise"}, "sweeps": {"my_sweep"}, "validation": {"x"}}
    owners = run.build_owners(build)
    table = run.rule_costs(owners, bench, planned={"simulate_events": (2, 12.0),
                                                   "report": (2, 20.0)})
    mine = {k: v for k, v in files.items() if "other" not in k}
    assert table.loc["all", "jobs"] == len(mine) == table["jobs"].drop("all").sum()
    assert table.loc["simulate_events"].tolist()[:5] == [2, 13.0, 14.0, 7.5, 500]
    assert table.loc["report", "jobs"] == 2 and table.loc["report", "CPU s"] == 22.5
    assert table.loc["all", "CPU s"] == pytest.approx(sum(cpu for _, _, cpu in mine.values()))
    assert table.loc["all", "peak memory MB"] == 900
    assert table.loc["all", "longest job s"] == 20
    assert table.loc["simulate_events", "planned CPU s"] == 12.0
    assert table.loc["generate_noise", "planned jobs"] == 0       # not in the plan given
    run.write_rule_costs(table, tmp_path / "costs.html", tmp_path / "costs.tsv")
    page = (tmp_path / "costs.html").read_text()
    assert f"{len(mine)} jobs of {len(table) - 1} kinds" in page and "<table" in page
    assert sorted(p.name for p in tmp_path.iterdir()) == ["benchmarks", "costs.html",
                                                          "costs.tsv"]
    empty = run.rule_costs(owners, tmp_path / "none")
    assert empty.empty
    run.write_rule_costs(empty, tmp_path / "e.html", tmp_path / "e.tsv")
    assert "No benchmark file" in (tmp_path / "e.html").read_text()
