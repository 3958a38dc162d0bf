"""The event figures of a two-wall study (a clearance between two stops): Figs. 7-9 and 14
drawn per wall.

A two-wall events dataset (``docs/datasets.md``, "Two walls") carries the statistics of each
wall along its ``wall`` dimension (``upper``: the wall at x = delta, hit from below;
``lower``: the wall at x = delta - gap, hit from above). The paper's figure functions
(`plotting.random.fig07` ...) hand such a dataset here: each density figure gets one panel
per wall, the means one colour per wall.
"""
from __future__ import annotations

import numpy as np

from vibroimpact.plotting._common import (
    _events_params, _figure, _header, _num, _panel_tag, _require, _density_deltas, axis_label,
    family_styles, note_on_axes)

#: How the figures name each wall (the ``wall`` coordinate's values).
WALL_NAMES = {"upper": "upper wall, x = $\\delta$ (hit from below)",
              "lower": "lower wall, x = $\\delta - g$ (hit from above)"}
#: Colour and marker of each wall in the means figure.
WALL_STYLES = {"upper": dict(color="C0", marker="o", ls="-"),
               "lower": dict(color="C3", marker="s", ls="--")}
#: Densities below this fraction of the panel's peak are not drawn on the log axis.
DENSITY_DECADES = 1e-5


def two_walls(ds):
    """Whether a dataset is a two-wall study's (it has the ``wall`` dimension)."""
    return "wall" in ds.dims


def wall_density_figure(events, i_beta, quantity, title, density_delta=None):
    """One density panel per wall of ``wall_{quantity}_density``, one curve per density delta.

    Parameters
    ----------
    events : xarray.Dataset
        A two-wall events dataset (``wall`` dimension).
    i_beta : int
        Index of the inv_beta row drawn.
    quantity : {"v_after", "interval"}
        The velocity after impact or the interval between collisions at the same wall.
    title : str
        The figure's title.
    density_delta : sequence of float, optional
        Plays drawn (nearest values of the dataset); default the largest seven.

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked log-density axes (upper wall, lower wall), each curve with a band of
        +-2 batch-means standard errors; the legend gives each play's collisions at that
        wall.
    """
    var = f"wall_{quantity}_density"
    ds = events.isel(inv_beta=i_beta)
    density = _require(ds, var, "this figure")
    stderr = ds.get(f"{var}_stderr")
    x = density.dims[-1]
    centres = np.asarray(ds[x], dtype=float)
    index = _density_deltas(events, density_delta)
    styles = family_styles(len(index))
    fig, axes = _figure(len(ds["wall"]), sharex=True)
    for ax, wall in zip(axes, ds["wall"].values):
        wall = str(wall)
        top, x_end = 0.0, centres[0]
        for style, k in zip(styles, index):
            cell = ds.isel(delta=k).sel(wall=wall)
            y = np.asarray(cell[var], dtype=float)
            n = int(cell["wall_n_collisions"])
            shown = y > 0.0
            label = (rf"$\delta$ = {_num(cell['delta'])}  "
                     f"({n:,} collision{'' if n == 1 else 's'})")
            ax.plot(centres, np.where(shown, y, np.nan), color=style["color"], ls=style["ls"],
                    label=label)
            if stderr is not None and shown.any():
                se = np.asarray(cell[f"{var}_stderr"], dtype=float)
                ax.fill_between(centres, np.where(shown, np.maximum(y - 2 * se, y * 1e-3),
                                                  np.nan),
                                np.where(shown, y + 2 * se, np.nan), color=style["color"],
                                alpha=0.15, lw=0, gid="band")
            if shown.any():
                top = max(top, float(y.max()))
                x_end = max(x_end, float(centres[shown].max()))
        ax.set_yscale("log")
        if top > 0.0:
            ax.set_ylim(top * DENSITY_DECADES, top * 3.0)
            ax.set_xlim(0.0, x_end * 1.05)
        else:
            note_on_axes(ax, "no collision at this wall at any $\\delta$ drawn")
        ax.set_ylabel(_density_label(quantity))
        _panel_tag(ax, WALL_NAMES.get(wall, wall))
        ax.legend(loc="upper right", fontsize="small")
    axes[-1].set_xlabel(axis_label(ds[x]))
    _header(fig, title, _events_params(events, i_beta, (quantity,)))
    return fig


def _density_label(quantity):
    return {"v_after": "density of the velocity\nafter impact",
            "interval": "density of the interval\nbetween collisions at the wall"
            }[quantity]


def wall_means_figure(events, title, i_beta=0):
    """Fig. 9 per wall: the mean velocity after impact and the mean interval between
    collisions at each wall against delta, with their 95 % intervals.

    Parameters
    ----------
    events : xarray.Dataset
        A two-wall events dataset: ``wall_v_after_mean(_lo, _hi)``,
        ``wall_interval_mean(_lo, _hi)``, ``wall_n_collisions`` over ``(inv_beta, delta,
        wall)``.
    title : str
        The figure's title.
    i_beta : int
        Index of the inv_beta row drawn.

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked axes sharing delta, one colour per wall; (b) on a log scale. Plays with
        no collision at a wall have no point for it.
    """
    ds = events.isel(inv_beta=i_beta)
    delta = np.asarray(ds["delta"], dtype=float)
    fig, axes = _figure(2, sharex=True)
    for wall in ds["wall"].values:
        wall = str(wall)
        at = ds.sel(wall=wall)
        style = WALL_STYLES.get(wall, dict(color="k", marker="^", ls=":"))
        hit = np.asarray(at["wall_n_collisions"]) > 0
        for ax, name in zip(axes, ("wall_v_after_mean", "wall_interval_mean")):
            mean = np.asarray(_require(at, name, "this figure"), dtype=float)
            lo = np.asarray(at[f"{name}_lo"], dtype=float)
            hi = np.asarray(at[f"{name}_hi"], dtype=float)
            ok = hit & np.isfinite(mean)
            err = np.vstack([mean - lo, np.where(np.isfinite(hi), hi - mean, 0.0)])
            ax.errorbar(delta[ok], mean[ok], yerr=err[:, ok], color=style["color"],
                        marker=style["marker"], ls=style["ls"], markersize=3.5, capsize=2,
                        label=WALL_NAMES.get(wall, wall))
    axes[0].set_ylabel("mean velocity\nafter impact")
    axes[1].set_ylabel("mean interval between\ncollisions at the wall")
    axes[1].set_yscale("log")
    axes[1].set_xlabel(axis_label(ds["delta"]))
    _panel_tag(axes[0], r"(a) mean velocity after impact $\varepsilon_w u$")
    _panel_tag(axes[1], r"(b) mean interval $T / N_w$")
    axes[0].legend(loc="best", fontsize="small")
    _header(fig, title, _events_params(events, i_beta, ("v_after", "interval")))
    return fig
