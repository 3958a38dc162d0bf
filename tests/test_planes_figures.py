"""Maps over any two parameters (issue 36): labels, captions, Figs. 15 and 16 over other
planes, and a sweep's stack of maps side by side. (That the paper's own figures do not move
is `benchmarks/same_build.py`'s: a build of the old code against one of the new, pixel for
pixel; a test bound to a baseline at a path of one machine skipped everywhere else.)

The maps over other planes are laid out by hand (a probability hill whose place the test
knows) and written and read back with the real writer, so ``attrs["axes"]`` and
``attrs["fixed"]`` travel through netCDF as the pipeline's datasets do.
"""
import json

import numpy as np
import pytest
import xarray as xr

from vibroimpact import plotting
from vibroimpact._symbols import (PARAMETERS, fixed_caption, parameter_label,
                                  parameter_symbol)
from vibroimpact.pipeline import datasets, io
from vibroimpact.plotting._common import plane_axes, plane_caption, plane_fixed
from vibroimpact.plotting.planes import map_stack, swept_parameter

EPS = np.round(np.arange(0.1, 0.951, 0.05), 10)
DELTA = np.round(np.arange(-1.0, 2.001, 0.1), 10)
FIXED = {"zeta": 0.05, "amplitude": 1.0, "inv_beta": 1.1, "rms": 0.29}
HILL = (-0.2, 0.25)


def _plane_map(tmp_path, rms=0.29, x=("eps", EPS), y=("delta", DELTA), name="map"):
    """A map over (x, y): the (1/1) motion a hill whose top is at `HILL` (shares of the axes'
    ranges from their middles), the (2/1) its complement, stored as (motion, y, x) to prove
    the figures read the axes by name; one flagged cell."""
    (xn, xv), (yn, yv) = x, y
    gx, gy = np.meshgrid((xv - xv.mean()) / np.ptp(xv), (yv - yv.mean()) / np.ptp(yv),
                         indexing="ij")
    hill = np.exp(-((gx - HILL[0]) ** 2 + (gy - HILL[1]) ** 2) / (0.05 + rms))
    p = np.stack([0.95 * hill, 0.9 * (1.0 - hill)])
    few = np.zeros(hill.shape, "int8")
    few[2, 3] = 1
    ds = xr.Dataset({"probability": (("motion", xn, yn), p),
                     "few_switches": ((xn, yn), few),
                     "reached": ((xn, yn), np.ones(hill.shape, "int8")),
                     "simulated_time": ((xn, yn), np.full(hill.shape, 5000.0))},
                    coords={"motion": ["1/1", "2/1"], xn: xv, yn: yv},
                    attrs=dict(axes=[xn, yn], fixed=json.dumps(dict(FIXED, rms=rms)),
                               noise_kind="band_limited", noise_beta_c=4.0,
                               motion_window=0.1, target_stderr=0.01, max_periods=8000,
                               min_switches=10))
    ds = ds.transpose("motion", yn, xn)
    path = tmp_path / f"{name}.nc"
    io.write_dataset(datasets.annotate(ds), path)
    return io.load_dataset(path)


# --- labels and captions ------------------------------------------------------------------------

def test_every_parameter_has_the_paper_symbol_and_a_label():
    expected = {"zeta": "ζ", "eps": "ε", "eps_lower": "ε_l", "delta": "δ", "gap": "g",
                "amplitude": "A", "inv_beta": "1/β_f", "rms": "σ_r"}
    assert set(PARAMETERS) == set(expected)
    for name, text in expected.items():
        assert parameter_symbol(name, math=False) == text
        symbol = parameter_symbol(name)
        assert symbol.startswith("$") and symbol.endswith("$")
        assert symbol[1:-1] in parameter_label(name)
        assert plotting.LABELS[name] == parameter_label(name)
    # the paper's plane keeps the labels its maps always had
    assert parameter_label("delta") == r"play $\delta$"
    assert parameter_label("inv_beta") == r"inverse forcing frequency $1/\beta_f$"
    with pytest.raises(ValueError, match="'beta' is not one a map's plane may run over"):
        parameter_label("beta")


def test_caption_says_what_is_fixed_in_order_and_in_symbols():
    fixed = {"rms": 0.29, "inv_beta": 1.1, "amplitude": 1.0, "zeta": 0.05}
    assert fixed_caption(fixed, math=False) == "ζ = 0.05, A = 1, 1/β_f = 1.1, σ_r = 0.29"
    assert fixed_caption(fixed) == (r"$\zeta$ = 0.05, $A$ = 1, $1/\beta_f$ = 1.1, "
                                    r"$\sigma_r$ = 0.29")
    assert fixed_caption({"eps": 0.1 + 0.2}, math=False) == "ε = 0.3"    # 4 digits
    assert fixed_caption({"gap": 1.0, "noise": "white"}, math=False) == "g = 1, noise = white"
    assert fixed_caption({}) == ""
    with pytest.raises(ValueError, match="fixed must be a dict"):
        fixed_caption([("zeta", 0.05)])


def test_a_dataset_names_its_plane_and_what_it_fixes(tmp_path):
    ds = _plane_map(tmp_path)
    assert plane_axes(ds) == ("eps", "delta")
    assert plane_fixed(ds) == FIXED
    assert plane_caption(ds, math=False) == "fixed: ζ = 0.05, A = 1, 1/β_f = 1.1, σ_r = 0.29"
    # the paper's map names nothing: its plane and its attributes
    paper = xr.Dataset(coords=dict(inv_beta=[1.0], delta=[0.0]),
                       attrs=dict(zeta=0.05, eps=0.5, amplitude=1.0, noise_rms=0.29))
    assert plane_axes(paper) == ("inv_beta", "delta")
    assert plane_caption(paper, math=False) == "fixed: ζ = 0.05, ε = 0.5, A = 1, σ_r = 0.29"
    with pytest.raises(ValueError, match=r"\['gap'\] is not among"):
        plane_axes(ds.assign_attrs(axes=["eps", "gap"]))
    with pytest.raises(ValueError, match="two different parameters"):
        plane_axes(ds.assign_attrs(axes=["eps"]))
    with pytest.raises(ValueError, match="must be JSON text"):
        plane_fixed(ds.assign_attrs(fixed="zeta = 0.05"))


# --- Fig. 15 over another plane -----------------------------------------------------------------

def test_fig15_over_eps_delta_reads_the_axes_by_name(tmp_path):
    ds = _plane_map(tmp_path)
    assert ds["probability"].dims == ("motion", "delta", "eps")      # stored transposed
    fig = plotting.fig15(ds)
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.get_title()]
    assert [ax.get_title() for ax in axes] == ["(1/1)", "(2/1)"]
    bottom = axes[0]
    assert bottom.get_xlabel() == r"restitution $\varepsilon$"
    assert bottom.get_ylabel() == r"play $\delta$"
    assert bottom.get_xlim() == (EPS[0], EPS[-1])
    assert bottom.get_ylim() == (DELTA[0], DELTA[-1])
    header = fig.get_suptitle()
    assert (r"fixed: $\zeta$ = 0.05, $A$ = 1, $1/\beta_f$ = 1.1, $\sigma_r$ = 0.29"
            in header)
    assert r"$\varepsilon$ = " not in header          # an axis is never called fixed
    # the hill's top (the (1/1) motion at 95 %) is drawn where the data put it: the band
    # from 90 % covers that point, and a point as far on the other side lies far below it
    fill = bottom.collections[0]

    def band(fx, fy):
        point = (EPS.mean() + fx * np.ptp(EPS), DELTA.mean() + fy * np.ptp(DELTA))
        inside = [k for k, path in enumerate(fill.get_paths())
                  if path.vertices.size and path.contains_point(point)]
        return list(fill.levels)[max(inside)]

    assert band(*HILL) == 90.0
    assert band(-HILL[0], -HILL[1]) <= 30.0


def test_fig16_over_a_plane_from_orbit_plane(tmp_path):
    from vibroimpact.orbits.plane import orbit_plane

    eps = np.round(np.arange(0.1, 0.91, 0.1), 10)
    delta = np.round(np.arange(-1.0, 1.51, 0.1), 10)
    orbits = orbit_plane("eps", eps, "delta", delta, {"zeta": 0.05, "inv_beta": 1.1},
                         types=((1, 1), (2, 1)))
    io.write_dataset(orbits, tmp_path / "orbits.nc")
    orbits = io.load_dataset(tmp_path / "orbits.nc")
    fig = plotting.fig16(orbits)
    panels = [ax for ax in fig.axes if ax.get_title() in ("(1/1)", "(2/1)")]
    assert len(panels) == 2
    assert panels[0].get_xlabel() in ("", r"restitution $\varepsilon$")
    assert any(ax.get_xlabel() == r"restitution $\varepsilon$" for ax in fig.axes)
    assert r"fixed: $\zeta$ = 0.05, $A$ = 1, $1/\beta_f$ = 1.1" in fig.get_suptitle()
    with pytest.raises(ValueError, match=r"traced over \['inv_beta', 'delta'\] but the orbit "
                                         r"map runs over \['eps', 'delta'\]"):
        plotting.fig16(orbits, boundaries=xr.Dataset())


def test_fig15_vs_fig16_needs_one_plane(tmp_path):
    from vibroimpact.orbits.plane import orbit_plane

    motion_map = _plane_map(tmp_path)
    orbits = orbit_plane("eps", EPS, "delta", DELTA, {"zeta": 0.05, "inv_beta": 1.1},
                         types=((1, 1), (2, 1)))
    fig = plotting.fig15_vs_fig16(motion_map, orbits)
    assert fig.axes[0].get_xlabel() == r"restitution $\varepsilon$"
    other = orbit_plane("eps", EPS, "delta", DELTA, {"zeta": 0.1, "inv_beta": 1.1},
                        types=((1, 1),))
    with pytest.raises(ValueError, match="the map has zeta = 0.05 but the orbit map 0.1"):
        plotting.fig15_vs_fig16(motion_map, other)
    swapped = orbit_plane("delta", DELTA, "eps", EPS, {"zeta": 0.05, "inv_beta": 1.1},
                          types=((1, 1),))
    with pytest.raises(ValueError, match="not the same plane"):
        plotting.fig15_vs_fig16(motion_map, swapped)


# --- a stack of maps ----------------------------------------------------------------------------

def test_stack_one_column_per_swept_value_on_one_colour_scale(tmp_path):
    maps = [_plane_map(tmp_path, rms=r, name=f"m{k}") for k, r in enumerate((0.4, 0.1, 0.2))]
    assert swept_parameter(maps) == ("rms", [0.4, 0.1, 0.2])
    reached = maps[0]["reached"].copy()
    reached.loc[dict(eps=EPS[4], delta=DELTA[7])] = 0           # capped: a dot, rms = 0.4
    maps[0] = maps[0].assign(reached=reached)
    fig = map_stack(*maps)
    titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
    assert titles == [r"(1/1),  $\sigma_r$ = 0.1", r"(1/1),  $\sigma_r$ = 0.2",
                      r"(1/1),  $\sigma_r$ = 0.4", r"(2/1),  $\sigma_r$ = 0.1",
                      r"(2/1),  $\sigma_r$ = 0.2", r"(2/1),  $\sigma_r$ = 0.4"]
    panels = [ax for ax in fig.axes if ax.get_title()]
    fills = [ax.collections[0] for ax in panels]
    assert all(list(f.levels) == list(fills[0].levels) for f in fills)
    assert {f.norm.vmin for f in fills} == {-10} and {f.norm.vmax for f in fills} == {100}
    dots = [[(line.get_xdata()[0], line.get_ydata()[0]) for line in ax.get_lines()
             if line.get_marker() == "."] for ax in panels]
    assert dots == [[], [], [(EPS[4], DELTA[7])], [], [], [(EPS[4], DELTA[7])]]
    colourbars = [ax for ax in fig.axes if ax.get_ylabel() == "probability of the motion (%)"]
    assert len(colourbars) == 1
    header = fig.get_suptitle()
    assert r"$\sigma_r$ = 0.1, 0.2, 0.4" in header
    assert r"fixed: $\zeta$ = 0.05, $A$ = 1, $1/\beta_f$ = 1.1" in header
    assert r"$\sigma_r$ = 0.29" not in header


def test_stack_errors_name_the_problem(tmp_path):
    a, b = _plane_map(tmp_path, 0.1, name="a"), _plane_map(tmp_path, 0.2, name="b")
    with pytest.raises(ValueError, match="differ in no fixed parameter"):
        map_stack(a, _plane_map(tmp_path, 0.1, name="c"))
    with pytest.raises(ValueError, match=r"differ in \['amplitude', 'rms'\]"):
        fixed = dict(json.loads(b.attrs["fixed"]), amplitude=2.0)
        map_stack(a, b.assign_attrs(fixed=json.dumps(fixed)))
    with pytest.raises(ValueError, match="run over one plane"):
        map_stack(a, _plane_map(tmp_path, 0.2, x=("zeta", EPS / 2), name="d"))
    with pytest.raises(ValueError, match="two maps or more"):
        map_stack(a)
    with pytest.raises(ValueError, match=r"motions \['1/2'\] are not in every map"):
        map_stack(a, b, motions=["1/2"])


def test_residence_over_another_plane(tmp_path):
    ds = _plane_map(tmp_path)
    shape = (ds.sizes["motion"], ds.sizes["delta"], ds.sizes["eps"])
    time = np.broadcast_to(np.linspace(1.0, 50.0, ds.sizes["eps"]), shape).copy()
    ds = ds.assign(residence_time=(("motion", "delta", "eps"), time),
                   n_stretches=(("motion", "delta", "eps"), np.full(shape, 20)),
                   residence_time_none=(("delta", "eps"), time[0]),
                   n_stretches_none=(("delta", "eps"), np.full(shape[1:], 20)))
    fig = plotting.residence(ds)
    panels = [ax for ax in fig.axes if ax.get_title() in ("(1/1)", "(2/1)", "none")]
    assert len(panels) == 3
    mesh = [c for c in panels[0].collections if c.get_gid() == "residence"][0]
    # cells coloured along eps (x) by the time that grows along eps
    drawn = mesh.get_array().reshape(ds.sizes["delta"], ds.sizes["eps"])
    assert np.allclose(drawn[0], np.linspace(1.0, 50.0, ds.sizes["eps"]))
    assert panels[0].get_xlabel() == r"restitution $\varepsilon$"


def test_the_predictors_read_a_plane_by_its_axes(tmp_path):
    """The report's predictors over an (eps, delta) map and its Fig. 16 (`orbit_plane`, on a
    finer grid): S is solved at each map cell by the axes' names (the map stored (y, x)), as
    `orbit_plane` gives it at the map's own cells."""
    from vibroimpact.orbits.plane import orbit_plane
    from vibroimpact.orbits.cells import orbits_at_cells
    from vibroimpact.reports.predictors import _stable_domain, predictor_correlations

    motion_map = _plane_map(tmp_path)
    fixed = {"zeta": 0.05, "inv_beta": 1.1}
    fine = orbit_plane("eps", np.round(np.arange(0.1, 0.951, 0.02), 10), "delta",
                       np.round(np.arange(-1.0, 2.001, 0.02), 10), fixed, types=((1, 1), (2, 1)))
    orbits = orbits_at_cells(motion_map, fine)
    stable, S = _stable_domain(motion_map.transpose(..., "eps", "delta"), orbits, None, "1/1")
    own = orbit_plane("eps", EPS, "delta", DELTA, fixed, types=((1, 1), (2, 1)))
    expected = own["n_stable"].sel(type="1/1").transpose("eps", "delta").values > 0
    np.testing.assert_array_equal(stable, expected)
    rows = predictor_correlations(motion_map, orbits, n_resamples=20)
    assert any(r.predictor == "S" and np.isfinite(r.rho) for r in rows)


def test_a_seed_swept_over_maps_is_read_from_the_sweeps_attributes(tmp_path):
    """The noise's seed is no parameter of the map (its fixed values agree, the rms too when
    it is an axis): the sweep's own attribute names it; with none, or two, nothing is swept."""
    maps = [_plane_map(tmp_path, rms=0.29, name=f"s{k}") for k in range(2)]
    with pytest.raises(ValueError, match="nothing is swept"):
        swept_parameter(maps)
    for k, ds in enumerate(maps):
        ds.attrs.update(sweep_seed=k + 7, sweep_index=k)
    assert swept_parameter(maps) == ("seed", [7, 8])
    maps[1].attrs["sweep_zeta"], maps[0].attrs["sweep_zeta"] = 0.1, 0.05
    with pytest.raises(ValueError, match=r"2 sweep attributes \(\['seed', 'zeta'\]\)"):
        swept_parameter(maps)
