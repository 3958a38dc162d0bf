"""What a reader sees on Figs. 15, 15 vs 16 and 16: whole cells, one cliff line, named regions.

The datasets are small and laid out by hand so that each feature sits where the test knows it:
a probability map with a cliff (0 to 100 % within one cell), a smooth hill and flagged cells;
an orbit map with a stable band, a stable domain one cell wide, and regions of every reason.
"""
import matplotlib.colors
import numpy as np
import pytest
import xarray as xr
from matplotlib.contour import ContourSet
from matplotlib.text import Text

from vibroimpact import plotting
from vibroimpact.plotting.maps import (CLIFF_LEVEL, FEW_SWITCHES_STYLE, MAP_TEXT_SIZE,
                                       TYPE_COLORS, cell_edges)
from vibroimpact.plotting.orbits import REASONS

INV_BETA = np.round(np.arange(0.2, 3.001, 0.1), 10)
DELTA = np.round(np.arange(-1.5, 3.001, 0.1), 10)
#: Flagged cells (index along inv_beta, along delta): a pair side by side and a single one.
FEW = [(10, 20), (11, 20), (20, 35)]
#: The (1/1) cliff: probability 0 left of 1/beta = CLIFF_A + CLIFF_B delta, 100 right of it.
CLIFF_A, CLIFF_B = 0.8, 0.1


def _motion_map():
    ib, d = np.meshgrid(INV_BETA, DELTA, indexing="ij")
    cliff = np.where(ib > CLIFF_A + CLIFF_B * d, 1.0, 0.0) * (d > 0.5)
    hill = np.exp(-((ib - 2.0) ** 2 + (d + 0.5) ** 2) / 0.5)
    p = np.stack([np.maximum(cliff, 0.9 * hill * (d <= 0.5)), 0.8 * hill, np.zeros_like(ib)])
    few = np.zeros(ib.shape, "int8")
    for i, j in FEW:
        few[i, j] = 1
    scalars = dict(few_switches=few, reached=np.ones(ib.shape, "int8"),
                   simulated_time=np.full(ib.shape, 5000.0))
    return xr.Dataset({"probability": (("motion", "inv_beta", "delta"), p),
                       **{k: (("inv_beta", "delta"), v) for k, v in scalars.items()}},
                      coords=dict(motion=["1/1", "2/1", "1/2"], inv_beta=INV_BETA, delta=DELTA),
                      attrs=dict(zeta=0.05, eps=0.5, amplitude=1.0, noise_rms=0.29,
                                 noise_kind="band_limited", noise_beta_c=4.0,
                                 motion_window=0.1, target_stderr=0.01, max_periods=8000,
                                 min_switches=10))


#: Orbit map: (row slice along inv_beta, column slice along delta) of each feature.
BAND = (slice(5, 25), slice(20, 26))         # stable, 20 x 6 cells
THIN = (slice(5, 25), slice(35, 36))         # stable, one cell wide
UNSTABLE = (slice(5, 25), slice(26, 29))     # only unstable solutions, above the band
WALL = (slice(0, 29), slice(0, 15))          # solutions crossing the wall, the lower third


def _orbits():
    shape = (INV_BETA.size, DELTA.size)
    reason = np.ones(shape, "int8")
    reason[WALL] = 2
    reason[UNSTABLE] = 3
    reason[BAND] = 0
    reason[THIN] = 0
    stable = reason == 0
    ib, d = np.meshgrid(INV_BETA, DELTA, indexing="ij")
    S = np.where(stable, 5.0 + 35.0 * np.clip((d - 0.5) / 0.6, 0, 1) * ib / 3.0, np.nan)
    lam = np.where(stable, 1.0 - S / 100.0, np.where(reason >= 2, 1.2, np.nan))
    one = {"n_stable": stable.astype(int), "S": S, "lam": lam, "reason": reason}
    return xr.Dataset({k: (("type", "inv_beta", "delta"), np.stack([v, v]))
                       for k, v in one.items()},
                      coords=dict(type=["1/1", "2/1"], inv_beta=INV_BETA, delta=DELTA),
                      attrs=dict(zeta=0.05, eps=0.5))


@pytest.fixture(scope="module")
def figures():
    with plotting.style():
        return {"fig15": plotting.fig15(_motion_map()),
                "fig15_vs_fig16": plotting.fig15_vs_fig16(_motion_map(), _orbits()),
                "fig16": plotting.fig16(_orbits())}


def _rect(path):
    (x0, y0), (x1, y1) = path.vertices.min(axis=0), path.vertices.max(axis=0)
    return np.round([x0, y0, x1, y1], 9)


@pytest.mark.parametrize("name", ["fig15", "fig15_vs_fig16"])
def test_few_switches_marks_whole_cells_in_one_style(figures, name):
    fig = figures[name]
    xe, ye = cell_edges(INV_BETA), cell_edges(DELTA)
    cells = sorted(tuple(np.round([xe[i], ye[j], xe[i + 1], ye[j + 1]], 9)) for i, j in FEW)
    panels = [ax for ax in fig.axes if ax.get_title()]
    for ax in panels:
        (marked,) = [c for c in ax.collections if c.get_gid() == "few_switches"]
        assert sorted(tuple(_rect(p)) for p in marked.get_paths()) == cells
        assert marked.get_hatch() == FEW_SWITCHES_STYLE["hatch"]
    (legend,) = fig.legends
    hatches = [h.get_hatch() for h in legend.get_patches() if h.get_hatch()]
    assert hatches == [FEW_SWITCHES_STYLE["hatch"]], "one hatching style, in the legend too"


def _contour_sets(ax):
    return [c for c in ax.collections if isinstance(c, ContourSet) and not c.filled]


def test_a_cliff_is_one_line_without_labels(figures):
    ax = figures["fig15"].axes[0]
    assert ax.get_title() == "(1/1)"
    cliff = [c for c in ax.collections if c.get_gid() == "cliff"]
    vertices = np.concatenate([s for c in cliff for s in c.get_segments()])
    on_cliff = vertices[:, 1] > 0.6
    # one line, within one cell of the step it stands for
    cell = INV_BETA[1] - INV_BETA[0]
    v = vertices[on_cliff]
    assert np.all(np.abs(v[:, 0] - (CLIFF_A + CLIFF_B * v[:, 1])) < cell)
    # no other level runs along the cliff, and no label sits on it
    (lines,) = _contour_sets(ax)
    for level, path in zip(lines.levels, lines.get_paths()):
        w = path.vertices[path.vertices[:, 1] > 0.7]
        step = np.abs(w[:, 0] - (CLIFF_A + CLIFF_B * w[:, 1])) < cell
        assert not step.any(), f"the {level:g} % line runs along the cliff"
    for text in ax.texts:
        x, y = text.get_position()
        assert y < 0.6 or abs(x - (CLIFF_A + CLIFF_B * y)) > cell, text.get_text()
    assert any(f"only the {CLIFF_LEVEL:g} % line" in t.get_text()
               for t in figures["fig15"].legends[0].get_texts())


@pytest.mark.parametrize("name", ["fig15", "fig15_vs_fig16", "fig16"])
def test_contour_labels_readable(figures, name):
    labels = [t for ax in figures[name].axes for c in _contour_sets(ax)
              for t in getattr(c, "labelTexts", [])]
    assert labels, "some contour is labelled"
    assert min(t.get_fontsize() for t in labels) >= 7.0
    assert MAP_TEXT_SIZE >= 7.0


def test_fig16_names_every_reason_in_its_region(figures):
    fig = figures["fig16"]
    x, y = INV_BETA, DELTA
    reason = _orbits()["reason"].values[0]
    for ax in fig.axes[1:3]:
        named = {}
        for text in ax.texts:
            if (text.get_gid() or "").startswith("reason-"):
                named.setdefault(int(text.get_gid().split("-")[1]), []).append(text)
        assert set(named) == {1, 2, 3}
        for code, texts in named.items():
            assert all(t.get_text() == REASONS[code][1] or "\n" in t.get_text()
                       for t in texts)
            for t in texts:
                # the word stands in its region, or its leader ends there
                xy = t.xy if hasattr(t, "xy") else t.get_position()
                i, j = np.abs(x - xy[0]).argmin(), np.abs(y - xy[1]).argmin()
                assert reason[i, j] == code, (code, xy)
    legend = " ".join(t.get_text() for t in fig.legends[0].get_texts())
    legend += fig.legends[0].get_title().get_text()
    assert "D, V, X" in legend and "U" in legend and "(22)" in legend and "(13)" in legend


def test_fig16_thin_domain_shows_its_colour(figures):
    ax = figures["fig16"].axes[1]
    ye = cell_edges(DELTA)
    row = THIN[1].start
    edges = [c for c in ax.collections if c.get_gid() == "stable-edge"]
    assert edges
    for c in edges:
        for (_x0, y0), (_x1, y1) in c.get_segments():
            assert not (min(y0, y1) >= ye[row] - 1e-9 and max(y0, y1) <= ye[row + 1] + 1e-9), \
                "an edge line covers the one-cell-wide domain"
    meshes = [c for c in ax.collections if c.get_cmap().name == "viridis_r"]
    (mesh,) = meshes
    S = np.ma.masked_invalid(mesh.get_array()).reshape(DELTA.size, INV_BETA.size)
    assert np.all(~S.mask[row, THIN[0]])


@pytest.mark.parametrize("name", ["fig15", "fig15_vs_fig16", "fig16"])
def test_no_config_keys_on_the_figure(figures, name):
    fig = figures[name]
    texts = [t.get_text() for t in fig.findobj(Text)]
    texts += [ax.get_xlabel() for ax in fig.axes] + [ax.get_ylabel() for ax in fig.axes]
    for key in ("inv_beta", "min_switches", "motion_window", "n_stable", "few_switches",
                "target_stderr", "1/beta"):
        assert not any(key in t for t in texts), key
    assert any(r"$1/\beta" in ax.get_xlabel() for ax in fig.axes)
    assert any(r"$\delta$" in ax.get_ylabel() for ax in fig.axes)


def test_type_colours_tell_the_first_five_motions_apart():
    """Issue 33: (2/1) in vermillion and (3/1) in orange read as one hue in Fig. 16. Every
    two of the first five differ by 30 degrees of hue or 0.4 of HSV value."""
    hsv = matplotlib.colors.rgb_to_hsv([matplotlib.colors.to_rgb(c) for c in TYPE_COLORS[:5]])
    for a in range(5):
        for b in range(a):
            hue = abs(hsv[a, 0] - hsv[b, 0]) * 360.0
            assert min(hue, 360.0 - hue) >= 30.0 or abs(hsv[a, 2] - hsv[b, 2]) >= 0.4, (a, b)


def test_fig15_two_panels_a_row_its_colour_bar_beside_them(figures):
    """Issue 33: four panels in a row left the labels tiny at a page's width, the colour bar
    far from the panels, and the record's length without a unit."""
    fig = figures["fig15"]
    fig.canvas.draw()
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.get_title()]
    (bar,) = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    assert fig.get_figwidth() <= 10.0 and len({ax.get_position().x0 for ax in panels}) <= 2
    right = max(ax.get_position().x1 for ax in panels)
    assert 0.0 < bar.get_position().x0 - right < 0.06       # figure fraction
    assert "time units" in fig.get_suptitle()

