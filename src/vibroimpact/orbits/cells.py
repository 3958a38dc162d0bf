"""The periodic orbits of an orbit map's system at the cells of another map (Fig. 15's):
what finding 8, the predictors of P and Fig. 15 against Fig. 16 compare P with, cell for
cell (rule ``solve_map_orbits``, ``results/datasets/{study}_map_orbits.nc``).

A map's cells need not be the orbit map's: the paper's Fig. 15 has steps of 0.05, Fig. 16
of 0.02, so every other row and column of the map lies halfway between two orbit cells and
"the nearest orbit cell" is a tie broken by rounding. The orbits are therefore solved at
each map cell's own centre, by the orbit map's own solver and fixed parameters.
"""
import json

import numpy as np

from vibroimpact._plane import dataset_axes
from vibroimpact._symbols import PARAMETERS

__all__ = ["COMPLEX_CODES", "orbits_at_cells"]


def _grid_text(values):
    values = np.asarray(values, dtype=float)
    if values.size < 2:
        return ", ".join(f"{v:.4g}" for v in values)
    return f"{values[0]:.4g} to {values[-1]:.4g} ({values.size} values)"


def _on_grid(ds, motion_map, axes):
    """``ds`` with the map's coordinates; ValueError naming both grids unless its cells are
    the map's (same values to 1e-9 of the larger of 1 and the grid's largest magnitude, the
    config check's tolerance: `vibroimpact.pipeline.config.checks`)."""
    def scale(d):
        return max(1.0, float(np.abs(motion_map[d].values).max(initial=0.0)))

    same = all(d in ds.dims and ds.sizes[d] == motion_map.sizes[d]
               and np.allclose(ds[d].values, motion_map[d].values, rtol=0.0,
                               atol=1e-9 * scale(d))
               for d in axes)
    if not same:
        def grid(data):
            return ", ".join(f"{d} {_grid_text(data[d])}" if d in data.dims else f"no {d} axis"
                             for d in axes)
        raise ValueError(f"the two-wall orbit map's cells nearest to the map's ({grid(ds)}) "
                         f"are not the map's ({grid(motion_map)}): its orbits are read, not "
                         "solved, at the map's cells; give the orbits entry a grid that holds "
                         "them")
    return ds.assign_coords({d: motion_map[d].values for d in axes})


#: Codes of :func:`orbits_at_cells`' ``complex`` (int8; netCDF has no bool).
COMPLEX_CODES = ("1 complex pair of multipliers, 0 real, -1 not known (no stable orbit or "
                 "two walls)")


def _orbit_system(orbits, axes):
    """``(fixed, two_walls)`` of an orbit map: what its solver held fixed (``attrs["fixed"]``
    of a plane, else the paper's ``zeta``, ``eps``, ``amplitude``), and whether it has a
    second wall."""
    fixed = orbits.attrs.get("fixed")
    if fixed is not None:
        fixed = json.loads(fixed.decode() if isinstance(fixed, bytes) else fixed)
    else:
        fixed = {k: float(orbits.attrs[k]) for k in ("zeta", "eps", "amplitude", "gap",
                                                     "eps_lower") if k in orbits.attrs}
    fixed = {k: float(v) for k, v in fixed.items() if k not in axes}
    missing = [k for k in ("zeta", "eps") if k not in fixed and k not in axes]
    if missing:
        raise ValueError(f"the orbit map gives no {', '.join(missing)} (attrs): its orbits "
                         "cannot be solved at the map's cells")
    two_walls = ("gap" in fixed or "gap" in axes
                 or int(np.asarray(orbits.attrs.get("n_walls", 1))) == 2)
    return fixed, two_walls


def _complex_pairs(x_name, xs, y_name, ys, fixed, types, n_stable, S):
    """1 where the stable orbit :func:`orbits_at_cells` reports (the smallest lambda of
    `vibroimpact.orbits.periodic_orbits` at the cell, the one whose S is the map's to 1e-6)
    has a complex pair of multipliers, 0 where they are real, -1 where it is not found."""
    from vibroimpact.orbits.api import periodic_orbits

    out = np.full(n_stable.shape, -1, dtype=np.int8)
    for k, label in enumerate(types):
        m, n = (int(v) for v in label.split("/"))
        for i, j in zip(*np.nonzero(n_stable[k] > 0)):
            p = dict(fixed, **{x_name: float(xs[i]), y_name: float(ys[j])})
            amplitude = p.get("amplitude", 1.0)
            stable = [o for o in periodic_orbits(m, n, 1.0 / p["inv_beta"],
                                                 p["delta"] / amplitude, p["zeta"], p["eps"])
                      if o.stable]
            if not stable:
                continue
            best = min(stable, key=lambda o: o.lam)
            if abs(best.S - S[k, i, j]) <= 1e-6:
                out[k, i, j] = int(abs(best.multipliers[0].imag) > 0.0)
    return out


def orbits_at_cells(motion_map, orbits, progress=None):
    """The periodic orbits of ``orbits``' system at the centre of every cell of the map, for
    the motions both name: what finding 8 and the predictors compare P with, cell for cell.

    One wall: solved at the map's own cells by the solver of the orbit map itself
    (`vibroimpact.orbits.plane.orbit_plane`: Fig. 16's `orbit_map` over ``(1/beta_f,
    delta)``), with the orbit map's fixed parameters; never read at a nearby cell of its grid.
    Two walls (the shooting solver, seeded by the simulator): read from the orbit map,
    whose grid must then hold every map cell (to 1e-9).

    Parameters
    ----------
    motion_map : xarray.Dataset
        ``results/datasets/{study}_map.nc``: its plane and motions.
    orbits : xarray.Dataset
        ``results/orbits/{name}.nc`` of the same system.
    progress : callable, optional
        ``progress(k)`` as ``k`` more cells are solved (`orbit_plane`'s) or read.

    Returns
    -------
    xarray.Dataset or None
        Over ``(type, x, y)`` (the map's axes and values): ``n_stable``, ``S`` (NaN where no
        stable orbit), and ``complex`` (int8, `COMPLEX_CODES`: whether the stable orbit's
        multipliers are a complex pair, so that S does not depend on delta; one wall only).
        None when no motion of the map is in the orbit map.

    Raises
    ------
    ValueError
        Two walls and a map cell that is not an orbit-map cell (both grids named).
    """
    import xarray as xr

    axes = dataset_axes(motion_map)
    x_name, y_name = axes
    xs, ys = (np.asarray(motion_map[d].values, dtype=float) for d in axes)
    types = [str(m) for m in motion_map["motion"].values if str(m) in orbits["type"].values]
    if not types:
        return None
    fixed, two_walls = _orbit_system(orbits, axes)
    if two_walls:
        # the orbit-map cells nearest to the map's: refused unless they are the map's own
        o = _on_grid(orbits.sel({x_name: xs, y_name: ys}, method="nearest"), motion_map, axes)
        o = o.sel(type=types).transpose("type", x_name, y_name)
        n_stable, S = o["n_stable"].values, o["S"].values
        complex_ = np.full(n_stable.shape, -1, dtype=np.int8)
        solver = "read from the orbit map (two walls)"
        if progress is not None:
            progress(xs.size * ys.size)
    else:
        from vibroimpact.orbits.plane import orbit_plane

        solved = orbit_plane(x_name, xs, y_name, ys, dict(fixed),
                             types=[tuple(int(v) for v in t.split("/")) for t in types],
                             progress=progress)
        solved = solved.transpose("type", x_name, y_name)
        n_stable, S = solved["n_stable"].values, solved["S"].values
        complex_ = _complex_pairs(x_name, xs, y_name, ys, fixed, types, n_stable, S)
        solver = str(solved.attrs.get("solver", "orbit_plane"))
    S = np.where(n_stable > 0, S, np.nan)
    dims = ("type", x_name, y_name)
    ds = xr.Dataset({"n_stable": (dims, np.asarray(n_stable, dtype=np.int64)),
                     "S": (dims, S), "complex": (dims, complex_)},
                    coords={"type": types, x_name: motion_map[x_name].values,
                            y_name: motion_map[y_name].values})
    ds["n_stable"].attrs.update(long_name="stable orbits at the cell's centre", units="1")
    ds["S"].attrs.update(long_name="degree of stability at the cell's centre", units="%")
    ds["complex"].attrs.update(long_name="multipliers a complex pair", units="1",
                               codes=COMPLEX_CODES)
    ds["type"].attrs.update(long_name="impact motion (m/n)", units="1")
    for name in axes:      # the map's words for its axes, else orbit_plane's (dimensionless)
        words = motion_map[name].attrs
        ds[name].attrs.update(long_name=words.get("long_name") or PARAMETERS[name][2],
                              units=words.get("units") or "1")
    ds.attrs.update(solver=solver, fixed=json.dumps(fixed, sort_keys=True))
    if "axes" in motion_map.attrs:
        ds.attrs["axes"] = json.dumps(list(axes))
    return ds
