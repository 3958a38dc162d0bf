"""Tests of vibroimpact.plotting on datasets made by the workflow's own writers.

The module fixture runs the pipeline's tasks on short records: a noise file
(`pipeline.io.write_noise`), the events, spectra and traces of a random and a harmonic study
(simulated cell by cell by `pipeline.cells`, stored by `pipeline.datasets`), and an orbit map on
a small grid (`orbits.orbit_map`, `datasets.orbit_map_dataset`). No dataset is written by hand,
so a figure that reads a name or attribute the writers do not produce fails here. Assertions are
about what a figure shows (lines, labels, bands, markers) against the datasets' values.
"""
import os

import numpy as np
import pytest
import xarray as xr
from matplotlib.colors import same_color
from matplotlib.figure import Figure

from helpers import assert_figure
from vibroimpact import plotting, stats
from vibroimpact.orbits import orbit_map, periodic_orbits
from vibroimpact.pipeline import datasets, tasks
from vibroimpact.plotting import axis_label, critical_delta
from vibroimpact.plotting.orbits import S_LEVELS, TYPE_COLORS, complex_multipliers
from vibroimpact.stats.events import poisson_interval, t_quantile

NOISE = dict(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0, n_samples=60_001,
             seed=19740914, nperseg=1024)
BINS = dict(v_after=dict(max=2.5, n=50), interval=dict(max=10.0, n=50), ratio=dict(max=4.0, n=80))
COMMON = dict(noise="band", zeta=0.05, eps=0.5, transient=100.0, tile_size=100, n_batches=20,
              motion_window=0.1, motions=[[1, 1], [2, 1], [1, 2]], bins=BINS,
              spectra=dict(delta=[3.0, 1.0, 0.0, -0.5], nperseg=512, t_end=6000.0))
#: Random study: impacts stop between 3 and 4.5 on this record; 3 has only a handful.
RANDOM = dict(COMMON, amplitude=0.0, delta=[-1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 3.0, 4.5, 6.0],
              trace=dict(delta=0.0, t_end=60.0))
HARMONIC_INV_BETA = [0.8, 1.1, 1.4]
HARMONIC = dict(COMMON, amplitude=1.0, inv_beta=HARMONIC_INV_BETA,
                delta=[-0.5, 0.0, 0.5, 1.0, 2.0],
                trace=dict(delta=0.0, t_end=60.0, inv_beta=1 / 1.1))
#: Deliberately off-grid, to exercise the nearest-delta selection (-> 2, 0.5, 0, -0.5).
DENSITY_DELTA = [1.9, 0.52, 0.0, -0.5]
ORBIT_TYPES = [(1, 1), (2, 1), (1, 2), (1, 3), (3, 1)]


def _study(tmp, name, block, noise_path):
    """Events, spectra and trace datasets of one study, through the workflow's tasks."""
    out = {}
    for kind, make in (("events", tasks.events_tile), ("spectra", tasks.spectra_tile)):
        tile = tmp / f"{name}_{kind}_tile.nc"
        make(name, block, 0, noise_path, tile)
        path = tmp / f"{name}_{kind}.nc"
        tasks.aggregate(name, block, kind, [tile], path, noise_path=noise_path)
        out[kind] = xr.load_dataset(path)
    tasks.trace(name, block, noise_path, tmp / f"{name}_trace.nc")
    out["trace"] = xr.load_dataset(tmp / f"{name}_trace.nc")
    return out


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("plotting")
    noise_path = tmp / "band.nc"
    tasks.make_noise(NOISE, noise_path)
    random, harmonic = _study(tmp, "random", RANDOM, noise_path), _study(tmp, "h", HARMONIC,
                                                                          noise_path)
    inv_beta = np.round(np.arange(0.6, 1.61, 0.1), 10)
    deltas = np.round(np.arange(-0.5, 2.51, 0.25), 10)
    orbits = datasets.orbit_map_dataset(
        orbit_map(inv_beta, deltas, types=ORBIT_TYPES, zeta=0.05, eps=0.5),
        dict(zeta=0.05, eps=0.5, amplitude=1.0))
    return {"noise": xr.load_dataset(noise_path), "trace": random["trace"],
            "events": random["events"], "spectra": random["spectra"],
            "trace_h": harmonic["trace"], "events_h": harmonic["events"],
            "spectra_h": harmonic["spectra"], "orbits": orbits}


def _data_lines(ax):
    """Lines that carry data (axvline/axhline reference lines excluded)."""
    return [ln for ln in ax.get_lines() if not _is_reference(ln)]


def _is_reference(line):
    """axvline/axhline: drawn in blended data/axes coordinates."""
    return line.get_transform() is not line.axes.transData


def _vlines_at(ax):
    return sorted(float(ln.get_xdata()[0]) for ln in ax.get_lines()
                  if _is_reference(ln) and np.ptp(np.asarray(ln.get_xdata(), float)) == 0)


def _legend(ax):
    """The legend of `ax`, or of its figure when the figure holds it (below the axes)."""
    return ax.get_legend() or ax.figure.legends[0]


def _legend_texts(ax):
    return [t.get_text() for t in _legend(ax).get_texts()]


def _title(fig):
    return fig.get_suptitle()


# ------------------------------------------------------------------------- each figure

def test_fig03_input_and_motion_with_impacts(data):
    trace = data["trace"]
    fig = plotting.fig03(trace)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    ax_r, ax_a = fig.axes
    assert ax_r.get_ylabel() == axis_label(trace["r"])
    assert ax_a.get_ylabel() == axis_label(trace["a"])
    assert ax_a.get_xlabel() == axis_label(trace["tau"])
    marks = [ln for ln in ax_a.get_lines() if ln.get_marker() == "v"]
    rebounds = [ln for ln in ax_a.get_lines() if ln.get_marker() == "|"]
    n_collisions = np.unique(trace["impact_collision"].values).size
    assert len(marks) == 1 and len(marks[0].get_xdata()) == n_collisions > 3
    # the chatter rebounds are told apart from the collisions that start them
    assert len(marks[0].get_xdata()) + len(rebounds[0].get_xdata()) == trace.sizes["impact"]
    np.testing.assert_array_equal(marks[0].get_ydata(), 0.0)    # impacts sit on the wall a = 0
    assert any(t.startswith("collision: first impact") for t in _legend_texts(ax_a))


def test_fig04_fig05_describe_the_noise_from_its_file(data):
    noise = data["noise"]
    fig4, fig5 = plotting.fig04(noise), plotting.fig05(noise)
    for fig in (fig4, fig5):
        text = _title(fig)
        for part in ("band-limited white noise", "rms = 0.5", r"$\Delta\tau$ = 0.1",
                     r"$\beta_c$ = 4", "seed 19740914", "60,001 samples"):
            assert part in text, (part, text)
    (ax4,) = fig4.axes
    assert len(_data_lines(ax4)) == 2                              # estimate and target
    assert ax4.get_ylabel() == axis_label(noise["phi_estimate"])
    assert ax4.get_xlabel() == axis_label(noise["lag"])
    assert "target of the sample sequence" in _legend_texts(ax4)[1]


def test_fig05_tells_the_sample_target_from_the_piecewise_linear_force(data):
    # For dt = 0.1, beta_c = 4 the piecewise-linear force's PSD is sinc^4(beta dt/2) = 0.974
    # times the target at the cut-off: a 2.6 % difference, above VISIBLE_DIFFERENCE, so
    # it is its own line, labelled as such.
    noise = data["noise"]
    (ax,) = plotting.fig05(noise).axes
    lines = _data_lines(ax)
    labels = _legend_texts(ax)
    assert len(lines) == 3
    assert "target of the sample sequence" in labels[1] and "piecewise-linear" in labels[2]
    np.testing.assert_array_equal(lines[2].get_ydata(), noise["S_target_linear"].values)
    assert lines[1].get_linestyle() != lines[2].get_linestyle()
    assert "two-sided, angular" in ax.get_ylabel()
    assert min(lines[0].get_xdata()) >= 0.0
    assert "rms$^2$ = 0.25" in ax.get_legend().get_title().get_text()


def test_fig06_one_curve_per_delta_and_linear_reference(data):
    spectra = data["spectra"]
    (ax,) = plotting.fig06(spectra).axes
    assert ax.get_yscale() == "log"
    assert len(_data_lines(ax)) == spectra.sizes["delta"] + 1
    assert any("|H|^2" in t for t in _legend_texts(ax))
    assert ax.get_xlabel() == axis_label(spectra["beta"])


@pytest.mark.parametrize("name, var", [("fig07", "v_after"), ("fig08", "interval")])
def test_density_figures_label_impacts_beyond_axis_and_batch_band(data, name, var):
    events = data["events"].isel(inv_beta=0)
    ax = getattr(plotting, name)(data["events"], density_delta=DENSITY_DELTA).axes[0]
    lines = _data_lines(ax)
    labels = _legend_texts(ax)
    assert len(lines) == len(DENSITY_DELTA)
    t = t_quantile(20)
    for _line, label, d in zip(lines, labels, [2.0, 0.5, 0.0, -0.5]):   # nearest, largest first
        cell = events.sel(delta=d)
        assert label.split("=")[1].split()[0] == f"{d:g}"
        assert f"({int(cell['n_collisions']):,} collisions" in label
        beyond = float(cell[f"{var}_beyond"])
        assert (f"{100 * beyond:.3g} % beyond axis" in label) == (beyond > 1e-3), label
    if var == "interval":   # intervals at the largest play overrun the 10-unit axis
        assert "beyond axis" in labels[0]
    # band = +-t batch-means s.e., t of B - 1 = 19 dof, joined with Garwood's interval
    assert "batch-means" in _legend(ax).get_title().get_text()
    assert "Garwood" in _legend(ax).get_title().get_text()
    assert f"t = {t:.4g}" in _legend(ax).get_title().get_text()
    # the band of a bin drawn on its own (>= MIN_BIN_COUNT values): the wider of density +-
    # t s.e. and Garwood's 95 % interval of its count c, G(c) / (n w)
    cell = events.sel(delta=0.0)
    y = np.asarray(cell[f"{var}_density"])
    se = np.asarray(cell[f"{var}_density_stderr"])
    _, counts, n = plotting.bin_counts(cell, f"{var}_density")
    width = float(events[var][1] - events[var][0])
    alone = counts >= plotting.MIN_BIN_COUNT
    g_hi = poisson_interval(counts[alone].astype(float))[1] / (n * width)
    bands = [c for c in ax.collections if c.get_gid() == "band"]
    assert len(bands) == len(lines)
    band = bands[2].get_paths()[0].vertices[:, 1]                        # delta = 0: third curve
    assert np.nanmax(band) == pytest.approx(np.max(np.fmax((y + t * se)[alone], g_hi)),
                                            rel=1e-12)
    assert np.max(g_hi) > 0 and np.all(g_hi > y[alone])
    assert ax.get_ylabel() == axis_label(events[f"{var}_density"])
    assert ax.figure.axes[-1].get_xlabel() == axis_label(events[var])


def test_fig08_panel_a_shows_every_drawn_interval_and_b_the_bulk(data):
    """Issue 33: the axis ended at 20 and hid the long waits of the smallest plays."""
    fig = plotting.fig08(data["events"], density_delta=DENSITY_DELTA, zoom=4.0)
    ax_all, ax_bulk = fig.axes
    assert ax_all.get_yscale() == ax_bulk.get_yscale() == "log"
    last = max(np.nanmax(ln.get_xdata()) for ln in _data_lines(ax_all))
    assert ax_all.get_xlim()[1] >= last            # no drawn point beyond the axis
    assert last > 4.0                              # the fixture's tails reach past the zoom
    assert ax_bulk.get_xlim()[1] == pytest.approx(4.0)
    # the same curves in both panels
    for a, b in zip(_data_lines(ax_all), _data_lines(ax_bulk)):
        np.testing.assert_array_equal(a.get_xdata(), b.get_xdata())


def _overlaps_data(fig, ax):
    """Whether a figure legend's box covers any drawn data point of `ax` (display space)."""
    fig.canvas.draw()
    box = (fig.legends[0] if fig.legends else ax.get_legend()).get_window_extent()
    for line in _data_lines(ax):
        xy = ax.transData.transform(np.column_stack([line.get_xdata(), line.get_ydata()]))
        xy = xy[np.isfinite(xy).all(axis=1)]
        inside = ((xy[:, 0] > box.x0) & (xy[:, 0] < box.x1)
                  & (xy[:, 1] > box.y0) & (xy[:, 1] < box.y1))
        if inside.any():
            return True
    return False


def test_fig12_legend_covers_no_spectrum(data):
    """Issue 33: the legend hid the delta = 2 peak and the tops of the harmonics' lines."""
    fig = plotting.fig12(data["spectra_h"], inv_beta=1.1)
    assert not _overlaps_data(fig, fig.axes[0])


def test_fig13_pair_label_points_off_its_axis(data):
    """The (2/1) intervals lie in pairs on both sides of z_j/z = 1/2, none on it: the label
    is centred on the line and points both ways, not written as if a peak stood there."""
    fig = plotting.fig13(data["events_h"], inv_beta=1.1, density_delta=DENSITY_DELTA)
    for ax in fig.axes:
        (label,) = [t for t in ax.texts if "(2/1)" in t.get_text()]
        assert label.get_position()[0] == 0.5 and label.get_horizontalalignment() == "center"
        assert "leftarrow" in label.get_text() and "rightarrow" in label.get_text()


def test_headers_define_only_the_collision_quantities_drawn(data):
    """Issue 33: the header of Figs. 7-9, 13, 14 defined z_j on figures that do not draw it."""
    v_def, z_def = (plotting.COLLISION_QUANTITIES[k] for k in ("v_after", "interval"))
    events, harmonic = data["events"], data["events_h"]
    for fig, drawn in ((plotting.fig07(events, density_delta=DENSITY_DELTA), v_def),
                       (plotting.fig08(events, density_delta=DENSITY_DELTA), z_def),
                       (plotting.fig13(harmonic, inv_beta=1.1), z_def),
                       (plotting.fig14(harmonic, inv_beta=1.1), v_def)):
        title = _title(fig)
        assert drawn in title and ({v_def, z_def} - {drawn}).pop() not in title, title
        assert "per collision" in title
    title = _title(plotting.fig09(events))
    assert v_def in title and z_def in title


@pytest.mark.parametrize("plain, shown", [
    ("forcing phase in [0, 2 pi), x0 = delta - g with g in [0, 4], v0 in [-4, 4]",
     r"forcing phase in [0, $2\pi$), $x_0$ = $\delta$ - g with g in [0, 4], $v_0$ in [-4, 4]"),
    ("|mu-mu_ind|/max(1,|mu_ind|) over tol(d)",
     r"|$\mu$-$\mu_{\rm ind}$|/max(1,|$\mu_{\rm ind}$|) over tol(d)"),
    ("contact edges, a(tau) and x' at samples", r"contact edges, $a(\tau)$ and $x'$ at samples"),
    (r"$\delta$ = 2, a delta; epsilon, mu", r"$\delta$ = 2, a $\delta$; epsilon, $\mu$"),
    ("max(replay |dx|,|du|; -min a)", "max(replay |dx|,|du|; -min a)"),
])
def test_symbols_write_plain_names_as_the_papers_symbols(plain, shown):
    """Only whole names outside mathtext change, each once (2 pi is not 2 then pi)."""
    assert plotting.symbols(plain) == shown


def test_density_delta_without_impacts_keeps_its_line(data):
    ax = plotting.fig07(data["events"], density_delta=[6.0, 0.0]).axes[0]
    assert len(_data_lines(ax)) == 2
    assert "no collision" in _legend_texts(ax)[0]


def test_fig09_bars_scale_and_markers(data):
    events = data["events"]
    ds = events.isel(inv_beta=0)
    n = ds["n_collisions"].values
    few = (n > 0) & (n < plotting.random.FEW_IMPACTS)
    enough = n >= plotting.random.FEW_IMPACTS
    assert few.any() and (n == 0).any(), "the fixture must hold a few-impact and an empty cell"
    d_c = critical_delta(events)
    assert d_c == ds["delta"].values[n > 0].max()
    fig = plotting.fig09(events)
    ax_v, ax_z = fig.axes
    assert ax_v.get_yscale() == "linear" and ax_z.get_yscale() == "log"
    for ax, name in ((ax_v, "v_after"), (ax_z, "interval")):
        # the plays without a collision in the record: shaded from d_c on, not a threshold line
        spans = [p for p in ax.patches if p.get_gid() == "no_collision"]
        assert len(spans) == 1
        assert spans[0].get_x() == pytest.approx(d_c)
        # bars: the stored 95 % interval ends (asymmetric for T/N), exactly
        lo, hi = ds[f"{name}_mean_lo"].values, ds[f"{name}_mean_hi"].values
        segments = ax.containers[0].lines[2][0].get_segments()
        drawn = enough & np.isfinite(lo)
        np.testing.assert_allclose([s[0, 1] for s in segments], lo[drawn], rtol=1e-12)
        np.testing.assert_allclose([s[1, 1] for s in segments], hi[drawn], rtol=1e-12)
        squares = [ln for ln in ax.get_lines() if ln.get_marker() == "s"]
        assert len(squares) == 1
        # (b) T/N rests on the count: from one collision on; (a) a mean needs an interval
        shown = few & np.isfinite(lo) & (n >= (2 if name == "v_after" else 1))
        np.testing.assert_array_equal(squares[0].get_xdata(), ds["delta"].values[shown])
        assert squares[0].get_markerfacecolor() == "white"
    # T/N is the record length over the count, and its interval holds it
    z = ds["interval_mean"].values[n > 0]
    np.testing.assert_allclose(z, ds["simulated_time"].values[n > 0] / n[n > 0], rtol=1e-12)
    assert np.all((ds["interval_mean_lo"].values[n > 0] < z)
                  & (z < ds["interval_mean_hi"].values[n > 0]))
    labels = [t.get_text() for t in fig.legends[0].get_texts()]     # one legend, both panels
    assert any("fewer than 20 collisions" in s for s in labels)
    assert any(f"no collision in this record for $\\delta$ > {d_c:g}" in s for s in labels)
    assert any("95 % intervals" in s and "Garwood" in s for s in labels)
    assert ax_v.get_ylabel() == axis_label(ds["v_after_mean"])
    assert ax_z.get_ylabel() == axis_label(ds["interval_mean"])
    assert ax_z.get_xlabel() == axis_label(ds["delta"])


def test_fig09_names_the_plays_held_on_the_wall_that_it_cannot_draw(data):
    """A play too deep for the force to lift the mass (no collision, below every play with
    one) has nothing to draw; the legend names it rather than the axis dropping it."""
    events = data["events"].copy(deep=True)
    lowest = float(events["delta"].min())
    cell = dict(delta=lowest)
    events["n_collisions"].loc[cell] = 0
    for name in ("v_after_mean", "v_after_mean_lo", "v_after_mean_hi", "interval_mean",
                 "interval_mean_lo", "interval_mean_hi"):
        events[name].loc[cell] = np.nan
    events["contact_fraction"].loc[cell] = 1.0
    labels = [t.get_text() for t in plotting.fig09(events).legends[0].get_texts()]
    held = [s for s in labels if s.startswith("not drawn: no collision")]
    assert len(held) == 1 and f"= {lowest:g} (held on the wall" in held[0]
    assert "at least 100 % of the record" in held[0]
    untouched = [t.get_text() for t in plotting.fig09(data["events"]).legends[0].get_texts()]
    assert not any(s.startswith("not drawn") for s in untouched)


def test_fig09_draws_rice_asymptotes_of_the_wall_free_response(data):
    """Rice's rate checked against its closed form at one point, independent of the code:
    sigma_x = sigma_v = sqrt(S0 / 4 zeta) for white noise of two-sided level S0."""
    # the aggregation stores the wall-free std's for the random force alone, not with a sine
    assert data["events"].attrs["linear_sigma_x"] > 0
    assert data["events"].attrs["linear_sigma_v"] > 0
    assert "linear_sigma_x" not in data["events_h"].attrs
    events = data["events"].copy()
    zeta, s0 = 0.05, 0.02
    sigma = np.sqrt(s0 / (4 * zeta))
    events.attrs.update(linear_sigma_x=sigma, linear_sigma_v=sigma)
    fig = plotting.fig09(events)
    ax_v, ax_z = fig.axes
    (v_line,) = [ln for ln in ax_v.get_lines() if ln.get_gid() == "rice"]
    (z_line,) = [ln for ln in ax_z.get_lines() if ln.get_gid() == "rice"]
    eps = float(events.attrs["eps"])
    np.testing.assert_allclose(v_line.get_ydata(), eps * sigma * np.sqrt(np.pi / 2), rtol=1e-12)
    d, z = (np.asarray(v, dtype=float) for v in z_line.get_data())
    # mean interval between up-crossings of d: 2 pi exp(d^2 / 2 sigma^2) (sigma_v = sigma_x)
    np.testing.assert_allclose(z, 2 * np.pi * np.exp(d**2 / (2 * sigma**2)), rtol=1e-12)
    assert d.min() == pytest.approx(plotting.random.RICE_FROM_SIGMA * sigma)
    events.attrs.pop("linear_sigma_x")
    assert not [ln for ax in plotting.fig09(events).axes for ln in ax.get_lines()
                if ln.get_gid() == "rice"]



def _envelope_lines(fig):
    return [[ln for ln in ax.get_lines() if ln.get_gid() == "envelope"] for ax in fig.axes]


def test_fig09_envelope_theory_only_where_it_applies_unless_asked(data):
    """The energy-envelope curves (gid "envelope") are those of `stats.energy_envelope` at
    S0 = 4 zeta sigma_x^2, on delta >= 0 only; at the fixture's eps = 0.5 (outside the range
    eps >= 0.8) they are left out with a note, drawn dash-dotted and labelled on request."""
    events = data["events"]
    eps, zeta = float(events.attrs["eps"]), float(events.attrs["zeta"])
    assert eps < stats.ENVELOPE_EPS_MIN
    fig = plotting.fig09(events)
    assert _envelope_lines(fig) == [[], []]
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any("not drawn" in s and "outside its range" in s for s in labels)
    assert not [s for s in [t.get_text() for t in plotting.fig09(events, envelope="never")
                            .legends[0].get_texts()] if "energy-envelope" in s]
    s0 = 4 * zeta * float(events.attrs["linear_sigma_x"]) ** 2
    for attrs, style in (({}, "-."), ({"eps": 0.9}, "-")):
        ev = events.copy()
        ev.attrs.update(attrs)
        fig = plotting.fig09(ev, envelope="always" if not attrs else "auto")
        (v_line,), (z_line,) = _envelope_lines(fig)
        d = np.asarray(v_line.get_xdata(), dtype=float)
        assert d.min() == pytest.approx(stats.ENVELOPE_DELTA_MIN)
        assert d.max() == pytest.approx(float(ev["delta"].max()))
        th = stats.energy_envelope(d, eps=float(ev.attrs["eps"]), zeta=zeta, S0=s0)
        np.testing.assert_allclose(v_line.get_ydata(), th.v_after_mean, rtol=1e-12)
        np.testing.assert_allclose(z_line.get_ydata(), th.interval_mean, rtol=1e-12)
        assert v_line.get_linestyle() == style
        label = [t.get_text() for t in fig.legends[0].get_texts() if "energy-envelope" in
                 t.get_text()][0]
        assert "white noise at $\\omega = 1$" in label and "\\varepsilon \\to 1" in label
        assert ("OUTSIDE its range" in label) == (not attrs)
    silent = events.copy()
    silent.attrs.update(linear_sigma_x=0.0, eps=0.9)   # no random force: nothing to say
    assert not [t for t in plotting.fig09(silent).legends[0].get_texts()
                if "energy-envelope" in t.get_text()]
    with pytest.raises(ValueError, match="envelope"):
        plotting.fig09(events, envelope="yes")


def test_fig07_envelope_densities_for_the_plays_it_covers(data):
    events = data["events"].copy()
    events.attrs["eps"] = 0.9
    fig = plotting.fig07(events, density_delta=DENSITY_DELTA)
    drawn = _envelope_lines(fig)
    deltas = [2.0, 0.5, 0.0]                       # the density deltas >= 0, largest first
    assert [len(lines) for lines in drawn] == [len(deltas)] * 2
    s0 = 4 * 0.05 * float(events.attrs["linear_sigma_x"]) ** 2
    data_colors = [ln.get_color() for ln in _data_lines(fig.axes[0])
                   if ln.get_gid() != "envelope"]
    for k, (line, d) in enumerate(zip(drawn[0], deltas)):
        w, p = (np.asarray(v, dtype=float) for v in line.get_data())
        expected = stats.envelope_v_after_pdf(w, d, eps=0.9, zeta=0.05, S0=s0)
        np.testing.assert_allclose(p[np.isfinite(p)], expected[np.isfinite(p)], rtol=1e-12)
        assert same_color(line.get_color(), data_colors[k])   # its delta curve's colour
    assert any("energy-envelope" in s for s in _legend_texts(fig.axes[0]))
    events.attrs["eps"] = 0.5
    assert _envelope_lines(plotting.fig07(events, density_delta=DENSITY_DELTA)) == [[], []]

def test_events_store_batch_lag1_and_no_ratio_statistics_without_harmonic(data):
    events, harmonic = data["events"], data["events_h"]
    for ds in (events, harmonic):
        assert (ds["n_batches"] == 20).all()
        for name in ("v_after_lag1", "interval_lag1", "v_after_beyond", "interval_beyond"):
            assert ds[name].dims == ("inv_beta", "delta")
        assert "batch-means" in ds["v_after_density_stderr"].attrs["long_name"]
    for name in ("ratio_density", "ratio_beyond", "motion_probability", "ratio", "motion"):
        assert name not in events.variables and name in harmonic.variables
    with pytest.raises(ValueError, match="harmonic"):
        plotting.fig13(events, inv_beta=1.0)
    with pytest.raises(ValueError, match="harmonic"):
        plotting.fig14(events, inv_beta=1.0)


def test_critical_delta_undefined_when_the_sweep_never_stops_impacting(data):
    impacting = data["events"].sel(delta=[-1.0, 0.0, 1.0])
    empty = data["events"].sel(delta=[4.5, 6.0])
    assert np.isnan(critical_delta(impacting)) and np.isnan(critical_delta(empty))
    fig = plotting.fig09(impacting)
    assert not [p for ax in fig.axes for p in ax.patches if p.get_gid() == "no_collision"]


def test_fig10_harmonic_input_and_motion(data):
    trace = data["trace_h"]
    fig = plotting.fig10(trace)
    assert len(fig.axes) == 2
    assert fig.axes[0].get_ylabel() == axis_label(trace["f"])
    assert r"\sin(1.1\,\tau)" in _title(fig)


def test_fig11_fig12_select_the_nearest_forcing_frequency(data):
    spectra = data["spectra_h"]
    fig11 = plotting.fig11(spectra, inv_beta=1.08)
    fig12 = plotting.fig12(spectra, inv_beta=1.08)
    for fig in (fig11, fig12):
        assert r"\sin(\tau/1.1)" in _title(fig)
    assert _vlines_at(fig12.axes[0]) == [pytest.approx(1 / 1.1)]
    assert len(_data_lines(fig12.axes[0])) == spectra.sizes["delta"] + 1


def test_fig12_states_the_resolution_and_each_line_power(data):
    """Welch peak heights depend on the resolution; the legend gives what does not."""
    spectra = data["spectra_h"]
    ax = plotting.fig12(spectra, inv_beta=1.1).axes[0]
    step = float(spectra["beta"][1] - spectra["beta"][0])
    assert f"resolution $\\Delta\\beta$ = {step:.3g}" in _legend(ax).get_title().get_text()
    cells = spectra.isel(inv_beta=_nearest_index(spectra["inv_beta"], 1.1))
    texts = _legend_texts(ax)
    for d in cells["delta"].values:
        power = stats.line_power(cells["beta"], cells["S_a"].sel(delta=d), 1.1 ** -1)
        assert any(t.startswith(f"$\\delta$ = {d:g} ") and f"power {power:.3g})" in t
                   for t in texts), (d, power, texts)


@pytest.mark.parametrize("plays, way", [
    ({2.0: (1.0, 1.7), -0.5: (1.3, 0.2)}, "rises as $\\delta$ decreases, against the paper"),
    ({2.0: (1.3, 1.7), -0.5: (1.0, 0.2)}, "falls as $\\delta$ decreases, as in the paper"),
    ({2.0: (1.2, 1.7), -0.5: (1.2, 0.2)}, "shows no resolved move")])
def test_fig12_gives_both_readings_and_which_way_the_broadband_moves(data, plays, way):
    """Welch spectra with batches of a broadband resonance (at the plays' resonances) under a
    line at beta_f strong at the large play and weak at the small (tests/test_centroid.py):
    the header gives the centroid with the lines and the broadband one with its interval,
    both as `vibroimpact.stats.centroid.shift` computes them, and the broadband's way."""
    from test_centroid import spectra_row

    from vibroimpact.stats.centroid import shift

    row = spectra_row(plays)
    spectra = xr.concat([row], dim="inv_beta").assign_coords(inv_beta=[1.1])
    spectra["S_lin"] = ("beta", np.full(row.beta.size, 1e-3))
    spectra.attrs = dict(data["spectra_h"].attrs)
    title = _title(plotting.fig12(spectra, inv_beta=1.1)).replace("\n", " ")
    sh = shift(row, 1 / 1.1)
    assert (f"with the lines at $k\\beta_f$ {sh.centroid_lines[-1]:.2f} $\\to$ "
            f"{sh.centroid_lines[0]:.2f} broadband (lines' $\\pm$5 bins out): "
            f"{sh.centroid[-1]:.2f} [{sh.centroid_low[-1]:.2f}, {sh.centroid_high[-1]:.2f}] "
            f"$\\to$ {sh.centroid[0]:.2f} [") in title, title
    assert way in title and "(95 %, 10 batches)" in title
    assert "opposite" not in title


def _nearest_index(coord, value):
    return int(np.argmin(np.abs(np.asarray(coord, float) - value)))


def test_fig11_draws_the_harmonic_part_as_a_line_of_power_half(data):
    """The input's PSD: the random part as a curve, sin(beta_f tau) as an arrow at beta_f
    labelled with its power A^2/2, never a Welch-smeared peak."""
    spectra = data["spectra_h"]
    ax = plotting.fig11(spectra, inv_beta=1.08).axes[0]
    arrows = [t for t in ax.texts if hasattr(t, "xy")]
    assert [a.xy[0] for a in arrows] == [pytest.approx(1 / 1.1)]
    assert any("power $A^2/2$ = 0.5" in t for t in _legend_texts(ax))
    curve = _data_lines(ax)[0]
    beta = np.asarray(curve.get_xdata(), float)
    S = np.asarray(curve.get_ydata(), float)
    near = np.abs(beta - 1 / 1.1) < 0.1
    # no peak at the forcing frequency: the curve is the random part alone
    assert S[near].max() < 2.0 * np.median(S[beta < 3.0])


def test_fig13_ratio_density_with_motion_marks(data):
    events = data["events_h"]
    ax, ax_lin = plotting.fig13(events, inv_beta=1.1, density_delta=DENSITY_DELTA).axes
    assert ax.get_yscale() == "log" and ax_lin.get_yscale() == "linear"
    for a in (ax, ax_lin):
        assert len(_data_lines(a)) == len(DENSITY_DELTA)
        assert _vlines_at(a) == [0.5, 1.0, 2.0]
        chain = [ln for ln in a.get_lines() if _is_reference(ln) and ln.get_linestyle() == "-."]
        assert len(chain) == 1 and chain[0].get_xdata()[0] == 0.5
        assert a.get_ylabel() == axis_label(events["ratio_density"])
    assert "batch-means" in _legend(ax).get_title().get_text()


def test_fig14_velocity_density_at_one_forcing_frequency(data):
    ax, ax_lin = plotting.fig14(data["events_h"], inv_beta=1.4, density_delta=DENSITY_DELTA).axes
    assert len(_data_lines(ax)) == len(_data_lines(ax_lin)) == len(DENSITY_DELTA)
    # neighbouring curves differ in line style and marker, not only in colour
    styles = [(ln.get_linestyle(), ln.get_marker()) for ln in _data_lines(ax)]
    assert all(a[0] != b[0] and a[1] != b[1] for a, b in zip(styles, styles[1:]))
    assert r"\sin(\tau/1.4)" in _title(ax.figure)


def test_fig16_contours_only_where_s_depends_on_delta(data):
    orbits = data["orbits"]
    fig = plotting.fig16(orbits)
    overview = fig.axes[0]
    colors = [ln.get_color() for ln in overview.get_lines()]
    assert colors == list(TYPE_COLORS[:len(ORBIT_TYPES)])           # qualitative, all distinct
    sel = orbits.sel(type="1/1")
    cplx = complex_multipliers(sel, 1, 1) & (sel["n_stable"].values > 0)
    assert cplx.any() and ((sel["n_stable"].values > 0) & ~cplx).any()
    x, y = orbits["inv_beta"].values, orbits["delta"].values
    panel = fig.axes[1]
    s_sets = [c for c in panel.collections if tuple(getattr(c, "levels", ())) == S_LEVELS]
    assert len(s_sets) == 1
    vertices = np.concatenate([p.vertices for p in s_sets[0].get_paths() if len(p.vertices)])
    i = np.abs(vertices[:, :1] - x[None, :]).argmin(axis=1)
    j = np.abs(vertices[:, 1:] - y[None, :]).argmin(axis=1)
    assert not cplx[i, j].any(), "an S contour crosses the complex-multiplier plateau"


def test_complex_multiplier_flag_matches_the_orbits(data):
    # The flag read from lam must agree with the multipliers of the most stable orbit.
    sel = data["orbits"].sel(type="1/1")
    flag = complex_multipliers(sel, 1, 1)
    for i, ib in enumerate(sel["inv_beta"].values[::2]):
        for j, d in enumerate(sel["delta"].values[::3]):
            if sel["n_stable"].values[2 * i, 3 * j] == 0:
                continue
            best = min(periodic_orbits(1, 1, 1 / ib, d, 0.05, 0.5), key=lambda o: o.lam)
            assert flag[2 * i, 3 * j] == bool(abs(best.multipliers[0].imag) > 1e-9), (ib, d)


# ------------------------------------------------------------------------- shared contract

def test_every_figure_states_its_parameters(data):
    figs = [plotting.fig03(data["trace"]), plotting.fig06(data["spectra"]),
            plotting.fig07(data["events"]), plotting.fig09(data["events"]),
            plotting.fig13(data["events_h"], 1.1)]
    for fig in figs:
        text = _title(fig)
        assert r"$\zeta$ = 0.05" in text and r"$\varepsilon$ = 0.5" in text
        assert "rms$_r$ = 0.5" in text and "band-limited white" in text
        assert r"$\beta_c$ = 4" in text
        assert "band_limited" not in text and "noise '" not in text     # no config keys
    assert r"$\delta$ = 0" in _title(figs[0])


def test_units_other_than_dimensionless_appear_in_labels(data):
    events = data["events"].copy()
    events["v_after_mean"] = events["v_after_mean"].assign_attrs(units="m/s")
    assert plotting.fig09(events).axes[0].get_ylabel() == (
        r"mean velocity after impact $\overline{\varepsilon u_{j-0}}$ [m/s]")


def test_missing_parameter_attribute_is_named(data):
    events = data["events"].copy()
    del events.attrs["zeta"]
    with pytest.raises(KeyError, match="'zeta'"):
        plotting.fig07(events)
    noise = data["noise"].copy()
    del noise.attrs["noise_kind"]
    with pytest.raises(KeyError, match="'noise_kind'"):
        plotting.fig04(noise)


def test_style_is_scoped_to_the_figure_functions(data):
    import matplotlib
    before = dict(matplotlib.rcParams)
    fig = plotting.fig04(data["noise"])       # one panel, legend inside: the style's size
    assert tuple(fig.get_size_inches()) == (6.5, 4.5)
    assert dict(matplotlib.rcParams) == before


def test_save_writes_png_and_pdf_atomically(data, tmp_path):
    fig = plotting.fig04(data["noise"])
    png, pdf = plotting.save(fig, tmp_path / "figs" / "fig04.png")
    assert sorted(os.listdir(tmp_path / "figs")) == ["fig04.pdf", "fig04.png"]
    assert_figure(png)
    assert_figure(pdf)
    with pytest.raises(ValueError, match="path_png"):
        plotting.save(fig, tmp_path / "fig04.svg")


# ------------------------------------------------------------------ Fig. 15 and its comparison

def _synthetic_map():
    """A map whose (1/1) probability is 1 inside a disc and (2/1) 1 outside, one cell few."""
    inv_beta = np.round(np.arange(0.5, 2.51, 0.1), 10)
    delta = np.round(np.arange(-1.0, 2.01, 0.1), 10)
    ib, d = np.meshgrid(inv_beta, delta, indexing="ij")
    inside = (ib - 1.5) ** 2 + d ** 2 < 0.5
    p = np.stack([inside * 0.9, ~inside * 0.6, np.zeros_like(ib)])
    few = np.zeros(ib.shape, "int8")
    few[3, 4] = 1
    reached = np.ones(ib.shape, "int8")
    reached[0, 0] = 0
    scalars = dict(few_switches=few, reached=reached, simulated_time=np.full(ib.shape, 5000.0))
    ds = xr.Dataset({"probability": (("motion", "inv_beta", "delta"), p),
                     **{k: (("inv_beta", "delta"), v) for k, v in scalars.items()}},
                    coords=dict(motion=["1/1", "2/1", "1/2"], inv_beta=inv_beta, delta=delta),
                    attrs=dict(zeta=0.05, eps=0.5, amplitude=1.0, noise_rms=0.29,
                               noise_kind="band_limited", noise_beta_c=4.0, motion_window=0.1,
                               target_stderr=0.01, max_periods=8000, min_switches=10))
    stable = np.stack([inside, np.zeros_like(inside), np.zeros_like(inside)])
    orbits = xr.Dataset({"n_stable": (("type", "inv_beta", "delta"), stable.astype(int)),
                         "S": (("type", "inv_beta", "delta"),
                               np.where(stable, 40.0 - 10 * np.hypot(ib - 1.5, d), np.nan))},
                        coords=dict(type=["1/1", "2/1", "1/2"], inv_beta=inv_beta, delta=delta),
                        attrs=dict(zeta=0.05, eps=0.5))
    return ds, orbits


def test_fig15_three_maps_in_percent_with_untrusted_cells_marked():
    ds, _ = _synthetic_map()
    fig = plotting.fig15(ds)
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == ["(1/1)", "(2/1)", "(1/2)"]
    hatched = [c for ax in panels for c in ax.collections if c.get_gid() == "few_switches"]
    assert len(hatched) == 3 and all(c.get_hatch() for c in hatched), \
        "cells with few switches must be hatched on every panel"
    title = _title(fig)
    assert "99.8 % of cells" in title and r"\sin(\beta_f\tau)" in title
    assert any("percent" in ax.get_ylabel() or "%" in ax.get_ylabel() for ax in fig.axes)


def test_fig15_draws_a_cell_short_of_its_target_whole_at_the_planes_edge():
    """Issue 43: the dots of the cells where the cap stopped the record sat on the axes' edge
    (the grid runs from centre to centre) and were cut in half; they are not clipped."""
    ds, _ = _synthetic_map()
    fig = plotting.fig15(ds)
    for ax in [ax for ax in fig.axes if ax.get_title()]:
        (dots,) = [line for line in ax.get_lines() if line.get_gid() == "not_reached"]
        assert not dots.get_clip_on()
        assert (dots.get_xdata()[0], dots.get_ydata()[0]) == (ax.get_xlim()[0],
                                                              ax.get_ylim()[0])


def test_fig16_legend_of_three_types_hides_no_domain():
    """Issue 43: over the (eps, delta) plane panel (a)'s legend covered the (1/1) grazing and
    (2/1) fold edges; with an empty panel in the grid the legend goes there, off the data."""
    inv_beta = np.round(np.arange(0.6, 1.61, 0.1), 10)
    deltas = np.round(np.arange(-0.5, 2.51, 0.25), 10)
    types = [(1, 1), (2, 1), (1, 2)]
    orbits = datasets.orbit_map_dataset(orbit_map(inv_beta, deltas, types=types, zeta=0.05,
                                                  eps=0.5),
                                        dict(zeta=0.05, eps=0.5, amplitude=1.0))
    fig = plotting.fig16(orbits)
    fig.canvas.draw()
    overview = fig.axes[0]
    assert overview.get_legend() is None
    (holder,) = [ax for ax in fig.axes if ax.get_legend() is not None]
    assert [t.get_text() for t in holder.get_legend().get_texts()] == ["(1/1)", "(2/1)",
                                                                       "(1/2)"]
    box = holder.get_legend().get_window_extent()
    for ax in fig.axes[:len(types) + 1]:          # (a) and the type panels
        assert not box.overlaps(ax.get_window_extent()), ax.get_title()


def test_fig15_vs_fig16_prints_the_agreement_and_refuses_another_system():
    ds, orbits = _synthetic_map()
    fig = plotting.fig15_vs_fig16(ds, orbits)
    agreement = plotting.map_agreement(ds, orbits)
    assert agreement["1/1"]["dominant_inside"] == 1.0 and agreement["1/1"]["domain_covered"] == 1.0
    assert agreement["2/1"]["n_domain"] == 0
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert any("100 % inside" in t for t in texts)
    with pytest.raises(ValueError, match="zeta"):
        plotting.fig15_vs_fig16(ds, orbits.assign_attrs(zeta=0.06))


def test_fig15_vs_fig16_reads_its_agreement_at_the_map_s_own_cells():
    """Given the orbits at the map's cells (rule solve_map_orbits), the boxes print the
    agreement read there: (1/1) stable on every cell there, with P 0.9 inside the
    disc and 0 outside, gives a rank correlation where the orbit map's domain (the disc,
    P constant) gives none; orbits off the map's grid are refused."""
    ds, orbits = _synthetic_map()
    ib, d = np.meshgrid(ds.inv_beta, ds.delta, indexing="ij")
    at = orbits.copy(deep=True)
    at["n_stable"].loc[{"type": "1/1"}] = 1
    at["S"].loc[{"type": "1/1"}] = 40.0 - 10 * np.hypot(ib - 1.5, d)
    expected = plotting.map_agreement(ds, at)["1/1"]["rank_correlation"]
    assert np.isnan(plotting.map_agreement(ds, orbits)["1/1"]["rank_correlation"])
    assert expected > 0.5
    fig = plotting.fig15_vs_fig16(ds, orbits, at)
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert any(t.endswith(f"rank corr. $(P, S)$ inside: {expected:.2f}") for t in texts)
    with pytest.raises(ValueError, match="not lie on the map's delta grid"):
        plotting.fig15_vs_fig16(ds, orbits, at.isel(delta=slice(1, None)))


# ------------------------------------------------------------------------- sparse-bin rule

def test_merge_sparse_bins_keeps_full_bins_and_merges_sparse_runs():
    edges = np.arange(11.0)
    counts = np.array([0, 3, 50, 4, 0, 7, 1, 12, 2, 0])
    left, right, count = plotting.merge_sparse_bins(edges, counts, min_count=10)
    # bin 1 (3 values) meets the full bin 2 before it holds 10: dropped; 3..5 hold 4+0+7 = 11;
    # bin 6 (1 value) meets the full bin 7: dropped; 8..9 end below 10: dropped
    assert left.tolist() == [2.0, 3.0, 7.0]
    assert right.tolist() == [3.0, 6.0, 8.0]
    assert count.tolist() == [50, 11, 12]
    # every value drawn is counted once, and no drawn bin holds fewer than min_count
    assert (count >= 10).all() and count.sum() <= counts.sum()


def test_merge_sparse_bins_with_min_count_one_changes_nothing_but_empty_bins():
    edges = np.linspace(0.0, 1.0, 6)
    counts = np.array([1, 0, 2, 5, 0])
    left, right, count = plotting.merge_sparse_bins(edges, counts, min_count=1)
    assert count.tolist() == [1, 2, 5] and left.tolist() == [edges[0], edges[2], edges[3]]


def test_density_figure_draws_no_point_below_the_sparse_bin_count(data):
    """A single value in a bin cannot show: every drawn density is >= MIN_BIN_COUNT / (n W)."""
    events = data["events"].copy(deep=True)
    cell = dict(inv_beta=0, delta=int(np.argmin(np.abs(events["delta"].values))))
    n = int(events["n_collisions"][cell])
    width = float(events["v_after"][1] - events["v_after"][0])
    dens = events["v_after_density"][cell].values
    dens[-1] = 1.0 / (n * width)                # one value in the last bin, far in the tail
    events["v_after_density"][cell] = dens
    ax = plotting.fig07(events, density_delta=[0.0]).axes[0]
    (line,) = _data_lines(ax)
    x = np.asarray(line.get_xdata(), dtype=float)
    assert np.nanmax(x) < float(events["v_after"][-1]) - 0.5 * width   # the lone bin is not drawn
    assert ax.get_xlim()[1] < float(events["v_after"][-1])              # nor the axis taken to it


def test_density_figure_draws_merged_runs_apart_from_the_curve(data):
    """A merged run of sparse bins is a bar over its width, never a plateau of the curve."""
    events = data["events"].copy(deep=True)
    cell = dict(inv_beta=0, delta=int(np.argmin(np.abs(events["delta"].values))))
    n = int(events["n_collisions"][cell])
    width = float(events["v_after"][1] - events["v_after"][0])
    dens = events["v_after_density"][cell].values.copy()
    dens[-6:] = [30.0, 20.0, 4.0, 0.0, 3.0, 5.0]     # 12 values in the last four bins,
    dens[-6:] /= n * width                            # after two full ones
    events["v_after_density"][cell] = dens
    ax = plotting.fig07(events, density_delta=[0.0]).axes[0]
    (line,) = _data_lines(ax)
    x = np.asarray(line.get_xdata(), dtype=float)
    edges_right = float(events["v_after"][-1]) + 0.5 * width
    assert np.nanmax(x) < edges_right - 4 * width       # the curve stops before the run
    runs = [c for c in ax.collections if c.get_gid() == "sparse_run"]
    (bar,) = [c for c in runs if np.allclose(np.diff(c.get_segments()[0][:, 1]), 0.0)]
    (seg,) = [g for g in bar.get_segments() if g[1, 0] == pytest.approx(edges_right)]
    np.testing.assert_allclose(seg[:, 0], [edges_right - 4 * width, edges_right], rtol=1e-12)
    np.testing.assert_allclose(seg[:, 1], 12.0 / (n * 4 * width), rtol=1e-12)


def test_a_single_bin_spans_zero_to_max():
    """``bins: {max: 1000, n: 1}``: one bin [0, 1000] holding every interval (it was given a
    width of 1 and failed as "not a count")."""
    cell = xr.Dataset({"interval_density": ("interval", [1.0 / 1000.0]), "n_collisions": 369},
                      coords={"interval": [500.0]})
    edges, counts, n = plotting.bin_counts(cell, "interval_density")
    assert edges.tolist() == [0.0, 1000.0] and counts.tolist() == [368] and n == 368


@pytest.mark.parametrize("inches", [3.0, 4.0, 6.5, 9.0])
def test_a_long_header_stays_inside_its_figure_whatever_its_width(inches):
    """Every line of a header, as the renderer lays it out, lies inside the figure, broken at
    ';  ', ', ' or a space but never inside maths: one part alone (the two-wall line, the
    escape figure's definition) is wider than a narrow figure."""
    from vibroimpact.plotting._common import _header, symbols
    params = (r"zeta = 0.05, eps = 0.5;  two walls, the lower at $\delta$ - g (g = 2, "
              r"$\varepsilon_l$ = 0.5): collisions at both walls pooled;  input band_limited, "
              r"$\beta_c$ = 4;  varied: rms$_r$ (legend)" "\n"
              r"residence time T: mean length of the complete stretches of a motion (free and "
              r"impact-stick together), $w$ = 0.1;  $\Delta$: slope of $\ln T$ against "
              r"1/rms$_r^2$ (weighted)")
    fig = Figure(figsize=(inches, 4))
    _header(fig, "Sweep 's11': mean velocity", params)
    fig.canvas.draw()
    box = fig._suptitle.get_window_extent()
    assert 0 <= box.x0 and box.x1 <= fig.bbox.x1, (box, fig.bbox)
    lines = fig.get_suptitle().split("\n")
    assert all(line.count("$") % 2 == 0 for line in lines)
    assert len(lines) > 3                       # the two lines given broke somewhere
    # nothing lost or added: the same words, in order
    assert fig.get_suptitle().split() == f"Sweep 's11': mean velocity {symbols(params)}".split()
