"""Tests of vibroimpact.plotting on small synthetic datasets laid out as in docs/datasets.md.

The builders below (`make_noise`, `make_trace`, `make_events`, `make_spectra`) are the
schema of docs/datasets.md written as code: same dimensions, variables, coordinates and
attributes, with plausible shapes (densities that narrow as delta falls, a resonance peak that
moves with delta) so the rendered figures can also be inspected by eye. Assertions are exact
(counts of axes and lines, label strings, a marker position); no file bytes are compared.
"""
import os

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure

from vibroimpact import plotting
from vibroimpact.plotting import axis_label, critical_delta

PROVENANCE = {"package_version": "0.1.0", "git_commit": "0" * 40, "config_digest": "abc123",
              "seed": 20240101, "paper_reference": "Irie, Yamada, Matsuzaki (1974)"}
ZETA, EPS, RMS = 0.05, 0.5, 0.29
#: Swept deltas of the synthetic random study; impacts stop above CRITICAL.
DELTAS = np.round(np.arange(-0.5, 2.01, 0.25), 10)
CRITICAL = 1.5
#: Deliberately off-grid, to exercise the nearest-delta selection (-> 1.5, 0.5, 0.0, -0.5).
DENSITY_DELTA = [1.49, 0.52, 0.0, -0.5]
HARMONIC_INV_BETA = [0.8, 1.1, 1.4]


def _var(dims, values, long_name, units="1", **attrs):
    return (dims, np.asarray(values), {"long_name": long_name, "units": units, **attrs})


def _band_limited(rng, n, dt, rms, beta_c):
    """Gaussian samples with a flat two-sided PSD on |beta| < beta_c (FFT filter)."""
    spec = np.fft.rfft(rng.standard_normal(n))
    spec[2 * np.pi * np.fft.rfftfreq(n, dt) > beta_c] = 0.0
    r = np.fft.irfft(spec, n)
    return r * (rms / r.std())


def make_noise(n=2**14, dt=0.1, rms=0.5, beta_c=5.0, seed=1):
    """``results/noise/{noise}.nc``: samples, autocorrelation and PSD, estimate and target."""
    r = _band_limited(np.random.default_rng(seed), n, dt, rms, beta_c)
    lag = np.arange(0, 101) * dt
    full = np.fft.irfft(np.abs(np.fft.rfft(r, 2 * n)) ** 2)[: lag.size] / n
    nseg = 512
    window = np.hanning(nseg)
    segs = r[: n // nseg * nseg].reshape(-1, nseg) * window
    S_est = dt * np.mean(np.abs(np.fft.rfft(segs, axis=1)) ** 2, axis=0) / np.sum(window**2)
    beta = 2 * np.pi * np.fft.rfftfreq(nseg, dt)
    S_tgt = np.where(beta <= beta_c, np.pi * rms**2 / beta_c, 0.0)
    return xr.Dataset(
        {"r": _var("sample", r, "random force sample r_k", dt=dt, kind="band_limited",
                   rms=rms, beta_c=beta_c, zeta_f=0.0, seed=seed),
         "phi_estimate": _var("lag", full, "autocorrelation phi_f, estimated"),
         "phi_target": _var("lag", rms**2 * np.sinc(beta_c * lag / np.pi),
                            "autocorrelation phi_f, target"),
         "S_estimate": _var("beta", S_est, "power spectral density S_f, estimated"),
         "S_target": _var("beta", S_tgt, "power spectral density S_f, target")},
        coords={"lag": _var("lag", lag, "time lag tau*"),
                "beta": _var("beta", beta, "frequency ratio beta")},
        attrs={**PROVENANCE, "noise": "band5"})


def make_trace(amplitude=0.0, beta_f=1.0, delta=0.0, seed=2):
    """``results/traces/{study}.nc``: a short record starting at rest, impacts at a = 0."""
    dt = 0.05
    tau = np.arange(0, 1201) * dt
    r = np.interp(tau, tau[::2], _band_limited(np.random.default_rng(seed), 601, 0.1, RMS, 5))
    f = r + amplitude * np.sin(beta_f * tau)
    omega = 1.3
    a = 0.7 * (1 - np.exp(-tau / 8)) * np.abs(np.sin(omega * tau + 0.2 * np.sin(0.3 * tau)))
    crossing = np.flatnonzero(np.diff(np.sign(np.diff(a))) > 0) + 1   # local minima of a
    t_imp = tau[crossing][a[crossing] < 0.02]
    return xr.Dataset(
        {"r": _var("tau", r, "random force r"),
         "f": _var("tau", f, "total force f"),
         "a": _var("tau", a, "displacement from the wall a"),
         "x": _var("tau", delta - a, "displacement x"),
         "impact_time": _var("impact", t_imp, "time of impact"),
         "impact_velocity": _var("impact", np.full(t_imp.size, 0.4), "approach velocity u_-")},
        coords={"tau": _var("tau", tau, "dimensionless time tau")},
        attrs={**PROVENANCE, "delta": delta, "zeta": ZETA, "eps": EPS, "amplitude": amplitude,
               "beta_f": beta_f, "noise": "band5", "noise_rms": RMS})


def make_events(inv_beta=(1.0,), amplitude=0.0, deltas=DELTAS, critical=CRITICAL):
    """``results/datasets/{study}_events.nc``; no impact for delta > `critical`."""
    nb, nd = len(inv_beta), len(deltas)
    v = np.linspace(0.0, 2.0, 41)[:-1] + 0.025
    z = np.linspace(0.0, 20.0, 81)[:-1] + 0.125
    ratio = np.linspace(0.0, 3.0, 61)[:-1] + 0.025
    d = np.asarray(deltas, dtype=float)[None, :, None]
    active = (np.asarray(deltas) <= critical)[None, :]
    n = np.where(active, np.round(4000 * np.exp(-0.6 * np.asarray(deltas))), 0).astype(int)
    n = np.broadcast_to(n, (nb, nd)).copy()
    hit = active[..., None]
    scale = 0.1 + 0.25 * (d + 0.6)                                      # velocities grow with delta
    v_pdf = np.where(hit, v / scale**2 * np.exp(-v**2 / (2 * scale**2)), np.nan)
    shape, mean_z = 3.0, 2.0 + 3.0 * (d + 0.6)                          # so do the intervals
    z_pdf = np.where(hit, z ** (shape - 1) * np.exp(-shape * z / mean_z), np.nan)
    z_pdf /= np.nansum(z_pdf, axis=-1, keepdims=True) * 0.25
    w = np.clip((d + 0.5) / 2.0, 0, 1)                                  # 1/1 at large delta
    g = lambda c, s: np.exp(-0.5 * ((ratio - c) / s) ** 2) / (s * np.sqrt(2 * np.pi))
    r_pdf = w * g(1.0, 0.08) + (1 - w) * 0.5 * (g(0.35, 0.06) + g(0.65, 0.06))
    r_pdf = np.broadcast_to(np.where(hit, r_pdf, np.nan), (nb, nd, ratio.size))
    nan_if_none = lambda x: np.where(n > 0, x, np.nan)
    v_mean = nan_if_none(np.broadcast_to(scale[..., 0] * np.sqrt(np.pi / 2), (nb, nd)))
    z_mean = nan_if_none(np.broadcast_to(mean_z[..., 0], (nb, nd)))
    sqrt_n = np.sqrt(np.maximum(n, 1))
    T = np.full((nb, nd), 2.0e4)
    dims2, dims3 = ("inv_beta", "delta"), ("inv_beta", "delta")
    prob = np.broadcast_to(np.stack([w[..., 0], 0.5 * (1 - w[..., 0]), 0.05 + 0 * w[..., 0]],
                                    axis=-1), (nb, nd, 3))
    return xr.Dataset(
        {"n_impacts": _var(dims2, n, "number of impacts"),
         "impact_rate": _var(dims2, n / T, "impacts per unit time"),
         "simulated_time": _var(dims2, T, "record length after the transient"),
         "v_after_mean": _var(dims2, v_mean, "mean velocity after impact"),
         "v_after_stderr": _var(dims2, 3 * v_mean / sqrt_n, "standard error of the mean velocity"),
         "interval_mean": _var(dims2, z_mean, "mean interval between impacts"),
         "interval_stderr": _var(dims2, 3 * z_mean / sqrt_n, "standard error of the mean interval"),
         "v_after_density": _var((*dims3, "v_after"), np.broadcast_to(v_pdf, (nb, nd, v.size)),
                                 "probability density of the velocity after impact"),
         "v_after_density_stderr": _var((*dims3, "v_after"),
                                        np.broadcast_to(v_pdf, (nb, nd, v.size)) * 0.05,
                                        "standard error of the velocity density"),
         "interval_density": _var((*dims3, "interval"), np.broadcast_to(z_pdf, (nb, nd, z.size)),
                                  "probability density of the interval between impacts"),
         "interval_density_stderr": _var((*dims3, "interval"),
                                         np.broadcast_to(z_pdf, (nb, nd, z.size)) * 0.05,
                                         "standard error of the interval density"),
         "ratio_density": _var((*dims3, "ratio"), r_pdf, "probability density of z_j/z"),
         "motion_probability": _var((*dims3, "motion"), prob, "fraction of time in the motion"),
         "contact_fraction": _var(dims2, np.zeros((nb, nd)), "fraction of time on the wall"),
         "n_chatter": _var(dims2, np.zeros((nb, nd), dtype=int), "chatter sequences")},
        coords={"inv_beta": _var("inv_beta", np.asarray(inv_beta, float), "1/beta_f"),
                "delta": _var("delta", np.asarray(deltas, float), "play delta"),
                "v_after": _var("v_after", v, "velocity after impact"),
                "interval": _var("interval", z, "interval between impacts z_j"),
                "ratio": _var("ratio", ratio, "interval over forcing period z_j/z"),
                "motion": _var("motion", np.array(["1/1", "2/1", "1/2"]), "impact motion")},
        attrs={**PROVENANCE, "zeta": ZETA, "eps": EPS, "amplitude": amplitude,
               "noise": "band5", "noise_rms": RMS,
               "motion_window": 0.1})


def make_spectra(inv_beta=(1.0,), amplitude=0.0, deltas=(2.0, 1.0, 0.5, 0.0, -0.5), seed=3):
    """``results/datasets/{study}_spectra.nc``: S_a per delta, S_f and the linear S_lin."""
    rng = np.random.default_rng(seed)
    beta = np.linspace(0.0, 2 * np.pi / 0.1 / 2, 801)
    nb, nd = len(inv_beta), len(deltas)
    S_r = np.where(beta <= 5.0, np.pi * RMS**2 / 5.0, 1e-6)
    H2 = 1.0 / ((1 - beta**2) ** 2 + (2 * ZETA * beta) ** 2)
    S_lin = np.broadcast_to(H2 * S_r, (nb, beta.size))
    spike = np.exp(-0.5 * ((beta[None] - 1 / np.asarray(inv_beta)[:, None]) / 0.03) ** 2)
    S_f = S_r[None] * rng.gamma(20, 1 / 20, (nb, beta.size)) + amplitude * 40 * spike
    S_a = np.empty((nb, nd, beta.size))
    for j, d in enumerate(deltas):
        peak = 1.0 + 0.6 * max(0.0, 1.2 - d)        # rises and flattens as delta falls
        damp = ZETA + 0.15 * max(0.0, 1.2 - d)
        shape = 1.0 / ((peak**2 - beta**2) ** 2 + (2 * damp * beta * peak) ** 2)
        S_a[:, j] = shape * S_r * rng.gamma(20, 1 / 20, (nb, beta.size)) + amplitude * spike
    return xr.Dataset(
        {"S_a": _var(("inv_beta", "delta", "beta"), S_a, "power spectral density of a"),
         "S_f": _var(("inv_beta", "beta"), S_f, "power spectral density of the input f"),
         "S_lin": _var(("inv_beta", "beta"), S_lin, "linear reference |H|^2 S_f"),
         "n_segments": _var(("inv_beta", "delta"), np.full((nb, nd), 400), "Welch segments")},
        coords={"inv_beta": _var("inv_beta", np.asarray(inv_beta, float), "1/beta_f"),
                "delta": _var("delta", np.asarray(deltas, float), "play delta"),
                "beta": _var("beta", beta, "frequency ratio beta")},
        attrs={**PROVENANCE, "zeta": ZETA, "eps": EPS, "amplitude": amplitude,
               "noise": "band5", "noise_rms": RMS})


@pytest.fixture(scope="module")
def data():
    return {"noise": make_noise(), "trace": make_trace(),
            "trace_h": make_trace(amplitude=1.0, beta_f=1.1),
            "events": make_events(), "spectra": make_spectra(),
            "events_h": make_events(HARMONIC_INV_BETA, amplitude=1.0),
            "spectra_h": make_spectra(HARMONIC_INV_BETA, amplitude=1.0)}


def _data_lines(ax):
    """Lines that carry data (axvline/axhline reference lines excluded)."""
    return [ln for ln in ax.get_lines() if not _is_reference(ln)]


def _is_reference(line):
    """axvline/axhline: drawn in blended data/axes coordinates."""
    return line.get_transform() is not line.axes.transData


def _vlines_at(ax):
    return sorted(float(ln.get_xdata()[0]) for ln in ax.get_lines()
                  if _is_reference(ln) and np.ptp(np.asarray(ln.get_xdata(), float)) == 0)


def _legend_texts(ax):
    return [t.get_text() for t in ax.get_legend().get_texts()]


# ------------------------------------------------------------------------- each figure

def test_fig03_input_and_motion_with_impacts(data):
    trace = data["trace"]
    fig = plotting.fig03(trace)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    ax_r, ax_a = fig.axes
    assert ax_r.get_ylabel() == axis_label(trace["r"]) == "random force r"
    assert ax_a.get_ylabel() == "displacement from the wall a"
    assert ax_a.get_xlabel() == "dimensionless time tau"
    marks = [ln for ln in ax_a.get_lines() if ln.get_marker() == "v"]
    assert len(marks) == 1 and len(marks[0].get_xdata()) == trace.sizes["impact"] > 3
    np.testing.assert_array_equal(marks[0].get_ydata(), 0.0)    # impacts sit on the wall a = 0


def test_fig04_fig05_noise_estimate_against_target(data):
    noise = data["noise"]
    fig4, fig5 = plotting.fig04(noise), plotting.fig05(noise)
    for fig, var in ((fig4, "phi_estimate"), (fig5, "S_estimate")):
        (ax,) = fig.axes
        assert len(_data_lines(ax)) == 2                          # estimate and target
        assert ax.get_ylabel().startswith(noise[var].attrs["long_name"])
    assert fig4.axes[0].get_xlabel() == "time lag tau*"
    assert "two-sided, angular" in fig5.axes[0].get_ylabel()
    assert min(fig5.axes[0].get_lines()[0].get_xdata()) >= 0.0
    assert "rms = 0.5" in fig5._suptitle.get_text()              # the spectrum is stated


def test_fig06_one_curve_per_delta_and_linear_reference(data):
    spectra = data["spectra"]
    (ax,) = plotting.fig06(spectra).axes
    assert ax.get_yscale() == "log"
    assert len(_data_lines(ax)) == spectra.sizes["delta"] + 1
    assert any("|H|^2" in t for t in _legend_texts(ax))
    assert ax.get_xlabel() == "frequency ratio beta"


@pytest.mark.parametrize("name, var", [("fig07", "v_after_density"),
                                       ("fig08", "interval_density")])
def test_density_figures_draw_the_nearest_density_deltas(data, name, var):
    events = data["events"]
    (ax,) = getattr(plotting, name)(events, density_delta=DENSITY_DELTA).axes
    assert len(_data_lines(ax)) == len(DENSITY_DELTA)
    shown = [t.split("=")[1].split()[0] for t in _legend_texts(ax)]
    assert shown == ["1.5", "0.5", "0", "-0.5"]                  # nearest, largest first
    assert ax.get_ylabel() == events[var].attrs["long_name"]
    assert ax.get_xlabel() == events[events[var].dims[-1]].attrs["long_name"]


def test_density_delta_without_impacts_keeps_its_line(data):
    events = data["events"]
    (ax,) = plotting.fig07(events, density_delta=[2.0, 0.0]).axes   # 2.0 > CRITICAL: no impacts
    assert len(_data_lines(ax)) == 2
    assert "no impacts" in _legend_texts(ax)[0]


def test_fig09_marks_the_critical_delta(data):
    events = data["events"]
    assert critical_delta(events) == CRITICAL
    fig = plotting.fig09(events)
    assert len(fig.axes) == 2
    for ax in fig.axes:
        marks = [ln for ln in ax.get_lines() if ln.get_gid() == "critical_delta"]
        assert len(marks) == 1
        np.testing.assert_array_equal(marks[0].get_xdata(), CRITICAL)
    assert fig.axes[0].get_ylabel() == "mean velocity after impact"
    assert fig.axes[1].get_ylabel() == "mean interval between impacts"
    assert fig.axes[1].get_xlabel() == "play delta"
    assert any("1.5" in t.get_text() for t in fig.axes[0].texts)  # annotated


def test_critical_delta_undefined_when_the_sweep_never_stops_impacting():
    assert np.isnan(critical_delta(make_events(critical=10.0)))
    assert np.isnan(critical_delta(make_events(critical=-10.0)))
    fig = plotting.fig09(make_events(critical=10.0))
    assert not [ln for ax in fig.axes for ln in ax.get_lines() if ln.get_gid()]


def test_fig10_harmonic_input_and_motion(data):
    trace = data["trace_h"]
    fig = plotting.fig10(trace)
    assert len(fig.axes) == 2
    assert fig.axes[0].get_ylabel() == "total force f"
    assert r"\sin(1.1\,\tau)" in fig._suptitle.get_text()


def test_fig11_fig12_select_the_nearest_forcing_frequency(data):
    spectra = data["spectra_h"]
    fig11 = plotting.fig11(spectra, inv_beta=1.08)
    fig12 = plotting.fig12(spectra, inv_beta=1.08)
    for fig in (fig11, fig12):
        assert r"\sin(\tau/1.1)" in fig._suptitle.get_text()
        assert _vlines_at(fig.axes[0]) == [pytest.approx(1 / 1.1)]
    assert len(_data_lines(fig11.axes[0])) == 1
    assert len(_data_lines(fig12.axes[0])) == spectra.sizes["delta"] + 1


def test_fig13_ratio_density_with_motion_marks(data):
    events = data["events_h"]
    (ax,) = plotting.fig13(events, inv_beta=1.1, density_delta=DENSITY_DELTA).axes
    assert len(_data_lines(ax)) == len(DENSITY_DELTA)
    assert _vlines_at(ax) == [0.5, 1.0, 2.0]
    chain = [ln for ln in ax.get_lines() if ln.get_linestyle() == "-."]
    assert len(chain) == 1 and chain[0].get_xdata()[0] == 0.5
    assert ax.get_ylabel() == "probability density of z_j/z"


def test_fig14_velocity_density_at_one_forcing_frequency(data):
    (ax,) = plotting.fig14(data["events_h"], inv_beta=1.4, density_delta=DENSITY_DELTA).axes
    assert len(_data_lines(ax)) == len(DENSITY_DELTA)
    assert r"\sin(\tau/1.4)" in ax.figure._suptitle.get_text()


# ------------------------------------------------------------------------- shared contract

def test_every_figure_states_its_parameters(data):
    figs = [plotting.fig03(data["trace"]), plotting.fig06(data["spectra"]),
            plotting.fig07(data["events"]), plotting.fig09(data["events"]),
            plotting.fig13(data["events_h"], 1.1)]
    for fig in figs:
        text = fig._suptitle.get_text()
        assert r"$\zeta$ = 0.05" in text and r"$\varepsilon$ = 0.5" in text
        assert "rms$_r$ = 0.29" in text
    assert r"$\delta$ = 0" in figs[0]._suptitle.get_text()


def test_units_other_than_dimensionless_appear_in_labels(data):
    events = data["events"].copy()
    events["v_after_mean"] = events["v_after_mean"].assign_attrs(units="m/s")
    assert plotting.fig09(events).axes[0].get_ylabel() == "mean velocity after impact [m/s]"


def test_missing_parameter_attribute_is_named(data):
    events = data["events"].copy()
    del events.attrs["zeta"]
    with pytest.raises(KeyError, match="'zeta'"):
        plotting.fig07(events)


def test_netcdf_round_trip_is_plottable(data, tmp_path):
    # a dataset read back from netCDF draws the same figure as the one written
    data["events"].to_netcdf(tmp_path / "events.nc")
    with xr.open_dataset(tmp_path / "events.nc") as ds:
        assert len(_data_lines(plotting.fig07(ds, density_delta=[0.5]).axes[0])) == 1


def test_style_is_scoped_to_the_figure_functions(data):
    import matplotlib
    before = dict(matplotlib.rcParams)
    fig = plotting.fig06(data["spectra"])
    assert tuple(fig.get_size_inches()) == (6.5, 4.5)
    assert dict(matplotlib.rcParams) == before


def test_save_writes_png_and_pdf_atomically(data, tmp_path):
    fig = plotting.fig04(data["noise"])
    png, pdf = plotting.save(fig, tmp_path / "figs" / "fig04.png")
    assert sorted(os.listdir(tmp_path / "figs")) == ["fig04.pdf", "fig04.png"]
    assert png.stat().st_size > 0 and pdf.stat().st_size > 0
    with pytest.raises(ValueError, match="path_png"):
        plotting.save(fig, tmp_path / "fig04.svg")
