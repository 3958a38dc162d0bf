"""Style and the helpers every figure shares: labels from CF attributes, parameter lines, save.

Figures are built on the non-interactive Agg canvas without pyplot, so nothing here changes
the process-wide backend or keeps figures alive in a global registry.
"""
from __future__ import annotations

import contextlib
import functools
import json
import re
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import matplotlib.style
import numpy as np
from matplotlib.textpath import text_to_path
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from vibroimpact._files import atomic_path
from vibroimpact._plane import dataset_axes
from vibroimpact._symbols import PARAMETERS, fixed_caption, parameter_symbol
from vibroimpact.stats.events import poisson_interval, t_quantile
from vibroimpact.stats.spectra import line_power
from vibroimpact.stats.theory import upcrossing_rate

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


#: The one labelling vocabulary of every figure: a quantity's axis label in the paper's
#: symbols (eq. 2 ff.: tau, delta, beta = omega/omega_0, z_j, u_{j-0} the approach velocity
#: at the j-th collision, epsilon u_{j-0} the velocity after it), keyed by the variable name
#: the datasets use. A variable not listed here is labelled by its CF ``long_name``.
LABELS = {
    "tau": r"time $\tau$",
    "lag": r"time lag $\tau^*$",
    "delta": r"play $\delta$",
    "inv_beta": r"inverse forcing frequency $1/\beta_f$",
    "beta": r"frequency ratio $\beta = \omega/\omega_0$",
    "r": r"random force $r(\tau)$",
    "f": r"input force $f(\tau)$",
    "a": r"displacement from the wall $a(\tau)$",
    "x": r"displacement $x(\tau)$",
    "phi_estimate": r"autocorrelation $\varphi_f(\tau^*)$",
    "phi_r": r"autocorrelation $\varphi_f(\tau^*)$",
    "v_after": r"velocity after impact $\varepsilon u_{j-0}$",
    "interval": r"interval between collisions $z_j$",
    "ratio": r"$z_j/z$,  $z = 2\pi/\beta_f$",
    "v_after_density": r"probability density of $\varepsilon u_{j-0}$",
    "interval_density": r"probability density of $z_j$",
    "ratio_density": r"probability density of $z_j/z$",
    "v_after_mean": r"mean velocity after impact $\overline{\varepsilon u_{j-0}}$",
    "interval_mean": r"mean interval $\overline{z_j}$",
    "S_a": r"PSD $S_a(\beta)$ of $a(\tau)$",
    "S_estimate": r"PSD $S_f(\beta)$",
    "S_f": r"PSD $S_f(\beta)$",
    "S": r"degree of stability $S$",
}
#: Every parameter a map's plane may run over has its label here too (`vibroimpact._symbols`:
#: zeta, eps, eps_lower, gap, amplitude, rms; delta and inv_beta as above).
LABELS.update({name: label for name, (_, _, label) in PARAMETERS.items()
               if name not in LABELS})


def axis_label(da, extra=""):
    """Axis label of a DataArray: its entry of `LABELS`, else ``"long_name [units]"``.

    Units are omitted when dimensionless (every quantity of the paper is).

    Parameters
    ----------
    da : xarray.DataArray
        Variable or coordinate; a name outside `LABELS` is labelled by its CF attribute
        ``long_name`` (the variable name when that is missing) and ``units``.
    extra : str, optional
        Appended after the name, before the units (e.g. a convention note).
    """
    name = str(LABELS.get(da.name, da.attrs.get("long_name", da.name))) + extra
    units = da.attrs.get("units")
    if units is None or str(units) in DIMENSIONLESS:
        return name
    return f"{name} [{units}]"


def _psd_label(da):
    """PSD axis label stating the convention of paper eq. (9): two-sided, angular frequency.

    A long_name that says "two-sided" but not "angular" (the writers' names) gets "angular"
    added there; one that says neither gets the whole note appended.
    """
    if da.name in LABELS:
        return axis_label(da, " (two-sided, angular)")
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


def _same_system(a, b, names):
    """Raise unless datasets `a` and `b` have the same zeta and eps (`names`: how the error
    calls them, ``("the map", "the orbit map")``)."""
    for key in ("zeta", "eps"):
        if float(_attr(a, key)) != float(_attr(b, key)):
            raise ValueError(f"{names[0]} has {key} = {_attr(a, key)!r} but {names[1]} "
                             f"{_attr(b, key)!r}: not the same system")


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


#: Characters of a parameter line above which it is broken at its "; " separators.
HEADER_WIDTH = 90

#: Plain-ASCII names that text stored with the data uses (a basins box, a stress family's
#: error measure), and the paper's symbols a header shows for them (`symbols`); the longer
#: name first where one contains another.
SYMBOLS = (
    (r"\b2 pi\b", r"$2\pi$"),
    (r"\bpi\b", r"$\pi$"),
    (r"\bdelta\b", r"$\delta$"),
    (r"\bx0\b", r"$x_0$"),
    (r"\bv0\b", r"$v_0$"),
    (r"\ba\(tau\)", r"$a(\tau)$"),
    (r"\bx'", r"$x'$"),
    (r"\bmu_ind\b", r"$\mu_{\rm ind}$"),
    (r"\bmu\b", r"$\mu$"),
)
#: One pass over a text: a name matched is replaced once, never inside a symbol put there.
_SYMBOLS_RE = re.compile("|".join(f"({pattern})" for pattern, _ in SYMBOLS))


def symbols(text):
    r"""`text` with the plain names of `SYMBOLS` written as the paper's symbols (mathtext).

    Only the parts outside ``$...$`` change, so a text already in mathtext stays as it is:
    ``"forcing phase in [0, 2 pi), x0 = delta - g"`` becomes
    ``"forcing phase in [0, $2\pi$), $x_0$ = $\delta$ - g"``.
    """
    parts = str(text).split("$")
    for k in range(0, len(parts), 2):          # even parts lie outside math
        parts[k] = _SYMBOLS_RE.sub(lambda m: SYMBOLS[m.lastindex - 1][1], parts[k])
    return "$".join(parts)


#: Characters of a header line an inch of figure holds (the title size, 10 pt; 6.5 in, the
#: default width, holds `HEADER_WIDTH`): a narrower figure breaks its lines shorter.
HEADER_CHARS_PER_INCH = 14.0


def _header(fig, title, params, fit=True):
    """The figure's title and its parameter lines (plain names as symbols, `symbols`),
    long lines broken at their ``";  "`` separators (`HEADER_WIDTH`, or the characters a
    narrower figure holds); with ``fit``, a line still wider than the figure, as its title's
    font draws it (`_points`), breaks again: at the last ``";  "``, else ``", "``, else space
    outside maths where what comes before fits (a figure that shrinks its header's font
    instead passes ``fit=False``)."""
    width = min(HEADER_WIDTH, int(fig.get_figwidth() * HEADER_CHARS_PER_INCH))
    prop = fig.suptitle(title).get_fontproperties()
    room = 72.0 * fig.get_figwidth() - 2 * HEADER_MARGIN_PT
    lines = []
    for line in symbols(params).split("\n"):
        while len(line) > width and ";  " in line[:width + 10]:
            cut = line.rfind(";  ", 0, width + 10)
            lines.append(line[:cut + 1])
            line = line[cut + 3:]
        while fit and _points(line, prop) > room:
            cut, skip = _break_outside_math(line, lambda head: _points(head, prop) <= room)
            if cut < 0:
                break
            lines.append(line[:cut])
            line = line[cut + skip:]
        lines.append(line)
    fig.suptitle("\n".join([title, *lines]))


#: Points a header keeps clear of each side of the figure.
HEADER_MARGIN_PT = 6.0


def _points(text, prop):
    """The width in points of one line of ``text`` drawn in font ``prop`` (maths as
    mathtext), measured by Matplotlib's own text layout."""
    if not text:
        return 0.0
    ismath = text.count("$") >= 2 and text.count("$") % 2 == 0
    return float(text_to_path.get_text_width_height_descent(text, prop, ismath=ismath)[0])


def _break_outside_math(line, fits):
    """``(end, skip)`` of the break of ``line`` outside ``$...$`` after which the head
    ``line[:end]`` ``fits`` (a predicate): after its last such ``";  "`` (the semicolon kept),
    else ``", "`` (the comma kept), else space; the line goes on ``skip`` characters later.
    ``(-1, 0)`` if there is none."""
    for sep, keep in ((";  ", 1), (", ", 1), (" ", 0)):
        cut = line.rfind(sep)
        while cut > 0:
            if line.count("$", 0, cut) % 2 == 0 and fits(line[:cut + keep]):
                return cut + keep, len(sep) - keep
            cut = line.rfind(sep, 0, cut)
    return -1, 0


def _panel_tag(ax, tag):
    ax.text(0.005, 1.02, tag, transform=ax.transAxes, ha="left", va="bottom",
            fontweight="bold")


def _padded(values, fraction=0.05):
    """``(low, high)`` of `values` widened by `fraction` of their range (by 0.5 when flat)."""
    low, high = float(np.min(values)), float(np.max(values))
    pad = fraction * (high - low) if high > low else 0.5
    return low - pad, high + pad


def note_on_axes(ax, text):
    """Write `text` at the centre of an axes that has nothing to draw (gid ``"note"``)."""
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="0.25",
            gid="note", bbox=dict(facecolor="white", edgecolor="0.7", pad=4))


def input_is_zero(ds):
    """Whether the force of a dataset is zero: no random part (``noise_rms`` 0) and no harmonic."""
    return float(ds.attrs.get("noise_rms", 1.0)) == 0.0 and float(_attr(ds, "amplitude")) == 0.0


def no_collision_text(ds, where="in this record at any $\\delta$"):
    """Why a figure of collision statistics has nothing to draw, in words for its axes.

    Parameters
    ----------
    ds : xarray.Dataset
        Events or map dataset with ``delta``, global attributes ``noise_rms``, ``amplitude``
        and, from an events dataset, ``linear_sigma_x``, ``linear_sigma_v`` (the wall-free
        response's stds) and ``record_length``.
    where : str, optional
        Where no collision happened (``"in any cell of this map"``).

    Returns
    -------
    str
        ``"no collision in this record at any delta"`` and the reason: the force is zero
        (the mass stays at rest), there is no random part (rms_r = 0), or the smallest play
        in units of the wall-free std sigma_x with the up-crossings of it that Rice's rate
        (`vibroimpact.stats.upcrossing_rate`) expects in the record's length: a property of
        this record, the rate falls with delta but never to zero.
    """
    text = f"no collision {where}"
    rms = float(ds.attrs.get("noise_rms", np.nan))
    sigma_x = float(ds.attrs.get("linear_sigma_x", 0.0))
    sigma_v = float(ds.attrs.get("linear_sigma_v", 0.0))
    if input_is_zero(ds):
        return text + "\nthe force is zero (rms$_r$ = 0, no harmonic): the mass stays at rest"
    if rms == 0.0:
        return text + " (rms$_r$ = 0)"
    if sigma_x > 0.0 and sigma_v > 0.0 and "delta" in ds.variables:
        smallest = float(np.min(np.asarray(ds["delta"], dtype=float)))
        text += ("\n" + rf"its smallest $\delta$ = {_num(smallest)} is "
                 rf"{_num(smallest / sigma_x)} $\sigma_x$ of the wall-free response "
                 rf"($\sigma_x$ = {_num(sigma_x)})")
        if "record_length" in ds.attrs:
            record = float(ds.attrs["record_length"])
            expected = record * upcrossing_rate(smallest, sigma_x, sigma_v)
            text += ("\n" + rf"where Rice's rate expects {expected:.2g} up-crossings in the "
                     f"record's length {record:.4g}")
    return text


# --------------------------------------------------------------------------------------------
# The parameter line every figure prints
# --------------------------------------------------------------------------------------------

def two_wall_dataset(ds):
    """Whether a dataset is a two-wall study's (its attribute ``n_walls`` is 2; the
    attractor datasets' ``gap`` is their box of starts, not a wall)."""
    return int(ds.attrs.get("n_walls", 1)) == 2


def _system_text(ds):
    text = rf"$\zeta$ = {_num(_attr(ds, 'zeta'))}, $\varepsilon$ = {_num(_attr(ds, 'eps'))}"
    text += _law_text(ds)
    if two_wall_dataset(ds):    # two walls: the second wall's place and restitution
        text += (rf";  lower wall at $\delta$ - {_num(ds.attrs['gap'])}, "
                 rf"$\varepsilon_l$ = {_num(ds.attrs['eps_lower'])}")
        if "speed_scale_lower" in ds.attrs:
            text += rf" (at $u$ = 0, halved at $u$ = {_num(ds.attrs['speed_scale_lower'])})"
    return text


def speed_law(ds):
    """Whether a dataset's walls follow an impact law other than Newton's (a restitution
    that falls with the impact speed: its ``speed_scale`` attribute)."""
    return "speed_scale" in ds.attrs or "speed_scale_lower" in ds.attrs


def _law_text(ds):
    """The impact law of a dataset whose restitution falls with the speed, for its header
    (empty under Newton's law): the figure says which law drew it."""
    if "speed_scale" not in ds.attrs:
        return ""
    return (rf" at $u$ = 0, falling as $\varepsilon(u) = \varepsilon / (1 + u / "
            rf"{_num(ds.attrs['speed_scale'])})$")


# --------------------------------------------------------------------------------------------
# The plane of a map: its two axes and what it holds fixed
# --------------------------------------------------------------------------------------------

#: Global attributes a map dataset of the paper's plane carries for its fixed parameters
#: (the fixed caption of a dataset without ``attrs["fixed"]``), by parameter name.
FIXED_ATTRS = {"zeta": "zeta", "eps": "eps", "eps_lower": "eps_lower", "delta": "delta",
               "gap": "gap", "amplitude": "amplitude", "inv_beta": "inv_beta",
               "rms": "noise_rms"}


def _decoded(value, what):
    """An attribute stored as JSON text (or already decoded by the reader)."""
    if isinstance(value, (bytes, str)):
        try:
            return json.loads(value)
        except ValueError:
            raise ValueError(f"attrs[{what!r}] must be JSON text, got {value!r}") from None
    return value


def plane_axes(ds):
    """The names ``(x, y)`` of a map's two axes (`vibroimpact._plane.dataset_axes`: its
    ``axes`` attribute, x first, else the paper's); each must be a dimension of `ds`."""
    axes = dataset_axes(ds)
    missing = [a for a in axes if a not in ds.dims]
    if missing:
        raise ValueError(f"the plane's axes {list(axes)} must be dimensions of the dataset; "
                         f"{missing} is not among {list(ds.dims)}")
    return axes


def custom_plane(ds):
    """Whether a map dataset names its plane (``attrs["axes"]``): its figures then write the
    fixed caption (`plane_fixed`) in place of the paper's parameter line."""
    return "axes" in ds.attrs


def plane_fixed(ds):
    """``{name: value}`` of what a map holds fixed: ``ds.attrs["fixed"]`` (JSON text of a
    dict), else the parameters among the global attributes (`FIXED_ATTRS`); never an axis."""
    axes = plane_axes(ds)
    if "fixed" in ds.attrs:
        fixed = _decoded(ds.attrs["fixed"], "fixed")
        if not isinstance(fixed, dict):
            raise ValueError(f"attrs['fixed'] must be a dict, got {fixed!r}")
    else:
        fixed = {name: ds.attrs[key] for name, key in FIXED_ATTRS.items() if key in ds.attrs}
    return {k: v for k, v in fixed.items() if k not in axes}


def plane_caption(ds, math=True):
    """``"fixed: ζ = 0.05, A = 1, 1/β_f = 1.1, σ_r = 0.29"`` of a map dataset (`plane_fixed`);
    with a second wall whose restitution is given nowhere, ``ε_l = ε`` (its default)."""
    fixed = plane_fixed(ds)
    text = fixed_caption(fixed, math=math)
    axes = plane_axes(ds)
    if ("gap" in axes or "gap" in fixed) and "eps_lower" not in axes and "eps_lower" not in fixed:
        text += (", " if text else "") + (r"$\varepsilon_l = \varepsilon$" if math
                                          else "ε_l = ε")
    law = law_caption(ds, math=math)
    if law:
        text += (", " if text else "") + law
    return f"fixed: {text}" if text else "nothing fixed"


def law_caption(ds, math=True):
    """The impact law of a dataset whose restitution falls with the speed, as a caption's
    item (``"ε(u) = ε/(1 + u/0.5)"``; the second wall's after it); empty under Newton's
    law."""
    parts = []
    if "speed_scale" in ds.attrs:
        scale = _num(ds.attrs["speed_scale"])
        parts.append(rf"$\varepsilon(u) = \varepsilon/(1 + u/{scale})$" if math
                     else f"ε(u) = ε/(1 + u/{scale})")
    if "speed_scale_lower" in ds.attrs:
        scale = _num(ds.attrs["speed_scale_lower"])
        parts.append(rf"$\varepsilon_l(u) = \varepsilon_l/(1 + u/{scale})$" if math
                     else f"ε_l(u) = ε_l/(1 + u/{scale})")
    return ", ".join(parts)


def on_plane(da, ds):
    """`da` with its plane's axes last, x before y (a ``(..., x, y)`` array for drawing)."""
    x, y = plane_axes(ds)
    return da.transpose(..., x, y)


def motion_title(name):
    """A motion's name as the figures print it: ``(1/1)``, and a two-wall motion
    ``(1,1)/1`` as it is (already bracketed)."""
    return name if name.startswith("(") or name == "none" else f"({name})"


#: How a figure names each noise kind (`vibroimpact.noise.KINDS`), never the config key.
NOISE_KINDS = {"white": "white", "band_limited": "band-limited white",
               "lowpass2": "2nd-order low-pass"}


def _kind_text(attrs):
    """The noise kind in words (``"band-limited white"``); an unknown kind as it is stored."""
    kind = str(attrs["noise_kind"])
    return NOISE_KINDS.get(kind, kind)


def _spectrum_parts(attrs):
    """``["band-limited white", "beta_c = 4"]``: the input's spectrum from ``noise_*``
    attributes."""
    parts = [_kind_text(attrs)] if "noise_kind" in attrs else []
    return parts + _filter_parts(attrs)


def _filter_parts(attrs):
    """Cut-off beta_c and filter damping zeta_f, for the noise kinds that have them."""
    symbols = (("noise_beta_c", r"$\beta_c$"), ("noise_zeta_f", r"$\zeta_f$"))
    return [f"{sym} = {_num(attrs[key])}" for key, sym in symbols if key in attrs]


def _noise_text(ds):
    """``rms_r = ...`` and the spectrum, from the dataset's global attributes (the config's
    name of the noise record is provenance, in the dataset and the report, not on a figure)."""
    rms = ds.attrs.get("noise_rms")
    parts = [] if rms is None else [f"rms$_r$ = {_num(rms)}"]
    parts += _spectrum_parts(ds.attrs)
    return ", ".join(parts)


def _sine_argument(beta_f):
    r"""Argument of the harmonic in mathtext, as the paper writes it: ``1.1\,\tau`` for
    beta_f = 1.1 and ``\tau/1.1`` for beta_f = 1/1.1, whichever prints shorter (4 digits)."""
    beta_f = float(beta_f)
    times, over = _num(beta_f), _num(1.0 / beta_f)
    return rf"{times}\,\tau" if len(times) <= len(over) else rf"\tau/{over}"


def _forcing_text(ds, beta_f=None, inv_beta=None):
    """``f(tau) = A sin(1.1 tau) + r(tau)`` at beta_f (or 1/inv_beta), with the noise."""
    amplitude = float(_attr(ds, "amplitude"))
    if amplitude == 0.0:
        harmonic = ""
    else:
        arg = _sine_argument(beta_f if inv_beta is None else 1.0 / float(inv_beta))
        scale = "" if amplitude == 1.0 else f"{_num(amplitude)}"
        harmonic = rf"{scale}$\sin({arg})$ + "
    noise = _noise_text(ds)
    return rf"$f(\tau)$ = {harmonic}$r(\tau)$" + (f" ({noise})" if noise else "")


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
    return (f"{_kind_text(noise.attrs)} noise: {', '.join(spectrum)};  "
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
    ax_f.plot(tau, force, color="C0", lw=0.9, label=axis_label(force))
    if harmonic:
        ax_f.plot(tau, trace["f"] - trace["r"], color="0.35", lw=0.9, ls="--",
                  label=r"harmonic part $f - r$")
        _headroom(ax_f)
        ax_f.legend(loc="upper right", ncols=2)
    ax_f.set_ylabel(axis_label(force))
    _panel_tag(ax_f, "(a)")

    ax_a.plot(tau, trace["a"], color="C0", lw=1.0)
    # two walls: the lower wall at a = gap, its impacts drawn there
    gap = (float(trace.attrs["gap"]) if "impact_wall" in trace and two_wall_dataset(trace)
           else 0.0)
    ax_a.axhline(0.0, color="0.2", lw=1.4,
                 label=r"upper wall ($a = 0$)" if gap else r"wall ($a = 0$)")
    t_imp = np.asarray(trace["impact_time"])
    at = (np.where(np.asarray(trace["impact_wall"]) == 1, gap, 0.0) if gap
          else np.zeros(t_imp.size))
    if gap:
        ax_a.axhline(gap, color="0.2", lw=1.4, ls="--", label=r"lower wall ($a = g$)")
    shown = (t_imp >= float(tau[0])) & (t_imp <= float(tau[-1]))
    if "impact_collision" in trace:
        # a collision's first impact, and the rebounds of its chatter apart (docs/figures.md)
        col = np.asarray(trace["impact_collision"])
        first = np.ones(col.size, bool)
        first[1:] = col[1:] != col[:-1]
        rebound = shown & ~first
        if rebound.any():
            ax_a.plot(t_imp[rebound], at[rebound], ls="none", marker="|",
                      color="0.35", markersize=7, label=f"chatter rebound ({int(rebound.sum())})")
        shown &= first
        label = f"collision: first impact ({int(shown.sum())})"
    else:
        label = f"impact ({int(shown.sum())})"
    if not shown.any():
        label = "no collision in this stretch"
    ax_a.plot(t_imp[shown], at[shown], ls="none", marker="v", color="C3",
              markersize=5, label=label)
    a = np.asarray(trace["a"], dtype=float)
    if np.ptp(np.append(a, 0.0)) > 0.0:
        ax_a.set_ylim(bottom=min(-0.06 * a.max(), a.min()))
    else:
        ax_a.set_ylim(-0.06, 1.0)           # a = 0 throughout: the mass rests at the wall
    _headroom(ax_a)
    ax_a.set_ylabel(axis_label(trace["a"]))
    ax_a.set_xlabel(axis_label(tau))
    ax_a.legend(loc="upper right", ncols=2)
    _panel_tag(ax_a, "(b)")

    beta_f = trace.attrs.get("beta_f")
    params = (f"{_system_text(trace)}, $\\delta$ = {_num(_attr(trace, 'delta'))};  "
              f"{_forcing_text(trace, beta_f=beta_f)}")
    if "axes" in trace.attrs and "cell" in trace.attrs:     # a plane study's point
        axes = trace.attrs["axes"]
        if isinstance(axes, (bytes, str)):
            text = axes.decode() if isinstance(axes, bytes) else axes
            axes = _decoded(text, "axes") if text.lstrip().startswith("[") else text.split()
        axes = [str(a) for a in np.atleast_1d(axes)]
        point = ", ".join(f"{parameter_symbol(k)} = {_num(v)}"
                          for k, v in zip(axes, np.atleast_1d(trace.attrs["cell"])))
        params += (f"\nat the point {point} of the study's "
                   f"({', '.join(parameter_symbol(k) for k in axes)}) plane")
    _header(fig, title, params)
    return fig


def _response_spectra(spectra, i_beta, title, params, beta_max, lin_label):
    """S_a for every delta of the dataset (log y), with the linear reference S_lin."""
    fig, (ax,) = _figure()
    ds = spectra.isel(inv_beta=i_beta)
    ds = ds.isel(beta=np.flatnonzero(np.asarray(ds["beta"]) <= beta_max))
    deltas = np.asarray(ds["delta"], dtype=float)
    order = np.argsort(deltas)[::-1]
    harmonic = float(_attr(spectra, "amplitude")) != 0.0
    beta_f = 1.0 / float(spectra["inv_beta"][i_beta])
    full = spectra.isel(inv_beta=i_beta)
    for style, k in zip(family_styles(deltas.size), order):
        label = rf"$\delta$ = {_num(deltas[k])}"
        if harmonic:
            power = line_power(full["beta"], full["S_a"].isel(delta=k), beta_f)
            label += rf"  (line at $\beta_f$: power {power:.3g})"
        ax.plot(ds["beta"], ds["S_a"].isel(delta=k), color=style["color"], ls=style["ls"],
                lw=1.2, label=label)
    ax.plot(ds["beta"], ds["S_lin"], color="k", ls=(0, (1.5, 1.5)), lw=1.1, label=lin_label)
    if harmonic:
        _mark_forcing(ax, float(spectra["inv_beta"][i_beta]))
    if input_is_zero(spectra):
        # what the record holds is round-off: a log axis would show it as a spectrum
        ax.set_ylim(-0.05, 1.0)
        note_on_axes(ax, "the force is zero (rms$_r$ = 0, no harmonic):\n"
                         r"the mass stays at rest, $a(\tau)$ has no power")
    else:
        ax.set_yscale("log")
    ax.set_xlim(0.0, float(ds["beta"].max()))
    ax.set_xlabel(axis_label(ds["beta"]))
    ax.set_ylabel(_psd_label(ds["S_a"]))
    # below the axes: inside, it hid the resonance peaks and the harmonics of the forcing
    fig.set_figheight(fig.get_figheight() * 1.3)
    fig.legend(loc="outside lower center", ncols=2, fontsize=7.5,
               title=_welch_text(full, harmonic), title_fontsize=7)
    _header(fig, title, params)
    return fig


def _welch_text(ds, lines):
    """Legend title of a Welch spectrum: its resolution, segments and, with spectral `lines`,
    why their peak heights are not comparable but their powers are (`stats.line_power`)."""
    step = float(ds["beta"][1] - ds["beta"][0])
    segments = np.asarray(ds["n_segments"]) if "n_segments" in ds else np.array([])
    text = rf"Welch, Hann window: resolution $\Delta\beta$ = {step:.3g}"
    if segments.size:
        n = int(segments.min())
        text += f", {n:,} segment{'' if n == 1 else 's'}"
    if lines:
        text += ("\n" r"a line's peak height grows as 1/$\Delta\beta$; its power "
                 r"$\frac{1}{\pi}\int (S - S_{\rm background})\,d\beta$ does not")
    return text


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


#: The sparse-bin rule of every density figure: a bin is drawn on its own only when it holds
#: at least this many values; a run of neighbouring sparser bins is merged until the run holds
#: that many (a bar over the run's width, apart from the curve, density = count / (n * run
#: width)), and a run
#: that ends below it is not drawn. With 10 values the relative error of a merged bin is
#: below about 1/sqrt(10) ~ 0.3, so no single value spikes down the log axis.
MIN_BIN_COUNT = 10
#: Line styles and markers of a family of curves, with the colours: neighbouring members
#: differ in all three (cycled when a family has more members).
FAMILY_LINESTYLES = ("-", "--", "-.", ":")
FAMILY_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
#: Markers drawn per curve (spread over its points, staggered between the curves).
MARKERS_PER_CURVE = 9


def family_styles(n):
    """Colour, line style and marker of each of `n` curves of a family (a list of dicts)."""
    colors = _colors(n)
    return [dict(color=colors[k], ls=FAMILY_LINESTYLES[k % len(FAMILY_LINESTYLES)],
                 marker=FAMILY_MARKERS[k % len(FAMILY_MARKERS)]) for k in range(n)]


def _markevery(n_points, k, n_curves):
    """Evenly spread marker positions of curve `k` of `n_curves`, staggered between curves."""
    step = max(n_points // MARKERS_PER_CURVE, 1)
    return (int(step * k / max(n_curves, 1)) % step, step)


def merge_sparse_bins(edges, counts, min_count=MIN_BIN_COUNT):
    """Bins of a histogram after the sparse-bin rule (`MIN_BIN_COUNT`).

    Parameters
    ----------
    edges : array_like, shape (n + 1,)
        Bin edges, increasing.
    counts : array_like, shape (n,)
        Values in each bin (non-negative integers).
    min_count : int, optional
        Fewest values a drawn bin holds.

    Returns
    -------
    left, right, count : numpy.ndarray
        The drawn bins: every bin holding ``>= min_count`` values as it is, and each run of
        neighbouring sparser bins merged, from left to right, until the run holds
        ``min_count`` values. A run that meets a full bin, or the last bin, before it holds
        that many is dropped (not drawn), as are empty bins outside every run that holds values.
    """
    edges = np.asarray(edges, dtype=float)
    counts = np.asarray(counts)
    if edges.size != counts.size + 1:
        raise ValueError(f"need len(edges) == len(counts) + 1, got {edges.size} and {counts.size}")
    if min_count < 1:
        raise ValueError(f"min_count must be >= 1, got {min_count}")
    left, right, count = [], [], []
    start, total = None, 0
    for i, c in enumerate(counts):
        if c >= min_count:
            start, total = None, 0          # an unfinished sparse run before it is dropped
            left.append(edges[i]), right.append(edges[i + 1]), count.append(c)
            continue
        if start is None:
            if c == 0:
                continue                    # a run starts at its first value
            start = i
        total += c
        if total >= min_count:
            left.append(edges[start]), right.append(edges[i + 1]), count.append(total)
            start, total = None, 0
    return np.array(left), np.array(right), np.array(count)


def bin_counts(cell, var):
    """Values per bin of density `var` of one cell: ``density * n * width``, rounded.

    `n` is what the density is normalised by (`vibroimpact.stats.density` with ``total``):
    one value per collision for the velocity, one per interval (collisions - 1) for the
    interval and z_j/z. The product is an integer to round-off (checked).
    """
    x = cell[var].dims[-1]
    edges = _bin_edges(cell[x])
    n = int(cell["n_collisions"]) - (0 if var.startswith("v_after") else 1)
    exact = np.nan_to_num(np.asarray(cell[var], dtype=float)) * max(n, 0) * np.diff(edges)
    counts = np.rint(exact)
    if np.any(np.abs(exact - counts) > 1e-6 * np.maximum(counts, 1.0)):
        raise ValueError(f"{var} times n * width is not a count: the density is not normalised "
                         f"by n = {n} values (see vibroimpact.stats.density)")
    return edges, counts.astype(np.int64), n


def _bin_edges(centres):
    """Edges of evenly spaced bins from their centres (the first edge at 0 for one bin)."""
    c = np.asarray(centres, dtype=float)
    half = 0.5 * (c[1] - c[0]) if c.size > 1 else c[0]     # one bin: [0, max] (datasets.bin_edges)
    return np.concatenate([c - half, [c[-1] + half]])


def _drawn_density(cell, var, band):
    """The drawn parts of one cell's density after the sparse-bin rule: ``(curve, runs)``.

    ``curve = (x, density, stderr, count)``: the bins drawn on their own (>= `MIN_BIN_COUNT`
    values), a point at each centre, with NaN breaks where the bins between two drawn ones
    were empty, dropped or merged. ``runs = (left, right, density, stderr, count)``: the
    merged runs of sparse bins. A run's density is known only as its mean over the run, so
    it is drawn apart from the curve (a bar over the run's width), never joined to it as a
    plateau that would read as structure. A run's standard error combines its bins' as
    independent, ``sqrt(sum (se_i w_i)^2) / W`` (neighbouring bins' batch means are nearly
    uncorrelated). ``stderr`` is None without a ``band``.
    """
    edges, counts, n = bin_counts(cell, var)
    left, right, count = merge_sparse_bins(edges, counts)
    w = np.diff(edges)
    lo = np.searchsorted(edges, left + 0.5 * w[0]) - 1     # first bin of each drawn bin
    hi = np.searchsorted(edges, right - 0.5 * w[0])         # one past its last
    se_bins = (None if band is None
               else np.nan_to_num(np.asarray(cell[band], dtype=float)) * w)
    width = right - left
    y = count / (n * width) if count.size else np.empty(0)
    se = (np.full(count.size, np.nan) if se_bins is None else
          np.array([np.sqrt(np.sum(se_bins[i:j] ** 2)) for i, j in zip(lo, hi)]) / width)
    single = (hi - lo) == 1
    xs, ys, ses, cs = [], [], [], []
    previous = None                                  # one past the last bin on the curve
    for j in np.flatnonzero(single):
        if previous is not None and lo[j] != previous:     # a gap, or a merged run between
            xs.append(np.nan), ys.append(np.nan), ses.append(np.nan), cs.append(0)
        xs.append(0.5 * (left[j] + right[j])), ys.append(y[j]), ses.append(se[j])
        cs.append(count[j])
        previous = hi[j]
    curve = (np.array(xs), np.array(ys), None if band is None else np.array(ses),
             np.array(cs, dtype=np.int64))
    m = ~single
    runs = (left[m], right[m], y[m], None if band is None else se[m], count[m])
    return curve, runs


def _density_bounds(y, half, count, n, width):
    """The band of a drawn density: ``y +- half`` joined with Garwood's interval of its count.

    ``count`` values in a bin (or run) of ``width`` out of ``n``: the density is never less
    uncertain than its Poisson count says (`vibroimpact.stats.poisson_interval`, 95 %), and
    the batch-means half-width ``half`` widens it where the values are correlated.
    """
    g_lo, g_hi = poisson_interval(np.asarray(count, dtype=float), CONFIDENCE)
    scale = 1.0 / (n * np.asarray(width, dtype=float))
    return (np.fmin(np.clip(y - half, 1e-300, None), g_lo * scale),
            np.fmax(y + half, g_hi * scale))


def _density_figure(events, i_beta, var, title, params, density_delta=None, linear=False,
                    zoom=None):
    """One density curve per density delta at inv_beta index `i_beta`, with a confidence band.

    Panel (a) has a log density axis (the tails matter as much as the bulk); with `linear`,
    panel (b) draws the same curves on a linear axis, where the spread of the bulk reads;
    with `zoom` (a value of x), panel (a) shows every drawn bin and panel (b) the same
    curves, log too, on ``[0, zoom]``, where the bulk reads. The curves, their bands and
    the legend's title are :func:`_draw_densities` and :func:`_density_rule_text`, which the
    two-wall figures (`plotting.walls.wall_density_figure`) draw with too. Each legend entry
    gives the cell's number of collisions and, when above `BEYOND_SHOWN`, the fraction of
    values beyond the last bin (``{quantity}_beyond``). The x axis ends at the last drawn bin.

    Returns
    -------
    (Figure, list of Axes)
    """
    two = linear or zoom is not None
    fig, axes = _figure(2 if two else 1, sharex=zoom is None,
                        height_ratios=(1.3, 1.0) if two else None)
    ds = events.isel(inv_beta=i_beta)
    index = _density_deltas(events, density_delta)
    x = _require(ds, var, "this figure").dims[-1]
    beyond = _require(ds, f"{var.removesuffix('_density')}_beyond", "this figure")
    labels = []
    for k in index:
        n = int(ds["n_collisions"][k])
        impacts = f"{n:,} collision{'' if n == 1 else 's'}" if n else "no collision"
        labels.append(rf"$\delta$ = {_num(ds['delta'][k])}  ({impacts}{_beyond_text(beyond[k])})")
    drawn = _draw_densities(axes, ds, var, index, labels)
    edges = _bin_edges(ds[x])
    for ax in axes if zoom is not None else axes[:1]:
        _density_log_limits(ax, drawn)
    if drawn.top <= 0.0:
        shown = ds.isel(delta=index)
        empty = (no_collision_text(shown, where=r"in this record at any $\delta$ drawn")
                 if int(shown["n_collisions"].sum()) == 0 else SPARSE_TEXT)
        for ax in axes:
            note_on_axes(ax, empty)
    for ax in axes[1:] if linear else ():
        ax.set_ylim(0.0, 1.08 * drawn.top if drawn.top > 0.0 else 1.0)
    for ax in axes:
        ax.set_xlim(edges[0], drawn.x_end if drawn.x_end > edges[0] else edges[-1])
        ax.set_ylabel(_restitution_note(ds, axis_label(ds[var])))
    axes[-1].set_xlabel(_restitution_note(ds, axis_label(ds[x])))
    if linear:
        _panel_tag(axes[0], "(a) log scale")
        _panel_tag(axes[1], "(b) linear scale")
    if zoom is not None:
        axes[1].set_xlim(edges[0], min(float(zoom), axes[0].get_xlim()[1]))
        axes[0].set_xlabel(_restitution_note(ds, axis_label(ds[x])))
        _panel_tag(axes[0], "(a) every bin drawn")
        _panel_tag(axes[1], f"(b) the bulk, up to {_num(axes[1].get_xlim()[1])}")
    title_text = _density_rule_text(ds, index, drawn)
    if len(index) > LEGEND_INSIDE or two:
        # a legend this tall would hide the curves' peaks: below the axes instead
        fig.set_figheight(fig.get_figheight() * (1.2 if two else 1.3))
        fig.legend(loc="outside lower center", ncols=2, title=title_text, title_fontsize=7.5,
                   fontsize=7.5)
    else:
        axes[0].legend(loc="upper right", title=title_text, title_fontsize=7.5)
    _header(fig, title, params)
    return fig, axes


#: What a density panel says when no curve is drawn although there were collisions.
SPARSE_TEXT = (f"no bin run holds {MIN_BIN_COUNT} values at any $\\delta$ drawn:\n"
               "too few collisions for a density")


@dataclass(frozen=True)
class DrawnDensities:
    """What :func:`_draw_densities` drew: the x axis's end (the last drawn bin's right
    edge, or the first edge when nothing was drawn), the largest and smallest densities
    drawn (``top`` 0 and ``low`` inf when none), whether a merged run was drawn, and the
    band's Student quantile per delta of the dataset (None without a band)."""
    x_end: float
    top: float
    low: float
    any_run: bool
    t: np.ndarray | None


def _draw_densities(axes, ds, var, index, labels=None):
    """Draw the densities `var` of the cells ``ds.isel(delta=k)``, k in `index`, on each of `axes`.

    Bins follow the sparse-bin rule (`MIN_BIN_COUNT`, :func:`merge_sparse_bins`): a curve
    joins the bins drawn on their own; a merged run of sparse bins is a bar over its width
    apart from the curve (gid ``"sparse_run"``), with a vertical 95 % interval. The band
    (gid ``"band"``) is +-t batch-means standard errors (``{var}_stderr``), t the Student
    quantile of B - 1 dof (`CONFIDENCE`, B = ``n_batches``), joined with Garwood's interval
    of the bin's count (a density of few values is never drawn surer than its Poisson
    count allows).

    Parameters
    ----------
    axes : sequence of matplotlib.axes.Axes
        Every axes gets every curve.
    ds : xarray.Dataset
        One inv_beta row of an events dataset (or a wall's view of it,
        `plotting.walls.wall_view`): ``var``, optionally ``{var}_stderr``, ``n_collisions``
        and ``n_batches`` over ``delta``.
    var : str
        ``"v_after_density"``, ``"interval_density"`` or ``"ratio_density"``.
    index : sequence of int
        The deltas drawn, in the order of `family_styles`.
    labels : sequence of str, optional
        The legend entry of each curve, on ``axes[0]``; None: no entry.

    Returns
    -------
    DrawnDensities
    """
    x = _require(ds, var, "this figure").dims[-1]
    band = f"{var}_stderr" if f"{var}_stderr" in ds else None
    t = None
    if band is not None:
        t = t_quantile(np.asarray(_require(ds, "n_batches", "the confidence band")), CONFIDENCE)
    styles = family_styles(len(index))
    edges = _bin_edges(ds[x])
    x_end, top, low = edges[0], 0.0, np.inf
    any_run = False
    for j, (style, k) in enumerate(zip(styles, index)):
        cell = ds.isel(delta=k)
        (xs, y, se, c), (r_left, r_right, r_y, r_se, r_c) = _drawn_density(cell, var, band)
        n_values = bin_counts(cell, var)[2]
        label = None if labels is None else labels[j]
        if band is not None and xs.size:
            b_lo, b_hi = _density_bounds(y, t[k] * se, c, n_values, np.diff(edges)[0])
        if band is not None and r_y.size:
            r_lo, r_hi = _density_bounds(r_y, t[k] * r_se, r_c, n_values, r_right - r_left)
        for ax in axes:
            ax.plot(xs, y, color=style["color"], ls=style["ls"], marker=style["marker"],
                    markersize=3.5, markevery=_markevery(xs.size, j, len(index)),
                    label=label if ax is axes[0] else None)
            if band is not None and xs.size:
                ax.fill_between(xs, b_lo, b_hi, color=style["color"], alpha=0.15, lw=0,
                                gid="band")
            if r_y.size:       # merged runs: apart from the curve, a bar over their width
                ax.hlines(r_y, r_left, r_right, color=style["color"], lw=1.6,
                          gid="sparse_run")
                if band is not None:
                    ax.vlines(0.5 * (r_left + r_right), r_lo, r_hi, color=style["color"],
                              lw=0.8, gid="sparse_run")
        any_run |= bool(r_y.size)
        drawn_x = np.concatenate([xs[np.isfinite(xs)] + 0.5 * np.diff(edges)[0], r_right])
        if drawn_x.size:
            x_end = max(x_end, float(drawn_x.max()))
            all_y = np.concatenate([y[np.isfinite(y)], r_y])
            top = max(top, float(all_y.max()))
            low = min(low, float(all_y.min()))
    return DrawnDensities(x_end, top, low, any_run, t)


def _density_log_limits(ax, drawn):
    """A log density axis from the smallest drawn density (halved), at most `DENSITY_DECADES`
    below the largest, to three times the largest."""
    ax.set_yscale("log")
    if drawn.top > 0.0:
        ax.set_ylim(max(drawn.low / 2.0, drawn.top * DENSITY_DECADES), drawn.top * 3.0)
    else:
        ax.set_ylim(DENSITY_DECADES, 1.0)


def _density_rule_text(ds, index, drawn):
    """The title of a density figure's legend: the band (when drawn) and the sparse-bin rule.

    `ds` and `index` as for :func:`_draw_densities`, `drawn` what it returned (``t`` None:
    no band).
    """
    rule = (f"bins with < {MIN_BIN_COUNT} values merged with their neighbours until they hold "
            f"{MIN_BIN_COUNT}, runs still below not drawn")
    if drawn.any_run:
        rule += ("\nbars apart from the curves: a merged run's mean density over its width"
                 + (" (vertical: its 95 % interval)" if drawn.t is not None else ""))
    if drawn.t is None:
        return rule
    b = np.unique(np.asarray(ds["n_batches"])[index])
    t_text = (f"t = {_num(drawn.t[index[0]])}, B = {int(b[0])} batches" if b.size == 1
              else "t of B - 1 dof")
    return (rf"band: $\pm$t$\cdot$batch-means s.e. "
            f"({100 * CONFIDENCE:g} %, {t_text}), at least Garwood's interval "
            f"of the count\n{rule}")


def _require_harmonic(events, figure):
    """Raise unless `events` is the dataset of a harmonic study (z_j / z needs a period)."""
    if float(_attr(events, "amplitude")) == 0.0 or "ratio_density" not in events:
        raise ValueError(f"{figure} needs the events of a harmonic study (amplitude != 0, "
                         f"with ratio_density); got amplitude = {events.attrs.get('amplitude')!r}")


#: What an impact statistic counts, printed on every figure of one (docs/figures.md).
COLLISION_NOTE = (r"per collision (an impact after a free flight, with its chatter and "
                  r"sticking)")
#: How each collision statistic is read off a collision; a figure defines those it draws.
COLLISION_QUANTITIES = {"v_after": r"$\varepsilon u_{j-0}$: its first rebound",
                        "interval": r"$z_j$: first impact to first impact"}


def _events_params(events, i_beta, drawn=tuple(COLLISION_QUANTITIES)):
    """Parameter line of an events/spectra dataset at inv_beta index `i_beta`; an events
    dataset (collision statistics) adds `COLLISION_NOTE` on a line of its own, with the
    definitions of the quantities `drawn` (keys of `COLLISION_QUANTITIES`) only."""
    inv_beta = float(events["inv_beta"][i_beta])
    harmonic = float(_attr(events, "amplitude")) != 0.0
    line = f"{_system_text(events)};  " + _forcing_text(
        events, inv_beta=inv_beta if harmonic else None)
    if "n_collisions" not in events:
        return line
    return line + "\n" + ";  ".join([COLLISION_NOTE]
                                    + [_restitution_note(events, COLLISION_QUANTITIES[name])
                                       for name in drawn])


def _restitution_note(ds, text):
    """A quantity's definition or label with the restitution each rebound had: its wall's
    ``eps_w`` when there are two, ``eps(u)`` under a law whose restitution falls with the
    speed; unchanged for one wall under Newton's law."""
    symbol = r"\varepsilon_w" if two_wall_dataset(ds) else r"\varepsilon"
    if speed_law(ds):
        symbol += r"(u)\,"
    return text.replace(r"\varepsilon u", symbol + " u")


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
