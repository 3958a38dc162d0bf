"""Style and the helpers every figure shares: labels from CF attributes, parameter lines, save.

Figures are built on the non-interactive Agg canvas without pyplot, so nothing here changes
the process-wide backend or keeps figures alive in a global registry.
"""
from __future__ import annotations

import contextlib
import functools
from pathlib import Path

import matplotlib
import matplotlib.style
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from vibroimpact._files import atomic_path
from vibroimpact.stats.events import t_quantile

#: The house style sheet (the only place rcParams are set).
STYLE_FILE = Path(__file__).with_name("vibroimpact.mplstyle")
#: Upper end of the frequency axis of the response spectra (figs 6, 11, 12): the resonance
#: of the impacting system lies below 2.5 for every delta the studies use.
SPECTRUM_BETA_MAX = 4.0
#: Lower end of the log density axis of figs 7, 8, 13, 14, relative to the highest density.
DENSITY_DECADES = 1e-5
#: Confidence level of the bars (fig09) and bands (figs 7, 8, 13, 14): +-t standard errors, t
#: the Student quantile of B - 1 dof for B batches, as `vibroimpact.stats.BatchMeans.interval`.
CONFIDENCE = 0.95
#: A density curve's legend states the share of values beyond the last bin above this fraction.
BEYOND_SHOWN = 1e-3
#: A mean resting on fewer impacts than this is drawn as such (open marker, no bar) in fig09.
FEW_IMPACTS = 20
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
    """PSD axis label stating the convention of paper eq. (9): two-sided, angular frequency.

    A long_name that says "two-sided" but not "angular" (the writers' names) gets "angular"
    added there; one that says neither gets the whole note appended.
    """
    name = str(da.attrs.get("long_name", da.name))
    if "angular" in name:
        return axis_label(da)
    if "two-sided" in name:
        return axis_label(da.assign_attrs(long_name=name.replace("two-sided",
                                                                 "two-sided, angular", 1)))
    return axis_label(da, " (two-sided, angular)")


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


#: Characters of a parameter line above which it is broken at its "; " separators.
HEADER_WIDTH = 90


def _header(fig, title, params):
    lines = []
    for line in params.split("\n"):
        while len(line) > HEADER_WIDTH and ";  " in line[:HEADER_WIDTH + 10]:
            cut = line.rfind(";  ", 0, HEADER_WIDTH + 10)
            lines.append(line[:cut + 1])
            line = line[cut + 3:]
        lines.append(line)
    fig.suptitle("\n".join([title, *lines]))


def _panel_tag(ax, tag):
    ax.text(0.005, 1.02, tag, transform=ax.transAxes, ha="left", va="bottom",
            fontweight="bold")


# --------------------------------------------------------------------------------------------
# The parameter line every figure prints
# --------------------------------------------------------------------------------------------

def _system_text(ds):
    return rf"$\zeta$ = {_num(_attr(ds, 'zeta'))}, $\varepsilon$ = {_num(_attr(ds, 'eps'))}"


def _spectrum_parts(attrs):
    """``["band_limited", "beta_c = 4"]``: the input's spectrum from ``noise_*`` attributes."""
    parts = [str(attrs["noise_kind"])] if "noise_kind" in attrs else []
    return parts + _filter_parts(attrs)


def _filter_parts(attrs):
    """Cut-off beta_c and filter damping zeta_f, for the noise kinds that have them."""
    symbols = (("noise_beta_c", r"$\beta_c$"), ("noise_zeta_f", r"$\zeta_f$"))
    return [f"{sym} = {_num(attrs[key])}" for key, sym in symbols if key in attrs]


def _noise_text(ds):
    """``rms_r = ...``, the spectrum and the noise's name, from the dataset's global attributes."""
    rms = ds.attrs.get("noise_rms")
    parts = [] if rms is None else [f"rms$_r$ = {_num(rms)}"]
    parts += _spectrum_parts(ds.attrs)
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


def _spectrum_text(noise):
    """Description of a noise record from its global attributes (``pipeline.io.write_noise``).

    Kind, rms, sample step, cut-off beta_c and filter damping zeta_f (when the kind has them),
    seed and number of samples; a missing required attribute raises KeyError naming it.
    """
    attrs = noise.attrs
    dt = attrs["noise_dt"] if "noise_dt" in attrs else _attr(noise, "dt")
    spectrum = [f"rms = {_num(_attr(noise, 'noise_rms'))}", rf"$\Delta\tau$ = {_num(dt)}",
                *_filter_parts(attrs)]
    n = int(attrs["n_samples"]) if "n_samples" in attrs else int(noise["r"].size)
    return (f"{_attr(noise, 'noise_kind')} noise: {', '.join(spectrum)};  "
            f"seed {_attr(noise, 'seed')}, {n:,} samples")


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
    shown = (t_imp >= float(tau[0])) & (t_imp <= float(tau[-1]))
    if "impact_collision" in trace:
        # a collision's first impact, and the rebounds of its chatter apart (docs/figures.md)
        col = np.asarray(trace["impact_collision"])
        first = np.ones(col.size, bool)
        first[1:] = col[1:] != col[:-1]
        rebound = shown & ~first
        if rebound.any():
            ax_a.plot(t_imp[rebound], np.zeros(int(rebound.sum())), ls="none", marker="|",
                      color="0.35", markersize=7, label=f"chatter rebound ({int(rebound.sum())})")
        shown &= first
        label = f"collision: first impact ({int(shown.sum())})"
    else:
        label = f"impact ({int(shown.sum())})"
    ax_a.plot(t_imp[shown], np.zeros(int(shown.sum())), ls="none", marker="v", color="C3",
              markersize=5, label=label)
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


#: Curves drawn by a density figure when no deltas are given (the largest deltas of the grid).
DENSITY_CURVES = 7
#: Legend entries a density figure keeps inside its axes; more go beside them.
LEGEND_INSIDE = 4


def _density_deltas(events, density_delta):
    """Indices of the dataset deltas nearest to ``density_delta``, largest first.

    ``None`` or empty: the `DENSITY_CURVES` largest deltas of the dataset.
    """
    deltas = np.asarray(events["delta"], dtype=float)
    if density_delta is None or len(density_delta) == 0:
        return list(np.argsort(-deltas)[:DENSITY_CURVES])
    wanted = np.atleast_1d(np.asarray(density_delta, dtype=float))
    index = list(dict.fromkeys(_nearest(events["delta"], d) for d in wanted))
    return sorted(index, key=lambda k: -deltas[k])


def _require(ds, name, why):
    """Variable `name` of a dataset, with an error naming it and what needs it."""
    if name not in ds.variables:
        raise KeyError(f"dataset lacks the variable {name!r} that {why} needs; "
                       f"variables present: {sorted(ds.data_vars)}")
    return ds[name]


def _beyond_text(fraction):
    """``", 18.5 % beyond axis"`` when more than `BEYOND_SHOWN` of the values lie past the bins."""
    fraction = float(fraction)
    if not np.isfinite(fraction) or fraction <= BEYOND_SHOWN:
        return ""
    return f", {100.0 * fraction:.3g} % beyond axis"


def _density_figure(events, i_beta, var, title, params, density_delta=None):
    """One density curve per density delta at inv_beta index `i_beta`, with a confidence band.

    The band is +-t batch-means standard errors (``{var}_stderr``), t the Student quantile
    of B - 1 dof (`CONFIDENCE`, B = ``n_batches``); each legend entry gives the cell's number
    of collisions and, when above `BEYOND_SHOWN`, the fraction of values beyond the last bin
    (``{quantity}_beyond``).
    """
    fig, (ax,) = _figure()
    ds = events.isel(inv_beta=i_beta)
    index = _density_deltas(events, density_delta)
    x = _require(ds, var, "this figure").dims[-1]
    beyond = _require(ds, f"{var.removesuffix('_density')}_beyond", "this figure")
    band = f"{var}_stderr"
    has_band = band in ds
    if has_band:
        t = t_quantile(np.asarray(_require(ds, "n_batches", "the confidence band")), CONFIDENCE)
    for color, k in zip(_colors(len(index)), index):
        cell = ds.isel(delta=k)
        n = int(cell["n_collisions"])
        y = np.asarray(cell[var], dtype=float)
        impacts = f"{n:,} collisions" if n else "no impacts"
        label = rf"$\delta$ = {_num(cell['delta'])}  ({impacts}{_beyond_text(beyond[k])})"
        ax.plot(cell[x], y, color=color, label=label)
        if has_band:
            half = t[k] * np.asarray(cell[band], dtype=float)
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
    title_text = None
    if has_band:
        b = np.unique(np.asarray(ds["n_batches"])[index])
        t_text = (f"t = {_num(t[index[0]])}, B = {int(b[0])} batches" if b.size == 1
                  else "t of B - 1 dof")
        title_text = (rf"band: $\pm$t$\cdot$batch-means s.e. "
                      f"({100 * CONFIDENCE:g} %, {t_text})")
    if len(index) > LEGEND_INSIDE:
        # a legend this tall would hide the curves' peaks: below the axes instead
        fig.set_figheight(fig.get_figheight() * 1.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), ncols=2, title=title_text,
                  title_fontsize=8, fontsize=8)
    else:
        ax.legend(loc="upper right", title=title_text, title_fontsize=8)
    _header(fig, title, params)
    return fig, ax


def _require_harmonic(events, figure):
    """Raise unless `events` is the dataset of a harmonic study (z_j / z needs a period)."""
    if float(_attr(events, "amplitude")) == 0.0 or "ratio_density" not in events:
        raise ValueError(f"{figure} needs the events of a harmonic study (amplitude != 0, "
                         f"with ratio_density); got amplitude = {events.attrs.get('amplitude')!r}")


#: What an impact statistic counts, printed on every figure of one (docs/figures.md).
COLLISION_NOTE = ("per collision: an impact after a free flight, with its chatter and sticking;  "
                  "v of its first rebound, z_j from first impact to first impact")


def _events_params(events, i_beta):
    """Parameter line of an events/spectra dataset at inv_beta index `i_beta`; an events
    dataset (collision statistics) adds `COLLISION_NOTE` on a line of its own."""
    inv_beta = float(events["inv_beta"][i_beta])
    harmonic = float(_attr(events, "amplitude")) != 0.0
    line = f"{_system_text(events)};  " + _forcing_text(
        events, inv_beta=inv_beta if harmonic else None)
    return line + (f"\n{COLLISION_NOTE}" if "n_collisions" in events else "")


# --------------------------------------------------------------------------------------------


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
            with atomic_path(path) as tmp:
                fig.savefig(tmp, format=fmt, metadata=metadata[fmt])
    return png, pdf
