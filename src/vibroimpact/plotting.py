"""The paper's figures, one function each: data in, :class:`matplotlib.figure.Figure` out.

Every function takes already opened :class:`xarray.Dataset` objects laid out as in
``docs/datasets.md`` and returns a Figure; none of them touches a file. :func:`save` is the
only writer (the workflow's figure rule calls it). Axis labels come from each variable's
``long_name`` and ``units`` attributes; the look comes from the one style file
``vibroimpact.mplstyle``, applied by :func:`style`. Every figure prints the parameters it
was computed with (zeta, eps, delta, the input's rms and spectrum, the harmonic forcing).

Figures are built on the non-interactive Agg canvas without pyplot, so nothing here changes
the process-wide backend or keeps figures alive in a global registry.

Datasets and the figures that read them::

    results/noise/{noise}.nc            fig04, fig05
    results/traces/{study}.nc           fig03, fig10
    results/datasets/{study}_spectra.nc fig06, fig11, fig12
    results/datasets/{study}_events.nc  fig07, fig08, fig09, fig13, fig14
    results/orbits/{name}.nc            fig16
"""
from __future__ import annotations

import contextlib
import functools
import os
import secrets
from pathlib import Path

import matplotlib
import matplotlib.style
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch

__all__ = [
    "STYLE_FILE", "style", "axis_label", "critical_delta", "save",
    "fig03", "fig04", "fig05", "fig06", "fig07", "fig08", "fig09",
    "fig10", "fig11", "fig12", "fig13", "fig14", "fig16",
]

#: The house style sheet (the only place rcParams are set).
STYLE_FILE = Path(__file__).with_name("vibroimpact.mplstyle")
#: Upper end of the frequency axis of the response spectra (figs 6, 11, 12): the resonance
#: of the impacting system lies below 2.5 for every delta the studies use.
SPECTRUM_BETA_MAX = 4.0
#: Lower end of the log density axis of figs 7, 8, 13, 14, relative to the highest density.
DENSITY_DECADES = 1e-5
#: Confidence bars are +-Z_95 standard errors (normal 95 % quantile).
Z_95 = 1.96
#: Part of the colour map used for a family of curves (the top end of viridis is too pale).
COLOR_SPAN = (0.0, 0.88)
#: Units that mean "dimensionless" (CF writes "1") and are left out of axis labels.
DIMENSIONLESS = ("1", "", "-")
#: Height (inches) of the figures with two stacked panels; one-panel figures use the style's.
TWO_PANEL_HEIGHT = 5.5
#: Fraction of the data range added above the data so a legend does not hide it.
LEGEND_HEADROOM = 0.35
#: Frequency axis of the input PSD (fig05) ends at 1.25 x the last beta where the target
#: exceeds this fraction of its peak (the rest is the empty stop band).
STOP_BAND_LEVEL = 1e-3


# --------------------------------------------------------------------------------------------
# Style and small helpers
# --------------------------------------------------------------------------------------------

@contextlib.contextmanager
def style():
    """Context in which the house style sheet is active (figures must be built inside it)."""
    with matplotlib.style.context(STYLE_FILE):
        yield


def _styled(func):
    """Build the figure of `func` inside :func:`style`."""
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with style():
            return func(*args, **kwargs)
    return wrapper


def _figure(nrows=1, sharex=True, height_ratios=None):
    """A new Figure on an Agg canvas, with `nrows` stacked axes (a list)."""
    fig = Figure()
    FigureCanvasAgg(fig)
    if nrows > 1:
        fig.set_figheight(TWO_PANEL_HEIGHT)
    axes = fig.subplots(nrows, 1, sharex=sharex, squeeze=False,
                        gridspec_kw={"height_ratios": height_ratios})[:, 0]
    return fig, list(axes)


def axis_label(da, extra=""):
    """Axis label ``"long_name [units]"`` of a DataArray (units omitted when dimensionless).

    Parameters
    ----------
    da : xarray.DataArray
        Variable or coordinate with CF attributes ``long_name`` and ``units``; the variable
        name stands in for a missing ``long_name``.
    extra : str, optional
        Appended after the name, before the units (e.g. a convention note).
    """
    name = str(da.attrs.get("long_name", da.name)) + extra
    units = da.attrs.get("units")
    if units is None or str(units) in DIMENSIONLESS:
        return name
    return f"{name} [{units}]"


def _psd_label(da):
    """PSD axis label stating the convention of paper eq. (9) unless long_name already does."""
    name = str(da.attrs.get("long_name", da.name))
    return axis_label(da, "" if "two-sided" in name else " (two-sided, angular)")


def _num(value):
    """A parameter value printed with 4 significant digits (never 0.30000000000000004)."""
    return f"{float(value):.4g}"


def _attr(ds, name):
    """Required global attribute `name` of a dataset, with an error naming it."""
    try:
        return ds.attrs[name]
    except KeyError:
        raise KeyError(f"dataset lacks the global attribute {name!r} that the figure prints; "
                       f"attributes present: {sorted(ds.attrs)}") from None


def _colors(n):
    """`n` colours along the style's colour map (one per curve of a family)."""
    cmap = matplotlib.colormaps[matplotlib.rcParams["image.cmap"]]
    return cmap(np.linspace(*COLOR_SPAN, max(n, 1)))


def _nearest(coord, value):
    """Index of the entry of a 1-D coordinate nearest to `value` (no monotonicity needed)."""
    return int(np.argmin(np.abs(np.asarray(coord, dtype=float) - float(value))))


def _headroom(ax):
    """Extend the y axis upwards so a legend in an upper corner leaves the data visible."""
    low, high = ax.get_ylim()
    ax.set_ylim(low, high + LEGEND_HEADROOM * (high - low))


def _bin_limits(ax, centres):
    """x limits at the outer bin edges of evenly spaced bin centres."""
    c = np.asarray(centres, dtype=float)
    half = 0.5 * (c[1] - c[0]) if c.size > 1 else 0.5
    ax.set_xlim(c[0] - half, c[-1] + half)


def _header(fig, title, params):
    fig.suptitle(f"{title}\n{params}")


def _panel_tag(ax, tag):
    ax.text(0.005, 1.02, tag, transform=ax.transAxes, ha="left", va="bottom",
            fontweight="bold")


# --------------------------------------------------------------------------------------------
# The parameter line every figure prints
# --------------------------------------------------------------------------------------------

def _system_text(ds):
    return rf"$\zeta$ = {_num(_attr(ds, 'zeta'))}, $\varepsilon$ = {_num(_attr(ds, 'eps'))}"


def _noise_text(ds):
    """``rms r = ...`` and the noise's name, from whichever attributes the dataset carries."""
    rms = ds.attrs.get("noise_rms")
    if rms is None and "r" in ds.variables:
        rms = ds["r"].attrs.get("rms")
    parts = [] if rms is None else [f"rms$_r$ = {_num(rms)}"]
    name = ds.attrs.get("noise")
    if isinstance(name, str) and name:
        parts.append(f"noise '{name}'")
    return ", ".join(parts)


def _forcing_text(ds, beta_f=None, inv_beta=None):
    """``f(tau) = A sin(...) + r(tau)``; the harmonic written as sin(tau/inv_beta) if given."""
    amplitude = float(_attr(ds, "amplitude"))
    if amplitude == 0.0:
        harmonic = ""
    else:
        arg = rf"\tau/{_num(inv_beta)}" if inv_beta is not None else rf"{_num(beta_f)}\,\tau"
        scale = "" if amplitude == 1.0 else f"{_num(amplitude)}"
        harmonic = rf"{scale}$\sin({arg})$ + "
    noise = _noise_text(ds)
    return rf"f($\tau$) = {harmonic}r($\tau$)" + (f" ({noise})" if noise else "")


def _spectrum_text(r):
    """Description of a random force from the attributes of the noise variable ``r``."""
    attrs = r.attrs
    parts = [f"{attrs['kind']} noise"] if "kind" in attrs else []
    symbols = (("rms", "rms"), ("dt", r"$\Delta\tau$"), ("beta_c", r"$\beta_c$"),
               ("zeta_f", r"$\zeta_f$"))
    parts += [f"{sym} = {_num(attrs[key])}" for key, sym in symbols if key in attrs]
    if "seed" in attrs:
        parts.append(f"seed {attrs['seed']}")
    parts.append(f"{r.size} samples")
    return ", ".join(parts)


# --------------------------------------------------------------------------------------------
# Shared figure bodies
# --------------------------------------------------------------------------------------------

def _trace_figure(trace, title, harmonic):
    """Input force (a) and a(tau) with the impacts (b) of one short simulation."""
    fig, (ax_f, ax_a) = _figure(2, height_ratios=(1.0, 1.3))
    tau = trace["tau"]
    force = trace["f"] if harmonic else trace["r"]
    ax_f.axhline(0.0, color="0.5", lw=0.6)
    ax_f.plot(tau, force, color="C0", lw=0.9, label=force.attrs.get("long_name", force.name))
    if harmonic:
        ax_f.plot(tau, trace["f"] - trace["r"], color="0.35", lw=0.9, ls="--",
                  label="harmonic part")
        _headroom(ax_f)
        ax_f.legend(loc="upper right", ncols=2)
    ax_f.set_ylabel(axis_label(force))
    _panel_tag(ax_f, "(a)")

    ax_a.plot(tau, trace["a"], color="C0", lw=1.0)
    ax_a.axhline(0.0, color="0.2", lw=1.4, label="wall (a = 0)")
    t_imp = np.asarray(trace["impact_time"])
    t_imp = t_imp[(t_imp >= float(tau[0])) & (t_imp <= float(tau[-1]))]
    ax_a.plot(t_imp, np.zeros_like(t_imp), ls="none", marker="v", color="C3",
              markersize=5, label=f"impact ({t_imp.size})")
    ax_a.set_ylim(bottom=min(-0.06 * float(trace["a"].max()), float(trace["a"].min())))
    _headroom(ax_a)
    ax_a.set_ylabel(axis_label(trace["a"]))
    ax_a.set_xlabel(axis_label(tau))
    ax_a.legend(loc="upper right", ncols=2)
    _panel_tag(ax_a, "(b)")

    beta_f = trace.attrs.get("beta_f")
    params = (f"{_system_text(trace)}, $\\delta$ = {_num(_attr(trace, 'delta'))};  "
              f"{_forcing_text(trace, beta_f=beta_f)}")
    _header(fig, title, params)
    return fig


def _response_spectra(spectra, i_beta, title, params, beta_max, lin_label):
    """S_a for every delta of the dataset (log y), with the linear reference S_lin."""
    fig, (ax,) = _figure()
    ds = spectra.isel(inv_beta=i_beta)
    ds = ds.isel(beta=np.flatnonzero(np.asarray(ds["beta"]) <= beta_max))
    deltas = np.asarray(ds["delta"], dtype=float)
    order = np.argsort(deltas)[::-1]
    for color, k in zip(_colors(deltas.size), order):
        ax.plot(ds["beta"], ds["S_a"].isel(delta=k), color=color,
                label=rf"$\delta$ = {_num(deltas[k])}")
    ax.plot(ds["beta"], ds["S_lin"], color="k", ls="--", lw=1.1, label=lin_label)
    if float(_attr(spectra, "amplitude")) != 0.0:
        _mark_forcing(ax, float(spectra["inv_beta"][i_beta]))
    ax.set_yscale("log")
    ax.set_xlim(0.0, float(ds["beta"].max()))
    ax.set_xlabel(axis_label(ds["beta"]))
    ax.set_ylabel(_psd_label(ds["S_a"]))
    ax.legend(loc="upper right", ncols=1 if deltas.size < 7 else 2)
    _header(fig, title, params)
    return fig


def _mark_forcing(ax, inv_beta):
    """Dotted vertical line at the forcing frequency beta_f = 1/inv_beta."""
    ax.axvline(1.0 / inv_beta, color="0.4", ls=":", lw=1.0,
               label=rf"forcing $\beta_f$ = 1/{_num(inv_beta)} = {_num(1.0 / inv_beta)}")


def _density_deltas(events):
    """Indices of the dataset deltas nearest to attribute ``density_delta``, largest first."""
    wanted = np.atleast_1d(np.asarray(_attr(events, "density_delta"), dtype=float))
    index = list(dict.fromkeys(_nearest(events["delta"], d) for d in wanted))
    deltas = np.asarray(events["delta"], dtype=float)
    return sorted(index, key=lambda k: -deltas[k])


def _density_figure(events, i_beta, var, title, params):
    """One density curve (with a 95 % band) per density delta, at inv_beta index `i_beta`."""
    fig, (ax,) = _figure()
    ds = events.isel(inv_beta=i_beta)
    index = _density_deltas(events)
    x = ds[var].dims[-1]
    band = f"{var}_stderr"
    for color, k in zip(_colors(len(index)), index):
        cell = ds.isel(delta=k)
        n = int(cell["n_impacts"])
        y = np.asarray(cell[var], dtype=float)
        impacts = f"{n:,} impacts" if n else "no impacts"
        ax.plot(cell[x], y, color=color, label=rf"$\delta$ = {_num(cell['delta'])}  ({impacts})")
        if band in cell:
            half = Z_95 * np.asarray(cell[band], dtype=float)
            ax.fill_between(cell[x], np.clip(y - half, 1e-300, None), y + half, color=color,
                            alpha=0.2, lw=0)
    # log scale: chatter puts a tall spike at small velocities and intervals, and the
    # distributions' tails matter as much as their bulk
    top = np.nanmax([np.nanmax(np.asarray(ds.isel(delta=k)[var], dtype=float), initial=0.0)
                     for k in index] + [0.0])
    if top > 0.0:
        ax.set_yscale("log")
        ax.set_ylim(top * DENSITY_DECADES, top * 3.0)
    else:
        ax.set_ylim(bottom=0.0)
    _bin_limits(ax, ds[x])
    ax.set_xlabel(axis_label(ds[x]))
    ax.set_ylabel(axis_label(ds[var]))
    ax.legend(loc="upper right", title="bands: 95 % confidence" if band in ds else None)
    _header(fig, title, params)
    return fig, ax


def _events_params(events, i_beta):
    """Parameter line of an events/spectra dataset at inv_beta index `i_beta`."""
    inv_beta = float(events["inv_beta"][i_beta])
    harmonic = float(_attr(events, "amplitude")) != 0.0
    return f"{_system_text(events)};  " + _forcing_text(
        events, inv_beta=inv_beta if harmonic else None)


# --------------------------------------------------------------------------------------------
# Random force (paper section 3): figs 3-9
# --------------------------------------------------------------------------------------------

@_styled
def fig03(trace):
    """Fig. 3: (a) the random input r(tau); (b) a(tau) = delta - x(tau) with the impacts.

    Parameters
    ----------
    trace : xarray.Dataset
        ``results/traces/{study}.nc``: ``r(tau)``, ``a(tau)``, ``impact_time(impact)``;
        global attributes ``zeta``, ``eps``, ``delta``, ``amplitude`` (and ``noise_rms`` or
        ``r.attrs["rms"]`` to print the input's rms).

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked axes sharing tau; impacts are markers on the wall line a = 0.
    """
    return _trace_figure(trace, "Fig. 3  Random input and the motion of the mass",
                         harmonic=False)


@_styled
def fig04(noise):
    """Fig. 4: autocorrelation phi_f(tau*) of the random input (paper eq. 8), estimate vs target.

    Parameters
    ----------
    noise : xarray.Dataset
        ``results/noise/{noise}.nc``: ``phi_estimate(lag)``, ``phi_target(lag)``, ``r(sample)``
        with attributes ``kind``, ``rms``, ``dt``, ``beta_c``, ``zeta_f``, ``seed``.

    Returns
    -------
    matplotlib.figure.Figure
        One axes: the estimate (solid) and the target of the piecewise-linear force (dashed).
    """
    fig, (ax,) = _figure()
    ax.plot(noise["lag"], noise["phi_estimate"], color="C0", marker="o", markersize=2.5,
            label="estimate from the samples")
    ax.plot(noise["lag"], noise["phi_target"], color="k", ls="--", lw=1.1,
            label="target (piecewise-linear force)")
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(axis_label(noise["lag"]))
    ax.set_ylabel(axis_label(noise["phi_estimate"]))
    ax.legend(loc="upper right")
    _header(fig, r"Fig. 4  Autocorrelation $\varphi_f(\tau^*)$ of the random input (eq. 8)",
            _spectrum_text(noise["r"]))
    return fig


@_styled
def fig05(noise):
    """Fig. 5: PSD S_f(beta) of the random input (paper eq. 9), estimate vs target, beta >= 0.

    Parameters
    ----------
    noise : xarray.Dataset
        ``results/noise/{noise}.nc``: ``S_estimate(beta)``, ``S_target(beta)``, ``r(sample)``.

    Returns
    -------
    matplotlib.figure.Figure
        One axes; the y label states the two-sided angular convention, and a note compares
        the variance recovered from the estimate, ``(1/pi) int_0^inf S dbeta``, with rms^2.

    Notes
    -----
    Two-sided, angular: ``variance = (1/2 pi) int_{-inf}^{inf} S(beta) dbeta`` (eq. 9).
    """
    fig, (ax,) = _figure()
    ds = noise.isel(beta=np.flatnonzero(np.asarray(noise["beta"]) >= 0.0))
    ax.plot(ds["beta"], ds["S_estimate"], color="C0", label="estimate from the samples")
    ax.plot(ds["beta"], ds["S_target"], color="k", ls="--", lw=1.1,
            label="target (piecewise-linear force)")
    beta, target = np.asarray(ds["beta"]), np.asarray(ds["S_target"])
    variance = np.trapezoid(np.asarray(ds["S_estimate"]), beta) / np.pi
    note = (r"$\sigma^2 = \frac{1}{2\pi}\int_{-\infty}^{\infty} S\,d\beta$"
            rf" from the estimate: {variance:.4g}")
    if "rms" in noise["r"].attrs:
        note += rf"  (rms$^2$ = {float(noise['r'].attrs['rms']) ** 2:.4g})"
    band = np.flatnonzero(target > STOP_BAND_LEVEL * target.max())
    ax.set_xlim(0.0, min(beta.max(), 1.25 * beta[band[-1]]) if band.size else beta.max())
    ax.set_ylim(bottom=0.0)
    _headroom(ax)
    ax.set_xlabel(axis_label(ds["beta"]))
    ax.set_ylabel(_psd_label(ds["S_estimate"]))
    ax.legend(loc="upper right", title=note, title_fontsize=8)
    _header(fig, r"Fig. 5  Power spectral density $S_f(\beta)$ of the random input (eq. 9)",
            _spectrum_text(noise["r"]))
    return fig


@_styled
def fig06(spectra, beta_max=SPECTRUM_BETA_MAX):
    """Fig. 6: PSD of a(tau) for each delta of the dataset, with the linear |H|^2 S_f.

    Parameters
    ----------
    spectra : xarray.Dataset
        ``results/datasets/{study}_spectra.nc`` of the random-force study (inv_beta index 0
        is used): ``S_a(inv_beta, delta, beta)``, ``S_lin(inv_beta, beta)``.
    beta_max : float, optional
        Upper end of the frequency axis.

    Returns
    -------
    matplotlib.figure.Figure
        One log-y axes: one curve per delta (viridis, largest delta first) and S_lin dashed.
    """
    return _response_spectra(
        spectra, 0, "Fig. 6  Power spectral density of the displacement a(τ) of the mass",
        _events_params(spectra, 0), beta_max, r"linear $|H|^2 S_f$ (no impacts)")


@_styled
def fig07(events):
    """Fig. 7: probability density of the velocity after impact, one curve per density delta.

    Parameters
    ----------
    events : xarray.Dataset
        ``results/datasets/{study}_events.nc``; inv_beta index 0; the deltas shown are those
        of the dataset nearest to the attribute ``density_delta``.

    Returns
    -------
    matplotlib.figure.Figure
        One axes, one line per (distinct) density delta with a shaded 95 % band.
    """
    fig, _ = _density_figure(events, 0, "v_after_density",
                             "Fig. 7  Probability density of the velocity after impact",
                             _events_params(events, 0))
    return fig


@_styled
def fig08(events):
    """Fig. 8: probability density of the interval between adjacent impacts (as fig07)."""
    fig, _ = _density_figure(events, 0, "interval_density",
                             "Fig. 8  Probability density of the interval between impacts",
                             _events_params(events, 0))
    return fig


def critical_delta(events, inv_beta_index=0):
    """Smallest swept delta above which the record holds no impact (fig09's marker).

    Parameters
    ----------
    events : xarray.Dataset
        Events dataset with ``n_impacts(inv_beta, delta)``.
    inv_beta_index : int, optional
        Which forcing frequency.

    Returns
    -------
    float
        The largest delta with ``n_impacts > 0`` when every larger delta has none, i.e. no
        impact occurs for delta > critical_delta; NaN when the largest swept delta still has
        impacts (the sweep does not reach the critical play) or when no delta has any.
        The true threshold lies between this value and the next swept delta.
    """
    ds = events.isel(inv_beta=inv_beta_index).sortby("delta")
    hit = np.flatnonzero(np.asarray(ds["n_impacts"]) > 0)
    if hit.size == 0 or hit[-1] == ds["delta"].size - 1:
        return float("nan")
    return float(ds["delta"][hit[-1]])


@_styled
def fig09(events):
    """Fig. 9: mean velocity after impact and mean interval against delta, 95 % bars.

    Parameters
    ----------
    events : xarray.Dataset
        Events dataset of a fine delta sweep (inv_beta index 0): ``v_after_mean``,
        ``v_after_stderr``, ``interval_mean``, ``interval_stderr``, ``n_impacts``.

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked axes sharing delta. Bars are +-1.96 batch-means standard errors. Deltas
        without impacts are drawn as open markers at 0. A vertical line (gid
        ``"critical_delta"``) marks :func:`critical_delta` on both axes, and a shaded span
        reaches to the first impact-free delta, where the true threshold lies.
    """
    fig, axes = _figure(2)
    ds = events.isel(inv_beta=0).sortby("delta")
    delta = np.asarray(ds["delta"], dtype=float)
    none = np.asarray(ds["n_impacts"]) == 0
    d_c = critical_delta(events)
    for ax, name, color in zip(axes, ("v_after", "interval"), ("C0", "C1")):
        mean, err = ds[f"{name}_mean"], Z_95 * np.asarray(ds[f"{name}_stderr"], dtype=float)
        ax.errorbar(delta, mean, yerr=err, color=color, marker="o", markersize=3.5,
                    label="mean ± 1.96 standard errors")
        if none.any():
            ax.plot(delta[none], np.zeros(none.sum()), ls="none", marker="o", mfc="white",
                    color="0.45", markersize=4, clip_on=False, zorder=5,
                    label="no impact in the record")
        if np.isfinite(d_c):
            line = ax.axvline(d_c, color="C3", ls="--", lw=1.1)
            line.set_gid("critical_delta")
            ax.axvspan(d_c, delta[delta > d_c][0], color="C3", alpha=0.12, lw=0)
        ax.set_ylabel(axis_label(mean))
        ax.set_ylim(bottom=0.0)
    if np.isfinite(d_c):
        axes[0].annotate(rf"$\delta_c$ = {_num(d_c)}: no impact for $\delta > \delta_c$",
                         xy=(d_c, 0.12), xycoords=("data", "axes fraction"),
                         xytext=(-8, 0), textcoords="offset points", ha="right", va="center",
                         color="C3", fontsize=8.5,
                         bbox={"boxstyle": "round", "fc": "white", "ec": "none", "alpha": 0.8})
    axes[0].legend(loc="upper left")
    axes[1].set_xlabel(axis_label(ds["delta"]))
    _panel_tag(axes[0], "(a)")
    _panel_tag(axes[1], "(b)")
    _header(fig, "Fig. 9  Mean velocity after impact and mean interval between impacts",
            _events_params(events, 0))
    return fig


# --------------------------------------------------------------------------------------------
# Harmonic + random force (paper section 5): figs 10-14
# --------------------------------------------------------------------------------------------

@_styled
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
    """Fig. 11: PSD of the total input sin(beta_f tau) + r(tau) at one forcing frequency.

    Parameters
    ----------
    spectra : xarray.Dataset
        Spectra dataset of the harmonic study: ``S_f(inv_beta, beta)``.
    inv_beta : float
        1/beta_f; the nearest value of the dataset is shown (and printed).
    beta_max : float, optional
        Upper end of the frequency axis.

    Returns
    -------
    matplotlib.figure.Figure
        One log-y axes with S_f and a dotted line at the forcing frequency.
    """
    fig, (ax,) = _figure()
    i = _nearest(spectra["inv_beta"], inv_beta)
    ds = spectra.isel(inv_beta=i)
    ds = ds.isel(beta=np.flatnonzero(np.asarray(ds["beta"]) <= beta_max))
    ax.plot(ds["beta"], ds["S_f"], color="C0", label="estimate from the simulated record")
    _mark_forcing(ax, float(ds["inv_beta"]))
    ax.set_yscale("log")
    ax.set_xlim(0.0, float(ds["beta"].max()))
    ax.set_xlabel(axis_label(ds["beta"]))
    ax.set_ylabel(_psd_label(ds["S_f"]))
    ax.legend(loc="upper right")
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
        As :func:`fig06`; S_lin (random part only) dashed, the forcing frequency dotted.
    """
    i = _nearest(spectra["inv_beta"], inv_beta)
    return _response_spectra(
        spectra, i, "Fig. 12  Power spectral density of the displacement a(τ) of the mass",
        _events_params(spectra, i), beta_max, r"linear $|H|^2 S_r$ (random part only)")


@_styled
def fig13(events, inv_beta):
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
        One axes: one line per density delta, a dash-dot line at z_j/z = 1/2 (the symmetry
        axis of the (2/1) motion) and dotted marks at 1 ((1/1) motion) and 2 ((1/2) motion).
    """
    i = _nearest(events["inv_beta"], inv_beta)
    fig, ax = _density_figure(
        events, i, "ratio_density",
        r"Fig. 13  Probability density of $z_j/z$, the interval over the forcing period",
        _events_params(events, i))
    marks = ((0.5, "-.", "(2/1)"), (1.0, ":", "(1/1)"), (2.0, ":", "(1/2)"))
    for x, ls, _ in marks:
        ax.axvline(x, color="0.3", ls=ls, lw=1.0)
    motions = ax.secondary_xaxis("top")
    motions.set_xticks([x for x, _, _ in marks], labels=[m for _, _, m in marks], fontsize=8)
    motions.tick_params(length=0, colors="0.3")
    motions.spines["top"].set_visible(False)
    return fig


@_styled
def fig14(events, inv_beta):
    """Fig. 14: density of the velocity after impact under sin(tau/inv_beta) + r(tau)."""
    i = _nearest(events["inv_beta"], inv_beta)
    fig, _ = _density_figure(events, i, "v_after_density",
                             "Fig. 14  Probability density of the velocity after impact",
                             _events_params(events, i))
    return fig


# --------------------------------------------------------------------------------------------
# Fig. 16: periodic impact motions under the harmonic force alone
# --------------------------------------------------------------------------------------------

#: Colours of the regions without a stable motion (paper's letters: D/V/X no solution, U unstable).
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


# --------------------------------------------------------------------------------------------
# The only writer
# --------------------------------------------------------------------------------------------

def save(fig, path_png):
    """Write `fig` to ``path_png`` and its vector twin ``.pdf`` next to it, atomically.

    Each file is rendered to a temporary name in the target directory and moved into place
    with :func:`os.replace`, so a reader never sees a half-written figure and an interrupted
    run leaves no partial output.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        A figure returned by one of the ``figNN`` functions.
    path_png : str or os.PathLike
        Target ending in ``.png``; the PDF goes to the same path with suffix ``.pdf``.

    Returns
    -------
    tuple of pathlib.Path
        The PNG and PDF paths written.
    """
    png = Path(path_png)
    if png.suffix.lower() != ".png":
        raise ValueError(f"path_png must end in .png, got {str(path_png)!r}")
    png.parent.mkdir(parents=True, exist_ok=True)
    pdf = png.with_suffix(".pdf")
    # Fixed metadata: the same figure gives the same bytes on every run.
    metadata = {"png": {"Software": None}, "pdf": {"CreationDate": None, "Producer": None}}
    with style():
        for path, fmt in ((png, "png"), (pdf, "pdf")):
            # Same directory as the target, so os.replace is a rename on one file system;
            # opened with "xb" (not mkstemp) so the file gets the usual umask permissions.
            tmp = path.with_name(f".{path.name}.{secrets.token_hex(6)}.tmp")
            try:
                with open(tmp, "xb") as fh:
                    fig.savefig(fh, format=fmt, metadata=metadata[fmt])
                os.replace(tmp, path)
            except BaseException:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(tmp)
                raise
    return png, pdf
