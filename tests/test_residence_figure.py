"""The `residence` map (`plotting.maps.residence`): not in the figure table yet."""
import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import LogNorm
from matplotlib.path import Path

from vibroimpact.plotting.maps import residence

STATES = ["1/1", "2/1", "1/2", "none"]
ATTRS = dict(zeta=0.05, eps=0.5, amplitude=1.0, noise_kind="band_limited", noise_rms=0.29,
             noise_beta_c=4.0, dt=0.1, motion_window=0.1, transient=200.0, target_stderr=0.03,
             min_time=500.0, max_periods=500, min_switches=10)


PLANE = ("inv_beta", "delta")


def _stored(name, values):
    """``values`` over (state, inv_beta, delta) as the map stores them: the motions over
    `motion`, "none" under ``<name>_none``."""
    return {name: (("motion", *PLANE), values[:-1]), f"{name}_none": (PLANE, values[-1])}


def _map(t, n):
    shape = t.shape[1:]
    return xr.Dataset(
        dict(**_stored("residence_time", t), **_stored("n_stretches", n),
             reached=(PLANE, np.ones(shape, np.int8)), simulated_time=(PLANE, np.full(shape, 1e3)),
             n_collisions=(PLANE, np.full(shape, 100))),
        coords=dict(motion=STATES[:-1], inv_beta=[0.5, 1.0, 1.5], delta=[0.0, 1.0]),
        attrs=ATTRS)


def test_one_log_scale_panel_per_state_with_few_stretches_hatched():
    rng = np.random.default_rng(0)
    t = 10 ** rng.uniform(-0.5, 1.5, (4, 3, 2))
    n = rng.integers(0, 20, (4, 3, 2))
    t[n == 0] = np.nan
    fig = residence(_map(t, n))
    FigureCanvasAgg(fig).draw()
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == ["(1/1)", "(2/1)", "(1/2)", "none"]
    meshes = [c for ax in panels for c in ax.collections if c.get_gid() == "residence"]
    assert len(meshes) == 4
    norm = meshes[0].norm
    assert isinstance(norm, LogNorm) and all(m.norm is norm for m in meshes)
    assert norm.vmin == np.nanmin(t) and norm.vmax == np.nanmax(t)
    for ax, few in zip(panels, n < 5):
        hatched = [c for c in ax.patches if c.get_gid() == "few_stretches"]
        assert len(hatched) == int(few.any())
        if few.any():       # one compound path, a closed rectangle per cell
            path = hatched[0].get_path()
            assert (path.codes == Path.CLOSEPOLY).sum() == few.sum()
    # a cell without a complete stretch is left blank (masked)
    assert meshes[0].get_array().mask.sum() == (n[0] == 0).sum()


def test_a_map_without_any_complete_stretch_says_so():
    fig = residence(_map(np.full((4, 3, 2), np.nan), np.zeros((4, 3, 2), int)))
    FigureCanvasAgg(fig).draw()
    notes = [t.get_text() for ax in fig.axes for t in ax.texts if t.get_gid() == "note"]
    assert notes == ["no complete stretch of any motion"]


def test_a_state_seen_only_in_cut_stretches_is_marked_not_left_blank():
    """A motion held through the whole record has no complete stretch: no mean, but a pale
    cell, so that it does not read as a motion that never occurs."""
    t = np.full((4, 3, 2), 3.0)
    n = np.full((4, 3, 2), 20)
    t[0, 1, 1], n[0, 1, 1] = np.nan, 0          # held throughout: one stretch, cut twice
    t[1, 2, 0], n[1, 2, 0] = np.nan, 0          # never occurs
    ds = _map(t, n)
    censored = np.zeros((4, 3, 2), int)
    censored[0, 1, 1] = 1
    ds = ds.assign(_stored("n_censored", censored))
    fig = residence(ds)
    FigureCanvasAgg(fig).draw()
    panels = [ax for ax in fig.axes if ax.get_title()]
    marks = [[c for c in ax.patches if c.get_gid() == "only_cut"] for ax in panels]
    assert [len(m) for m in marks] == [1, 0, 0, 0]
    cell = marks[0][0].get_path()
    assert (cell.codes == Path.CLOSEPOLY).sum() == 1
    assert cell.get_extents().bounds == pytest.approx((0.75, 0.5, 0.5, 1.0))
