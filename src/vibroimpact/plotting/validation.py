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
from matplotlib.text import Text

from vibroimpact.plotting._common import _attr, _header, _num, _require, _styled

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
#: A solve_ivp method whose errors (below `ORDER_ONE`) span less than this factor over its
#: tolerances is "insensitive to rtol": the panel's note on it gets the footnote on restarts.
RTOL_INSENSITIVE = 10.0
#: Width (inches) of one work-precision panel, the narrowest figure, and its height.
PANEL_WIDTH = 3.6
MIN_WIDTH = 7.5
WP_HEIGHT = 5.6
#: Inches per legend column: the legend is wrapped to the figure's width.
LEGEND_COLUMN_WIDTH = 2.9
#: Axis labels and the error's definition (header) in the paper's symbols: impact instants
#: tau_j, approach velocities u_{j-0}, time tau.
WP_XLABEL = r"largest impact error $e$"
WP_ERROR = (r"$e$ = max$_j$ (|$\tau_j - \tau_j^{\rm ref}$|, |$u_{j-0}/u_{j-0}^{\rm ref} - 1$|) "
            "against a 34-digit reference")
#: Title of the figure; its header shrinks (down to this size) to fit the figure's width.
WP_TITLE = "Work-precision: this simulator against the integrators a user would reach for"
MIN_HEADER_SIZE = 6.5
WP_YLABEL = r"wall time per unit of $\tau$ [s]"
#: Where a setting's label may go around its point: (dx, dy) in points, ha, va; tried in this
#: order, the near ring first; labels on the far ring get a thin leader line.
LABEL_OFFSETS = [(4, 3, "left", "bottom"), (4, -3, "left", "top"),
                 (-4, 3, "right", "bottom"), (-4, -3, "right", "top"),
                 (0, 6, "center", "bottom"), (0, -6, "center", "top"),
                 (7, 0, "left", "center"), (-7, 0, "right", "center")]
FAR = 2.6
#: Font size of the footnote, and its characters per inch of figure width (wrapped to fit;
#: its mathtext has no spaces, so it is never broken inside).
FOOTNOTE_SIZE = 7
FOOTNOTE_CHARS_PER_INCH = 19
#: Font size of the setting labels, and their clearance (pixels) from every other mark.
LABEL_SIZE = 6.5
LABEL_PAD = 1.0


def _setting_text(setting):
    """``rtol=1e-06`` -> ``1e-6``; ``h=dt/8`` -> ``Δτ/8``: short labels next to the points."""
    text = str(setting)
    if text.startswith("rtol="):
        mantissa, _, exponent = text[5:].partition("e")
        return f"{mantissa}e{int(exponent)}" if exponent else mantissa
    return text.removeprefix("h=").replace("dt", r"$\Delta\tau$")


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


def _short_method(method):
    """``solve_ivp DOP853`` -> ``DOP853``: the method's name in a panel title."""
    return str(method).removeprefix("solve_ivp ")


def _most_accurate_peer(ds):
    """Run index of the peer run with the smallest finite error (the first of equals), or None."""
    error = np.asarray(ds["error"], dtype=float)
    peer = (np.asarray(ds["method"]) != SIMULATOR) & np.isfinite(error)
    if not peer.any():
        return None
    return int(np.flatnonzero(peer)[np.argmin(error[peer])])


def rtol_spread(ds, method):
    """How little a solve_ivp method's error depends on its tolerance, at one play.

    Parameters
    ----------
    ds : xarray.Dataset
        One play (``delta`` selected) of the work-precision dataset.
    method : str
        A method of the dataset (``"solve_ivp DOP853"``).

    Returns
    -------
    spread : float
        Largest over smallest error of its runs with errors below `ORDER_ONE` (NaN when fewer
        than two such runs).
    failed : list of str
        Settings whose error is O(1) (an impact missed or spurious).
    """
    error, _, settings = _series(ds, method)
    ok = np.isfinite(error) & (error < ORDER_ONE) & (error > 0.0)
    failed = [s for s, good in zip(settings, ok) if not good]
    spread = error[ok].max() / error[ok].min() if ok.sum() >= 2 else np.nan
    return float(spread), failed


def _peer_title(ds):
    """Two lines on the most accurate peer run (with a ``*`` when a restarted solve_ivp
    method that hardly depends on rtol), and whether it got the star."""
    j = _most_accurate_peer(ds)
    if j is None:
        return "", False
    run = ds.isel(run=j)
    method = str(run["method"].item())
    spread, failed = rtol_spread(ds, method)
    star = method.startswith("solve_ivp") and spread < RTOL_INSENSITIVE and not failed
    setting = _setting_text(run["setting"].item())
    setting = f"rtol {setting}" if method.startswith("solve_ivp") else f"step {setting}"
    return (f"most accurate peer: {_short_method(method)}, {setting}{'*' if star else ''}\n"
            f"its error {_ratio_text(run['error_ratio'])}, its cost "
            f"{_ratio_text(run['cost_ratio'])} the simulator's"), star


def _restart_footnote(ds, starred):
    """The footnote behind the ``*``: why that solve_ivp method hardly depends on rtol, with
    the spread of its errors over rtol at every play, from the data."""
    methods = {str(ds.isel(delta=i, run=_most_accurate_peer(ds.isel(delta=i)))["method"].item())
               for i in starred}
    parts = []
    for method in sorted(methods):
        spans = []
        for i in range(ds.sizes["delta"]):
            spread, failed = rtol_spread(ds.isel(delta=i), method)
            where = rf"$\delta$ = {_num(ds['delta'][i])}"
            text = f"{_ratio_text(spread)} at {where}" if np.isfinite(spread) else ""
            if failed:
                text += (" (" if text else f"at {where} ") + f"rtol {', '.join(failed)} miss or " \
                        "misplace impacts" + (")" if text else "")
            spans.append(text)
        settings = [_setting_text(s) for s, m in zip(np.asarray(ds["setting"]),
                                                      np.asarray(ds["method"])) if m == method]
        parts.append(f"{_short_method(method)}'s error, largest over smallest for rtol "
                     f"{settings[0]} ... {settings[-1]}: {', '.join(spans)}")
    return ("* solve_ivp is restarted at every force sample (the force is piecewise linear) and "
            r"after every impact, so no step exceeds $\Delta\tau$; where one step is already "
            "accurate the tolerance hardly matters.\n  " + ";  ".join(parts))


def _work_precision_panel(ax, ds, methods):
    """One play: a line per method through its settings, the simulator as a star. Returns
    the setting labels to place: (error, cost, text, colour, priority), ends of a series
    first."""
    labels = []
    for method in methods:
        color, marker = METHOD_STYLE.get(method, ("C5", "P"))
        error, cost, settings = _series(ds, method)
        shown = np.isfinite(error) & (error > 0.0)
        if method == SIMULATOR:
            ax.plot(error[shown], cost[shown], ls="none", marker=marker, color=color,
                    markersize=14, zorder=6, gid="simulator")
            for e, c in zip(error[shown], cost[shown]):
                ax.annotate("this simulator", (e, c), xytext=(9, -3), textcoords="offset points",
                            fontsize=8, fontweight="bold", va="top", gid="simulator_label")
            continue
        ax.plot(error[shown], cost[shown], marker=marker, color=color, markersize=4.5, lw=1.0,
                alpha=0.9)
        index = np.flatnonzero(shown)
        for rank, k in enumerate(index):
            end = rank in (0, index.size - 1)
            labels.append((error[k], cost[k], settings[k], color, 0 if end else 1))
    ax.axvline(float(ds["roundoff"]), color="0.35", ls=":", lw=1.0, gid="roundoff")
    ax.axvspan(ORDER_ONE, 1e300, color="0.9", lw=0, zorder=0)
    ax.set_xscale("log")
    ax.set_yscale("log")
    title = (rf"$\delta$ = {_num(ds['delta'])}:  {int(ds['n_compared'])} impacts compared, "
             rf"$\tau \leq$ {_num(ds['t_stretch'])}")
    note, star = _peer_title(ds)
    ax.set_title(f"{title}\n{note}" if note else title, fontsize=8.5)
    return labels, star


def _obstacles(ax):
    """Pixel boxes a setting label must not cover: every marker, points along every line,
    and the texts already in the axes."""
    boxes = []
    for line in ax.get_lines():
        if line.get_gid() == "roundoff":
            continue
        xy = ax.transData.transform(np.column_stack(line.get_data()).astype(float))
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        half = line.get_markersize() * ax.figure.dpi / 72.0 / 2.0 if line.get_marker() else 0.0
        boxes += [(x - half, y - half, x + half, y + half) for x, y in xy]
        if line.get_linestyle() not in ("None", "none", "") and len(xy) > 1:
            for a, b in zip(xy[:-1], xy[1:]):
                n = int(np.hypot(*(b - a)) // 3.0) + 2
                boxes += [(x - 0.5, y - 0.5, x + 0.5, y + 0.5)
                          for x, y in np.linspace(a, b, n)]
    return boxes


def _overlaps(box, boxes):
    x0, y0, x1, y1 = box
    return any(x0 < b[2] + LABEL_PAD and b[0] - LABEL_PAD < x1 and y0 < b[3] + LABEL_PAD
               and b[1] - LABEL_PAD < y1 for b in boxes)


def place_setting_labels(ax, labels, renderer):
    """Write each setting next to its point where it covers no mark and stays in the axes.

    Candidates around the point (`LABEL_OFFSETS`, then the same directions `FAR` times
    further with a leader line) are tried in order; a label that fits nowhere is left out
    (the legend names every series' settings). Ends of a series are placed first.

    Returns
    -------
    list of matplotlib.text.Annotation
        The labels written (gid ``"setting_label"``).
    """
    frame = ax.get_window_extent(renderer)
    boxes = _obstacles(ax) + [tuple(t.get_window_extent(renderer).extents) for t in ax.texts]
    placed = []
    for e, c, text, color, _ in sorted(labels, key=lambda label: label[4]):
        for scale in (1.0, FAR):
            for dx, dy, ha, va in LABEL_OFFSETS:
                arrow = dict(arrowstyle="-", lw=0.4, color=color, shrinkA=0, shrinkB=2.5)
                ann = ax.annotate(text, (e, c), xytext=(dx * scale, dy * scale),
                                  textcoords="offset points", fontsize=LABEL_SIZE, color=color,
                                  ha=ha, va=va, gid="setting_label", annotation_clip=True,
                                  arrowprops=arrow if scale > 1.0 else None)
                ann.set_in_layout(False)
                ann.update_positions(renderer)
                box = Text.get_window_extent(ann, renderer).extents
                inside = (box[0] >= frame.x0 + 1 and box[2] <= frame.x1 - 1
                          and box[1] >= frame.y0 + 1 and box[3] <= frame.y1 - 1)
                if inside and not _overlaps(box, boxes):
                    boxes.append(tuple(box))
                    placed.append(ann)
                    break
                ann.remove()
            else:
                continue
            break
    return placed


@_styled
def work_precision(ds):
    """Work-precision diagram: run time per unit of simulated time against impact error.

    Parameters
    ----------
    ds : xarray.Dataset
        ``results/validation/work_precision.nc``: ``error(delta, run)``, ``cost(delta, run)``,
        ``error_ratio``, ``cost_ratio``, coordinates ``method(run)``, ``setting(run)`` and
        ``timing_repeats(run)``; ``roundoff``, ``n_compared``, ``t_stretch`` per delta; the
        problem, ``timing_statistic`` and the machine in the attributes.

    Returns
    -------
    matplotlib.figure.Figure
        One log-log panel per play (largest delta first, shared axes), one line per method
        through its tolerances or steps, the simulator a black star (gid ``"simulator"``).
        Settings are written next to their points where they cover nothing else and stay
        inside the axes (gid ``"setting_label"``; the ends of each series first); the legend
        names every series' range. Dotted: the round-off level of the stretch, the error of a
        float64-precision (53-bit) run of the reference; grey: errors of O(1), where impacts
        are missed or spurious. Each panel names the most accurate peer run and its error and
        cost relative to the simulator's; a ``*`` there refers to the footnote on solve_ivp's
        restarts, with its errors' spread over rtol from the data. The header states the
        problem and how the runs were timed (statistic, repeats, load).
    """
    for name in ("error", "cost", "roundoff", "n_compared", "t_stretch", "error_ratio",
                 "cost_ratio", "timing_repeats"):
        _require(ds, name, "the work-precision figure")
    ds = ds.sortby("delta", ascending=False)
    methods = list(dict.fromkeys(np.asarray(ds["method"]).tolist()))
    n = ds.sizes["delta"]
    fig = Figure(figsize=(max(PANEL_WIDTH * n + 0.6, MIN_WIDTH), WP_HEIGHT))
    FigureCanvasAgg(fig)
    # a flat row under the panels holds the legend, which the layout makes room for, so that
    # the footnote (the figure's x label, at the bottom) never runs into it
    grid = fig.add_gridspec(2, n, height_ratios=(1.0, 1e-3))
    axes = [fig.add_subplot(grid[0, 0])]
    axes += [fig.add_subplot(grid[0, i], sharex=axes[0], sharey=axes[0]) for i in range(1, n)]
    for ax in axes[1:]:
        ax.tick_params(labelleft=False)
    key = fig.add_subplot(grid[1, :])
    key.set_axis_off()
    labels, starred = [], []
    for ax, i in zip(axes, range(n)):
        panel_labels, star = _work_precision_panel(ax, ds.isel(delta=i), methods)
        labels.append(panel_labels)
        ax.set_xlabel(WP_XLABEL)
        if star:
            starred.append(i)
    axes[0].set_ylabel(WP_YLABEL)
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
    key.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 1.0), fontsize=7.5,
               ncols=max(1, min(len(handles), int(width // LEGEND_COLUMN_WIDTH))))
    _header(fig, WP_TITLE, _wp_params(ds), fit=False)     # its two lines kept: `_fit_header`
    notes = [_restart_footnote(ds, starred)] if starred else []
    if missing:
        notes.append(f"{missing} runs found no impact (not drawn)")
    if notes:  # the figure's x label sits below the legend: the footnote's place
        chars = int(fig.get_figwidth() * FOOTNOTE_CHARS_PER_INCH)
        text = "\n".join(textwrap.fill(line, chars, subsequent_indent="  ")
                         for note in notes for line in note.split("\n"))
        fig.supxlabel(text, x=0.005, ha="left", fontsize=FOOTNOTE_SIZE, color="0.2",
                      gid="footnote")
    renderer = fig.canvas.get_renderer()
    _fit_header(fig, renderer)
    fig.draw_without_rendering()
    for ax, panel_labels in zip(axes, labels):
        place_setting_labels(ax, panel_labels, renderer)
    return fig


def _fit_header(fig, renderer):
    """Shrink the header's font, if need be, until its widest line fits the figure."""
    header = next(t for t in fig.texts if t.get_text().startswith(WP_TITLE))
    fig.draw_without_rendering()
    ratio = 0.98 * fig.bbox.width / header.get_window_extent(renderer).width
    if ratio < 1.0:
        header.set_fontsize(max(header.get_fontsize() * ratio, MIN_HEADER_SIZE))


def _wp_params(ds):
    """The header's two parameter lines: the problem; how error and cost were measured."""
    repeats = np.unique(np.asarray(ds["timing_repeats"]))
    statistic = {"min": "fastest"}.get(str(_attr(ds, "timing_statistic")),
                                       str(_attr(ds, "timing_statistic")))
    timed = (f"{statistic} of {int(repeats[0])} runs" if repeats.size == 1
             else f"{statistic} of {int(repeats.min())}-{int(repeats.max())} runs")
    return (rf"$\zeta$ = {_num(_attr(ds, 'zeta'))}, $\varepsilon$ = {_num(_attr(ds, 'eps'))}; "
            rf"force $r(\tau)$: N(0, 1) samples every $\Delta\tau$ = {_num(_attr(ds, 'dt'))}, "
            f"linear in between (seed {_attr(ds, 'seed')}); from rest at "
            r"$x = \min(0, \delta)$"
            f"\n{WP_ERROR}; cost: {timed}, on {_attr(ds, 'machine')} "
            f"({int(_attr(ds, 'cpu_count'))} CPUs, load "
            f"{float(_attr(ds, 'load_average_start')):.1f} before, "
            f"{float(_attr(ds, 'load_average_end')):.1f} after)")


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
    what = "rtol = atol =" if method.startswith("solve_ivp") else "step"
    span = settings[0] if len(settings) == 1 else f"{settings[0]} ... {settings[-1]}"
    return f"{method}, {what} {span}"


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
