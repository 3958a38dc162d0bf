"""Two-wall studies on the workflow side (issue 35): the config keys, the resolved model, the
per-wall statistics of a cell and the classification by the collisions' wall sequence."""
import numpy as np
import pytest
import yaml

from vibroimpact.model import Model
from vibroimpact.pipeline import cells, datasets
from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline.cells import study_model
from vibroimpact.pipeline.study import JOB_KEYS, ORBIT_JOB_KEYS, Study
from vibroimpact.stats import motions as motion_stats

from helpers import ROOT

# --- the classification by the collisions' wall sequence ---------------------------------------


def test_two_wall_motions_read_the_walls_and_one_wall_motions_do_not():
    # a (1,1)/1 stretch (alternating walls, half a period apart), then (1,0)/1 (upper only)
    ratio = np.array([0.5, 0.5, 0.5, 0.5, 1.0, 1.0, 1.0])
    walls = np.array([0, 1, 0, 1, 0, 0, 0])
    two = [(1, 1, 1), (1, 0, 1), (0, 1, 1)]
    labels = motion_stats.classify_impact_intervals(ratio, 0.1, two, walls=walls)
    assert labels.tolist() == [0, 0, 0, 0, 1, 1, 1]
    # the same intervals at one wall only: no (1,1)/1 (its pairs have no lower collision)
    same = motion_stats.classify_impact_intervals(ratio, 0.1, two, walls=np.zeros(7, int))
    assert same.tolist() == [-1, -1, -1, -1, 1, 1, 1]
    # (m, n) pairs ignore the walls: today's labels with or without them
    pairs = [(1, 1), (2, 1), (1, 2)]
    assert np.array_equal(motion_stats.classify_impact_intervals(ratio, 0.1, pairs),
                          motion_stats.classify_impact_intervals(ratio, 0.1, pairs, walls=walls))


def test_a_lower_wall_motion_and_its_names():
    ratio = np.array([1.0, 1.0, 0.3, 0.7])
    walls = np.array([1, 1, 0, 0])
    labels = motion_stats.classify_impact_intervals(ratio, 0.1, [(0, 1, 1), (2, 0, 1)],
                                                    walls=walls)
    assert labels.tolist() == [0, 0, 1, 1]
    assert motion_stats.motion_key((1, 1, 1)) == "(1,1)/1"
    assert motion_stats.motion_key((2, 1)) == "2/1"
    p = motion_stats.impact_motion_probabilities(ratio * 2 * np.pi, 1.0, 0.1,
                                                 motions=[(0, 1, 1), (2, 0, 1)], walls=walls)
    assert p == pytest.approx({"(0,1)/1": 2.0 / 3.0, "(2,0)/1": 1.0 / 3.0}, rel=1e-12)


def test_a_two_wall_motion_without_walls_is_refused():
    with pytest.raises(ValueError, match="walls"):
        motion_stats.classify_impact_intervals([1.0], 0.1, [(1, 1, 1)])
    with pytest.raises(ValueError, match="one wall per interval"):
        motion_stats.classify_impact_intervals([1.0, 1.0], 0.1, [(1, 1, 1)], walls=[0])
    with pytest.raises(ValueError, match="triples"):
        motion_stats.classify_impact_intervals([1.0], 0.1, [(0, 0, 1)], walls=[0])


# --- config: keys, errors, the resolved model --------------------------------------------------

OWN = ("paper: false\nstudies:\n  mine:\n    noise: harmonic_input\n    zeta: 0.05\n"
       "    eps: 0.5\n    amplitude: 1.0\n    inv_beta: [1.1]\n    delta: [0.0, 1.0]\n"
       "    transient: 100.0\n    figures: [fig09]\n")


def _load(tmp_path, text):
    path = tmp_path / "mine.yaml"
    path.write_text(text)
    return configuration.load(root=ROOT, user_files=[path])[0]


@pytest.mark.parametrize("extra, key, fragment", [
    ("    eps_lower: 0.3\n", "studies.mine.eps_lower", "give studies.mine.gap > 0"),
    ("    gap: 0.0\n", "studies.mine.gap", "0"),
    ("    gap: 2.0\n    eps_lower: 1.5\n", "studies.mine.eps_lower", "1"),
    ("    motions: [[1, 1, 1]]\n", "studies.mine.motions", "give studies.mine.gap > 0"),
])
def test_a_bad_second_wall_is_refused_naming_its_key(tmp_path, extra, key, fragment):
    with pytest.raises(configuration.ConfigError) as info:
        _load(tmp_path, OWN + extra)
    text = "\n".join(info.value.problems)
    assert key in text and fragment in text, text


def test_a_gap_without_eps_lower_takes_eps_and_resolves_one_model(tmp_path):
    config = _load(tmp_path, OWN + "    gap: 2.0\n    motions: [[1, 1, 1], [1, 1]]\n")
    entry = config["studies"]["mine"]
    study = Study.from_config("mine", entry)
    assert (study.gap, study.eps_lower, study.n_walls) == (2.0, 0.5, 2)
    cell = study.cells()[1]
    model = study_model(study, cell)
    assert (model.delta, model.lower, model.eps_lower) == (1.0, -1.0, 0.5)
    assert model.beta == 1.0 / 1.1
    assert study.motions == ((1, 1, 1), (1, 1))


def test_the_paper_studies_have_one_wall_and_their_job_params_no_wall_key():
    config = configuration.load(root=ROOT)[0]
    for kind in ("events", "map", "spectra", "trace", "escape"):
        assert {"gap", "eps_lower"} <= set(JOB_KEYS[kind])
    for kind in ORBIT_JOB_KEYS:
        assert {"gap", "eps_lower"} <= set(ORBIT_JOB_KEYS[kind])
    for name, entry in config["studies"].items():
        assert "gap" not in entry and "eps_lower" not in entry, name
        study = Study.from_config(name, entry)
        assert study.walls() == {} and study.n_walls == 1
        assert study_model(study, study.cells(
            "events" if study.delta.size else "spectra")[0]).n_walls == 1


def test_the_example_config_loads_with_two_walls():
    config = configuration.load(
        root=ROOT, user_files=[ROOT / "config/examples/clearance.yaml"])[0]
    raw = yaml.safe_load((ROOT / "config/examples/clearance.yaml").read_text())
    for name in raw["studies"]:
        study = Study.from_config(name, config["studies"][name])
        assert study.gap == 2.0 and study.eps_lower == 0.5


# --- a cell's per-wall statistics --------------------------------------------------------------

BINS = {"v_after": np.linspace(0, 3, 31), "interval": np.linspace(0, 30, 61),
        "ratio": np.linspace(0, 4, 41)}


def _noise(n=40001, seed=3, rms=0.6):
    return rms * np.random.default_rng(seed).standard_normal(n)


def test_symmetric_stops_mirror_the_walls_exactly():
    """Stops at +-1 (delta = 1, gap = 2), both eps = 0.5, no harmonic force, from rest at 0:
    the force -r drives the mirror image x -> -x of the motion under r, so each wall's
    statistics under r are the other wall's under -r (to round-off: the two walls are
    searched in mirrored frames by the same code)."""
    r = _noise(rms=1.2)
    model = Model.paper(0.05, 0.5, 1.0, gap=2.0, eps_lower=0.5)
    kw = dict(transient=50.0, bins=BINS, n_batches=10)
    a = cells.event_statistics(r, 0.1, model, **kw)
    b = cells.event_statistics(-r, 0.1, model, **kw)
    assert a["wall_n_collisions"].sum() == a["n_collisions"] > 100
    assert a["wall_n_collisions"].min() > 20
    assert a["wall_n_collisions"].tolist() == b["wall_n_collisions"][::-1].tolist()
    for name in ("wall_v_after_mean", "wall_interval_mean", "wall_collision_rate"):
        np.testing.assert_allclose(a[name], b[name][::-1], rtol=1e-9, err_msg=name)
    np.testing.assert_allclose(a["wall_v_after_density"], b["wall_v_after_density"][::-1],
                               rtol=1e-9, atol=1e-12)
    # the self-audit with a term per wall: both identities hold within their errors
    for name in ("power", "virial"):
        assert abs(a[f"{name}_residual"]) < 4.0 * a[f"{name}_residual_stderr"], name


def test_each_wall_rebounds_with_its_own_restitution():
    """Stops at +-1 with eps 0.7 above and 0.3 below under r, against eps 0.3 above and 0.7
    below under -r: the mirror image, so the walls' statistics swap (velocity after impact
    eps_w u with each wall's own eps_w)."""
    r = _noise(rms=1.2, seed=11)
    kw = dict(transient=50.0, bins=BINS, n_batches=10)
    a = cells.event_statistics(r, 0.1, Model.paper(0.05, 0.7, 1.0, gap=2.0, eps_lower=0.3),
                               **kw)
    b = cells.event_statistics(-r, 0.1, Model.paper(0.05, 0.3, 1.0, gap=2.0, eps_lower=0.7),
                               **kw)
    assert a["wall_n_collisions"].min() > 20
    assert a["wall_n_collisions"].tolist() == b["wall_n_collisions"][::-1].tolist()
    np.testing.assert_allclose(a["wall_v_after_mean"], b["wall_v_after_mean"][::-1], rtol=1e-9)
    # the physical and impacts-only rules (the per-rebound rule's floor test is
    # `stats.group_collisions`', which takes one eps until it knows the walls)
    np.testing.assert_allclose(a["rule_v_after_mean"][:2], b["rule_v_after_mean"][:2],
                               rtol=1e-9)
    np.testing.assert_allclose(a["rebound_v_after_mean"], b["rebound_v_after_mean"],
                               rtol=1e-9)


def test_a_far_second_wall_gives_the_one_wall_cell():
    """A lower wall 1e3 below (never reached): every statistic of the one-wall cell, and
    every collision at the upper wall."""
    r = _noise(20001, seed=5)
    kw = dict(transient=50.0, bins=BINS, n_batches=10, motions=((1, 1), (2, 1), (1, 2)))
    one = cells.event_statistics(r, 0.1, Model.paper(0.05, 0.5, 0.5, 1.0, 1.0 / 1.1), **kw)
    two = cells.event_statistics(r, 0.1, Model.paper(0.05, 0.5, 0.5, 1.0, 1.0 / 1.1, gap=1e3),
                                 **kw)
    assert two["wall_n_collisions"].tolist() == [one["n_collisions"], 0]
    for name in ("n_collisions", "v_after_mean", "interval_mean", "v_after_density",
                 "interval_density", "ratio_density", "motion_probability",
                 "motion_stick_probability", "stuck_fraction"):
        np.testing.assert_array_equal(two[name], one[name], err_msg=name)
    assert two["wall_v_after_mean"][0] == one["v_after_mean"]


def test_the_two_wall_tile_dataset_has_a_wall_dimension():
    r = _noise(20001, seed=7)
    study = Study.from_config("s", dict(zeta=0.05, eps=0.5, amplitude=1.0, inv_beta=[1.0],
                                        delta=[1.0], tile_size=1, gap=2.0, eps_lower=0.3,
                                        motions=[[1, 1, 1], [1, 0, 1]]))
    cell = study.cells()[0]
    result = cells.event_statistics(r, 0.1, study_model(study, cell), transient=50.0, bins=BINS,
                                    n_batches=10, motions=study.motions)
    ds = datasets.events_tile([cell], [result], BINS, {}, motions=study.motions)
    assert ds["wall"].values.tolist() == ["upper", "lower"]
    assert ds["wall_v_after_density"].dims == ("cell", "wall", "v_after")
    assert ds["motion"].values.tolist() == ["(1,1)/1", "(1,0)/1"]
    assert int(ds["wall_n_collisions"].sum()) == int(ds["n_collisions"].sum())
    assert ds["wall_collision_rate"].attrs["long_name"]
    # the velocity after impact at the lower wall is eps_lower u: bounded by eps_lower times
    # the fastest approach, and each wall's mean is eps_w times its mean approach
    assert result["wall_v_after_mean"][1] < result["wall_v_after_mean"][0]


# --- the workflow: a tiny two-wall config's datasets and one figure -----------------------------

TINY = """\
paper: false
noises:
  tiny_input:
    kind: band_limited
    rms: 0.29
    dt: 0.1
    beta_c: 4.0
    n_samples: 40001
    seed: 7
studies:
  clear:
    noise: tiny_input
    zeta: 0.05
    eps: 0.5
    gap: 2.0
    eps_lower: 0.3
    amplitude: 1.0
    inv_beta: [1.1]
    delta: [0.5, 1.0]
    transient: 100.0
    tile_size: 1
    motions: [[1, 1, 1], [1, 0, 1]]
    figures: [fig09]
  clear_map:
    noise: tiny_input
    zeta: 0.05
    eps: 0.5
    gap: 2.0
    amplitude: 1.0
    inv_beta: [0.9, 1.1]
    delta: [0.5, 1.0]
    transient: 100.0
    tile_size: 2
    motions: [[1, 1, 1], [1, 0, 1], [0, 1, 1]]
    map: {target_stderr: 0.05, min_time: 500.0, max_periods: 300}
    figures: [fig15]
"""


@pytest.mark.workflow
def test_a_two_wall_config_builds_its_datasets_and_a_figure(tmp_path):
    import xarray as xr

    from helpers import assert_cf, make_workdir, snakemake

    work = make_workdir(tmp_path / "wf")
    (work / "tiny.yaml").write_text(TINY)
    targets = ["results/datasets/clear_events.nc", "results/datasets/clear_map_map.nc",
               "results/figures/clear/fig09.png"]
    snakemake(work, *targets, config="tiny.yaml")
    assert_cf(work / "results")        # a two-wall study's files (the clearance example's)
    events = xr.load_dataset(work / targets[0])
    assert events.attrs["gap"] == 2.0 and events.attrs["eps_lower"] == 0.3
    assert events["wall"].values.tolist() == ["upper", "lower"]
    n = events["wall_n_collisions"].sum("wall")
    assert (n == events["n_collisions"]).all() and int(n.sum()) > 0
    # stops at 0.5 and -1.5 under sin + r: the upper wall, nearer the rest position, is hit
    # more often than the lower one
    at = events.sel(delta=0.5).isel(inv_beta=0)
    assert int(at["wall_n_collisions"].sel(wall="upper")) > int(
        at["wall_n_collisions"].sel(wall="lower"))
    assert events["motion"].values.tolist() == ["(1,1)/1", "(1,0)/1"]
    motion_map = xr.load_dataset(work / targets[1])
    assert motion_map["motion"].values.tolist() == ["(1,1)/1", "(1,0)/1", "(0,1)/1"]
    assert motion_map["wall_collision_rate"].dims == ("inv_beta", "delta", "wall")
    assert float(motion_map["probability"].max()) > 0.0
    assert (work / targets[2]).stat().st_size > 10_000


def test_the_paper_cells_get_the_arguments_they_always_got():
    """The jobs resolve each cell's model (`cells.study_model`); for the paper's one-wall
    studies it is the model of the loose values the jobs passed before models, float for
    float (so their datasets stay bit for bit)."""
    config, plan = configuration.load(root=ROOT)
    for name, study in plan.studies.items():
        for kind in ("events", "spectra"):
            for cell in study.cells(kind):
                model = study_model(study, cell)
                assert model == Model.paper(study.zeta, study.eps, cell.delta,
                                            study.amplitude, 1.0 / cell.inv_beta), (name, cell)
                assert (model.zeta, model.eps, model.delta, model.amplitude, model.beta) == (
                    study.zeta, study.eps, cell.delta, study.amplitude, 1.0 / cell.inv_beta)


def test_the_plan_resolves_each_study_once_from_the_checked_grids():
    """`configuration.load` expands each grid once (the checks) and the plan, the workflow
    (common.smk's STUDIES = PLAN.studies) and the cost model reuse it; a study resolved
    anew from its entry has the same grids, value for value."""
    config, plan = configuration.load(root=ROOT)
    assert set(plan.studies) == set(config["studies"])
    for name, study in plan.studies.items():
        again = Study.from_config(name, config["studies"][name])
        for axis in ("inv_beta", "delta", "spectra_delta"):
            assert np.array_equal(getattr(study, axis), getattr(again, axis)), (name, axis)


def test_the_aggregate_reads_the_axes_from_its_tiles():
    study = Study.from_config("s", dict(zeta=0.05, eps=0.5, amplitude=1.0,
                                        inv_beta=[0.9090909090909091, 1.1],
                                        delta={"start": 2.0, "stop": 3.0, "step": 0.1},
                                        tile_size=4))
    tiles = []
    for t in range(study.n_tiles()):
        cells_t = study.tile(t)
        tiles.append(datasets.xr.Dataset(coords=datasets._cell_coords(cells_t)))
    inv_beta, delta = datasets.tile_axes(tiles[::-1], n_cells=len(study.cells()))
    assert np.array_equal(inv_beta, study.inv_beta) and np.array_equal(delta, study.delta)
    with pytest.raises(ValueError, match="expected 0..21"):
        datasets.tile_axes(tiles[1:], n_cells=22)


@pytest.mark.slow
def test_the_two_wall_orbit_map_sees_the_mirror_of_its_cells():
    """The clearance of the example (stops 2 apart) under sin(tau/0.75): at delta = 1 the
    stops are symmetric and the (1,1)/1 motion is stable; the cells delta = 0.25 and 1.75 are
    each other's mirror image (x -> -x with the force's half-period shift), so the (1,0)/1
    motion of one is the (0,1)/1 motion of the other, with the same degree of stability (to
    the solver's precision)."""
    from vibroimpact.attractors.plane import orbit_plane

    types = [(1, 1, 1), (1, 0, 1), (0, 1, 1)]
    ds = orbit_plane("inv_beta", [0.75], "delta", [0.25, 1.0, 1.75],
                     dict(zeta=0.05, eps=0.5, gap=2.0), types)
    out = {k: ds[k].values for k in ("S", "reason")}
    assert out["S"].shape == (3, 1, 3)
    assert out["reason"][0, 0, 1] == 0 and out["S"][0, 0, 1] > 0
    mirror = {0: 0, 1: 2, 2: 1}
    for k, k_m in mirror.items():
        assert out["reason"][k, 0, 0] == out["reason"][k_m, 0, 2], types[k]
        if out["reason"][k, 0, 0] == 0:
            assert abs(out["S"][k, 0, 0] - out["S"][k_m, 0, 2]) < 1e-6, types[k]
    assert out["reason"][1, 0, 0] == 0 and out["reason"][2, 0, 2] == 0


def test_dataset_motion_names_are_the_classifications_names():
    from vibroimpact.pipeline import datasets
    from vibroimpact.stats.motions import motion_key

    motions = [(1, 1), (2, 1), (1, 2), (1, 1, 1), (1, 0, 1), (0, 1, 2), (2, 3, 4)]
    assert datasets._motion_names(motions) == [motion_key(m) for m in motions]
