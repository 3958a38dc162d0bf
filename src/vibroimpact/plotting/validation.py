"""Validation figures: work-precision against the peers, and the stress families' margins.

Both take the datasets the workflow writes under ``results/validation/``
(``vibroimpact.validation.work_precision`` and ``vibroimpact.validation.campaign``) and
return a Figure; neither imports the simulator or the validation code.
"""
from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from vibroimpact.plotting._common import _attr, _header, _num, _require, _styled, axis_label

#: Label of this package's simulator in the work-precision dataset.
SIMULATOR = "simulate"
#: Colour and marker of each method (the simulator: black star); others cycle.
METHOD_STYLE = {
    SIMULATOR: ("k", "*"),
    "solve_ivp RK45": ("C0", "o"),
    "solve_ivp DOP853": ("C1", "s"),
    "solve_ivp LSODA": ("C2", "^"),
    "RK4 + event location": ("C4", "D"),
    "RK4 clamp": ("C7", "v"),
}
#: Errors at or above this are O(1): impacts missed, spurious or misplaced by a whole flight.
ORDER_ONE = 0.1
#: A setting is written next to its point unless an already written one of the same series
#: lies closer than this (decades, in both error and cost): the loosest and tightest first.
LABEL_SPACING = 0.4
#: Width (inches) of one work-precision panel, and the narrowest figure (room for the header).
PANEL_WIDTH = 3.6
MIN_WIDTH = 7.5
#: Characters of header text per inch of figure width (the style's title size), and inches
#: per legend column: the header and the legend are wrapped to the figure's width.
HEADER_CHARS_PER_INCH = 14
LEGEND_COLUMN_WIDTH = 2.9


def _setting_text(setting):
    """``rtol=1e-06`` -> ``1e-6``; ``h=dt/8`` -> ``dt/8``: short labels next to the points."""
    text = str(setting)
    if text.startswith("rtol="):
        mantissa, _, exponent = text[5:].partition("e")
        return f"{mantissa}e{int(exponent)}" if exponent else mantissa
    return text.removeprefix("h=")


def _labelled(error, cost, shown):
    """Indices of the points whose settings are written (see `LABEL_SPACING`)."""
    index = np.flatnonzero(shown)
    if index.size == 0:
        return []
    order = [index[0], index[-1], *index[1:-1]]
    kept = []
    for k in dict.fromkeys(order):
        if all(abs(np.log10(error[k] / error[j])) > LABEL_SPACING
               or abs(np.log10(cost[k] / cost[j])) > LABEL_SPACING for j in kept):
            kept.append(k)
    return kept


def _series(ds, method):
    """(error, cost, settings) of one method's runs, in run order."""
    sel = np.flatnonzero(np.asarray(ds["method"]) == method)
    return (np.asarray(ds["error"], dtype=float)[sel], np.asarray(ds["cost"], dtype=float)[sel],
            [_setting_text(s) for s in np.asarray(ds["setting"])[sel]])


def _ratio_text(value):
    """``x21.8``, ``x1.5e4``: a ratio to the simulator, short."""
    value = float(value)
    if not np.isfinite(value) or value < 1000.0:
        return f"\u00d7{value:.3g}"
    exponent = int(np.floor(np.log10(value)))
    return f"\u00d7{value / 10.0 ** exponent:.2g}e{exponent}"


def _closest_peer_text(ds):
    """The peer run with the smallest error: its error and cost against the simulator's."""
    error = np.asarray(ds["error"], dtype=float)
    peer = np.asarray(ds["method"]) != SIMULATOR
    if not peer.any() or not np.isfinite(error[peer]).any():
        return ""
    j = np.flatnonzero(peer)[np.nanargmin(np.where(np.isfinite(error[peer]), error[peer], np.inf))]
    run = ds.isel(run=j)
    return (f"most accurate peer: {run['method'].item()} {_setting_text(run['setting'].item())}\n"
            f"its error {_ratio_text(run['error_ratio'])}, its cost "
            f"{_ratio_text(run['cost_ratio'])} the simulator's")


def _work_precision_panel(ax, ds, methods):
    """One play: a line per method through its settings, the simulator as a star."""
    for method in methods:
        color, marker = METHOD_STYLE.get(method, ("C5", "P"))
        error, cost, settings = _series(ds, method)
        shown = np.isfinite(error) & (error > 0.0)
        if method == SIMULATOR:
            ax.plot(error[shown], cost[shown], ls="none", marker=marker, color=color,
                    markersize=14, zorder=6, gid="simulator")
            for e, c in zip(error[shown], cost[shown]):
                ax.annotate("this simulator", (e, c), xytext=(9, -3), textcoords="offset points",
                            fontsize=8, fontweight="bold", va="top")
            continue
        ax.plot(error[shown], cost[shown], marker=marker, color=color, markersize=4.5, lw=1.0,
                alpha=0.9)
        for k in _labelled(error, cost, shown):
            ax.annotate(settings[k], (error[k], cost[k]), xytext=(3, 3),
                        textcoords="offset points", fontsize=6, color=color)
    roundoff = float(ds["roundoff"])
    ax.axvline(roundoff, color="0.35", ls=":", lw=1.0, gid="roundoff")
    ax.axvspan(ORDER_ONE, 1e300, color="0.9", lw=0, zorder=0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    title = (rf"$\delta$ = {_num(ds['delta'])}:  {int(ds['n_compared'])} impacts compared, "
             rf"$\tau$ $\leq$ {_num(ds['t_stretch'])}")
    note = _closest_peer_text(ds)
    ax.set_title(f"{title}\n{note}" if note else title, fontsize=8.5)


@_styled
def work_precision(ds):
    """Work-precision diagram: run time per unit of simulated time against impact error.

    Parameters
    ----------
    ds : xarray.Dataset
        ``results/validation/work_precision.nc``: ``error(delta, run)``, ``cost(delta, run)``,
        ``error_ratio``, ``cost_ratio``, coordinates ``method(run)`` and ``setting(run)``;
        ``roundoff``, ``n_compared``, ``t_stretch`` per delta; the problem in the attributes.

    Returns
    -------
    matplotlib.figure.Figure
        One log-log panel per play (largest delta first, shared axes), one line per method
        through its tolerances or steps (written next to the points), the simulator a black
        star (gid ``"simulator"``). Dotted: the round-off level of the stretch, the error of a
        float64-precision (53-bit) run of the reference; grey: errors of O(1), where impacts
        are missed or spurious. Each panel names the most accurate peer run and its error and
        cost relative to the simulator's under its title.
    """
    for name in ("error", "cost", "roundoff", "n_compared", "t_stretch", "error_ratio",
                 "cost_ratio"):
        _require(ds, name, "the work-precision figure")
    ds = ds.sortby("delta", ascending=False)
    methods = list(dict.fromkeys(np.asarray(ds["method"]).tolist()))
    n = ds.sizes["delta"]
    fig = Figure(figsize=(max(PANEL_WIDTH * n + 0.6, MIN_WIDTH), 5.2))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, n, sharex=True, sharey=True, squeeze=False)[0]
    for ax, i in zip(axes, range(n)):
        _work_precision_panel(ax, ds.isel(delta=i), methods)
        ax.set_xlabel("largest impact error (time, relative velocity)")
    axes[0].set_ylabel(axis_label(ds["cost"]))
    _limits(axes[0], ds)
    missing = int(np.sum(~np.isfinite(np.asarray(ds["error"], dtype=float))))
    handles = [Line2D([], [], color=METHOD_STYLE.get(m, ("C5", "P"))[0],
                      marker=METHOD_STYLE.get(m, ("C5", "P"))[1], ls="none" if m == SIMULATOR
                      else "-", markersize=9 if m == SIMULATOR else 4.5,
                      label=_method_label(ds, m)) for m in methods]
    handles += [Line2D([], [], color="0.35", ls=":", label="float64 round-off (53-bit reference)"),
                Line2D([], [], color="0.9", lw=6,
                       label=f"error > {_num(ORDER_ONE)}: impacts missed or misplaced")]
    width = fig.get_figwidth()
    fig.legend(handles=handles, loc="outside lower center", fontsize=7.5,
               ncols=max(1, min(len(handles), int(width // LEGEND_COLUMN_WIDTH))))
    params = (rf"$\zeta$ = {_num(_attr(ds, 'zeta'))}, $\varepsilon$ = {_num(_attr(ds, 'eps'))}, "
              rf"$\Delta\tau$ = {_num(_attr(ds, 'dt'))}, force: {_attr(ds, 'force')} "
              f"(seed {_attr(ds, 'seed')}), {_attr(ds, 'initial_state')}\n"
              "error: largest |impact time error| or |relative impact velocity error| over the "
              "first impacts, against the mpmath reference (34 digits)\n"
              f"cost: wall time, one process on {_attr(ds, 'machine')} "
              f"(load average {float(_attr(ds, 'load_average')):.1f} on "
              f"{int(_attr(ds, 'cpu_count'))} CPUs at the start)\n"
              f"compiled methods timed on {int(_attr(ds, 'long_samples')):,} samples (best of "
              f"{int(_attr(ds, 'repeats'))}), solve_ivp once on the compared stretch"
              + (f"\n{missing} runs found no impact (not drawn)" if missing else ""))
    _header(fig, "Work-precision: this simulator against the integrators a user would reach for",
            "\n".join(textwrap.fill(line, int(width * HEADER_CHARS_PER_INCH))
                      for line in params.split("\n")))
    return fig


def _limits(ax, ds):
    """Log limits with room for the labels: the errors and the round-off level, the costs."""
    error = np.asarray(ds["error"], dtype=float)
    cost = np.asarray(ds["cost"], dtype=float)
    finite = error[np.isfinite(error) & (error > 0.0)]
    if finite.size == 0:
        return
    low = min(finite.min(), float(ds["roundoff"].min()))
    ax.set_xlim(10.0 ** (np.floor(np.log10(low)) - 0.5), 10.0 ** (np.log10(finite.max()) + 0.8))
    cost = cost[np.isfinite(cost) & (cost > 0.0)]
    ax.set_ylim(cost.min() / 4.0, cost.max() * 4.0)


def _method_label(ds, method):
    """Legend entry: the method and the range of its settings."""
    if method == SIMULATOR:
        return "simulate (this package, closed form)"
    settings = [_setting_text(s) for s, m in zip(np.asarray(ds["setting"]),
                                                  np.asarray(ds["method"])) if m == method]
    what = "rtol = atol" if method.startswith("solve_ivp") else "h ="
    span = settings[0] if len(settings) == 1 else f"{settings[0]} ... {settings[-1]}"
    return f"{method} ({what} {span})"


#: Colour of a family that passed / failed.
PASS_COLOR, FAIL_COLOR = "#009E73", "#D55E00"
#: Where a family whose worst error is exactly zero is drawn (fraction of the left decade).
ZERO_AT = 0.5


def _measure_key(row):
    """What a family's ratio measures: its error measure over its tolerance."""
    tolerance = float(row["tolerance"])
    return str(row["measure"].item()) + ("" if tolerance == 1.0 else f", over {_num(tolerance)}")


def _measures(ds):
    """The distinct error measures of the families, in order of first appearance."""
    return list(dict.fromkeys(_measure_key(ds.isel(family=k)) for k in range(ds.sizes["family"])))


def _count_text(row):
    """``25 cases, 457 compared;  missed 0, spurious 0, exceptions 0`` (+ failed, approximated)."""
    text = (f"{int(row['cases'])} cases, {int(row['compared'])} compared;  missed "
            f"{int(row['missed'])}, spurious {int(row['spurious'])}, exceptions "
            f"{int(row['exceptions'])}")
    if int(row["approximated"]):
        text += f", approximated {int(row['approximated'])}"
    if int(row["failed"]):
        text += f";  FAILED {int(row['failed'])}"
    return text


@_styled
def stress(ds):
    """The stress families: worst error over allowance, and what each family counted.

    Parameters
    ----------
    ds : xarray.Dataset
        ``results/validation/stress_sample.nc``: per ``family``, ``worst_error``,
        ``tolerance``, ``measure``, the counts ``cases``, ``compared``, ``missed``,
        ``spurious``, ``exceptions``, ``approximated``, ``failed``, and ``seconds``.

    Returns
    -------
    matplotlib.figure.Figure
        One row per family: ``worst_error / tolerance`` on a log axis with the line at 1 (the
        allowance: a family passes when all its compared events lie below it), green when the
        family passed, orange when a case failed (an error above its allowance, a missed or
        spurious event, or an exception); each row's counts written beside it. Families
        whose worst error is 0 are drawn as open circles at the left edge.
    """
    for name in ("worst_error", "tolerance", "cases", "compared", "missed", "spurious",
                 "exceptions", "approximated", "failed"):
        _require(ds, name, "the stress figure")
    families = [str(f) for f in np.asarray(ds["family"])]
    ratio = np.asarray(ds["worst_error"], dtype=float) / np.asarray(ds["tolerance"], dtype=float)
    failed = np.asarray(ds["failed"]) > 0
    fig = Figure(figsize=(9.0, 0.32 * len(families) + 2.2))
    FigureCanvasAgg(fig)
    ax, table = fig.subplots(1, 2, gridspec_kw={"width_ratios": (1.0, 1.0)}, sharey=True)
    y = np.arange(len(families))[::-1]
    positive = ratio[np.isfinite(ratio) & (ratio > 0.0)]
    low = 10.0 ** (np.floor(np.log10(positive.min())) - 1) if positive.size else 1e-6
    high = 10.0 ** max(np.ceil(np.log10(positive.max())) + 0.5, 1.0) if positive.size else 10.0
    zero = ratio == 0.0
    ax.axvline(1.0, color="k", lw=1.2, gid="allowance")
    ax.axvspan(1.0, high, color=FAIL_COLOR, alpha=0.08, lw=0)
    for ok, color in ((True, PASS_COLOR), (False, FAIL_COLOR)):
        sel = (failed != ok) & ~zero
        ax.hlines(y[sel], low, ratio[sel], color=color, lw=1.0, alpha=0.5)
        ax.plot(ratio[sel], y[sel], ls="none", marker="o", color=color, markersize=6)
    if zero.any():
        ax.plot(np.full(zero.sum(), low * 10.0 ** ZERO_AT), y[zero], ls="none", marker="o",
                mfc="white", color="0.4", markersize=6)
    ax.set_xscale("log")
    ax.set_xlim(low, high)
    ax.set_yticks(y, families)
    ax.set_ylim(-0.7, len(families) - 0.3)
    ax.set_xlabel("worst error / tolerance (each family's own measure)")
    ax.grid(False, axis="y")
    table.set_axis_off()
    measures = _measures(ds)
    for yi, k in zip(y, range(len(families))):
        row = ds.isel(family=k)
        tag = "abcdefghijklmnopqrstuvwxyz"[list(measures).index(_measure_key(row))]
        table.text(0.0, yi, f"({tag})  {_count_text(row)}", va="center", ha="left",
                   fontsize=7.5, color=FAIL_COLOR if failed[k] else "0.1")
    table.set_xlim(0.0, 1.0)
    handles = [Line2D([], [], ls="none", marker="o", color=PASS_COLOR, label="passed"),
               Line2D([], [], ls="none", marker="o", color=FAIL_COLOR, label="a case failed"),
               Line2D([], [], color="k", lw=1.2, label="allowance (error = tolerance)")]
    if zero.any():
        handles.append(Line2D([], [], ls="none", marker="o", mfc="white", color="0.4",
                              label="worst error 0"))
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=7.5)
    seed = ds.attrs.get("seed")
    total = float(np.sum(ds["seconds"])) if "seconds" in ds else float("nan")
    title = "Stress families: the worst error of each family against its allowance (< 1: passed)"
    params = (f"seeded {'quick ' if ds.attrs.get('size') == 'quick' else ''}sample"
              + (f", seed {seed}" if seed is not None else "")
              + f", {int(np.sum(ds['cases'])):,} cases, {int(np.sum(ds['compared'])):,} events "
              f"compared with independent references, {total:.0f} s;  error measures:\n"
              + "\n".join(f"({tag}) {m}" for tag, m in zip("abcdefghijklmnopqrstuvwxyz",
                                                             measures)))
    _header(fig, title, params)
    return fig
