"""Fig. 16: domains of stable periodic impact motions under the harmonic force alone."""
from __future__ import annotations

import json

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from vibroimpact._plane import dataset_axes
from vibroimpact.plotting._common import (_attr, _header, _nearest, _same_system, _styled,
                                          _system_text, axis_label, custom_plane,
                                          motion_title, on_plane, plane_axes, plane_caption,
                                          plane_fixed, speed_law)
from vibroimpact.plotting.maps import (MAP_TEXT_SIZE, S_LEVELS, TYPE_COLORS, cell_edges,
                                       cell_outline, label_contours)

#: Why a cell has no stable motion (the dataset's ``reason``): colour, the words written in
#: its regions, and the legend's cause (paper Section 5: no solution satisfying eqs. (10),
#: (11), (13) in its domains D, V, X; eq. (22) violated in its domain U).
REASONS = {
    1: ("white", "no solution", "no solution of eqs. (10), (11)"),
    2: ("0.84", "crosses\nthe wall", "solutions cross the wall: eq. (13) violated"),
    3: ("#f4b6b6", "unstable", "solutions unstable: eq. (22) violated (the paper's U)"),
}
#: With two walls, or under an impact law, the motions come from Newton shooting seeded by
#: settled starts (`vibroimpact.attractors.shooting`): code 1 says none was found, not that
#: none exists.
TWO_WALL_REASONS = {**REASONS, 1: ("white", "none found",
                                   "no motion of the type found from the settled starts")}
#: Text colour of each reason's region words (dark enough on its own fill).
REASON_TEXT_COLORS = {1: "0.25", 2: "0.2", 3: "#8b1a1a"}
#: A reason is named in its largest connected region when that holds `LARGEST_NAMED` of the
#: panel's cells or more, and in every other region holding `NAMED_SHARE` or more.
LARGEST_NAMED = 0.002
NAMED_SHARE = 0.05
#: Free space (pt) kept around a region's word.
WORD_MARGIN = 2.5
#: Longest leader (share of the panel) from a region's word to a region too thin to hold it.
LEADER_LENGTH = 0.3
#: Width (pt) of a stable domain's edge: thin, so a domain one or two cells wide still
#: shows its colour.
EDGE_WIDTH = 0.8
#: Line style of each kind of boundary curve (a boundaries dataset's ``kind``) and its words
#: in the legend. The dotted style stays with the edge of complex multipliers.
BOUNDARY_KINDS = {
    "fold": ("-", "fold: a stable and an unstable solution meet and vanish"),
    "grazing": ((0, (3.5, 1.5)), "grazing: the motion touches the wall, eq. (13) at its limit"),
    "period_doubling": ((0, (7.0, 1.5, 1.5, 1.5)),
                        "period doubling: a multiplier passes -1, eq. (22) at its limit"),
    "existence": ((0, (0.1, 2.0)), "existence: the solution of eqs. (10), (11) ends"),
}
#: Kinds drawn wider with round caps: a dotted line of round dots, heavier than the fine
#: dotted edge of complex multipliers.
ROUND_KINDS = {"existence": 1.9}
#: Width (pt) of a boundary curve on a type's panel and on the overview (a).
BOUNDARY_WIDTH = 1.1
OVERVIEW_WIDTH = 1.3
#: Marker of a codimension-two point (two boundaries meet).
CODIM2_STYLE = dict(ls="none", marker="o", ms=4.5, mfc="white", mew=1.0, zorder=4)
#: lam within this relative distance of eps e^(-zeta z / m) counts as complex multipliers.
COMPLEX_RTOL = 1e-7


def _on_cells(orbits, name):
    """Parameter `name` at every cell of an orbit map's plane, shape (x, y): its coordinate
    when it is an axis, else its fixed value (`plane_fixed`; the paper's plane: attributes)."""
    x, y = plane_axes(orbits)
    shape = (orbits[x].size, orbits[y].size)
    if name == x:
        return np.broadcast_to(np.asarray(orbits[x], dtype=float)[:, None], shape)
    if name == y:
        return np.broadcast_to(np.asarray(orbits[y], dtype=float)[None, :], shape)
    fixed = plane_fixed(orbits)
    if name not in fixed:
        raise KeyError(f"the orbit map neither runs over nor fixes {name!r}")
    return np.full(shape, float(fixed[name]))


def _type_counts(name):
    """``(m, m_lower, n)`` of a type named ``"m/n"`` (``m_lower`` 0) or ``"(m,m_lower)/n"``."""
    counts, n = name.rsplit("/", 1)
    parts = [int(k) for k in counts.strip("()").split(",")]
    return (parts + [0])[:2] + [int(n)] if len(parts) == 1 else parts + [int(n)]


def complex_multipliers(orbits, m, n, m_lower=0):
    """Where the most stable (m/n) motion has a complex pair of multipliers.

    Parameters
    ----------
    orbits : xarray.Dataset
        Orbit map of one type: ``lam`` over its plane (``(inv_beta, delta)``, or the two axes
        of ``attrs["axes"]``); zeta, eps and 1/beta from the axes or the fixed values
        (global attributes ``zeta``, ``eps`` on the paper's plane).
    m, n : int
        The motion type.
    m_lower : int
        Impacts per period at the lower wall of a two-wall type ``(m, m_lower)/n`` (``m`` then
        those at the upper wall; ``det T = eps^2m eps_lower^2m_lower e^(-2 zeta z)``).

    Returns
    -------
    ndarray of bool, shape (x, y)

    Notes
    -----
    Complex multipliers have ``|mu| = sqrt(det T) = eps^m e^(-zeta z)`` (docs/model.md,
    Section 8.7), so there ``lam = eps e^(-zeta z / m)`` and ``S = 100 (1 - lam)`` depend on
    1/beta alone (``z = 2 pi n / beta``): contours of S are vertical lines there. Where the
    multipliers turn real, S leaves that value with infinite slope (a square-root branch), so
    contour levels interpolated across the switch are artefacts of the grid. With two walls
    ``det T = eps^(2 m) eps_lower^(2 m_lower) e^(-2 zeta z)``, so ``eps`` and ``m`` above
    become ``(eps^m eps_lower^m_lower)^(1/(m + m_lower))`` and ``m + m_lower``.
    """
    total = m + m_lower
    if not custom_plane(orbits):
        zeta, eps = float(_attr(orbits, "zeta")), float(_attr(orbits, "eps"))
        z = 2.0 * np.pi * n * np.asarray(orbits["inv_beta"], dtype=float)
        if m_lower:     # two walls: m upper and m_lower lower impacts, |mu|^2 = det T
            eps_l = float(_attr(orbits, "eps_lower"))
            lam_c = (eps ** m * eps_l ** m_lower) ** (1.0 / total) * np.exp(-zeta * z / total)
        else:
            lam_c = eps * np.exp(-zeta * z / m)
        lam_c = lam_c[:, None]
    else:               # a named plane: zeta, eps, eps_lower, 1/beta per cell
        zeta, eps = _on_cells(orbits, "zeta"), _on_cells(orbits, "eps")
        if m_lower:
            lower = (_on_cells(orbits, "eps_lower") if "eps_lower" in plane_axes(orbits)
                     or "eps_lower" in plane_fixed(orbits) else eps)
            eps = (eps ** m * lower ** m_lower) ** (1.0 / total)
        z = 2.0 * np.pi * n * _on_cells(orbits, "inv_beta")
        lam_c = eps * np.exp(-zeta * z / total)
    lam = on_plane(orbits["lam"], orbits).values.astype(float)
    with np.errstate(invalid="ignore"):
        return lam <= lam_c * (1.0 + COMPLEX_RTOL)


def _box_cells(ax, word, shape):
    """Cells (along 1/beta, along delta; odd numbers) that `word` covers at `MAP_TEXT_SIZE`.

    Measured on the axes as laid out when called, with `WORD_MARGIN` each side.
    """
    renderer = ax.figure.canvas.get_renderer()
    probe = ax.text(0.0, 0.0, word, fontsize=MAP_TEXT_SIZE, linespacing=1.0)
    box, axes_box = probe.get_window_extent(renderer), ax.get_window_extent(renderer)
    probe.remove()
    pad = 2.0 * WORD_MARGIN * ax.figure.dpi / 72.0
    cells = [(box.width + pad) / axes_box.width * shape[0],
             (box.height + pad) / axes_box.height * shape[1]]
    return tuple(int(np.ceil(c)) // 2 * 2 + 1 for c in cells)


def _marker_cells(ax, x, y):
    """Cells of the grid (x, y) that the codimension-two markers of `ax` cover (gid
    ``"codim2"``), with `WORD_MARGIN` around them: no word may be written over a marker."""
    taken = np.zeros((x.size, y.size), bool)
    axes_box = ax.get_window_extent(ax.figure.canvas.get_renderer())
    reach = (0.5 * CODIM2_STYLE["ms"] + WORD_MARGIN) * ax.figure.dpi / 72.0
    di = int(np.ceil(reach / axes_box.width * x.size))
    dj = int(np.ceil(reach / axes_box.height * y.size))
    for line in ax.get_lines():
        if line.get_gid() != "codim2":
            continue
        for px, py in zip(line.get_xdata(), line.get_ydata()):
            i, j = _nearest(x, px), _nearest(y, py)
            taken[max(i - di, 0):i + di + 1, max(j - dj, 0):j + dj + 1] = True
    return taken


def _name_regions(ax, x, y, reason, stable, reasons=REASONS):
    """Write each reason's words in its sizable regions (with a leader to those too thin).

    A word goes where its box fits inside the region (on two lines if it must), as deep
    inside as it can; a region too thin for it gets the word on the nearest free cells (no
    stable domain, no other word, no codimension-two marker: `_marker_cells`) within
    `LEADER_LENGTH`, with a line to the region's deepest point that crosses no stable
    domain. The texts have gid ``reason-<code>``.
    """
    from scipy import ndimage   # scipy in fig16's job only, not in every job importing plotting

    taken = stable | _marker_cells(ax, x, y)
    scale = np.array([1.0 / x.size, 1.0 / y.size])        # a cell, as a share of the panel
    for code in (3, 2, 1):       # the thin unstable regions first: they need space near them
        word = reasons[code][1]
        mask = reason == code
        parts, n = ndimage.label(mask)
        sizes = ndimage.sum_labels(mask, parts, np.arange(1, n + 1))
        style = dict(fontsize=MAP_TEXT_SIZE, ha="center", va="center", linespacing=1.0,
                     color=REASON_TEXT_COLORS[code], gid=f"reason-{code}")
        wordings = [(w, _box_cells(ax, w, mask.shape))
                    for w in dict.fromkeys([word, word.replace(" ", "\n")])]
        for rank, k in enumerate(np.argsort(-sizes)):
            if sizes[k] < (NAMED_SHARE if rank else LARGEST_NAMED) * mask.size:
                break
            part = parts == k + 1
            depth = ndimage.distance_transform_edt(np.pad(part, 1), sampling=scale)[1:-1, 1:-1]
            for text, (bw, bh) in wordings:
                fits = _fits(part & ~taken, bw, bh)
                if fits.any():
                    i, j = np.unravel_index(np.argmax(np.where(fits, depth, -1.0)), part.shape)
                    ax.text(x[i], y[j], text, **style)
                    break
            else:
                text, (bw, bh) = wordings[0]
                target = np.unravel_index(np.argmax(depth), part.shape)
                spot = _leader_spot(_fits(~stable & ~taken & ~part, bw, bh), target, stable,
                                    scale)
                if spot is None:
                    continue
                i, j = spot
                ax.annotate(text, xy=(x[target[0]], y[target[1]]), xytext=(x[i], y[j]),
                            arrowprops=dict(arrowstyle="-", color=style["color"], lw=0.6,
                                            shrinkA=2, shrinkB=0), **style)
            taken[max(i - bw // 2 - 1, 0):i + bw // 2 + 2,
                  max(j - bh // 2 - 1, 0):j + bh // 2 + 2] = True


def _leader_spot(free, target, stable, scale):
    """The cell of `free` nearest to `target` within `LEADER_LENGTH` whose straight line to
    it crosses no `stable` cell, or None."""
    cells = np.argwhere(free)
    distance = np.hypot(*((cells - target) * scale).T)
    for c in np.argsort(distance):
        if distance[c] > LEADER_LENGTH:
            return None
        path = np.rint(np.linspace(cells[c], target, 50)).astype(int)
        if not stable[path[:, 0], path[:, 1]].any():
            return tuple(cells[c])
    return None


def _fits(allowed, bw, bh):
    """Cells on which a box of bw x bh cells, centred, covers only `allowed` cells."""
    from scipy import ndimage

    return ndimage.minimum_filter(allowed.astype(np.uint8), size=(bw, bh), mode="constant",
                                  cval=0) > 0


def boundary_axes(boundaries):
    """The plane ``(x, y)`` of a boundaries dataset (`vibroimpact._plane.dataset_axes`; its
    points are variables over ``point``, not dimensions)."""
    return dataset_axes(boundaries)


def _fixed_of(boundaries):
    """``{parameter: value}`` a boundaries dataset over a plane holds fixed
    (``attrs["fixed"]``, JSON text)."""
    fixed = boundaries.attrs.get("fixed", "{}")
    return json.loads(fixed) if isinstance(fixed, (str, bytes)) else dict(fixed)


def boundary_curves(boundaries):
    """The curves of a boundaries dataset: ``[(index, type, kind, vertices)]``.

    Parameters
    ----------
    boundaries : xarray.Dataset
        ``inv_beta(point)``, ``delta(point)``, ``curve(point)`` (a curve's points
        consecutive, in order along it), ``kind(curve)``, ``type(curve)``.

    Returns
    -------
    list of (int, str, str, ndarray of shape (n, 2))
        Vertices as ``(inv_beta, delta)``; a kind outside `BOUNDARY_KINDS` raises ValueError.
    """
    kinds = [str(k) for k in boundaries["kind"].values]
    unknown = sorted(set(kinds) - set(BOUNDARY_KINDS))
    if unknown:
        raise ValueError(f"boundary kinds {unknown} are not among {list(BOUNDARY_KINDS)}")
    types = [str(t) for t in boundaries["type"].values]
    curve = np.asarray(boundaries["curve"].values, dtype=int)
    if curve.size == 0:
        return []
    x_name, y_name = boundary_axes(boundaries)
    xy = np.column_stack([np.asarray(boundaries[x_name].values, dtype=float),
                          np.asarray(boundaries[y_name].values, dtype=float)])
    starts = np.flatnonzero(np.r_[True, curve[1:] != curve[:-1]])
    return [(int(curve[a]), types[curve[a]], kinds[curve[a]], piece)
            for a, piece in zip(starts, np.split(xy, starts[1:]))]


def _kind_style(kind):
    """Line2D keywords of a boundary of `kind` on a type's panel (`BOUNDARY_KINDS`)."""
    if kind in ROUND_KINDS:
        return dict(ls=BOUNDARY_KINDS[kind][0], lw=ROUND_KINDS[kind], dash_capstyle="round")
    return dict(ls=BOUNDARY_KINDS[kind][0], lw=BOUNDARY_WIDTH)


def _overview_style(style, k):
    """A boundary's style (`_kind_style`) on the overview (a), for the `k`-th type: wider
    (`OVERVIEW_WIDTH`), and a dashed pattern shifted by half its period for every other
    type, so where two types' edges of one kind coincide both colours show in turn."""
    ls = style["ls"]
    if isinstance(ls, tuple) and k % 2:
        offset, pattern = ls
        ls = (offset + 0.5 * sum(pattern), pattern)
    return dict(style, ls=ls, lw=style["lw"] * OVERVIEW_WIDTH / BOUNDARY_WIDTH)


def _draw_boundaries(overview, panels, boundaries):
    """Boundary curves and codimension-two points of each type on its panel and on (a).

    `panels` maps a type to ``(axes, colour)``. A curve is one Line2D per panel, gid
    ``boundary-<curve>`` on the type's panel and ``overview-boundary-<curve>`` on (a); the
    codimension-two points of a type are one Line2D of markers per panel, gid ``codim2``.
    Returns the kinds drawn and whether a codimension-two point was.
    """
    drawn = set()
    order = {name: k for k, name in enumerate(panels)}
    for c, name, kind, xy in boundary_curves(boundaries):
        if name not in panels:
            continue
        ax, color = panels[name]
        style = _kind_style(kind)
        ax.plot(xy[:, 0], xy[:, 1], color="k", gid=f"boundary-{c}", **style)
        overview.plot(xy[:, 0], xy[:, 1], color=color, gid=f"overview-boundary-{c}",
                      **_overview_style(style, order[name]))
        drawn.add(kind)
    types = np.array([str(t) for t in boundaries["codim2_type"].values])
    x_name, y_name = boundary_axes(boundaries)
    x = np.asarray(boundaries[f"codim2_{x_name}"].values, dtype=float)
    y = np.asarray(boundaries[f"codim2_{y_name}"].values, dtype=float)
    marked = False
    for name, (ax, color) in panels.items():
        here = types == name
        if here.any():
            ax.plot(x[here], y[here], mec="k", gid="codim2", **CODIM2_STYLE)
            overview.plot(x[here], y[here], mec=color, gid="codim2", **CODIM2_STYLE)
            marked = True
    return [k for k in BOUNDARY_KINDS if k in drawn], marked


@_styled
def fig16(orbits, boundaries=None):
    """Domains of stable (m/n) periodic impact motions over the (1/beta, delta) plane.

    Parameters
    ----------
    orbits : xarray.Dataset
        ``results/orbits/{name}.nc``: ``n_stable``, ``lam``, ``S``, ``reason`` over
        ``(type, inv_beta, delta)``; global attributes ``zeta``, ``eps``.
    boundaries : xarray.Dataset, optional
        ``results/orbits/{name}_boundaries.nc`` of the same system: the curves bounding each
        type's stable domain (``inv_beta``, ``delta``, ``curve`` over ``point``; ``kind``,
        ``type`` over ``curve``) and the points where two of them meet (``codim2_*``). One
        with the attribute ``traced = 0`` (eps = 0, not traced) is drawn as None is.

    Returns
    -------
    matplotlib.figure.Figure
        Panel (a) outlines the stable domain of every type, one qualitative colour each.
        One panel per type then shows, cell by cell, the degree of stability S in colour and
        why the other cells have no stable motion (`REASONS`: no solution, solutions that
        cross the wall, only unstable solutions), the causes written in their regions; the
        stable domain's edge is a thin line along the cells where the domain is three cells
        thick or more; a thinner one is shown by its colour alone. Labelled thin contours of
        S (`label_contours`) are drawn where the multipliers are real; where they are
        complex S depends on 1/beta alone (`complex_multipliers`), so no contour is drawn
        there and a dotted line marks that region's edge.

        With `boundaries`, the edges of the stable domains (on the type's panel in black, on
        panel (a) in the type's colour) are the curves, drawn in a line style per kind
        (`BOUNDARY_KINDS`: fold, grazing, period doubling, end of existence), the
        codimension-two points marked (`CODIM2_STYLE`); the cells keep S, the contours and the
        region words, and no cell-edge line is drawn.

    Notes
    -----
    The paper (Section 5) names D, V, X the domains without a solution satisfying eqs. (10),
    (11) and (13), and U the domain where eq. (22) (stability) fails, without saying which
    letter is which region on its figure: the legend maps causes to letters, not regions.
    """
    from scipy import ndimage

    if boundaries is not None and not int(boundaries.attrs.get("traced", 1)):
        boundaries = None           # not traced (eps = 0): the cell edges, as without them
    if boundaries is not None and boundary_axes(boundaries) != tuple(plane_axes(orbits)):
        raise ValueError(f"the boundaries are traced over {list(boundary_axes(boundaries))} "
                         f"but the orbit map runs over {list(plane_axes(orbits))}: not the "
                         f"same plane")
    if boundaries is not None and custom_plane(orbits):
        a, b = _fixed_of(boundaries), plane_fixed(orbits)
        for key in sorted(set(a) | set(b)):
            if key not in a or key not in b or float(a[key]) != float(b[key]):
                raise ValueError(f"the boundaries hold {key} = {a.get(key, 'unset')} but the "
                                 f"orbit map {b.get(key, 'unset')}: not the same system")
    elif boundaries is not None:
        _same_system(boundaries, orbits, ("the boundaries", "the orbit map"))
    types = [str(t) for t in orbits["type"].values]
    ncols = 3
    nrows = -(-(len(types) + 1) // ncols)
    fig = Figure(figsize=(10.0, 3.3 * nrows))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False).ravel()
    x_name, y_name = plane_axes(orbits)
    x = orbits[x_name].values
    y = orbits[y_name].values
    xe, ye = cell_edges(x), cell_edges(y)
    overview = axes[0]
    two_walls = any(str(t).startswith("(") for t in types)
    law = speed_law(orbits)
    shot = orbits.attrs.get("solver") == "periodic_motions"     # the shooting solver's map
    reasons = TWO_WALL_REASONS if two_walls or shot else REASONS
    reason_cmap = ListedColormap([REASONS[c][0] for c in sorted(REASONS)])
    shaded, regions, panels = None, [], {}
    for i, name in enumerate(types):
        sel = orbits.sel(type=name)
        color = TYPE_COLORS[i % len(TYPE_COLORS)]
        stable = on_plane(sel["n_stable"], orbits).values > 0
        panels[name] = (axes[i + 1], color)
        if boundaries is None:
            overview.add_collection(LineCollection(cell_outline(x, y, stable), colors=[color],
                                                   linewidths=1.3, capstyle="projecting"))
        overview.plot([], [], color=color, lw=1.8, label=motion_title(name))
        ax = axes[i + 1]
        reason = on_plane(sel["reason"], orbits).values
        ax.pcolormesh(xe, ye, np.ma.masked_where(stable, reason).T, cmap=reason_cmap,
                      vmin=min(REASONS) - 0.5, vmax=max(REASONS) + 0.5, rasterized=True)
        S = np.where(stable, on_plane(sel["S"], orbits).values, np.nan)
        # cell by cell (a domain one cell wide included), rasterized in the PDF
        shaded = ax.pcolormesh(xe, ye, np.ma.masked_invalid(S).T, cmap="viridis_r", vmin=0.0,
                               vmax=100.0, rasterized=True)
        if stable.any():
            m, m_lower, n = _type_counts(name)
            # under a speed-dependent law det T is no closed form in eps: no such edge
            cplx = (np.zeros_like(stable) if law else
                    complex_multipliers(sel, m, n, m_lower) & stable)
            real = np.where(cplx, np.nan, S).T
            if np.isfinite(real).any():
                lines = ax.contour(x, y, real, levels=S_LEVELS, colors="k", linewidths=0.5)
                label_contours(ax, lines, "%d")
            if cplx.any() and (stable & ~cplx).any():
                # between stable cells only: the domain's own edge is drawn below
                edge = np.where(stable, cplx, np.nan).T
                ax.contour(x, y, edge, levels=[0.5], colors="0.1",
                           linewidths=0.9, linestyles=":")
        if stable.any() and boundaries is None:
            # where the domain is at least three cells thick: a thinner one is its colour alone
            thick = ndimage.binary_opening(stable, structure=np.ones((3, 3), bool))
            ax.add_collection(LineCollection(cell_outline(x, y, stable, only=thick), colors="k",
                                             linewidths=EDGE_WIDTH, capstyle="projecting",
                                             gid="stable-edge"))
        regions.append((ax, reason, stable))
        ax.set_title(motion_title(name))
    kinds, marked = ([], False) if boundaries is None else _draw_boundaries(overview, panels,
                                                                            boundaries)
    overview.set_title("(a) stable domains")
    spare = axes[len(types) + 1:]
    if spare.size:
        # in the first empty panel's place: inside (a) it hid edges of the domains
        spare[0].axis("off")
        spare[0].legend(*overview.get_legend_handles_labels(), loc="upper left",
                        title="(a): stable domain of", title_fontsize=8, frameon=False)
        spare = spare[1:]
    else:
        overview.legend(loc="lower right")
    for ax in axes:
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])
    for ax in spare:
        ax.set_visible(False)
    for ax in axes:
        ax.set_xlabel(axis_label(orbits[x_name]))
        ax.set_ylabel(axis_label(orbits[y_name]))
        ax.label_outer()
    for ax in axes[len(types) + 1 - ncols:len(types) + 1]:
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel(axis_label(orbits[x_name]))
    present = set(np.unique(orbits["reason"].values).tolist())
    handles = [Patch(facecolor=colour, edgecolor="0.6", label=cause)
               for code, (colour, _, cause) in reasons.items() if code in present]
    if boundaries is None:
        handles.append(Line2D([], [], color="k", lw=EDGE_WIDTH,
                              label="edge of the stable domain (where 3 cells thick or more)"))
    handles += [Line2D([], [], color="k", label=f"edge of the stable domain, "
                                                f"{BOUNDARY_KINDS[kind][1]}", **_kind_style(kind))
                for kind in kinds]
    if marked:
        handles.append(Line2D([], [], mec="k", label="codimension two: two edges meet",
                              **CODIM2_STYLE))
    restitution = (r"(\varepsilon^{m_u}\varepsilon_l^{m_l})^{1/m}" if two_walls
                   else r"\varepsilon")
    if not law:
        handles += [Line2D([], [], color="0.1", lw=0.9, ls=":",
                           label=r"edge of complex multipliers (inside: $S = 100(1 - "
                                 rf"{restitution} e^{{-\zeta z/m}})$, no contours)")]
    if shaded is not None:
        fig.colorbar(shaded, ax=axes[1:].tolist(), label=axis_label(orbits["S"]), shrink=0.8,
                     ticks=np.arange(0, 101, 10))
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7,
               title="the paper's D, V, X: no solution satisfying eqs. (10), (11), (13) "
                     "(white and grey here; it does not say which letter is which region)",
               title_fontsize=7)
    edges = "" if boundaries is None else ";  bold lines: the domains' edges, by kind"
    system = (rf"{_system_text(orbits)};  $f(\tau) = \sin(\beta_f\tau)$"
              if not custom_plane(orbits)
              else rf"{plane_caption(orbits)};  $f(\tau) = A\sin(\beta_f\tau)$")
    _header(fig, "Fig. 16  Parameter domains of stable periodic impact motions",
            rf"{system};  thin lines: contours of the degree of stability $S$ (%)" + edges)
    fig.draw_without_rendering()       # the words are fitted to the panels' final size
    for ax, reason, stable in regions:
        _name_regions(ax, x, y, reason, stable, reasons)
    return fig
