"""Fig. 15, the probability maps of the impact motions, and their comparison with Fig. 16.

Also what every map over the (1/beta, delta) plane shares (Fig. 16 imports it from here):
cells drawn whole (`cell_rectangles`, `cell_outline`), the few-switches marking, contour
labels placed only where lines are well apart, the type colours and S levels.
"""
from __future__ import annotations

import contourpy
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.contour import ContourSet
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, PathPatch, Rectangle
from matplotlib.path import Path

from vibroimpact import stats
from vibroimpact.plotting._common import (_attr, _header, _noise_text, _num, _same_system,
                                          _spectrum_parts, _styled, _system_text, axis_label,
                                          custom_plane, motion_title, no_collision_text,
                                          note_on_axes, on_plane, plane_axes, plane_caption,
                                          plane_fixed)

#: Probability contours (%) of Fig. 15 (the paper draws 10 % steps).
PROBABILITY_LEVELS = (10, 20, 30, 40, 50, 60, 70, 80, 90)
#: Probability contours (%) drawn over the stable domains in the comparison with Fig. 16.
COMPARISON_LEVELS = (20, 50, 80)


# --------------------------------------------------------------------------------------------
# What every map over the (1/beta, delta) plane shares (Figs. 15, 16 and their comparison)
# --------------------------------------------------------------------------------------------

#: Contour levels of the degree of stability S (%).
S_LEVELS = (5, 10, 20, 30, 40, 50, 60, 70, 80, 90)
#: One colour per motion type: the Okabe-Ito qualitative palette, which readers with the
#: common colour-vision deficiencies can also tell apart; black fifth, orange last: the (3/1)
#: motion in orange beside (2/1) in vermillion read as one hue in Fig. 16.
TYPE_COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#000000", "#56B4E9", "#E69F00")
#: Font size (pt) of contour labels and of the words written in a map's regions.
MAP_TEXT_SIZE = 7.5
#: A contour label keeps this distance (fraction of the panel's width and height) from the
#: labels already placed, and `LINE_CLEARANCE` from every other contour line, so that labels
#: sit only where the lines are well apart.
LABEL_SPACING = 0.1
LINE_CLEARANCE = 0.02
#: A line shorter than this (fraction of the panel's size) gets no label.
LABELLED_LENGTH = 0.1
#: Look of the cells whose record switched between motions only 1 to min_switches - 1 times
#: (their probabilities are not stationary): whole cells, hatched over a light veil so the
#: hatch reads on the dark bands too, their union outlined.
FEW_SWITCHES_STYLE = dict(facecolor=(1.0, 1.0, 1.0, 0.55), edgecolor="0.1", hatch="/////",
                          linewidth=0.0)


def cell_edges(centres):
    """Edges of the cells around evenly or unevenly spaced increasing `centres` (n + 1)."""
    c = np.asarray(centres, dtype=float)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[2.0 * c[0] - mid[0]], mid, [2.0 * c[-1] - mid[-1]]])


def cell_outline(x, y, mask, border=False, only=None):
    """Segments of the cell edges between the cells in `mask` and those outside.

    Parameters
    ----------
    x, y : array_like, shape (nx,), (ny,)
        Cell centres.
    mask : ndarray of bool, shape (nx, ny)
    border : bool
        Also outline the flagged cells along the grid's border (else a region that runs off
        the grid stays open there: it goes on beyond the map).
    only : ndarray of bool, shape (nx, ny), optional
        Outline only the edges of the cells of `mask` that are also in `only`.

    Returns
    -------
    list of ((x0, y0), (x1, y1))
    """
    xe, ye = cell_edges(x), cell_edges(y)
    mode = "constant" if border else "edge"
    m = np.pad(np.asarray(mask, bool), 1, mode=mode)
    k = m & np.pad(np.ones(m[1:-1, 1:-1].shape, bool) if only is None else only, 1, mode=mode)
    a, b = np.nonzero((m[1:, 1:-1] != m[:-1, 1:-1])             # edges at x = xe[a]
                      & (k[1:, 1:-1] | k[:-1, 1:-1]))
    segments = [((xe[i], ye[j]), (xe[i], ye[j + 1])) for i, j in zip(a, b)]
    a, b = np.nonzero((m[1:-1, 1:] != m[1:-1, :-1])             # edges at y = ye[b]
                      & (k[1:-1, 1:] | k[1:-1, :-1]))
    return segments + [((xe[i], ye[j]), (xe[i + 1], ye[j])) for i, j in zip(a, b)]


def cell_rectangles(x, y, mask):
    """One :class:`~matplotlib.patches.Rectangle` per cell in `mask` (centres `x`, `y`)."""
    xe, ye = cell_edges(x), cell_edges(y)
    return [Rectangle((xe[i], ye[j]), xe[i + 1] - xe[i], ye[j + 1] - ye[j])
            for i, j in zip(*np.nonzero(mask))]


def cells_path(x, y, mask):
    """One compound :class:`~matplotlib.path.Path` of the whole cells in `mask` (centres `x`,
    `y`), a closed rectangle each: drawn as one path, a hatch over thousands of cells renders
    in one pass (a collection of rectangles hatches each on its own, ~10 s for 5 000)."""
    xe, ye = cell_edges(x), cell_edges(y)
    i, j = np.nonzero(mask)
    corners = np.stack([np.column_stack([xe[i], ye[j]]), np.column_stack([xe[i + 1], ye[j]]),
                        np.column_stack([xe[i + 1], ye[j + 1]]),
                        np.column_stack([xe[i], ye[j + 1]]),
                        np.column_stack([xe[i], ye[j]])], axis=1)
    codes = np.tile([Path.MOVETO, Path.LINETO, Path.LINETO, Path.LINETO, Path.CLOSEPOLY],
                    i.size)
    return Path(corners.reshape(-1, 2), codes.astype(Path.code_type))


def mark_few_switches(ax, x, y, few):
    """Hatch the whole cells whose probabilities are not stationary and outline their union.

    The hatched collection has gid ``"few_switches"``; its paths are the cells' rectangles.
    """
    if not few.any():
        return
    ax.add_collection(PatchCollection(cell_rectangles(x, y, few), gid="few_switches",
                                      **FEW_SWITCHES_STYLE), autolim=False)
    ax.add_collection(LineCollection(cell_outline(x, y, few, border=True), colors="0.1",
                                     linewidths=0.7, capstyle="projecting"), autolim=False)


def few_switches_handle(motion_map, short=False):
    """Legend entry of :func:`mark_few_switches` (the same style, written once)."""
    n = int(_attr(motion_map, "min_switches")) - 1
    text = "few switches" if short else f"1 to {n} switches between motions"
    return Patch(**{**FEW_SWITCHES_STYLE, "linewidth": 0.7},
                 label=f"{text}: probabilities not stationary")


def _lines(ax, cs):
    """The vertex arrays of a ContourSet's lines, per level, in axes coordinates."""
    to_axes = ax.transData + ax.transAxes.inverted()
    out = []
    for path in cs.get_paths():
        v = to_axes.transform(path.vertices) if len(path.vertices) else path.vertices
        if path.codes is None:
            starts = np.array([0]) if len(v) else np.array([], int)
        else:
            starts = np.flatnonzero(path.codes == Path.MOVETO)
        pieces = np.split(v, starts[1:]) if len(starts) else []
        out.append([piece for piece in pieces if len(piece) > 1])
    return out


def label_contours(ax, cs, fmt, avoid=()):
    """Label the lines of `cs` only where they are well apart, at `MAP_TEXT_SIZE`.

    Each line gets at most one label, at the vertex nearest its middle that lies
    `LINE_CLEARANCE` from every line of another level (and from the vertex arrays `avoid`,
    data coordinates) and `LABEL_SPACING` from the labels already placed; longest lines
    first, a level's second label only after every level had its chance at a first one.
    Returns the label texts (none when `cs` is None).
    """
    from scipy.spatial import cKDTree   # scipy in the map figures' jobs only

    if cs is None:
        return []
    to_axes = ax.transData + ax.transAxes.inverted()
    lines = _lines(ax, cs)
    extra = [to_axes.transform(np.asarray(v, float)) for v in avoid if len(v)]
    trees = {}
    for k in range(len(lines)):
        near = [v for j, level in enumerate(lines) if j != k for v in level] + extra
        trees[k] = cKDTree(np.concatenate(near)) if near else None
    candidates = sorted(((np.sum(np.hypot(*np.diff(v, axis=0).T)), k, v)
                         for k, level in enumerate(lines) for v in level),
                        key=lambda c: -c[0])
    candidates = [c for c in candidates if c[0] >= LABELLED_LENGTH]
    kept, labelled, done = [], set(), set()
    for first in (True, False):
        for n, (_, k, v) in enumerate(candidates):
            if n in done or (first and k in labelled):
                continue
            ok = np.all((v > LINE_CLEARANCE) & (v < 1.0 - LINE_CLEARANCE), axis=1)
            if trees[k] is not None:
                ok &= trees[k].query(v, p=np.inf)[0] >= LINE_CLEARANCE
            for i in np.argsort(np.abs(np.arange(len(v)) - 0.5 * (len(v) - 1))):
                if ok[i] and all(np.max(np.abs(v[i] - q)) >= LABEL_SPACING for q in kept):
                    kept.append(v[i])
                    labelled.add(k)
                    done.add(n)
                    break
    if not kept:
        return []
    to_data = to_axes.inverted()
    return ax.clabel(cs, fmt=fmt, fontsize=MAP_TEXT_SIZE, inline=True, inline_spacing=3,
                     manual=[tuple(to_data.transform(q)) for q in kept])


#: Neighbouring cells whose probabilities differ by `CLIFF_JUMP` (pp) or more are a cliff:
#: every contour level between them would run through the same half cell, so only the
#: `CLIFF_LEVEL` line is drawn there, smoothed over `CLIFF_SMOOTHING` vertices (the grid
#: places it only to within a cell, and its steps are the grid's, not the map's).
CLIFF_JUMP = 40.0
CLIFF_LEVEL = 50.0
CLIFF_SMOOTHING = 5
#: A piece of line left between two cliffs shorter than this (cells) is dropped: it would
#: read as a dash along the cliff.
CLIFF_STUB = 5.0


def _cliff_flags(p):
    """``(across_x, across_y)``: the grid edges between neighbouring cells that are a cliff."""
    return tuple(np.abs(np.diff(p, axis=axis)) >= CLIFF_JUMP for axis in (0, 1))


def _on_cliff(v, x, y, across_x, across_y):
    """Which vertices of a contour line lie on a cliff edge of the grid."""
    tol_x, tol_y = 1e-9 * np.ptp(x), 1e-9 * np.ptp(y)
    jy = np.clip(np.searchsorted(y, v[:, 1]), 0, y.size - 1)
    jy = np.where(np.abs(y[jy - 1] - v[:, 1]) < np.abs(y[jy] - v[:, 1]), jy - 1, jy)
    ix = np.clip(np.searchsorted(x, v[:, 0]), 0, x.size - 1)
    ix = np.where(np.abs(x[ix - 1] - v[:, 0]) < np.abs(x[ix] - v[:, 0]), ix - 1, ix)
    on_row = np.abs(y[jy] - v[:, 1]) <= tol_y        # on an edge across x, between columns
    on_col = np.abs(x[ix] - v[:, 0]) <= tol_x
    i = np.clip(np.searchsorted(x, v[:, 0]) - 1, 0, x.size - 2)
    j = np.clip(np.searchsorted(y, v[:, 1]) - 1, 0, y.size - 2)
    return (on_row & across_x[i, jy]) | (on_col & across_y[ix, j])


def _smoothed(v):
    """Moving average of a line's vertices over `CLIFF_SMOOTHING`, its ends kept."""
    half = CLIFF_SMOOTHING // 2
    if len(v) <= 2 * half + 1:
        return v
    kernel = np.ones(CLIFF_SMOOTHING) / CLIFF_SMOOTHING
    out = v.copy()
    out[half:-half] = np.column_stack([np.convolve(v[:, k], kernel, mode="valid")
                                       for k in (0, 1)])
    return out


def _runs(v, keep):
    """Maximal runs of consecutive segments of `v` flagged in `keep`, as vertex arrays."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(int), [0]])))
    return [v[a:b + 1] for a, b in zip(edges[::2], edges[1::2])]


def probability_contours(ax, x, y, p, levels, **line_kw):
    """Contours of a probability map (%) with each cliff drawn as one line.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    x, y : ndarray, shape (nx,), (ny,)
        Cell centres (increasing); the lines are interpolated between them.
    p : ndarray, shape (nx, ny)
        Probability (%).
    levels : sequence of float
    **line_kw
        ``colors``, ``linewidths`` ... of :class:`~matplotlib.contour.ContourSet`.

    Returns
    -------
    (ContourSet, list of ndarray)
        The contour lines off the cliffs (to be labelled; None when there are none), and the
        `CLIFF_LEVEL` line along the cliffs, smoothed (vertex arrays, data coordinates; the
        caller draws them).

    Notes
    -----
    Where the probability jumps by `CLIFF_JUMP` or more between neighbouring cells (e.g.
    from no impact at all to one motion only) the grid does not resolve where in between
    each level is crossed: its lines would pile up along the cell row, labels on top of each
    other. There only the `CLIFF_LEVEL` line is kept; a segment is on a cliff when both its
    ends lie on grid edges between such cells.
    """
    across_x, across_y = _cliff_flags(p)
    generator = contourpy.contour_generator(x, y, p.T, line_type=contourpy.LineType.Separate)

    cell = np.array([np.ptp(x) / max(x.size - 1, 1), np.ptp(y) / max(y.size - 1, 1)])

    def stub(run, on):
        """A short piece that ends on a cliff (not a small closed loop of the map)."""
        length = np.sum(np.hypot(*(np.diff(run, axis=0) / cell).T))
        return length < CLIFF_STUB and (on[0] or on[-1])

    def split(level):
        kept, steep = [], []
        for v in generator.lines(level):
            on = _on_cliff(v, x, y, across_x, across_y)
            cliff = on[1:] & on[:-1]
            edges = np.flatnonzero(np.diff(np.concatenate([[0], (~cliff).astype(int), [0]])))
            for a, b in zip(edges[::2], edges[1::2]):
                if stub(v[a:b + 1], on[a:b + 1]):
                    cliff[a:b] = True            # part of the cliff it lies along
            kept += _runs(v, ~cliff)
            steep += _runs(v, cliff)
        return kept, steep

    segs = [split(level)[0] for level in levels]
    cliff = [_smoothed(v) for v in split(CLIFF_LEVEL)[1]]
    if not any(segs):
        return None, cliff
    return ContourSet(ax, levels, segs, **line_kw), cliff


def _map_forcing_text(ds):
    """``f(tau) = A sin(beta_f tau) + r(tau) (noise)``, beta_f the map's coordinate."""
    amplitude = float(_attr(ds, "amplitude"))
    scale = "" if amplitude == 1.0 else _num(amplitude)
    return rf"$f(\tau)$ = {scale}$\sin(\beta_f\tau) + r(\tau)$ ({_noise_text(ds)})"


def _map_text(ds):
    """The map's statistics: window, target precision, share reached, record lengths."""
    reached = float(np.mean(ds["reached"].values))
    t = ds["simulated_time"].values
    return (rf"$z_j$ between collisions (chatter and sticking grouped), "
            rf"$w$ = {_num(_attr(ds, 'motion_window'))};  "
            "each cell from rest over one noise record, "
            rf"to s.e. $\leq$ {100 * float(_attr(ds, 'target_stderr')):.3g} pp "
            rf"({100 * reached:.1f} % of cells) or {int(_attr(ds, 'max_periods'))} periods;  "
            rf"records of {t.min():,.0f} to {t.max():,.0f} time units $\tau$ "
            rf"(median {np.median(t):,.0f})")


def _grid(ds):
    """Cell centres ``(x, y)`` along the map's two axes (`plane_axes`)."""
    x, y = plane_axes(ds)
    return ds[x].values, ds[y].values


def _plane_forcing_text(ds):
    """The force of a map over a named plane: ``f(tau) = A sin(beta_f tau) + r(tau)`` (the
    spectrum's kind and cut-off; its rms and A, when fixed, are in the fixed caption)."""
    spectrum = ", ".join(_spectrum_parts(ds.attrs))
    return (r"$f(\tau)$ = $A\sin(\beta_f\tau) + r(\tau)$"
            + (f" ({spectrum})" if spectrum else ""))


def _map_params(ds):
    """The header's parameter line: the paper's for its plane, else the fixed caption."""
    if not custom_plane(ds):
        return f"{_system_text(ds)};  {_map_forcing_text(ds)}"
    return f"{plane_caption(ds)};  {_plane_forcing_text(ds)}"


def _cliff_handle(lw):
    return Line2D([], [], color="k", lw=lw,
                  label=f"cliff: {CLIFF_JUMP:g} pp or more between neighbouring cells "
                        f"(only the {CLIFF_LEVEL:g} % line drawn, smoothed)")


def _finish_figure(fig, motion_map, handles, title):
    """Legend below the panels and the header: system, forcing, the map's statistics."""
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7)
    _header(fig, title, f"{_map_params(motion_map)}\n{_map_text(motion_map)}")
    return fig


def _finish_axes(axes, ds):
    """Labels, the grid's extent (from centre to centre, as the filled contours) and, on a
    map without a collision, the words."""
    x, y = _grid(ds)
    x_name, y_name = plane_axes(ds)
    empty = "n_collisions" in ds and int(ds["n_collisions"].sum()) == 0
    for ax in axes:
        ax.set_xlim(*(x if x.size > 1 else cell_edges(x))[[0, -1]])
        ax.set_ylim(*(y if y.size > 1 else cell_edges(y))[[0, -1]])
        ax.set_xlabel(axis_label(ds[x_name]))
        ax.set_ylabel(axis_label(ds[y_name]))
        ax.label_outer()
        if empty:
            note_on_axes(ax, no_collision_text(ds, where="in any cell\nof this map"))


#: Panels per row of fig15.
FIG15_COLUMNS = 2


@_styled
def fig15(motion_map, levels=PROBABILITY_LEVELS):
    """Fig. 15: probability (%) of each impact motion over the (1/beta, delta) plane.

    Parameters
    ----------
    motion_map : xarray.Dataset
        ``results/datasets/{study}_map.nc``: ``probability(motion, inv_beta, delta)``,
        ``few_switches``, ``reached``; attributes of the study and the map.
    levels : sequence of float
        Contour levels in percent.

    Returns
    -------
    matplotlib.figure.Figure
        One contour map per motion with free flights (the periodic impact motions of Fig. 16)
        and, when the dataset has ``stick_probability``, one of their impact-stick variants
        together (a collision of the motion ends sticking: the impact-chatter-stick cycle of
        a pre-loaded wall, which `periodic_orbits` does not return): filled bands and lines
        of the probability in percent, labelled where they are apart (`label_contours`), a
        cliff drawn as one line (`probability_contours`); whole cells hatched where the
        record switched between motions only 1 to ``min_switches - 1`` times (its numbers
        say where it started, not the long-run share; `mark_few_switches`); dots where the
        cap stopped the cell before the target precision.
    """
    motions = [str(m) for m in motion_map["motion"].values]
    panels = [(motion_title(m), on_plane(motion_map["probability"].sel(motion=m),
                                         motion_map).values)
              for m in motions]
    if "stick_probability" in motion_map:
        panels.append((" + ".join(motion_title(m) for m in motions) + " with sticking",
                       on_plane(motion_map["stick_probability"].sum("motion"),
                                motion_map).values))
    x, y = _grid(motion_map)
    # two panels a row: at a page's width four in a row left the labels tiny
    ncols = min(len(panels), FIG15_COLUMNS)
    nrows = -(-len(panels) // ncols)
    fig = Figure(figsize=(4.2 * ncols + 1.3, 3.6 * nrows + 2.0))
    FigureCanvasAgg(fig)
    grid = fig.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False).ravel()
    for ax in grid[len(panels):]:
        ax.set_visible(False)
    axes = grid[:len(panels)]
    few = on_plane(motion_map["few_switches"], motion_map).values.astype(bool)
    short = ~on_plane(motion_map["reached"], motion_map).values.astype(bool)
    fill_levels = [0.0, *levels, 100.0]
    shaded, has_cliff = None, False
    for ax, (title, prob) in zip(axes, panels):
        p = 100.0 * prob
        shaded = ax.contourf(x, y, p.T, levels=fill_levels, cmap="Blues", vmin=-10, vmax=100)
        lines, cliff = probability_contours(ax, x, y, p, levels, colors="k", linewidths=0.6)
        ax.add_collection(LineCollection(cliff, colors="k", linewidths=1.0, gid="cliff"),
                          autolim=False)
        label_contours(ax, lines, "%d", avoid=cliff)
        has_cliff |= bool(cliff)
        mark_few_switches(ax, x, y, few)
        if short.any():
            i, j = np.nonzero(short)
            # whole at the plane's edge too: a cell centre on the axis limit is not clipped,
            # and drawn over the spine
            ax.plot(x[i], y[j], ls="none", marker=".", ms=1.5, color="C3", clip_on=False,
                    zorder=3, gid="not_reached")
        ax.set_title(title, fontsize=9 if len(title) > 12 else None)
    _finish_axes(axes, motion_map)
    for ax in grid[len(panels) - ncols:len(panels)]:
        ax.xaxis.set_tick_params(labelbottom=True)      # under a hidden panel's place too
        ax.set_xlabel(axis_label(motion_map[plane_axes(motion_map)[0]]))
    fig.colorbar(shaded, ax=grid.tolist(), label="probability of the motion (%)",
                 shrink=0.6, pad=0.02, aspect=30)
    handles = [few_switches_handle(motion_map)] if few.any() else []
    if has_cliff:
        handles.append(_cliff_handle(1.0))
    if short.any():
        handles.append(Line2D([], [], ls="none", marker=".", color="C3",
                              label="target precision not reached (cap)"))
    return _finish_figure(fig, motion_map, handles, "Fig. 15  Probability of the impact motions "
                          "under harmonic plus random force")


def _orbits_on(motion_map, orbits, name):
    """``(stable, S)`` of motion `name` on the map's grid (nearest orbit-map cell)."""
    x, y = plane_axes(motion_map)
    sel = orbits.sel(type=name).sel({x: motion_map[x], y: motion_map[y]}, method="nearest")
    stable = on_plane(sel["n_stable"], motion_map).values > 0
    return stable, np.where(stable, on_plane(sel["S"], motion_map).values, np.nan)


#: Parameters a map and the orbit map drawn under it must share (the noise's are the map's
#: alone: the orbit map has none).
SHARED_PARAMETERS = ("zeta", "eps", "eps_lower", "delta", "gap", "amplitude", "inv_beta")


def _same_plane(motion_map, orbits):
    """Raise unless a map and an orbit map are of one system over one plane: the paper's
    check (zeta, eps) for its plane; over a named plane the same axes and the same value of
    every parameter both hold fixed (`SHARED_PARAMETERS`)."""
    if not custom_plane(motion_map) and not custom_plane(orbits):
        _same_system(motion_map, orbits, ("the map", "the orbit map"))
        return
    if plane_axes(motion_map) != plane_axes(orbits):
        raise ValueError(f"the map runs over {list(plane_axes(motion_map))} but the orbit map "
                         f"over {list(plane_axes(orbits))}: not the same plane")
    a, b = plane_fixed(motion_map), plane_fixed(orbits)
    for key in SHARED_PARAMETERS:
        if key in a and key in b and float(a[key]) != float(b[key]):
            raise ValueError(f"the map has {key} = {a[key]!r} but the orbit map {b[key]!r}: "
                             f"not the same system")


def map_agreement(motion_map, orbits, threshold=0.5):
    """`stats.motion_map_agreement` of every motion the map and the orbit map share.

    The orbit map is read at its cell nearest to each map cell (grids may differ).
    Returns ``{motion: dict}``.
    """
    shared = [str(m) for m in motion_map["motion"].values if str(m) in orbits["type"].values]
    out = {}
    for name in shared:
        stable, S = _orbits_on(motion_map, orbits, name)
        p = on_plane(motion_map["probability"].sel(motion=name), motion_map).values
        out[name] = stats.motion_map_agreement(p, stable, S, threshold)
    return out


def _agreement_text(a):
    def pct(v):
        return "n/a" if not np.isfinite(v) else f"{100 * v:.0f} %"
    rho = "n/a" if not np.isfinite(a["rank_correlation"]) else f"{a['rank_correlation']:.2f}"
    return (rf"$P \geq 50$ %: {a['n_dominant']} cells, {pct(a['dominant_inside'])} inside"
            "\n"
            rf"domain with $P \geq 50$ %: {pct(a['domain_covered'])}"
            "\n"
            rf"rank corr. $(P, S)$ inside: {rho}")


def _cells_of(at_cells, motion_map):
    """The orbits at the map's cells (``n_stable``, ``S`` over ``(type, x, y)``) with the
    map's coordinates; their axes must hold the map's values (to 1e-9)."""
    for name in plane_axes(motion_map):
        if (name not in at_cells.dims or at_cells.sizes[name] != motion_map.sizes[name]
                or not np.allclose(at_cells[name].values, motion_map[name].values,
                                   rtol=0.0, atol=1e-9)):
            raise ValueError(f"the orbits at the map's cells do not lie on the map's {name} "
                             "grid")
    return at_cells.assign_coords({n: motion_map[n].values for n in plane_axes(motion_map)})


@_styled
def fig15_vs_fig16(motion_map, orbits, at_cells=None, levels=COMPARISON_LEVELS):
    """The probability contours of Fig. 15 over the stable domains and S contours of Fig. 16.

    Parameters
    ----------
    motion_map : xarray.Dataset
        Probability map (as for :func:`fig15`).
    orbits : xarray.Dataset
        Orbit map of the same system (``results/orbits/{name}.nc``); its zeta and eps must
        equal the map's.
    at_cells : xarray.Dataset, optional
        The orbits solved at the map's own cells (``results/datasets/{study}_map_orbits.nc``,
        rule ``solve_map_orbits``): the agreement numbers are read there, as finding 8
        reads them. Without: at the orbit map's cell nearest to each
        map cell (a tie where a map cell lies halfway between two).
    levels : sequence of float
        Probability contours drawn (%).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per motion in both maps: the stable domain under ``sin(beta_f tau)`` alone
        shaded, its thin S contours, the probability contours under harmonic plus random
        force in colour, and the agreement numbers of :func:`map_agreement` (share of the
        cells with probability >= 50 % inside the stable domain; share of the domain where
        the motion dominates; Spearman's rank correlation of probability and S there).
    """
    _same_plane(motion_map, orbits)
    agreement = map_agreement(motion_map, orbits if at_cells is None else
                              _cells_of(at_cells, motion_map))
    if not agreement:
        raise ValueError(f"no motion of the map {list(motion_map['motion'].values)} is in the "
                         f"orbit map {list(orbits['type'].values)}")
    x, y = _grid(motion_map)
    xo, yo = (orbits[name].values for name in plane_axes(motion_map))
    fig = Figure(figsize=(4.0 * len(agreement) + 0.5, 4.8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(agreement), sharex=True, sharey=True, squeeze=False).ravel()
    few = on_plane(motion_map["few_switches"], motion_map).values.astype(bool)
    has_cliff = False
    for k, (ax, name) in enumerate(zip(axes, agreement)):
        sel = orbits.sel(type=name)
        stable = on_plane(sel["n_stable"], motion_map).values > 0
        color = TYPE_COLORS[k % len(TYPE_COLORS)]
        if stable.any():
            ax.contourf(xo, yo, stable.T.astype(float), levels=[0.5, 1.5], colors=["0.88"])
            S = np.where(stable, on_plane(sel["S"], motion_map).values, np.nan)
            ax.contour(xo, yo, S.T, levels=S_LEVELS, colors="0.55", linewidths=0.4)
            ax.contour(xo, yo, stable.T.astype(float), levels=[0.5], colors="0.3",
                       linewidths=1.0)
        p = 100.0 * on_plane(motion_map["probability"].sel(motion=name), motion_map).values
        widths = [1.8 if level == CLIFF_LEVEL else 0.8 for level in levels]
        lines, cliff = probability_contours(ax, x, y, p, levels, colors=[color],
                                            linewidths=widths)
        ax.add_collection(LineCollection(cliff, colors=[color], linewidths=1.8, gid="cliff"),
                          autolim=False)
        label_contours(ax, lines, "%d %%", avoid=cliff)
        has_cliff |= bool(cliff)
        mark_few_switches(ax, x, y, few)
        ax.text(0.98, 0.02, _agreement_text(agreement[name]), transform=ax.transAxes,
                ha="right", va="bottom", fontsize=6.5,
                bbox=dict(facecolor="white", edgecolor="0.7", alpha=0.85, pad=2))
        ax.set_title(motion_title(name))
    _finish_axes(axes, motion_map)
    handles = [Patch(facecolor="0.88", edgecolor="0.3",
                     label=r"stable under $\sin(\beta_f\tau)$ alone (Fig. 16)"),
               Line2D([], [], color="0.55", lw=0.4, label="its degree of stability $S$ (%)"),
               Line2D([], [], color="k", lw=1.8,
                      label=f"probability {', '.join(map(str, levels))} % with noise (Fig. 15)")]
    if has_cliff:
        handles.append(_cliff_handle(1.8))
    if few.any():
        handles.append(few_switches_handle(motion_map, short=True))
    return _finish_figure(fig, motion_map, handles, "Fig. 15 over Fig. 16  Likely motions under "
                          "noise and stable periodic motions")


#: Complete stretches a cell needs for its mean residence time to be drawn unmarked.
RESIDENCE_MIN_STRETCHES = 5
#: Look of the cells with fewer complete stretches (their mean is a few samples, or none).
FEW_STRETCHES_STYLE = dict(facecolor="none", edgecolor="0.35", hatch="xxx", linewidth=0.0)
#: Marker of the cells where the state occurs only in the stretches cut by the record's ends
#: (the one it starts in, the one it ends in): seen, not measured; a motion held through the
#: whole record is one.
ONLY_CUT_STYLE = dict(facecolor="#f4c7a1", edgecolor="none", linewidth=0.0)


@_styled
def residence(motion_map, min_stretches=RESIDENCE_MIN_STRETCHES):
    """Mean residence time of each motion (and of "none") over the (1/beta, delta) plane.

    Parameters
    ----------
    motion_map : xarray.Dataset
        ``results/datasets/{study}_map.nc`` with ``residence_time(state, inv_beta, delta)``
        and ``n_stretches`` (docs/datasets.md).
    min_stretches : int
        Cells with fewer complete stretches of the state are cross-hatched (a mean of a few
        stretches, or none: then also left blank).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per state, whole cells coloured by the mean length of the complete stretches
        in forcing periods on one logarithmic scale for all panels; hatched cells
        (gid ``"few_stretches"``) hold fewer than `min_stretches` complete stretches.
        A pale orange cell (gid ``"only_cut"``) is one where the state occurs only in the
        stretches cut by the record's ends (``n_censored`` > 0, no complete stretch): seen,
        but not measured; a motion held through the whole record (P near 1) is one.
    """
    from matplotlib.colors import LogNorm

    from vibroimpact.stats.residence import by_state

    stay = by_state(motion_map)
    states = [str(s) for s in stay["state"].values]
    x, y = _grid(motion_map)
    xe, ye = cell_edges(x), cell_edges(y)
    t = on_plane(stay["residence_time"], motion_map).values
    n = on_plane(stay["n_stretches"], motion_map).values
    shown = np.isfinite(t) & (t > 0)
    norm = (LogNorm(vmin=float(t[shown].min()), vmax=max(float(t[shown].max()),
                                                          1.01 * float(t[shown].min())))
            if shown.any() else None)
    fig = Figure(figsize=(3.6 * len(states) + 1.0, 4.4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(states), sharex=True, sharey=True, squeeze=False).ravel()
    mesh = None
    few_any = False
    cut = ((n == 0) & (on_plane(stay["n_censored"], motion_map).values > 0)
           if "n_censored" in stay
           else np.zeros(n.shape, bool))
    for k, (ax, name, ts, ns, ok) in enumerate(zip(axes, states, t, n, shown)):
        if ok.any():
            mesh = ax.pcolormesh(xe, ye, np.ma.masked_where(~ok, ts).T, norm=norm,
                                 cmap="viridis", gid="residence")
        few = ns < min_stretches
        if few.any():
            few_any = True
            ax.add_patch(PathPatch(cells_path(x, y, few), gid="few_stretches",
                                   **FEW_STRETCHES_STYLE))
        if cut[k].any():
            ax.add_patch(PathPatch(cells_path(x, y, cut[k]), gid="only_cut",
                                   **ONLY_CUT_STYLE))
        ax.set_title(motion_title(name))
    _finish_axes(axes, motion_map)
    for ax in axes:                       # cells drawn whole: the extent is the cells' edges
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])
    if mesh is not None:
        fig.colorbar(mesh, ax=axes.tolist(), shrink=0.85,
                     label="mean residence time (forcing periods)")
    else:
        note_on_axes(axes[0], "no complete stretch of any motion")
    handles = ([Patch(**{**FEW_STRETCHES_STYLE, "linewidth": 0.7},
                      label=f"fewer than {min_stretches} complete stretches (blank: none)")]
               if few_any else [])
    if cut is not None and cut.any():
        handles.append(Patch(**ONLY_CUT_STYLE,
                             label="only in the stretch the record starts or ends in (no "
                                   "complete stretch; e.g. held throughout)"))
    return _finish_figure(fig, motion_map, handles, "Mean residence time in each impact motion "
                          "under harmonic plus random force")
