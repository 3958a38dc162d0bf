"""Figures of the random-force study (paper section 3): Figs. 3-9."""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from vibroimpact.plotting._common import (
    CONFIDENCE, FEW_IMPACTS, SPECTRUM_BETA_MAX, STOP_BAND_LEVEL, _attr, _density_figure,
    _events_params, _figure, _header, _headroom, _num, _padded, _panel_tag, _psd_label, _require,
    _restitution_note, _density_deltas, _response_spectra, _spectrum_text, _styled,
    _trace_figure, axis_label, family_styles, no_collision_text, note_on_axes, speed_law,
    t_quantile)
from vibroimpact.plotting.walls import two_walls, wall_density_figure, wall_means_figure
from vibroimpact.model import rebound_velocity
from vibroimpact.stats.theory import (
    ENVELOPE_DELTA_MIN, ENVELOPE_EPS_MIN, energy_envelope, envelope_v_after_pdf,
    upcrossing_rate)

#: fig05 draws the PSD of the piecewise-linear force as its own line when it differs from the
#: target of the samples by more than this fraction of the target's peak on the axis shown.
VISIBLE_DIFFERENCE = 0.01
#: Height (inches) of fig09: two panels plus the legend below them.
FIG09_HEIGHT = 7.4


def fig03(trace):
    """Fig. 3: (a) the random input r(tau); (b) a(tau) = delta - x(tau) with the impacts.

    Parameters
    ----------
    trace : xarray.Dataset
        ``results/traces/{study}.nc``: ``r(tau)``, ``a(tau)``, ``impact_time(impact)``;
        global attributes ``zeta``, ``eps``, ``delta``, ``amplitude`` (and the noise file's
        ``noise_rms``, ``noise_kind``, ... to describe the input).

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
        and the global attributes ``noise_kind``, ``noise_rms``, ``noise_dt``, ``noise_beta_c``,
        ``noise_zeta_f`` (as the kind has them), ``seed``, ``n_samples``.

    Returns
    -------
    matplotlib.figure.Figure
        One axes: the estimate (points) and the target of the sample sequence r_k (dashed,
        ``NoiseSpec.autocorrelation``); the subtitle describes the noise.
    """
    fig, (ax,) = _figure()
    ax.plot(noise["lag"], noise["phi_estimate"], color="C0", marker="o", markersize=2.5,
            label="estimate from the samples")
    ax.plot(noise["lag"], noise["phi_target"], color="k", ls="--", lw=1.1,
            label=r"target of the sample sequence $r_k$")
    ax.axhline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(axis_label(noise["lag"]))
    ax.set_ylabel(axis_label(noise["phi_estimate"]))
    ax.legend(loc="upper right")
    _header(fig, r"Fig. 4  Autocorrelation $\varphi_f(\tau^*)$ of the random input (eq. 8)",
            _spectrum_text(noise))
    return fig


@_styled
def fig05(noise):
    """Fig. 5: PSD S_f(beta) of the random input (paper eq. 9), estimate vs target, beta >= 0.

    Parameters
    ----------
    noise : xarray.Dataset
        ``results/noise/{noise}.nc``: ``S_estimate(beta)``, ``S_target(beta)``,
        ``S_target_linear(beta)`` and the global attributes described in :func:`fig04`.

    Returns
    -------
    matplotlib.figure.Figure
        One axes: the estimate, the target of the sample sequence (dashed) and, when it
        differs visibly (`VISIBLE_DIFFERENCE`), the PSD of the piecewise-linear force the
        simulator integrates (dotted). The y label states the two-sided angular convention,
        and a note compares the variance recovered from the estimate,
        ``(1/pi) int_0^inf S dbeta``, with rms^2.

    Notes
    -----
    Two-sided, angular: ``variance = (1/2 pi) int_{-inf}^{inf} S(beta) dbeta`` (eq. 9).
    """
    fig, (ax,) = _figure()
    ds = noise.isel(beta=np.flatnonzero(np.asarray(noise["beta"]) >= 0.0))
    ax.plot(ds["beta"], ds["S_estimate"], color="C0", label="estimate from the samples")
    ax.plot(ds["beta"], ds["S_target"], color="k", ls="--", lw=1.1,
            label=r"target of the sample sequence $r_k$")
    beta, target = np.asarray(ds["beta"]), np.asarray(ds["S_target"])
    band = np.flatnonzero(target > STOP_BAND_LEVEL * target.max())
    beta_max = min(beta.max(), 1.25 * beta[band[-1]]) if band.size else beta.max()
    linear = np.asarray(_require(ds, "S_target_linear", "fig05"))
    shown = beta <= beta_max
    if np.max(np.abs(linear - target)[shown]) > VISIBLE_DIFFERENCE * target[shown].max():
        ax.plot(beta, linear, color="C3", ls=":", lw=1.4,
                label="piecewise-linear force the simulator integrates")
    variance = np.trapezoid(np.asarray(ds["S_estimate"]), beta) / np.pi
    note = (r"$\sigma^2 = \frac{1}{2\pi}\int_{-\infty}^{\infty} S\,d\beta$"
            rf" from the estimate: {variance:.4g}"
            rf"  (rms$^2$ = {float(_attr(noise, 'noise_rms')) ** 2:.4g})")
    ax.set_xlim(0.0, beta_max)
    ax.set_ylim(bottom=0.0)
    _headroom(ax)
    ax.set_xlabel(axis_label(ds["beta"]))
    ax.set_ylabel(_psd_label(ds["S_estimate"]))
    ax.legend(loc="upper right", title=note, title_fontsize=8)
    _header(fig, r"Fig. 5  Power spectral density $S_f(\beta)$ of the random input (eq. 9)",
            _spectrum_text(noise))
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
        spectra, 0, r"Fig. 6  Power spectral density of the displacement $a(\tau)$ of the mass",
        _events_params(spectra, 0), beta_max, r"linear $|H|^2 S_f$ (no impacts)")


@_styled
def fig07(events, density_delta=None, envelope="auto"):
    """Fig. 7: probability density of the velocity after impact, one curve per density delta.

    Parameters
    ----------
    events : xarray.Dataset
        ``results/datasets/{study}_events.nc``; inv_beta index 0.
    density_delta : sequence of float, optional
        Deltas to draw (the dataset's nearest values; config key ``density_delta``); default
        the largest seven of the dataset.
    envelope : {"auto", "always", "never"}
        The energy-envelope theory's density (`vibroimpact.stats.envelope_v_after_pdf`):
        drawn where it applies, also outside it (dash-dotted, labelled so), or never; at
        delta >= `ENVELOPE_DELTA_MIN` only. See :func:`fig09`.

    Returns
    -------
    matplotlib.figure.Figure
        (a) log and (b) linear density axes, one line per (distinct) density delta with a
        shaded 95 % band; sparse bins merged (`MIN_BIN_COUNT`). The theory, when drawn, is a
        thin line of its delta's colour (gid ``"envelope"``). A two-wall dataset: one panel
        per wall (`plotting.walls.wall_density_figure`; the one-wall theory is not drawn).
    """
    if two_walls(events):
        return wall_density_figure(events, 0, "v_after", "Fig. 7 (two walls)  Probability "
                                   "density of the velocity after impact, per wall",
                                   density_delta)
    fig, axes = _density_figure(events, 0, "v_after_density",
                                "Fig. 7  Probability density of the velocity after impact",
                                _events_params(events, 0, ("v_after",)), density_delta,
                                linear=True)
    theory = _envelope(events, envelope)
    if theory is None:
        if envelope == "auto":
            _envelope_note(fig, None, False, "", events)
        return fig
    ds = events.isel(inv_beta=0)
    index = _density_deltas(events, density_delta)
    w = np.linspace(*axes[0].get_xlim(), 400)[1:]
    low, top = axes[0].get_ylim()
    drawn = False
    for style, k in zip(family_styles(len(index)), index):
        delta = float(ds["delta"][k])
        if delta < ENVELOPE_DELTA_MIN:
            continue
        p = envelope_v_after_pdf(w, delta, eps=theory["eps"], zeta=theory["zeta"],
                                 S0=theory["S0"])
        for ax in axes:
            (line,) = ax.plot(w, np.where(p > 0.0, p, np.nan), color=style["color"],
                              ls=theory["ls"], lw=ENVELOPE_DENSITY_LW, alpha=0.4, zorder=1)
            line.set_gid("envelope")
        drawn = True
    axes[0].set_ylim(low, top)      # the theory's far tail does not stretch the log axis
    _envelope_note(fig, theory, drawn, "wide pale lines, each in its $\\delta$'s colour",
                   events)
    return fig


#: Upper end of fig08's panel (b), the bulk of the intervals (panel (a) shows every bin).
FIG08_ZOOM = 20.0


@_styled
def fig08(events, density_delta=None, zoom=FIG08_ZOOM):
    """Fig. 8: probability density of the interval between collisions (as fig07).

    Parameters
    ----------
    events : xarray.Dataset
        As for :func:`fig07`.
    density_delta : sequence of float, optional
        As for :func:`fig07`.
    zoom : float, optional
        Upper end of panel (b).

    Returns
    -------
    matplotlib.figure.Figure
        Two log-density axes: (a) up to the last drawn bin, so the long waits of the
        smallest plays (the tail that grows again as delta falls below about -0.2) are
        seen whole; (b) the bulk, ``0 <= z_j <= zoom``. A two-wall dataset: one panel per
        wall, the interval from a collision at the wall to its next there
        (`plotting.walls.wall_density_figure`).
    """
    if two_walls(events):
        return wall_density_figure(events, 0, "interval", "Fig. 8 (two walls)  Probability "
                                   "density of the interval between collisions, per wall",
                                   density_delta)
    fig, _ = _density_figure(events, 0, "interval_density",
                             "Fig. 8  Probability density of the interval between collisions",
                             _events_params(events, 0, ("interval",)), density_delta,
                             zoom=zoom)
    return fig


def critical_delta(events, inv_beta_index=0):
    """Largest swept delta with a collision in the record, when every larger one has none.

    Not a physical threshold: under a Gaussian force the collision rate falls with delta
    (as Rice's up-crossing rate, `vibroimpact.stats.upcrossing_rate`) but never reaches
    zero; this is the largest play the record's largest excursion reached.

    Parameters
    ----------
    events : xarray.Dataset
        Events dataset with ``n_collisions(inv_beta, delta)``.
    inv_beta_index : int, optional
        Which forcing frequency.

    Returns
    -------
    float
        The largest delta with ``n_collisions > 0`` when every larger delta has none; NaN
        when the largest swept delta still has collisions or when no delta has any.
    """
    ds = events.isel(inv_beta=inv_beta_index).sortby("delta")
    hit = np.flatnonzero(np.asarray(ds["n_collisions"]) > 0)
    if hit.size == 0 or hit[-1] == ds["delta"].size - 1:
        return float("nan")
    return float(ds["delta"][hit[-1]])


#: Rice's asymptotes are drawn from this many wall-free stds sigma_x of play upwards (where
#: the wall's memory is short against the mean interval, `stats.upcrossing_rate`).
RICE_FROM_SIGMA = 1.5
#: ... up to this many: beyond, Rice's mean interval exceeds exp(30^2 / 2) ~ 1e195, off every
#: axis (and, past ~37 stds, beyond float64).
RICE_TO_SIGMA = 30.0


@_styled
def fig09(events, envelope="auto"):
    """Fig. 9: mean velocity after impact and mean interval against delta, 95 % bars.

    Parameters
    ----------
    events : xarray.Dataset
        Events dataset of a fine delta sweep (inv_beta index 0): ``v_after_mean``,
        ``v_after_mean_lo/_hi``, ``interval_mean`` (T/N), ``interval_mean_lo/_hi``,
        ``n_collisions``, ``n_batches`` (a dataset without the ``_lo/_hi`` ends: ``*_stderr``,
        drawn +-t); attributes ``record_length`` and, to draw Rice's asymptotes,
        ``linear_sigma_x`` and ``linear_sigma_v``.
    envelope : {"auto", "always", "never"}
        The energy-envelope averaging (`vibroimpact.stats.energy_envelope`, docs/model.md
        section 7.2): ``"auto"`` draws it where it applies (eps >= `ENVELOPE_EPS_MIN`,
        delta >= `ENVELOPE_DELTA_MIN`) and otherwise says in the legend that it is not
        drawn; ``"always"`` draws it at every delta >= `ENVELOPE_DELTA_MIN` also for a
        smaller eps, dash-dotted and labelled as outside its range; ``"never"`` leaves it
        out. Its white-noise level at the resonance is ``S0 = 4 zeta sigma_x^2``.

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked axes sharing delta; (b), the mean interval, on a log scale. Bars are the
        stored 95 % intervals, honest for few and bursty collisions: (a) over equal stretches
        of time (`vibroimpact.stats.mark_mean`), (b) Garwood's interval of the count widened
        for overdispersion (`vibroimpact.stats.event_rate`). Points resting on fewer than
        `FEW_IMPACTS` collisions are open squares, with their bars; (b) draws T/N from one
        collision on, (a) leaves out plays whose collisions give no interval (a single
        collision) and says so in the legend. Rice's large-play asymptotes (gid ``"rice"``):
        the mean velocity after impact ``eps sigma_v sqrt(pi/2)`` and the mean interval
        ``1/nu+(delta)``, with the
        record length, beyond which no interval can be measured. The plays with no
        collision in the record are shaded (gid ``"no_collision"``), from
        :func:`critical_delta` on: a property of this record, not a threshold. The
        energy-envelope theory (gid ``"envelope"``): (a) ``eps <V>``, (b) ``1 / nu``.
        A two-wall dataset: the means of each wall, one colour each
        (`plotting.walls.wall_means_figure`; the one-wall asymptotes are not drawn).
    """
    if two_walls(events):
        return wall_means_figure(events, "Fig. 9 (two walls)  Mean velocity after impact and "
                                 "mean interval against $\\delta$, per wall")
    fig, axes = _figure(2)
    fig.set_figheight(FIG09_HEIGHT)
    ds = events.isel(inv_beta=0).sortby("delta")
    delta = np.asarray(ds["delta"], dtype=float)
    n = np.asarray(ds["n_collisions"])
    n_batches = np.asarray(_require(ds, "n_batches", "fig09's confidence bars"))
    t = t_quantile(n_batches, CONFIDENCE)
    enough = n >= FEW_IMPACTS
    batches = np.unique(n_batches[enough] if enough.any() else n_batches)
    t_text = (f"t = {_num(t_quantile(batches[0], CONFIDENCE))}, {int(batches[0])} batches"
              if batches.size == 1 else "t of B - 1 dof")
    bar_label = rf"mean $\pm$ t$\cdot$batch-means s.e. ({100 * CONFIDENCE:g} %, {t_text})"
    if "interval_mean_lo" in ds:
        b_text = f"{int(batches[0])}" if batches.size == 1 else "B"
        bar_label = (f"95 % intervals: (a) t over {b_text} equal stretches of time; (b) T/N "
                     "(record / collisions),\nGarwood's interval of the count, widened where "
                     "bursts of collisions overdisperse it")
    d_c = critical_delta(events)
    record = ds.attrs.get("record_length")
    sigma = (ds.attrs.get("linear_sigma_x"), ds.attrs.get("linear_sigma_v"))
    # a zero force (rms 0) has a wall-free response without excursions: no asymptote
    rice = None not in sigma and min(float(v) for v in sigma) > 0.0
    if rice:
        sigma_x, sigma_v = (float(v) for v in sigma)
        d_lo = max(RICE_FROM_SIGMA * sigma_x, delta.min())
        d_hi = min(RICE_TO_SIGMA * sigma_x, delta.max())
        rice = d_lo < d_hi      # the asymptotes reach the sweep, on a finite axis
    if rice:
        d_rice = np.linspace(d_lo, d_hi, 200)
        eps = float(_attr(ds, "eps"))
        asymptotes = (np.full_like(d_rice, _rice_rebound(ds, eps, sigma_v)),
                      1.0 / upcrossing_rate(d_rice, sigma_x, sigma_v))
    theory = _envelope(events, envelope)
    if theory is not None:
        lo = max(ENVELOPE_DELTA_MIN, delta.min())
        d_env = np.linspace(lo, delta.max(), 200) if lo < delta.max() else np.empty(0)
        if d_env.size:
            th = energy_envelope(d_env, eps=theory["eps"], zeta=theory["zeta"],
                                 S0=theory["S0"])
            envelope_curves = (th.v_after_mean, th.interval_mean)
    few_any = False
    for k, (ax, name, color) in enumerate(zip(axes, ("v_after", "interval"), ("C0", "C1"))):
        mean = np.asarray(ds[f"{name}_mean"], dtype=float)
        if f"{name}_mean_lo" in ds:           # the stored interval (honest for few events)
            lo = np.asarray(ds[f"{name}_mean_lo"], dtype=float)
            hi = np.asarray(ds[f"{name}_mean_hi"], dtype=float)
        else:                                 # an older dataset: +-t batch-means s.e.
            err = t * np.asarray(ds[f"{name}_stderr"], dtype=float)
            lo, hi = mean - err, mean + err
        # (b) T/N rests on the count, valid from one collision on; (a) a mean of marks
        # needs them spread over two or more batches (its interval is NaN otherwise)
        shown = np.isfinite(mean) & np.isfinite(lo) & (n >= (1 if k else 2))
        solid = shown & enough
        hi_drawn = np.where(np.isfinite(hi), hi, np.nan)
        yerr = np.vstack([mean - lo, hi_drawn - mean])
        ax.errorbar(delta[solid], mean[solid], yerr=yerr[:, solid], color=color, marker="o",
                    markersize=3.5, ls="-")
        few = shown & ~enough
        few_any |= bool(few.any())
        ax.errorbar(delta[few], mean[few], yerr=yerr[:, few], ls="none", marker="s",
                    mfc="white", color=color, markersize=4.5, elinewidth=0.8)
        if rice:
            (line,) = ax.plot(d_rice, asymptotes[k], color="0.25", ls="--", lw=1.1)
            line.set_gid("rice")
        if theory is not None and d_env.size:
            (line,) = ax.plot(d_env, envelope_curves[k], color=ENVELOPE_COLOR,
                              ls=theory["ls"], lw=1.2)
            line.set_gid("envelope")
        if np.isfinite(d_c):
            span = ax.axvspan(d_c, delta.max(), color="0.85", lw=0, zorder=0)
            span.set_gid("no_collision")
        ax.set_ylabel(_restitution_note(ds, axis_label(ds[f"{name}_mean"])))
    axes[0].set_ylim(bottom=0.0)
    if "v_after_mean_lo" in ds and enough.any():
        # the intervals of a handful of collisions run off the axis (they are that wide)
        v_top = np.nanmax(np.asarray(ds["v_after_mean_hi"], dtype=float)[enough])
        if np.isfinite(v_top):
            axes[0].set_ylim(top=1.6 * v_top)
    # the mean interval spans orders of magnitude (about 1 to 1e5 over the default sweep)
    axes[1].set_yscale("log")
    measured = np.asarray(ds["interval_mean"], dtype=float)
    if np.isfinite(measured).any():
        axes[1].set_ylim(0.5 * np.nanmin(measured),
                         20.0 * max(np.nanmax(measured), float(record or 0.0)))
    if not n.any():
        axes[0].set_xlim(*_padded(delta))
        axes[1].set_ylim(1.0, 20.0 * float(record or 1.0))
        for ax in axes:
            note_on_axes(ax, no_collision_text(ds))
    if record is not None:
        axes[1].axhline(float(record), color="0.45", ls=":", lw=1.0)
    # one legend for both panels, below them, so it never hides a point
    marks = [Line2D([], [], color="0.3", marker="o", markersize=3.5, label=bar_label)]
    if few_any:
        marks.append(Line2D([], [], ls="none", marker="s", mfc="white", color="0.3",
                            markersize=4.5, label=f"fewer than {FEW_IMPACTS} collisions ((b) one "
                                                  "collision: T/N is the record length)"))
    lone = (n == 1) | ((n > 1) & ~np.isfinite(np.asarray(
        ds["v_after_mean_lo"] if "v_after_mean_lo" in ds else ds["v_after_stderr"],
        dtype=float)))
    if lone.any():
        where = (f"{_num(delta[lone].min())}" if lone.sum() == 1
                 else f"{_num(delta[lone].min())}-{_num(delta[lone].max())}")
        what = ("a single collision" if np.all(n[lone] == 1)
                else "collisions in one stretch of time only")
        marks.append(Line2D([], [], ls="none",
                            label=rf"(a) left out at $\delta$ = {where}: {what} (a count, "
                                  "not a mean)"))
    first = np.flatnonzero(n > 0)
    held = (n == 0) & (delta < delta[first[0]]) if first.size else np.zeros(n.size, bool)
    if held.any():
        # a play too deep for the force ever to lift the mass: nothing to draw, said so
        contact = (np.asarray(ds["contact_fraction"], dtype=float)[held]
                   if "contact_fraction" in ds else np.empty(0))
        rest = (f", in contact with it for at least {100 * float(contact.min()):.3g} % of the "
                "record" if contact.size else "")
        marks.append(Line2D([], [], ls="none",
                            label=rf"not drawn: no collision at $\delta$ = "
                                  f"{', '.join(_num(d) for d in delta[held])} (held on the wall "
                                  f"throughout{rest})"))
    if rice:
        marks.append(Line2D([], [], color="0.25", ls="--", lw=1.1,
                            label=r"Rice, large $\delta$: (a) "
                                  + (r"$\langle\varepsilon(u)u\rangle$ ($u$ Rayleigh), "
                                     if "speed_scale" in ds.attrs
                                     else r"$\varepsilon\sigma_v\sqrt{\pi/2}$, ")
                                  + r"(b) $1/\nu^+(\delta)$, $\nu^+ = "
                                  r"\frac{\sigma_v}{2\pi\sigma_x}e^{-\delta^2/2\sigma_x^2}$ "
                                  rf"($\sigma_x$ = {_num(sigma_x)}, $\sigma_v$ = {_num(sigma_v)}: "
                                  "wall-free response)"))
    if theory is not None and d_env.size:
        marks.append(Line2D([], [], color=ENVELOPE_COLOR, ls=theory["ls"], lw=1.2,
                            label=_envelope_label(theory, r"(a) $\varepsilon\langle V\rangle$, "
                                                          r"(b) $1/\nu$")))
    elif envelope != "never" and _envelope_absent(events, theory):
        marks.append(Line2D([], [], ls="none", label=_envelope_absent(events, theory)))
    if record is not None:
        marks.append(Line2D([], [], color="0.45", ls=":", lw=1.0,
                            label=f"(b) record length {float(record):.3g}: no longer "
                                  "interval can be seen"))
    if np.isfinite(d_c):
        marks.append(Patch(color="0.85", label=rf"no collision in this record for $\delta$ > "
                                               rf"{_num(d_c)} (its largest excursion; the "
                                               "rate only falls, never to zero)"))
    fig.legend(handles=marks, loc="outside lower center", ncols=1, fontsize=7.5)
    axes[1].set_xlabel(axis_label(ds["delta"]))
    _panel_tag(axes[0], "(a)")
    _panel_tag(axes[1], "(b)")
    _header(fig, "Fig. 9  Mean velocity after impact and mean interval between collisions",
            _events_params(events, 0))
    return fig


#: Colour of the energy-envelope theory in fig09 (fig07 draws it in each delta's colour).
ENVELOPE_COLOR = "C2"
#: Its line style where it applies, and where it is drawn outside its range.
ENVELOPE_LS, ENVELOPE_OUTSIDE_LS = "-", "-."
#: Width of fig07's theory densities: wide and pale (alpha 0.4), behind the measured ones.
ENVELOPE_DENSITY_LW = 3.0
_ENVELOPE_MODES = ("auto", "always", "never")


def _rice_rebound(ds, eps, sigma_v):
    """Rice's large-play mean velocity after impact: the wall is met at Rayleigh speeds of
    scale ``sigma_v`` (the wall-free response's up-crossings of a high level), each leaving at
    its law's rebound speed: ``eps sigma_v sqrt(pi / 2)`` under Newton's law, the mean of
    ``eps(u) u`` over that distribution under a law that falls with the speed (a quadrature
    on 4001 points to 12 sigma_v: the density's tail beyond is below 1e-31)."""
    if "speed_scale" not in ds.attrs:       # the wall at delta: Newton's law
        return eps * sigma_v * np.sqrt(np.pi / 2.0)
    u = np.linspace(0.0, 12.0 * sigma_v, 4001)
    density = u / sigma_v**2 * np.exp(-0.5 * (u / sigma_v) ** 2)
    rebound = -rebound_velocity(eps, u, 1.0 / float(ds.attrs["speed_scale"]))
    return float(np.trapezoid(rebound * density, u))


def _envelope(events, envelope):
    """What fig07 and fig09 need to draw the energy-envelope theory, or None when it is not
    drawn: ``eps``, ``zeta``, ``S0 = 4 zeta sigma_x^2``, whether eps is in its range
    (``inside``), its line style."""
    if envelope not in _ENVELOPE_MODES:
        raise ValueError(f"envelope must be one of {_ENVELOPE_MODES}, got {envelope!r}")
    sigma_x = events.attrs.get("linear_sigma_x")
    if envelope == "never" or sigma_x is None or not float(sigma_x) > 0.0:
        return None
    eps, zeta = float(_attr(events, "eps")), float(_attr(events, "zeta"))
    # the theory's restitution is a constant: a law that falls with the speed is outside it
    inside = eps >= ENVELOPE_EPS_MIN and not speed_law(events)
    if envelope == "auto" and not inside:
        return None
    return dict(eps=eps, zeta=zeta, S0=4.0 * zeta * float(sigma_x) ** 2, inside=inside,
                ls=ENVELOPE_LS if inside else ENVELOPE_OUTSIDE_LS)


def _envelope_label(theory, what, sep=" "):
    """Legend text of the energy-envelope curves: what they are and under which assumptions
    (`sep` between its parts: a newline for a narrow legend column)."""
    text = (rf"energy-envelope averaging,{sep}$\varepsilon \to 1$, white noise at $\omega = 1$ "
            rf"($S_f(1) = 4\zeta\sigma_x^2$ = {_num(theory['S0'])}):{sep}{what}, "
            rf"$\delta \geq$ {_num(ENVELOPE_DELTA_MIN)}")
    if not theory["inside"]:
        text += (";\n" rf"OUTSIDE its range ($\varepsilon$ = {_num(theory['eps'])} < "
                 rf"{_num(ENVELOPE_EPS_MIN)}, or a restitution that falls with the speed): "
                 rf"for orientation only")
    return text


def _envelope_absent(events, theory, sep=" "):
    """Legend text saying why the energy-envelope theory is not drawn (`theory` from
    :func:`_envelope`): eps outside its range, or no play it covers; None for a force without
    a random part (no wall-free sigma_x), where it has nothing to say."""
    if theory is not None:
        return rf"energy-envelope theory: no $\delta \geq$ {_num(ENVELOPE_DELTA_MIN)} to draw"
    if float(events.attrs.get("linear_sigma_x", 0.0)) > 0.0 and speed_law(events):
        return (rf"energy-envelope theory not drawn:{sep}its restitution is a constant, this "
                rf"wall's falls with the impact speed")
    if float(events.attrs.get("linear_sigma_x", 0.0)) > 0.0 and float(
            _attr(events, "eps")) < ENVELOPE_EPS_MIN:
        return (rf"energy-envelope theory ($\varepsilon \to 1$) not drawn:{sep}"
                rf"$\varepsilon$ = {_num(_attr(events, 'eps'))} is outside its range "
                rf"$\varepsilon \geq$ {_num(ENVELOPE_EPS_MIN)} (docs/model.md 7.2)")
    return None


def _envelope_note(fig, theory, drawn, how, events=None):
    """Add the energy-envelope entry to fig07's legend (below the axes): the curves drawn
    (`theory`, when `drawn`), or why there are none."""
    legend = fig.legends[0] if fig.legends else None
    absent = None if drawn else _envelope_absent(events, theory, "\n")
    if legend is None or not (drawn or absent):
        return
    entry = (Line2D([], [], color="0.3", ls=theory["ls"], lw=ENVELOPE_DENSITY_LW, alpha=0.4,
                    label=_envelope_label(theory, "density of $\\varepsilon V$", "\n")
                    + f"\n{how}")
             if drawn else
             Line2D([], [], ls="none", label=absent))
    handles = list(legend.legend_handles) + [entry]
    labels = [t.get_text() for t in legend.get_texts()] + [entry.get_label()]
    title = legend.get_title().get_text()
    legend.remove()
    fig.legend(handles, labels, loc="outside lower center", ncols=2, title=title,
               title_fontsize=7.5, fontsize=7.5)
