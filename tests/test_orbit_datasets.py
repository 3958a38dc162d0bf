"""The boundary, basins and Lyapunov datasets: built from the numerics' results as
docs/datasets.md says, joined from tiles in any order, written and read back unchanged."""
from dataclasses import dataclass

import numpy as np
import pytest

from vibroimpact.pipeline import datasets, io


@dataclass
class _Curve:
    kind: str
    inv_beta: np.ndarray
    delta: np.ndarray


@dataclass
class _Point:
    inv_beta: float
    delta: float
    kinds: tuple


class _Curves(list):
    def __init__(self, curves, points):
        super().__init__(curves)
        self.codimension_two = points


def test_boundaries_dataset_keeps_every_curve_in_order(tmp_path):
    t = np.linspace(0.0, 1.0, 7)
    by_type = {
        (1, 1): _Curves([_Curve("fold", 0.5 + t, 1.0 - t), _Curve("grazing", 1.5 + t, -t)],
                        [_Point(1.5, 0.0, ("fold", "grazing"))]),
        (2, 1): _Curves([_Curve("period_doubling", t[:3], t[:3] ** 2)], []),
        (1, 2): _Curves([], []),
    }
    ds = datasets.boundaries_dataset(by_type, dict(zeta=0.05, eps=0.5))
    path = tmp_path / "b.nc"
    io.write_dataset(ds, path)
    back = io.load_dataset(path)
    assert list(back["kind"].values) == ["fold", "grazing", "period_doubling"]
    assert list(back["type"].values) == ["1/1", "1/1", "2/1"]
    assert back.sizes["point"] == 17
    np.testing.assert_array_equal(back["inv_beta"].values[back["curve"].values == 1], 1.5 + t)
    np.testing.assert_array_equal(back["delta"].values[back["curve"].values == 2], t[:3] ** 2)
    assert list(back["codim2_kinds"].values) == ["fold+grazing"]
    assert list(back["codim2_type"].values) == ["1/1"]
    assert back.attrs["zeta"] == 0.05


def _fake_attractor_result(rows, deltas, n_starts, rng):
    types = ["1/1", "2/1"]
    nb, nd = rows.size, deltas.size
    motion = rng.integers(0, 3, size=(n_starts, nb, nd))
    count = np.stack([(motion == k).sum(axis=0) for k in range(3)])
    classes = rng.integers(0, 6, size=(n_starts, nb, nd)).astype(np.int8)
    class_count = np.stack([(classes == k).sum(axis=0) for k in range(6)])
    lyap = rng.normal(size=(n_starts, nb, nd))
    return dict(
        inv_beta=rows, delta=deltas, motions=types + ["other"], count=count,
        fraction=count / n_starts, fraction_lo=count / n_starts / 2,
        fraction_hi=(1 + count / n_starts) / 2,
        n_stable=rng.integers(0, 2, size=(2, nb, nd)),
        stick_count=rng.integers(0, 2, size=(2, nb, nd)),
        class_count=class_count, cell_class=np.argmax(class_count, axis=0).astype(np.int8),
        lyapunov=lyap.max(axis=0), lyapunov_start=lyap, class_start=classes,
        lyapunov_class=np.take_along_axis(classes, lyap.argmax(axis=0)[None], axis=0)[0],
        lyapunov_second_start=lyap - 1.0,
        lyapunov_stderr=np.full((nb, nd), np.nan), impact_rate=rng.random((nb, nd)),
        settle_time=rng.random((n_starts, nb, nd)), motion_start=motion)


@pytest.mark.parametrize("order", [(0, 1, 2), (2, 0, 1)])
def test_attractor_tiles_join_into_the_basins_and_lyapunov_datasets(tmp_path, order):
    rng = np.random.default_rng(5)
    rows = np.array([0.4, 0.6, 0.8, 1.0, 1.2])
    deltas = np.array([-0.5, 0.0, 0.5, 1.0])
    attrs = dict(zeta=0.05, eps=0.5, n_starts=8)
    whole = _fake_attractor_result(rows, deltas, 8, rng)
    tiles = []
    for k in range(3):
        part = {key: (value[..., k::3, :] if isinstance(value, np.ndarray) and value.ndim >= 2
                      else value) for key, value in whole.items()}
        part["inv_beta"] = rows[k::3]
        path = tmp_path / f"{k}.nc"
        io.write_dataset(datasets.attractor_tile_dataset(part, attrs), path)
        tiles.append(io.load_dataset(path))
    joined = datasets.concat_attractor_tiles([tiles[k] for k in order])
    basins = datasets.basins_dataset(joined)
    lyap = datasets.lyapunov_dataset(joined)
    np.testing.assert_array_equal(basins["inv_beta"].values, rows)
    assert list(basins["motion"].values) == ["1/1", "2/1", "other"]
    np.testing.assert_array_equal(basins["fraction"].values, whole["fraction"])
    np.testing.assert_array_equal(basins["n_stable"].values[:2], whole["n_stable"])
    assert (basins["n_stable"].values[2] == 0).all()
    np.testing.assert_array_equal(basins["stick_fraction"].values[:2],
                                  whole["stick_count"] / 8)
    assert np.isnan(basins["stick_fraction"].values[2]).all()
    np.testing.assert_allclose(basins["class_fraction"].sum("class").values, 1.0)
    np.testing.assert_array_equal(lyap["lyapunov"].values, whole["lyapunov"])
    np.testing.assert_array_equal(lyap["cell_class"].values, whole["cell_class"])
    np.testing.assert_array_equal(lyap["class_start"].values, whole["class_start"])
    np.testing.assert_array_equal(lyap["lyapunov_class"].values, whole["lyapunov_class"])
    for name in ("cell_class", "lyapunov_class", "class_start"):
        assert lyap[name].attrs["flag_meanings"].split() == list(datasets.ATTRACTOR_CLASSES)
    for ds in (basins, lyap):
        for name in ds.data_vars:
            assert "long_name" in ds[name].attrs, name
        path = tmp_path / "out.nc"
        io.write_dataset(ds, path)
        io.load_dataset(path)


def test_orbit_map_result_round_trips_the_map():
    from vibroimpact.orbits import orbit_map

    result = orbit_map([0.8, 1.0], [0.0, 0.5, 1.0], types=[(1, 1), (2, 1)])
    ds = datasets.orbit_map_dataset(result, dict(zeta=0.05, eps=0.5))
    back = datasets.orbit_map_result(ds)
    for key in ("exists", "n_solutions", "n_stable", "reason", "inv_beta", "delta", "types"):
        np.testing.assert_array_equal(back[key], result[key])
    np.testing.assert_array_equal(back["lam"], result["lam"])


def test_no_curves_are_traced_at_eps_zero_and_fig16_keeps_the_cell_edges(tmp_path):
    """eps = 0: every impact ends at rest on the wall, no boundary condition is regular; the
    boundaries job says so in its dataset, and Fig. 16 draws the cells' edges as without it."""
    from vibroimpact import plotting
    from vibroimpact.orbits import orbit_map
    from vibroimpact.pipeline import tasks

    entry = dict(zeta=0.05, eps=0.0, inv_beta=[0.8, 1.0, 1.2], delta=[0.0, 0.5, 1.0, 1.5],
                 types=[[1, 1]])
    result = orbit_map(entry["inv_beta"], entry["delta"], types=[(1, 1)], zeta=0.05, eps=0.0)
    orbits_path = tmp_path / "o.nc"
    io.write_dataset(datasets.orbit_map_dataset(result, dict(zeta=0.05, eps=0.0)), orbits_path)
    out = tmp_path / "b.nc"
    tasks.boundaries(entry, orbits_path, out)
    ds = io.load_dataset(out)
    assert ds.attrs["traced"] == 0 and "eps = 0" in ds.attrs["not_traced"]
    assert ds.sizes["curve"] == 0 and ds.sizes["point"] == 0
    orbits = io.load_dataset(orbits_path)
    with plotting.style():
        without = plotting.fig16(orbits)
        given = plotting.fig16(orbits, ds)
    assert ([a.get_gid() for a in without.axes[1].collections]
            == [a.get_gid() for a in given.axes[1].collections])
    assert "stable-edge" in [a.get_gid() for a in given.axes[1].collections]


def test_the_class_names_are_one_list():
    """The kernels' class codes, the datasets' flag meanings and the figure's colours name
    the same classes in the same order (a reordering would remap every cell_class)."""
    from vibroimpact.attractors import CLASSES
    from vibroimpact.attractors import kernels as ak
    from vibroimpact.plotting import attractors as drawn

    assert tuple(CLASSES) == datasets.ATTRACTOR_CLASSES == tuple(drawn.CLASSES)
    assert [ak.LISTED, ak.PERIODIC_OTHER, ak.STICKING, ak.CHAOTIC, ak.UNDECIDED,
            ak.WALL_FREE] == list(range(len(CLASSES)))
