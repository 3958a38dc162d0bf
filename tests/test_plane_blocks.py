"""A study with a plane draws its basins, Lyapunov exponents and escape against noise level
over that plane (issue 36): through the workflow's own tasks and the params the rules pass
(`JOB_KEYS`), the paper's plane gives today's datasets bit for bit, a column of another plane
the paper's column, and the config refuses what a plane cannot have."""
import json
import sys

import numpy as np
import pytest
import xarray as xr

from helpers import ROOT, TINY_MAP, TINY_NOISE
from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline import figures, tasks, targets
from vibroimpact.pipeline.config import ConfigError
from vibroimpact.pipeline.study import JOB_KEYS, ORBIT_JOB_KEYS, plane_attractor_rows

sys.path.insert(0, str(ROOT / "benchmarks"))
from same_build import _data  # what same_build compares: no attrs, no timings

NOISE = TINY_NOISE
MAP = TINY_MAP
ATTRACTORS = "{n_starts: 6, max_time: 300.0, seed: 3, tile_rows: 1}"
ORBITS = NOISE + """studies: {}
orbits:
  paper:
    zeta: 0.05
    eps: 0.5
    inv_beta: [0.9, 1.1]
    delta: [0.0, 1.0]
    attractors:
      inv_beta: [0.9, 1.1]
      delta: [-0.5, 0.25, 1.0, 2.5]
      n_starts: 6
      max_time: 300.0
      seed: 3
      tile_rows: 1
    figures: [basins, lyapunov]
"""
PAPER_PLANE = NOISE + f"""studies:
  flat:
    noise: tiny
    plane: [inv_beta, delta]
    eps: 0.5
    inv_beta: [0.9, 1.1]
    delta: [-0.5, 0.25, 1.0, 2.5]
{MAP}    attractors: {ATTRACTORS}
    figures: [fig15, basins, lyapunov]
"""
EPS_DELTA = NOISE + f"""studies:
  restitution:
    noise: tiny
    plane: [eps, delta]
    eps: [0.3, 0.5]
    inv_beta: 1.1
    delta: [-0.5, 0.25, 1.0, 2.5]
{MAP}    attractors: {ATTRACTORS}
    escape: {{cells: [[0.5, 1.0], [0.3, 0.25]], rms: [0.2, 0.29, 0.4], record_length: 2000.0}}
    figures: [fig15, basins, lyapunov, escape_vs_noise]
"""
PAPER_ESCAPE = NOISE + f"""studies:
  flat:
    noise: tiny
    eps: 0.5
    inv_beta: [1.0, 1.1]
    delta: [0.25, 1.0]
{MAP}    escape: {{cells: [[1.1, 1.0], [1.1, 0.25]], rms: [0.2, 0.29, 0.4], record_length: 2000.0}}
    figures: [fig15, escape_vs_noise]
"""


def _load(tmp_path, text):
    path = tmp_path / "config.yaml"
    path.write_text(text)
    return configuration.load(root=ROOT, user_files=[path])


def _plane_attractors(tmp_path, text, name):
    config, _ = _load(tmp_path, text)
    entry = config["studies"][name]
    block = {k: entry[k] for k in JOB_KEYS["attractors"] if k in entry}
    _, n = plane_attractor_rows(entry)
    tiles = [tmp_path / f"{name}_tile{t}.nc" for t in range(n)]
    for t, path in enumerate(tiles):
        tasks.attractor_tile(block, t, path, study=name)
    out = tmp_path / f"{name}_basins.nc", tmp_path / f"{name}_lyapunov.nc"
    tasks.aggregate_plane_attractors(block, tiles, *out)
    return [xr.load_dataset(p) for p in out]


@pytest.fixture(scope="module")
def orbit_attractors(tmp_path_factory):
    """Today's path: the orbits entry's attractor tiles and datasets."""
    tmp_path = tmp_path_factory.mktemp("orbits")
    config, _ = _load(tmp_path, ORBITS)
    entry = config["orbits"]["paper"]
    block = {k: entry[k] for k in ORBIT_JOB_KEYS["attractors"] if k in entry}
    tiles = [tmp_path / f"tile{t}.nc" for t in range(2)]
    for t, path in enumerate(tiles):
        tasks.attractor_tile(block, t, path)
    out = tmp_path / "basins.nc", tmp_path / "lyapunov.nc"
    tasks.aggregate_attractors(block, tiles, *out)
    return out


def test_the_paper_plane_gives_todays_attractor_datasets(orbit_attractors, tmp_path):
    basins, lyapunov = _plane_attractors(tmp_path, PAPER_PLANE, "flat")
    for new, old in zip((basins, lyapunov), orbit_attractors):
        xr.testing.assert_identical(_data(old), new.drop_vars(
            [v for v in new.variables if new[v].attrs.get("run_measurement") == 1]
        ).drop_attrs())
    assert list(lyapunov.attrs["axes"]) == ["inv_beta", "delta"]


def test_the_eps_delta_column_is_the_paper_column(orbit_attractors, tmp_path):
    """The issue's test for the attractor datasets: the (eps, delta) study's column at eps =
    0.5 is the (1/beta_f, delta) entry's column at 1/beta_f = 1.1 (same starts, same seed)."""
    basins, lyapunov = _plane_attractors(tmp_path, EPS_DELTA, "restitution")
    assert basins["fraction"].dims == ("motion", "eps", "delta")
    assert json.loads(lyapunov.attrs["fixed"]) == {"amplitude": 1.0, "inv_beta": 1.1,
                                                   "zeta": 0.05}
    for new, path in zip((basins, lyapunov), orbit_attractors):
        old = _data(path).sel(inv_beta=1.1, drop=True)
        col = new.drop_attrs().sel(eps=0.5, drop=True)
        xr.testing.assert_identical(old, col)
    assert not lyapunov["lyapunov_start"].sel(eps=0.3).equals(
        lyapunov["lyapunov_start"].sel(eps=0.5))


def _escape(tmp_path, text, name):
    config, _ = _load(tmp_path, text)
    entry = config["studies"][name]
    kind = "plane_escape" if entry.get("plane") else "escape"
    block = {k: entry[k] for k in JOB_KEYS[kind] if k in entry}
    noise = {k: v for k, v in config["noises"][entry["noise"]].items()
             if k in ("kind", "dt", "beta_c", "zeta_f", "seed")}
    parts = [tmp_path / f"{name}_level{k}.nc" for k in range(len(block["escape"]["rms"]))]
    for k, part in enumerate(parts):
        tasks.escape_level(name, block, noise, k, part)
    tasks.aggregate_escape(name, block, noise, parts, tmp_path / f"{name}_escape.nc")
    return xr.load_dataset(tmp_path / f"{name}_escape.nc")


def test_escape_cells_in_the_planes_coordinates(tmp_path):
    """The (eps, delta) study's escape cells [0.5, 1.0], [0.3, 0.25] at 1/beta_f = 1.1: the
    first is the paper-plane study's cell [1.1, 1.0] bit for bit (same level records), the
    second another restitution; the cells carry their plane's coordinates."""
    plane = _escape(tmp_path, EPS_DELTA, "restitution")
    paper = _escape(tmp_path, PAPER_ESCAPE, "flat")
    assert list(plane["eps"].values) == [0.5, 0.3]
    assert list(plane["delta"].values) == [1.0, 0.25]
    assert "inv_beta" not in plane.coords and plane.attrs["inv_beta"] == 1.1
    assert list(plane.attrs["axes"]) == ["eps", "delta"]
    skip = ["eps", "delta", "inv_beta"]
    a = _data_of(plane).isel(cell=0).drop_vars(skip, errors="ignore")
    b = _data_of(paper).isel(cell=0).drop_vars(skip, errors="ignore")
    xr.testing.assert_identical(a, b)
    assert not np.array_equal(plane["residence_time"].isel(cell=1).values,
                              paper["residence_time"].isel(cell=1).values, equal_nan=True)


def _data_of(ds):
    return ds.drop_vars([v for v in ds.variables
                         if ds[v].attrs.get("run_measurement") == 1]).drop_attrs()


def test_the_figures_name_the_plane(tmp_path):
    """The basins, Lyapunov and escape figures of the (eps, delta) study: axes and panel
    titles in the paper's symbols, the header says what is fixed."""
    from vibroimpact import plotting
    from vibroimpact.plotting.attractors import basins, lyapunov
    from vibroimpact.plotting.escape import escape_vs_noise

    b, ly = _plane_attractors(tmp_path, EPS_DELTA, "restitution")
    esc = _escape(tmp_path, EPS_DELTA, "restitution")
    with plotting.style():
        for fig in (basins(b), lyapunov(ly)):
            ax = fig.axes[0]
            assert ax.get_ylabel() == r"play $\delta$"
            assert fig.axes[-2].get_xlabel() == r"restitution $\varepsilon$" or any(
                a.get_xlabel() == r"restitution $\varepsilon$" for a in fig.axes)
            title = fig._suptitle.get_text()
            assert r"fixed: $\zeta$ = 0.05, $A$ = 1, $1/\beta_f$ = 1.1" in title
        fig = escape_vs_noise(esc)
        assert fig.axes[0].get_title().startswith(r"$\varepsilon$ = 0.5, $\delta$ = 1:")
        assert r"fixed: $\zeta$ = 0.05, $A$ = 1, $1/\beta_f$ = 1.1" in fig._suptitle.get_text()


def test_the_targets_and_the_plan(tmp_path):
    config, plan = _load(tmp_path, EPS_DELTA)
    assert targets.figure_inputs(config, "restitution", "basins") == [
        "results/datasets/restitution_basins.nc"]
    assert "plane_basins" in targets.study_datasets(config, "restitution")
    row = next(r for r in plan.rows if r.key == "studies.restitution")
    assert "attractors over (eps, delta) 8 cells x 6 starts" in row.detail
    caption = figures.caption("study", "restitution", config["studies"]["restitution"],
                              "basins")
    assert "over the plane (eps, delta)" in caption and "1/beta\\_f = 1.1" in caption


@pytest.mark.parametrize("change, key, fragment", [
    ("plane: [rms, delta]\n    rms: [0.1, 0.2]\n    eps: 0.5", "attractors",
     "harmonic force alone, which has no rms"),
    ("attractors: {gap: [0.0, 4.0], n_starts: 6}\n    gap: 2.0", "attractors.gap",
     "smallest clearance of the plane is gap = 2"),
    ("attractors: {max_time: 100.0}", "attractors.max_time", "too short for a start"),
    ("escape: {cells: [[0.5, 9.0]], rms: [0.2, 0.3, 0.4]}", "escape.cells[0]",
     "outside the study's (eps, delta) plane"),
    ("escape: {cells: [[1.5, 1.0]], rms: [0.2, 0.3, 0.4]}", "escape.cells[0]",
     "eps = 1.5 is out of its range"),
    ("spectra: {delta: [1.0]}", "spectra", "has no spectra: they run at plays"),
])
def test_a_plane_block_is_refused_naming_its_key(tmp_path, change, key, fragment):
    text = EPS_DELTA.replace("    escape: {cells: [[0.5, 1.0], [0.3, 0.25]], "
                             "rms: [0.2, 0.29, 0.4], record_length: 2000.0}\n", "")
    text = text.replace("figures: [fig15, basins, lyapunov, escape_vs_noise]",
                        "figures: [fig15, basins, lyapunov]")
    if change.startswith("plane:"):
        text = text.replace("plane: [eps, delta]\n    eps: [0.3, 0.5]", change)
    elif change.startswith("attractors:"):
        text = text.replace(f"    attractors: {ATTRACTORS}\n", f"    {change}\n")
    else:
        text = text.replace("    figures:", f"    {change}\n    figures:")
    with pytest.raises(ConfigError) as err:
        _load(tmp_path, text)
    lines = [p for p in err.value.problems if f"studies.restitution.{key}" in p]
    assert lines and fragment in lines[0], err.value.problems


def _trace(tmp_path, text, name):
    config, _ = _load(tmp_path, text)
    entry = config["studies"][name]
    kind = "plane_trace" if entry.get("plane") else "trace"
    block = {k: entry[k] for k in JOB_KEYS[kind] if k in entry}
    noise = tmp_path / f"{entry['noise']}.nc"
    if not noise.exists():
        tasks.make_noise(config["noises"][entry["noise"]], noise)
    tasks.trace(name, block, noise, tmp_path / f"{name}_trace.nc")
    return xr.load_dataset(tmp_path / f"{name}_trace.nc")


TRACE_PLANE = EPS_DELTA.replace(
    "    figures: [fig15, basins, lyapunov, escape_vs_noise]",
    "    trace: {cell: [0.5, 1.0], t_end: 60.0}\n"
    "    figures: [fig15, basins, lyapunov, escape_vs_noise, fig10]")
TRACE_PAPER = PAPER_ESCAPE.replace(
    "    figures: [fig15, escape_vs_noise]",
    "    trace: {delta: 1.0, inv_beta: 1.1, t_end: 60.0}\n    figures: [fig15, fig10]")
TRACE_RMS = NOISE.replace("rms: 0.29", "rms: 1.0") + f"""studies:
  noisy:
    noise: tiny
    plane: [rms, delta]
    eps: 0.5
    rms: [0.1, 0.29]
    inv_beta: 1.1
    delta: [0.25, 1.0]
{MAP}    trace: {{cell: [0.29, 1.0], t_end: 60.0}}
    figures: [fig15, fig10]
"""
TRACE_RMS_PAPER = NOISE + f"""studies:
  flat:
    noise: tiny
    eps: 0.5
    inv_beta: [1.0, 1.1]
    delta: [0.25, 1.0]
{MAP}    trace: {{delta: 1.0, inv_beta: 1.1, t_end: 60.0}}
    figures: [fig15, fig10]
"""


def test_a_plane_trace_at_its_cell(tmp_path):
    """The (eps, delta) study's trace at cell [0.5, 1.0] (1/beta_f = 1.1 fixed) is the
    paper-plane study's trace at delta = 1, 1/beta_f = 1.1 on the same record, bit for bit;
    on an (rms, delta) plane the unit record times the cell's rms is the record at that rms
    (to round-off: the generator scales its unit draws), so the two traces agree to 1e-12."""
    plane = _trace(tmp_path, TRACE_PLANE, "restitution")
    paper = _trace(tmp_path, TRACE_PAPER, "flat")
    assert list(plane.attrs["cell"]) == [0.5, 1.0] and list(plane.attrs["axes"]) == ["eps",
                                                                                     "delta"]
    assert plane.attrs["eps"] == 0.5 and plane.attrs["delta"] == 1.0
    xr.testing.assert_identical(_data_of(plane), _data_of(paper))
    assert plane.sizes["impact"] > 0
    (tmp_path / "unit").mkdir()
    (tmp_path / "at").mkdir()
    rms = _trace(tmp_path / "unit", TRACE_RMS, "noisy")      # the record at rms 1, times 0.29
    ref = _trace(tmp_path / "at", TRACE_RMS_PAPER, "flat")   # the record at rms 0.29
    np.testing.assert_allclose(rms["x"].values, ref["x"].values, rtol=0, atol=1e-12)
    assert rms.sizes["impact"] == ref.sizes["impact"]
    # the trace's record is the scaled one: its rms is the cell's, as the reference's
    assert rms.attrs["noise_rms"] == pytest.approx(ref.attrs["noise_rms"], rel=1e-12)
    assert rms.attrs["noise_unit_rms"] == 1.0
    from vibroimpact import plotting
    from vibroimpact.plotting.harmonic import fig10

    with plotting.style():
        title = fig10(plane)._suptitle.get_text()
    assert r"at the point $\varepsilon$ = 0.5, $\delta$ = 1 of the study's" in title


@pytest.mark.parametrize("trace, key, fragment", [
    ("{delta: 1.0, t_end: 60.0}", "trace.delta", "gives its trace's point as cell"),
    ("{t_end: 60.0}", "trace.cell", "missing: the trace's point"),
    ("{cell: [0.5, 7.0], t_end: 60.0}", "trace.cell", "outside the study's (eps, delta)"),
])
def test_a_bad_plane_trace_is_refused(tmp_path, trace, key, fragment):
    text = TRACE_PLANE.replace("trace: {cell: [0.5, 1.0], t_end: 60.0}", f"trace: {trace}")
    with pytest.raises(ConfigError) as err:
        _load(tmp_path, text)
    lines = [p for p in err.value.problems if f"studies.restitution.{key}" in p]
    assert lines and fragment in lines[0], err.value.problems


def test_basins_in_a_study_without_a_plane_is_refused(tmp_path):
    text = PAPER_ESCAPE.replace("figures: [fig15, escape_vs_noise]", "figures: [fig15, basins]")
    with pytest.raises(ConfigError) as err:
        _load(tmp_path, text)
    lines = [p for p in err.value.problems if "studies.flat.figures[1]" in p]
    assert lines and "draws basins over its plane, and this study has none" in lines[0]
