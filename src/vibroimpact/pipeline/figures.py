"""The figure table: which datasets each figure draws and which config keys are its options.

One table for the one figure rule (``draw_figure``): a figure's inputs are the datasets listed
under ``reads``, its drawing options come from its owner's config entry (keys listed under
``options``, figure-only keys that never reach a simulation) and from the figure's own item
in the entry's ``figures`` list. A figure that names a ``per`` parameter is drawn once per
listed value: the item ``{name: fig13, inv_beta: [0.8, 1.25]}`` gives the targets
``fig13-0`` and ``fig13-1`` (an index, never a float in a file name); a list of one value
keeps the plain name ``fig13``; a ``per`` figure listed by its name alone is drawn once per
value of its entry's grid of that parameter (:func:`per_values`). ``harmonic`` figures
(Figs. 10-15) need a study with a harmonic force (``amplitude != 0``). A figure that lists
``sources`` reads those datasets from the config entry its item names (``fig15_vs_fig16``
draws the map over the ``orbits`` entry given as ``{name: fig15_vs_fig16, orbits: harmonic}``).

``needs`` names the block of an ``orbits`` entry a figure draws from (``attractors``).
``also`` gives a figure drawn from an entry of another kind too: ``{kind: {reads, needs,
shows}}`` (the basins and Lyapunov maps of a study with a ``plane`` and an ``attractors``
block); :func:`figure_spec` resolves a figure for an entry's kind.

``draw`` names the function that draws the figure, ``"module:function"`` with the module
under `vibroimpact.plotting` (``"random:fig07"``), resolved by :func:`drawing_function` when
a job draws: the table is read at every workflow parse, which must not import matplotlib.
"""
import importlib
import re

from vibroimpact.pipeline.study import grid_values
from vibroimpact.reports import arguments

__all__ = ["FIGURES", "VALIDATION_FIGURES", "figure_spec", "drawing_function", "figure_targets",
           "figure_variant", "figure_options", "figure_item", "figure_sources", "paper_target",
           "caption", "rest_text", "per_values"]

FIGURES = {
    "fig03": dict(draw="random:fig03",
                  owner="study", reads=("trace",),
                  shows="a stretch of the random input r(tau) and the motion x(tau) of the mass "
                        "from rest, with the wall at delta"),
    "fig04": dict(draw="random:fig04",
                  owner="study", reads=("noise",),
                  shows="the autocorrelation of the random input, estimated from its record "
                        "against the target (paper eq. 8)"),
    "fig05": dict(draw="random:fig05",
                  owner="study", reads=("noise",),
                  shows="the power spectral density of the random input, estimated against "
                        "the target (paper eq. 9)"),
    "fig06": dict(draw="random:fig06",
                  owner="study", reads=("spectra",),
                  shows="the PSD of the acceleration a(tau) for several plays delta, with the "
                        "wall-free response |H|^2 S_f"),
    "fig07": dict(draw="random:fig07",
                  owner="study", reads=("events",), options=("density_delta", "envelope"),
                  shows="the probability density of the velocity after impact for several "
                        "plays delta"),
    "fig08": dict(draw="random:fig08",
                  owner="study", reads=("events",), options=("density_delta",),
                  shows="the probability density of the interval between impacts for several "
                        "plays delta"),
    "fig09": dict(draw="random:fig09",
                  owner="study", reads=("events",), options=("envelope",),
                  shows="the mean velocity after impact and the mean interval against delta, "
                        "with batch-means confidence bars, down to the play beyond which no "
                        "impact occurs"),
    "fig10": dict(draw="harmonic:fig10",
                  owner="study", reads=("trace",), harmonic=True,
                  shows="the input sin(beta_f tau) + r(tau) and the motion of the mass from rest"),
    "fig11": dict(draw="harmonic:fig11",
                  owner="study", reads=("spectra",), per="inv_beta", harmonic=True,
                  shows="the PSD of the input sin(beta_f tau) + r(tau): the random part and "
                        "the line of the harmonic force"),
    "fig12": dict(draw="harmonic:fig12",
                  owner="study", reads=("spectra",), per="inv_beta", harmonic=True,
                  shows="the PSD of the acceleration a(tau) under sin(beta_f tau) + r(tau) for "
                        "several plays delta"),
    "fig13": dict(draw="harmonic:fig13",
                  owner="study", reads=("events",), options=("density_delta",), per="inv_beta",
                  harmonic=True,
                  shows="the probability density of z_j/z (interval over forcing period) for "
                        "several plays delta: (1/1) at 1, (2/1) about 1/2, (1/2) at 2"),
    "fig14": dict(draw="harmonic:fig14",
                  owner="study", reads=("events",), options=("density_delta",), per="inv_beta",
                  harmonic=True,
                  shows="the probability density of the velocity after impact under "
                        "sin(beta_f tau) + r(tau) for several plays delta"),
    "fig15": dict(draw="maps:fig15",
                  owner="study", reads=("map",), harmonic=True,
                  shows="maps over the (1/beta_f, delta) plane of the probability (%) of the "
                        "(1/1), (2/1) and (1/2) impact motions under sin(beta_f tau) + r(tau)"),
    # map_orbits: the orbits at the map's own cells its agreement numbers read
    "fig15_vs_fig16": dict(draw="maps:fig15_vs_fig16",
                           owner="study", reads=("map", "orbits", "map_orbits"),
                           sources=("orbits",),
                           harmonic=True,
                           shows="the probability contours of Fig. 15 over the stable domains "
                                 "of Fig. 16, with the agreement measures of each motion"),
    "residence": dict(draw="maps:residence",
                      owner="study", reads=("map",), harmonic=True,
                      shows="the mean residence time (forcing periods) in each impact motion "
                            "and in no listed motion, over the (1/beta_f, delta) plane of "
                            "Fig. 15 under sin(beta_f tau) + r(tau); hatched cells hold few "
                            "complete stretches"),
    "fig16": dict(draw="orbits:fig16",
                  owner="orbits", reads=("orbits", "boundaries"),
                  shows="the domains over the (1/beta_f, delta) plane of stable periodic "
                        "(m/n) impact motions under sin(beta_f tau) alone, with contours of "
                        "the degree of stability S; their edges are the exact grazing, fold, "
                        "period-doubling and existence curves"),
    "basins": dict(draw="attractors:basins",
                   owner="orbits", reads=("basins", "orbits"), needs="attractors",
                   also={"study": dict(
                       reads=("plane_basins",), needs="attractors",
                       shows="the share of starting states that settle on each stable (m/n) "
                             "motion under A sin(beta_f tau) alone (its basin of attraction), "
                             "over the study's plane, cell for cell with its map")},
                   shows="the share of starting states that settle on each stable (m/n) "
                         "motion under sin(beta_f tau) alone (its basin of attraction), over "
                         "the (1/beta_f, delta) plane of Fig. 15"),
    "lyapunov": dict(draw="attractors:lyapunov",
                     owner="orbits", reads=("lyapunov",), needs="attractors",
                     also={"study": dict(
                         reads=("plane_lyapunov",), needs="attractors",
                         shows="the largest Lyapunov exponent under A sin(beta_f tau) alone "
                               "and what each cell's starts settle on, over the study's "
                               "plane")},
                     shows="the largest Lyapunov exponent under sin(beta_f tau) alone and what "
                           "each cell's starts settle on: a listed periodic motion, another "
                           "periodic motion, sticking, chaos"),
    "escape_vs_noise": dict(draw="escape:escape_vs_noise",
                            owner="study", reads=("escape",), harmonic=True,
                            shows="the mean residence time in each impact motion against "
                                  "1/rms^2 of the random force at a few cells of the "
                                  "(1/beta_f, delta) plane, with the fitted escape law "
                                  "ln T = ln C + Delta/rms^2"),
}

#: The figures of the validation targets (rule ``draw_validation_figure``), each drawn from
#: its one dataset.
VALIDATION_FIGURES = {
    "work_precision": dict(draw="validation:work_precision"),
    "stress": dict(draw="validation:stress"),
}


def figure_spec(name, kind):
    """The figure table's entry of figure ``name`` drawn from a ``kind`` entry (``"study"``
    or ``"orbits"``): its own, or its ``also[kind]`` over it; None when that kind does not
    draw it."""
    spec = FIGURES[name]
    if spec["owner"] == kind:
        return spec
    other = spec.get("also", {}).get(kind)
    return None if other is None else dict(spec, owner=kind, **other)


def drawing_function(name):
    """The function of `vibroimpact.plotting` that draws figure ``name`` (``fig07``, not
    ``fig13-1``; or a validation figure), from its ``draw`` in the tables above."""
    spec = FIGURES.get(name) or VALIDATION_FIGURES.get(name)
    if spec is None:
        raise ValueError(f"no figure {name!r}; the figures: "
                         f"{sorted(FIGURES) + sorted(VALIDATION_FIGURES)}")
    module, function = spec["draw"].split(":")
    return getattr(importlib.import_module(f"vibroimpact.plotting.{module}"), function)


_VARIANT = re.compile(r"^(?P<name>[a-z][a-z0-9_]*?)(-(?P<index>[0-9]+))?$")


def figure_variant(target):
    """``"fig13-1"`` -> ``("fig13", 1)``; ``"fig07"`` -> ``("fig07", None)``."""
    match = _VARIANT.match(target)
    if match is None:
        raise ValueError(f"figure target must look like fig07 or fig13-1, got {target!r}")
    index = match["index"]
    return match["name"], None if index is None else int(index)


def _item_name(item):
    return item if isinstance(item, str) else item["name"]


def figure_item(entry, name):
    """The item of ``entry["figures"]`` that asks for figure ``name`` (a mapping)."""
    for item in entry.get("figures", []):
        if _item_name(item) == name:
            return {"name": item} if isinstance(item, str) else dict(item)
    raise ValueError(f"figures: {name!r} is not listed; listed: "
                     f"{[_item_name(i) for i in entry.get('figures', [])]}")


def per_values(entry, item):
    """The values of a ``per`` figure's parameter: the item's list, or, for a figure listed
    by its name alone, every value of the entry's grid of that parameter (``fig14`` alone in
    a study with ``inv_beta: [0.5, 1.1]`` draws ``fig14-0`` and ``fig14-1``); None for a
    figure drawn once."""
    per = FIGURES[_item_name(item)].get("per")
    if per is None:
        return None
    if not isinstance(item, str) and per in item:
        return list(item[per])
    return [float(v) for v in grid_values(entry[per])] if per in entry else None


def figure_targets(entry):
    """Target names (``fig07``, ``fig13-0`` ...) of every figure an entry lists."""
    targets = []
    for item in entry.get("figures", []):
        name, values = _item_name(item), per_values(entry, item)
        if values is None or len(values) == 1:
            targets.append(name)
        else:
            targets += [f"{name}-{k}" for k in range(len(values))]
    return targets


def figure_options(entry, target):
    """Keyword options of the plotting function for ``target`` of a config entry.

    The figure's ``options`` keys of the entry, then the item's own keys (except ``name``);
    for a ``per`` figure, the parameter's value of this variant.
    """
    name, index = figure_variant(target)
    spec = FIGURES[name]
    options = {key: entry[key] for key in spec.get("options", ()) if entry.get(key)}
    item = figure_item(entry, name)
    options.update({k: v for k, v in item.items()
                    if k != "name" and k not in spec.get("sources", ())})
    per, values = spec.get("per"), per_values(entry, item)
    if values is not None:
        if index is None and len(values) == 1:
            index = 0       # one value: the plain name (fig11), no variant suffix
        if index is None or not 0 <= index < len(values):
            raise ValueError(f"figure {target!r}: {name} is drawn per {per}; "
                             f"give {name}-k with k in [0, {len(values) - 1}]")
        options[per] = values[index]
    elif index is not None:
        raise ValueError(f"figure {target!r}: {name} lists no {per or 'parameter'} values")
    return options


def figure_sources(entry, name):
    """``{dataset kind: config entry name}`` for the ``sources`` of figure ``name``."""
    sources = FIGURES[name].get("sources", ())
    if not sources:
        return {}
    item = figure_item(entry, name)
    missing = [k for k in sources if k not in item]
    if missing:
        raise ValueError(f"figures: {name} needs {missing} in its item, e.g. "
                         f"{{name: {name}, {missing[0]}: <entry>}}")
    return {k: item[k] for k in sources}


def paper_target(entry, name):
    """The target of ``entry`` that the paper figure ``name`` copies (its first variant)."""
    targets = [t for t in figure_targets(entry) if figure_variant(t)[0] == name]
    if not targets:
        raise ValueError(f"figures: {name!r} is not listed")
    return targets[0]


_PHYSICS_KEYS = ("zeta", "eps", "amplitude", "noise")


def _values_text(values):
    values = list(values) if isinstance(values, (list, tuple)) else values
    if isinstance(values, dict):
        return f"{values['start']:g} to {values['stop']:g} in steps of {values['step']:g}"
    if isinstance(values, list):
        return ", ".join(f"{v:.4g}" for v in values)
    return f"{values:.4g}" if isinstance(values, float) else str(values)


#: Characters with a meaning in reStructuredText inline markup (``|H|`` is a substitution,
#: ``*x*`` emphasis, ``name_`` a reference ...); a backslash makes each one literal.
_REST_SPECIAL = re.compile(r"([\\`*_|\[\]<>:])")


def rest_text(text):
    """``text`` as literal reStructuredText: every markup character backslash-escaped, so that
    docutils prints it as written (``|H|^2 S_f`` is not a substitution reference)."""
    return _REST_SPECIAL.sub(r"\\\1", str(text))


def _type_text(t):
    """``(m/n)``, or ``(m_upper,m_lower)/n`` for a two-wall type (as `stats.motions` names
    them; not imported here: reading a config loads no statistics)."""
    return f"({t[0]}/{t[1]})" if len(t) == 2 else f"({t[0]},{t[1]})/{t[2]}"


def caption(kind, name, entry, target):
    """What figure ``target`` of config entry ``name`` shows and with which parameters: one
    paragraph of reStructuredText, escaped (:func:`rest_text`), for the Snakemake report's
    caption (``workflow/report/figure.rst``).

    ``kind`` is ``"study"`` or ``"orbits"``.
    """
    fig, _ = figure_variant(target)
    number = fig[3:5].lstrip("0") if fig.startswith("fig") else fig
    what = (figure_spec(fig, kind) or FIGURES[fig])["shows"]
    plane = entry.get("plane")
    if plane:
        what = what.replace("the (1/beta_f, delta) plane", f"the ({plane[0]}, {plane[1]}) "
                            f"plane").replace("over the (1/beta_f, delta) plane of Fig. 15",
                                              f"over the ({plane[0]}, {plane[1]}) plane")
    title = {"fig15_vs_fig16": "Fig. 15 against Fig. 16", "basins": "Basins of attraction",
             "lyapunov": "Lyapunov exponents",
             "residence": "Residence times",
             "escape_vs_noise": "Escape against noise level"}.get(fig, f"Fig. {number}")
    parts = [f"{key} = {_values_text(entry[key])}" for key in _PHYSICS_KEYS if key in entry]
    if kind == "study" and entry.get("plane"):
        parts.insert(0, f"over the plane ({entry['plane'][0]}, {entry['plane'][1]}), every "
                        f"other parameter fixed")
    if kind == "study":
        if arguments.harmonic(entry) and "inv_beta" in entry:
            parts.append(f"1/beta_f = {_values_text(entry['inv_beta'])}")
        parts.append(f"delta = {_values_text(entry['delta'])}")
        options = figure_options(entry, target)
        if options:
            parts.append("drawn with " + ", ".join(f"{key} = {_values_text(value)}"
                                                   for key, value in options.items()))
    elif plane:
        parts = [f"{key} = {_values_text(entry[key])}"
                 for key in ("zeta", "eps", "eps_lower", "gap", "amplitude", "inv_beta",
                             "delta") if entry.get(key) is not None]
        if "amplitude" not in entry:
            parts.append("amplitude = 1")
        parts.append("types " + ", ".join(_type_text(t) for t in entry.get("types", [])))
    else:
        parts += [f"1/beta_f = {_values_text(entry['inv_beta'])}",
                  f"delta = {_values_text(entry['delta'])}",
                  "types " + ", ".join(_type_text(t) for t in entry.get("types", []))]
    sweep = entry.get("sweep")
    if sweep:
        parts.append(f"combination {sweep['index']} of sweep {sweep['name']}")
    return rest_text(f"{title} ({'orbits entry' if kind == 'orbits' else 'study'} {name}): "
                     f"{what}. Parameters: {'; '.join(parts)}.")
