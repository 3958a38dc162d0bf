"""Fig. 16 with its exact boundary curves, and the basin and Lyapunov maps.

The datasets are small and synthetic (`attractor_data`): an orbit map laid out by hand (a
stable (1/1) band bounded by a wall-crossing region below, an unstable strip above and no
solution elsewhere, plus a small (1/2) domain), the boundary curves made from its cells,
basins and Lyapunov maps drawn from it on a coarse grid.
"""
import subprocess
import types
import warnings
from pathlib import Path

import matplotlib
import numpy as np
import pytest
import xarray as xr
from matplotlib.lines import Line2D
from matplotlib.text import Text

import attractor_data
from vibroimpact import plotting
from vibroimpact.plotting.attractors import CLASSES, NAN_COLOR, STICK_COLOR
from vibroimpact.plotting.orbits import BOUNDARY_KINDS, _kind_style

CLASSES_LIST = list(CLASSES)

ROOT = Path(__file__).resolve().parents[1]
#: The last commit before fig16 took `boundaries`: fig16(orbits) must draw what it drew.
BEFORE_BOUNDARIES = "b1ccd6b"
INV_BETA = np.round(np.arange(0.2, 3.001, 0.1), 10)
DELTA = np.round(np.arange(-1.5, 3.001, 0.1), 10)


def _orbits():
    shape = (INV_BETA.size, DELTA.size)
    one = np.ones(shape, "int8")
    one[:, :20] = 2                   # crosses the wall, below
    one[5:25, 26:29] = 3              # unstable strip above the band
    one[5:25, 20:26] = 0              # the stable band
    two = np.ones(shape, "int8")
    two[:, :15] = 2
    two[12:18, 30:36] = 0
    reason = np.stack([one, two])
    stable = reason == 0
    d = DELTA[None, None, :] + 0.0 * INV_BETA[None, :, None]
    S = np.where(stable, 10.0 + 30.0 * np.clip(d - 0.5, 0.0, 1.0), np.nan)
    lam = np.where(stable, 1.0 - S / 100.0, np.where(reason >= 2, 1.2, np.nan))
    dims = ("type", "inv_beta", "delta")
    return xr.Dataset({"n_stable": (dims, stable.astype(int)), "S": (dims, S),
                       "lam": (dims, lam), "reason": (dims, reason)},
                      coords=dict(type=["1/1", "1/2"], inv_beta=INV_BETA, delta=DELTA),
                      attrs=dict(zeta=0.05, eps=0.5))


@pytest.fixture(scope="module")
def data():
    orbits = _orbits()
    boundaries = attractor_data.boundaries(orbits)
    basins = attractor_data.basins(orbits, *attractor_data.grid(0.1))
    lyap = attractor_data.lyapunov(basins)
    return dict(orbits=orbits, boundaries=boundaries, basins=basins, lyapunov=lyap)


@pytest.fixture(scope="module")
def fig16_curves(data):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return plotting.fig16(data["orbits"], data["boundaries"])


def _panel(fig, title):
    (ax,) = [ax for ax in fig.axes if ax.get_title() == title]
    return ax


def _gid(ax, gid):
    return [a for a in ax.get_children() if a.get_gid() == gid]


def test_the_synthetic_boundaries_have_every_kind_and_codim2_points(data):
    b = data["boundaries"]
    assert set(b["kind"].values) == set(BOUNDARY_KINDS)
    assert b.sizes["codim2"] >= 2
    assert set(b["kind"].values) <= set(BOUNDARY_KINDS)


def test_fig16_draws_one_line_per_curve_styled_by_kind(data, fig16_curves):
    b = data["boundaries"]
    curve = b["curve"].values
    colors = dict(zip(data["orbits"]["type"].values,
                      [line.get_color() for line in
                       fig16_curves.axes[0].get_legend().get_lines()]))
    for c, (kind, name) in enumerate(zip(b["kind"].values, b["type"].values)):
        points = np.column_stack([b["inv_beta"].values, b["delta"].values])[curve == c]
        ax = _panel(fig16_curves, f"({name})")
        (line,) = _gid(ax, f"boundary-{c}")
        (over,) = _gid(fig16_curves.axes[0], f"overview-boundary-{c}")
        reference = Line2D([], [], **_kind_style(str(kind)))
        for drawn in (line, over):
            np.testing.assert_array_equal(drawn.get_xydata(), points)
            # the dashes (on (a) every other type's shifted by half a period: _overview_style)
            assert drawn._unscaled_dash_pattern[1] == reference._unscaled_dash_pattern[1], kind
        assert line._unscaled_dash_pattern == reference._unscaled_dash_pattern
        assert matplotlib.colors.same_color(line.get_color(), "k")
        assert matplotlib.colors.same_color(over.get_color(), colors[name])
    for ax in fig16_curves.axes:
        assert not _gid(ax, "stable-edge"), "no cell-edge line beside the curves"


def test_fig16_overview_shifts_every_other_types_dashes(data, fig16_curves):
    """Issue 33: the (2/1) and (3/1) grazing edges coincide below 1/beta = 1; in phase, the
    later dashes hid the earlier. Shifted by half a period, both colours show in turn."""
    types = [str(t) for t in data["orbits"]["type"].values]
    b = data["boundaries"]
    for c, (kind, name) in enumerate(zip(b["kind"].values, b["type"].values)):
        (over,) = _gid(fig16_curves.axes[0], f"overview-boundary-{c}")
        offset, dashes = over._unscaled_dash_pattern
        if dashes is None:
            continue                            # solid: nothing to shift
        expected = 0.5 * sum(dashes) if types.index(str(name)) % 2 else 0.0
        assert offset == pytest.approx(expected + _kind_style(str(kind))["ls"][0]), (kind, name)


def test_fig16_writes_no_region_word_over_a_codim2_marker(data, fig16_curves):
    """Issue 33: the "unstable" label covered the codimension-two markers of (1/2)."""
    fig16_curves.canvas.draw()
    renderer = fig16_curves.canvas.get_renderer()
    checked = 0
    for ax in fig16_curves.axes[1:]:
        marks = ax.transData.transform(np.vstack(
            [line.get_xydata() for line in _gid(ax, "codim2")] or [np.empty((0, 2))]))
        for text in ax.texts:
            if not str(text.get_gid()).startswith("reason-"):
                continue
            box = Text.get_window_extent(text, renderer)    # the word, not its leader
            checked += len(marks)
            assert not any(box.contains(*xy) for xy in marks), text.get_text()
    assert checked, "the fixture has words and markers on one panel"


def test_fig16_moves_a_region_word_off_a_codim2_marker(data, fig16_curves):
    """A marker put where a word was written pushes the word elsewhere."""
    word = next(t for ax in fig16_curves.axes[1:] for t in ax.texts
                if str(t.get_gid()).startswith("reason-"))
    name = word.axes.get_title().strip("()")
    x, y = word.get_position()
    b = data["boundaries"]
    extra = {"codim2_inv_beta": [x], "codim2_delta": [y], "codim2_type": [name],
             "codim2_kinds": ["fold+grazing"]}
    moved = b.drop_dims("codim2").assign(
        {k: ("codim2", np.concatenate([b[k].values, np.array(v, dtype=b[k].dtype)]))
         for k, v in extra.items()})
    fig = plotting.fig16(data["orbits"], moved)
    ax = _panel(fig, f"({name})")
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    mark = ax.transData.transform([[x, y]])[0]
    words = [t for t in ax.texts if t.get_gid() == word.get_gid()]
    # the word's own box (an Annotation's extent would include its leader)
    assert words and not any(Text.get_window_extent(t, renderer).contains(*mark) for t in words)


def test_fig16_marks_every_codim2_point_on_its_panel(data, fig16_curves):
    b = data["boundaries"]
    for name in data["orbits"]["type"].values:
        here = b["codim2_type"].values == name
        marks = _gid(_panel(fig16_curves, f"({name})"), "codim2")
        if not here.any():
            assert not marks
            continue
        (mark,) = marks
        np.testing.assert_array_equal(mark.get_xdata(), b["codim2_inv_beta"].values[here])
        np.testing.assert_array_equal(mark.get_ydata(), b["codim2_delta"].values[here])
    n = sum(len(m.get_xdata()) for m in _gid(fig16_curves.axes[0], "codim2"))
    assert n == b.sizes["codim2"]


def test_fig16_legend_names_each_kind_drawn_once(data, fig16_curves):
    (legend,) = fig16_curves.legends
    texts = [t.get_text() for t in legend.get_texts()]
    for kind, (_, words) in BOUNDARY_KINDS.items():
        assert sum(words in t for t in texts) == (kind in data["boundaries"]["kind"].values)
    assert sum("codimension two" in t for t in texts) == 1
    assert not any("3 cells thick" in t for t in texts)


def test_fig16_refuses_boundaries_of_another_system(data):
    with pytest.raises(ValueError, match="not the same system"):
        plotting.fig16(data["orbits"], data["boundaries"].assign_attrs(eps=0.6))
    bad = data["boundaries"].copy()
    bad["kind"] = bad["kind"].copy(data=np.where(bad["kind"].values == "fold", "hopf",
                                                 bad["kind"].values))
    with pytest.raises(ValueError, match="hopf"):
        plotting.fig16(data["orbits"], bad)


def test_fig16_with_no_curves_draws_none(data):
    empty = data["boundaries"].isel(point=slice(0, 0), curve=slice(0, 0),
                                    codim2=slice(0, 0))
    fig = plotting.fig16(data["orbits"], empty)
    assert not any((a.get_gid() or "").startswith(("boundary", "overview-boundary", "codim2",
                                                   "stable-edge"))
                   for ax in fig.axes for a in ax.get_children())


def _old_fig16():
    """fig16 as it was before `boundaries` (the module's source at `BEFORE_BOUNDARIES`)."""
    try:
        source = subprocess.run(
            ["git", "show", f"{BEFORE_BOUNDARIES}:src/vibroimpact/plotting/orbits.py"],
            cwd=ROOT, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip(f"no git history with {BEFORE_BOUNDARIES} here")
    module = types.ModuleType("orbits_before_boundaries")
    exec(compile(source, "orbits_before_boundaries.py", "exec"), module.__dict__)
    return module.fig16


def _pixels(fig):
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())


def test_fig16_without_boundaries_draws_what_it_drew(data):
    old = _old_fig16()
    now = plotting.fig16(data["orbits"])
    np.testing.assert_array_equal(_pixels(now), _pixels(old(data["orbits"])))
    assert not any((a.get_gid() or "").startswith(("boundary", "overview-boundary", "codim2"))
                   for ax in now.axes for a in ax.get_children())


# --------------------------------------------------------------------------------------------
# Basins
# --------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def basin_figure(data):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return plotting.basins(data["basins"], data["orbits"])


def test_basins_one_panel_per_motion(data, basin_figure):
    titles = [ax.get_title() for ax in basin_figure.axes if ax.get_visible() and ax.get_title()]
    motions = [m for m in data["basins"]["motion"].values if m != "other"]
    assert titles == [f"({m})" for m in motions] + ["other: none of these types"]


def test_basins_outline_the_wall_free_response_in_the_other_panel(data, basin_figure):
    from vibroimpact.plotting.attractors import WALL_FREE_SHARE, cell_outline

    ds = data["basins"]
    free = ds["class_fraction"].sel({"class": "wall_free"}).values >= WALL_FREE_SHARE
    assert free.any() and not free.all()
    (line,) = _gid(_panel(basin_figure, "other: none of these types"), "wall-free")
    expected = cell_outline(ds["inv_beta"].values, ds["delta"].values, free)
    assert len(line.get_segments()) == len(expected)
    for ax in basin_figure.axes:
        if ax.get_title() != "other: none of these types":
            assert not _gid(ax, "wall-free")
    labels = [t.get_text() for t in basin_figure.legends[0].get_texts()]
    assert sum("wall-free response" in t for t in labels) == 1
    assert "wall-free response" in basin_figure.legends[0].get_title().get_text()


def test_basins_leave_cells_without_a_stable_orbit_blank(data, basin_figure):
    ds = data["basins"]
    for name in ("1/1", "1/2", "1/3"):
        ax = _panel(basin_figure, f"({name})")
        (mesh,) = _gid(ax, "fraction")
        shown = ~np.ma.getmaskarray(mesh.get_array()).reshape(ds.sizes["delta"],
                                                              ds.sizes["inv_beta"]).T
        has = ds["n_stable"].sel(motion=name).values > 0
        np.testing.assert_array_equal(shown, has)
        assert bool(_gid(ax, "no-orbit")) == bool((~has).any())
        # the outline of Fig. 16's domain on the panels of the types the orbit map has
        assert bool(_gid(ax, "stable-domain")) == (name in data["orbits"]["type"].values)
    (mesh,) = _gid(_panel(basin_figure, "other: none of these types"), "fraction")
    assert not np.ma.getmaskarray(mesh.get_array()).any()


def test_basins_print_the_starts_and_the_interval(data, basin_figure):
    title = basin_figure.get_suptitle()
    # the box as stored, its plain names in the paper's symbols (plotting.symbols)
    assert "64 starts per cell" in title and plotting.symbols(data["basins"].attrs["box"]) in title
    assert "$x_0$" in title and " x0 " not in title
    assert "Clopper-Pearson" in title
    assert "\\n" not in title                 # line breaks, not escaped ones
    legend = basin_figure.legends[0].get_title().get_text()
    assert "sticking to the wall" in legend and "chaotic" in legend


def test_basins_draw_nan_cells_blank_without_warning(data):
    ds = data["basins"].copy(deep=True)
    ds["fraction"][:, 3:6, 4:8] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plotting.basins(ds)
    (mesh,) = _gid(_panel(fig, "other: none of these types"), "fraction")
    mask = np.ma.getmaskarray(mesh.get_array()).reshape(ds.sizes["delta"],
                                                        ds.sizes["inv_beta"]).T
    assert mask[3:6, 4:8].all() and mask.sum() == 12
    assert not any(_gid(ax, "stable-domain") for ax in fig.axes)


def test_basins_dot_starts_settled_where_the_solver_has_no_stable_orbit(data):
    ds = data["basins"].copy(deep=True)
    k = list(ds["motion"].values).index("1/3")
    no_orbit = np.argwhere(ds["n_stable"].values[k] == 0)[5]
    ds["fraction"].values[k, no_orbit[0], no_orbit[1]] = 2 / 64
    fig = plotting.basins(ds)
    (dots,) = _gid(_panel(fig, "(1/3)"), "stray")
    assert (ds["inv_beta"].values[no_orbit[0]], ds["delta"].values[no_orbit[1]]) in set(
        zip(dots.get_xdata(), dots.get_ydata()))


def test_basins_refuse_an_orbit_map_of_another_system(data):
    with pytest.raises(ValueError, match="not the same system"):
        plotting.basins(data["basins"], data["orbits"].assign_attrs(zeta=0.1))


# --------------------------------------------------------------------------------------------
# Lyapunov
# --------------------------------------------------------------------------------------------

def _lyapunov_with_gaps(ds):
    """Every start sticks in a block of cells (-inf), no value in another (NaN)."""
    ds = ds.copy(deep=True)
    ds["lyapunov"][0:4, 0:3] = -np.inf
    ds["lyapunov"][10:12, 20:22] = np.nan
    return ds


@pytest.fixture(scope="module")
def lyapunov_figure(data):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return plotting.lyapunov(_lyapunov_with_gaps(data["lyapunov"]))


def test_lyapunov_two_panels(lyapunov_figure):
    titles = [ax.get_title() for ax in lyapunov_figure.axes if ax.get_title()]
    assert titles == ["(a) largest Lyapunov exponent", "(b) what the starts settle to"]


def _cells(mesh, ds):
    mask = np.ma.getmaskarray(mesh.get_array()).reshape(ds.sizes["delta"], ds.sizes["inv_beta"])
    return ~mask.T


def test_lyapunov_minus_infinity_and_nan_in_their_own_colours(data, lyapunov_figure):
    ds = _lyapunov_with_gaps(data["lyapunov"])
    lam = ds["lyapunov"].values
    ax = lyapunov_figure.axes[0]
    (sticking,) = _gid(ax, "sticking")
    (missing,) = _gid(ax, "nan")
    (values,) = _gid(ax, "lyapunov")
    np.testing.assert_array_equal(_cells(sticking, ds), np.isneginf(lam))
    np.testing.assert_array_equal(_cells(missing, ds), np.isnan(lam))
    np.testing.assert_array_equal(_cells(values, ds), np.isfinite(lam))
    assert matplotlib.colors.same_color(sticking.get_cmap()(0.5), STICK_COLOR)
    assert matplotlib.colors.same_color(missing.get_cmap()(0.5), NAN_COLOR)
    assert values.norm(0.0) == pytest.approx(0.5), "the colour map is centred at 0"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(r"$-\infty$" in t for t in labels) and "no value" in labels


def test_lyapunov_classes_named_in_the_legend(data, lyapunov_figure):
    ax = _panel(lyapunov_figure, "(b) what the starts settle to")
    (mesh,) = _gid(ax, "cell-class")
    code = data["lyapunov"]["cell_class"].values
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    for k, (_, words) in enumerate(CLASSES.values()):
        assert sum(t.startswith(words) for t in labels) == int((code == k).any()), words
    np.testing.assert_array_equal(np.asarray(mesh.get_array()).reshape(code.T.shape).T, code)


def test_lyapunov_dots_exponents_of_unresolved_sign(data):
    ds = data["lyapunov"].copy(deep=True)
    ds["lyapunov"][2, 3] = 0.001
    ds["lyapunov_stderr"][2, 3] = 0.004       # 0 lies within 2 s.e.
    ds["lyapunov"][4, 5] = 0.02
    ds["lyapunov_stderr"][4, 5] = 0.004       # positive, resolved
    resolved = np.isfinite(ds["lyapunov_stderr"].values)
    resolved &= np.abs(ds["lyapunov"].values) >= 2.0 * ds["lyapunov_stderr"].values
    fig = plotting.lyapunov(ds)
    (dots,) = _gid(fig.axes[0], "unresolved")
    xy = set(zip(dots.get_xdata(), dots.get_ydata()))
    x, y = ds["inv_beta"].values, ds["delta"].values
    assert (x[2], y[3]) in xy and (x[4], y[5]) not in xy
    assert len(xy) == np.sum(np.isfinite(ds["lyapunov_stderr"].values) & ~resolved)


def test_lyapunov_refuses_unknown_classes(data):
    ds = data["lyapunov"].copy()
    ds["cell_class"].attrs["flag_meanings"] = "periodic chaotic"
    with pytest.raises(ValueError, match="flag_meanings"):
        plotting.lyapunov(ds)


def test_lyapunov_marks_where_a_coexisting_motion_holds_the_largest_exponent(data):
    ds = data["lyapunov"]
    code = ds["cell_class"].values
    owner = ds["lyapunov_class"].values
    other = np.isfinite(ds["lyapunov"].values) & (owner != code)
    assert other.any() and (code == CLASSES_LIST.index("wall_free")).any()
    fig = plotting.lyapunov(ds)
    ax = fig.axes[0]
    x, y = ds["inv_beta"].values, ds["delta"].values
    drawn = set()
    for k, name in enumerate(CLASSES_LIST):
        lines = [ln for ln in ax.lines if ln.get_gid() == f"owner-{name}"]
        here = other & (owner == k)
        assert len(lines) == int(here.any()), name
        for ln in lines:
            assert matplotlib.colors.same_color(ln.get_color(), CLASSES[name][0])
            xy = set(zip(ln.get_xdata(), ln.get_ydata()))
            i, j = np.nonzero(here)
            assert xy == set(zip(x[i], y[j]))
            drawn |= xy
    assert len(drawn) == other.sum()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("largest from fewer starts: chaotic (") for t in labels)


def test_lyapunov_colour_bar_ticks_both_ends_evenly(lyapunov_figure):
    (values,) = _gid(lyapunov_figure.axes[0], "lyapunov")
    bar = values.colorbar
    ticks = np.asarray(bar.get_ticks())
    norm = values.norm
    assert ticks[0] == norm.vmin and ticks[-1] == norm.vmax and 0.0 in ticks
    # two slopes, each half ticked at 0, half its end and its end: evenly spaced on the bar
    np.testing.assert_allclose(norm(ticks), [0.0, 0.25, 0.5, 0.75, 1.0], atol=1e-12)
    labels = [t.get_text() for t in bar.ax.get_yticklabels()]
    assert all(labels) and labels[0].startswith(("-", "\N{MINUS SIGN}"))


def test_lyapunov_draws_a_dataset_of_five_classes(data):
    # written before the wall-free class: codes 0-4 keep their meanings
    ds = data["lyapunov"].copy(deep=True).drop_vars("lyapunov_class")
    five = CLASSES_LIST[:5]
    ds = ds.isel({"class": slice(0, 5)})
    ds["cell_class"] = ds["cell_class"].where(ds["cell_class"] < 5, 1).astype("int8")
    ds["cell_class"].attrs.update(flag_values=np.arange(5, dtype="int8"),
                                  flag_meanings=" ".join(five))
    fig = plotting.lyapunov(ds)
    labels = [t.get_text() for t in _panel(fig, "(b) what the starts settle to")
              .get_legend().get_texts()]
    assert not any(t.startswith(CLASSES["wall_free"][1]) for t in labels)


# --------------------------------------------------------------------------------------------
# The periodic-motions report's tables
# --------------------------------------------------------------------------------------------

def _four_cells():
    """2 x 2 cells of 4 starts: (0, 0) three listed starts at -0.1 and a chaotic one at
    +0.5; (0, 1) every start sticks; (1, 0) every start on the wall-free response; (1, 1)
    three sticking starts and one periodic impact motion of another type at -0.2."""
    code = {n: k for k, n in enumerate(CLASSES_LIST)}
    cls = np.empty((4, 2, 2), np.int8)
    lam = np.empty((4, 2, 2))
    cls[:, 0, 0], lam[:, 0, 0] = [code["listed"]] * 3 + [code["chaotic"]], [-0.1] * 3 + [0.5]
    cls[:, 0, 1], lam[:, 0, 1] = code["sticking"], -np.inf
    cls[:, 1, 0], lam[:, 1, 0] = code["wall_free"], -0.05
    cls[:, 1, 1] = [code["sticking"]] * 3 + [code["periodic_other"]]
    lam[:, 1, 1] = [-np.inf] * 3 + [-0.2]
    counts = np.stack([(cls == k).sum(axis=0) for k in range(len(CLASSES_LIST))])
    flags = dict(flag_meanings=" ".join(CLASSES_LIST))
    plane = ("inv_beta", "delta")
    ds = xr.Dataset(
        {"lyapunov": (plane, lam.max(axis=0)),
         "cell_class": (plane, np.argmax(counts, axis=0).astype(np.int8), flags),
         "lyapunov_class": (plane, np.take_along_axis(cls, lam.argmax(axis=0)[None], 0)[0],
                            flags),
         "lyapunov_start": (("start", *plane), lam),
         "class_start": (("start", *plane), cls, flags),
         "class_fraction": (("class", *plane), counts / 4.0)},
        coords={"inv_beta": [1.0, 2.0], "delta": [0.0, 1.0], "class": CLASSES_LIST})
    basins = xr.Dataset(
        {"n_stable": (("motion", *plane), np.array([[[1, 0], [0, 0]], [[0, 0], [0, 0]]])),
         "fraction": (("motion", *plane), np.array([[[0.75, 0], [0, 0]],
                                                    [[0.25, 1], [1, 1]]])),
         "fraction_lo": (("motion", *plane), np.zeros((2, 2, 2))),
         "fraction_hi": (("motion", *plane), np.ones((2, 2, 2))),
         "class_fraction": ds["class_fraction"]},
        coords={"motion": ["1/1", "other"], "inv_beta": [1.0, 2.0], "delta": [0.0, 1.0],
                "class": CLASSES_LIST})
    return ds, basins


def test_lyapunov_table_gives_each_class_its_own_exponent_and_counts_minus_infinity():
    from vibroimpact.reports.notebook import lyapunov_summary

    ds, basins = _four_cells()
    table = lyapunov_summary(ds, basins)
    own = table["exponent of its own starts, range"]
    # the listed cell: its own starts' -0.1, not the chaotic start's +0.5
    assert own["listed"] == "-0.1 .. -0.1"
    assert table.loc["listed", "cells where another class holds the largest exponent"] == (
        "1: chaotic 1")
    assert table.loc["listed", "that exponent, range"] == "0.5 .. 0.5"
    assert own["sticking"] == "-inf (all 2 cells)"
    assert table.loc["sticking", "cells where another class holds the largest exponent"] == (
        "1: periodic other 1")
    assert table.loc["sticking", "that exponent, range"] == "-0.2 .. -0.2"
    # every entry short enough for pandas' default column width (50 characters)
    assert max(len(str(v)) for v in table.values.ravel()) < 50
    assert own["wall free"] == "-0.05 .. -0.05" and table.loc["wall free", "cells"] == 1
    assert table.loc["listed", "starts in the class, min - median (%)"] == "75 - 75"
    # a dataset without the per-start classes: the cells' largest exponent, -inf counted
    old = lyapunov_summary(ds.drop_vars(["class_start", "lyapunov_class"]), basins)
    assert old.loc["sticking", "largest exponent, range"] == "-0.2 .. -0.2; -inf in 1 cells"


def test_basin_table_names_the_wall_free_response():
    from vibroimpact.reports.notebook import basin_summary

    _, basins = _four_cells()
    row = basin_summary(basins).loc["of other: wall-free response (every cell)"]
    assert row["basin min - max (%)"] == "0 - 100"
    assert row["cells where every start settles on it"] == 1


def test_boundary_table_one_column_per_pair_of_kinds():
    from vibroimpact.reports.notebook import boundary_summary

    edges = xr.Dataset(
        {"curve": ("point", np.array([0, 0, 1, 1])),
         "kind": ("curve", np.array(["grazing", "fold"])),
         "type": ("curve", np.array(["1/1", "1/1"])),
         "codim2_type": ("codim2", np.array(["1/1", "1/1", "1/1", "2/1"])),
         "codim2_kinds": ("codim2", np.array(["fold+grazing", "fold+grazing",
                                              "grazing+period_doubling", "fold+grazing"]))})
    table = boundary_summary(edges)
    assert table.loc["(1/1)", "codim-2: fold + grazing"] == "2"
    assert table.loc["(1/1)", "codim-2: grazing + period_doubling"] == "1"
    assert table.loc["(2/1)", "codim-2: grazing + period_doubling"] == ""
    # every cell short enough for pandas' default column width (50 characters)
    assert max(len(str(v)) for v in table.values.ravel()) < 50


def test_the_class_words_follow_the_system():
    """The paper's grid has Fig. 16 beside it; a plane study has no Fig. 16, and with a
    second wall its listed orbits are found at either wall and its wall-free response must
    clear the wall below too."""
    from vibroimpact.plotting import attractors as pa

    grid = xr.Dataset(attrs={})
    plane = xr.Dataset(coords={"eps": [0.5], "delta": [1.0]}, attrs={"axes": ["eps", "delta"]})
    walls = xr.Dataset(coords={"gap": [1.0, 2.0], "inv_beta": [1.0]},
                       attrs={"axes": ["gap", "inv_beta"]})
    fixed_gap = xr.Dataset(coords={"eps": [0.5], "delta": [1.0]},
                           attrs={"axes": ["eps", "delta"], "gap": 2.0})
    assert "Fig. 16" in pa._class_words(grid)["listed"]
    assert "Fig. 16" not in pa._class_words(plane)["listed"]
    assert pa._short(plane, "listed") == "a listed type"
    for ds in (walls, fixed_gap):
        words = pa._class_words(ds)
        assert "either wall" in words["listed"]
        assert r"\delta - g" in words["wall_free"] and r"q < \delta" in words["wall_free"]
    assert r"\delta - g" not in pa._class_words(plane)["wall_free"]
