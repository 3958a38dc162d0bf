"""Figures of the harmonic-plus-random study (paper section 5): Figs. 10-14."""
from __future__ import annotations

import re

import numpy as np

from vibroimpact.plotting._common import (
    SPECTRUM_BETA_MAX, _attr, _density_figure, _events_params, _figure, _header, _nearest,
    _num, _require_harmonic, _response_spectra, _styled, _trace_figure, _welch_text,
    axis_label)
from vibroimpact.plotting._common import two_wall_dataset
from vibroimpact.plotting.walls import two_walls, wall_density_figure
from vibroimpact.stats.centroid import CENTROID_BAND, LINE_BINS, shift
from vibroimpact.stats.motions import DEFAULT_MOTIONS, motion_key


def fig10(trace):
    """Fig. 10: (a) the input sin(beta_f tau) + r(tau); (b) a(tau) with the impacts.

    Parameters
    ----------
    trace : xarray.Dataset
        As for :func:`fig03`, with ``f(tau)`` the total force and attribute ``beta_f``.

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked axes sharing tau; (a) also shows the harmonic part f - r dashed.
    """
    return _trace_figure(trace, "Fig. 10  Harmonic plus random input and the motion of the mass",
                         harmonic=True)


@_styled
def fig11(spectra, inv_beta, beta_max=SPECTRUM_BETA_MAX):
    """Fig. 11: PSD of the input A sin(beta_f tau) + r(tau) at one forcing frequency.

    Parameters
    ----------
    spectra : xarray.Dataset
        Spectra dataset of the harmonic study: ``S_f(inv_beta, beta)`` (random part,
        estimated from the record), ``S_r_target(beta)``; attribute ``amplitude``.
    inv_beta : float
        1/beta_f; the nearest value of the dataset is shown (and printed).
    beta_max : float, optional
        Upper end of the frequency axis.

    Returns
    -------
    matplotlib.figure.Figure
        One log-y axes: the continuous part (the random input, estimate and target) and the
        harmonic part drawn as what it is, a spectral line at beta_f carrying the power
        A**2 / 2 (in the paper's two-sided angular convention the pair of delta functions
        ``pi A**2 / 2 [delta(beta - beta_f) + delta(beta + beta_f)]``), not a smeared peak.
    """
    fig, (ax,) = _figure()
    i = _nearest(spectra["inv_beta"], inv_beta)
    ds = spectra.isel(inv_beta=i)
    ds = ds.isel(beta=np.flatnonzero(np.asarray(ds["beta"]) <= beta_max))
    ax.plot(ds["beta"], ds["S_f"], color="C0",
            label=r"random part $r(\tau)$: estimate from the simulated record")
    if "S_r_target" in ds:
        ax.plot(ds["beta"], ds["S_r_target"], color="k", ls="--", lw=1.0,
                label=r"random part: target $S_r$")
    amplitude = float(_attr(spectra, "amplitude"))
    beta_f = 1.0 / float(ds["inv_beta"])
    ax.set_yscale("log")
    low, high = ax.get_ylim()
    ax.set_ylim(low, high * 30.0)
    ax.annotate("", xy=(beta_f, 1.0), xycoords=("data", "axes fraction"), xytext=(beta_f, 0.0),
                textcoords=("data", "axes fraction"),
                arrowprops=dict(arrowstyle="-|>", color="C3", lw=1.6))
    ax.plot([], [], color="C3", lw=1.6,
            label=rf"line of $A\sin(\beta_f\tau)$, A = {_num(amplitude)}, at $\beta_f$ = "
                  rf"{_num(beta_f)}: power $A^2/2$ = {_num(amplitude ** 2 / 2)}")
    ax.set_xlim(0.0, float(ds["beta"].max()))
    ax.set_xlabel(axis_label(ds["beta"]))
    ax.set_ylabel(r"PSD $S_f(\beta)$ of the input (two-sided, angular)")
    ax.legend(loc="upper right", fontsize=7, title=_welch_text(ds, False), title_fontsize=7)
    _header(fig, "Fig. 11  Power spectral density of the harmonic plus random input",
            _events_params(spectra, i))
    return fig


@_styled
def fig12(spectra, inv_beta, beta_max=SPECTRUM_BETA_MAX):
    """Fig. 12: PSD of a(tau) under sin(tau/inv_beta) + r(tau), one curve per delta.

    Parameters
    ----------
    spectra : xarray.Dataset
        Spectra dataset of the harmonic study.
    inv_beta : float
        1/beta_f; the nearest value of the dataset is shown.
    beta_max : float, optional
        Upper end of the frequency axis.

    Returns
    -------
    matplotlib.figure.Figure
        As :func:`fig06`; S_lin (random part only) dashed, the forcing frequency dotted;
        each delta's legend entry gives the power of the response's line at beta_f
        (`vibroimpact.stats.line_power`), comparable with Fig. 11's A^2/2 where the Welch
        peak heights are not, and the legend's title the resolution. The header's last
        lines give the response's centroid (`vibroimpact.stats.centroid`, the reports'
        finding 5) at the largest delta and the smallest in both readings: with the lines at
        k beta_f (whose strength follows delta) and of the broadband response (the lines
        taken out), with its 95 % interval from the batch spectra; and, one wall only, which
        way the broadband centroid moves against the paper's "to lower frequency" when every
        choice of the measure reads the same way (not resolved otherwise).
    """
    i = _nearest(spectra["inv_beta"], inv_beta)
    return _response_spectra(
        spectra, i, r"Fig. 12  Power spectral density of the displacement $a(\tau)$ of the mass",
        _events_params(spectra, i) + _centroid_note(spectra, i), beta_max,
        r"linear $|H|^2 S_r$ (random part only)")


def _centroid_note(spectra, i_beta):
    """Header lines: the response's centroid at the largest and the smallest delta with
    the lines and of the broadband response (`vibroimpact.stats.centroid.shift`), and, one
    wall only, which way the broadband centroid moves against the paper (empty with fewer
    than two deltas)."""
    row = spectra.isel(inv_beta=i_beta).sortby("delta")
    if row.sizes["delta"] < 2:
        return ""
    sh = shift(row, 1.0 / float(row.inv_beta))
    if not np.all(np.isfinite(sh.centroid[[0, -1]])):
        return ""
    d_hi, d_lo = _num(float(sh.delta[-1])), _num(float(sh.delta[0]))

    def between(k):
        low, high = sh.centroid_low[k], sh.centroid_high[k]
        return (f"{sh.centroid[k]:.2f}" if not np.isfinite(low) else
                f"{sh.centroid[k]:.2f} [{low:.2f}, {high:.2f}]")

    text = (f"\nresponse's centroid ($\\beta \\leq$ {CENTROID_BAND:g}), $\\delta$ = {d_hi} "
            f"$\\to$ {d_lo}: with the lines at $k\\beta_f$ {sh.centroid_lines[-1]:.2f} $\\to$ "
            f"{sh.centroid_lines[0]:.2f}\nbroadband (lines' $\\pm${LINE_BINS} bins out): "
            f"{between(-1)} $\\to$ {between(0)}"
            + (f" (95 %, {sh.n_batches} batches)" if sh.n_batches else ""))
    if two_wall_dataset(spectra):   # two walls: the paper's finding (one wall) is no reference
        return text
    way = {"falls": "falls as $\\delta$ decreases, as in the paper",
           "rises": "rises as $\\delta$ decreases, against the paper",
           "unresolved": "shows no resolved move as $\\delta$ decreases"}[sh.reading()]
    scope = (f"under all {len(sh.change)} choices of the measure" if sh.reading() != "unresolved"
             else "no batch spectra" if not sh.n_batches else "not under every choice")
    return text + f"\nit {way}, {scope}"


@_styled
def fig13(events, inv_beta, density_delta=None):
    """Fig. 13: probability density of z_j / z (z = 2 pi / beta_f), one curve per density delta.

    Parameters
    ----------
    events : xarray.Dataset
        Events dataset of the harmonic study: ``ratio_density(inv_beta, delta, ratio)``.
    inv_beta : float
        1/beta_f; the nearest value of the dataset is shown.

    Returns
    -------
    matplotlib.figure.Figure
        (a) log and (b) linear density axes: one line per density delta, and the marks of
        the study's motions (the dataset's ``motion`` coordinate; the paper's (1/1), (2/1),
        (1/2) without one; :func:`ratio_marks`): a dotted line where a motion's intervals
        stand (one collision per n periods: z_j/z = n), a dash-dot line at the centre of a
        motion's groups of intervals (m >= 2 collisions per n periods: z_j/z = n/m; its
        label points to both sides, where the intervals of an uneven group lie). With the
        paper's motions: dash-dot at 1/2 ((2/1) pairs), dotted at 1 ((1/1)) and 2 ((1/2));
        with a clearance's motions the line at 1/2 is (1,1)/1's, whose symmetric form peaks
        on it (stops symmetric about the rest position).

    Raises
    ------
    ValueError
        If `events` is not from a harmonic study (no forcing period, no ``ratio_density``).
    """
    _require_harmonic(events, "fig13")
    i = _nearest(events["inv_beta"], inv_beta)
    fig, axes = _density_figure(
        events, i, "ratio_density",
        r"Fig. 13  Probability density of $z_j/z$, the interval over the forcing period",
        _events_params(events, i, ("interval",)), density_delta, linear=True)
    names = (events["motion"].values if "motion" in events.coords
             else [motion_key(m) for m in DEFAULT_MOTIONS])
    marks = ratio_marks(names)
    for ax in axes:
        for x, ls, texts in marks:
            ax.axvline(x, color="0.3", ls=ls, lw=1.0)
            for row, (text, ha) in enumerate(texts):
                ax.text(x, 0.97 - MARK_ROW * row, text, transform=ax.get_xaxis_transform(),
                        ha=ha, va="top", fontsize=8, color="0.3")
    return fig


#: Height (a fraction of the axes) between two labels of fig13 on one line.
MARK_ROW = 0.08


def ratio_marks(names):
    """Where fig13 marks each motion on the z_j/z axis, and how.

    Parameters
    ----------
    names : sequence of str
        Motion names, ``"m/n"`` (m collisions per n forcing periods, either wall) or
        ``"(m_upper,m_lower)/n"`` (two walls; `stats.motions.motion_key`).

    Returns
    -------
    list of (x, linestyle, [(text, ha), ...])
        One entry per position, ascending. A motion of one collision per n periods has its
        intervals at z_j/z = n: dotted, its name to the right of the line. A motion of m >= 2
        collisions has groups of m intervals adding up to n periods, centred on n/m (on it
        when the group is even, on both sides otherwise, as the (2/1) pairs of the paper):
        dash-dot (unless a one-collision motion stands there too), its label centred,
        pointing both ways. Motions with the same m and n share a label; labels at one
        position are stacked, the one-collision motions' first.
    """
    groups = {}
    for name in names:
        name = str(name)
        found = re.fullmatch(r"\((\d+),(\d+)\)/(\d+)|(\d+)/(\d+)", name)
        if found is None:
            raise ValueError(f"a motion name is 'm/n' or '(m_upper,m_lower)/n', got {name!r}")
        mu, ml, n2, m1, n1 = found.groups()
        m, n = (int(mu) + int(ml), int(n2)) if m1 is None else (int(m1), int(n1))
        if m < 1 or n < 1:
            raise ValueError(f"motion {name!r} has no collision or no period")
        groups.setdefault((m, n), []).append(name if name.startswith("(") else f"({name})")
    at = {}
    for (m, n), shown in groups.items():
        joined = ", ".join(shown)
        period = "z" if n == 1 else f"{n}z"
        if m == 1:
            text = (f" {joined}", "left")
        elif m == 2:
            text = (rf"$\leftarrow$ {joined}: pairs $z_j + z_{{j+1}} = {period}$ $\rightarrow$",
                    "center")
        else:
            text = (rf"$\leftarrow$ {joined}: $z_j + \dots + z_{{j+{m - 1}}} = {period}$ "
                    r"$\rightarrow$", "center")
        at.setdefault(n / m, []).append((m, text))
    marks = []
    for x in sorted(at):
        entries = sorted(at[x], key=lambda e: e[0] != 1)      # one-collision motions first
        ls = ":" if entries[0][0] == 1 else "-."
        marks.append((x, ls, [text for _, text in entries]))
    return marks


@_styled
def fig14(events, inv_beta, density_delta=None):
    """Fig. 14: density of the velocity after impact under sin(tau/inv_beta) + r(tau).

    As :func:`fig07`, at the ``inv_beta`` of the dataset nearest to the one given; a
    non-harmonic study raises ValueError (its velocity density is fig07). A two-wall
    dataset: one panel per wall (`plotting.walls.wall_density_figure`).
    """
    _require_harmonic(events, "fig14")
    i = _nearest(events["inv_beta"], inv_beta)
    if two_walls(events):
        return wall_density_figure(events, i, "v_after", "Fig. 14 (two walls)  Probability "
                                   "density of the velocity after impact, per wall",
                                   density_delta)
    fig, _ = _density_figure(events, i, "v_after_density",
                             "Fig. 14  Probability density of the velocity after impact",
                             _events_params(events, i, ("v_after",)), density_delta,
                             linear=True)
    return fig
