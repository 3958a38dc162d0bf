"""Fig. 16 over any plane of the harmonic-force problem's parameters.

`orbit_map` classifies the (m/n) motions over the ``(1/beta, delta)`` plane; `orbit_plane`
does it over any two of the parameters the periodic motions under ``A sin(beta tau)`` depend on:
``zeta``, ``eps``, ``delta``, ``inv_beta``, ``amplitude`` and, with a second wall, ``gap`` and
``eps_lower``. The random force's ``rms`` is not one of them: the periodic motions of Fig. 16
are those of the harmonic force alone, so a plane over the noise has no Fig. 16 (an error
says so).

Method
------
One wall, the closed-form solver (`vibroimpact.orbits.api`):

- A plane with ``delta`` on an axis: each value of the other axis is one column along delta,
  solved by `orbit_map` over that column (the global scan plus branch following along delta:
  the Fig. 16 algorithm). Over ``(inv_beta, delta)`` this *is* `orbit_map` (one call, rows in
  parallel), and the column of an ``(eps, delta)`` plane at the default eps is bit for bit the
  default map's column at the same 1/beta (`orbit_map`'s rows are independent).
- A plane without ``delta``: `periodic_orbits` at every cell (no branch to follow; its finer
  m = 3 scan).

The amplitude scales out. With ``x = A y`` (A > 0), ``x'' + 2 zeta x' + x = A sin(beta tau)``
becomes ``y'' + 2 zeta y' + y = sin(beta tau)``, the wall ``x = delta`` becomes ``y = delta /
A``, and the impact law ``y' -> -eps y'`` is unchanged (it is linear). An (m/n) motion at
``(A, delta)`` is therefore ``A`` times the one at ``(1, delta / A)``: same impact instants,
velocities times A, and the same one-period Jacobian up to the similarity ``diag(1, A)`` of
``(tau, u)``, hence the same multipliers, lam and S. A cell at amplitude A is solved at
``delta / A`` with the unit force. (A < 0 is the force shifted by half a period, A = 0 has no
impact motion: the amplitude must be > 0.)

Two walls: `vibroimpact.attractors.plane.orbit_plane` (the same call), Newton shooting on the
exact flow at every cell, whose seeds the simulator settles: it lives a floor up, beside the
shooting solver, so that a one-wall plane loads no simulator. This module holds what both
share (the checks, the classification of a cell, the dataset).
"""
from __future__ import annotations

import json
import math

import numpy as np

from vibroimpact import _checks
from vibroimpact._symbols import (HARMONIC_PARAMETERS, NOISE_PARAMETERS, PARAMETERS,
                                  TWO_WALL_PARAMETERS)
from vibroimpact.orbits.api import Reason, orbit_map, periodic_orbits

__all__ = ["orbit_plane", "plane_dataset", "check_plane", "classify",
           "HARMONIC_PARAMETERS", "TWO_WALL_PARAMETERS", "NOISE_PARAMETERS"]
#: Fixed values taken when `fixed` does not give them: Fig. 16's force is ``sin(beta tau)``.
DEFAULT_FIXED = {"amplitude": 1.0}
#: Variables of the result, as `orbit_map` returns them.
VARIABLES = ("exists", "n_solutions", "n_stable", "lam", "S", "reason")
#: Long names and units of the variables (CF), as the pipeline's orbit datasets write them.
META = {
    "exists": ("an admissible solution of the type exists (1) or not (0)", "1"),
    "n_solutions": ("number of admissible solutions of the type", "1"),
    "n_stable": ("number of stable admissible solutions of the type", "1"),
    "lam": ("smallest lambda = max|mu|^(1/m) among the admissible solutions", "1"),
    "S": ("degree of stability S = 100 (1 - lambda)", "%"),
    "reason": ("why no stable solution: 0 stable, 1 no solution (two walls: none found), "
               "2 inadmissible, 3 unstable", "1"),
}


def _check_value(name, value):
    """One parameter value checked against its allowed range (a message naming it)."""
    if name == "zeta":
        return _checks.zeta(value)
    if name in ("eps", "eps_lower"):
        return _checks.eps(value, name)
    if name in ("inv_beta", "gap"):
        return _checks.real(name, value, low=0.0, low_open=True)
    if name == "amplitude":
        try:
            return _checks.real(name, value, low=0.0, low_open=True)
        except ValueError as err:
            raise ValueError(f"{err} (the periodic motions of A sin(beta tau) are those of "
                             f"sin(beta tau) with delta / A for A > 0; A = 0 has none, A < 0 "
                             f"is a half-period shift: give |A|)") from None
    return _checks.real(name, value)


def _axis(name, values, allowed, two_walls):
    if not isinstance(name, str):
        raise ValueError(f"an axis is named by a parameter (str), got {name!r}")
    if name in NOISE_PARAMETERS:
        raise ValueError(f"a plane over {name!r} (the random force's rms) has no Fig. 16: the "
                         f"periodic motions are those of the harmonic force alone, which does "
                         f"not depend on the noise; Fig. 16 planes run over {list(allowed)}")
    if name not in allowed:
        extra = ("" if two_walls or name not in TWO_WALL_PARAMETERS
                 else " (gap and eps_lower need a second wall: give gap in fixed)")
        known = "" if name in PARAMETERS else f"; the parameters: {list(PARAMETERS)}"
        raise ValueError(f"axis {name!r} is not a parameter of the harmonic-force problem"
                         f"{extra}; Fig. 16 planes run over {list(allowed)}{known}")
    arr = np.ascontiguousarray(values, dtype=float).ravel()
    if arr.size == 0:
        raise ValueError(f"{name} values must be a non-empty array")
    for v in arr:
        _check_value(name, float(v))
    return arr


def _parse_types(types, two_walls):
    """``[(label, key)]``: one wall ``("1/1", (1, 1))``; two walls ``("(1,1)/1", "(1,1)/1")``."""
    if len(types) == 0:
        raise ValueError("types must hold at least one motion type")
    out = []
    for t in types:
        if two_walls:
            if isinstance(t, str):
                name = t.replace(" ", "")
            elif len(t) == 3:
                mu, ml, n = (_checks.integer("types", k, low=0) for k in t)
                name = f"({mu},{ml})/{n}"
            else:
                raise ValueError(f"a two-wall type is (m_upper, m_lower, n) or a name like "
                                 f"'(1,1)/1', got {t!r}")
            try:
                counts, n = name[1:].split(")/")
                mu, ml = (int(k) for k in counts.split(","))
                n = int(n)
            except ValueError:
                raise ValueError(f"a two-wall type is named '(m_upper,m_lower)/n', got "
                                 f"{t!r}") from None
            if not name.startswith("(") or n < 1 or mu + ml < 1 or min(mu, ml) < 0:
                raise ValueError(f"a two-wall type needs n >= 1 and at least one impact, "
                                 f"got {t!r}")
            out.append((f"({mu},{ml})/{n}", (mu, ml, n)))
        else:
            if isinstance(t, str) or len(t) != 2:
                raise ValueError(f"types must be (m, n) pairs, got {t!r}")
            m = _checks.integer("m", t[0], low=1)
            n = _checks.integer("n", t[1], low=1)
            out.append((f"{m}/{n}", (m, n)))
    return out


def _resolve(x_name, y_name, fixed):
    """The fixed parameters checked and completed (`DEFAULT_FIXED`), noise ones dropped."""
    if not isinstance(fixed, dict):
        raise ValueError(f"fixed must be a dict {{parameter: value}}, got {type(fixed).__name__}")
    unknown = sorted(set(fixed) - set(PARAMETERS))
    if unknown:
        raise ValueError(f"fixed names {unknown}, not parameters; the parameters: "
                         f"{list(PARAMETERS)}")
    on_axes = sorted({x_name, y_name} & set(fixed))
    if on_axes:
        raise ValueError(f"{on_axes} is on an axis of the plane and cannot be fixed too")
    out = {**DEFAULT_FIXED, **{k: v for k, v in fixed.items() if k not in NOISE_PARAMETERS}}
    for name in list(out):
        if name in (x_name, y_name):
            del out[name]
        else:
            out[name] = _check_value(name, out[name])
    return out


def orbit_plane(x_name, x_values, y_name, y_values, fixed, types=((1, 1), (2, 1), (1, 2)), *,
                progress=None):
    """Existence and stability of periodic impact motions over any plane (Fig. 16 analogue).

    Parameters
    ----------
    x_name, y_name : str
        The plane's axes, two different parameters among ``zeta``, ``eps``, ``delta``,
        ``inv_beta``, ``amplitude``. ``rms`` raises: a plane over the noise has no Fig. 16.
        A second wall (``gap`` on an axis or fixed; then also ``eps_lower``) raises here:
        `vibroimpact.attractors.plane.orbit_plane` solves it (same call).
    x_values, y_values : array_like, shape (nx,), (ny,)
        Values along each axis, each within its parameter's range (zeta in (0, 1), eps in
        [0, 1], inv_beta, amplitude and gap > 0).
    fixed : dict
        Every other parameter of the problem: ``zeta``, ``eps``, ``delta``, ``inv_beta`` unless
        on an axis; ``amplitude`` (default 1); ``gap`` for a second wall and ``eps_lower``
        (default eps). A fixed ``rms`` (the map study's noise) is accepted and ignored.
    types : sequence
        One wall: ``(m, n)`` pairs (m <= 3). Two walls: ``(m_upper, m_lower, n)`` triples or
        names ``"(1,1)/1"``.
    progress : callable, optional
        ``progress(k)`` as ``k`` more cells are solved (`orbit_map`'s).

    Returns
    -------
    xarray.Dataset
        ``exists`` (int8), ``n_solutions``, ``n_stable``, ``lam``, ``S``, ``reason`` (as
        `orbit_map`: `Reason` codes) over ``(type, x_name, y_name)``; coordinates ``type``
        (``"1/1"`` or ``"(1,1)/1"``) and the two axes; attributes ``axes`` (``[x_name,
        y_name]``), ``fixed`` (JSON of the fixed values used), each fixed value on its own,
        ``n_walls`` and ``solver``.

    Notes
    -----
    The module docstring: one column along delta per `orbit_map` call when delta is an axis
    (exactly `orbit_map` over ``(inv_beta, delta)``), `periodic_orbits` per cell otherwise,
    the amplitude scaled out (``delta / A``).

    Tiles: the columns along delta are independent, the cells along delta within one are not
    (branch following). A plane may be split into tiles over its other axis and the tiles
    joined, bit for bit the whole plane's result; a tile over delta gives other results near
    folds (the branches start again at its first delta).
    """
    xs, ys, fixed, parsed, two_walls = check_plane(x_name, x_values, y_name, y_values, fixed,
                                                   types)
    if two_walls:
        raise ValueError("a plane with a second wall (gap) is solved by "
                         "vibroimpact.attractors.plane.orbit_plane (Newton shooting seeded by "
                         "the simulator); this one is the one-wall closed form")
    if "delta" in (x_name, y_name):
        result = _columns(x_name, xs, y_name, ys, fixed, parsed, progress)
        solver = "orbit_map"
    else:
        result = _cells(x_name, xs, y_name, ys, fixed, parsed, progress)
        solver = "periodic_orbits"
    return plane_dataset(x_name, xs, y_name, ys, fixed, parsed, result, solver, n_walls=1)


def check_plane(x_name, x_values, y_name, y_values, fixed, types):
    """``(xs, ys, fixed, types, two_walls)`` of an `orbit_plane` call, checked: the axes'
    values as arrays, the fixed values completed (`DEFAULT_FIXED`, noise ones dropped), the
    types as ``[(label, key)]``; a ValueError naming the problem otherwise."""
    if x_name == y_name:
        raise ValueError(f"the plane's two axes must differ, got {x_name!r} twice")
    if not isinstance(fixed, dict):
        raise ValueError(f"fixed must be a dict {{parameter: value}}, got {type(fixed).__name__}")
    two_walls = "gap" in (x_name, y_name) or "gap" in fixed
    allowed = TWO_WALL_PARAMETERS if two_walls else HARMONIC_PARAMETERS
    xs = _axis(x_name, x_values, allowed, two_walls)
    ys = _axis(y_name, y_values, allowed, two_walls)
    fixed = _resolve(x_name, y_name, fixed)
    missing = [k for k in ("zeta", "eps", "delta", "inv_beta") if k not in fixed
               and k not in (x_name, y_name)]
    if missing:
        raise ValueError(f"fixed must give {missing}: every parameter of the harmonic-force "
                         f"problem that is not on an axis")
    if not two_walls and "eps_lower" in fixed:
        raise ValueError("eps_lower needs a second wall: give gap as well")
    return xs, ys, fixed, _parse_types(types, two_walls), two_walls


def plane_dataset(x_name, xs, y_name, ys, fixed, parsed, result, solver, n_walls):
    """The Dataset of `orbit_plane` from the arrays of `VARIABLES` (shape (types, nx, ny))."""
    import xarray as xr

    shape = (len(parsed), xs.size, ys.size)
    dims = ("type", x_name, y_name)
    ds = xr.Dataset({k: (dims, result[k].reshape(shape)) for k in VARIABLES},
                    coords={"type": [label for label, _ in parsed], x_name: xs, y_name: ys})
    ds["exists"] = ds["exists"].astype("int8")
    for name, (long_name, units) in META.items():
        ds[name].attrs.update(long_name=long_name, units=units)
    for name in (x_name, y_name):
        ds[name].attrs.update(long_name=PARAMETERS[name][2], units="1")
    ds["type"].attrs.update(long_name="impact motion (m/n)", units="1")
    ds.attrs.update({k: float(v) for k, v in fixed.items()})
    ds.attrs.update(axes=[x_name, y_name], fixed=json.dumps(fixed, sort_keys=True),
                    n_walls=n_walls, solver=solver)
    return ds


def empty(shape):
    return {"exists": np.zeros(shape, bool), "n_solutions": np.zeros(shape, np.int64),
            "n_stable": np.zeros(shape, np.int64), "lam": np.full(shape, np.nan),
            "reason": np.zeros(shape, np.int8)}


def finish(out):
    out["S"] = 100.0 * (1.0 - out["lam"])
    return out


def value_at(name, k_x, k_y, x_name, xs, y_name, ys, fixed):
    """A parameter's value at cell ``(k_x, k_y)``."""
    if name == x_name:
        return float(xs[k_x])
    if name == y_name:
        return float(ys[k_y])
    return float(fixed[name])


def _columns(x_name, xs, y_name, ys, fixed, parsed, progress=None):
    """One wall, delta on an axis: `orbit_map` along delta, one column per other value."""
    types = [key for _, key in parsed]
    swap = x_name == "delta"
    other, o_values = (y_name, ys) if swap else (x_name, xs)
    deltas = xs if swap else ys
    shape = (len(types), o_values.size, deltas.size)
    out = {}

    def put(k, res):
        for name in VARIABLES:
            out.setdefault(name, np.empty(shape, dtype=res[name].dtype))
            out[name][:, k] = res[name][:, 0]

    if other == "inv_beta":          # the Fig. 16 call itself: rows in parallel
        amp = fixed["amplitude"]
        res = orbit_map(o_values, deltas / amp, types=types, zeta=fixed["zeta"],
                        eps=fixed["eps"], progress=progress)
        for name in VARIABLES:
            out[name] = res[name]
    else:
        for k, v in enumerate(o_values):
            p = dict(fixed, **{other: float(v)})
            res = orbit_map([p["inv_beta"]], deltas / p["amplitude"], types=types,
                            zeta=p["zeta"], eps=p["eps"], progress=progress)
            put(k, res)
    if swap:                         # (type, other, delta) -> (type, delta, other)
        out = {k: np.swapaxes(v, 1, 2) for k, v in out.items()}
    return {k: np.ascontiguousarray(v) for k, v in out.items()}


def _cells(x_name, xs, y_name, ys, fixed, parsed, progress=None):
    """One wall, no delta axis: `periodic_orbits` at every cell."""
    shape = (len(parsed), xs.size, ys.size)
    out = empty(shape)
    for i in range(xs.size):
        for j in range(ys.size):
            p = {k: value_at(k, i, j, x_name, xs, y_name, ys, fixed)
                 for k in HARMONIC_PARAMETERS}
            for t, (_, (m, n)) in enumerate(parsed):
                orbits = periodic_orbits(m, n, 1.0 / p["inv_beta"], p["delta"] / p["amplitude"],
                                         p["zeta"], p["eps"], include_inadmissible=True)
                classify(out, (t, i, j), orbits, [o.admissible for o in orbits])
        if progress is not None:
            progress(ys.size)
    return finish(out)


def classify(out, idx, found, admissible):
    """Fill one cell of one type from its solutions (`Reason` as the map kernel does)."""
    adm = [o for o, a in zip(found, admissible) if a]
    n_stable = sum(bool(o.stable) for o in adm)
    out["exists"][idx] = bool(adm)
    out["n_solutions"][idx] = len(adm)
    out["n_stable"][idx] = n_stable
    out["lam"][idx] = min(o.lam for o in adm) if adm else math.nan
    out["reason"][idx] = (Reason.STABLE if n_stable else Reason.NO_SOLUTION if not found
                          else Reason.INADMISSIBLE if not adm else Reason.UNSTABLE)
