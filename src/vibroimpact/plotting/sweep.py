"""The side-by-side figure of a sweep (README, "Sweeps"): Fig. 9's means, one curve per study."""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from vibroimpact.plotting._common import (
    CONFIDENCE, FEW_IMPACTS, _attr, _colors, _figure, _filter_parts, _header, _num, _padded,
    _panel_tag, _require, _styled, axis_label, note_on_axes, t_quantile, two_wall_dataset)

#: Height (inches): two panels and the legend below them.
SWEEP_HEIGHT = 7.0
#: The combinations' points at one delta are spread over this fraction of the smallest delta
#: step, so that their bars do not hide one another (the spread is stated on the figure).
DODGE = 0.3
#: Combinations drawn in the qualitative colour cycle (tab10); more take the colour map.
CYCLE_COLORS = 10
#: Line styles of the second and further swept keys, when the first one has the colours.
LINE_STYLES = ("-", "--", ":", "-.")
#: Global attributes printed once in the parameter line when every study shares them.
_SHARED = (("zeta", r"$\zeta$"), ("eps", r"$\varepsilon$"), ("amplitude", "A"),
           ("noise_rms", r"rms$_r$"))


def _shared_text(datasets):
    """The parameter line: the values the studies share, and which ones vary."""
    parts, varied = [], []
    for key, symbol in _SHARED:
        values = {float(_attr(ds, key)) for ds in datasets}
        if len(values) == 1:
            value = values.pop()
            if key != "amplitude" or value != 0.0:
                parts.append(f"{symbol} = {_num(value)}")
        else:
            varied.append(symbol)
    walls_text = ""
    if any(two_wall_dataset(ds) for ds in datasets):
        # two walls: where the lower one stands and its restitution; the means pool the
        # collisions at both walls (the members' own Fig. 9 draws them per wall)
        walls = []
        for key, symbol in (("gap", "g"), ("eps_lower", r"$\varepsilon_l$")):
            values = {float(ds.attrs[key]) for ds in datasets if key in ds.attrs}
            if len(values) == 1:
                walls.append(f"{symbol} = {_num(values.pop())}")
            elif values:
                varied.append(symbol)
        walls_text = (r"two walls, the lower at $\delta$ - g"
                      + (f" ({', '.join(walls)})" if walls else "")
                      + ": collisions at both walls pooled")
    seeds = {int(ds.attrs.get("seed", -1)) for ds in datasets}
    if len(seeds) > 1:
        varied.append("seed")
    first = datasets[0].attrs
    noise = ", ".join([str(first.get("noise_kind", "")), *_filter_parts(first)]).strip(", ")
    line = ", ".join(parts) + (f";  {walls_text}" if walls_text else "") + (
        f";  input {noise}" if noise else "")
    inv_beta = {float(ds["inv_beta"][0]) for ds in datasets}
    if any(float(_attr(ds, "amplitude")) != 0.0 for ds in datasets) and len(inv_beta) == 1:
        line += rf",  $\sin(\tau/{_num(inv_beta.pop())})$"
    if varied:
        line += f";  varied: {', '.join(varied)} (legend)"
    return line


def _styles(datasets):
    """``(colour, line style)`` of each combination.

    With two or more swept keys (global attributes ``sweep_<key>``, in the sweep's order),
    the first key's value picks the colour and the other keys' values the line style, so
    each key's effect reads on its own; otherwise each combination has its own colour.
    """
    keys = [k for k in datasets[0].attrs if k.startswith("sweep_") and k != "sweep_index"]
    n = len(datasets)
    if len(keys) >= 2 and all(k in ds.attrs for ds in datasets for k in keys):
        first = [ds.attrs[keys[0]] for ds in datasets]
        rest = [tuple(ds.attrs[k] for k in keys[1:]) for ds in datasets]
        hues, dashes = list(dict.fromkeys(first)), list(dict.fromkeys(rest))
        if len(hues) <= CYCLE_COLORS and len(dashes) <= len(LINE_STYLES):
            return [(f"C{hues.index(f)}", LINE_STYLES[dashes.index(r)])
                    for f, r in zip(first, rest)]
    colors = [f"C{i}" for i in range(n)] if n <= CYCLE_COLORS else list(_colors(n))
    return [(c, "-") for c in colors]


def _offsets(datasets):
    """Horizontal offset of each combination's points (total spread `DODGE` x smallest step)."""
    steps = [np.diff(np.unique(np.asarray(ds["delta"], dtype=float))) for ds in datasets]
    steps = np.concatenate([s for s in steps if s.size] or [np.array([0.0])])
    n = len(datasets)
    if n == 1 or not steps.size or steps.min() <= 0.0:
        return np.zeros(n), 0.0
    spread = DODGE * float(steps.min())
    return np.linspace(-spread / 2, spread / 2, n), spread


@_styled
def sweep_means(datasets, labels):
    """Mean velocity after impact and mean interval against delta, one curve per combination.

    Parameters
    ----------
    datasets : sequence of xarray.Dataset
        The events datasets of a sweep's studies (``results/datasets/<sweep>_<k>_events.nc``)
        in the order of its combinations; inv_beta index 0 of each is drawn. Each needs
        ``v_after_mean``, ``v_after_stderr``, ``interval_mean``, ``interval_stderr``,
        ``n_collisions``, ``n_batches`` and the global attributes ``zeta``, ``eps``,
        ``amplitude``, ``noise_rms`` (``sweep``, the sweep's name, for the title).
    labels : sequence of str
        One legend label per dataset, its combination's values (``"eps = 0.8, rms = 0.3"``).

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked axes sharing delta, as Fig. 9 (`vibroimpact.plotting.fig09`): (a) the
        mean velocity after impact, (b) the mean interval on a log scale. Bars are +-t
        batch-means standard errors (t the Student quantile of B - 1 dof at `CONFIDENCE`);
        means resting on fewer than `FEW_IMPACTS` collisions are open squares without bars;
        deltas without impacts are left out, a combination without any is named so in the
        legend, and when no combination has one the axes say so in words. With two or more
        swept keys the first one's value gives the colour and the others' the line style,
        else each combination has its colour; each combination's points are shifted by a
        fixed small offset in delta (`DODGE`, stated in the legend). The parameter line
        gives the values the studies share and names those that vary.

    Raises
    ------
    ValueError
        If there is no dataset or the labels do not match the datasets one to one.
    """
    if not datasets or len(datasets) != len(labels):
        raise ValueError(f"sweep_means needs one label per dataset, got {len(datasets)} "
                         f"dataset(s) and {len(labels)} label(s)")
    fig, axes = _figure(2)
    fig.set_figheight(SWEEP_HEIGHT)
    offsets, spread = _offsets(datasets)
    handles, any_few, batches = [], False, set()
    for ds, label, (color, ls), offset in zip(datasets, labels, _styles(datasets), offsets):
        cell = ds.isel(inv_beta=0).sortby("delta")
        delta = np.asarray(cell["delta"], dtype=float) + offset
        impacts = np.asarray(_require(cell, "n_collisions", "the sweep figure"))
        enough, few = impacts >= FEW_IMPACTS, (impacts > 0) & (impacts < FEW_IMPACTS)
        n_batches = np.asarray(_require(cell, "n_batches", "the sweep figure's bars"))
        batches.update(int(b) for b in np.unique(n_batches[enough]))
        t = t_quantile(n_batches, CONFIDENCE)
        for ax, name in zip(axes, ("v_after", "interval")):
            mean = np.asarray(_require(cell, f"{name}_mean", "the sweep figure"), dtype=float)
            err = t * np.asarray(_require(cell, f"{name}_stderr", "the sweep figure"), dtype=float)
            ax.errorbar(delta[enough], mean[enough], yerr=err[enough], color=color, marker="o",
                        markersize=3.5, lw=1.1, ls=ls)
            if few.any():
                ax.plot(delta[few], mean[few], ls="none", marker="s", mfc="white", color=color,
                        markersize=4.5)
        any_few |= bool(few.any())
        handles.append(Line2D([], [], color=color, ls=ls, marker="o", markersize=3.5,
                              label=label if impacts.any() else f"{label}  (no collision)"))
    reference = datasets[0].isel(inv_beta=0)
    for ax, name in zip(axes, ("v_after", "interval")):
        ax.set_ylabel(axis_label(reference[f"{name}_mean"]))
    axes[0].set_ylim(bottom=0.0)
    axes[1].set_yscale("log")       # the mean interval spans orders of magnitude over delta
    intervals = np.concatenate([np.ravel(ds["interval_mean"]) for ds in datasets])
    if not np.isfinite(intervals).any():     # nothing on the log axis to scale it by
        axes[1].set_ylim(1.0, 20.0 * float(reference.attrs.get("record_length", 1.0)))
    if not any(int(ds["n_collisions"].sum()) for ds in datasets):
        delta = np.concatenate([np.asarray(ds["delta"], dtype=float) for ds in datasets])
        axes[0].set_xlim(*_padded(delta))
        for ax in axes:
            note_on_axes(ax, "no collision in the record of any combination at any "
                             r"$\delta$")
    axes[1].set_xlabel(axis_label(reference["delta"]))
    _panel_tag(axes[0], "(a)")
    _panel_tag(axes[1], "(b)")
    if any_few:
        handles.append(Line2D([], [], ls="none", marker="s", mfc="white", color="0.3",
                              markersize=4.5,
                              label=f"fewer than {FEW_IMPACTS} collisions (no bar)"))
    t_text = (f"t = {_num(t_quantile(batches.pop(), CONFIDENCE))}" if len(batches) == 1
              else "t of B - 1 dof")
    title = rf"mean $\pm$ t$\cdot$batch-means s.e. ({100 * CONFIDENCE:g} %, {t_text})"
    if spread:
        title += rf";  points offset by up to $\pm${_num(spread / 2)} in $\delta$ for legibility"
    fig.legend(handles=handles, loc="outside lower center", ncols=min(len(handles), 3),
               title=title, title_fontsize=8)
    name = datasets[0].attrs.get("sweep")
    head = f"Sweep '{name}'" if name else "Sweep"
    _header(fig, f"{head}: mean velocity after impact and mean interval between impacts",
            _shared_text(datasets))
    return fig
