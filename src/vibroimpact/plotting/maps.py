"""Fig. 15, the probability maps of the impact motions, and their comparison with Fig. 16."""
from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from vibroimpact import stats
from vibroimpact.plotting._common import (_attr, _header, _noise_text, _num, _styled,
                                          _system_text, axis_label)
from vibroimpact.plotting.orbits import S_LEVELS, TYPE_COLORS

#: Probability contours (%) of Fig. 15 (the paper draws 10 % steps).
PROBABILITY_LEVELS = (10, 20, 30, 40, 50, 60, 70, 80, 90)
#: Probability contours (%) drawn over the stable domains in the comparison with Fig. 16.
COMPARISON_LEVELS = (20, 50, 80)
#: Hatching of cells whose record switched too rarely between motions to be trusted.
FEW_SWITCHES_HATCH = "////"


def _map_forcing_text(ds):
    """``f(tau) = A sin(beta_f tau) + r(tau) (noise)``, beta_f the map's coordinate."""
    amplitude = float(_attr(ds, "amplitude"))
    scale = "" if amplitude == 1.0 else _num(amplitude)
    return rf"f($\tau$) = {scale}$\sin(\beta_f\tau)$ + r($\tau$) ({_noise_text(ds)})"


def _map_text(ds):
    """The map's statistics: window, target precision, share reached, record lengths."""
    reached = float(np.mean(ds["reached"].values))
    t = ds["simulated_time"].values
    return (rf"z_j between collisions (chatter and sticking grouped), "
            rf"w = {_num(_attr(ds, 'motion_window'))};  each cell from rest over one noise record, "
            rf"to s.e. $\leq$ {100 * float(_attr(ds, 'target_stderr')):.3g} pp "
            rf"({100 * reached:.1f} % of cells) or {int(_attr(ds, 'max_periods'))} periods;  "
            rf"record {t.min():.0f}-{t.max():.0f} (median {np.median(t):.0f})")


def _grid(ds):
    return ds["inv_beta"].values, ds["delta"].values


def _few_switches(ax, x, y, few):
    """Hatch the cells whose probabilities are not stationary (`motion_map_cell`)."""
    if few.any():
        ax.contourf(x, y, few.T.astype(float), levels=[0.5, 1.5], colors="none",
                    hatches=[FEW_SWITCHES_HATCH])


def _finish_figure(fig, motion_map, handles, title):
    """Legend below the panels and the header: system, forcing, the map's statistics."""
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7)
    _header(fig, title, f"{_system_text(motion_map)};  {_map_forcing_text(motion_map)}\n"
                        f"{_map_text(motion_map)}")
    return fig


def _finish_axes(axes, ds):
    for ax in axes:
        ax.set_xlabel(axis_label(ds["inv_beta"]))
        ax.set_ylabel(axis_label(ds["delta"]))
        ax.label_outer()


@_styled
def fig15(motion_map, levels=PROBABILITY_LEVELS):
    """Fig. 15: probability (%) of each impact motion over the (1/beta, delta) plane.

    Parameters
    ----------
    motion_map : xarray.Dataset
        ``results/datasets/{study}_map.nc``: ``probability(motion, inv_beta, delta)``,
        ``few_switches``, ``reached``; attributes of the study and the map.
    levels : sequence of float
        Contour levels in percent.

    Returns
    -------
    matplotlib.figure.Figure
        One contour map per motion with free flights (the periodic impact motions of Fig. 16)
        and, when the dataset has ``stick_probability``, one of their impact-stick variants
        together (a collision of the motion ends sticking: the impact-chatter-stick cycle of
        a pre-loaded wall, which `periodic_orbits` does not return): filled bands and
        labelled lines of the probability in percent; hatched where the record switched
        between motions only 1 to ``min_switches - 1`` times (its numbers say where it
        started, not the long-run share); dots where the cap stopped the cell before the
        target precision.
    """
    motions = [str(m) for m in motion_map["motion"].values]
    panels = [(f"({m})", motion_map["probability"].sel(motion=m).values) for m in motions]
    if "stick_probability" in motion_map:
        panels.append((" + ".join(f"({m})" for m in motions) + " with sticking",
                       motion_map["stick_probability"].sum("motion").values))
    x, y = _grid(motion_map)
    fig = Figure(figsize=(4.0 * len(panels) + 1.0, 4.4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(panels), sharex=True, sharey=True, squeeze=False).ravel()
    few = motion_map["few_switches"].values.astype(bool)
    short = ~motion_map["reached"].values.astype(bool)
    fill_levels = [0.0, *levels, 100.0]
    shaded = None
    for ax, (title, prob) in zip(axes, panels):
        p = 100.0 * prob
        shaded = ax.contourf(x, y, p.T, levels=fill_levels, cmap="Blues", vmin=-10, vmax=100)
        lines = ax.contour(x, y, p.T, levels=levels, colors="k", linewidths=0.6)
        ax.clabel(lines, fmt="%d", fontsize=6)
        _few_switches(ax, x, y, few)
        if short.any():
            i, j = np.nonzero(short)
            ax.plot(x[i], y[j], ls="none", marker=".", ms=1.5, color="C3")
        ax.set_title(title, fontsize=9 if len(title) > 12 else None)
    _finish_axes(axes, motion_map)
    fig.colorbar(shaded, ax=axes.tolist(), label="probability of the motion (%)", shrink=0.85)
    handles = [Patch(facecolor="white", edgecolor="k", hatch=FEW_SWITCHES_HATCH,
                     label=f"1 to {int(_attr(motion_map, 'min_switches')) - 1} switches "
                           "between motions: not stationary")]
    if short.any():
        handles.append(Line2D([], [], ls="none", marker=".", color="C3",
                              label="target precision not reached (cap)"))
    return _finish_figure(fig, motion_map, handles,
                          "Fig. 15  Probability of the impact motions under harmonic plus random force")


def _orbits_on(motion_map, orbits, name):
    """``(stable, S)`` of motion `name` on the map's grid (nearest orbit-map cell)."""
    sel = orbits.sel(type=name).sel(inv_beta=motion_map["inv_beta"], delta=motion_map["delta"],
                                    method="nearest")
    stable = sel["n_stable"].values > 0
    return stable, np.where(stable, sel["S"].values, np.nan)


def map_agreement(motion_map, orbits, threshold=0.5):
    """`stats.motion_map_agreement` of every motion the map and the orbit map share.

    The orbit map is read at its cell nearest to each map cell (grids may differ).
    Returns ``{motion: dict}``.
    """
    shared = [str(m) for m in motion_map["motion"].values if str(m) in orbits["type"].values]
    out = {}
    for name in shared:
        stable, S = _orbits_on(motion_map, orbits, name)
        p = motion_map["probability"].sel(motion=name).values
        out[name] = stats.motion_map_agreement(p, stable, S, threshold)
    return out


def _agreement_text(a):
    def pct(v):
        return "n/a" if not np.isfinite(v) else f"{100 * v:.0f} %"
    rho = "n/a" if not np.isfinite(a["rank_correlation"]) else f"{a['rank_correlation']:.2f}"
    return (f"P ≥ 50 %: {a['n_dominant']} cells, {pct(a['dominant_inside'])} inside\n"
            f"domain with P ≥ 50 %: {pct(a['domain_covered'])}\n"
            f"rank corr. (P, S) inside: {rho}")


@_styled
def fig15_vs_fig16(motion_map, orbits, levels=COMPARISON_LEVELS):
    """The probability contours of Fig. 15 over the stable domains and S contours of Fig. 16.

    Parameters
    ----------
    motion_map : xarray.Dataset
        Probability map (as for :func:`fig15`).
    orbits : xarray.Dataset
        Orbit map of the same system (``results/orbits/{name}.nc``); its zeta and eps must
        equal the map's.
    levels : sequence of float
        Probability contours drawn (%).

    Returns
    -------
    matplotlib.figure.Figure
        One panel per motion in both maps: the stable domain under ``sin(beta_f tau)`` alone
        shaded, its thin S contours, the probability contours under harmonic plus random
        force in colour, and the agreement numbers of :func:`map_agreement` (share of the
        cells with probability >= 50 % inside the stable domain; share of the domain where
        the motion dominates; Spearman's rank correlation of probability and S there).
    """
    for key in ("zeta", "eps"):
        if float(_attr(motion_map, key)) != float(_attr(orbits, key)):
            raise ValueError(f"the map has {key} = {_attr(motion_map, key)!r} but the orbit map "
                             f"{_attr(orbits, key)!r}: not the same system")
    agreement = map_agreement(motion_map, orbits)
    if not agreement:
        raise ValueError(f"no motion of the map {list(motion_map['motion'].values)} is in the "
                         f"orbit map {list(orbits['type'].values)}")
    x, y = _grid(motion_map)
    xo, yo = orbits["inv_beta"].values, orbits["delta"].values
    fig = Figure(figsize=(4.0 * len(agreement) + 0.5, 4.8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(agreement), sharex=True, sharey=True, squeeze=False).ravel()
    few = motion_map["few_switches"].values.astype(bool)
    for k, (ax, name) in enumerate(zip(axes, agreement)):
        sel = orbits.sel(type=name)
        stable = sel["n_stable"].values > 0
        color = TYPE_COLORS[k % len(TYPE_COLORS)]
        if stable.any():
            ax.contourf(xo, yo, stable.T.astype(float), levels=[0.5, 1.5], colors=["0.88"])
            S = np.where(stable, sel["S"].values, np.nan)
            ax.contour(xo, yo, S.T, levels=S_LEVELS, colors="0.55", linewidths=0.4)
            ax.contour(xo, yo, stable.T.astype(float), levels=[0.5], colors="0.3",
                       linewidths=1.0)
        p = 100.0 * motion_map["probability"].sel(motion=name).values
        lines = ax.contour(x, y, p.T, levels=levels, colors=[color],
                           linewidths=[0.8, 1.8, 0.8][:len(levels)] if len(levels) == 3 else 1.2)
        ax.clabel(lines, fmt="%d %%", fontsize=6)
        _few_switches(ax, x, y, few)
        ax.text(0.98, 0.02, _agreement_text(agreement[name]), transform=ax.transAxes,
                ha="right", va="bottom", fontsize=6.5,
                bbox=dict(facecolor="white", edgecolor="0.7", alpha=0.85, pad=2))
        ax.set_title(f"({name})")
    _finish_axes(axes, motion_map)
    handles = [Patch(facecolor="0.88", edgecolor="0.3", label=r"stable under $\sin(\beta_f\tau)$ alone (Fig. 16)"),
               Line2D([], [], color="0.55", lw=0.4, label="its degree of stability S (%)"),
               Line2D([], [], color="k", lw=1.8,
                      label=f"probability {', '.join(map(str, levels))} % with noise (Fig. 15)"),
               Patch(facecolor="white", edgecolor="k", hatch=FEW_SWITCHES_HATCH,
                     label="few switches: not stationary")]
    return _finish_figure(fig, motion_map, handles,
                          "Fig. 15 over Fig. 16  Likely motions under noise and stable periodic motions")
