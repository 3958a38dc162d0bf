"""Escape against noise level: the residence times of the impact motions against 1/rms^2.

One panel per cell of the (1/beta_f, delta) plane: the mean residence time of each state
(the motions and "none") on a log axis against 1/rms^2, with the straight line of
ln(residence time) against 1/rms^2 fitted over the weak-noise levels (`stats.escape_fit`,
stored in the dataset by the aggregation: the figure draws, it does not fit), and the levels
where a motion was never left drawn as lower bounds.
"""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter

from vibroimpact._symbols import fixed_caption, parameter_symbol
from vibroimpact.plotting._common import (CONFIDENCE, _attr, _decoded, _header, _num,
                                          _spectrum_parts, _styled, _system_text, motion_title,
                                          law_caption, note_on_axes)
from vibroimpact.plotting.maps import TYPE_COLORS
from vibroimpact.stats.escape import MIN_FIT_LEVELS, censored_bound
from vibroimpact.stats.events import t_quantile

__all__ = ["escape_vs_noise"]

#: Colour of the state "none" (time in no listed motion).
NONE_COLOR = "0.45"
#: Markers of the states, in the order of the dataset's ``state``.
STATE_MARKERS = ("o", "s", "^", "D", "v", "P")
#: Look of the levels left out of the fits by ``fit_max_rms``: a light band.
OUTSIDE_FIT_STYLE = dict(color="0.9", zorder=0, linewidth=0)


def _state_label(name):
    return motion_title(name)


def _interval_text(value, lo, hi):
    """``0.163 [0.146, 0.180]``: the value and its interval to the decimal of the interval's
    second significant digit (half its width), no more; 3 significant digits when the
    interval has no width."""
    half = 0.5 * (float(hi) - float(lo))
    if not (np.isfinite(half) and half > 0.0):
        return f"{value:.3g} [{lo:.3g}, {hi:.3g}]"
    decimals = max(0, 1 - int(np.floor(np.log10(half))))
    # + 0.0 turns the -0.0 of a value that rounds to zero into 0.0
    value, lo, hi = (round(float(v), decimals) + 0.0 for v in (value, lo, hi))
    return f"{value:.{decimals}f} [{lo:.{decimals}f}, {hi:.{decimals}f}]"


def _fit_text(cell, k):
    """``Delta = 0.163 [0.146, 0.180]``, with chi^2/dof when there is one."""
    text = r"$\Delta$ = " + _interval_text(cell["slope"].values[k], cell["slope_lo"].values[k],
                                           cell["slope_hi"].values[k])
    chi2 = float(cell["chi2_red"].values[k])
    return text + (rf", $\chi^2/\nu$ = {chi2:.2g}" if np.isfinite(chi2) else "")


def _no_fit_text(cell, k, min_stretches, allowed):
    """``no fit: 2 levels with >= 20 complete stretches (3 needed)``."""
    n = cell["n_stretches"].values[:, k]
    usable = int(np.count_nonzero((n >= min_stretches) & allowed))
    return (f"no fit: {usable} level{'s' if usable != 1 else ''} with "
            rf"$\geq$ {min_stretches} complete stretches ({MIN_FIT_LEVELS} needed)")


def _panel(ax, cell, states, min_stretches, x_line, home, allowed):
    """One cell: points with error bars (filled: in the fit), the levels where a motion was
    never left drawn as lower bounds, the fitted lines (solid for the cell's ``home`` state,
    thin dashed for the others); returns whether it holds a point."""
    x = cell["inv_rms2"].values
    drawn = False
    for k, name in enumerate(states):
        t = cell["residence_time"].values[:, k]
        e = cell["residence_time_stderr"].values[:, k]
        n = cell["n_stretches"].values[:, k]
        used = cell["fit_used"].values[:, k].astype(bool)
        shown = np.isfinite(t) & (t > 0) & (n >= min(min_stretches, 2))
        bound = (censored_bound(n, cell["n_censored"].values[:, k],
                                cell["censored_time"].values[:, k],
                                cell["probability"].values[:, k])
                 if "censored_time" in cell else np.full(x.shape, np.nan))
        bounded = np.isfinite(bound)
        if not (shown.any() or bounded.any()) or ((n < min_stretches).all()
                                                  and not bounded.any()):
            continue            # a state never held long enough to say anything
        drawn = True
        color = NONE_COLOR if name == "none" else TYPE_COLORS[k % len(TYPE_COLORS)]
        marker = STATE_MARKERS[k % len(STATE_MARKERS)]
        # the same confidence as Delta's interval: +-t s.e. of a mean of n stretches, the
        # lower end kept above 0 on the log axis
        half = np.nan_to_num(t_quantile(n, CONFIDENCE) * e)
        err = np.vstack([np.minimum(half, 0.999 * np.nan_to_num(t)), half])
        label = _state_label(name)
        fitted = np.isfinite(cell["slope"].values[k])
        label += ": " + (_fit_text(cell, k) if fitted
                         else _no_fit_text(cell, k, min_stretches, allowed))
        labelled = False
        for mask, face, gid in ((shown & used, color, "fitted_points"),
                                (shown & ~used, "white", "excluded_points")):
            if mask.any():
                ax.errorbar(x[mask], t[mask], yerr=err[:, mask], fmt=marker, color=color,
                            markerfacecolor=face, markersize=5, capsize=2, linestyle="none",
                            gid=gid, label=None if labelled else label)
                labelled = True
        if bounded.any():
            # never left: the mean is longer than the cut stretches' mean length, an arrow
            # up from it (to twice the bound on the log axis)
            ax.errorbar(x[bounded], bound[bounded], yerr=[np.zeros(bounded.sum()),
                                                          bound[bounded]],
                        lolims=True, fmt="_", markersize=9, color=color, capsize=3,
                        linestyle="none", gid="censored_bound",
                        label=None if labelled else label)
        if fitted:
            line = np.exp(cell["intercept"].values[k] + cell["slope"].values[k] * x_line)
            ax.plot(x_line, line, color=color, gid="fit",
                    **(dict(linewidth=1.4) if k == home else dict(linewidth=0.8,
                                                                   linestyle="--")))
    return drawn


@_styled
def escape_vs_noise(escape):
    """Mean residence time of each impact motion against 1/rms^2, one panel per cell.

    Parameters
    ----------
    escape : xarray.Dataset
        ``results/datasets/{study}_escape.nc`` (docs/datasets.md): ``residence_time``,
        ``residence_time_stderr``, ``n_stretches``, ``probability``, ``fit_used`` over
        ``(rms, cell, state)``, the fits ``slope``, ``slope_lo``, ``slope_hi``,
        ``intercept``, ``chi2_red`` over ``(cell, state)``.

    Returns
    -------
    matplotlib.figure.Figure
        Per cell: the residence times (forcing periods, log axis) with `CONFIDENCE` bars
        (+-t standard errors of the mean of the n complete stretches, t of n - 1 dof, as
        Delta's interval), filled where the level is in the fit (gid ``"fitted_points"``),
        open where it is not (``"excluded_points"``: fewer than ``min_stretches`` complete
        stretches, or rms above ``fit_max_rms``, whose levels lie in a grey band, or no fit:
        fewer than three such levels); where a motion holding most of the record was never
        left (no complete stretch), an arrow up from the mean length of its cut stretches
        (``"censored_bound"``, `stats.censored_bound`: a lower bound, not in the fit); the
        fitted lines (``"fit"``) with Delta, its 95 % interval and chi^2 per degree of
        freedom in the legend, or why there is no fit. A state with fewer than
        ``min_stretches`` complete stretches at every level and no bound is not drawn.
    """
    states = [str(s) for s in escape["state"].values]
    n_cells = escape.sizes["cell"]
    min_stretches = int(_attr(escape, "min_stretches"))
    top = float(escape.attrs.get("fit_max_rms", np.nan))
    x = escape["inv_rms2"].values
    x_line = np.linspace(0.75 * x.min(), 1.05 * x.max(), 200)
    ncols = min(n_cells, 3)
    nrows = -(-n_cells // ncols)
    fig = Figure(figsize=(4.6 * ncols + 0.4, 4.4 * nrows + 1.6), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax in axes[n_cells:]:
        ax.set_visible(False)
    weakest = int(np.argmin(escape["rms"].values))
    for c, ax in enumerate(axes[:n_cells]):
        cell = escape.isel(cell=c)
        if np.isfinite(top):
            ax.axvspan(x_line[0], 1.0 / top ** 2, gid="outside_fit", **OUTSIDE_FIT_STYLE)
        share = cell["probability"].values[weakest]
        home = int(np.argmax(share))
        allowed = (escape["rms"].values <= top * (1 + 1e-12) if np.isfinite(top)
                   else np.ones(escape.sizes["rms"], dtype=bool))
        if not _panel(ax, cell, states, min_stretches, x_line, home, allowed):
            note_on_axes(ax, f"no state with {min_stretches} complete stretches\n"
                             "at any noise level")
        else:
            ax.set_yscale("log")
            plain = FuncFormatter(lambda v, _: f"{v:g}")
            ax.yaxis.set_major_formatter(plain)
            ax.yaxis.set_minor_formatter(FuncFormatter(
                lambda v, _: f"{v:g}" if f"{v:g}"[0] in "25" else ""))
            ax.legend(loc="upper left", fontsize=6.5, title_fontsize=6.5,
                      title=r"fit $\ln T = \ln C + \Delta/\mathrm{rms}_r^2$:  $\Delta$ "
                      f"[{int(100 * CONFIDENCE)} % interval]" + r", $\chi^2$ per d.o.f. $\nu$")
        ax.set_title(f"{_cell_text(escape, cell)}: {_state_label(states[home])} "
                     rf"{100 * share[home]:.0f} % at rms {_num(escape['rms'].values[weakest])}")
        ax.set_xlim(x_line[0], x_line[-1])
        ax.set_xlabel(r"$1/\mathrm{rms}_r^2$")
        ax.set_ylabel("mean residence time (forcing periods)")
        top_axis = ax.secondary_xaxis("top", functions=(_rms_of, _inv2_of))
        top_axis.set_xticks(escape["rms"].values)
        top_axis.set_xticklabels([_num(v) for v in escape["rms"].values], fontsize=7)
        top_axis.set_xlabel(r"rms$_r$", fontsize=8)
    handles = [Line2D([], [], marker="o", color="0.3", linestyle="none",
                      label=f"in the fit (bars: {100 * CONFIDENCE:g} %, $\\pm$t s.e. of the "
                            "mean of n stretches, t of n - 1 d.o.f.)"),
               Line2D([], [], marker="o", color="0.3", markerfacecolor="white",
                      linestyle="none",
                      label=f"not in a fit (fewer than {min_stretches} complete stretches"
                            + (f", or rms > {_num(top)}" if np.isfinite(top) else "")
                            + f"; no fit from fewer than {MIN_FIT_LEVELS} levels)")]
    if "censored_time" in escape and _has_bound(escape, states):
        handles.append(Line2D([], [], marker="$\\uparrow$", color="0.3", linestyle="none",
                              markersize=8,
                              label="never left: T above the mean length of its stretches "
                                    "cut by the record (lower bound, not in the fit)"))
    if np.isfinite(top):
        handles.append(Patch(label=f"rms > {_num(top)}: outside the fits",
                             **{k: v for k, v in OUTSIDE_FIT_STYLE.items() if k == "color"}))
    # side by side under three panels; one above another under fewer (their labels are long)
    fig.legend(handles=handles, loc="outside lower center",
               ncols=len(handles) if ncols >= 3 else 1, fontsize=7)
    noise = ", ".join(_spectrum_parts(escape.attrs))
    law = law_caption(escape)
    system, force = ((f"{_system_text(escape)};  ", r"$\sin(\beta_f\tau) + r(\tau)$")
                     if _cell_axes(escape) == ("inv_beta", "delta") else
                     (f"fixed: {fixed_caption(_decoded(escape.attrs['fixed'], 'fixed'))}"
                      + (f", {law}" if law else "") + ";  ",
                      r"$A\sin(\beta_f\tau) + r(\tau)$"))
    _header(fig, "Escape from the impact motions against the noise level",
            f"{system}"
            rf"$f(\tau)$ = {force} ({noise});  "
            f"each cell from rest on one record per rms, "
            f"{float(_attr(escape, 'record_length')):,.0f} time units after the transient "
            f"{_num(_attr(escape, 'transient'))} "
            f"(seed {_attr(escape, 'seed')}, a spawned child per rms)\n"
            "residence time T: mean length of the complete stretches of a motion (free and "
            rf"impact-stick together), $w$ = {_num(_attr(escape, 'motion_window'))};  "
            r"$\Delta$: slope of $\ln T$ against $1/\mathrm{rms}_r^2$ (weighted)")
    return fig


def _has_bound(escape, states):
    """Whether any (level, cell, state) is drawn as a lower bound."""
    return bool(np.isfinite(censored_bound(
        escape["n_stretches"].values, escape["n_censored"].values,
        escape["censored_time"].values, escape["probability"].values)).any())


def _cell_axes(escape):
    """The two parameters an escape cell is given by: ``attrs["axes"]`` of a plane study's
    dataset, else the paper's ``("inv_beta", "delta")``."""
    axes = escape.attrs.get("axes")
    if axes is None:
        return ("inv_beta", "delta")
    if isinstance(axes, str):
        axes = _decoded(axes, "axes") if axes.lstrip().startswith("[") else axes.split()
    return tuple(str(a) for a in np.atleast_1d(axes))


def _cell_text(escape, cell):
    """``"$1/\\beta_f$ = 1.1, $\\delta$ = 1"``: a cell in its plane's symbols."""
    return ", ".join(f"{parameter_symbol(k)} = {_num(cell[k])}" for k in _cell_axes(escape))


def _rms_of(x):
    """rms from 1/rms^2 (the top axis; kept finite where matplotlib probes x <= 0)."""
    return 1.0 / np.sqrt(np.maximum(np.asarray(x, dtype=float), 1e-300))


def _inv2_of(r):
    """1/rms^2 from rms."""
    return 1.0 / np.maximum(np.asarray(r, dtype=float), 1e-150) ** 2
