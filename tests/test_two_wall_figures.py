"""The density figures of a two-wall study (Figs. 7, 8, 13, 14) held to the one-wall rules.

A two-wall events dataset is made by the workflow's own tasks (a clearance of 2 under
sin(tau/1.1) + r(tau), as config/examples/clearance.yaml, on a short record). Each wall's
panel of Figs. 7 and 8 is compared, artist for artist, with the one-wall figure drawn from a
one-wall dataset that holds that wall's statistics under the one-wall names: the same curves,
sparse-bin runs and bands (issue 43: the two-wall panels had no merging and their own band).
Fig. 13 marks the study's own motions.
"""
import numpy as np
import pytest
import xarray as xr

from vibroimpact import plotting
from vibroimpact.pipeline import tasks
from vibroimpact.plotting._common import MIN_BIN_COUNT, bin_counts
from vibroimpact.plotting.harmonic import ratio_marks
from vibroimpact.plotting.walls import wall_view

NOISE = dict(kind="band_limited", rms=0.29, dt=0.1, beta_c=4.0, n_samples=60_001,
             seed=20261127, nperseg=1024)
BINS = dict(v_after=dict(max=3.0, n=60), interval=dict(max=30.0, n=120),
            ratio=dict(max=4.0, n=80))
#: The clearance example's motions (m_upper, m_lower, n).
MOTIONS = [[1, 1, 1], [1, 0, 1], [0, 1, 1], [1, 1, 2]]
#: Stops at +-1 (delta = 1) and shifted up (delta = 2: the upper stop is reached rarely, so
#: its densities are sparse and the merging rule has runs to merge).
CLEARANCE = dict(noise="clearance_input", zeta=0.05, eps=0.5, gap=2.0, eps_lower=0.5,
                 amplitude=1.0, inv_beta=[1.1], delta=[1.0, 2.0], transient=100.0,
                 tile_size=2, n_batches=20, motion_window=0.1, motions=MOTIONS, bins=BINS)


@pytest.fixture(scope="module")
def events(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("two_wall_figures")
    noise_path = tmp / "noise.nc"
    tasks.make_noise(NOISE, noise_path)
    tile = tmp / "tile.nc"
    tasks.events_tile("clearance", CLEARANCE, 0, noise_path, tile)
    path = tmp / "events.nc"
    tasks.aggregate("clearance", CLEARANCE, "events", [tile], path, noise_path=noise_path)
    return xr.load_dataset(path)


def _one_wall(events, wall):
    """A one-wall events dataset holding `wall`'s collision statistics under the one-wall
    names (what a study with that wall alone would store, for the densities drawn here)."""
    out = events.drop_vars([v for v in events.variables if str(v).startswith("wall_")]
                           + ["wall"])
    for q in ("v_after", "interval"):
        for name in (f"{q}_density", f"{q}_density_stderr", f"{q}_beyond"):
            out[name] = events[f"wall_{name}"].sel(wall=wall, drop=True)
    out["n_collisions"] = events["wall_n_collisions"].sel(wall=wall, drop=True)
    for key in ("gap", "eps_lower", "n_walls", "walls"):
        out.attrs.pop(key, None)
    return out


def _drawn(ax):
    """What a density panel draws, as arrays: each curve's points, each band's outline, each
    sparse run's bar and interval, in drawing order."""
    curves = [(np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float))
              for ln in ax.get_lines() if ln.get_transform() is ln.axes.transData]
    bands = [[p.vertices for p in c.get_paths()] for c in ax.collections
             if c.get_gid() == "band"]
    runs = [c.get_segments() for c in ax.collections if c.get_gid() == "sparse_run"]
    return curves, bands, runs


def _assert_same_drawing(two_wall_ax, one_wall_ax):
    (c2, b2, r2), (c1, b1, r1) = _drawn(two_wall_ax), _drawn(one_wall_ax)
    assert len(c2) == len(c1) and len(b2) == len(b1) and len(r2) == len(r1)
    for (x2, y2), (x1, y1) in zip(c2, c1):
        np.testing.assert_array_equal(x2, x1)
        np.testing.assert_array_equal(y2, y1)
    for p2, p1 in zip(b2, b1):
        assert len(p2) == len(p1)
        for v2, v1 in zip(p2, p1):
            np.testing.assert_array_equal(v2, v1)
    for s2, s1 in zip(r2, r1):
        assert len(s2) == len(s1)
        for v2, v1 in zip(s2, s1):
            np.testing.assert_array_equal(v2, v1)


@pytest.mark.parametrize("figure", ["fig07", "fig08"])
def test_each_wall_is_drawn_as_the_one_wall_figure_draws_the_same_data(events, figure):
    """Issue 43: the two-wall density panels drew every bin (single-bin spikes of a few
    collisions) and a band of +-2 s.e. clipped at 1e-3 of the value, unlabelled."""
    two = getattr(plotting, figure)(events)
    kwargs = dict(envelope="never") if figure == "fig07" else {}
    for ax, wall in zip(two.axes, ("upper", "lower")):
        one = getattr(plotting, figure)(_one_wall(events, wall), **kwargs)
        _assert_same_drawing(ax, one.axes[0])       # the one-wall log panel: every bin
        band, rule = one.legends[0].get_title().get_text().split("\n")[:2]
        title = two.legends[0].get_title().get_text()
        assert band in title and "Garwood" in band and rule in title
    # the merging had runs to merge here (the upper wall at delta = 2 is reached rarely)
    assert any(c.get_gid() == "sparse_run" for ax in two.axes for c in ax.collections)


@pytest.mark.parametrize("figure, quantity", [("fig07", "v_after"), ("fig08", "interval")])
def test_no_drawn_bin_of_a_wall_holds_fewer_values_than_the_rule(events, figure, quantity):
    fig = getattr(plotting, figure)(events)
    ds = events.isel(inv_beta=0)
    width = float(np.diff(ds[quantity])[0])
    for ax, wall in zip(fig.axes, ("upper", "lower")):
        view = wall_view(ds, quantity, wall)
        curves = _drawn(ax)[0]
        assert len(curves) == ds.sizes["delta"]
        for k, (_, y) in zip(np.argsort(-ds["delta"].values), curves):
            n = bin_counts(view.isel(delta=k), f"{quantity}_density")[2]
            shown = np.isfinite(y)
            # a point on a curve is one bin with at least MIN_BIN_COUNT values (to round-off)
            assert np.all(y[shown] * n * width > MIN_BIN_COUNT - 1e-6), (wall, k)


def test_the_legend_names_each_plays_collisions_at_each_wall(events):
    fig = plotting.fig08(events)
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    at = events.isel(inv_beta=0)
    for text, k in zip(texts, np.argsort(-at["delta"].values)):
        n = at["wall_n_collisions"].isel(delta=k)
        assert f"upper {int(n.sel(wall='upper')):,}" in text
        assert f"lower {int(n.sel(wall='lower')):,}" in text


def test_fig13_of_a_clearance_names_its_own_motions(events):
    """Issue 43: the peak at z_j/z = 1/2 of the symmetric motion was labelled "(2/1): pairs",
    where the study's own Fig. 15 calls that motion (1,1)/1."""
    fig = plotting.fig13(events, inv_beta=1.1)
    for ax in fig.axes:
        texts = {(t.get_position()[0], t.get_text()) for t in ax.texts}
        assert not any("(2/1)" in text or "(1/1)" in text for _, text in texts)
        (half,) = [text for x, text in texts if x == 0.5]
        assert "(1,1)/1: pairs" in half
        at_one = sorted(text for x, text in texts if x == 1.0)
        assert at_one[0] == " (1,0)/1, (0,1)/1" and "(1,1)/2: pairs" in at_one[1]
        assert "= 2z" in at_one[1]
        lines = sorted((float(ln.get_xdata()[0]), ln.get_linestyle()) for ln in ax.get_lines()
                       if ln.get_transform() is not ln.axes.transData)
        assert lines == [(0.5, "-."), (1.0, ":")]


def test_ratio_marks_of_the_paper_motions_are_fig13s_marks():
    """The paper's (1/1), (2/1), (1/2) give the one-wall Fig. 13 its marks: dash-dot at 1/2
    for the (2/1) pairs, dotted at 1 and 2."""
    assert ratio_marks(["1/1", "2/1", "1/2"]) == [
        (0.5, "-.", [(r"$\leftarrow$ (2/1): pairs $z_j + z_{j+1} = z$ $\rightarrow$",
                      "center")]),
        (1.0, ":", [(" (1/1)", "left")]),
        (2.0, ":", [(" (1/2)", "left")])]
    (third,) = ratio_marks(["3/1"])
    assert third[0] == pytest.approx(1 / 3) and r"z_{j+2} = z" in third[2][0][0]


def test_a_motion_name_fig13_cannot_read_is_refused_naming_it():
    with pytest.raises(ValueError, match=r"'1-1'"):
        ratio_marks(["1-1"])
