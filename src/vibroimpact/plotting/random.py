"""Figures of the random-force study (paper section 3): Figs. 3-9."""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from vibroimpact.plotting._common import (
    CONFIDENCE, FEW_IMPACTS, SPECTRUM_BETA_MAX, STOP_BAND_LEVEL, _attr, _density_figure,
    _events_params, _figure, _header, _headroom, _num, _panel_tag, _psd_label, _require,
    _response_spectra, _spectrum_text, _styled, _trace_figure, axis_label, t_quantile)

#: fig05 draws the PSD of the piecewise-linear force as its own line when it differs from the
#: target of the samples by more than this fraction of the target's peak on the axis shown.
VISIBLE_DIFFERENCE = 0.01
#: Height (inches) of fig09: two panels plus the legend below them.
FIG09_HEIGHT = 6.6


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
        spectra, 0, "Fig. 6  Power spectral density of the displacement a(τ) of the mass",
        _events_params(spectra, 0), beta_max, r"linear $|H|^2 S_f$ (no impacts)")


@_styled
def fig07(events, density_delta=None):
    """Fig. 7: probability density of the velocity after impact, one curve per density delta.

    Parameters
    ----------
    events : xarray.Dataset
        ``results/datasets/{study}_events.nc``; inv_beta index 0.
    density_delta : sequence of float, optional
        Deltas to draw (the dataset's nearest values; config key ``density_delta``); default
        the largest seven of the dataset.

    Returns
    -------
    matplotlib.figure.Figure
        (a) log and (b) linear density axes, one line per (distinct) density delta with a
        shaded 95 % band; sparse bins merged (`MIN_BIN_COUNT`).
    """
    fig, _ = _density_figure(events, 0, "v_after_density",
                             "Fig. 7  Probability density of the velocity after impact",
                             _events_params(events, 0), density_delta, linear=True)
    return fig


@_styled
def fig08(events, density_delta=None):
    """Fig. 8: probability density of the interval between collisions (as fig07)."""
    fig, _ = _density_figure(events, 0, "interval_density",
                             "Fig. 8  Probability density of the interval between collisions",
                             _events_params(events, 0), density_delta)
    return fig


def critical_delta(events, inv_beta_index=0):
    """Smallest swept delta above which the record holds no impact (fig09's marker).

    Parameters
    ----------
    events : xarray.Dataset
        Events dataset with ``n_collisions(inv_beta, delta)``.
    inv_beta_index : int, optional
        Which forcing frequency.

    Returns
    -------
    float
        The largest delta with ``n_collisions > 0`` when every larger delta has none, i.e. no
        impact occurs for delta > critical_delta; NaN when the largest swept delta still has
        impacts (the sweep does not reach the critical play) or when no delta has any.
        The true threshold lies between this value and the next swept delta.
    """
    ds = events.isel(inv_beta=inv_beta_index).sortby("delta")
    hit = np.flatnonzero(np.asarray(ds["n_collisions"]) > 0)
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
        ``v_after_stderr``, ``interval_mean``, ``interval_stderr``, ``n_collisions``,
        ``n_batches``.

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked axes sharing delta; (b), the mean interval, on a log scale. Bars are
        +-t batch-means standard errors, t the Student quantile of B - 1 dof at
        `CONFIDENCE` (as `vibroimpact.stats.BatchMeans.interval`). Means resting on fewer
        than `FEW_IMPACTS` collisions are open squares without bars; deltas without impacts
        are open circles on the lower edge of each axes. A vertical line (gid
        ``"critical_delta"``) marks :func:`critical_delta` on both axes, and a shaded span
        reaches to the first impact-free delta, where the true threshold lies.
    """
    fig, axes = _figure(2)
    fig.set_figheight(FIG09_HEIGHT)
    ds = events.isel(inv_beta=0).sortby("delta")
    delta = np.asarray(ds["delta"], dtype=float)
    n = np.asarray(ds["n_collisions"])
    none, few = n == 0, (n > 0) & (n < FEW_IMPACTS)
    enough = n >= FEW_IMPACTS
    n_batches = np.asarray(_require(ds, "n_batches", "fig09's confidence bars"))
    t = t_quantile(n_batches, CONFIDENCE)
    batches = np.unique(n_batches[enough] if enough.any() else n_batches)
    t_text = (f"t = {_num(t_quantile(batches[0], CONFIDENCE))}, {int(batches[0])} batches"
              if batches.size == 1 else "t of B - 1 dof")
    bar_label = rf"mean $\pm$ t$\cdot$batch-means s.e. ({100 * CONFIDENCE:g} %, {t_text})"
    d_c = critical_delta(events)
    for ax, name, color in zip(axes, ("v_after", "interval"), ("C0", "C1")):
        mean = np.asarray(ds[f"{name}_mean"], dtype=float)
        err = t * np.asarray(ds[f"{name}_stderr"], dtype=float)
        ax.errorbar(delta[enough], mean[enough], yerr=err[enough], color=color, marker="o",
                    markersize=3.5)
        if few.any():
            ax.plot(delta[few], mean[few], ls="none", marker="s", mfc="white", color=color,
                    markersize=4.5)
        if none.any():
            # on the lower edge of the axes: "zero" on the linear axis, the floor of the log one
            ax.plot(delta[none], np.zeros(none.sum()), ls="none", marker="o", mfc="white",
                    color="0.45", markersize=4, clip_on=False, zorder=5,
                    transform=ax.get_xaxis_transform())
        if np.isfinite(d_c):
            line = ax.axvline(d_c, color="C3", ls="--", lw=1.1)
            line.set_gid("critical_delta")
            ax.axvspan(d_c, delta[delta > d_c][0], color="C3", alpha=0.12, lw=0)
        ax.set_ylabel(axis_label(ds[f"{name}_mean"]))
    axes[0].set_ylim(bottom=0.0)
    # the mean interval spans orders of magnitude (about 1 to 3.5e5 over the default sweep)
    axes[1].set_yscale("log")
    if np.isfinite(d_c):
        axes[0].annotate(rf"$\delta_c$ = {_num(d_c)}: no impact for $\delta > \delta_c$",
                         xy=(d_c, 0.12), xycoords=("data", "axes fraction"),
                         xytext=(-8, 0), textcoords="offset points", ha="right", va="center",
                         color="C3", fontsize=8.5,
                         bbox={"boxstyle": "round", "fc": "white", "ec": "none", "alpha": 0.8})
    # one legend for both panels, below them, so it never hides a point
    marks = [Line2D([], [], color="0.3", marker="o", markersize=3.5, label=bar_label)]
    if few.any():
        marks.append(Line2D([], [], ls="none", marker="s", mfc="white", color="0.3",
                            markersize=4.5, label=f"fewer than {FEW_IMPACTS} collisions (no bar)"))
    if none.any():
        marks.append(Line2D([], [], ls="none", marker="o", mfc="white", color="0.45",
                            markersize=4, label="no impact in the record"))
    fig.legend(handles=marks, loc="outside lower center", ncols=min(len(marks), 2))
    axes[1].set_xlabel(axis_label(ds["delta"]))
    _panel_tag(axes[0], "(a)")
    _panel_tag(axes[1], "(b)")
    _header(fig, "Fig. 9  Mean velocity after impact and mean interval between collisions",
            _events_params(events, 0))
    return fig
