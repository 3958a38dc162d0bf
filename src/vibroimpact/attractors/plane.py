"""Fig. 16 over any plane, with one wall or two, under any impact law.

`orbit_plane` here is `vibroimpact.orbits.plane.orbit_plane` (same call, same dataset) that
also solves a layout with a second wall, or walls whose restitution falls with the impact
speed: Newton shooting on the exact flow (`vibroimpact.attractors.shooting.periodic_motions`)
at every cell, seeded by starts the simulator settles. It lives on this floor because the
shooting solver does (it runs the simulator); one wall under Newton's law is handed to the
closed form below, which loads no simulator.

With two walls the motions found are those whose basin the grid of starts meets (every stable
one in practice, docs/model.md 8.8); an unstable motion is found only when Newton happens to
converge on it. A type is named by its impacts on each wall, ``"(1,1)/1"``; ``reason`` 1 then
means "none found", not "none exists". The amplitude is passed to the model as it is (no
scaling needed: the flow is exact at any A).
"""
from __future__ import annotations

import math

import numpy as np

from vibroimpact.attractors.shooting import periodic_motions
from vibroimpact.model import Model
from vibroimpact.orbits import plane as one_wall
from vibroimpact.orbits.plane import (HARMONIC_PARAMETERS, NOISE_PARAMETERS,
                                      TWO_WALL_PARAMETERS)

__all__ = ["orbit_plane", "attractor_plane"]


def orbit_plane(x_name, x_values, y_name, y_values, fixed, types=((1, 1), (2, 1), (1, 2)), *,
                speed_scale=math.inf, speed_scale_lower=None, progress=None):
    """Existence and stability of periodic impact motions over any plane, any wall layout,
    any impact law.

    The parameters and the result are those of `vibroimpact.orbits.plane.orbit_plane`; with
    ``gap`` on an axis or in `fixed` (a second wall at ``delta - gap``, restitution
    ``eps_lower``, default eps) the types are ``(m_upper, m_lower, n)`` triples or names
    ``"(1,1)/1"``. ``speed_scale`` (and ``speed_scale_lower``, the second wall's) make a
    wall's restitution fall with the impact speed (`vibroimpact.model.Restitution`); ``inf``
    is Newton's law. With a second wall or such a law every cell is solved by
    `periodic_motions` for the types' n (one wall: a type ``(m, n)`` is the motion of m
    impacts in n periods); the dataset's ``solver`` is ``"periodic_motions"``. One wall
    under Newton's law is the closed form's call, unchanged. ``progress(k)``: as ``k`` more
    cells are solved.
    """
    xs, ys, fixed_, parsed, two_walls = one_wall.check_plane(x_name, x_values, y_name,
                                                             y_values, fixed, types)
    laws = {} if speed_scale == math.inf and speed_scale_lower is None else dict(
        speed_scale=speed_scale, speed_scale_lower=speed_scale_lower)
    if not two_walls and not laws:
        return one_wall.orbit_plane(x_name, x_values, y_name, y_values, fixed, types,
                                    progress=progress)
    shape = (len(parsed), xs.size, ys.size)
    out = one_wall.empty(shape)
    ns = sorted({key[-1] for _, key in parsed})
    on_plane = (x_name, y_name)
    names = TWO_WALL_PARAMETERS if two_walls else HARMONIC_PARAMETERS
    for i in range(xs.size):
        for j in range(ys.size):
            p = {k: one_wall.value_at(k, i, j, x_name, xs, y_name, ys, fixed_)
                 for k in names if k != "eps_lower"}
            walls = {}
            if two_walls:
                walls = dict(gap=p["gap"], eps_lower=(
                    one_wall.value_at("eps_lower", i, j, x_name, xs, y_name, ys, fixed_)
                    if "eps_lower" in on_plane or "eps_lower" in fixed_ else p["eps"]))
            model = Model.paper(p["zeta"], p["eps"], p["delta"], p["amplitude"],
                                1.0 / p["inv_beta"], **walls, **laws)
            motions = periodic_motions(model, ns).motions
            for t, (label, key) in enumerate(parsed):
                # two walls: the name "(m_upper,m_lower)/n"; one: m impacts in n periods
                found = [mo for mo in motions if (mo.name == label if two_walls
                                                  else (mo.m, mo.n) == key)]
                one_wall.classify(out, (t, i, j), found, [mo.admissible for mo in found])
        if progress is not None:
            progress(ys.size)
    ds = one_wall.plane_dataset(x_name, xs, y_name, ys, fixed_, parsed, one_wall.finish(out),
                                "periodic_motions", n_walls=2 if two_walls else 1)
    ds.attrs.update({k: float(v) for k, v in laws.items() if v is not None})
    return ds


#: The two parameters `vibroimpact.attractor_map` runs over in one call (its grid).
MAP_AXES = ("inv_beta", "delta")
#: The start-by-start arrays of an `attractor_map` result, each over ``(..., inv_beta,
#: delta)``; everything else in the result is a coordinate.
_ARRAYS = ("count", "stick_count", "fraction", "fraction_lo", "fraction_hi", "n_stable",
           "class_count", "cell_class", "lyapunov", "lyapunov_class", "lyapunov_start",
           "lyapunov_second_start", "lyapunov_stderr", "impact_rate", "impact_rate_lower",
           "settle_time", "motion_start", "class_start", "period_start",
           "impacts_lower_start")


def attractor_plane(x_name, x_values, y_name, y_values, fixed, types=None, *,
                    gap=(0.0, 4.0), velocity=(-4.0, 4.0), progress=None, **options):
    """Basins of attraction and Lyapunov exponents (`vibroimpact.attractor_map`) over any
    plane of the harmonic-force problem.

    Parameters
    ----------
    x_name, y_name : str
        Two different parameters among ``zeta``, ``eps``, ``delta``, ``inv_beta``,
        ``amplitude`` and, with a second wall, ``gap``, ``eps_lower``. ``rms`` raises: the
        attractors are those of the harmonic force alone.
    x_values, y_values : array_like
        The axes' values, each in its parameter's range (amplitude > 0).
    fixed : dict
        Every other parameter (`vibroimpact.orbits.plane.orbit_plane`'s ``fixed``: zeta,
        eps, delta, inv_beta unless on an axis; amplitude, default 1; gap for a second wall
        and eps_lower, default eps); a fixed ``rms`` is ignored.
    types : sequence of (m, n), optional
        The one-wall closed-form types matched (default `attractor_map`'s).
    gap, velocity : (low, high)
        The starts' box in the oscillator's own units: distance ``g`` from the wall at delta
        (``x0 = delta - g``) and velocity ``v0``; with a second wall ``gap[1]`` must not exceed
        any cell's clearance.
    progress : callable, optional
        ``progress(k)`` as ``k`` more cells are solved (`attractor_map`'s).
    **options
        ``n_starts``, ``max_time``, ``match_tol``, ``seed`` of `attractor_map`.

    Returns
    -------
    dict
        `attractor_map`'s result with its arrays over ``(..., x_name, y_name)`` in place of
        ``(..., inv_beta, delta)``, the coordinates ``x_name``, ``y_name`` (``inv_beta`` and
        ``delta`` only when on the plane), ``axes`` (``[x_name, y_name]``) and ``fixed``
        (the fixed values used, amplitude and every wall parameter included).

    Notes
    -----
    A cell's starts and orbits depend on its own parameters only (the Sobol starts are the
    same in every cell), so the plane is solved one `attractor_map` call per value of its
    axes that is not ``inv_beta`` or ``delta``: over ``(inv_beta, delta)`` one call, and the
    result is `attractor_map`'s bit for bit; over ``(eps, delta)`` one call per eps, whose
    column at an eps equals the ``(inv_beta, delta)`` map's column at that eps and the fixed
    1/beta, bit for bit; over a plane without either, one call per cell.

    The amplitude scales out as in `vibroimpact.orbits.plane`: with ``x = A y`` (A > 0) the
    cell at amplitude A is the unit-force cell at ``delta / A``, its starts' box and clearance
    divided by A (the same physical starts), the same exponents, rates and settling times.
    """
    for name in (x_name, y_name):
        if name in NOISE_PARAMETERS:
            raise ValueError(f"a plane over {name!r} (the random force's rms) has no basins "
                             f"or Lyapunov exponents: they are those of the harmonic force "
                             f"alone; attractor planes run over {list(TWO_WALL_PARAMETERS)}")
    two_walls = "gap" in (x_name, y_name) or "gap" in (fixed or {})
    dummy = [(1, 0, 1)] if two_walls else [(1, 1)]         # types are attractor_map's own
    xs, ys, fixed_, _, two_walls = one_wall.check_plane(x_name, x_values, y_name, y_values,
                                                        fixed, dummy)
    from vibroimpact.attractors.api import DEFAULT_TYPES, attractor_map

    types = DEFAULT_TYPES if types is None else types
    if two_walls and "eps_lower" not in (x_name, y_name) and "eps_lower" not in fixed_:
        fixed_["eps_lower"] = fixed_["eps"] if "eps" in fixed_ else None
    nx, ny = xs.size, ys.size
    on_map = [n for n in (x_name, y_name) if n in MAP_AXES]
    out, coords = {}, None

    def solve(i_cells, j_cells, p, ib, dd):
        """One attractor_map call over ``ib x dd`` at the parameters ``p``; its cells are the
        plane's ``(i_cells, j_cells)`` (arrays shaped like the call's grid)."""
        nonlocal coords
        amp = p["amplitude"]
        kw = dict(options, types=types, gap=tuple(float(g) / amp for g in gap),
                  velocity=tuple(float(v) / amp for v in velocity), progress=progress)
        if two_walls:
            kw.update(clearance=p["gap"] / amp,
                      eps_lower=p["eps"] if p.get("eps_lower") is None else p["eps_lower"])
        res = attractor_map(ib, np.asarray(dd, float) / amp, p["zeta"], p["eps"], **kw)
        coords = {k: res[k] for k in ("motions", "classes")}
        for name in _ARRAYS:
            a = res[name]
            if name not in out:
                out[name] = np.empty(a.shape[:-2] + (nx, ny), dtype=a.dtype)
            out[name][..., i_cells, j_cells] = a

    def params(i, j):
        return {k: (one_wall.value_at(k, i, j, x_name, xs, y_name, ys, fixed_)
                    if k in (x_name, y_name) or fixed_.get(k) is not None else None)
                for k in TWO_WALL_PARAMETERS}

    if len(on_map) == 2:                    # the map's own plane: one call
        ib, dd = (xs, ys) if x_name == "inv_beta" else (ys, xs)
        i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
        if x_name == "delta":
            i, j = i.T, j.T
        solve(i, j, params(0, 0), ib, dd)
    elif len(on_map) == 1:                  # one call per value of the other axis
        along = on_map[0]
        for k in range((ny if along == x_name else nx)):
            if along == x_name:             # a row of the plane along x
                i, j = np.arange(nx), np.full(nx, k)
                p = params(0, k)
            else:
                i, j = np.full(ny, k), np.arange(ny)
                p = params(k, 0)
            values = xs if along == x_name else ys
            if along == "inv_beta":
                solve(i[:, None], j[:, None], p, values, [p["delta"]])
            else:
                solve(i[None, :], j[None, :], p, [p["inv_beta"]], values)
    else:                                   # one call per cell
        for i in range(nx):
            for j in range(ny):
                p = params(i, j)
                solve(np.array([[i]]), np.array([[j]]), p, [p["inv_beta"]], [p["delta"]])
    used = {k: v for k, v in fixed_.items() if v is not None}
    return dict(out, **coords, **{x_name: xs, y_name: ys}, axes=[x_name, y_name],
                fixed=used)
