"""Legitimate but degenerate studies: no collision at any play, the schema's minimum sizes, a
study with a trace and nothing else.

The fast tests build their datasets with the workflow's own tasks (`pipeline.tasks`) on short
records: a zero force (rms 0), a random force whose plays lie far out of its reach, a harmonic
force too weak to reach the wall, and a probability map of it. Every figure of collision
statistics must still be drawn, with its axes, and say in words that nothing collided; the
findings that need collisions must be ``n/a`` with that reason. The `workflow` test builds
such studies end to end, with their reports.
"""
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml
from matplotlib.backends.backend_agg import FigureCanvasAgg

from helpers import assert_figure, make_workdir, snakemake
from vibroimpact import plotting
from vibroimpact.orbits import orbit_map
from vibroimpact.pipeline import datasets, tasks
from vibroimpact.plotting.sweep import sweep_means
from vibroimpact.reports import findings
from vibroimpact.reports import notebook as nb

NOISE = dict(kind="band_limited", dt=0.1, beta_c=4.0, n_samples=2001, seed=7, nperseg=256)
BINS = dict(v_after=dict(max=2.5, n=50), interval=dict(max=20.0, n=50), ratio=dict(max=4.0, n=80))
COMMON = dict(zeta=0.05, eps=0.5, transient=10.0, tile_size=100, n_batches=20,
              motion_window=0.1, bins=BINS, motions=[[1, 1], [2, 1], [1, 2]])
#: A zero force: the mass never leaves its rest, resting on the wall at delta <= 0.
SILENT = dict(COMMON, noise="zero", amplitude=0.0, delta=[-0.5, 0.0, 1.0],
              spectra=dict(delta=[1.0, 0.0], nperseg=256), trace=dict(delta=0.0, t_end=60.0))
#: rms 0.5 and plays of 50 wall-free stds and more; 0 is hit, the partial case of fig09.
FAR = dict(COMMON, noise="band", amplitude=0.0, delta=[50.0, 60.0])
PARTIAL = dict(FAR, delta=[0.0, 50.0, 60.0])
#: Welch segments of the schema's minimum, 16 samples: a beta step of 3.9, wider than the band
#: the spectral findings read.
COARSE = dict(FAR, delta=[1.0, 0.5, 0.0], spectra=dict(delta=[1.0, 0.5, 0.0], nperseg=16))
#: A weak harmonic force alone (rms 0) at plays far beyond its response (~0.1 / (2 zeta)).
WEAK = dict(COMMON, noise="zero", amplitude=0.1, inv_beta=[1.1], delta=[20.0, 30.0])
WEAK_MAP = dict(WEAK, inv_beta=[0.5, 1.0], map=dict(target_stderr=0.03, min_time=100.0,
                                                    max_periods=20, min_switches=10))
NO_COLLISION = "no collision in this record at any"


def _events(tmp, name, block, noise, kind="events"):
    """The dataset of one study (one tile), made and aggregated by the workflow's tasks."""
    make = {"events": tasks.events_tile, "spectra": tasks.spectra_tile, "map": tasks.map_tile}
    tile, path = tmp / f"{name}_{kind}_tile.nc", tmp / f"{name}_{kind}.nc"
    make[kind](name, block, 0, noise, tile)
    tasks.aggregate(name, block, kind, [tile], path, noise_path=noise)
    return xr.load_dataset(path)


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("degenerate")
    zero, band = tmp / "zero.nc", tmp / "band.nc"
    tasks.make_noise(dict(NOISE, rms=0.0), zero)
    tasks.make_noise(dict(NOISE, rms=0.5), band)
    tasks.trace("silent", SILENT, zero, tmp / "trace.nc")
    out = {"silent": _events(tmp, "silent", SILENT, zero),
           "spectra": _events(tmp, "silent", SILENT, zero, "spectra"),
           "trace": xr.load_dataset(tmp / "trace.nc"),
           "far": _events(tmp, "far", FAR, band),
           "partial": _events(tmp, "partial", PARTIAL, band),
           "coarse": _events(tmp, "coarse", COARSE, band, "spectra"),
           "weak": _events(tmp, "weak", WEAK, zero),
           "weak_spectra": _events(tmp, "weak", dict(WEAK, spectra=dict(
               delta=[20.0, 30.0], nperseg=256)), zero, "spectra"),
           "map": _events(tmp, "weak_map", WEAK_MAP, zero, "map")}
    out["orbits"] = datasets.orbit_map_dataset(
        orbit_map(np.array([0.5, 1.0]), np.array([20.0, 30.0]), types=[(1, 1), (2, 1), (1, 2)],
                  zeta=0.05, eps=0.5), dict(zeta=0.05, eps=0.5, amplitude=1.0))
    return out


def _drawn(fig):
    """Render `fig` (a log axis without positive data fails only here) and return it."""
    FigureCanvasAgg(fig).draw()
    return fig


def _notes(fig):
    """The words on each axes that has nothing to draw (`plotting._common.note_on_axes`)."""
    return [t.get_text() for ax in fig.axes for t in ax.texts if t.get_gid() == "note"]


def test_the_fixture_has_no_collision_where_the_tests_say(data):
    for name in ("silent", "far", "weak", "map"):
        assert int(data[name]["n_collisions"].sum()) == 0, name
    hit = data["partial"]["n_collisions"].isel(inv_beta=0)
    assert int(hit.sel(delta=0.0)) > 0 and int(hit.sel(delta=[50.0, 60.0]).sum()) == 0


@pytest.mark.parametrize("name", ["silent", "far"])
def test_fig09_without_any_collision_is_drawn_and_says_so(data, name):
    fig = _drawn(plotting.fig09(data[name]))
    notes = _notes(fig)
    assert len(notes) == 2 and all(NO_COLLISION in n for n in notes)
    low, high = fig.axes[0].get_xlim()
    assert low < float(data[name]["delta"].min()) and high > float(data[name]["delta"].max())
    rice = [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid() == "rice"]
    if name == "silent":       # a zero force: no wall-free excursions, no asymptote
        assert "force is zero" in notes[0] and not rice
    else:                      # plays of 50 and 60 wall-free stds: said in sigma_x units;
        # Rice's mean interval there, beyond exp(30^2 / 2), is off every axis: not drawn
        sigma_x = float(data[name].attrs["linear_sigma_x"])
        assert f"{50.0 / sigma_x:.4g} $\\sigma_x$" in notes[0] and not rice


def test_fig09_with_collisions_at_some_plays_is_unchanged(data):
    fig = _drawn(plotting.fig09(data["partial"]))
    assert not _notes(fig)
    spans = [p for ax in fig.axes for p in ax.patches if p.get_gid() == "no_collision"]
    assert len(spans) == 2 and spans[0].get_x() == pytest.approx(0.0)


@pytest.mark.parametrize("figure, name, args", [
    ("fig07", "silent", ()), ("fig08", "far", ()), ("fig13", "weak", (1.1,)),
    ("fig14", "weak", (1.1,))])
def test_density_figures_without_any_collision_say_so_on_every_axes(data, figure, name, args):
    fig = _drawn(getattr(plotting, figure)(data[name], *args))
    panels = [ax for ax in fig.axes if ax.get_ylabel()]
    assert panels[0].get_yscale() == "log"
    notes = _notes(fig)
    assert len(notes) == len(panels) and all(NO_COLLISION in n for n in notes)
    if name == "weak":
        assert "rms$_r$ = 0" in notes[0]


def test_fig03_and_fig06_of_a_zero_force(data):
    fig = _drawn(plotting.fig03(data["trace"]))
    ax_a = fig.axes[1]
    assert "no collision in this stretch" in [t.get_text() for t in ax_a.get_legend().texts]
    low, high = ax_a.get_ylim()
    assert low < 0.0 < 0.5 < high, "a = 0 at the wall needs a readable axis, not one of 1e-17"
    fig = _drawn(plotting.fig06(data["spectra"]))
    assert fig.axes[0].get_yscale() == "linear", "round-off must not be drawn as a log spectrum"
    assert any("force is zero" in n for n in _notes(fig))


def test_fig15_and_its_comparison_without_any_collision(data):
    x, y = data["map"]["inv_beta"].values, data["map"]["delta"].values
    for fig in (plotting.fig15(data["map"]), plotting.fig15_vs_fig16(data["map"], data["orbits"])):
        _drawn(fig)
        panels = [ax for ax in fig.axes if ax.get_title()]
        notes = _notes(fig)
        assert len(notes) == len(panels) >= 3 and all("in any cell" in n for n in notes)
        assert all(ax.get_xlim() == (x[0], x[-1]) and ax.get_ylim() == (y[0], y[-1])
                   for ax in panels), "the axes span the map's grid"
        assert not fig.legends or fig.legends[0].get_texts()


def test_sweep_figure_without_any_collision(data):
    fig = _drawn(sweep_means([data["silent"], data["far"]], ["rms = 0", "rms = 0.5"]))
    notes = _notes(fig)
    assert len(notes) == 2 and all("no collision" in n for n in notes)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["rms = 0  (no collision)", "rms = 0.5  (no collision)"]
    fig = _drawn(sweep_means([data["partial"], data["far"]], ["hit", "far"]))
    assert not _notes(fig)
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["hit", "far  (no collision)"]


def test_findings_that_need_collisions_are_na_with_the_reason(data):
    found = findings.random_force(events=data["silent"], spectra=data["spectra"])
    assert [f.holds for f in found] == ["n/a"] * 4
    assert "force is zero" in found[0].measured
    assert all(NO_COLLISION.replace("any", "any play") in f.measured for f in found[1:])
    far = findings.random_force(events=data["far"])
    assert all("(delta = 50, 60)" in f.measured for f in far[1:])
    weak = findings.harmonic_random(events=data["weak"], spectra=data["weak_spectra"],
                                    inv_beta=1.1)
    assert [f.holds for f in weak] == ["n/a"] * 4
    assert "no collision in this record at the plays of the spectra" in weak[0].measured
    assert all(NO_COLLISION.replace("any", "any play") in f.measured for f in weak[1:3])


def test_spectral_findings_on_segments_of_16_samples_are_na(data):
    coarse = data["coarse"]
    assert float(coarse.beta[1] - coarse.beta[0]) > 3.0
    for found in (findings.finding1(coarse), findings.finding5(coarse)):
        assert found.holds == "n/a" and "spectra.nperseg" in found.measured


def test_report_settings_come_from_the_trace_when_the_study_has_nothing_else(data):
    table = nb.study_settings(nb.first(None, None, data["trace"]), name="trace_only")
    values = table["value"]
    assert values["entry"] == "trace_only" and values["trace delta"] == "0"
    assert values["zeta"] == "0.05" and values["noise rms"] == "0"
    assert "trace beta_f" not in values, "a random-force trace has no forcing frequency"
    assert "no dataset" in nb.study_settings(nb.first(None, None)).data


STUDIES = {
    # no collision at any play: a zero force, every figure of a random-force study
    "silent": dict(noise="zero", zeta=0.05, eps=0.5, amplitude=0.0, delta=[0.0, 1.0],
                   transient=10.0, tile_size=5, spectra=dict(delta=[1.0], nperseg=256),
                   trace=dict(delta=0.0, t_end=30.0),
                   figures=["fig03", "fig04", "fig05", "fig06", "fig07", "fig08", "fig09"]),
    # the smallest events record: 2 batches of a natural period 2 pi (128 samples at dt =
    # 0.1), Welch segments of 16, no transient
    "minimal": dict(noise="tiny", zeta=0.05, eps=0.5, amplitude=0.0, delta=[0.0, 0.5],
                    transient=0.0, n_batches=2, trace=dict(delta=0.0, t_end=1.0),
                    figures=["fig03", "fig04", "fig05", "fig07", "fig08", "fig09"]),
    # a trace and nothing else, on the schema's smallest record (16 samples): the report has
    # no events or spectra dataset
    "trace_only": dict(noise="tiniest", zeta=0.05, eps=0.5, amplitude=0.0, delta=[0.0],
                       transient=0.0, trace=dict(delta=0.0, t_end=1.0), figures=["fig03"]),
}


#: The user's file of these studies (test_workflow.py dry-runs it against the plan too).
CONFIG = dict(paper=False, noises=dict(
    zero=dict(kind="band_limited", rms=0.0, dt=0.1, beta_c=4.0, n_samples=3001, seed=1),
    tiny=dict(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0, n_samples=128, nperseg=16,
              seed=2),
    tiniest=dict(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0, n_samples=16, nperseg=16,
                 seed=2)), studies=STUDIES)


@pytest.mark.workflow
def test_degenerate_studies_build_every_figure_and_report(tmp_path):
    workdir = make_workdir(tmp_path / "wf")
    (workdir / "degenerate.yaml").write_text(yaml.safe_dump(CONFIG))
    snakemake(workdir, config="degenerate.yaml")
    results = Path(workdir) / "results"
    for name, study in STUDIES.items():
        for fig in study["figures"]:
            assert_figure(results / "figures" / name / f"{fig}.png")
        html = (results / "reports" / name / "random_force.html").read_text()
        assert "n/a" in html and "Traceback" not in html, name
    silent = (results / "reports" / "silent" / "random_force.html").read_text()
    assert "no collision in this record at any play" in silent
