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

from dataclasses import replace

from vibroimpact.plotting._common import (
    SPARSE_TEXT, _beyond_text, _bin_edges, _density_deltas, _density_log_limits,
    _density_rule_text, _draw_densities, _events_params, _figure, _header, _num, _panel_tag,
    _require, _restitution_note, axis_label, note_on_axes)

#: How the figures name each wall (the ``wall`` coordinate's values).
WALL_NAMES = {"upper": "upper wall, x = $\\delta$ (hit from below)",
              "lower": "lower wall, x = $\\delta - g$ (hit from above)"}
#: Colour and marker of each wall in the means figure.
WALL_STYLES = {"upper": dict(color="C0", marker="o", ls="-"),
               "lower": dict(color="C3", marker="s", ls="--")}


def two_walls(ds):
    """Whether a dataset is a two-wall study's (it has the ``wall`` dimension)."""
    return "wall" in ds.dims


def wall_view(ds, quantity, wall):
    """One wall's density of `quantity` under the one-wall names, for the one-wall drawing.

    Parameters
    ----------
    ds : xarray.Dataset
        One inv_beta row of a two-wall events dataset.
    quantity : {"v_after", "interval", "ratio"}
        The density's quantity.
    wall : str
        A value of the ``wall`` coordinate.

    Returns
    -------
    xarray.Dataset
        ``{quantity}_density``, ``{quantity}_density_stderr`` (when the dataset has it),
        ``{quantity}_beyond`` and ``n_collisions`` of that wall (its ``wall_*`` variables),
        with ``n_batches``, over ``delta``: what `_common._draw_densities` reads of a
        one-wall dataset. A wall's densities are normalised by its own collisions
        (`stats.wall_statistics`), as the one-wall ones by all of them.
    """
    names = {f"wall_{quantity}_density": f"{quantity}_density",
             f"wall_{quantity}_density_stderr": f"{quantity}_density_stderr",
             f"wall_{quantity}_beyond": f"{quantity}_beyond",
             "wall_n_collisions": "n_collisions"}
    for name in (f"wall_{quantity}_density", f"wall_{quantity}_beyond", "wall_n_collisions",
                 "n_batches"):
        _require(ds, name, "a two-wall density figure")
    names = {old: new for old, new in names.items() if old in ds}
    return ds.sel(wall=wall)[[*names, "n_batches"]].rename(names)


def wall_density_figure(events, i_beta, quantity, title, density_delta=None):
    """One log-density panel per wall of ``wall_{quantity}_density``, one curve per density
    delta, drawn as the one-wall density figures draw theirs.

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
        Two stacked log-density axes (upper wall, lower wall) sharing x. Each wall's curves
        are `_common._draw_densities` of its `wall_view`: the sparse-bin rule
        (`_common.MIN_BIN_COUNT`, merged runs drawn as bars apart from the curves) and the
        band of +-t batch-means standard errors joined with Garwood's interval of the count,
        as in Figs. 7, 8, 13, 14 of one wall. One legend below the axes, its title the band
        and the rule (`_common._density_rule_text`); each entry gives the play's collisions
        at each wall and, when above `_common.BEYOND_SHOWN`, the fraction beyond the last bin.
    """
    var = f"{quantity}_density"
    ds = events.isel(inv_beta=i_beta)
    _require(ds, f"wall_{var}", "this figure")
    index = _density_deltas(events, density_delta)
    walls = [str(w) for w in ds["wall"].values]
    views = [wall_view(ds, quantity, wall) for wall in walls]
    labels = []
    for k in index:
        parts = [f"{wall} {int(view['n_collisions'][k]):,}"
                 f"{_beyond_text(view[f'{quantity}_beyond'][k])}"
                 for wall, view in zip(walls, views)]
        labels.append(rf"$\delta$ = {_num(ds['delta'][k])}  (collisions: {'; '.join(parts)})")
    fig, axes = _figure(len(walls), sharex=True)
    x = ds[f"wall_{var}"].dims[-1]
    edges = _bin_edges(ds[x])
    x_end, drawn_any = edges[0], []
    for j, (ax, wall, view) in enumerate(zip(axes, walls, views)):
        drawn = _draw_densities([ax], view, var, index, labels if j == 0 else None)
        _density_log_limits(ax, drawn)
        if drawn.top <= 0.0:
            hit = int(view["n_collisions"].isel(delta=index).sum()) > 0
            note_on_axes(ax, SPARSE_TEXT if hit
                         else "no collision at this wall at any $\\delta$ drawn")
        x_end = max(x_end, drawn.x_end)
        drawn_any.append(drawn)
        ax.set_ylabel(_density_label(quantity))
        _panel_tag(ax, WALL_NAMES.get(wall, wall))
    axes[0].set_xlim(edges[0], x_end if x_end > edges[0] else edges[-1])
    axes[-1].set_xlabel(_restitution_note(events, axis_label(ds[x])))    # eps_w u
    # one title for both walls: a merged run drawn at either wall is explained
    rule = _density_rule_text(views[0], index, replace(
        drawn_any[0], any_run=any(d.any_run for d in drawn_any)))
    # an entry per play, each naming both walls: one column, below the axes
    fig.set_figheight(fig.get_figheight() * (1.15 + 0.04 * len(index)))
    fig.legend(loc="outside lower center", ncols=1, title=rule, title_fontsize=7.5,
               fontsize=7.5)
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
