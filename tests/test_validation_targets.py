"""The validation targets: the work-precision dataset and figure, the stress sample, their rules.

Fast by default: the work-precision measurement runs at a tiny size (two plays, a few impacts,
two tolerances), the stress dataset is built from two real families at a handful of cases, and
the workflow is only dry-run. Nothing asserts a timing: timings are flagged and only their
presence and sign are checked. The end-to-end build of the test config (marker ``workflow``)
checks the files the rules write.
"""
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text

from helpers import assert_figure, make_workdir, scheduled_jobs
from vibroimpact import plotting
from vibroimpact.validation import peers
from vibroimpact.validation.campaign import (CASES, CHUNK_SIZES, COUNTS, FULL_ORBIT_CASES,
                                             ORBIT_CASES, REPLAYS, STREAM_SAMPLES,
                                             campaign_dataset, run_campaign, stress_sample)
from vibroimpact.validation.families import run_family
from vibroimpact.validation.orbit_families import run_orbit_family
from vibroimpact.validation.report import FamilyReport
from vibroimpact.plotting.validation import place_setting_labels
from vibroimpact.validation.work_precision import (DT, EPS, RK4_EVENT, RUN_MEASUREMENTS,
                                                   SIMULATOR, TIMING_STATISTIC, ZETA,
                                                   impact_errors, reference_run, split_time,
                                                   stretch_end, work_precision)

TINY = dict(delta=(1.0, 0.0), impacts=6, stretch=20.0, long_samples=3000, seed=19740072,
            rtol=(1e-3, 1e-9), solvers=("RK45", "DOP853", "LSODA"), rk4_steps=(1, 4, 16),
            repeats=2)
SEED = 20261122


@pytest.fixture(scope="module")
def wp():
    return work_precision(**TINY)


@pytest.fixture(scope="module")
def stress_ds():
    """Two real families at a few cases, and one failing report (so the figure shows both)."""
    reports = [run_family("release_touch", 3, SEED), run_orbit_family("orbit_grazing", 2, SEED)]
    failing = FamilyReport(family="made_to_fail", tolerance=1.0, measure="error / allowance",
                           cases=4, missed=1, exceptions=1)
    failing.add_error(3.5, {"zeta": 0.05, "noise": [0.0, 1.0]})
    failing.fail({"zeta": 0.05}, "missed an impact")
    return campaign_dataset(reports + [failing], dict(seed=SEED, size="quick"))


# --- the work-precision dataset ---------------------------------------------------------------

def test_work_precision_layout(wp):
    runs = 1 + len(TINY["solvers"]) * len(TINY["rtol"]) + len(TINY["rk4_steps"])
    assert dict(wp.sizes) == {"delta": 2, "run": runs}
    assert list(wp["delta"].values) == [1.0, 0.0]
    assert wp["method"].values[0] == SIMULATOR
    assert set(wp["method"].values) == {SIMULATOR, RK4_EVENT,
                                        *(f"solve_ivp {s}" for s in TINY["solvers"])}
    assert sorted(wp["steps_per_sample"].values[wp["method"].values == RK4_EVENT]) == [1, 4, 16]
    for name in wp.variables:
        assert {"long_name", "units"} <= set(wp[name].attrs), name
    flagged = {v for v in wp.variables if wp[v].attrs.get("run_measurement") == 1}
    assert flagged == set(RUN_MEASUREMENTS)
    assert wp["cost"].attrs["units"] == "s" and wp["seconds"].attrs["units"] == "s"
    assert wp.attrs["zeta"] == ZETA and wp.attrs["eps"] == EPS and wp.attrs["dt"] == DT
    assert wp.attrs["seed"] == TINY["seed"]


def test_work_precision_values(wp):
    assert np.all(wp["n_compared"] >= 3)
    assert np.all(wp["cost"] > 0) and np.all(np.isfinite(wp["cost"]))
    # every run's ratios are to the simulator's run (run 0) of the same play
    sim = wp.isel(run=0)
    assert wp["method"].values[0] == SIMULATOR
    np.testing.assert_allclose(wp["cost_ratio"], wp["cost"] / sim["cost"], rtol=1e-15, atol=0)
    np.testing.assert_allclose(wp["error_ratio"], wp["error"] / sim["error"], rtol=1e-15,
                               atol=0)
    np.testing.assert_allclose(wp["error"], np.maximum(wp["err_time"], wp["err_velocity"]))
    np.testing.assert_allclose(wp["cost"], wp["seconds"] / wp["timed_span"], rtol=1e-12)
    # the compiled methods are timed on the long record, solve_ivp on the first `stretch`
    # time units (its errors are taken over the whole compared stretch, t_stretch >= stretch)
    adaptive = np.isfinite(wp["rtol"].values)
    assert np.all(wp["timed_span"].values[:, ~adaptive] == TINY["long_samples"] * DT)
    np.testing.assert_allclose(wp["timed_span"].values[:, adaptive], TINY["stretch"], rtol=1e-12)
    assert np.all(wp["t_stretch"] >= TINY["stretch"])


def test_every_method_is_timed_the_same_way(wp):
    """Same repeats and the same statistic for every method, stated in the dataset."""
    np.testing.assert_array_equal(wp["timing_repeats"].values, TINY["repeats"])
    assert wp.attrs["timing_repeats"] == TINY["repeats"]
    assert wp.attrs["timing_statistic"] == TIMING_STATISTIC == "min"
    assert f"{TINY['repeats']} runs, the fastest kept" in wp.attrs["timing"]
    assert "fastest" in wp["seconds"].attrs["long_name"]
    assert np.all(wp["timing_spread"] >= 0.0) and np.all(np.isfinite(wp["timing_spread"]))
    assert {"load_average_start", "load_average_end"} <= set(wp.attrs)
    assert "restarted at every force sample" in wp.attrs["solve_ivp_restart"]


def test_restarted_dop853_hardly_depends_on_rtol(wp):
    """The reason DOP853 at a loose tolerance can be the most accurate peer: restarted at
    every force sample, no step of it exceeds dt, and one step of dt is already accurate, so
    its error moves by less than 10x from rtol 1e-3 to 1e-9, while RK45's falls by more than
    10x (measured: DOP853 x2.4 and x1.0, RK45 x18 and x65 at delta = 1 and 0)."""
    for delta in TINY["delta"]:
        row = wp.sel(delta=delta)
        for solver, within in (("DOP853", True), ("RK45", False)):
            error = row["error"].values[row["method"].values == f"solve_ivp {solver}"]
            assert np.all(error < 1e-3), (delta, solver, error)
            assert (error.max() / error.min() < 10.0) == within, (delta, solver, error)


def test_simulator_error_is_below_every_peer_and_at_round_off(wp):
    """Measured at these settings: every peer run's error exceeds the simulator's, which is
    within 10x of the round-off level (the error of a 53-bit run of the reference)."""
    for delta in wp["delta"].values:
        row = wp.sel(delta=delta)
        sim = float(row["error"].isel(run=0))
        peer = row["error"].values[1:]
        assert np.all(peer > sim), (delta, sim, peer)
        assert sim <= 10.0 * float(row["roundoff"]), (delta, sim, float(row["roundoff"]))


def test_work_precision_is_reproducible():
    """Same arguments, same data: only the variables flagged as run measurements differ."""
    small = dict(TINY, delta=(0.0,), impacts=3, stretch=10.0, long_samples=500, rtol=(1e-3,),
                 solvers=("DOP853",), rk4_steps=(2,))
    a, b = work_precision(**small), work_precision(**small)
    keep = [v for v in a.variables if a[v].attrs.get("run_measurement") != 1]
    xr.testing.assert_identical(a[keep].drop_attrs(), b[keep].drop_attrs())


def test_work_precision_rejects_bad_arguments():
    with pytest.raises(ValueError, match="long_samples"):
        work_precision(**dict(TINY, long_samples=100))
    with pytest.raises(ValueError, match="solvers"):
        work_precision(**dict(TINY, solvers=("Euler",)))
    with pytest.raises(ValueError, match="max_stretch"):
        work_precision(**dict(TINY, max_stretch=10.0))


def test_the_compared_stretch_lies_between_stretch_and_max_stretch():
    """Just past the n-th fast impact, never before `stretch` nor after `max_stretch`."""
    t = np.array([3.0, 10.0, 40.0, 90.0])
    u = np.ones(4)
    assert stretch_end(t, u, 2, 5.0, 10_001) == pytest.approx(1.05 * 10.0 + 2.0, abs=DT)
    assert stretch_end(t, u, 1, 5.0, 10_001) == pytest.approx(5.2, abs=1e-9)  # 5.15, on the grid
    assert stretch_end(t, u, 1, 8.0, 10_001) == pytest.approx(8.0, abs=1e-9)  # at least stretch
    assert stretch_end(t, u, 4, 5.0, 10_001) == pytest.approx(96.5, abs=1e-9)
    assert stretch_end(t, u, 4, 5.0, 10_001, 60.0) == pytest.approx(60.0, abs=1e-9)
    assert stretch_end(t, u, 1, 5.0, 10_001, 5.0) == pytest.approx(5.0, abs=1e-9)
    assert stretch_end(t, u, 4, 5.0, 301) == pytest.approx(30.0, abs=1e-9)  # the record's end


def test_a_longest_stretch_compares_fewer_impacts_with_the_same_errors():
    """Capping the stretch drops the last impacts; the errors over the impacts still compared
    are those of the uncapped run's first impacts (runs restart at every sample)."""
    small = dict(TINY, delta=(1.0,), impacts=3, stretch=5.0, long_samples=1000,
                 rtol=(1e-6,), solvers=("DOP853",), rk4_steps=(2,), repeats=1)
    full = work_precision(**small)
    capped = work_precision(**dict(small, max_stretch=35.0))
    assert float(capped["t_stretch"][0]) == pytest.approx(35.0)
    assert float(full["t_stretch"][0]) > 35.0
    assert 1 <= int(capped["n_compared"][0]) < int(full["n_compared"][0])
    assert capped.attrs["stretch_max"] == 35.0
    assert np.all(capped["error"].values <= full["error"].values)


# --- the fixed-step peer with event location ----------------------------------------------------

@pytest.mark.parametrize("delta, steps", [(1.0, (1, 2, 4, 8)), (0.0, (2, 4, 8, 16))])
def test_rk4_event_location_converges_at_fourth_order(delta, steps):
    """Impact time and velocity errors fall as h^4: the fitted order lies within 0.3 of 4
    (measured: 4.08 and 4.07 at delta = 1; 4.14 and 4.14 at delta = 0, from chatter-free
    impacts of a 100-unit record)."""
    noise = np.random.default_rng(19740072).standard_normal(1001)
    _, ref = reference_run(delta, noise, 100.0)
    n = min(10, ref[0].size)
    errors = []
    for k in steps:
        t_imp, u_imp = peers.rk4_event_impacts(ZETA, EPS, delta, noise, DT, k)
        errors.append(impact_errors(ref, *split_time(t_imp), u_imp, n))
    errors = np.array(errors)
    h = DT / np.array(steps)
    for column in errors.T:
        order = np.polyfit(np.log(h), np.log(column), 1)[0]
        assert abs(order - 4.0) < 0.3, (delta, column, order)


def test_event_location_catches_a_flight_inside_one_step():
    """Both ends of a step below the wall, the interpolant above it in between: the event is
    the interpolant's first upward zero, not a sign change of the end points. Here the cubic
    Hermite interpolant is the parabola p = -0.01 + 0.2 theta (1 - theta) (exactly), whose
    upward zero is (1 - sqrt(0.8)) / 2."""
    theta = peers._first_upcrossing(-0.01, 0.2, -0.01, -0.2, 0.0)
    assert theta == pytest.approx((1.0 - np.sqrt(0.8)) / 2.0, abs=1e-15)
    assert peers._first_upcrossing(-0.01, 0.2, -0.01, -0.2, 0.5) == -1.0   # only a way down
    assert peers._first_upcrossing(-0.01, -0.1, -0.02, -0.1, 0.0) == -1.0  # no contact


def test_rk4_event_location_checks_its_arguments():
    noise = np.zeros(11)
    with pytest.raises(ValueError, match="steps_per_sample"):
        peers.rk4_event_impacts(ZETA, EPS, 0.0, noise, DT, 0)
    with pytest.raises(ValueError, match="x0"):
        peers.rk4_event_impacts(ZETA, EPS, 0.0, noise, DT, 1, x0=0.5)


# --- the stress dataset -----------------------------------------------------------------------

def test_stress_dataset_layout(stress_ds):
    assert list(stress_ds["family"].values) == ["release_touch", "orbit_grazing", "made_to_fail"]
    for name in COUNTS:
        assert stress_ds[name].dtype == np.int64, name
    for name in stress_ds.variables:
        assert {"long_name", "units"} <= set(stress_ds[name].attrs), name
    flagged = {v for v in stress_ds.variables if stress_ds[v].attrs.get("run_measurement") == 1}
    assert flagged == {"seconds", "details"}
    assert list(stress_ds["failed"].values) == [0, 0, 1]
    assert list(stress_ds["cases"].values[:2]) == [3, 2]
    assert "noise=[2 values]" in str(stress_ds["worst_case"].values[2])
    assert "missed an impact" in str(stress_ds["first_failure"].values[2])
    assert stress_ds["first_failure"].values[0] == ""


def test_the_campaign_sizes_nest():
    """Every family at every size; the sample no larger than the quick sample, itself no larger
    than the full campaign; the sample's record streamed in three chunk sizes (one not a power
    of two), all but the last shorter than the record."""
    orbit_cases = dict(ORBIT_CASES, full=min(FULL_ORBIT_CASES.values()))
    for small, large in (("sample", "quick"), ("quick", "full")):
        assert CASES[small].keys() == CASES[large].keys()
        assert all(1 <= CASES[small][k] <= CASES[large][k] for k in CASES[small])
        assert 1 <= orbit_cases[small] <= orbit_cases[large]
        assert STREAM_SAMPLES[small] <= STREAM_SAMPLES[large]
        assert 1 <= REPLAYS[small] <= REPLAYS[large]
    chunks = CHUNK_SIZES["sample"]
    assert len(chunks) >= 3 and any(c & (c - 1) for c in chunks)
    assert all(c < STREAM_SAMPLES["sample"] for c in chunks[:-1])


def test_the_sample_draws_the_first_cases_of_the_quick_sample():
    """A smaller size runs the first cases of the same seeded sequence: its worst error cannot
    exceed the larger size's over the same family."""
    few, more = run_family("release_touch", 3, SEED), run_family("release_touch", 8, SEED)
    assert few.compared <= more.compared
    assert few.worst_error <= more.worst_error


def test_campaign_sizes_are_checked():
    with pytest.raises(ValueError, match="size"):
        run_campaign(SEED, size="huge")
    with pytest.raises(ValueError, match="size"):
        stress_sample(SEED, size="full")


def test_stress_dataset_survives_netcdf(stress_ds, tmp_path):
    path = tmp_path / "stress.nc"
    stress_ds.to_netcdf(path)
    back = xr.load_dataset(path)
    xr.testing.assert_identical(back, stress_ds)


# --- the figures ---------------------------------------------------------------------------------

def _inside_and_apart(fig, axes):
    """Every setting label lies inside its axes and overlaps no other label."""
    renderer = fig.canvas.get_renderer()
    boxes = []
    for ax in axes:
        frame = ax.get_window_extent(renderer)
        for text in ax.texts:
            if text.get_gid() != "setting_label":
                continue
            box = Text.get_window_extent(text, renderer)
            assert frame.x0 <= box.x0 and box.x1 <= frame.x1, text.get_text()
            assert frame.y0 <= box.y0 and box.y1 <= frame.y1, text.get_text()
            boxes.append(box)
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            assert not a.overlaps(b), (a, b)
    return len(boxes)


def test_work_precision_figure(wp):
    fig = plotting.work_precision(wp)
    assert isinstance(fig, Figure)
    axes = [ax for ax in fig.axes if ax.get_xscale() == "log"]
    assert len(axes) == wp.sizes["delta"]
    header = fig.get_suptitle()
    assert header.count("\n") <= 2     # a title and at most two lines of parameters
    assert f"fastest of {TINY['repeats']} runs" in header
    words = re.sub(r"\$[^$]*\$", "", header)      # outside mathtext: symbols, not config keys
    assert "delta" not in words and "dt" not in words and "rtol=" not in words
    assert r"$\tau$" in axes[0].get_ylabel() and "$e$" in axes[0].get_xlabel()
    fig.canvas.draw()
    assert _inside_and_apart(fig, axes) >= 4
    renderer = fig.canvas.get_renderer()
    for text in fig.texts:          # the header and the footnote fit the figure's width
        box = text.get_window_extent(renderer)
        assert fig.bbox.x0 <= box.x0 and box.x1 <= fig.bbox.x1, text.get_text()
    for ax, delta in zip(axes, [1.0, 0.0]):
        assert f"= {delta:g}:" in ax.get_title()
        stars = [ln for ln in ax.get_lines() if ln.get_gid() == "simulator"]
        assert len(stars) == 1
        x, y = stars[0].get_data()
        row = wp.sel(delta=delta).isel(run=0)
        np.testing.assert_allclose([x[0], y[0]], [float(row["error"]), float(row["cost"])])
        assert any(ln.get_gid() == "roundoff" for ln in ax.get_lines())
        assert ax.get_yscale() == "log"


def test_the_most_accurate_peer_insensitive_to_rtol_gets_the_restart_footnote(wp):
    """DOP853 is the most accurate peer of both plays here, with errors within 10x over rtol
    (test_restarted_dop853_hardly_depends_on_rtol): its titles are starred, and the footnote
    gives the reason and its errors' spread at each play."""
    fig = plotting.work_precision(wp)
    titles = [ax.get_title() for ax in fig.axes if ax.get_xscale() == "log"]
    assert all("DOP853" in t and "*" in t for t in titles), titles
    [text] = [t.get_text() for t in fig.texts if t.get_gid() == "footnote"]
    assert "restarted at every force sample" in text and "piecewise linear" in text
    assert text.count(r"at $\delta$ =") == 2


def test_setting_labels_never_overlap_or_leave_the_axes():
    """Twelve labels crowded on three points near a corner: those placed are inside the axes
    and apart, the rest are left out."""
    fig = Figure(figsize=(3.0, 2.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(1e-12, 1e2)
    ax.set_ylim(1e-7, 1e-2)
    points = [(30.0, 8e-3), (50.0, 7e-3), (20.0, 9e-3)]
    ax.plot(*zip(*points), marker="s")
    labels = [(x, y, f"1e-{k}", "C1", k % 2) for k in range(12) for x, y in points[k % 3:][:1]]
    fig.draw_without_rendering()
    placed = place_setting_labels(ax, labels, fig.canvas.get_renderer())
    fig.canvas.draw()
    assert 1 <= len(placed) < len(labels)
    assert _inside_and_apart(fig, [ax]) == len(placed)


def test_stress_figure(stress_ds):
    fig = plotting.stress(stress_ds)
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert ax.get_xscale() == "log"
    assert [t.get_text() for t in ax.get_yticklabels()] == list(stress_ds["family"].values)
    assert any(ln.get_gid() == "allowance" for ln in ax.get_lines())
    texts = " ".join(t.get_text() for t in fig.axes[1].texts)
    assert "FAILED 1" in texts and "missed 1" in texts and "exceptions 1" in texts
    fig.canvas.draw()


def test_figures_save_png_and_pdf(wp, stress_ds, tmp_path):
    for name, ds in (("work_precision", wp), ("stress", stress_ds)):
        png, pdf = plotting.save(getattr(plotting, name)(ds), tmp_path / f"{name}.png")
        assert_figure(png)
        assert_figure(pdf)


# --- the rules -----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return make_workdir(tmp_path_factory.mktemp("validation_wf"))


@pytest.mark.parametrize("figure, rules", [
    ("work_precision", {"measure_work_precision", "draw_validation_figure"}),
    ("stress", {"sample_stress_families", "draw_validation_figure"}),
])
def test_a_validation_figure_schedules_only_its_rules(workdir, figure, rules):
    """The PNG and the PDF in one dry run: the jobs of both are these rules."""
    jobs = scheduled_jobs(workdir, f"results/figures/{figure}.png",
                          f"results/figures/{figure}.pdf")
    assert {j["rule"] for j in jobs} == rules
    drawn = next(j for j in jobs if j["rule"] == "draw_validation_figure")["output"]
    assert {f"results/figures/{figure}.png", f"results/figures/{figure}.pdf"} <= drawn


@pytest.mark.workflow
def test_the_validation_targets_are_built(built):
    """The test config's build: both datasets with provenance, both figures as PNG and PDF."""
    results = Path(built) / "results"
    for name in ("work_precision", "stress"):
        for ext in ("png", "pdf"):
            assert_figure(results / "figures" / f"{name}.{ext}")
    for name in ("work_precision", "stress_sample"):
        ds = xr.load_dataset(results / "validation" / f"{name}.nc")
        assert {"config", "config_digest", "git_commit", "seed"} <= set(ds.attrs)
        assert any(ds[v].attrs.get("run_measurement") == 1 for v in ds.variables)
    for rule in ("measure_work_precision", "sample_stress_families"):
        assert (results / "benchmarks" / f"{rule}.tsv").is_file()


def test_the_plan_costs_the_validation_runs_from_their_sizes():
    """The plan's cost of the two runs follows the config: more repeats, a longer timed or
    compared stretch, more plays cost more; the quick stress sample more than the sample."""
    from vibroimpact.pipeline.config import costs

    block = dict(delta=[1.0, 0.0, -0.5], impacts=20, stretch=5.0, max_stretch=60.0,
                 long_samples=20_000, rtol=[1e-3, 1e-6, 1e-9, 1e-12],
                 solvers=["RK45", "DOP853", "LSODA"], rk4_steps=[1, 2, 4, 8, 16, 32, 64],
                 repeats=3)
    base = costs.work_precision_cpu_s(block)
    for change in (dict(repeats=6), dict(stretch=20.0), dict(max_stretch=200.0, impacts=60),
                   dict(delta=[1.0, 0.0, -0.5, 2.0]), dict(long_samples=100_000)):
        assert costs.work_precision_cpu_s(dict(block, **change)) > base, change
    assert costs.work_precision_cpu_s(dict(block, impacts=1)) < base
    assert costs.stress_cpu_s({"size": "quick"}) > costs.stress_cpu_s({"size": "sample"})


def test_the_campaign_table_is_the_slow_suites():
    """``workflow/notebooks/stress_campaign.csv`` (the stability report's and the README's
    table) is :func:`campaign_table` of a full campaign: every family in the campaign's
    order, at the full campaign's sizes, with its columns."""
    from vibroimpact.reports.notebook import csv_table
    from vibroimpact.validation.campaign import TABLE_COLUMNS
    from vibroimpact.validation.families import FULL_CASES
    from vibroimpact.validation.orbit_families import FAMILIES as ORBIT_FAMILIES
    from vibroimpact.validation.streaming import FAMILY as STREAMED

    table = csv_table(Path(__file__).parents[1] / "workflow" / "notebooks"
                      / "stress_campaign.csv")
    assert tuple(table.columns) == TABLE_COLUMNS
    sizes = dict(FULL_CASES, **FULL_ORBIT_CASES, **{STREAMED: 3})
    assert list(table["family"]) == list(FULL_CASES) + list(ORBIT_FAMILIES) + [STREAMED]
    assert [int(c) for c in table["cases"]] == [sizes[f] for f in table["family"]]


def test_the_campaign_table_reads_the_reports():
    from vibroimpact.validation.campaign import campaign_table
    from vibroimpact.validation.report import FamilyReport

    a = FamilyReport("a", tolerance=1e-3, measure="m", cases=5, compared=40, missed=1,
                     worst_error=2.5e-4, extra={"ambiguous": 3})
    b = FamilyReport("b", tolerance=1e-9, measure="m", cases=3, compared=7,
                     worst_error=2.1e-14)
    got = campaign_table([a, b])
    assert got.values.tolist() == [["a", "5", "40", "1", "0", "0", "0.25", "3"],
                                   ["b", "3", "7", "0", "0", "0", "2.1e-05", ""]]
