"""Fig. 16 over any plane, with one wall or two (issue 36).

`orbit_plane` here is `vibroimpact.orbits.plane.orbit_plane` (same call, same dataset) that
also solves a layout with a second wall: Newton shooting on the exact flow
(`vibroimpact.attractors.shooting.periodic_motions`) at every cell, seeded by starts the
simulator settles. It lives on this floor because the shooting solver does (it runs the
simulator); a one-wall plane is handed to the closed form below, which loads no simulator.

With two walls the motions found are those whose basin the grid of starts meets (every stable
one in practice, docs/model.md 8.8); an unstable motion is found only when Newton happens to
converge on it. A type is named by its impacts on each wall, ``"(1,1)/1"``; ``reason`` 1 then
means "none found", not "none exists". The amplitude is passed to the model as it is (no
scaling needed: the flow is exact at any A).
"""
from __future__ import annotations

from vibroimpact.attractors.shooting import periodic_motions
from vibroimpact.model import Model
from vibroimpact.orbits import plane as one_wall
from vibroimpact.orbits.plane import TWO_WALL_PARAMETERS

__all__ = ["orbit_plane"]


def orbit_plane(x_name, x_values, y_name, y_values, fixed, types=((1, 1), (2, 1), (1, 2))):
    """Existence and stability of periodic impact motions over any plane, any wall layout.

    The parameters and the result are those of `vibroimpact.orbits.plane.orbit_plane`; with
    ``gap`` on an axis or in `fixed` (a second wall at ``delta - gap``, restitution
    ``eps_lower``, default eps) the types are ``(m_upper, m_lower, n)`` triples or names
    ``"(1,1)/1"`` and every cell is solved by `periodic_motions` for the types' n; the
    dataset's ``solver`` is ``"periodic_motions"`` and ``n_walls`` 2. Without a second wall
    the call is the one-wall closed form's, unchanged.
    """
    xs, ys, fixed_, parsed, two_walls = one_wall.check_plane(x_name, x_values, y_name,
                                                             y_values, fixed, types)
    if not two_walls:
        return one_wall.orbit_plane(x_name, x_values, y_name, y_values, fixed, types)
    shape = (len(parsed), xs.size, ys.size)
    out = one_wall.empty(shape)
    ns = sorted({key[2] for _, key in parsed})
    on_plane = (x_name, y_name)
    for i in range(xs.size):
        for j in range(ys.size):
            p = {k: one_wall.value_at(k, i, j, x_name, xs, y_name, ys, fixed_)
                 for k in TWO_WALL_PARAMETERS if k != "eps_lower"}
            eps_lower = (one_wall.value_at("eps_lower", i, j, x_name, xs, y_name, ys, fixed_)
                         if "eps_lower" in on_plane or "eps_lower" in fixed_ else p["eps"])
            model = Model.paper(p["zeta"], p["eps"], p["delta"], p["amplitude"],
                                1.0 / p["inv_beta"], gap=p["gap"], eps_lower=eps_lower)
            motions = periodic_motions(model, ns).motions
            for t, (label, _) in enumerate(parsed):
                found = [mo for mo in motions if mo.name == label]
                one_wall.classify(out, (t, i, j), found, [mo.admissible for mo in found])
    return one_wall.plane_dataset(x_name, xs, y_name, ys, fixed_, parsed,
                                  one_wall.finish(out), "periodic_motions", n_walls=2)
