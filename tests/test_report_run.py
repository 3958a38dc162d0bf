"""A report's "Run" section (`vibroimpact.reports.run`): the versions each dataset recorded
beside the report's own environment, and the costs of the jobs behind it from Snakemake's
benchmark files."""
import json

import xarray as xr

from vibroimpact._release import SOFTWARE, software
from vibroimpact.pipeline.provenance import provenance
from vibroimpact.reports import run

HEADER = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


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
    files = {"simulate_events/mine/0.tsv": "7.5\t0:00:07\t480\t0\t0\t0\t0\t0\t90\t7.0\n",
             "aggregate_events/mine.tsv": "1.5\t0:00:01\t180\t0\t0\t0\t0\t0\t50\t1.4\n",
             "generate_noise/my_noise.tsv": "2.6\t0:00:02\t390\t0\t0\t0\t0\t0\t80\t2.5\n",
             "draw_figure/orbits/mine/fig16.tsv": "1\t0:00:01\t200\t0\t0\t0\t0\t0\t80\t0.9\n",
             "simulate_events/other/0.tsv": "9\t0:00:09\t999\t0\t0\t0\t0\t0\t90\t9.0\n",
             "report/mine/harmonic_random.tsv": "20\t0:00:20\t900\t0\t0\t0\t0\t0\t90\t19\n"}
    for rel, row in files.items():
        (bench / rel).parent.mkdir(parents=True, exist_ok=True)
        (bench / rel).write_text(HEADER + row)
    costs = run.job_costs(["mine", "noise/my_noise", "orbits/mine"], bench)
    assert list(costs.rule) == ["aggregate_events", "draw_figure", "generate_noise",
                                "simulate_events"]
    assert costs["CPU s"].sum() == 7.0 + 1.4 + 2.5 + 0.9
    assert costs["peak memory MB"].max() == 480
    assert run.job_costs(["mine"], tmp_path / "none").empty
    (bench / "measure_work_precision.tsv").write_text(HEADER + files["aggregate_events/mine.tsv"])
    one = run.job_costs(["measure_work_precision"], bench)     # a rule of one job
    assert one[["rule", "job"]].values.tolist() == [["measure_work_precision", ""]]


def test_a_study_and_an_orbits_entry_of_one_name_own_their_own_jobs(tmp_path):
    """config.yaml names a study and an orbits entry ``harmonic``: the orbits report counts
    the entry's jobs and the map it reads, not the study's simulations; the study's report
    not the entry's tiles. A value Snakemake could not measure ("-") is no number."""
    bench = tmp_path / "benchmarks"
    files = {"simulate_events/harmonic/0.tsv": "7\t0:00:07\t480\t0\t0\t0\t0\t0\t90\t7.0\n",
             "draw_figure/harmonic/fig11.tsv": "1\t0:00:01\t200\t0\t0\t0\t0\t0\t80\t0.9\n",
             "solve_orbit_tile/harmonic/0.tsv": "9\t0:00:09\t300\t0\t0\t0\t0\t0\t90\t9.0\n",
             "aggregate_attractors/harmonic.tsv": "1\t0:00:01\t-\t0\t0\t0\t0\t0\t90\t0.5\n",
             "draw_figure/orbits/harmonic/fig16.tsv": "2\t0:00:02\t250\t0\t0\t0\t0\t0\t80\t1.9\n",
             "simulate_map/motion_map/0.tsv": "30\t0:00:30\t500\t0\t0\t0\t0\t0\t90\t29\n",
             "simulate_escape/motion_map/0.tsv": "5\t0:00:05\t400\t0\t0\t0\t0\t0\t90\t4.9\n",
             "generate_noise/harmonic.tsv": "2\t0:00:02\t390\t0\t0\t0\t0\t0\t80\t2.0\n"}
    for rel, row in files.items():
        (bench / rel).parent.mkdir(parents=True, exist_ok=True)
        (bench / rel).write_text(HEADER + row)
    jobs = {owners: [str(p.relative_to(bench)) for p in run.owner_jobs(owners, bench)]
            for owners in [("orbits/harmonic", "map/motion_map"), ("harmonic",)]}
    assert jobs[("orbits/harmonic", "map/motion_map")] == [
        "aggregate_attractors/harmonic.tsv", "draw_figure/orbits/harmonic/fig16.tsv",
        "simulate_map/motion_map/0.tsv", "solve_orbit_tile/harmonic/0.tsv"]
    assert jobs[("harmonic",)] == ["draw_figure/harmonic/fig11.tsv",
                                   "simulate_events/harmonic/0.tsv"]
    costs = run.job_costs(["orbits/harmonic"], bench)
    assert costs["peak memory MB"].isna().sum() == 1 and costs["CPU s"].sum() == 0.5 + 1.9 + 9.0
