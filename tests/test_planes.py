"""Maps over any two parameters (issue 36): a study's ``plane``, from the config to the map.

The physics of a plane's cell is the default map's cell with two parameters moved, so the
checks here are identities against the default (inv_beta, delta) map on the same record, bit
for bit, and the config's refusals; the workflow test builds a tiny (rms, delta) map.
"""
import json

import numpy as np
import pytest
import xarray as xr

from helpers import ROOT, TINY_MAP, TINY_NOISE
from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline import io, tasks
from vibroimpact.pipeline.config.sweeps import sweep_members
from vibroimpact.pipeline.study import JOB_KEYS, Study

NOISE = TINY_NOISE + "studies:\n"
#: The map settings every study here shares (a short record: the identities hold whatever
#: the precision reached).
MAP = TINY_MAP + "    figures: [fig15]\n"
DEFAULT = NOISE + """  flat:
    noise: tiny
    eps: 0.5
    inv_beta: [0.9, 1.1]
    delta: [0.0, 0.5, 1.0]
""" + MAP
EPS_DELTA = NOISE + """  plane:
    noise: tiny
    plane: [eps, delta]
    eps: [0.3, 0.5]
    inv_beta: 1.1
    delta: [0.0, 0.5, 1.0]
""" + MAP
RMS_DELTA = NOISE + """  noisy:
    noise: tiny
    plane: [rms, delta]
    eps: 0.5
    rms: {start: 0.1, stop: 0.29, step: 0.19}
    inv_beta: 1.1
    delta: [0.0, 0.5, 1.0]
""" + MAP


def _load(tmp_path, text):
    path = tmp_path / "planes.yaml"
    path.write_text(text)
    return configuration.load(root=ROOT, user_files=[path])


def _build_map(tmp_path, text, name):
    """The map dataset of study ``name`` of ``text``, built by the workflow's own tasks with
    the params the workflow passes (`JOB_KEYS`), its noise record written first."""
    config, plan = _load(tmp_path, text)
    entry = config["studies"][name]
    noise = entry["noise"]
    noise_path = tmp_path / f"{noise}.nc"
    if not noise_path.exists():
        tasks.make_noise(config["noises"][noise], noise_path)
    block = {k: entry[k] for k in JOB_KEYS["map"] if k in entry}
    tiles = []
    for t in range(plan.studies[name].n_tiles()):
        tiles.append(tmp_path / f"{name}_{t}.nc")
        tasks.map_tile(name, block, t, noise_path, tiles[-1])
    out = tmp_path / f"{name}_map.nc"
    tasks.aggregate(name, block, "map", tiles, out)
    return xr.load_dataset(out), config


#: Every variable of a map cell that the simulation fixes (the CPU time is the run's).
CELL_VARIABLES = ("probability", "probability_stderr", "stick_probability",
                  "rule_probability", "n_collisions", "n_switches", "record_end",
                  "simulated_time", "v_after_mean", "residence_time", "switch_rate")


def test_the_eps_column_equals_the_default_maps_row_bit_for_bit(tmp_path):
    flat, _ = _build_map(tmp_path, DEFAULT, "flat")
    plane, _ = _build_map(tmp_path, EPS_DELTA, "plane")
    assert plane["probability"].dims[-2:] == ("eps", "delta")
    assert plane.attrs["axes"] == ["eps", "delta"]
    assert json.loads(plane.attrs["fixed"]) == {"zeta": 0.05, "amplitude": 1.0,
                                                 "inv_beta": 1.1, "rms": 0.29}
    column, row = plane.sel(eps=0.5), flat.sel(inv_beta=1.1)
    np.testing.assert_array_equal(column["delta"], row["delta"])
    for name in CELL_VARIABLES:
        np.testing.assert_array_equal(column[name].values, row[name].values, err_msg=name)
    assert int(row["n_collisions"].sum()) > 0
    # and the other restitution is another system on the same record
    assert not np.array_equal(plane.sel(eps=0.3)["record_end"].values
                              + plane.sel(eps=0.3)["n_collisions"].values,
                              row["record_end"].values + row["n_collisions"].values)


def test_an_rms_plane_runs_the_unit_record_scaled_per_cell(tmp_path):
    """Each cell of an (rms, delta) map reads the unit-rms record times its rms: the cell at
    the entry's own rms is the default map's cell on the entry's record to round-off of the
    record (the generator is linear in the rms), and every cell the same random numbers."""
    from vibroimpact.noise import generate_array

    config, _ = _load(tmp_path, RMS_DELTA)
    entry = config["studies"]["noisy"]
    unit = config["noises"][entry["noise"]]
    assert unit["rms"] == 1.0 and unit["seed"] == 36 and entry["noise"] == "noisy_noise0"
    spec = tasks.noise_spec(config["noises"]["tiny"])
    at_rms = generate_array(spec, 20001, 36)
    scaled = 0.29 * generate_array(tasks.noise_spec(unit), 20001, 36)
    # the same random numbers: equal to round-off (a few ulps of the samples)
    np.testing.assert_allclose(scaled, at_rms, rtol=1e-12, atol=1e-14)
    ds, _ = _build_map(tmp_path, RMS_DELTA, "noisy")
    assert ds["probability"].dims[-2:] == ("rms", "delta")
    assert ds["rms"].values.tolist() == [0.1, 0.29]
    assert ds.attrs["noise_rms"] == 1.0 and "rms_axis" in ds.attrs
    # more noise, more switching between motions (the record is the same one)
    assert int(ds["n_switches"].sel(rms=0.29).sum()) >= int(ds["n_switches"].sel(rms=0.1).sum())


def test_the_default_config_keeps_its_plane_and_params():
    config, plan = configuration.load(root=ROOT)
    for name, entry in config["studies"].items():
        assert "plane" not in entry and "rms" not in entry, name
        study = plan.studies[name]
        assert study.plane is None and study.axis_names == ("inv_beta", "delta")
    cell = plan.studies["motion_map"].cells()[0]
    assert cell.axes == () and cell.values == {"inv_beta": 0.2, "delta": -1.5}


def test_a_sweep_over_a_planes_third_parameter_is_a_stack_of_maps(tmp_path):
    text = EPS_DELTA.replace("    zeta: 0.05\n", "    zeta: [0.05, 0.1]\n")
    config, plan = _load(tmp_path, text)
    members = sweep_members(config, "plane")
    assert [(m.study, m.values) for m in members] == [("plane_0", {"zeta": 0.05}),
                                                      ("plane_1", {"zeta": 0.1})]
    from vibroimpact.pipeline.targets import sweep_inputs

    assert sweep_inputs(config, "plane") == ["results/datasets/plane_0_map.nc",
                                             "results/datasets/plane_1_map.nc"]
    for m in members:
        study = plan.studies[m.study]
        assert study.plane == ("eps", "delta") and study.zeta == m.values["zeta"]
        assert study.axes["eps"].tolist() == [0.3, 0.5]


def test_a_gap_plane_resolves_each_cells_two_wall_model(tmp_path):
    from vibroimpact.pipeline.cells import study_model

    text = NOISE + """  joint:
    noise: tiny
    plane: [gap, inv_beta]
    eps: 0.5
    gap: [1.0, 2.0]
    inv_beta: [0.9, 1.1]
    delta: 1.0
    motions: [[1, 1, 1], [1, 0, 1]]
""" + MAP
    config, plan = _load(tmp_path, text)
    study = plan.studies["joint"]
    models = [study_model(study, c) for c in study.cells()]
    assert [(m.gap, round(1 / m.beta, 12), m.delta, m.eps_lower) for m in models] == [
        (1.0, 0.9, 1.0, 0.5), (1.0, 1.1, 1.0, 0.5), (2.0, 0.9, 1.0, 0.5),
        (2.0, 1.1, 1.0, 0.5)]
    assert study.fixed() == {"zeta": 0.05, "eps": 0.5, "amplitude": 1.0, "delta": 1.0,
                             "eps_lower": 0.5}
    noise = tmp_path / "tiny.nc"
    tasks.make_noise(config["noises"]["tiny"], noise)
    entry = config["studies"]["joint"]
    block = {k: entry[k] for k in JOB_KEYS["map"] if k in entry}
    tasks.map_tile("joint", block, 0, noise, tmp_path / "t0.nc")
    tile = io.load_dataset(tmp_path / "t0.nc")
    assert tile.attrs["eps_lower"] == 0.5 and tile.attrs["n_walls"] == 2
    assert "gap" not in tile.attrs and "inv_beta" not in tile.attrs    # the axes
    assert tile["wall_n_collisions"].dims == ("cell", "wall")


def test_the_plan_says_when_a_plane_runs_for_hours(tmp_path):
    # 20,301 cells of up to 200,000 periods of 2 pi 3 (3.8e7 steps) each
    text = EPS_DELTA.replace("max_periods: 200", "max_periods: 200000").replace(
        "n_samples: 20001", "n_samples: 40000001").replace(
        "    inv_beta: 1.1\n", "    inv_beta: 3.0\n").replace(
        "    eps: [0.3, 0.5]\n", "    eps: {start: 0.0, stop: 1.0, step: 0.01}\n").replace(
        "    delta: [0.0, 0.5, 1.0]\n", "    delta: {start: -1.0, stop: 3.0, step: 0.02}\n"
    ).replace("tile_size: 4", "tile_size: 2100")
    _, plan = _load(tmp_path, text)
    row = next(r for r in plan.rows if r.key == "studies.plane")
    assert row.cells == 101 * 201
    assert "map over (eps, delta)" in row.detail and "RUNS FOR HOURS" in row.detail
    _, small = _load(tmp_path, EPS_DELTA)
    assert "HOURS" not in next(r for r in small.rows if r.key == "studies.plane").detail


@pytest.mark.parametrize("change, key, fragment", [
    (("plane: [eps, delta]", "plane: [eps, seed]"), "studies.plane.plane", ""),
    (("plane: [eps, delta]", "plane: [eps, eps]"), "studies.plane.plane", "all different"),
    (("    eps: [0.3, 0.5]\n", "    eps: 0.5\n"), "studies.plane.eps",
     "eps is an axis of the plane"),
    (("    inv_beta: 1.1\n", "    inv_beta: [1.1, 1.2]\n"), "studies.plane.inv_beta",
     "fixed in the plane"),
    (("    inv_beta: 1.1\n", ""), "studies.plane.inv_beta", "fixes 1/beta_f"),
    (("    eps: [0.3, 0.5]\n", "    eps: [0.3, 1.5]\n"), "studies.plane.eps", ""),
    (("    eps: [0.3, 0.5]\n", "    eps: [0.5]\n"), "studies.plane.eps", "at least 2 values"),
    (("figures: [fig15]", "figures: [fig09]"), "studies.plane.figures[0]", "map only"),
    (("plane: [eps, delta]", "plane: [eps_lower, delta]"), "eps_lower",
     "missing: an axis"),
    (("plane: [eps, delta]\n    eps: [0.3, 0.5]",
      "plane: [eps_lower, delta]\n    eps: 0.5\n    eps_lower: [0.3, 0.5]"),
     "studies.plane.eps_lower", "one wall (no gap)"),
    (("    amplitude: 1.0\n", "    amplitude: 0.0\n"), "studies.plane.amplitude",
     "harmonic force"),
])
def test_a_bad_plane_is_refused_naming_its_key(tmp_path, change, key, fragment):
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, EPS_DELTA.replace(*change))
    text = "\n".join(info.value.problems)
    assert key in text and fragment in text, text


def test_a_grid_without_a_plane_is_refused(tmp_path):
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, DEFAULT.replace("    eps: 0.5\n", "    eps: {start: 0.1, stop: 0.5, "
                                        "step: 0.2}\n"))
    assert "studies.flat.eps" in "\n".join(info.value.problems)
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, DEFAULT.replace("    delta: [0.0, 0.5, 1.0]\n", "    delta: 1.0\n"))
    assert "no plane that fixes it" in "\n".join(info.value.problems)


#: An orbits entry over the (eps, delta) plane of study ``plane`` (EPS_DELTA), its fixed values.
EPS_DELTA_ORBITS = """orbits:
  restitution:
    plane: [eps, delta]
    zeta: 0.05
    eps: [0.3, 0.4, 0.5]
    inv_beta: 1.1
    delta: {start: 0.0, stop: 1.0, step: 0.05}
    types: [[1, 1], [2, 1], [1, 2]]
    tile_rows: 2
    figures: [fig16]
"""
WITH_FIG16 = EPS_DELTA.replace(
    "figures: [fig15]", "figures: [fig15, {name: fig15_vs_fig16, orbits: restitution}]")


def test_fig15_vs_fig16_over_a_plane_reads_an_orbits_entry_of_that_plane(tmp_path):
    config, plan = _load(tmp_path, WITH_FIG16 + EPS_DELTA_ORBITS)
    entry = config["orbits"]["restitution"]
    assert plan.drawn["orbits"] == {"restitution"}
    row = next(r for r in plan.rows if r.key == "orbits.restitution")
    assert row.orbit_cells == 3 * 21            # the plane's cells
    assert row.jobs == 2 + 1 + 1 + 1            # 2 tiles (eps), joined, boundaries, fig16
    assert tasks.orbit_plane_fixed(entry) == {"zeta": 0.05, "inv_beta": 1.1,
                                              "amplitude": 1.0}


@pytest.mark.parametrize("change, fragment", [
    (("    plane: [eps, delta]\n    zeta: 0.05\n    eps: [0.3, 0.4, 0.5]\n",
      "    zeta: 0.05\n    eps: 0.5\n    inv_beta: [1.0, 1.1]\n"),
     "maps the plane ['inv_beta', 'delta'], the study the plane ['eps', 'delta']"),
    (("    zeta: 0.05\n    eps: [0.3", "    zeta: 0.1\n    eps: [0.3"),
     "orbits.restitution has zeta = 0.1, the study zeta = 0.05"),
    (("    inv_beta: 1.1\n    delta: {", "    inv_beta: 1.2\n    delta: {"),
     "orbits.restitution has inv_beta = 1.2, the study inv_beta = 1.1"),
])
def test_fig15_vs_fig16_over_a_plane_needs_the_same_plane_and_fixed_values(tmp_path, change,
                                                                            fragment):
    orbits = EPS_DELTA_ORBITS.replace(*change)
    if "inv_beta: [1.0" in orbits:
        orbits = orbits.replace("    inv_beta: 1.1\n", "")
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, WITH_FIG16 + orbits)
    text = "\n".join(info.value.problems)
    assert "studies.plane.figures[1].orbits" in text and fragment in text, text


@pytest.mark.parametrize("change, key, fragment", [
    (("plane: [eps, delta]", "plane: [rms, delta]"), "orbits.restitution.plane",
     "a plane over the noise has no Fig. 16"),
    (("    inv_beta: 1.1\n", "    inv_beta: [1.0, 1.1]\n"), "orbits.restitution.inv_beta",
     "a grid, and inv_beta is fixed"),
    (("    eps: [0.3, 0.4, 0.5]\n", "    eps: 0.5\n"), "orbits.restitution.eps",
     "a number, and eps is an axis"),
    (("    eps: [0.3, 0.4, 0.5]\n", "    eps: [0.3, 1.5]\n"), "orbits.restitution.eps[1]",
     ">= 0 and <= 1"),
    (("    eps: [0.3, 0.4, 0.5]\n", "    eps: {start: 0.5, stop: 1.5, step: 0.5}\n"),
     "orbits.restitution.eps", "0 <= eps <= 1"),
    (("    zeta: 0.05\n", "    zeta: 0.05\n    amplitude: -1.0\n"),
     "orbits.restitution.amplitude", "amplitude A > 0"),
    (("    figures: [fig16]\n", "    figures: [fig16]\n    attractors: {inv_beta: [1.0, 1.1], "
      "delta: [0.0, 0.5]}\n"), "orbits.restitution.attractors", "not a job of an orbits "
     "entry"),
])
def test_a_bad_orbits_plane_is_refused_naming_its_key(tmp_path, change, key, fragment):
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, EPS_DELTA + EPS_DELTA_ORBITS.replace(*change))
    text = "\n".join(info.value.problems)
    assert key in text and fragment in text, text


def test_an_orbits_entry_without_a_plane_takes_no_grid_of_eps(tmp_path):
    orbits = EPS_DELTA_ORBITS.replace("    plane: [eps, delta]\n", "").replace(
        "    inv_beta: 1.1\n", "    inv_beta: [1.0, 1.1]\n")
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, EPS_DELTA + orbits)
    text = "\n".join(info.value.problems)
    assert "orbits.restitution.eps" in text and "no plane naming it" in text, text


def test_an_rms_plane_has_no_fig16(tmp_path):
    text = RMS_DELTA.replace("figures: [fig15]",
                             "figures: [fig15, {name: fig15_vs_fig16, orbits: harmonic}]")
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, text)
    text = "\n".join(info.value.problems)
    assert "studies.noisy.figures[1]" in text and "has no Fig. 16" in text, text


def test_the_tiles_name_their_coordinates_after_the_plane(tmp_path):
    config, plan = _load(tmp_path, EPS_DELTA)
    study = plan.studies["plane"]
    assert isinstance(study, Study) and [c.index for c in study.tile(0)] == [0, 2, 4]
    noise = tmp_path / "tiny.nc"
    tasks.make_noise(config["noises"]["tiny"], noise)
    block = {k: config["studies"]["plane"][k] for k in JOB_KEYS["map"]
             if k in config["studies"]["plane"]}
    tasks.map_tile("plane", block, 1, noise, tmp_path / "t1.nc")
    tile = io.load_dataset(tmp_path / "t1.nc")
    assert tile["eps_cell"].values.tolist() == [0.3, 0.5, 0.5]
    assert tile["delta_cell"].values.tolist() == [0.5, 0.0, 1.0]
    assert "inv_beta_cell" not in tile


# --- end to end -------------------------------------------------------------------------------

@pytest.mark.workflow
def test_a_tiny_rms_delta_map_builds(tmp_path):
    from helpers import assert_cf, make_workdir, snakemake

    work = make_workdir(tmp_path / "wf")
    (work / "tiny.yaml").write_text(RMS_DELTA)
    target = "results/datasets/noisy_map.nc"
    snakemake(work, target, config="tiny.yaml")
    assert_cf(work / "results")        # a plane study's files (the planes example's)
    ds = xr.load_dataset(work / target)
    assert ds.attrs["axes"] == ["rms", "delta"]
    fixed = json.loads(ds.attrs["fixed"])
    assert fixed["inv_beta"] == 1.1 and "rms" not in fixed
    assert ds["probability"].sizes == {"motion": 3, "rms": 2, "delta": 3}
    assert (work / "results/noise/noisy_noise0.nc").exists()


GAP_DELTA = NOISE + """  walls:
    noise: tiny
    plane: [gap, delta]
    eps: 0.5
    gap: [3.0, 4.0]
    inv_beta: 1.1
    delta: [0.5, 1.0]
""" + MAP


@pytest.mark.workflow
def test_a_two_wall_plane_builds_its_report(tmp_path):
    """A (gap, delta) map of two walls, through its executed report: the gap is an axis, so
    the report's two-wall section has no one gap to print and no mirror pairs (its mirror
    check raised KeyError 'gap' on such a map)."""
    from helpers import make_workdir, snakemake

    work = make_workdir(tmp_path / "wf")
    (work / "walls.yaml").write_text(GAP_DELTA)
    target = "results/reports/walls/harmonic_random.html"
    snakemake(work, target, config="walls.yaml")
    text = (work / target).read_text()
    assert "an axis of the map, 3 to 4" in text and "the map runs over (gap, delta)" in text


def test_an_orbits_plane_built_by_its_tasks_is_orbit_plane_bit_for_bit(tmp_path):
    """The orbits entry's tiles (eps columns strided over 2 jobs) joined by the aggregate are
    `orbit_plane` over the whole plane, bit for bit; the boundaries job writes the plane's
    curves with points named after its axes (one checked against the map's cells)."""
    from vibroimpact.orbits.plane import orbit_plane
    from vibroimpact.pipeline.study import ORBIT_JOB_KEYS, grid_values, orbit_rows

    config, _ = _load(tmp_path, WITH_FIG16 + EPS_DELTA_ORBITS)
    entry = config["orbits"]["restitution"]
    block = {k: entry[k] for k in ORBIT_JOB_KEYS["orbits"] if k in entry}
    _, n_tiles = orbit_rows(block)
    assert n_tiles == 2
    tiles = [tmp_path / f"tile{t}.nc" for t in range(n_tiles)]
    for t, path in enumerate(tiles):
        tasks.orbit_tile(block, t, path)
    tasks.aggregate_orbits(block, tiles, tmp_path / "orbits.nc")
    built = io.load_dataset(tmp_path / "orbits.nc")
    whole = orbit_plane("eps", [0.3, 0.4, 0.5], "delta", grid_values(entry["delta"]),
                        {"zeta": 0.05, "inv_beta": 1.1}, types=[(1, 1), (2, 1), (1, 2)])
    assert built.attrs["axes"] == ["eps", "delta"] or list(built.attrs["axes"]) == ["eps",
                                                                                    "delta"]
    for name in ("exists", "n_solutions", "n_stable", "lam", "S", "reason"):
        np.testing.assert_array_equal(built[name].values, whole[name].values)
    np.testing.assert_array_equal(built["delta"].values, whole["delta"].values)
    bblock = {k: entry[k] for k in ORBIT_JOB_KEYS["boundaries"] if k in entry}
    tasks.boundaries(bblock, tmp_path / "orbits.nc", tmp_path / "boundaries.nc")
    curves = io.load_dataset(tmp_path / "boundaries.nc")
    assert int(curves.attrs["traced"]) == 1
    assert {"eps", "delta", "codim2_eps", "codim2_delta"} <= set(curves.variables)
    assert "inv_beta" not in curves.variables
    # the (1/1) grazing edge at eps = 0.5 lies between the map's last unstable and first
    # stable cell of that column
    one = curves["type"].values == "1/1"
    graz = [c for c in np.flatnonzero(one) if curves["kind"].values[c] == "grazing"]
    assert graz
    pts = curves["curve"].values == graz[0]
    e, d = curves["eps"].values[pts], curves["delta"].values[pts]
    k = np.argmin(np.abs(e - 0.5))
    column = built["n_stable"].sel(type="1/1", eps=0.5).values > 0
    first = built["delta"].values[np.argmax(column)]
    assert abs(e[k] - 0.5) < 0.02 and first - 0.05 < d[k] <= first


def test_the_planes_example_draws_fig16_over_its_restitution_plane():
    """config/examples/planes.yaml: the (eps, delta) study draws fig15_vs_fig16 over the
    orbits entry of its plane; the plan costs the entry's tiles, join, edges and figure."""
    config, plan = configuration.load(root=ROOT,
                                      user_files=[ROOT / "config/examples/planes.yaml"])
    entry = config["orbits"]["restitution"]
    assert entry["plane"] == config["studies"]["restitution"]["plane"] == ["eps", "delta"]
    assert {"name": "fig15_vs_fig16", "orbits": "restitution"} in (
        config["studies"]["restitution"]["figures"])
    row = next(r for r in plan.rows if r.key == "orbits.restitution")
    assert row.orbit_cells == 41 * 201 and row.jobs == 2 + 1 + 1 + 1


@pytest.mark.parametrize("grid", ["[0.5, 1.0]", "{start: 0.5, stop: 1.0, step: 0.5}"])
def test_an_amplitude_plane_is_planned_with_its_report_and_captions(tmp_path, grid):
    """The amplitude is an axis the README offers: a plane over it plans (its targets, its
    report, the figures' captions), its report the harmonic one, its amplitude argument NaN
    (no one amplitude)."""
    from vibroimpact.pipeline import figures, targets
    from vibroimpact.reports import arguments

    text = EPS_DELTA.replace("plane: [eps, delta]", "plane: [amplitude, delta]").replace(
        "    eps: [0.3, 0.5]\n", "    eps: 0.5\n").replace("    amplitude: 1.0\n",
                                                          f"    amplitude: {grid}\n")
    config, plan = _load(tmp_path, text)
    entry = config["studies"]["plane"]
    assert plan.studies["plane"].plane == ("amplitude", "delta")
    assert arguments.study_report_kind(entry) == "harmonic_random"
    assert "results/reports/plane/harmonic_random.html" in targets.report_targets(
        config, {"studies": ["plane"], "orbits": []})
    assert "1/beta\\_f = 1.1" in figures.caption("study", "plane", entry, "fig15")
    got = arguments.notebook_parameters("harmonic_random", {}, study="plane", entry=entry,
                                        inv_beta=[1.1])
    assert got["amplitude"] == "nan"


def test_the_restitution_study_s_predictors_read_its_own_basins_and_exponents():
    """config/examples/planes.yaml: the restitution study simulates its basins and exponents
    over its own (eps, delta) cells (its `attractors` block): the predictors of its P read
    them, with its map and the orbits of the entry its fig15_vs_fig16 names at its cells
    (rule solve_map_orbits, from the map and that orbit map)."""
    from vibroimpact.pipeline import targets

    config, _ = configuration.load(root=ROOT, user_files=[ROOT / "config/examples/planes.yaml"])
    assert targets.predictors_inputs(config, "restitution") == {
        "map": "results/datasets/restitution_map.nc",
        "orbits": "results/datasets/restitution_map_orbits.nc",
        "basins": "results/datasets/restitution_basins.nc",
        "lyapunov": "results/datasets/restitution_lyapunov.nc"}
    assert targets.map_orbits_inputs(config, "restitution") == {
        "map": "results/datasets/restitution_map.nc",
        "orbits": "results/orbits/restitution.nc"}


def test_two_rms_planes_on_one_noise_entry_share_its_unit_rms_record(tmp_path):
    """Two (rms, delta) studies of one noise entry read the same unit-rms record: one copy
    of the entry, one file; a third on another seed gets its own."""
    second = RMS_DELTA.split("studies:\n")[1].replace("  noisy:", "  noisy_too:").replace(
        "    eps: 0.5\n", "    eps: 0.7\n")
    third = second.replace("  noisy_too:", "  reseeded:").replace(
        "    noise: tiny\n", "    noise: tiny\n    seed: 99\n")
    config, _ = _load(tmp_path, RMS_DELTA + second + third)
    noises = {name: config["studies"][name]["noise"]
              for name in ("noisy", "noisy_too", "reseeded")}
    assert noises["noisy"] == noises["noisy_too"] != noises["reseeded"]
    unit = config["noises"][noises["noisy"]]
    assert unit["rms"] == 1.0 and unit["seed"] == config["noises"]["tiny"]["seed"]
    assert config["noises"][noises["reseeded"]]["seed"] == 99


def test_every_pair_of_axes_is_a_plane(tmp_path):
    """One file with a study over each of the 28 pairs of `PLANE_PARAMETERS` plans (an
    amplitude axis raised TypeError for every pair that named it; the issue's trial file). A
    plane naming eps_lower gets the second wall (gap 4) it needs."""
    import itertools

    import yaml

    from vibroimpact.pipeline.study import PLANE_PARAMETERS

    grid = {"zeta": [0.03, 0.05], "eps": [0.3, 0.5], "eps_lower": [0.3, 0.5],
            "delta": [0.0, 1.0], "gap": [4.0, 5.0], "amplitude": [0.8, 1.0],
            "inv_beta": [1.0, 1.1], "rms": [0.2, 0.29]}
    fixed = {"zeta": 0.05, "eps": 0.5, "delta": 1.0, "amplitude": 1.0, "inv_beta": 1.1}
    studies = {}
    for x, y in itertools.combinations(PLANE_PARAMETERS, 2):
        entry = dict(fixed, noise="tiny", plane=[x, y], transient=100.0, figures=["fig15"],
                     map=dict(target_stderr=0.1, min_time=300.0, max_periods=200))
        if "eps_lower" in (x, y):
            entry["gap"] = 4.0
        entry.update({x: grid[x], y: grid[y]})
        studies[f"p_{x}_{y}"] = entry
    text = TINY_NOISE + yaml.safe_dump({"studies": studies}, sort_keys=False)
    config, plan = _load(tmp_path, text)
    assert len(studies) == 28
    for name, entry in studies.items():
        assert config["studies"][name]["plane"] == entry["plane"]
    assert plan.cells == 28 * 4
