"""Escape against noise level: the fit, the cell, the seeds, the config, the figure, the rules.

- `stats.escape_fit` recovers a known slope of ln T against 1/rms^2;
- `pipeline.cells.escape_cell` labels its record as `motion_map_cell` does (bit for bit);
- each noise level's record is seeded ``SeedSequence(seed, spawn_key=(k,))``;
- a bad ``escape`` block is refused naming its key;
- `plotting.escape_vs_noise` draws points, excluded points and fitted lines;
- the figure needs only the escape jobs (dry run), and builds (``workflow``).
"""
import copy

import numpy as np
import pytest
import xarray as xr
import yaml
from matplotlib.backends.backend_agg import FigureCanvasAgg

from vibroimpact import Model, stats
from vibroimpact.noise import NoiseSpec, generate_array
from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline import datasets, tasks
from vibroimpact.pipeline.cells import escape_cell, motion_map_cell
from vibroimpact.pipeline.study import escape_samples, escape_seed

from helpers import ROOT, assert_figure, make_workdir, scheduled_rules, snakemake

TEST_CONFIG = yaml.safe_load((ROOT / "config" / "test.yaml").read_text())
SYSTEM = dict(zeta=0.05, eps=0.5, amplitude=1.0)


# --- the fit ---------------------------------------------------------------------------------

def test_fit_recovers_a_known_slope_exactly_from_exact_data():
    x = 1.0 / np.array([0.15, 0.18, 0.22, 0.29]) ** 2
    t = 3.0 * np.exp(0.16 * x)
    fit = stats.escape_fit(x, t, 0.05 * t, np.full(4, 100))
    assert fit.slope == pytest.approx(0.16, rel=1e-12)
    assert fit.intercept == pytest.approx(np.log(3.0), rel=1e-12)
    assert fit.chi2_red == pytest.approx(0.0, abs=1e-20) and fit.n_used == 4
    # unscaled (chi2_red < 1): the standard error the errors give (numpy's unscaled
    # covariance of the same weighted line, computed apart)
    _, cov = np.polyfit(x, np.log(t), 1, w=1.0 / np.full(4, 0.05), cov="unscaled")
    assert fit.slope_stderr == pytest.approx(np.sqrt(cov[0, 0]), rel=1e-9)


@pytest.mark.parametrize("k", [3, 4, 6])
def test_the_interval_is_students_t_at_k_minus_2_degrees_of_freedom(k):
    """A known small sample: the half-width is scipy.stats.t.ppf(0.975, K - 2) standard
    errors (12.71, 4.30, 2.78), not the normal 1.96, whether or not the scatter is scaled."""
    from scipy.stats import norm, t as student

    rng = np.random.default_rng(k)
    x = 1.0 / np.linspace(0.15, 0.3, k) ** 2
    for rel in (0.5, 0.001):                     # chi2_red < 1, then > 1
        t = 2.0 * np.exp(0.1 * x + 0.05 * rng.standard_normal(k))
        fit = stats.escape_fit(x, t, rel * t, np.full(k, 50))
        q = student.ppf(0.975, k - 2)
        assert (fit.chi2_red > 1.0) == (rel < 0.01)
        assert fit.slope_hi - fit.slope == pytest.approx(q * fit.slope_stderr, rel=1e-10)
        assert fit.slope - fit.slope_lo == pytest.approx(q * fit.slope_stderr, rel=1e-10)
        assert q > norm.ppf(0.975) + 0.8


def test_an_overdispersed_fit_scales_its_covariance_by_chi2_per_dof():
    """ln T curved: chi2_red > 1 and the slope's standard error is sqrt(chi2_red) times the
    errors' one, numpy's scaled covariance of the same weighted line (chi^2 / nu, computed
    apart); the interval t(0.975, 2) = 4.303 of those."""
    x = 1.0 / np.array([0.15, 0.18, 0.22, 0.29]) ** 2
    t = 3.0 * np.exp(0.16 * x - 0.001 * x ** 2)
    fit = stats.escape_fit(x, t, 0.01 * t, np.full(4, 100))
    assert fit.chi2_red > 1.0
    y, w = np.log(t), np.full(4, 1.0 / 0.01)
    _, scaled = np.polyfit(x, y, 1, w=w, cov=True)
    _, unscaled = np.polyfit(x, y, 1, w=w, cov="unscaled")
    assert fit.slope_stderr == pytest.approx(np.sqrt(scaled[0, 0]), rel=1e-9)
    assert fit.slope_stderr == pytest.approx(np.sqrt(fit.chi2_red * unscaled[0, 0]), rel=1e-9)
    assert fit.slope_hi - fit.slope == pytest.approx(4.302653 * fit.slope_stderr, rel=1e-6)


@pytest.mark.parametrize("spread", [1.0, 3.0])
def test_fit_covers_the_slope_of_noisy_data_at_least_at_its_confidence(spread):
    """500 synthetic data sets of 5 levels, each ln T off by ``spread`` times its stated
    error. The interval holds the true slope in at least 95 % of them (binomial 3 sigma,
    -3 %, allowed): as stated (spread 1) the t interval on 3 degrees of freedom, scaled only
    when chi2_red > 1, is conservative (measured 500 of 500; the errors' own normal interval
    94.8 %); with the errors understated three times (overdispersion) the scale keeps it at
    96.4 %, where the errors' own normal interval covers 50.4 %. chi2_red ~ spread^2."""
    rng = np.random.default_rng(7)
    x = 1.0 / np.array([0.15, 0.18, 0.22, 0.26, 0.29]) ** 2
    rel = np.array([0.2, 0.08, 0.04, 0.02, 0.015])     # few stretches where T is long
    hits, chi2 = 0, []
    for _ in range(500):
        t = 2.0 * np.exp(0.07 * x + spread * rel * rng.standard_normal(5))
        fit = stats.escape_fit(x, t, rel * t, np.full(5, 50))
        hits += fit.slope_lo <= 0.07 <= fit.slope_hi
        chi2.append(fit.chi2_red)
    assert hits / 500 >= 0.95 - 0.03
    assert np.mean(chi2) == pytest.approx(spread ** 2, rel=0.15)


def test_fit_leaves_out_levels_with_few_stretches_or_above_the_cut():
    x = 1.0 / np.array([0.15, 0.18, 0.2, 0.29, 0.4]) ** 2
    t = np.exp(0.1 * x)
    t_bad = t.copy()
    t_bad[0] *= 50.0                                     # a wild mean of few stretches
    t_bad[4] *= 0.01                                     # strong noise off the law
    fit = stats.escape_fit(x, t_bad, 0.01 * t, [3, 30, 30, 30, 30], min_stretches=20,
                           allowed=[True, True, True, True, False])
    assert fit.used.tolist() == [False, True, True, True, False] and fit.n_used == 3
    assert fit.slope == pytest.approx(0.1, rel=1e-12) and fit.chi2_red < 1e-20


@pytest.mark.parametrize("n", [[30, 30, 3], [30, 30, 30]])
def test_a_fit_through_two_levels_is_refused(n):
    """Two usable levels (a third with few stretches, or at the same rms): no fit, as with
    fewer; a line through two points has no residual to scale or quantile to take."""
    x = [10.0, 20.0, 30.0] if n[2] == 3 else [10.0, 20.0, 20.0]
    fit = stats.escape_fit(x, [5.0, 9.0, 20.0], [0.5, 0.9, 2.0], n)
    assert np.isnan([fit.slope, fit.slope_lo, fit.slope_hi, fit.chi2_red]).all()
    assert fit.n_used == 0 and not fit.used.any()
    fit = stats.escape_fit([10.0, 20.0], [5.0, np.nan], [0.5, np.nan], [30, 0])
    assert np.isnan(fit.slope) and fit.n_used == 0 and not fit.used.any()


def test_the_censored_bound_marks_only_a_motion_never_left():
    """Levels: a mean exists; never left (one cut stretch over the whole record); left once
    (two cut stretches); seen once before the motion settled (a short cut stretch); not seen."""
    bound = stats.censored_bound(n_stretches=[25, 0, 0, 0, 0], n_censored=[2, 1, 2, 1, 0],
                                 censored_time=[40.0, 3000.0, 2800.0, 0.4, 0.0],
                                 probability=[0.9, 1.0, 0.97, 1e-4, 0.0])
    np.testing.assert_array_equal(bound, [np.nan, 3000.0, 1400.0, np.nan, np.nan])


# --- the cell and its seeds ------------------------------------------------------------------

def test_escape_cell_labels_as_motion_map_cell_bit_for_bit():
    """The same record, the same cell: motion_map_cell stopped at the same sample (a target it
    reaches at once, min_time = record_length) gives identical residence times."""
    transient, length, dt = 200.0, 3000.0, 0.1
    r = generate_array(NoiseSpec("band_limited", 0.29, dt, 4.0),
                       escape_samples(transient, length, dt) + 400, 5)
    beta_f = 1.0 / 1.1
    for delta in (1.0, 0.1, 2.5):
        model = Model.paper(SYSTEM["zeta"], SYSTEM["eps"], delta, SYSTEM["amplitude"], beta_f)
        got = escape_cell(r, dt, model, transient=transient, record_length=length)
        ref = motion_map_cell(r, dt, model, transient=transient, target_stderr=0.5,
                              min_time=length, max_periods=int(length * beta_f / (2 * np.pi)) + 1,
                              min_switches=1)
        assert got["record_end"] == ref["record_end"] == transient + length
        for key in ("residence_time", "residence_time_stderr", "n_stretches", "n_censored"):
            np.testing.assert_array_equal(got[key], ref[key], err_msg=key)
        shares = np.append(ref["probability"] + ref["stick_probability"], 0.0)
        np.testing.assert_allclose(got["probability"][:-1], shares[:-1], rtol=0, atol=0)
        assert got["probability"].sum() == pytest.approx(1.0, abs=1e-12)
        assert got["n_collisions"] == ref["n_collisions"]


def test_escape_cell_refuses_a_short_record():
    with pytest.raises(ValueError, match="record_length"):
        escape_cell(np.zeros(100), 0.1, Model.paper(0.05, 0.5, 1.0, 1.0, 1.0), transient=5.0,
                    record_length=10.0)


def test_each_level_is_the_spawned_child_of_the_noise_seed():
    draw = [np.random.Generator(np.random.PCG64(escape_seed(19741001, k))).random(4)
            for k in range(3)]
    children = np.random.SeedSequence(19741001).spawn(3)
    for k in range(3):
        np.testing.assert_array_equal(
            draw[k], np.random.Generator(np.random.PCG64(children[k])).random(4))
    assert not np.array_equal(draw[0], draw[1])


# --- the config ------------------------------------------------------------------------------

def _refused(change):
    """The problems of test.yaml with ``change(cfg)`` applied to a copy."""
    cfg = copy.deepcopy(TEST_CONFIG)
    change(cfg)
    with pytest.raises(configuration.ConfigError) as info:
        configuration.load(cfg, root=ROOT)
    problems = info.value.problems
    assert all(len(p.splitlines()) <= 2 for p in problems)
    return "\n".join(problems)


def _escape(cfg):
    return cfg["studies"]["motion_map"]["escape"]


@pytest.mark.parametrize("change, key, fragment", [
    (lambda c: _escape(c).update(cells=[]), "studies.motion_map.escape.cells", "empty"),
    (lambda c: _escape(c).update(rms=[0.2, 0.0]), "studies.motion_map.escape.rms[1]", "> 0"),
    (lambda c: _escape(c).update(rms=[0.2, -0.3]), "studies.motion_map.escape.rms[1]", "> 0"),
    (lambda c: _escape(c).update(rms=[0.2, 0.3]), "studies.motion_map.escape.rms",
     "at least 3"),
    (lambda c: _escape(c).update(rms=[0.2, 0.3, 0.2]), "studies.motion_map.escape.rms",
     "listed more than once"),
    (lambda c: _escape(c).update(cells=[[1.0, 1.0], [5.0, 1.0]]),
     "studies.motion_map.escape.cells[1]", "inv_beta in [0.5, 2.5]"),
    (lambda c: _escape(c).update(cells=[[1.0, 7.0]]),
     "studies.motion_map.escape.cells[0]", "delta in [-1, 3]"),
    (lambda c: _escape(c).update(cells=[[-1.0, 1.0]]),
     "studies.motion_map.escape.cells[0]", "inv_beta > 0"),
    (lambda c: _escape(c).update(cells=[[1.0]]), "studies.motion_map.escape.cells[0]",
     "exactly 2"),
    (lambda c: _escape(c).update(record_length=0.0),
     "studies.motion_map.escape.record_length", "> 0"),
    (lambda c: _escape(c).update(record_length=9e6),
     "studies.motion_map.escape.record_length", "held in memory"),
    (lambda c: _escape(c).update(fit_max_rms=0.25), "studies.motion_map.escape.fit_max_rms",
     "fewer than 3 noise levels"),
    (lambda c: _escape(c).update(min_stretches=1), "studies.motion_map.escape.min_stretches",
     ">= 2"),
    (lambda c: c["studies"]["motion_map"].pop("escape"), "studies.motion_map.escape",
     "escape_vs_noise draws it"),
    (lambda c: c["studies"]["random"].update(escape={"cells": [[1.0, 0.0]],
                                                     "rms": [0.2, 0.3, 0.4]}),
     "studies.random.escape", "amplitude != 0"),
], ids=["empty_cells", "rms_zero", "rms_negative", "one_level", "repeated_rms",
        "cell_beyond_inv_beta", "cell_beyond_delta", "cell_negative_inv_beta", "cell_one_value",
        "record_zero", "record_too_long", "cut_leaves_one_level", "min_stretches_one",
        "figure_without_block", "escape_on_a_random_study"])
def test_a_bad_escape_block_is_refused_naming_its_key(change, key, fragment):
    text = _refused(change)
    assert key in text, text
    assert fragment in text, text


def test_the_schema_fills_the_escape_defaults():
    cfg = copy.deepcopy(TEST_CONFIG)
    _escape(cfg).clear()
    _escape(cfg).update(rms=[0.2, 0.3, 0.4])
    config, _ = configuration.load(cfg, root=ROOT)
    block = config["studies"]["motion_map"]["escape"]
    assert block["cells"] == [[1.1, 1.0], [1.1, 0.1], [1.2, 2.5]]
    assert block["record_length"] == 1e6 and block["min_stretches"] == 20
    assert block["fit_max_rms"] is None


def test_the_plan_counts_the_escape_jobs():
    """The escape study of the paper's config: 5 levels and their aggregation, 15 cells."""
    config, plan = configuration.load(root=ROOT)
    row = next(r for r in plan.rows if r.key == "studies.motion_map")
    assert "escape 3 cells x 5 noise levels" in row.detail
    from vibroimpact.pipeline.config import costs

    cpu = costs.escape_cpu_s(config["studies"]["motion_map"], 0.1)
    assert 2.0 < cpu < 30.0          # measured ~1 s per level of 1e7 samples (3 cells)


# --- the task and the dataset ----------------------------------------------------------------

@pytest.fixture(scope="module")
def escape_dataset(tmp_path_factory):
    """The test config's escape levels and dataset, made by the tasks the rules call."""
    cfg, _ = configuration.load(copy.deepcopy(TEST_CONFIG), root=ROOT)
    block = cfg["studies"]["motion_map"]
    noise = {k: v for k, v in cfg["noises"][block["noise"]].items()
             if k in ("kind", "dt", "beta_c", "zeta_f", "seed")}
    path = tmp_path_factory.mktemp("escape")
    parts = [path / f"{k}.nc" for k in range(len(block["escape"]["rms"]))]
    for k, part in enumerate(parts):
        tasks.escape_level("motion_map", block, noise, k, part)
    tasks.aggregate_escape("motion_map", block, noise, parts, path / "escape.nc")
    return xr.load_dataset(path / "escape.nc"), block


def test_the_dataset_holds_every_level_cell_and_state(escape_dataset):
    ds, block = escape_dataset
    assert dict(ds.sizes) == {"rms": 3, "cell": 2, "state": 4}
    assert ds["rms"].values.tolist() == sorted(block["escape"]["rms"])
    np.testing.assert_array_equal(ds["inv_beta"], [c[0] for c in block["escape"]["cells"]])
    np.testing.assert_allclose(ds["probability"].sum("state"), 1.0, atol=1e-12)
    assert (ds["simulated_time"] == block["escape"]["record_length"]).all()
    for name in ("residence_time", "slope", "chi2_red", "fit_used", "n_stretches"):
        assert ds[name].attrs["long_name"] and ds[name].attrs["units"] == "1"
    assert ds.attrs["seed"] == 19741001 and ds.attrs["min_stretches"] == 5
    assert ds["spawn_key"].values.tolist() == [0, 1, 2]


def test_weak_noise_holds_the_motion_longer(escape_dataset):
    """At 1/beta_f = 1, delta = 1 the (1/1) motion (stable there under sin(beta tau) alone)
    is left less often as the noise weakens: its residence time falls with rms, and its fit
    has a positive slope (its interval, on the test config's three levels, has one degree of
    freedom: Student's 12.7, wide)."""
    ds, _ = escape_dataset
    home = ds.isel(cell=0).sel(state="1/1")
    assert (np.diff(home["residence_time"].values) < 0).all()
    assert home["slope"] > 0 and home["slope_lo"] < home["slope"] < home["slope_hi"]


def test_the_dataset_is_reproducible_from_its_seeds(escape_dataset, tmp_path):
    ds, block = escape_dataset
    cfg, _ = configuration.load(copy.deepcopy(TEST_CONFIG), root=ROOT)
    noise = {k: v for k, v in cfg["noises"][block["noise"]].items()
             if k in ("kind", "dt", "beta_c", "zeta_f", "seed")}
    tasks.escape_level("motion_map", block, noise, 1, tmp_path / "1.nc")
    again = xr.load_dataset(tmp_path / "1.nc")
    np.testing.assert_array_equal(again["residence_time"].isel(rms=0),
                                  ds["residence_time"].sel(rms=block["escape"]["rms"][1]))


# --- the figure ------------------------------------------------------------------------------

def _synthetic(slopes=(0.16, 0.07), n_weak=(39, 3000), change=None):
    """An escape dataset of two cells whose home motions follow ln T = 1 + slope / rms^2
    (``change(k, c, result)``: edits the result of level k, cell c in place first)."""
    rms = [0.15, 0.18, 0.22, 0.29, 0.4]
    cells = [(1.1, 1.0), (1.1, 0.1)]
    parts = []
    for k, r in enumerate(rms):
        results = []
        for c, slope in enumerate(slopes):
            t = np.array([1.0, 1.0, 1.0, 0.7])
            t[c] = np.exp(1.0 + slope / r ** 2)
            n = np.array([500, 500, 0, 500])
            n[c] = n_weak[c] if k == 0 else 400
            t[n == 0] = np.nan
            results.append(dict(residence_time=t, residence_time_stderr=0.1 * t,
                                n_stretches=n, n_censored=np.zeros(4, int),
                                censored_time=np.zeros(4),
                                probability=np.array([0.9, 0.05, 0.0, 0.05]) if c == 0
                                else np.array([0.05, 0.9, 0.0, 0.05]),
                                n_collisions=1000, simulated_time=1e6))
            if change is not None:
                change(k, c, results[-1])
        parts.append(datasets.escape_part(k, r, cells, results, ((1, 1), (2, 1), (1, 2)),
                                          {}))
    attrs = dict(zeta=0.05, eps=0.5, amplitude=1.0, noise_kind="band_limited",
                 noise_beta_c=4.0, dt=0.1, seed=19741001, transient=200.0,
                 record_length=1e6, motion_window=0.1)
    return datasets.aggregate_escape(parts, attrs, min_stretches=20, fit_max_rms=0.29)


def test_the_aggregate_fits_the_synthetic_slopes():
    ds = _synthetic()
    assert ds["slope"].sel(state="1/1").values[0] == pytest.approx(0.16, rel=1e-9)
    assert ds["slope"].sel(state="2/1").values[1] == pytest.approx(0.07, rel=1e-9)
    assert ds["n_fit"].sel(state="1/1").values[0] == 4      # rms 0.4 above the cut
    assert np.isnan(ds["slope"].sel(state="1/2")).all()


def test_the_figure_draws_points_excluded_points_and_fits():
    ds = _synthetic(n_weak=(5, 3000))          # (1/1)'s weakest level: 5 stretches, excluded
    fig = plotting_escape(ds)
    FigureCanvasAgg(fig).draw()
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.get_ylabel()]
    assert len(panels) == 2
    for ax in panels:
        assert ax.get_yscale() == "log"
        assert any(p.get_gid() == "outside_fit" for p in ax.patches)
    first = panels[0]
    fits = [line for line in first.get_lines() if line.get_gid() == "fit"]
    assert len(fits) == 3                       # (1/1), (2/1) and none: each >= 3 levels
    excluded = [c for c in first.containers if c.lines[0].get_gid() == "excluded_points"]
    assert excluded                               # rms 0.4 and the weak (1/1) level
    legend = " ".join(t.get_text() for t in first.get_legend().get_texts())
    # to the decimal of the interval's second significant digit (half-width 0.095: three
    # levels, t = 12.7 at one degree of freedom)
    assert "(1/1): $\\Delta$ = 0.160 [0.065, 0.255]" in legend
    assert "-0.0000" not in legend
    assert "(1/1) 90 % at rms 0.15" in first.get_title()


def test_a_motion_never_left_is_a_bound_and_two_levels_are_no_fit():
    """The planes example's eps = 0.3 cell: the (1/1) motion never left at the weakest
    noise (no complete stretch, one cut stretch over the whole record), 20 or more complete
    stretches at two levels only. Its weakest level is drawn as a lower bound (an arrow up
    from the cut stretch's length, outside the fit), no line is fitted, and the legend says
    why."""
    def never_left(k, c, result):
        if c == 0 and k == 0:                     # rms 0.15: one cut stretch, no complete
            result.update(n_stretches=np.array([0, 0, 0, 0]), n_censored=np.array([1, 0, 0, 0]),
                          censored_time=np.array([5000.0, 0, 0, 0]),
                          residence_time=np.full(4, np.nan),
                          probability=np.array([1.0, 0.0, 0.0, 0.0]))
        if c == 0 and k == 3:                     # rms 0.29: too few stretches
            result["n_stretches"][0] = 5

    ds = _synthetic(change=never_left)
    cell = ds.isel(cell=0).sel(state="1/1")
    assert np.isnan(cell["slope"]) and cell["n_fit"] == 0 and not cell["fit_used"].any()
    fig = plotting_escape(ds)
    FigureCanvasAgg(fig).draw()
    first = [ax for ax in fig.axes if ax.get_visible() and ax.get_ylabel()][0]
    fits = [line.get_color() for line in first.get_lines() if line.get_gid() == "fit"]
    assert len(fits) == 2                       # (2/1) and none; (1/1) has no line
    (bound,) = [c for c in first.containers if c.lines[0].get_gid() == "censored_bound"]
    np.testing.assert_allclose(bound.lines[0].get_xydata(), [[1 / 0.15 ** 2, 5000.0]])
    assert first.get_ylim()[1] > 5000.0         # the bound is inside the axes
    legend = " ".join(t.get_text() for t in first.get_legend().get_texts())
    assert "(1/1): no fit: 2 levels with $\\geq$ 20 complete stretches (3 needed)" in legend
    labels = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    assert "never left" in labels and "lower bound" in labels
    # a cell without such a level draws no bound
    second = [ax for ax in fig.axes if ax.get_visible() and ax.get_ylabel()][1]
    assert not [c for c in second.containers if c.lines[0].get_gid() == "censored_bound"]


def test_the_bars_are_95_percent_intervals_as_delta_is():
    """Issue 33: +-1 s.e. bars sat beside 95 % intervals of Delta; now both are 95 %."""
    from vibroimpact.stats.events import t_quantile

    ds = _synthetic(n_weak=(5, 3000))
    fig = plotting_escape(ds)
    first = [ax for ax in fig.axes if ax.get_visible() and ax.get_ylabel()][0]
    (points,) = [c for c in first.containers if c.lines[0].get_gid() == "fitted_points"
                 and c.get_label().startswith("(1/1)")]
    cell = ds.isel(cell=0)
    used = cell["fit_used"].values[:, 0].astype(bool)
    t, se = cell["residence_time"].values[used, 0], cell["residence_time_stderr"].values[used, 0]
    half = t_quantile(cell["n_stretches"].values[used, 0], 0.95) * se
    segments = points.lines[2][0].get_segments()
    np.testing.assert_allclose([s[1][1] - s[0][1] for s in segments],
                               np.minimum(half, 0.999 * t) + half, rtol=1e-12)
    labels = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    assert "95 %" in labels and "1 s.e." not in labels


@pytest.mark.parametrize("value, lo, hi, text", [
    (0.163, 0.146, 0.18, "0.163 [0.146, 0.180]"),
    (0.00409, -0.000194, 0.00836, "0.0041 [-0.0002, 0.0084]"),
    (-0.0000004, -0.0081, 0.0081, "0.0000 [-0.0081, 0.0081]"),
    (12.3456, 10.0, 14.0, "12.3 [10.0, 14.0]"),
    (0.16, 0.16, 0.16, "0.16 [0.16, 0.16]"),
])
def test_delta_is_printed_to_its_interval(value, lo, hi, text):
    from vibroimpact.plotting.escape import _interval_text

    assert _interval_text(value, lo, hi) == text


def test_a_figure_without_a_usable_state_says_so():
    ds = _synthetic()
    ds["n_stretches"][:] = 1
    fig = plotting_escape(ds)
    FigureCanvasAgg(fig).draw()
    notes = [t.get_text() for ax in fig.axes for t in ax.texts if t.get_gid() == "note"]
    assert notes and "no state with 20 complete stretches" in notes[0]


def plotting_escape(ds):
    from vibroimpact.plotting import escape_vs_noise

    return escape_vs_noise(ds)


# --- the rules -------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return make_workdir(tmp_path_factory.mktemp("wf_escape"))


def test_escape_vs_noise_schedules_only_the_escape_jobs(workdir):
    """No noise file, no map simulation: the levels make their own records."""
    assert scheduled_rules(workdir, "results/figures/escape_vs_noise.png") == {
        "simulate_escape", "aggregate_escape", "draw_figure", "copy_paper_figure"}


@pytest.mark.workflow
def test_escape_vs_noise_builds(workdir):
    snakemake(workdir, "results/figures/escape_vs_noise.png", timeout=600)
    for ext in ("png", "pdf"):
        assert_figure(workdir / f"results/figures/escape_vs_noise.{ext}")
    ds = xr.load_dataset(workdir / "results/datasets/motion_map_escape.nc")
    assert dict(ds.sizes) == {"rms": 3, "cell": 2, "state": 4}
    assert ds.attrs["config_digest"] and ds.attrs["seed"] == 19741001
    assert not list((workdir / "results").rglob(".*.nc*"))      # no temporaries left
    assert not (workdir / "results" / "noise").exists()
