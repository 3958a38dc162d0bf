"""Where the starts go under the harmonic force alone: basins of attraction and Lyapunov maps.

Two maps over the Fig. 15 grid of (1/beta, delta), both from many starting states per cell
under ``sin(beta_f tau)`` alone: the share of starts that settle on each periodic impact
motion (:func:`basins`, the counterpart of Fig. 15 without noise, beside the stable domains
of Fig. 16), and the largest Lyapunov exponent with the class of motion each cell settles to
(:func:`lyapunov`).
"""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.colors import BoundaryNorm, ListedColormap, TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter

from vibroimpact.plotting._common import (_attr, _header, _same_system, _styled, _system_text,
                                          axis_label, custom_plane, motion_title, plane_axes,
                                          plane_caption)
from vibroimpact.plotting.maps import cell_edges, cell_outline, cell_rectangles, label_contours

#: The basin fraction (%) is filled in bands of `BASIN_BAND` and its labelled lines drawn
#: at `BASIN_LEVELS`: coarser than Fig. 15's 10 % lines, since with 64 starts a share of
#: 50 % is known only to about +-13 pp (95 %).
BASIN_BAND = 10
BASIN_LEVELS = (20, 50, 80)
#: The lines follow the share averaged over this many cells each way (the cells without a
#: stable orbit left out): one cell's share scatters by up to +-13 pp, its lines would
#: trace that scatter. The fill stays cell by cell.
LINE_SMOOTHING = 3
#: Colours of the basin maps: the fraction on part of Blues (its pale end reads as white),
#: the cells where the solver has no stable orbit of the type, the outline of Fig. 16's
#: stable domain, and the cells that settled on a type the solver has no stable orbit of.
BASIN_CMAP_SPAN = (0.12, 1.0)
NO_ORBIT_COLOR = "0.9"
DOMAIN_COLOR = "#D55E00"
STRAY_COLOR = "#CC79A7"
#: The "other" panel outlines the cells where at least this share of the starts settles on
#: the wall-free response (the linear response that never reaches the wall), in this colour.
WALL_FREE_SHARE = 0.5
WALL_FREE_LINE_COLOR = "#F0E442"
#: Share (%) of starts on a type's impact-stick variant drawn as a dashed line, its colour.
STICK_LEVEL = 10
STICK_LINE_COLOR = "#009E73"
#: The classes of a cell's starts (a dataset's ``class`` coordinate and ``cell_class``
#: codes 0-5, `vibroimpact.attractors.CLASSES`): colour and words. The wall-free response is
#: the linear steady response q sin(beta tau - phi), q < delta, that never reaches the wall.
CLASSES = {
    "listed": ("#0072B2", "periodic, of a type of Fig. 16"),
    "periodic_other": ("#56B4E9", "periodic impact motion of another type"),
    "sticking": ("#8C6D31", "sticking to the wall"),
    "chaotic": ("#D55E00", "chaotic"),
    "undecided": ("0.72", "undecided"),
    "wall_free": ("#C9E4B4", r"wall-free response ($q < \delta$)"),
}
#: Short names of the classes (legend of the markers of panel (a)).
CLASS_SHORT = {"listed": "a Fig. 16 type", "periodic_other": "another periodic",
               "sticking": "sticking", "chaotic": "chaotic", "undecided": "undecided",
               "wall_free": "wall-free"}
#: Colour of the cells with an exponent of -inf (every start sticks) and of those without a
#: value (NaN).
STICK_COLOR = CLASSES["sticking"][0]
NAN_COLOR = "0.55"
#: An exponent within this many standard errors of 0 has no resolved sign (dotted cell).
SIGN_STDERRS = 2.0
#: A class holding less than this share of the cell's starts is hatched (a mixed cell).
MIXED_SHARE = 0.5
MIXED_HATCH = "////"
#: Lyapunov colour map: diverging, centred at 0 (stable blue, chaotic red); each side ends at
#: this quantile of its exponents' magnitudes, so that a few outlying cells (a finite-time
#: estimate) do not wash out the rest, rounded up to a value of `LYAPUNOV_ENDS` (times a
#: power of ten); beyond it the end colour, an arrow on the colour bar. Each half of the bar
#: has its own scale, ticked at 0, half its end and its end (evenly spaced on the bar).
LYAPUNOV_CMAP = "RdBu_r"
LYAPUNOV_QUANTILE = 0.99
LYAPUNOV_ENDS = (1.0, 1.2, 1.6, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0)
#: Where the start holding a cell's largest exponent is not of the cell's class (a coexisting
#: attractor of fewer starts sets the colour of panel (a)): a marker in that class's colour.
OWNER_MARKER = dict(marker="D", ms=2.2, mec="k", mew=0.3, ls="none")


def _grid(ds):
    """Cell centres along the map's two axes (`plane_axes`: the paper's (1/beta_f, delta),
    or the plane a dataset names)."""
    x, y = plane_axes(ds)
    return ds[x].values, ds[y].values


def _params_text(ds):
    """The header's system and force: the paper's plane's words, or on a named plane what it
    holds fixed (`plane_caption`) and the force ``A sin(beta_f tau)``."""
    if not custom_plane(ds):
        return f"{_system_text(ds)};  " + r"$f(\tau) = \sin(\beta_f\tau)$"
    return f"{plane_caption(ds)};  " + r"$f(\tau) = A\sin(\beta_f\tau)$ alone"


def _finish_axes(axes, ds, bottom):
    """Cell-edge limits, labels on the outer panels, x labels on the `bottom` panels."""
    x, y = _grid(ds)
    x_name, y_name = plane_axes(ds)
    xe, ye = cell_edges(x), cell_edges(y)
    for ax in axes:
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])
        ax.set_xlabel(axis_label(ds[x_name]))
        ax.set_ylabel(axis_label(ds[y_name]))
        ax.label_outer()
    for ax in bottom:
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel(axis_label(ds[x_name]))


def _smoothed(p):
    """`p` averaged over `LINE_SMOOTHING` x `LINE_SMOOTHING` cells, NaN cells left out
    (and left NaN)."""
    from scipy import ndimage     # scipy in the map figures' jobs only

    has = np.isfinite(p)
    size = (LINE_SMOOTHING, LINE_SMOOTHING)
    total = ndimage.uniform_filter(np.where(has, p, 0.0), size, mode="constant")
    weight = ndimage.uniform_filter(has.astype(float), size, mode="constant")
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(has, total / weight, np.nan)


def _basin_colormap():
    import matplotlib

    bands = np.arange(0, 100 + BASIN_BAND, BASIN_BAND)
    cmap = ListedColormap(matplotlib.colormaps["Blues"](
        np.linspace(*BASIN_CMAP_SPAN, bands.size - 1)))
    return cmap, BoundaryNorm(bands, cmap.N)


def _pct(value):
    return f"{100.0 * value:.2g} %" if value < 0.1 else f"{100.0 * value:.0f} %"


def _composition_text(ds):
    """What the starts that settle on none of the listed types do, over the whole map."""
    if "class_fraction" not in ds:
        return None
    words = _class_words(ds)
    if "other_class_fraction" in ds:        # a two-wall study's motions: any class may be other
        share = ds["other_class_fraction"].mean(plane_axes(ds))
        parts = [f"{words.get(str(c), str(c))}: {_pct(float(share.sel({'class': c})))}"
                 for c in ds["class"].values]
        return _wrapped("other, of all starts over the map:  ", parts)
    share = ds["class_fraction"].mean(plane_axes(ds))
    parts = [f"{words.get(str(c), str(c))}: {_pct(float(share.sel({'class': c})))}"
             for c in ds["class"].values if str(c) != "listed"]
    return _wrapped("other, of all starts over the map:  ", parts)


#: Characters of a legend title's line: the figure is 10 in wide, the title 7 pt (the default
#: grid's one-line title, 189 characters, fits).
TITLE_WIDTH = 200


def _wrapped(head, parts):
    """``head`` and ``parts`` joined by ``";  "``, a new line before a part that would pass
    `TITLE_WIDTH` (the one-line title of a short list stays as it was)."""
    lines = [head]
    for k, part in enumerate(parts):
        sep = "" if k == 0 else ";  "
        if k and len(lines[-1]) + len(sep) + len(part) > TITLE_WIDTH:
            lines[-1] += ";"
            lines.append(part)
        else:
            lines[-1] += sep + part
    return "\n".join(lines)


@_styled
def basins(basins, orbits=None):
    """Basin of attraction of each periodic impact motion: share of starts settling on it.

    Parameters
    ----------
    basins : xarray.Dataset
        ``results/orbits/{name}_basins.nc``: ``fraction``, ``fraction_lo``, ``fraction_hi``,
        ``n_stable``, ``stick_fraction`` over ``(motion, inv_beta, delta)`` (the motions the
        orbit solver lists, and ``"other"``), ``class_fraction`` over ``(class, inv_beta,
        delta)``; global attributes ``zeta``, ``eps``, ``n_starts``, ``box``.
    orbits : xarray.Dataset, optional
        The orbit map of Fig. 16 of the same system: its stable domain of each type is
        outlined on the type's panel.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per motion type: cell by cell, the share (%) of the starts that settle on
        a stable periodic orbit of the type, filled in `BASIN_BAND` bands, with labelled
        lines at `BASIN_LEVELS` of the share averaged over neighbouring cells
        (`LINE_SMOOTHING`); cells where the solver has no stable orbit of the type grey
        (`NO_ORBIT_COLOR`), dotted if starts settled on the type there all the same; the
        dashed line where `STICK_LEVEL` % of the starts settle on the type's impact-stick
        variant; with `orbits`, Fig. 16's stable domain outlined. A last panel gives the
        share that settles on none of them ("other"); the legend's title says what those
        starts do over the whole map (``class_fraction``), and the "other" panel outlines
        the cells where `WALL_FREE_SHARE` of the starts settle on the wall-free response.

    Notes
    -----
    Each share is a count out of ``n_starts`` starting states; the header states the widest
    95 % Clopper-Pearson interval of the map (``fraction_lo``, ``fraction_hi``).
    """
    if orbits is not None:
        _same_system(basins, orbits, ("the basins", "the orbit map"))
    motions = [str(m) for m in basins["motion"].values]
    types = [m for m in motions if m != "other"]
    panels = types + (["other"] if "other" in motions else [])
    ncols = 3
    nrows = -(-len(panels) // ncols)
    fig = Figure(figsize=(10.0, 3.3 * nrows + 1.0))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False).ravel()
    x, y = _grid(basins)
    xe, ye = cell_edges(x), cell_edges(y)
    cmap, norm = _basin_colormap()
    shown = dict(no_orbit=False, stray=False, stick=False, domain=False, wall_free=False)
    shaded = None
    for ax, name in zip(axes, panels):
        sel = basins.sel(motion=name)
        p = 100.0 * np.asarray(sel["fraction"].values, dtype=float)
        # a two-wall study's own motions have no closed-form solver count: no grey cells
        has = (np.asarray(sel["n_stable"].values) > 0 if name != "other" and "n_stable" in sel
               else np.isfinite(p))
        if name != "other" and (~has).any():
            ax.pcolormesh(xe, ye, np.ma.masked_where(has, np.ones_like(p)).T,
                          cmap=ListedColormap([NO_ORBIT_COLOR]), rasterized=True,
                          gid="no-orbit")
            shown["no_orbit"] = True
        drawn = np.where(has, p, np.nan)
        shaded = ax.pcolormesh(xe, ye, np.ma.masked_invalid(drawn).T, cmap=cmap, norm=norm,
                               rasterized=True, gid="fraction")
        smooth = _smoothed(drawn)
        if np.isfinite(smooth).any() and np.nanmax(smooth) > min(BASIN_LEVELS):
            lines = ax.contour(x, y, smooth.T, levels=BASIN_LEVELS, colors="k",
                               linewidths=0.6)
            label_contours(ax, lines, "%d")
        stray = ~has & (p > 0)
        if stray.any():
            i, j = np.nonzero(stray)
            ax.plot(x[i], y[j], ls="none", marker=".", ms=2.5, color=STRAY_COLOR,
                    gid="stray")
            shown["stray"] = True
        if name != "other" and "stick_fraction" in sel:
            stick = 100.0 * np.nan_to_num(np.asarray(sel["stick_fraction"].values, float))
            if stick.max() >= STICK_LEVEL:
                ax.contour(x, y, stick.T, levels=[STICK_LEVEL], colors=STICK_LINE_COLOR,
                           linewidths=1.2, linestyles="--")
                shown["stick"] = True
        if orbits is not None and name in [str(t) for t in orbits["type"].values]:
            o = orbits.sel(type=name)
            stable = np.asarray(o["n_stable"].values) > 0
            ax.add_collection(LineCollection(
                cell_outline(o["inv_beta"].values, o["delta"].values, stable),
                colors=DOMAIN_COLOR, linewidths=1.1, capstyle="projecting",
                gid="stable-domain"), autolim=False)
            shown["domain"] |= bool(stable.any())
        if (name == "other" and "class_fraction" in basins
                and "wall_free" in basins["class"].values):
            # the wall-free response, a motion of its own among "other"
            free = np.asarray(basins["class_fraction"].sel({"class": "wall_free"}).values,
                              dtype=float) >= WALL_FREE_SHARE
            if free.any():
                ax.add_collection(LineCollection(cell_outline(x, y, free),
                                                 colors=WALL_FREE_LINE_COLOR, linewidths=1.6,
                                                 capstyle="projecting", gid="wall-free"),
                                  autolim=False)
                shown["wall_free"] = True
        ax.set_title("other: none of these types" if name == "other" else motion_title(name))
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    _finish_axes(axes[:len(panels)], basins, axes[max(len(panels) - ncols, 0):len(panels)])
    fig.colorbar(shaded, ax=axes[:len(panels)].tolist(), shrink=0.8,
                 label="starts settling on the motion (%)", ticks=norm.boundaries)
    handles = []
    if shown["no_orbit"]:
        handles.append(Patch(facecolor=NO_ORBIT_COLOR, edgecolor="0.6",
                             label="no stable orbit of the type (orbit solver)"))
    if shown["stray"]:
        handles.append(Line2D([], [], ls="none", marker=".", ms=5, color=STRAY_COLOR,
                              label="starts settled on the type where the solver has no "
                                    "stable orbit of it"))
    if shown["domain"]:
        handles.append(Line2D([], [], color=DOMAIN_COLOR, lw=1.1,
                              label="stable domain of Fig. 16 (cell edges of its map)"))
    if shown["wall_free"]:
        handles.append(Line2D([], [], color=WALL_FREE_LINE_COLOR, lw=1.6,
                              label=f"other: >= {100 * WALL_FREE_SHARE:.0f} % of starts on the "
                                    + (WALL_FREE_TWO_WALLS[:-1] + ", no impact)"
                                       if _two_walls(basins) else
                                       r"wall-free response ($q < \delta$, no impact)")))
    if shown["stick"]:
        handles.append(Line2D([], [], color=STICK_LINE_COLOR, lw=1.2, ls="--",
                              label=f"{STICK_LEVEL} % of starts on the type's impact-stick "
                                    "variant"))
    handles.append(Line2D([], [], color="k", lw=0.6,
                          label=f"share of starts {', '.join(map(str, BASIN_LEVELS))} %, "
                                f"averaged over {LINE_SMOOTHING} x {LINE_SMOOTHING} cells"))
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7,
               title=_composition_text(basins), title_fontsize=7)
    _header(fig, "Basins of attraction of the periodic impact motions",
            f"{_params_text(basins)}\n{_starts_text(basins)}")
    return fig


def _starts_text(basins):
    """``N = 64 starts per cell (box); 95 % Clopper-Pearson intervals up to x pp wide``: the
    width, not a half-width (an interval of 0 or N of N starts is one-sided: [0, x])."""
    n = int(_attr(basins, "n_starts"))
    text = (f"{n} starts per cell, a scrambled Sobol sample, the same in every cell:\n"
            f"{_attr(basins, 'box')}")
    if "fraction_lo" in basins and "fraction_hi" in basins:
        width = np.nanmax(np.asarray(basins["fraction_hi"] - basins["fraction_lo"]))
        text += ("\n" + f"a share's 95 % Clopper-Pearson interval: up to {100.0 * width:.0f} "
                 f"pp wide")
    return text


def _two_walls(ds):
    """Whether ``ds`` is over a plane study with a second wall (``gap`` on an axis or fixed)."""
    return "axes" in ds.attrs and ("gap" in plane_axes(ds) or "gap" in ds.attrs)


def _class_words(ds):
    """The words of `CLASSES` for the system of ``ds``: the paper's grid has Fig. 16 beside
    it; a plane study lists the types of its attractors block, found with a second wall on
    either wall (`vibroimpact.attractor_map`), and its wall-free response clears both walls
    (``-q > delta - gap``)."""
    words = {k: w for k, (_, w) in CLASSES.items()}
    if "axes" not in ds.attrs:
        return words
    if _two_walls(ds):
        words["listed"] = "periodic, a listed one-wall orbit (either wall)"
        words["wall_free"] = WALL_FREE_TWO_WALLS
    else:
        words["listed"] = "periodic, of a listed type (m/n)"
    return words


#: The wall-free response between two walls: it reaches neither.
WALL_FREE_TWO_WALLS = r"wall-free ($q < \delta$, $-q > \delta - g$)"


def _class_names(ds, name="cell_class"):
    """The classes of the codes of ``ds[name]``: its ``flag_meanings`` in order when it has
    them (each one of `CLASSES`; a dataset written before the wall-free class has codes 0-4),
    else `CLASSES` in order."""
    meanings = ds[name].attrs.get("flag_meanings")
    names = list(CLASSES) if meanings is None else str(meanings).split()
    unknown = [n for n in names if n not in CLASSES]
    if unknown:
        raise ValueError(f"{name} has the flag_meanings {meanings!r}; this figure knows the "
                         f"classes {list(CLASSES)}, not {unknown}")
    words = _class_words(ds)
    return names, [words[n] for n in names]


def _short(ds, name):
    """`CLASS_SHORT` of a class, "a listed type" where ``ds`` has no Fig. 16 beside it."""
    if name == "listed" and "axes" in ds.attrs:
        return "a listed type"
    return CLASS_SHORT[name]


def _tick_text(value, _pos=None):
    """A colour-bar tick: 3 significant digits, a true minus sign."""
    return f"{value:.3g}".replace("-", "\N{MINUS SIGN}")


def _nice_end(value):
    """The smallest of `LYAPUNOV_ENDS` times a power of ten that is >= `value` (> 0)."""
    power = 10.0 ** np.floor(np.log10(value))
    for step in LYAPUNOV_ENDS:
        if step * power >= value * (1.0 - 1e-12):
            return step * power
    return 10.0 * power


def _lyapunov_norm(finite):
    """Diverging norm centred at 0 from the finite exponents, each side ending at the
    `LYAPUNOV_QUANTILE` of its magnitudes rounded up (`_nice_end`), the colour bar's
    ``extend`` and its ticks (each side's end, half of it, 0)."""
    ends, sides = [], []
    for side in (-finite[finite < 0.0], finite[finite > 0.0]):
        ends.append(float(np.quantile(side, LYAPUNOV_QUANTILE)) if side.size else 0.0)
        sides.append(side)
    floor = 0.05 * max(*ends, 1e-12)        # a side without values keeps a sliver of colour
    ends = [_nice_end(max(end, floor)) for end in ends]
    beyond = [bool(side.size) and float(side.max()) > end for side, end in zip(sides, ends)]
    norm = TwoSlopeNorm(vcenter=0.0, vmin=-ends[0], vmax=ends[1])
    extend = {(False, False): "neither", (True, False): "min", (False, True): "max",
              (True, True): "both"}[tuple(beyond)]
    ticks = [-ends[0], -0.5 * ends[0], 0.0, 0.5 * ends[1], ends[1]]
    return norm, extend, ticks


@_styled
def lyapunov(lyapunov):
    """Largest Lyapunov exponent (a) and the class of motion (b) of each cell.

    Parameters
    ----------
    lyapunov : xarray.Dataset
        ``results/orbits/{name}_lyapunov.nc``: ``lyapunov`` (per unit time tau; -inf where
        every start sticks), ``lyapunov_stderr``, ``cell_class`` (int, codes of its
        ``flag_meanings``, `CLASSES`), ``impact_rate`` over ``(inv_beta, delta)``,
        ``class_fraction`` over ``(class, inv_beta, delta)``; optionally ``lyapunov_class``
        (the class of the start holding the largest exponent); global attributes ``zeta``,
        ``eps``.

    Returns
    -------
    matplotlib.figure.Figure
        (a) The exponent on a diverging map centred at 0 (`LYAPUNOV_CMAP`, each side
        scaled to its own range up to `LYAPUNOV_QUANTILE`, rounded up: red chaotic, blue
        settling; the bar ticked at both ends, their halves and 0), a diamond in the class's
        colour where the largest exponent belongs to a start of another class than the
        cell's (``lyapunov_class``: a coexisting motion of fewer starts),
        cells of -inf in the sticking colour (`STICK_COLOR`), cells without a value grey; a
        dot where the exponent lies within `SIGN_STDERRS` standard errors of 0 (its sign
        unresolved); the edge of the region where no start impacts (``impact_rate`` 0: the
        wall-free response, exponent -zeta). (b) The class of each cell (`CLASSES`),
        hatched where that class holds less than `MIXED_SHARE` of the cell's starts
        (``class_fraction``).
    """
    x, y = _grid(lyapunov)
    xe, ye = cell_edges(x), cell_edges(y)
    fig = Figure(figsize=(10.0, 6.4))
    FigureCanvasAgg(fig)
    ax_l, ax_c = fig.subplots(1, 2, sharex=True, sharey=True)
    lam = np.asarray(lyapunov["lyapunov"].values, dtype=float)
    finite = np.isfinite(lam)
    sticks = np.isneginf(lam)
    missing = np.isnan(lam)
    handles_l = []
    if missing.any():
        ax_l.pcolormesh(xe, ye, np.ma.masked_where(~missing, np.ones_like(lam)).T,
                        cmap=ListedColormap([NAN_COLOR]), rasterized=True, gid="nan")
        handles_l.append(Patch(facecolor=NAN_COLOR, edgecolor="0.6", label="no value"))
    if sticks.any():
        ax_l.pcolormesh(xe, ye, np.ma.masked_where(~sticks, np.ones_like(lam)).T,
                        cmap=ListedColormap([STICK_COLOR]), rasterized=True, gid="sticking")
        handles_l.append(Patch(facecolor=STICK_COLOR, edgecolor="0.6",
                               label=r"every start sticks: $-\infty$"))
    norm, extend, ticks = _lyapunov_norm(lam[finite])
    shaded = ax_l.pcolormesh(xe, ye, np.ma.masked_where(~finite, np.where(finite, lam, 0.0)).T,
                             cmap=LYAPUNOV_CMAP, norm=norm, rasterized=True, gid="lyapunov")
    if "lyapunov_stderr" in lyapunov:
        se = np.asarray(lyapunov["lyapunov_stderr"].values, dtype=float)
        with np.errstate(invalid="ignore"):
            unresolved = finite & np.isfinite(se) & (np.abs(lam) < SIGN_STDERRS * se)
        if unresolved.any():
            i, j = np.nonzero(unresolved)
            ax_l.plot(x[i], y[j], ls="none", marker=".", ms=2.0, color="k", gid="unresolved")
            handles_l.append(Line2D([], [], ls="none", marker=".", ms=4, color="k",
                                    label=rf"sign unresolved: within {SIGN_STDERRS:g} s.e. "
                                          "of 0"))
    if "impact_rate" in lyapunov:
        # no impact with a finite exponent: the wall-free response (not the mass at rest
        # on the wall, whose exponent is -inf)
        quiet = ((np.asarray(lyapunov["impact_rate"].values, dtype=float) == 0.0)
                 & np.isfinite(np.asarray(lyapunov["lyapunov"].values, dtype=float)))
        if quiet.any() and not quiet.all():
            ax_l.add_collection(LineCollection(cell_outline(x, y, quiet), colors="0.2",
                                               linewidths=0.9, gid="no-impact"),
                                autolim=False)
            handles_l.append(Line2D([], [], color="0.2", lw=0.9,
                                    label=r"edge of no impact (wall-free response, "
                                          r"$-\zeta$)"))
    names, words = _class_names(lyapunov)
    code = np.asarray(lyapunov["cell_class"].values).astype(int)
    if "lyapunov_class" in lyapunov:
        # the start holding the cell's largest exponent settled elsewhere than most starts:
        # the colour of (a) is that coexisting attractor's exponent
        own_names, _ = _class_names(lyapunov, "lyapunov_class")
        owner = np.asarray(lyapunov["lyapunov_class"].values).astype(int)
        for k, name in enumerate(own_names):
            here = finite & (owner == k) & (np.array(names)[np.clip(code, 0, len(names) - 1)]
                                            != name)
            if here.any():
                i, j = np.nonzero(here)
                ax_l.plot(x[i], y[j], color=CLASSES[name][0], gid=f"owner-{name}",
                          **OWNER_MARKER)
                handles_l.append(Line2D([], [], color=CLASSES[name][0], **OWNER_MARKER,
                                        label=f"largest from fewer starts: "
                                              f"{_short(lyapunov, name)} "
                                              f"({int(here.sum())} cells)"))
    bar = fig.colorbar(shaded, ax=ax_l, shrink=0.85, extend=extend, ticks=ticks,
                       format=FuncFormatter(_tick_text),
                       label="largest Lyapunov exponent (per unit $\\tau$)\n"
                             "each half of the bar to its own scale")
    bar.minorticks_off()
    ax_l.set_title("(a) largest Lyapunov exponent")

    colors = [CLASSES[n][0] for n in names]
    ax_c.pcolormesh(xe, ye, code.T, cmap=ListedColormap(colors), vmin=-0.5,
                    vmax=len(names) - 0.5, rasterized=True, gid="cell-class")
    handles_c = [Patch(facecolor=c, edgecolor="0.6",
                       label=f"{w} ({_pct(np.mean(code == k))})")
                 for k, (c, w) in enumerate(zip(colors, words)) if (code == k).any()]
    if "class_fraction" in lyapunov:
        cf = np.asarray(lyapunov["class_fraction"].sel({"class": names}).values, dtype=float)
        own = np.take_along_axis(cf, np.clip(code, 0, cf.shape[0] - 1)[None], axis=0)[0]
        mixed = own < MIXED_SHARE
        if mixed.any():
            ax_c.add_collection(PatchCollection(cell_rectangles(x, y, mixed), gid="mixed",
                                                facecolor="none", edgecolor="0.15",
                                                hatch=MIXED_HATCH, linewidth=0.0),
                                autolim=False)
            handles_c.append(Patch(facecolor="white", edgecolor="0.15", hatch=MIXED_HATCH,
                                   label=f"its class holds < {100 * MIXED_SHARE:.0f} % of "
                                         "the starts"))
    ax_c.set_title("(b) what the starts settle to")
    _finish_axes([ax_l, ax_c], lyapunov, [ax_l, ax_c])
    below = dict(loc="upper center", bbox_to_anchor=(0.5, -0.13), fontsize=7)
    if handles_l:
        ax_l.legend(handles=handles_l, **below)
    ax_c.legend(handles=handles_c, ncols=2, title="class of the cell (share of the cells)",
                title_fontsize=7, **below)
    n = lyapunov.attrs.get("n_starts")
    starts = "" if n is None else f";  {int(n)} starts per cell, the largest exponent of them"
    _header(fig, "Largest Lyapunov exponent and the motion the starts settle to",
            f"{_params_text(lyapunov)}{starts}")
    return fig

