"""Fig. 16: domains of stable periodic impact motions under the harmonic force alone."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from vibroimpact.plotting._common import _attr, _header, _styled, _system_text, axis_label

REASON_COLORS = {1: "white", 2: "0.82", 3: "#f4b6b6"}
#: Contour levels of the degree of stability S (%).
S_LEVELS = (5, 10, 20, 30, 40, 50, 60, 70, 80, 90)
#: Levels of the filled S map: steps fine enough that no band edge reads as a line.
S_FILL_LEVELS = np.linspace(0.0, 100.0, 101)
#: One colour per motion type in panel (a): the Okabe-Ito qualitative palette, which readers
#: with the common colour-vision deficiencies can also tell apart (black last).
TYPE_COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000")
#: Labels of S contours closer than this (fraction of the panel's width and height) to an
#: already placed one are dropped, so the labels stay readable.
LABEL_SPACING = 0.1
#: lam within this relative distance of eps e^(-zeta z / m) counts as complex multipliers.
COMPLEX_RTOL = 1e-7


def complex_multipliers(orbits, m, n):
    """Where the most stable (m/n) motion has a complex pair of multipliers.

    Parameters
    ----------
    orbits : xarray.Dataset
        Orbit map of one type: ``lam(inv_beta, delta)``; global attributes ``zeta``, ``eps``.
    m, n : int
        The motion type.

    Returns
    -------
    ndarray of bool, shape (inv_beta, delta)

    Notes
    -----
    Complex multipliers have ``|mu| = sqrt(det T) = eps^m e^(-zeta z)`` (docs/model.md,
    Section 8.7), so there ``lam = eps e^(-zeta z / m)`` and ``S = 100 (1 - lam)`` depend on
    1/beta alone (``z = 2 pi n / beta``): contours of S are vertical lines there. Where the
    multipliers turn real, S leaves that value with infinite slope (a square-root branch), so
    contour levels interpolated across the switch are artefacts of the grid.
    """
    zeta, eps = float(_attr(orbits, "zeta")), float(_attr(orbits, "eps"))
    z = 2.0 * np.pi * n * np.asarray(orbits["inv_beta"], dtype=float)
    lam_c = eps * np.exp(-zeta * z / m)
    lam = np.asarray(orbits["lam"], dtype=float)
    with np.errstate(invalid="ignore"):
        return lam <= lam_c[:, None] * (1.0 + COMPLEX_RTOL)


def _thin_labels(ax, lines):
    """Label the contour `lines` where the labels keep `LABEL_SPACING` from each other."""
    texts = ax.clabel(lines, fmt="%d", fontsize=6, inline=False)
    to_axes = ax.transData + ax.transAxes.inverted()
    kept = []
    for text in sorted(texts, key=lambda t: t.get_position()[0]):
        xy = to_axes.transform(text.get_position())
        if all(np.max(np.abs(xy - other)) >= LABEL_SPACING for other, _ in kept):
            kept.append((xy, text.get_position()))
    for text in list(texts):
        text.remove()
    lines.labelTexts.clear()
    lines.labelXYs.clear()
    lines.labelCValues.clear()
    if kept:
        ax.clabel(lines, fmt="%d", fontsize=6, inline=True, inline_spacing=2,
                  manual=[xy for _, xy in kept])


@_styled
def fig16(orbits):
    """Domains of stable (m/n) periodic impact motions over the (1/beta, delta) plane.

    Parameters
    ----------
    orbits : xarray.Dataset
        ``results/orbits/{name}.nc``: ``n_stable``, ``lam``, ``S``, ``reason`` over
        ``(type, inv_beta, delta)``; global attributes ``zeta``, ``eps``.

    Returns
    -------
    matplotlib.figure.Figure
        Panel (a) outlines the stable domain of every type, one qualitative colour each.
        One panel per type then shows the degree of stability S in colour (1 % steps), the
        stable domain's edge (bold), the regions where only unstable solutions exist (red)
        or solutions exist but cross the wall (grey); white is no solution at all.
        Labelled thin contours of S are drawn where the multipliers are real; where they are
        complex S depends on 1/beta alone (`complex_multipliers`), so no contour is drawn
        there and a dotted line marks that region's edge.
    """
    types = [str(t) for t in orbits["type"].values]
    ncols = 3
    nrows = -(-(len(types) + 1) // ncols)
    fig = Figure(figsize=(10.0, 3.3 * nrows))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False).ravel()
    x = orbits["inv_beta"].values
    y = orbits["delta"].values
    overview = axes[0]
    shaded = None
    for i, name in enumerate(types):
        sel = orbits.sel(type=name)
        color = TYPE_COLORS[i % len(TYPE_COLORS)]
        stable = sel["n_stable"].values > 0
        if stable.any():
            overview.contour(x, y, stable.T.astype(float), levels=[0.5], colors=[color],
                             linewidths=1.8)
        overview.plot([], [], color=color, lw=1.8, label=f"({name})")
        ax = axes[i + 1]
        reason = sel["reason"].values.T
        for code, colour in REASON_COLORS.items():
            mask = np.where(reason == code, 1.0, np.nan)
            ax.contourf(x, y, mask, levels=[0.5, 1.5], colors=[colour])
        S = np.where(stable, sel["S"].values, np.nan)
        if np.isfinite(S).any():
            m, n = (int(k) for k in name.split("/"))
            cplx = complex_multipliers(sel, m, n) & stable
            # 1 % steps: coarser filled bands draw their edges as lines across the plateau
            # (opaque, edges in the face colour: translucent bands show their seams as lines)
            shaded = ax.contourf(x, y, S.T, levels=S_FILL_LEVELS, cmap="viridis_r")
            shaded.set_edgecolor("face")
            real = np.where(cplx, np.nan, S).T
            if np.isfinite(real).any():
                lines = ax.contour(x, y, real, levels=S_LEVELS, colors="k", linewidths=0.5)
                _thin_labels(ax, lines)
            if cplx.any() and (stable & ~cplx).any():
                # between stable cells only: the domain's own edge is the bold line
                edge = np.where(stable, cplx, np.nan).T
                ax.contour(x, y, edge, levels=[0.5], colors="0.1",
                           linewidths=0.9, linestyles=":")
            ax.contour(x, y, stable.T.astype(float), levels=[0.5], colors="k", linewidths=1.8)
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
               Patch(facecolor="white", edgecolor="0.6", label="no solution (D, V, X)"),
               Line2D([], [], color="0.1", lw=0.9, ls=":",
                      label=r"edge of complex multipliers (inside: $S = 100(1 - "
                            r"\varepsilon e^{-\zeta z/m})$, no contours)")]
    if shaded is not None:
        fig.colorbar(shaded, ax=axes[1:].tolist(), label="degree of stability S (%)", shrink=0.8,
                     ticks=np.arange(0, 101, 10))
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7)
    _header(fig, "Fig. 16  Parameter domains of stable periodic impact motions",
            rf"{_system_text(orbits)};  f($\tau$) = $\sin(\beta_f\tau)$; bold: stable domain, "
            "thin: contours of S (%)")
    return fig
