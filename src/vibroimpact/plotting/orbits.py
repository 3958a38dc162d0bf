"""Fig. 16: domains of stable periodic impact motions under the harmonic force alone."""
from __future__ import annotations

from matplotlib.patches import Patch
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from vibroimpact.plotting._common import (
    _colors, _header, _styled, _system_text, axis_label)


REASON_COLORS = {1: "white", 2: "0.82", 3: "#f4b6b6"}
#: Contour levels of the degree of stability S (%).
S_LEVELS = (5, 10, 20, 30, 40, 50, 60, 70, 80, 90)


@_styled
def fig16(orbits):
    """Domains of stable (m/n) periodic impact motions over the (1/beta, delta) plane.

    Panel (a) outlines the stable domain of every type; one panel per type then shows the
    degree of stability S (filled, with labelled contour lines), the stable domain's edge
    (bold), and the regions where only unstable solutions exist (red) or solutions exist but
    cross the wall (grey); white is no solution at all.
    """
    types = [str(t) for t in orbits["type"].values]
    ncols = 3
    nrows = -(-(len(types) + 1) // ncols)
    fig = Figure(figsize=(10.0, 3.3 * nrows))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False).ravel()
    x = orbits["inv_beta"].values
    y = orbits["delta"].values
    colors = _colors(len(types))
    overview = axes[0]
    filled = None
    for i, name in enumerate(types):
        sel = orbits.sel(type=name)
        stable = (sel["n_stable"].values > 0).T.astype(float)
        if stable.any():
            overview.contour(x, y, stable, levels=[0.5], colors=[colors[i]], linewidths=1.8)
        overview.plot([], [], color=colors[i], lw=1.8, label=f"({name})")
        ax = axes[i + 1]
        reason = sel["reason"].values.T
        for code, colour in REASON_COLORS.items():
            mask = np.where(reason == code, 1.0, np.nan)
            ax.contourf(x, y, mask, levels=[0.5, 1.5], colors=[colour])
        S = np.where(reason == 0, sel["S"].values.T, np.nan)
        if np.isfinite(S).any():
            filled = ax.contourf(x, y, S, levels=np.linspace(0, 100, 21), cmap="viridis_r", alpha=0.8)
            lines = ax.contour(x, y, S, levels=S_LEVELS, colors="k", linewidths=0.5)
            ax.clabel(lines, fmt="%d", fontsize=6)
            ax.contour(x, y, stable, levels=[0.5], colors="k", linewidths=1.8)
        ax.set_title(f"({name})")
    overview.set_title("(a) stable domains")
    overview.legend(loc="upper right")
    for ax in axes[len(types) + 1:]:
        ax.set_visible(False)
    for ax in axes:
        ax.set_xlabel(axis_label(orbits["inv_beta"]))
        ax.set_ylabel(axis_label(orbits["delta"]))
        ax.label_outer()
    for ax in axes[len(types) + 1 - ncols:len(types) + 1]:
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel(axis_label(orbits["inv_beta"]))
    handles = [Patch(facecolor=REASON_COLORS[3], label="only unstable (U)"),
               Patch(facecolor=REASON_COLORS[2], label="inadmissible: crosses the wall"),
               Patch(facecolor="white", edgecolor="0.6", label="no solution (D, V, X)")]
    if filled is not None:
        fig.colorbar(filled, ax=axes[1:].tolist(), label="degree of stability S (%)", shrink=0.8)
    fig.legend(handles=handles, loc="outside lower center", ncols=3, fontsize=7)
    _header(fig, "Fig. 16  Parameter domains of stable periodic impact motions",
            rf"{_system_text(orbits)};  f($\tau$) = $\sin(\beta_f\tau)$; bold: stable domain, "
            "thin: contours of S (%)")
    return fig
