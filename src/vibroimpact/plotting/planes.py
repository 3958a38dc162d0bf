"""A stack of maps side by side: a sweep over a plane's third parameter.

A sweep is a list of studies; when they map one plane and differ in one fixed parameter (the
rms of the noise, say, for maps over (eps, delta)), `map_stack` draws them as one figure: a
column per swept value (its value in the column's title), a row per motion, one colour scale
for every panel. The maps come in as they are written (``results/datasets/{study}_map.nc``);
the swept parameter is the one fixed parameter whose value differs between them
(`swept_parameter`).
"""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from vibroimpact._symbols import PARAMETERS, fixed_caption, format_value, parameter_symbol
from vibroimpact.plotting._common import (_header, _styled, motion_title, on_plane, plane_axes,
                                          plane_fixed)
from vibroimpact.plotting.maps import (PROBABILITY_LEVELS, _finish_axes, _grid,
                                       _plane_forcing_text, few_switches_handle,
                                       label_contours, mark_few_switches,
                                       probability_contours)

__all__ = ["map_stack", "swept_parameter"]

#: Size (inches) of one panel of the stack, and the room of the header and the legend.
PANEL_WIDTH, PANEL_HEIGHT = 3.1, 2.7
HEADER_HEIGHT = 1.9


def swept_parameter(maps):
    """The fixed parameter whose value differs between `maps` (the sweep's), and its values.

    Parameters
    ----------
    maps : sequence of xarray.Dataset
        Map datasets over one plane (`plane_axes`), two or more.

    Returns
    -------
    (str, list of float)

    Raises
    ------
    ValueError
        The maps run over different planes, differ in no fixed parameter, or in more than
        one (a stack sweeps one parameter; the message names them).
    """
    if len(maps) < 2:
        raise ValueError(f"a stack needs two maps or more, got {len(maps)}")
    planes = {plane_axes(ds) for ds in maps}
    if len(planes) > 1:
        raise ValueError(f"the maps of a stack run over one plane; these run over "
                         f"{sorted(list(p) for p in planes)}")
    fixed = [plane_fixed(ds) for ds in maps]
    keys = sorted(set().union(*fixed))
    differ = [k for k in keys
              if len({format_value(f.get(k, "unset")) for f in fixed}) > 1]
    if not differ:
        # a parameter of the record, not of the map (the noise's seed; the rms when it is an
        # axis): the sweep's own attribute, sweep_<name>, says which
        swept = [{k[len("sweep_"):]: v for k, v in ds.attrs.items()
                  if k.startswith("sweep_") and k != "sweep_index"} for ds in maps]
        names = sorted(set().union(*swept))
        differ = [k for k in names if all(k in s for s in swept)
                  and len({format_value(s[k]) for s in swept}) > 1]
        if len(differ) == 1:
            return differ[0], [s[differ[0]] for s in swept]
        raise ValueError(f"the maps differ in no fixed parameter (fixed: {keys}) and in "
                         f"{len(differ)} sweep attributes ({differ}): nothing is swept")
    if len(differ) > 1:
        raise ValueError(f"the maps differ in {differ}: a stack sweeps one parameter")
    name = differ[0]
    missing = [k for k, f in enumerate(fixed) if name not in f]
    if missing:
        raise ValueError(f"map {missing[0]} does not give the swept parameter {name!r}")
    return name, [f[name] for f in fixed]


def _symbol(name):
    """A parameter's symbol in mathtext (another key of a fixed dict: its name)."""
    return parameter_symbol(name) if name in PARAMETERS else name


def _swept_title(name, value):
    return f"{_symbol(name)} = {format_value(value)}"


@_styled
def map_stack(*maps, motions=None, levels=PROBABILITY_LEVELS):
    """Fig. 15 maps of a sweep side by side: one column per swept value, one row per motion.

    Parameters
    ----------
    *maps : xarray.Dataset
        Map datasets over one plane that differ in one fixed parameter (`swept_parameter`),
        in any order (drawn by increasing swept value).
    motions : sequence of str, optional
        Motions drawn (``"1/1"`` ...); default every motion all the maps have.
    levels : sequence of float
        Probability contours (%), as `vibroimpact.plotting.fig15`.

    Returns
    -------
    matplotlib.figure.Figure
        Filled bands of the probability (%) on one colour scale for every panel (one colour
        bar), its contours labelled where apart and each cliff one line, as in Fig. 15;
        whole cells hatched where the record switched too few times, dots where the cap
        stopped a cell before the target precision. The swept value heads
        each column, the motion each row; the header names the plane, the sweep and what
        every map holds fixed.
    """
    name, values = swept_parameter(maps)
    order = np.argsort([float(v) for v in values], kind="stable")
    maps = [maps[k] for k in order]
    values = [values[k] for k in order]
    shared = [str(m) for m in maps[0]["motion"].values
              if all(str(m) in ds["motion"].values for ds in maps)]
    if motions is None:
        motions = shared
    unknown = [m for m in motions if m not in shared]
    if not motions or unknown:
        raise ValueError(f"motions {list(unknown or motions)} are not in every map; the "
                         f"maps share {shared}")
    nrows, ncols = len(motions), len(maps)
    fig = Figure(figsize=(PANEL_WIDTH * ncols + 1.3, PANEL_HEIGHT * nrows + HEADER_HEIGHT))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False)
    fill_levels = [0.0, *levels, 100.0]
    shaded, few_any, short_any = None, False, False
    for c, (ds, value) in enumerate(zip(maps, values)):
        x, y = _grid(ds)
        few = on_plane(ds["few_switches"], ds).values.astype(bool)
        few_any |= bool(few.any())
        short = ~on_plane(ds["reached"], ds).values.astype(bool)
        short_any |= bool(short.any())
        for r, motion in enumerate(motions):
            ax = axes[r, c]
            p = 100.0 * on_plane(ds["probability"].sel(motion=motion), ds).values
            shaded = ax.contourf(x, y, p.T, levels=fill_levels, cmap="Blues", vmin=-10,
                                 vmax=100)
            lines, cliff = probability_contours(ax, x, y, p, levels, colors="k",
                                                linewidths=0.5)
            ax.add_collection(LineCollection(cliff, colors="k", linewidths=1.0, gid="cliff"),
                              autolim=False)
            label_contours(ax, lines, "%d", avoid=cliff)
            mark_few_switches(ax, x, y, few)
            if short.any():
                i, j = np.nonzero(short)
                ax.plot(x[i], y[j], ls="none", marker=".", ms=1.5, color="C3")
            ax.set_title(f"{motion_title(motion)},  {_swept_title(name, value)}", fontsize=9)
        _finish_axes(axes[:, c], ds)
    fig.colorbar(shaded, ax=axes.ravel().tolist(), label="probability of the motion (%)",
                 shrink=0.7, pad=0.02, aspect=30)
    handles = [few_switches_handle(maps[0])] if few_any else []
    if short_any:
        handles.append(Line2D([], [], ls="none", marker=".", color="C3",
                              label="target precision not reached (cap)"))
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7)
    common = {k: v for k, v in plane_fixed(maps[0]).items() if k != name}
    x_name, y_name = plane_axes(maps[0])
    plane = ", ".join(_symbol(a) for a in (x_name, y_name))
    sweep = ", ".join(format_value(v) for v in values)
    _header(fig, f"Probability of the impact motions over the ({plane}) plane, "
                 f"{_symbol(name)} swept",
            f"{_symbol(name)} = {sweep};  fixed: {fixed_caption(common) or 'nothing else'};  "
            f"{_plane_forcing_text(maps[0])}")
    return fig
