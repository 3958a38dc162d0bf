"""Fig. 16 over any plane (issue 36): `orbit_plane` against `orbit_map`, `periodic_orbits` and
`periodic_motions`, the amplitude scaled out, and its error messages. One wall:
`vibroimpact.orbits.plane`; two walls: `vibroimpact.attractors.plane` (the same call)."""
import json

import numpy as np
import pytest
import xarray as xr

from vibroimpact.attractors import plane as any_walls
from vibroimpact.attractors.shooting import periodic_motions
from vibroimpact.model import Model
from vibroimpact.orbits import orbit_map, periodic_orbits
from vibroimpact.orbits.plane import orbit_plane

PAPER = {"zeta": 0.05, "eps": 0.5}
TYPES = ((1, 1), (2, 1), (1, 2), (1, 3), (3, 1))
INV_BETA = np.round(np.arange(0.3, 2.51, 0.2), 10)
DELTA = np.round(np.arange(-1.5, 3.001, 0.1), 10)
VARIABLES = ("exists", "n_solutions", "n_stable", "lam", "S", "reason")
#: S of one orbit by two routes (the map kernel, `periodic_orbits`): the same equations
#: solved to round-off from different seeds; 4.7e-13 measured over the (eps, delta) column
#: below, 1e-9 is the orbit tolerance of issue 35.
S_TOL = 1e-9


def _same(a, b):
    return np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float),
                          equal_nan=True)


def test_the_paper_plane_is_orbit_map_exactly():
    ds = orbit_plane("inv_beta", INV_BETA, "delta", DELTA, PAPER, types=TYPES)
    # any layout's call hands a one-wall plane to the closed form unchanged
    assert any_walls.orbit_plane("inv_beta", INV_BETA, "delta", DELTA, PAPER,
                                 types=TYPES).identical(ds)
    ref = orbit_map(INV_BETA, DELTA, types=TYPES, **PAPER)
    assert ds["n_stable"].dims == ("type", "inv_beta", "delta")
    assert list(ds["type"].values) == ["1/1", "2/1", "1/2", "1/3", "3/1"]
    for name in VARIABLES:
        assert _same(ds[name].values, ref[name]), name
    assert ds["n_stable"].values.sum() > 0                     # the test sees stable cells
    assert ds.attrs["axes"] == ["inv_beta", "delta"]
    assert json.loads(ds.attrs["fixed"]) == {"amplitude": 1.0, **PAPER}
    # the axes the other way round: the same cells, transposed
    swapped = orbit_plane("delta", DELTA, "inv_beta", INV_BETA, PAPER, types=TYPES)
    assert swapped["S"].dims == ("type", "delta", "inv_beta")
    assert _same(swapped["S"].transpose("type", "inv_beta", "delta").values, ref["S"])


def test_eps_column_at_the_paper_eps_is_the_default_column_and_periodic_orbits():
    k = 4                                                     # 1/beta = 1.1
    eps = [0.3, 0.5, 0.8]
    ds = orbit_plane("eps", eps, "delta", DELTA, {"zeta": 0.05, "inv_beta": INV_BETA[k]},
                     types=TYPES)
    column = ds.sel(eps=0.5)
    ref = orbit_map(INV_BETA, DELTA, types=TYPES, **PAPER)
    for name in VARIABLES:                                    # bit for bit
        assert _same(column[name].values, ref[name][:, k]), name
    # and cell by cell the closed-form solver at that point
    assert not _same(ds.sel(eps=0.8)["S"].values, column["S"].values)
    for t, (m, n) in enumerate(TYPES):
        for j, delta in enumerate(DELTA):
            orbits = periodic_orbits(m, n, 1.0 / INV_BETA[k], delta, **PAPER)
            assert int(column["n_solutions"][t, j]) == len(orbits)
            assert int(column["n_stable"][t, j]) == sum(o.stable for o in orbits)
            if orbits:
                S = 100.0 * (1.0 - min(o.lam for o in orbits))
                assert abs(float(column["S"][t, j]) - S) <= S_TOL


def test_a_plane_without_delta_is_periodic_orbits_per_cell():
    eps, zeta = [0.2, 0.7], [0.03, 0.1]
    ds = orbit_plane("eps", eps, "zeta", zeta, {"delta": 0.3, "inv_beta": 0.9},
                     types=((1, 1), (2, 1)))
    assert ds.attrs["solver"] == "periodic_orbits"
    for i, e in enumerate(eps):
        for j, z in enumerate(zeta):
            for t, (m, n) in enumerate(((1, 1), (2, 1))):
                orbits = periodic_orbits(m, n, 1.0 / 0.9, 0.3, z, e)
                assert int(ds["n_stable"][t, i, j]) == sum(o.stable for o in orbits)
                lam = min((o.lam for o in orbits), default=np.nan)
                assert _same(ds["lam"][t, i, j], lam)
    assert ds["n_stable"].values.sum() > 0


def test_the_amplitude_scales_out_as_delta_over_a():
    """x = A y: the motion at (A, delta) is A times the one at (1, delta / A), with the same
    multipliers; checked against the closed form at the scaled play and, independently, by
    the shooting solver run at amplitude A itself."""
    amplitude = [0.5, 1.0, 2.0]
    delta = np.round(np.arange(-0.5, 1.51, 0.25), 10)
    ds = orbit_plane("amplitude", amplitude, "delta", delta, {"inv_beta": 1.1, **PAPER},
                     types=((1, 1),))
    ref = orbit_map([1.1], delta, types=((1, 1),), **PAPER)
    assert _same(ds["S"].sel(amplitude=1.0).values, ref["S"][:, 0])
    for i, a in enumerate(amplitude):
        for j, d in enumerate(delta):
            orbits = periodic_orbits(1, 1, 1.0 / 1.1, d / a, **PAPER)
            assert int(ds["n_stable"][0, i, j]) == sum(o.stable for o in orbits)
    # the shooting solver, at amplitude 2 itself: the stable (1/1) motion and its S
    i, j = 2, int(np.flatnonzero(delta == 1.0)[0])
    assert int(ds["n_stable"][0, i, j]) == 1
    motions = periodic_motions(Model.paper(0.05, 0.5, 1.0, 2.0, 1.0 / 1.1), 1).motions
    ones = [mo for mo in motions if mo.name == "(1,0)/1" and mo.stable]
    assert len(ones) == 1
    assert abs(ones[0].S - float(ds["S"][0, i, j])) <= S_TOL
    # its impact speed is A times the unit force's at delta / A
    unit = [o for o in periodic_orbits(1, 1, 1.0 / 1.1, 0.5, **PAPER) if o.stable][0]
    assert abs(ones[0].impact_velocity[0] - 2.0 * unit.velocities[0]) <= 1e-9


def test_two_walls_run_periodic_motions_per_cell():
    gap, inv_beta = [1.0, 3.0], [0.8]
    fixed = {"zeta": 0.05, "eps": 0.5, "delta": 0.5}
    ds = any_walls.orbit_plane("gap", gap, "inv_beta", inv_beta, fixed,
                               types=["(1,1)/1", (1, 0, 1)])
    assert ds.attrs["solver"] == "periodic_motions" and ds.attrs["n_walls"] == 2
    assert list(ds["type"].values) == ["(1,1)/1", "(1,0)/1"]
    for i, g in enumerate(gap):
        motions = periodic_motions(Model.paper(0.05, 0.5, 0.5, 1.0, 1.0 / 0.8, gap=g), 1)
        for t, name in enumerate(["(1,1)/1", "(1,0)/1"]):
            stable = [mo for mo in motions if mo.name == name and mo.stable and mo.admissible]
            assert int(ds["n_stable"][t, i, 0]) == len(stable)
    # symmetric stops (delta = gap / 2): the symmetric (1,1)/1 motion is stable; a far lower
    # wall leaves the one-wall (1/1) motion, the (1,0)/1
    assert int(ds["n_stable"].sel(type="(1,1)/1", gap=1.0)[0]) == 1
    assert int(ds["n_stable"].sel(type="(1,0)/1", gap=3.0)[0]) == 1
    one_wall = [o for o in periodic_orbits(1, 1, 1.0 / 0.8, 0.5, **PAPER) if o.stable]
    assert abs(float(ds["S"].sel(type="(1,0)/1", gap=3.0)[0]) - one_wall[0].S) <= S_TOL


@pytest.mark.parametrize("args, message", [
    (("rms", [0.1, 0.2], "delta", [0.0, 1.0], {"zeta": 0.05, "eps": 0.5, "inv_beta": 1.1}),
     r"a plane over 'rms' \(the random force's rms\) has no Fig. 16"),
    (("beta", [1.0], "delta", [0.0], PAPER),
     r"axis 'beta' is not a parameter of the harmonic-force problem.*the parameters: "),
    (("gap", [1.0], "delta", [0.0], {**PAPER, "inv_beta": 1.1, "rms": 0.3}),
     None),                                                   # rms fixed: accepted
    (("eps_lower", [0.5], "delta", [0.0], {**PAPER, "inv_beta": 1.1}),
     r"gap and eps_lower need a second wall"),
    (("eps", [0.5], "eps", [0.5], {"zeta": 0.05}), "the plane's two axes must differ"),
    (("eps", [1.5], "delta", [0.0], {"zeta": 0.05, "inv_beta": 1.1}),
     r"eps must be a finite real number in \[0, 1\], got 1.5"),
    (("amplitude", [0.0], "delta", [0.0], {**PAPER, "inv_beta": 1.1}),
     r"amplitude must be a finite real number > 0, got 0.0 \(the periodic motions"),
    (("eps", [0.5], "delta", [0.0], {"zeta": 0.05}), r"fixed must give \['inv_beta'\]"),
    (("eps", [0.5], "delta", [0.0], {"zeta": 0.05, "inv_beta": 1.1, "eps": 0.5}),
     r"\['eps'\] is on an axis of the plane and cannot be fixed too"),
    (("eps", [0.5], "delta", [0.0], {"zeta": 0.05, "inv_beta": 1.1, "kappa": 1}),
     r"fixed names \['kappa'\], not parameters"),
    (("eps", [], "delta", [0.0], {"zeta": 0.05, "inv_beta": 1.1}),
     "eps values must be a non-empty array"),
])
def test_errors_name_the_problem(args, message):
    if message is None:
        ds = any_walls.orbit_plane(*args, types=["(1,1)/1"])
        assert "rms" not in json.loads(ds.attrs["fixed"])     # the noise has no Fig. 16 part
        return
    with pytest.raises(ValueError, match=message):
        orbit_plane(*args)


def test_type_errors():
    fixed = {"zeta": 0.05, "inv_beta": 1.1}
    with pytest.raises(ValueError, match=r"types must be \(m, n\) pairs"):
        orbit_plane("eps", [0.5], "delta", [0.0], fixed, types=["(1,1)/1"])
    with pytest.raises(ValueError, match="named '\\(m_upper,m_lower\\)/n'"):
        any_walls.orbit_plane("eps", [0.5], "delta", [0.0], {**fixed, "gap": 1.0},
                              types=["1/1"])
    with pytest.raises(ValueError, match="solved by vibroimpact.attractors.plane.orbit_plane"):
        orbit_plane("eps", [0.5], "delta", [0.0], {**fixed, "gap": 1.0}, types=["(1,1)/1"])
    with pytest.raises(ValueError, match="at least one motion type"):
        orbit_plane("eps", [0.5], "delta", [0.0], fixed, types=[])


def test_tiles_over_the_other_axis_join_to_the_whole_plane():
    fixed = {"zeta": 0.05, "inv_beta": 1.1}
    eps = [0.2, 0.4, 0.6, 0.8]
    whole = orbit_plane("eps", eps, "delta", DELTA, fixed, types=TYPES)
    tiles = [orbit_plane("eps", eps[k::2], "delta", DELTA, fixed, types=TYPES)
             for k in range(2)]
    joined = xr.concat(tiles, dim="eps").sortby("eps")
    for name in VARIABLES:
        assert _same(joined[name].values, whole[name].values), name
