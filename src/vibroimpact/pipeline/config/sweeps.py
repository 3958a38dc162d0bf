"""Sweeps: a study that lists values of zeta, eps, amplitude, rms or seed.

:func:`expand_sweeps` turns such a study into one ordinary study per combination of the
listed values, so everything after it (the schema, the checks, the plan, the workflow) sees
ordinary studies; :class:`Sweeps` restates an error about a generated study in the words of
the user's file (the sweep and its combination). :func:`drawn_sweeps` gives the sweeps whose
side-by-side figure ``rule all`` draws (`vibroimpact.pipeline.targets.sweep_targets`).
"""
import copy
from dataclasses import dataclass, field
import itertools
import math
import re

from vibroimpact.pipeline.config.messages import ConfigError, _num, _Problems, _short
from vibroimpact.pipeline.study import PLANE_PARAMETERS

__all__ = ["SWEEP_KEYS", "NOISE_KEYS", "Sweeps", "expand_sweeps", "sweep_label", "sweep_labels",
           "drawn_sweeps", "Member", "sweep_members"]

#: Study keys a list of values sweeps, in the order of the product: the first key varies
#: slowest, the last fastest (nested loops), so ``eps: [a, b]`` with ``rms: [c, d]`` gives
#: combinations 0-3 = (a, c), (a, d), (b, c), (b, d).
SWEEP_KEYS = ("zeta", "eps", "amplitude", "rms", "seed")
#: Of these, the keys that override the study's `noises` entry (a derived entry per value).
NOISE_KEYS = ("rms", "seed")
#: The rms of the record a study whose plane has the rms as an axis runs on: each cell scales
#: it by its rms (`pipeline.tasks.map_tile`), so every cell reads the same random numbers.
UNIT_RMS = 1.0
#: Combinations an error message lists before "...".
_LISTED = 6


def sweep_label(values, sep=" = "):
    """``"eps = 0.8, rms = 0.3"``: the values of one combination, in `SWEEP_KEYS` order."""
    def text(value):
        return _num(value) if isinstance(value, (int, float)) else _short(value)
    return ", ".join(f"{key}{sep}{text(value)}" for key, value in values.items())


def sweep_labels(sweep):
    """The labels of every combination of a ``config["sweeps"]`` record, in its order."""
    return [sweep_label(dict(zip(sweep["keys"], row))) for row in sweep["values"]]


@dataclass
class Sweeps:
    """What :func:`expand_sweeps` made: ``record`` (``config["sweeps"]``, by sweep name:
    ``studies``, ``keys``, ``values`` one row per study) and, for error messages, how each
    generated entry is named in the words of the user's file."""

    record: dict = field(default_factory=dict)
    studies: dict = field(default_factory=dict)     # "studies.s_2" -> ("s", 2)
    noises: dict = field(default_factory=dict)      # "noises.s_noise0" -> its label

    def _label(self, sweep, indices):
        n = len(self.record[sweep]["studies"])
        if len(indices) == 1:
            k = indices[0]
            values = dict(zip(self.record[sweep]["keys"], self.record[sweep]["values"][k]))
            return f"studies.{sweep} (combination {k}: {sweep_label(values, '=')})"
        if len(indices) == n:
            return f"studies.{sweep} (all {n} combinations)"
        return f"studies.{sweep} (combinations {_listed(indices)})"

    def relabel(self, err):
        """``err`` with each generated entry named by its sweep and combination; a problem
        that several combinations share is given once, naming them."""
        names = sorted([*self.studies, *self.noises], key=len, reverse=True)
        if not names:
            return err
        pattern = re.compile(r"(?<![\w.])(" + "|".join(map(re.escape, names)) + r")(?!\w)(\.?)")

        def name(match):
            path, dot = match.groups()
            if path in self.noises:
                label = self.noises[path]
            else:
                sweep, k = self.studies[path]
                label = self._label(sweep, [k])
            return label + (": " if dot else "")

        groups = {}     # problem with its combination left out -> the combinations, in order
        for problem in err.problems:
            first = pattern.search(problem)
            if first is None or first.group(1) not in self.studies:
                groups.setdefault((None, pattern.sub(name, problem)), [])
                continue
            sweep, k = self.studies[first.group(1)]
            key = (sweep, problem[:first.start()], first.group(2),
                   pattern.sub(name, problem[first.end():]))
            groups.setdefault(key, []).append(k)
        lines = []
        for (sweep, *parts), indices in groups.items():
            if sweep is None:
                lines.append(parts[0])
            else:
                head, dot, tail = parts
                lines.append(head + self._label(sweep, indices) + (": " if dot else "") + tail)
        return ConfigError(lines, details=err.details)


def _plane(entry):
    """The parameters a study's ``plane`` names that can be axes (grids, not sweeps), or ().
    A name no plane takes (``seed``) is no axis: the schema names the plane's mistake, and
    nothing reads the key as an axis meanwhile (a seed list was given the unit-rms value of
    an rms axis, and refused as "seed = 1.0"); such a plane sweeps nothing (`_swept`)."""
    plane = entry.get("plane")
    if not isinstance(plane, list):
        return ()
    return tuple(p for p in plane if p in PLANE_PARAMETERS)


def _swept(entry):
    """Whether a study entry is expanded: it lists a value of SWEEP_KEYS that is no axis of
    its plane, or overrides its noise (an rms axis too: its record is the unit-rms one)."""
    raw = entry.get("plane")
    if isinstance(raw, list) and any(p not in PLANE_PARAMETERS for p in raw):
        return False        # a misspelt axis (Eps): the schema names it; no sweep is meant
    plane = _plane(entry)
    return any(isinstance(entry.get(k), list) for k in SWEEP_KEYS if k not in plane) or any(
        k in entry for k in NOISE_KEYS)


def _axes(name, entry, problems, max_studies):
    """``{key: values}`` of the keys a study lists, or None after recording why not."""
    axes, ok = {}, True
    allowed_ = "a number, or a non-empty list of numbers (a sweep: one study per value)"
    plane = _plane(entry)
    for key in SWEEP_KEYS:
        if key not in entry or key in plane:     # an axis of the plane: a grid, no sweep
            continue
        value = entry[key]
        items = value if isinstance(value, list) else [value]
        if isinstance(value, list) and not value:
            problems.add(f"studies.{name}.{key}", value, "an empty list sweeps nothing", allowed_)
            ok = False
        elif any(isinstance(v, (list, dict)) for v in items):
            problems.add(f"studies.{name}.{key}", value, "not a number or a list of numbers",
                         allowed_)
            ok = False
        elif isinstance(value, list):
            repeated = sorted({_short(v) for i, v in enumerate(value) if v in value[:i]})
            if repeated:
                problems.add(f"studies.{name}.{key}", value, f"{', '.join(repeated)} listed "
                             f"more than once (identical studies)", "distinct values")
                ok = False
            axes[key] = value
    n = math.prod(len(v) for v in axes.values())
    if ok and max_studies is not None and n > max_studies:
        sizes = " x ".join(f"{len(v)} {k}" for k, v in axes.items())
        problems.add(f"studies.{name}", None, f"{sizes} = {n:,} combinations, a study each",
                     f"at most limits.max_jobs = {max_studies:,} combinations; shorten the "
                     f"lists or raise limits.max_jobs")
        ok = False
    return axes if ok else None


def _listed(indices):
    return ", ".join(map(str, indices[:_LISTED])) + (", ..." if len(indices) > _LISTED else "")


def _noise_label(name, override, indices, swept):
    if not swept:
        return f"studies.{name} (its noise: {sweep_label(override, '=')})"
    which = "combination" + ("s" if len(indices) > 1 else "")
    return f"studies.{name} (noise of {which} {_listed(indices)}: {sweep_label(override, '=')})"


def expand_sweeps(config, own=None, *, max_studies=None):
    """Expand, in place, every study that lists values into one study per combination.

    A study whose ``zeta``, ``eps``, ``amplitude``, ``rms`` or ``seed`` is a list (a
    *sweep*) becomes the studies ``<name>_0`` ... ``<name>_<N-1>``, one per combination of
    the listed values, in the order of `SWEEP_KEYS` (the first key slowest, the last
    fastest); each is a copy of the entry with one value per key and the key ``sweep:
    {name, index, values}`` (``values``: the listed keys' values of this combination).
    ``rms`` and ``seed`` override the study's ``noises`` entry: each distinct (rms, seed)
    pair that differs from the entry gets a copy of it, ``<name>_noise<j>`` (j in order of
    first use), shared by the combinations that use it and by any later study that needs
    the same copy of the same entry (two rms planes' unit-rms record: one file); the pair
    equal to the entry uses the entry itself (a list of rms alone keeps the entry's seed:
    the records differ only in scale, common random numbers). A study that only overrides
    rms or seed keeps its name.
    A parameter the study's ``plane`` names is an axis, not a sweep: its list (or
    ``{start, stop, step}``) stays in the study as the axis's grid; the rms as an axis gives
    the study its noise entry at unit rms (`UNIT_RMS`, a copy unless the entry has it).
    A study without lists or overrides is left as it is (the same dict).

    Parameters
    ----------
    config : dict
        The composed config (:func:`compose`), not yet validated.
    own : dict, optional
        ``{section: names}`` of the user's own entries (:func:`compose`), updated in place:
        a sweep of the user's is replaced by its studies, and its derived noises are added.
    max_studies : int, optional
        Largest number of combinations a sweep may have (``limits.max_jobs``).

    Returns
    -------
    Sweeps
        ``record`` for ``config["sweeps"]`` and the names of the generated entries, to
        restate an error about them in the user's words (:meth:`Sweeps.relabel`).

    Raises
    ------
    ConfigError
        A hand-written ``sweep`` key, an empty or nested list, too many combinations, or a
        generated name that is already taken (naming both).
    """
    sweeps = Sweeps()
    studies = config.get("studies")
    if not isinstance(studies, dict):
        return sweeps                           # the schema check names the problem
    noises = config["noises"] if isinstance(config.get("noises"), dict) else {}
    taken = {"studies": set(studies), "noises": set(noises)}
    problems, expanded, derived_noises, shared = _Problems(), {}, {}, {}
    for name, entry in studies.items():
        if isinstance(entry, dict) and "sweep" in entry:
            problems.add(f"studies.{name}.sweep", None, "set by the expansion of a sweep, "
                         "never by hand", "leave it out; list values under zeta, eps, "
                         "amplitude, rms or seed to sweep them")
            continue
        if not isinstance(entry, dict) or not _swept(entry):
            expanded[name] = entry
            continue
        axes = _axes(name, entry, problems, max_studies)
        if axes is None:
            continue
        noise = entry.get("noise")
        copies = _NoiseCopies(name, noises.get(noise) if isinstance(noise, str) else None,
                              taken["noises"], problems, shared,
                              noise if isinstance(noise, str) else None)
        made = _expand(name, entry, axes, copies, taken["studies"], problems, sweeps)
        expanded.update(made)
        derived_noises.update(copies.entries)
        if own is not None and name in own["studies"]:
            own["studies"].discard(name)
            own["studies"].update(_names(name, axes))
            own["noises"].update(copies.entries)
    if problems:
        raise ConfigError(problems)
    config["studies"] = expanded
    if derived_noises:
        config["noises"].update(derived_noises)
    return sweeps


def _names(name, axes):
    """The studies a sweep is expanded into, ``<name>_0`` ..., or ``[name]`` (no list)."""
    n = math.prod(len(v) for v in axes.values())
    return [f"{name}_{k}" for k in range(n)] if axes else [name]


def _expand(name, entry, axes, copies, taken, problems, sweeps):
    """``{study name: entry}`` of the combinations of study ``name`` (``axes``: the values of
    each listed key), recorded in ``sweeps``; a generated name already ``taken`` is recorded
    in ``problems`` instead."""
    combos = [dict(zip(axes, c)) for c in itertools.product(*axes.values())]
    names = _names(name, axes)
    made = {}
    for k, (study_name, values) in enumerate(zip(names, combos)):
        if axes and study_name in taken:
            problems.add(f"studies.{name}", None, f"its combination {k} "
                         f"({sweep_label(values, '=')}) would be named {study_name}, "
                         f"like the study studies.{study_name}",
                         f"rename the sweep or studies.{study_name}")
            continue
        taken.add(study_name)
        plane = _plane(entry)
        # the rms as an axis stays in the study (its grid); its record is the unit-rms one
        study = {key: copy.deepcopy(v) for key, v in entry.items()
                 if key not in NOISE_KEYS or key in plane}
        study.update({key: v for key, v in values.items() if key not in NOISE_KEYS})
        override = {key: UNIT_RMS if key in plane else values.get(key, entry[key])
                    for key in NOISE_KEYS if key in entry}
        noise = copies.noise(override, k)
        if noise is not None:
            study["noise"] = noise
        if axes:
            study["sweep"] = {"name": name, "index": k, "values": values}
            sweeps.studies[f"studies.{study_name}"] = (name, k)
        made[study_name] = study
    sweeps.noises.update(copies.labels(swept=bool(axes)))
    if axes:
        sweeps.record[name] = {"studies": names, "keys": list(axes),
                               "values": [list(c.values()) for c in combos]}
    return made


class _NoiseCopies:
    """The copies of a study's ``noises`` entry (``base``) that its ``rms`` and ``seed``
    call for: one per distinct (rms, seed) pair that differs from the entry, named
    ``<study>_noise<j>`` in order of first use and shared by the combinations that use it."""

    def __init__(self, study, base, taken, problems, shared=None, base_name=None):
        self.study, self.base, self.taken, self.problems = study, base, taken, problems
        # copies made for earlier studies, ``{(base_name, pair): noise name}``: a study that
        # needs the same record (e.g. two rms planes' unit-rms record) shares it
        self.shared = {} if shared is None else shared
        self.base_name = base_name
        self.names = {}         # (rms, seed) pair -> noise name
        self.entries = {}       # noise name -> its entry
        self.overrides = {}     # noise name -> {rms, seed} of its entry
        self.users = {}         # noise name -> the combinations that use it

    def noise(self, override, k):
        """The name of combination ``k``'s noise, or None when the entry itself serves."""
        if not isinstance(self.base, dict) or all(self.base.get(key) == value
                                                  for key, value in override.items()):
            return None
        pair = tuple(override.items())
        earlier = self.shared.get((self.base_name, pair))
        if pair not in self.names and earlier is not None:
            self.names[pair] = earlier          # another study's copy: the same record
            self.overrides[earlier] = override
        if pair not in self.names:
            name = f"{self.study}_noise{len(self.names)}"
            if name in self.taken:
                self.problems.add(f"studies.{self.study}", None, f"its noise for "
                                  f"{sweep_label(override, '=')} would be named {name}, "
                                  f"like the entry noises.{name}",
                                  f"rename the study or noises.{name}")
            self.taken.add(name)
            self.names[pair] = name
            self.entries[name] = dict(copy.deepcopy(self.base), **override)
            self.overrides[name] = override
            self.shared[(self.base_name, pair)] = name
        self.users.setdefault(self.names[pair], []).append(k)
        return self.names[pair]

    def labels(self, swept):
        """``{"noises.<name>": label}``: each copy in the words of the user's file."""
        return {f"noises.{name}": _noise_label(self.study, self.overrides[name], indices, swept)
                for name, indices in self.users.items()}


@dataclass(frozen=True)
class Member:
    """One study of a sweep: its name and its values of the swept keys (`sweep_members`)."""

    study: str
    values: dict


def sweep_members(config, name):
    """The studies of sweep ``name`` in the sweep's order, each with its values of the swept
    keys: a sweep over a plane's third parameter (``plane: [eps, delta]`` with ``zeta: [a,
    b]``) is the stack of maps ``[Member("<name>_0", {"zeta": a}), ...]`` that a figure
    sets side by side.

    Raises
    ------
    KeyError
        For a name that is no sweep of ``config`` (naming the sweeps there are).
    """
    sweeps = config.get("sweeps", {})
    if name not in sweeps:
        raise KeyError(f"no sweep {name!r}; the sweeps: {', '.join(sorted(sweeps)) or 'none'}")
    sweep = sweeps[name]
    return [Member(study, dict(zip(sweep["keys"], row)))
            for study, row in zip(sweep["studies"], sweep["values"])]


def drawn_sweeps(config, drawn):
    """Names of the sweeps whose studies are all among ``drawn["studies"]`` (:attr:`Plan.drawn`):
    `rule all` draws their side-by-side figures."""
    return sorted(name for name, sweep in config.get("sweeps", {}).items()
                  if set(sweep["studies"]) <= drawn["studies"])

