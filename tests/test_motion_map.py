"""The Fig. 15 map cell: deterministic limits against `periodic_orbits`, and bit-identity with
simulating the cell alone (`simulate`) and classifying its impacts."""
import numpy as np
import pytest

from vibroimpact import Model, periodic_orbits, simulate, stats
from vibroimpact.noise import NoiseSpec, generate_array
from vibroimpact.pipeline.cells import motion_map_cell

ZETA, EPS, DT = 0.05, 0.5, 0.1
MOTIONS = ((1, 1), (2, 1), (1, 2))
TRANSIENT = 3000.0   # e^(-zeta * 3000) = 1e-65: the transient from rest has died out


def _map_cell(noise, inv_beta, delta, **kw):
    kw = dict(dict(transient=TRANSIENT, min_time=2000.0, max_periods=600), **kw)
    return motion_map_cell(noise, DT, Model.paper(ZETA, EPS, delta, 1.0, 1.0 / inv_beta),
                           motions=MOTIONS, **kw)


def _alone(noise, inv_beta, delta, transient, t_end):
    """The cell simulated by itself over ``[0, t_end]``: its collisions after the transient."""
    res = simulate(ZETA, EPS, delta, noise=noise, dt=DT, amplitude=1.0, beta=1.0 / inv_beta,
                   t_end=t_end)
    keep = res.collision_time >= transient
    return (res, res.collision_step[keep], res.collision_offset[keep],
            res.collision_velocity[keep])


# (inv_beta, delta) inside the stable domain of each type (Fig. 16), where the motion from
# rest under sin(beta tau) alone settles on that orbit
DETERMINISTIC = [((1, 1), 1.1, 1.0), ((2, 1), 1.1, 0.0), ((1, 2), 1.1, 2.5),
                 ((1, 1), 0.6, 0.5)]


@pytest.mark.parametrize("motion, inv_beta, delta", DETERMINISTIC)
def test_without_noise_a_stable_orbit_is_the_whole_record(motion, inv_beta, delta):
    """r = 0: the probability of the orbit's type is 1 up to the uncovered ends of the record
    (before the first and after the last impact, and for m = 2 a lone interval at either end
    when the record starts or stops inside a pair); the others are 0; the impact velocities
    equal the orbit's to 1e-8."""
    noise = np.zeros(int((TRANSIENT + 600 * 2 * np.pi * inv_beta) / DT) + 10)
    m, n = motion
    (orbit,) = [o for o in periodic_orbits(m, n, 1.0 / inv_beta, delta, ZETA, EPS) if o.stable]
    cell = _map_cell(noise, inv_beta, delta)
    _, step, offset, u = _alone(noise, inv_beta, delta, TRANSIENT, cell["record_end"])
    t = step * DT + offset
    z = stats.impact_intervals(step, offset, DT)
    labels = stats.classify_impact_intervals(stats.interval_ratio(z, 1.0 / inv_beta),
                                             motions=MOTIONS)
    k = MOTIONS.index(motion)
    ends = (t[0] - TRANSIENT) + (cell["record_end"] - t[-1])
    if m == 1:
        assert (labels == k).all()
    else:
        assert (labels[1:-1] == k).all()
        ends += z[0] * (labels[0] != k) + z[-1] * (labels[-1] != k)
    assert cell["probability"][k] == pytest.approx(1.0 - ends / cell["simulated_time"],
                                                   abs=1e-12)
    assert np.delete(cell["probability"], k).max() == 0.0
    assert cell["n_switches"] == 0 and cell["reached"] and not cell["few_switches"]
    # every impact velocity of the record is one of the orbit's m velocities
    dist = np.abs(u[:, None] - orbit.velocities[None, :]).min(axis=1)
    assert dist.max() < 1e-8
    assert cell["v_after_mean"] == pytest.approx(EPS * orbit.velocities.mean(), abs=1e-8)


def test_without_noise_below_the_wall_there_is_no_impact():
    """1/beta = 0.3: the wall-free response has amplitude 1/|1 - beta^2| ~ 0.1 < delta = 1."""
    noise = np.zeros(100_000)
    cell = _map_cell(noise, 0.3, 1.0, transient=200.0, max_periods=5000)
    assert cell["n_collisions"] == 0 and not cell["probability"].any()
    assert not cell["stick_probability"].any()
    assert cell["reached"] and cell["simulated_time"] == pytest.approx(2000.0, abs=DT)


@pytest.fixture(scope="module")
def record():
    spec = NoiseSpec(kind="band_limited", rms=0.29, dt=DT, beta_c=4.0)
    return generate_array(spec, 300_001, 1974)


@pytest.mark.parametrize("inv_beta, delta", [(2.6, -0.75), (1.4, 0.7), (0.9, 1.3), (2.0, 0.95)])
def test_a_map_cell_is_bit_identical_to_the_cell_alone(record, inv_beta, delta):
    """Stopping at precision checks (chunks of any length) changes nothing: `simulate` to the
    cell's record end gives the same collisions, and classifying them the same probabilities,
    to the last bit."""
    cell = _map_cell(record, inv_beta, delta, transient=200.0, max_periods=1500,
                     target_stderr=0.02)
    assert cell["n_checks"] >= 2 or cell["reached"]
    res, step, offset, u = _alone(record, inv_beta, delta, 200.0, cell["record_end"])
    z = stats.impact_intervals(step, offset, DT)
    stuck = res.collision_stuck[res.collision_time >= 200.0][:-1]
    p = stats.impact_motion_probabilities(z, 1.0 / inv_beta, total_time=cell["simulated_time"],
                                          motions=MOTIONS, stuck=stuck)
    assert list(cell["probability"]) + list(cell["stick_probability"]) == list(p.values())
    assert cell["n_collisions"] == u.size and cell["v_after_mean"] == EPS * u.mean()


def test_a_cell_stops_at_its_precision_or_at_the_cap(record):
    """Precise cells stop early with every error at target; the cap stops the others, which
    say so; a record too short for the cap is refused before any simulation."""
    quick = _map_cell(record, 0.9, 1.3, transient=200.0, max_periods=2000, target_stderr=0.05)
    assert quick["reached"] and quick["stderr"].max() <= 0.05
    assert quick["simulated_time"] < 2000 * 2 * np.pi * 0.9
    capped = _map_cell(record, 2.0, 0.95, transient=200.0, max_periods=50, min_time=100.0,
                       target_stderr=1e-4)
    assert not capped["reached"]
    assert capped["record_end"] == pytest.approx(200.0 + 50 * 2 * np.pi * 2.0, abs=DT)
    with pytest.raises(ValueError, match="max_periods"):
        _map_cell(record[:1000], 2.0, 0.95, transient=200.0, max_periods=50)


#: the check schedule before the default (each check at 1.1 times the predicted length)
AIMED_PAST = dict(approach=1.1, approach_unswitched=1.1, min_growth=1.1)


@pytest.mark.parametrize("inv_beta, delta", [(2.6, -0.75), (1.4, 0.7), (2.0, 0.95)])
def test_the_check_schedule_moves_no_probability_beyond_its_error(record, inv_beta, delta):
    """The schedule of the precision checks is a numerical setting: a record stopped near its
    target (the default) and one aimed past it give probabilities within three of their
    standard errors (the records overlap, one a prefix of the other), both at the target."""
    kw = dict(transient=200.0, max_periods=1500, target_stderr=0.02)
    near = _map_cell(record, inv_beta, delta, **kw)
    past = _map_cell(record, inv_beta, delta, **kw, **AIMED_PAST)
    assert near["reached"] and past["reached"]
    assert near["record_end"] != past["record_end"]     # the schedules did stop apart
    for p, se in (("probability", "stderr"), ("stick_probability", "stick_stderr")):
        bound = 3.0 * np.maximum(near[se], past[se])
        assert (np.abs(near[p] - past[p]) <= bound).all(), (p, near[p], past[p], bound)


# --- residence times and switching rates of a cell (stats.residence_statistics) -------------

@pytest.fixture(scope="module")
def test_config_map():
    """The noise and map parameters of the `motion_map` study of config/test.yaml."""
    import yaml
    from pathlib import Path

    config = yaml.safe_load((Path(__file__).parents[1] / "config" / "test.yaml").read_text())
    study = config["studies"]["motion_map"]
    spec = dict(config["noises"][study["noise"]])
    n, seed = spec.pop("n_samples"), spec.pop("seed")
    noise = generate_array(NoiseSpec(**spec), n, seed)
    kw = dict(transient=study["transient"], n_batches=study["n_batches"],
              window=study["motion_window"], motions=tuple(map(tuple, study["motions"])),
              **study["map"])
    system = (study["zeta"], study["eps"], study["amplitude"])
    return noise, spec["dt"], system, kw


# many switches, 7 switches with none (a few-switches cell), and the (2/1)-dominated cell
@pytest.mark.parametrize("inv_beta, delta", [(2.5, 1.0), (1.5, -1.0), (1.0, 1.0), (1.5, 0.5)])
def test_stationary_distribution_of_the_rates_is_the_time_on_the_cell(test_config_map,
                                                                      inv_beta, delta):
    """The stationary distribution of the cell's rate matrix against the fractions of time it
    stores (probability plus its stick variant; "none" the rest): within one standard
    error. They differ only by the time before the first and after the last collision
    (counted as "none" by the probabilities, unknown for the stretches) and by the one
    switch by which the first and last states' ins and outs differ: an identity of the
    bookkeeping, Markov or not (`stats.residence_statistics`). Measured (the four cells):
    |pi - p| <= 0.014, at most 0.46 of the standard error."""
    noise, dt, (zeta, eps, amplitude), kw = test_config_map
    cell = motion_map_cell(noise, dt, Model.paper(zeta, eps, delta, amplitude, 1.0 / inv_beta),
                           **kw)
    p = cell["probability"] + cell["stick_probability"]
    p = np.append(p, 1.0 - p.sum())
    err = np.hypot(cell["stderr"], cell["stick_stderr"])
    err = np.append(err, np.sqrt((err ** 2).sum()))
    pi = stats.stationary_distribution(cell["switch_rate"])
    assert pi.sum() == pytest.approx(1.0)
    assert (np.abs(pi - p) <= err).all(), (pi, p, err)
    # the residence times and rates are in forcing periods and agree with the counts
    period = 2 * np.pi * inv_beta
    seen = cell["n_stretches"] + cell["n_censored"] > 0
    assert (cell["switch_count"].sum(axis=1)[seen] >= cell["n_stretches"][seen]).all()
    assert np.isnan(cell["switch_rate"][~seen]).all()
    assert np.nanmax(cell["residence_time"]) < cell["simulated_time"] / period


def test_residence_of_a_stable_orbit_without_noise_is_one_cut_stretch():
    """r = 0, the (1/1) orbit: one stretch, cut at both ends: no complete stretch, no mean,
    no switch."""
    inv_beta, delta = 1.1, 1.0
    noise = np.zeros(int((TRANSIENT + 600 * 2 * np.pi * inv_beta) / DT) + 10)
    cell = _map_cell(noise, inv_beta, delta)
    assert cell["n_stretches"].tolist() == [0, 0, 0, 0]
    assert cell["n_censored"].tolist() == [1, 0, 0, 0]
    assert np.isnan(cell["residence_time"]).all() and not cell["switch_count"].any()
    assert cell["switch_rate"][0].tolist() == [0.0] * 4
    assert stats.stationary_distribution(cell["switch_rate"]).tolist() == [1.0, 0.0, 0.0, 0.0]


def test_the_map_dataset_stores_residence_and_rates_beside_the_probabilities(tmp_path):
    """The workflow's tasks (`simulate_map` tile, `aggregate_map`) on a 2 x 2 map: the new
    variables over ``state`` / ``from_motion``, ``to_motion`` and the plane, described, and
    each cell's values those of `motion_map_cell` run alone."""
    import xarray as xr

    from vibroimpact.pipeline import tasks

    noise = tmp_path / "noise.nc"
    tasks.make_noise(dict(kind="band_limited", rms=0.29, dt=DT, beta_c=4.0, n_samples=60_001,
                          seed=5, nperseg=256), noise)
    block = dict(noise="n", zeta=ZETA, eps=EPS, amplitude=1.0, inv_beta=[1.0, 2.0],
                 delta=[0.0, 1.0], transient=200.0, tile_size=100, n_batches=20,
                 motion_window=0.1, motions=[[1, 1], [2, 1], [1, 2]],
                 map=dict(target_stderr=0.05, min_time=500.0, max_periods=300,
                          min_switches=10))
    tasks.map_tile("m", block, 0, noise, tmp_path / "tile.nc")
    tasks.aggregate("m", block, "map", [tmp_path / "tile.nc"], tmp_path / "map.nc")
    ds = xr.load_dataset(tmp_path / "map.nc")
    states = ["1/1", "2/1", "1/2", "none"]
    assert ds["motion"].values.tolist() == states[:3]
    assert ds["probability"].dims == ("motion", "inv_beta", "delta")
    for name in ("residence_time", "residence_time_stderr", "n_stretches", "n_censored"):
        assert ds[name].dims == ("motion", "inv_beta", "delta"), name
        assert ds[f"{name}_none"].dims == ("inv_beta", "delta"), name
        assert ds[name].attrs["long_name"], name
        assert ds[f"{name}_none"].attrs["long_name"], name
        assert stats.by_state(ds)[name].dims == ("state", "inv_beta", "delta")
    assert stats.by_state(ds)["state"].values.tolist() == states
    for name in ("switch_rate", "switch_count"):
        assert ds[name].dims == ("from_motion", "to_motion", "inv_beta", "delta"), name
        assert ds[name].attrs["long_name"], name
    for dim in ("from_motion", "to_motion"):
        assert ds[dim].values.tolist() == states
    from vibroimpact.pipeline import io

    samples, dt, _ = io.read_noise(noise)
    cell = motion_map_cell(samples, dt, Model.paper(ZETA, EPS, 1.0, 1.0, 0.5),
                           transient=200.0, target_stderr=0.05, min_time=500.0,
                           max_periods=300, min_switches=10, motions=MOTIONS)
    got = ds.sel(inv_beta=2.0, delta=1.0)
    stay = stats.by_state(ds).sel(inv_beta=2.0, delta=1.0)
    np.testing.assert_array_equal(stay["residence_time"].values, cell["residence_time"])
    np.testing.assert_array_equal(got["residence_time"].values, cell["residence_time"][:-1])
    assert got["residence_time_none"].values == cell["residence_time"][-1] or np.isnan(
        cell["residence_time"][-1])
    np.testing.assert_array_equal(got["switch_rate"].values, cell["switch_rate"])
    np.testing.assert_array_equal(stay["n_stretches"].values, cell["n_stretches"])
    np.testing.assert_array_equal(got["probability"].values, cell["probability"])
    assert cell["n_stretches"].sum() > 0


def test_residence_of_a_map_cell_is_that_of_the_cell_alone(record):
    """The residence times and rates read the same labelled record as the probabilities:
    `simulate` to the cell's record end, classified and cut into stretches, gives them to the
    last bit (in forcing periods)."""
    inv_beta, delta = 2.0, 0.95
    cell = _map_cell(record, inv_beta, delta, transient=200.0, max_periods=1500,
                     target_stderr=0.02)
    res, step, offset, _ = _alone(record, inv_beta, delta, 200.0, cell["record_end"])
    z = stats.impact_intervals(step, offset, DT)
    labels = stats.classify_impact_intervals(stats.interval_ratio(z, 1.0 / inv_beta),
                                             motions=MOTIONS)
    edges, states = stats.label_pieces(step * DT + offset, labels, 200.0, cell["record_end"],
                                       len(MOTIONS))
    r = stats.residence_statistics(edges, states, len(MOTIONS) + 1)
    period = 2 * np.pi * inv_beta
    np.testing.assert_array_equal(cell["residence_time"], r.mean / period)
    np.testing.assert_array_equal(cell["residence_time_stderr"], r.stderr / period)
    np.testing.assert_array_equal(cell["switch_rate"], r.rate * period)
    np.testing.assert_array_equal(cell["switch_count"], r.count)
    assert r.n_stretches.sum() >= 20
