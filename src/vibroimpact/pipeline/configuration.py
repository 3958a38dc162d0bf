"""The workflow's config: read, layered, checked and costed before any job runs.

One place for everything that can be known about a config before a simulation starts, so
that a bad value stops the build at once with a message of one or two lines naming the key
path, the value and the allowed range, instead of failing minutes into a build:

- :func:`read_yaml` reads a config file; a syntax error names the file, line and column.
- :func:`compose` layers a user's file on the paper's config (``config/config.yaml``): its
  entries are added; an entry named like a paper entry but different is refused unless the
  file lists it under ``replace`` (it would overwrite the paper's results); with
  ``paper: false`` only the file's own entries are built (the paper's stay available by
  name, e.g. a noise record or an orbits map).
- :func:`expand_sweeps` turns a study that lists values of zeta, eps, amplitude, rms or
  seed (a sweep) into one ordinary study per combination, so everything after it sees
  ordinary studies; an error about one names the sweep and its combination.
- :func:`check` validates against ``config/schema.yaml`` (filling defaults), rejects
  non-finite numbers (JSON Schema lets ``.nan`` through), checks every cross-field
  relation (records, grids, figures and the blocks they need), and returns the
  :class:`Plan`: cells, jobs, disk and a rough CPU time, refused beyond ``limits``.

The Snakefile and the ``python -m vibroimpact`` entry point both call :func:`load`, so a
dry run, a build and the plan see the same config and the same errors.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
import itertools
import math
import os
from pathlib import Path
import re

import numpy as np
import yaml

from vibroimpact.pipeline import figures
from vibroimpact.pipeline.study import grid_size, grid_values, map_cap_steps

__all__ = ["ConfigError", "Plan", "Sweeps", "read_yaml", "compose", "expand_sweeps", "check",
           "load", "drawn_sweeps", "sweep_figures", "sweep_label", "sweep_labels", "SECTIONS",
           "SWEEP_KEYS"]

#: Sections whose entries are named; a user's entry replaces a paper entry whole.
SECTIONS = ("noises", "studies", "orbits", "paper_figures")

#: Relative tolerance for "on the grid" (a value written as 1/1.1 matches 0.9090909091).
GRID_RTOL = 1e-6

#: Environment variable asking for the full schema validator output after the short one.
VERBOSE_ENV = "VIBROIMPACT_VERBOSE"


class ConfigError(ValueError):
    """A config that cannot be built; ``str()`` is one or two lines per problem."""

    def __init__(self, problems, details=None):
        self.problems = list(problems) if not isinstance(problems, str) else [problems]
        self.details = details
        text = "\n".join(self.problems)
        if details and os.environ.get(VERBOSE_ENV):
            text += "\n\n" + details
        super().__init__(text)


# --- reading and layering ---------------------------------------------------------------------

#: Values a config may hold once YAML aliases are expanded (the paper's config holds ~600);
#: a file beyond it (nested aliases: a "billion laughs") is refused before anything walks it.
MAX_VALUES = 1_000_000


class _StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a key given twice in one mapping (PyYAML keeps the
    last silently), naming both lines."""

    def construct_mapping(self, node, deep=False):
        seen = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue
            key = self.construct_object(key_node, deep=True)
            try:
                first = seen.get(key)
            except TypeError:
                continue                    # an unhashable key: the base class says so
            if first is not None:
                raise yaml.constructor.ConstructorError(
                    None, None, f"the key {key!r} is given twice in one mapping (first on "
                    f"line {first + 1}); YAML keeps one silently: delete or rename the other",
                    key_node.start_mark)
            seen[key] = key_node.start_mark.line
        return super().construct_mapping(node, deep=deep)


def expanded_size(value, limit=MAX_VALUES):
    """Number of values in ``value`` with every shared (aliased) part counted each time it
    is used, as code that walks it meets them; counting stops above ``limit``."""
    sizes = {}

    def size(v):
        if not isinstance(v, (dict, list)):
            return 1
        if id(v) not in sizes:
            sizes[id(v)] = 0            # a self-referencing alias counts as one value
            items = v.values() if isinstance(v, dict) else v
            total = 1
            for item in items:
                total += size(item)
                if total > limit:
                    break
            sizes[id(v)] = total
        return sizes[id(v)]

    return size(value)


def check_size(value, where):
    """Refuse ``value`` (a config read from ``where``) that expands beyond `MAX_VALUES`."""
    n = expanded_size(value)
    if n > MAX_VALUES:
        raise ConfigError(f"{where}: its YAML aliases (*name) expand to more than "
                          f"{MAX_VALUES:,} values (nested aliases repeat a part many times); "
                          f"allowed: a config of up to {MAX_VALUES:,} values, written out or "
                          f"with aliases used a few times")


def read_yaml(path, *, user=True):
    """The mapping in a YAML config file.

    A syntax error or a key given twice names the file, line and column; an empty file, a
    file that holds no mapping or whose aliases expand beyond `MAX_VALUES` names the file.
    ``user=False`` (the project's own files) lets an empty file through as ``{}``.
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as err:
        raise ConfigError(f"{path}: cannot read the config file ({err.strerror})") from None
    except UnicodeDecodeError as err:
        line = err.object[:err.start].count(b"\n") + 1
        raise ConfigError(f"{path}:{line}: not UTF-8 text (byte 0x{err.object[err.start]:02x}); "
                          f"allowed: a YAML file saved as UTF-8") from None
    try:
        data = yaml.load(text, Loader=_StrictLoader)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path)
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        context = getattr(err, "context", None)
        duplicate = isinstance(err, yaml.constructor.ConstructorError)
        kind = "YAML" if duplicate else "YAML syntax error"
        raise ConfigError(f"{where}: {kind}: {problem}"
                          + (f" ({context})" if context else "")) from None
    if data is None and user:
        raise ConfigError(f"{path}: the config file is empty (or only comments); allowed: a "
                          f"mapping of sections, e.g. studies: {{...}} (README, \"Your own "
                          f"studies\")")
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config file holds a mapping of keys (noises, studies, "
                          f"...), got a {type(data).__name__}")
    check_size(data, path)
    return data


def _replaced(user, section, name):
    replace = user.get("replace", False)
    if replace is True:
        return True
    return isinstance(replace, list) and f"{section}.{name}" in replace


def compose(paper, user):
    """``(config, own)``: the paper's config with a user's layered on, and what is built.

    ``own`` is ``None`` when everything is built (no user file, or ``paper: true``), else
    ``{section: names}`` of the user's own entries (``paper: false``).

    Raises
    ------
    ConfigError
        If a user entry would overwrite a different paper entry without being listed under
        ``replace``, or ``replace`` names no user entry.
    """
    if not user:
        return copy.deepcopy(paper), None
    replace = user.get("replace", False)
    if not isinstance(replace, (bool, list)):
        raise ConfigError(f"replace = {_short(replace)}: not allowed; allowed: true, or a list "
                          f"of section.name, e.g. replace: [studies.random]")
    config = copy.deepcopy(paper)
    problems = []
    for key, value in user.items():
        if key not in SECTIONS:
            config[key] = copy.deepcopy(value)      # paper, replace, limits: the user's
    config.setdefault("paper", True)
    for section in SECTIONS:
        mine = user.get(section)
        if mine is None:
            continue
        if not isinstance(mine, dict) or not isinstance(config.get(section, {}), dict):
            config[section] = copy.deepcopy(mine)     # the schema check names the problem
            continue
        merged = config.setdefault(section, {})
        for name, entry in mine.items():
            if name in merged and merged[name] != entry and not _replaced(user, section, name):
                problems.append(
                    f"{section}.{name}: the paper's config (config/config.yaml) has an entry "
                    f"of this name; yours differs and would overwrite its results.\n"
                    f"  Rename yours, or list it to replace the paper's: "
                    f"replace: [{section}.{name}] (or replace: true)")
            merged[name] = copy.deepcopy(entry)
    replace = user.get("replace")
    if isinstance(replace, list):
        for item in replace:
            section, _, name = str(item).partition(".")
            if section not in SECTIONS or name not in (user.get(section) or {}):
                problems.append(f"replace: {item!r} names no entry of your file; allowed: "
                                f"<section>.<name> with section in {list(SECTIONS)}")
    if problems:
        raise ConfigError(problems)
    own = None
    if user.get("paper", True) is False:
        own = {s: set(user.get(s) or {}) if isinstance(user.get(s), dict) else set()
               for s in SECTIONS}
    return config, own


# --- sweeps: a study listing values -----------------------------------------------------------

#: Study keys a list of values sweeps, in the order of the product: the first key varies
#: slowest, the last fastest (nested loops), so ``eps: [a, b]`` with ``rms: [c, d]`` gives
#: combinations 0-3 = (a, c), (a, d), (b, c), (b, d).
SWEEP_KEYS = ("zeta", "eps", "amplitude", "rms", "seed")
#: Of these, the keys that override the study's `noises` entry (a derived entry per value).
NOISE_KEYS = ("rms", "seed")
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


def _swept(entry):
    """Whether a study entry is expanded: it lists a value of SWEEP_KEYS or overrides its noise."""
    return any(isinstance(entry.get(k), list) for k in SWEEP_KEYS) or any(
        k in entry for k in NOISE_KEYS)


def _axes(name, entry, problems, max_studies):
    """``{key: values}`` of the keys a study lists, or None after recording why not."""
    axes, ok = {}, True
    allowed_ = "a number, or a non-empty list of numbers (a sweep: one study per value)"
    for key in SWEEP_KEYS:
        if key not in entry:
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
    first use), shared by the combinations that use it; the pair equal to the entry uses the
    entry itself (a list of rms alone keeps the entry's seed: the records differ only in
    scale, common random numbers). A study that only overrides rms or seed keeps its name.
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
    problems, expanded, derived_noises = _Problems(), {}, {}
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
        combos = [dict(zip(axes, c)) for c in itertools.product(*axes.values())]
        names = [f"{name}_{k}" for k in range(len(combos))] if axes else [name]
        noise = entry.get("noise")
        base = noises.get(noise) if isinstance(noise, str) else None
        derived, users = {}, {}     # (rms, seed) pair -> noise name; noise name -> combinations
        for k, (study_name, values) in enumerate(zip(names, combos)):
            if axes and study_name in taken["studies"]:
                problems.add(f"studies.{name}", None, f"its combination {k} "
                             f"({sweep_label(values, '=')}) would be named {study_name}, "
                             f"like the study studies.{study_name}",
                             f"rename the sweep or studies.{study_name}")
                continue
            taken["studies"].add(study_name)
            study = {key: copy.deepcopy(v) for key, v in entry.items() if key not in NOISE_KEYS}
            study.update({key: v for key, v in values.items() if key not in NOISE_KEYS})
            override = {key: values.get(key, entry[key]) for key in NOISE_KEYS if key in entry}
            if isinstance(base, dict) and any(base.get(key) != value
                                              for key, value in override.items()):
                pair = tuple(override.items())
                if pair not in derived:
                    derived[pair] = f"{name}_noise{len(derived)}"
                    if derived[pair] in taken["noises"]:
                        problems.add(f"studies.{name}", None, f"its noise for "
                                     f"{sweep_label(override, '=')} would be named "
                                     f"{derived[pair]}, like the entry noises.{derived[pair]}",
                                     f"rename the study or noises.{derived[pair]}")
                    taken["noises"].add(derived[pair])
                    derived_noises[derived[pair]] = dict(copy.deepcopy(base), **override)
                    sweeps.noises[f"noises.{derived[pair]}"] = override
                study["noise"] = derived[pair]
                users.setdefault(derived[pair], []).append(k)
            if axes:
                study["sweep"] = {"name": name, "index": k, "values": values}
                sweeps.studies[f"studies.{study_name}"] = (name, k)
            expanded[study_name] = study
        for noise_name, indices in users.items():
            override = sweeps.noises[f"noises.{noise_name}"]
            sweeps.noises[f"noises.{noise_name}"] = _noise_label(name, override, indices,
                                                                 bool(axes))
        if axes:
            sweeps.record[name] = {"studies": names, "keys": list(axes),
                                   "values": [list(c.values()) for c in combos]}
        if own is not None and name in own["studies"]:
            own["studies"].discard(name)
            own["studies"].update(names)
            own["noises"].update(derived.values())
    if problems:
        raise ConfigError(problems)
    config["studies"] = expanded
    if derived_noises:
        config["noises"].update(derived_noises)
    return sweeps


def drawn_sweeps(config, drawn):
    """Names of the sweeps whose studies are all among ``drawn["studies"]`` (:attr:`Plan.drawn`):
    `rule all` draws their side-by-side figures."""
    return sorted(name for name, sweep in config.get("sweeps", {}).items()
                  if set(sweep["studies"]) <= drawn["studies"])


def sweep_figures(config, drawn):
    """``results/figures/<sweep>/sweep.png`` of every sweep :func:`drawn_sweeps` gives."""
    return [f"results/figures/{name}/sweep.png" for name in drawn_sweeps(config, drawn)]


# --- schema validation with short messages ----------------------------------------------------

def _path(parts):
    text = ""
    for p in parts:
        text += f"[{p}]" if isinstance(p, int) else (f".{p}" if text else str(p))
    return text or "<top level>"


def _num(x):
    return f"{x:g}" if isinstance(x, float) else str(x)


def allowed(schema):
    """The allowed values of a schema node, in words (``a number > 0 and < 1``)."""
    if "$ref" in schema:
        schema = {**_resolve(schema["$ref"]), **{k: v for k, v in schema.items() if k != "$ref"}}
    if "enum" in schema:
        return "one of " + ", ".join(map(str, schema["enum"]))
    if "oneOf" in schema:
        return schema.get("description") or " or ".join(allowed(s) for s in schema["oneOf"])
    types = schema.get("type")
    types = [types] if isinstance(types, str) else list(types or [])
    null = "null" in types
    types = [t for t in types if t != "null"]
    kind = types[0] if types else None
    bounds = []
    for key, op in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                    ("exclusiveMaximum", "<")):
        if key in schema:
            bounds.append(f"{op} {_num(schema[key])}")
    if kind in ("number", "integer"):
        text = ("an integer" if kind == "integer" else "a finite number")
        text += (" " + " and ".join(bounds)) if bounds else ""
    elif kind == "string":
        text = "a string" + (f" matching {schema['pattern']}" if "pattern" in schema else "")
    elif kind == "boolean":
        text = "true or false"
    elif kind == "array":
        text = "a list"
        if "minItems" in schema:
            text += f" of at least {schema['minItems']} item(s)"
    elif kind == "object":
        props = list(schema.get("properties", {}))
        text = "a mapping" + (f" with keys {', '.join(props)}" if props else " of named entries")
    else:
        text = "a value"
    if null:
        text += ", or null"
    return text


_SCHEMA = {}


def _resolve(ref):
    node = _SCHEMA["root"]
    for part in ref.lstrip("#/").split("/"):
        node = node[part]
    return node


def _schema_at(parts):
    """The schema node describing the config value at ``parts`` (best effort)."""
    node = _SCHEMA["root"]
    for p in parts:
        while "$ref" in node:
            node = _resolve(node["$ref"])
        if "oneOf" in node:
            branch = [b for b in node["oneOf"]
                      if (b.get("type") == "array") == isinstance(p, int)]
            node = branch[0] if branch else node["oneOf"][0]
            while "$ref" in node:
                node = _resolve(node["$ref"])
        if isinstance(p, int):
            node = node.get("items", {})
        elif p in node.get("properties", {}):
            node = node["properties"][p]
        elif isinstance(node.get("additionalProperties"), dict):
            node = node["additionalProperties"]
        else:
            return {}
    while "$ref" in node:
        node = _resolve(node["$ref"])
    return node


def _scalar(node):
    """The number branch of a number-or-list node (``zeta``: a value or a sweep), else ``node``."""
    for branch in node.get("oneOf", ()):
        if branch.get("type") in ("number", "integer"):
            return branch
    return node


def _describe(parts, node=None):
    node = node if node is not None else _schema_at(parts)
    text = allowed(node) if node else "see config/schema.yaml"
    desc = node.get("description", "").strip() if node else ""
    if desc and desc != text and "oneOf" not in node:
        text += f" ({desc})"
    return text


def _short(value):
    text = yaml.safe_dump(value, default_flow_style=True, width=10**6).strip()
    text = text.removesuffix("...").strip()
    return text if len(text) <= 60 else text[:57] + "..."


def _read_as_text(value, integer=False):
    """Why a value that reads as a number is text (``1.0e6``: YAML 1.1 wants ``1.0e+6``),
    with how to write it (``integer``: as the integer, ``4e5`` -> 400000); None for any other
    value."""
    if not isinstance(value, str):
        return None
    try:
        number = float(value.replace("_", ""))
    except ValueError:
        return None
    if not math.isfinite(number):
        return None
    exponent = re.fullmatch(r"\s*([-+]?[0-9_]*\.?[0-9_]*)[eE]([-+]?)([0-9]+)\s*", value)
    if exponent is None:
        return f"read as the text {value!r} (it is quoted); write the number without quotes"
    mantissa, sign, digits = exponent.groups()
    if integer and number.is_integer():
        fix = f"{int(number)}"
    else:
        fix = f"{mantissa if '.' in mantissa else mantissa + '.0'}e{sign or '+'}{digits}"
    return (f"read as the text {value!r}: YAML 1.1 reads a number with an exponent only "
            f"with a dot and a signed exponent; write {fix}")


def _not_allowed(parts, value, node=None):
    """``<key path> = <value>: not allowed; allowed: ...`` (``node``: the schema node that
    failed, else the one at ``parts``), saying when a number was read as text."""
    node = node if node is not None else _schema_at(parts)
    problem = _read_as_text(value, integer=node.get("type") == "integer")
    return (f"{_path(parts)} = {_short(value)}: {problem or 'not allowed'}; "
            f"allowed: {_describe(parts, node)}")


def _schema_messages(error):
    """One or two lines for one jsonschema error (descending into oneOf branches)."""
    parts = list(error.absolute_path)
    where = _path(parts)
    kind = error.validator
    if kind in ("oneOf", "anyOf") and error.context:
        by_branch = {}
        for sub in error.context:
            by_branch.setdefault(sub.relative_schema_path[0], []).append(sub)
        for branch, subs in sorted(by_branch.items()):
            schema = error.validator_value[branch]
            while "$ref" in schema:
                schema = _resolve(schema["$ref"])
            want = schema.get("type")
            same = ((want == "object" and isinstance(error.instance, dict))
                    or (want == "array" and isinstance(error.instance, list))
                    or (want == "string" and isinstance(error.instance, str))
                    or (want in ("number", "integer")
                        and isinstance(error.instance, (int, float))))
            if same and not any(s.validator == "type" and not s.relative_path for s in subs):
                return [m for s in subs for m in _schema_messages(s)]
        node = _schema_at(parts)
        return [_not_allowed(parts, error.instance,
                             _scalar(node) if _read_as_text(error.instance) else node)]
    if kind == "required":
        missing = [k for k in error.validator_value if k not in error.instance]
        key = missing[0] if missing else error.message.split("'")[1]
        return [f"{_path(parts + [key])}: missing; allowed: {_describe(parts + [key])}"]
    if kind == "additionalProperties":
        known = list(error.schema.get("properties", {}))
        extra = [k for k in error.instance if k not in known]
        return [f"{_path(parts + [k])}: unknown key; allowed keys here: {', '.join(known)}"
                for k in extra]
    if "propertyNames" in error.schema_path:
        return [f"{where}: the name {error.instance!r} is not allowed; allowed: letters, "
                f"digits and _, starting with a letter, at most 120 characters (a file name)"]
    if kind in ("minProperties", "minItems") and not error.instance:
        return [f"{where}: empty; allowed: {_describe(parts)}"]
    # the failing node itself (a figure name's pattern, not the figure item's oneOf)
    node = error.schema if isinstance(error.schema, dict) and "oneOf" not in error.schema else None
    return [_not_allowed(parts, error.instance, node)]


def _validator(schema):
    import jsonschema

    base = jsonschema.Draft202012Validator
    properties = base.VALIDATORS["properties"]

    def set_defaults(validator, props, instance, schema_):
        if isinstance(instance, dict):
            for name, sub in props.items():
                if "default" in sub and name not in instance:
                    instance[name] = copy.deepcopy(sub["default"])
        yield from properties(validator, props, instance, schema_)

    return jsonschema.validators.extend(base, {"properties": set_defaults})(schema)


def _nonfinite(value, parts=()):
    if len(parts) == 3 and parts[0] == "studies" and parts[2] == "sweep":
        return      # a sweep's values repeat the study's own keys, reported there
    if isinstance(value, float) and not math.isfinite(value):
        yield list(parts), value
    elif isinstance(value, dict):
        for k, v in value.items():
            yield from _nonfinite(v, (*parts, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _nonfinite(v, (*parts, i))


def validate(config, schema):
    """Check ``config`` against the JSON Schema, filling defaults in place.

    Raises
    ------
    ConfigError
        One or two lines per problem (the full validator output with
        ``VIBROIMPACT_VERBOSE=1``).
    """
    _SCHEMA["root"] = schema
    problems = [f"{_path(p)} = {v}: not a finite number; allowed: "
                f"{_describe(p, _scalar(_schema_at(p)))}" for p, v in _nonfinite(config)]
    if problems:
        raise ConfigError(problems)
    errors = sorted(_validator(schema).iter_errors(config), key=lambda e: list(map(str, e.path)))
    if errors:
        lines = []
        for error in errors:
            for line in _schema_messages(error):
                if line not in lines:
                    lines.append(line)
        raise ConfigError(lines, details="\n\n".join(str(e) for e in errors))


# --- cross-field checks -----------------------------------------------------------------------

def _record(config, noise):
    """``(n_samples, dt, tau_end)`` of a noise entry."""
    entry = config["noises"][noise]
    n, dt = int(entry["n_samples"]), float(entry["dt"])
    return n, dt, (n - 1) * dt


def _on_grid(value, grid):
    return bool(np.any(np.abs(grid - value) <= GRID_RTOL * max(1.0, abs(value))))


def _grid_text(grid):
    if grid.size <= 8:
        return ", ".join(_num(float(v)) for v in grid)
    return f"{_num(float(grid[0]))}, {_num(float(grid[1]))}, ..., {_num(float(grid[-1]))}"


class _Problems(list):
    def add(self, where, value, problem, allowed_):
        shown = f" = {_short(value)}" if value is not None else ""
        self.append(f"{where}{shown}: {problem}; allowed: {allowed_}")


def _repeated(values):
    """The values of a list given more than once (equal within `GRID_RTOL`), ascending."""
    v = np.sort(np.asarray(values, dtype=float))
    close = np.diff(v) <= GRID_RTOL * np.maximum(1.0, np.abs(v[1:]))
    return sorted(set(v[1:][close].tolist()))


def _distinct(problems, where, values):
    """Record a list of values that repeats one (one cell, study or figure twice); True when
    it does not."""
    repeated = _repeated(values) if values else []
    if repeated:
        problems.add(where, values, f"{', '.join(map(_num, repeated))} listed more than once",
                     "distinct values")
    return not repeated


def _grid(problems, where, spec, limit, positive=False):
    """Values of a grid, or None after recording why it is unusable."""
    try:
        n = grid_size(spec)
    except ValueError as err:
        key = "stop" if "stop" in str(err) else "step"
        problems.add(f"{where}.{key}", spec.get(key), str(err).split(",")[0].removeprefix("grid "),
                     f"stop >= start = {_num(spec['start'])}" if key == "stop" else "> 0")
        return None
    if n > limit:
        problems.add(where, spec, f"{n:,} values (more than the limit of cells)",
                     f"at most {limit:,} values (limits.max_cells), e.g. a larger step")
        return None
    if isinstance(spec, list) and not _distinct(problems, where, spec):
        return None
    values = grid_values(spec)
    if positive and np.any(values <= 0.0):
        bad = float(values[values <= 0.0][0])
        key = f"{where}.start" if isinstance(spec, dict) else where
        problems.add(key, spec["start"] if isinstance(spec, dict) else spec,
                     f"1/beta_f = {_num(bad)} is not a forcing period ratio",
                     "values > 0")
        return None
    return values


def _check_noises(config, problems):
    from vibroimpact.noise import NoiseSpec   # its own checks (FIR length) after ours

    for name, entry in config["noises"].items():
        where = f"noises.{name}"
        kind, dt = entry["kind"], float(entry["dt"])
        needs = {"white": (), "band_limited": ("beta_c",), "lowpass2": ("beta_c", "zeta_f")}[kind]
        ok = True
        for key in ("beta_c", "zeta_f"):
            given = entry.get(key) is not None
            if given != (key in needs):
                ok = False
                problems.add(f"{where}.{key}", entry.get(key),
                             f"{'required' if not given else 'not used'} for kind {kind}",
                             "a number > 0" if not given else "null (or leave it out)")
        nyquist = math.pi / dt
        beta_c = entry.get("beta_c")
        if beta_c is not None and beta_c > nyquist * (1 + 1e-9):
            ok = False
            problems.add(f"{where}.beta_c", beta_c,
                         f"above the Nyquist frequency pi/dt of dt = {_num(dt)}",
                         f"0 < beta_c <= {nyquist:.6g}")
        if int(entry["nperseg"]) > int(entry["n_samples"]):
            problems.add(f"{where}.nperseg", entry["nperseg"], "longer than the record",
                         f"16 <= nperseg <= n_samples = {entry['n_samples']}")
        if ok:
            try:
                NoiseSpec(**{k: entry[k] for k in ("kind", "rms", "dt", "beta_c", "zeta_f")
                             if entry.get(k) is not None})
            except ValueError as err:
                problems.add(where, None, str(err), "see config/schema.yaml, noises")


def _check_figures(config, section, name, entry, problems, grids):
    where = f"{section}.{name}.figures"
    kind = "study" if section == "studies" else "orbits"
    if not entry["figures"]:
        allowed_ = sorted(f for f, s in figures.FIGURES.items() if s["owner"] == kind)
        problems.add(where, [], "no figure listed: this entry would build nothing",
                     f"a list of figures from {', '.join(allowed_)}")
        return
    seen = set()
    for i, item in enumerate(entry["figures"]):
        fig = item if isinstance(item, str) else item["name"]
        spec = figures.FIGURES[fig]
        at = f"{where}[{i}]"
        if spec["owner"] != kind:
            allowed_ = sorted(f for f, s in figures.FIGURES.items() if s["owner"] == kind)
            problems.add(at, fig, f"not drawn from {'a study' if kind == 'study' else 'an orbits map'}",
                         ", ".join(allowed_))
            continue
        if fig in seen:
            problems.add(at, fig, "listed twice", "each figure once (a list of values under "
                         "its `inv_beta` draws it several times)")
        seen.add(fig)
        if kind != "study":
            continue
        if spec.get("harmonic") and not entry.get("amplitude"):
            problems.add(f"studies.{name}.amplitude", entry.get("amplitude", 0.0),
                         f"{fig} shows the harmonic force", "amplitude != 0 for this figure")
        for block in ("trace", "spectra"):
            if block in spec["reads"] and not entry.get(block):
                problems.add(f"studies.{name}.{block}", None,
                             f"missing, and {fig} draws it",
                             f"a `{block}:` block (config/schema.yaml), or drop {fig}")
        item = {} if isinstance(item, str) else item
        for key in item:
            if key == "name":
                continue
            usable = (key == spec.get("per") or key in spec.get("options", ())
                      or key in spec.get("sources", ())
                      or (key == "beta_max" and "spectra" in spec["reads"]))
            if not usable:
                problems.add(f"{at}.{key}", item[key], f"not an option of {fig}",
                             _figure_keys(fig))
        if spec.get("per") == "inv_beta" and "inv_beta" in item:
            _distinct(problems, f"{at}.inv_beta", item["inv_beta"])
            for j, v in enumerate(item["inv_beta"]):
                if not _on_grid(v, grids["inv_beta"]):
                    problems.add(f"{at}.inv_beta[{j}]", v, "not on the study's inv_beta grid",
                                 _grid_text(grids["inv_beta"]))
        _distinct(problems, f"{at}.density_delta", item.get("density_delta"))
        for j, v in enumerate(item.get("density_delta", [])):
            if not _on_grid(v, grids["delta"]):
                problems.add(f"{at}.density_delta[{j}]", v, "not on the study's delta grid",
                             _grid_text(grids["delta"]))
        if "orbits" in spec.get("sources", ()):
            _check_orbits_item(config, name, entry, at, fig, item, problems)


def _figure_keys(fig):
    spec = figures.FIGURES[fig]
    keys = [*([spec["per"]] if spec.get("per") else []), *spec.get("options", ()),
            *spec.get("sources", ()), *(["beta_max"] if "spectra" in spec["reads"] else [])]
    return f"name, {', '.join(keys)}" if keys else f"only name ({fig} has no options)"


def _check_orbits_item(config, name, entry, at, fig, item, problems):
    orbits = item.get("orbits")
    names = sorted(config.get("orbits", {}))
    if orbits not in config.get("orbits", {}):
        problems.add(f"{at}.orbits", orbits, f"{fig} is drawn over an orbit map; give its "
                     f"entry as {{name: {fig}, orbits: <name>}}", ", ".join(names) or
                     "an `orbits` entry (none defined)")
        return
    other = config["orbits"][orbits]
    for key in ("zeta", "eps"):
        if float(other[key]) != float(entry[key]):
            problems.add(f"{at}.orbits", orbits, f"orbits.{orbits} has {key} = "
                         f"{_num(other[key])}, the study {key} = {_num(entry[key])}",
                         "an `orbits` entry of the same zeta and eps")
    types = {tuple(t) for t in other["types"]}
    missing = [m for m in entry["motions"] if tuple(m) not in types]
    if missing:
        problems.add(f"{at}.orbits", orbits, f"orbits.{orbits} maps no {missing} motion, "
                     f"which studies.{name}.motions lists", "an `orbits` entry whose types "
                     "include every motion of the study")


def _check_study(config, name, entry, problems, limits):
    where = f"studies.{name}"
    siblings = {name}           # itself, or every study of its sweep
    if "sweep" in entry:
        siblings = set(config.get("sweeps", {}).get(entry["sweep"]["name"], {}).get(
            "studies", [name]))
    for other in entry.get("report_with", []):
        if other in siblings or other not in config["studies"]:
            problems.add(f"{where}.report_with", other, "no other study of this name",
                         ", ".join(sorted(set(config["studies"]) - siblings)) or "none")
    if entry["noise"] not in config["noises"]:
        problems.add(f"{where}.noise", entry["noise"], "no such noise record",
                     ", ".join(sorted(config["noises"])))
        return None
    n, dt, tau = _record(config, entry["noise"])
    record = f"the record of noises.{entry['noise']} ends at tau = {tau:.6g}"
    grids = {"delta": _grid(problems, f"{where}.delta", entry["delta"], limits["max_cells"])}
    harmonic = float(entry["amplitude"]) != 0.0
    grids["inv_beta"] = (_grid(problems, f"{where}.inv_beta", entry["inv_beta"],
                               limits["max_cells"], positive=True)
                         if harmonic else np.array([1.0]))
    trace_inv_beta = (entry.get("trace") or {}).get("inv_beta")
    if harmonic:
        shortest = dt / (2 * math.pi)       # a forcing period of one sample step
        for key, values in (("inv_beta", grids["inv_beta"]),
                            ("trace.inv_beta", [trace_inv_beta] if trace_inv_beta else None)):
            fast = [float(v) for v in (values if values is not None else []) if v < shortest]
            if fast:
                problems.add(f"{where}.{key}", fast[0], f"a forcing period 2 pi/beta_f shorter "
                             f"than the sample step dt = {_num(dt)} of noises.{entry['noise']} "
                             f"(the pressed mass would stick and release many times a step)",
                             f"1/beta_f >= dt/(2 pi) = {shortest:.6g}")
    amplitude_swept = "amplitude" in entry.get("sweep", {}).get("values", {})
    if not harmonic and not amplitude_swept:
        # keys of the harmonic force a random study would silently ignore
        for key, value, default in (("inv_beta", entry["inv_beta"], [1.0]),
                                    ("trace.inv_beta", trace_inv_beta, None)):
            if value is not None and value != default:
                problems.add(f"{where}.{key}", value, "1/beta_f of the harmonic force, and "
                             "this study has none (amplitude = 0)", "leave it out, or give "
                             "the study an amplitude != 0")
    transient = float(entry["transient"])
    t_end = entry.get("t_end")
    end = tau if t_end is None else float(t_end)
    if t_end is not None and t_end > tau * (1 + 1e-9):
        problems.add(f"{where}.t_end", t_end, f"longer than the noise record ({record})",
                     f"transient < t_end <= {tau:.6g}, or null for the whole record")
    elif transient >= end:
        problems.add(f"{where}.transient", transient, "leaves no record for the statistics "
                     f"(t_end = {end:.6g})", f"0 <= transient < {end:.6g}")
    uses = {r for f in entry["figures"] for r in figures.FIGURES[
        f if isinstance(f, str) else f["name"]]["reads"]}
    spectra = entry.get("spectra")
    if spectra:
        s_end = tau if spectra.get("t_end") is None else float(spectra["t_end"])
        if s_end > tau * (1 + 1e-9):
            problems.add(f"{where}.spectra.t_end", spectra["t_end"],
                         f"longer than the noise record ({record})",
                         f"transient < t_end <= {tau:.6g}, or null")
        elif s_end <= transient:
            if transient < end:
                problems.add(f"{where}.spectra.t_end", spectra["t_end"],
                             f"leaves no record after the transient ({_num(transient)})",
                             f"{_num(transient)} < t_end <= {tau:.6g}, or null")
        else:
            # the samples k dt with transient <= k dt <= t_end (cells.spectra_cell)
            samples = (math.floor(s_end / dt + 1e-9) - math.ceil(transient / dt - 1e-9) + 1)
            if samples < 16:
                problems.add(f"{where}.spectra", None, f"its record holds {samples} samples "
                             f"(transient to t_end, at dt = {_num(dt)}), fewer than a Welch "
                             f"segment's 16", f"a record of 16 samples or more: n_samples >= "
                             f"{16 + math.ceil(transient / dt - 1e-9)} in noises."
                             f"{entry['noise']}, or a longer spectra.t_end")
            elif samples < int(spectra["nperseg"]):
                problems.add(f"{where}.spectra.nperseg", spectra["nperseg"],
                             f"longer than the spectra record ({samples} samples from the "
                             f"transient to t_end)",
                             f"16 <= nperseg <= {samples}, or a longer spectra.t_end")
        sgrid = _grid(problems, f"{where}.spectra.delta", spectra["delta"], limits["max_cells"])
        if sgrid is not None and grids["delta"] is not None:
            for j, v in enumerate(sgrid):
                if not _on_grid(v, grids["delta"]):
                    problems.add(f"{where}.spectra.delta" + (f"[{j}]" if isinstance(
                        spectra["delta"], list) else ""), float(v),
                        "not on the study's delta grid (a spectrum's cell has its impact "
                        "statistics too)", _grid_text(grids["delta"]))
    trace = entry.get("trace")
    if trace and float(trace["t_end"]) > tau * (1 + 1e-9):
        problems.add(f"{where}.trace.t_end", trace["t_end"],
                     f"longer than the noise record ({record})", f"0 < t_end <= {tau:.6g}")
    elif trace and float(trace["t_end"]) < dt * (1 - 1e-9):
        problems.add(f"{where}.trace.t_end", trace["t_end"], f"shorter than one sample step "
                     f"(dt = {_num(dt)} of noises.{entry['noise']}): a trace of one point",
                     f"{_num(dt)} <= t_end <= {tau:.6g}")
    _distinct(problems, f"{where}.density_delta", entry["density_delta"])
    if grids["delta"] is not None:
        for j, v in enumerate(entry["density_delta"]):
            if not _on_grid(v, grids["delta"]):
                problems.add(f"{where}.density_delta[{j}]", v, "not on the delta grid",
                             _grid_text(grids["delta"]))
    motions = [tuple(m) for m in entry["motions"]]
    if len(set(motions)) != len(motions):
        problems.add(f"{where}.motions", entry["motions"], "a motion is listed twice",
                     "distinct [m, n] pairs")
    if "map" in uses and harmonic and grids["inv_beta"] is not None:
        spec = entry["map"]
        try:        # the cap of the longest forcing period (the job's own check, at parse time)
            map_cap_steps(n, dt, transient, int(spec["max_periods"]),
                          1.0 / float(grids["inv_beta"].max()), where=f"{where}.map.max_periods")
        except ValueError as err:
            problems.append(f"{err} in noises.{entry['noise']}")
        if transient + float(spec["min_time"]) > tau * (1 + 1e-9):
            problems.add(f"{where}.map.min_time", spec["min_time"],
                         f"transient + min_time is beyond the record ({record})",
                         f"0 < min_time <= {tau - transient:.6g}")
    if "map" in uses and harmonic:
        _plane(problems, where, grids, "fig15")
    if all(g is not None for g in grids.values()):
        _check_figures(config, "studies", name, entry, problems, grids)
    return grids


def _plane(problems, where, grids, fig):
    """Record a (1/beta_f, delta) plane too small for `fig`'s contours (2 values an axis)."""
    for key in ("inv_beta", "delta"):
        if grids[key] is not None and grids[key].size < 2:
            problems.add(f"{where}.{key}", float(grids[key][0]), f"{fig} draws contours "
                         f"over the (1/beta_f, delta) plane", "at least 2 values")


def _check_orbits(config, name, entry, problems, limits):
    from vibroimpact.orbits.api import MAX_M

    where = f"orbits.{name}"
    grids = {"inv_beta": _grid(problems, f"{where}.inv_beta", entry["inv_beta"],
                               limits["max_orbit_cells"], positive=True),
             "delta": _grid(problems, f"{where}.delta", entry["delta"],
                            limits["max_orbit_cells"])}
    if "fig16" in [f if isinstance(f, str) else f["name"] for f in entry["figures"]]:
        _plane(problems, where, grids, "fig16")
    for j, (m, n) in enumerate(entry["types"]):
        if m > MAX_M:
            problems.add(f"{where}.types[{j}]", [m, n], f"the orbit solver finds (m/n) motions "
                         f"with m <= {MAX_M} impacts a period only", f"[m, n] with 1 <= m <= "
                         f"{MAX_M} and 1 <= n <= 12")
    types = [tuple(t) for t in entry["types"]]
    if len(set(types)) != len(types):
        problems.add(f"{where}.types", entry["types"], "a type is listed twice",
                     "distinct [m, n] pairs")
    _check_figures(config, "orbits", name, entry, problems, None)


def _check_paper_figures(config, problems, only=None):
    for fig, name in config["paper_figures"].items():
        if only is not None and fig not in only:
            continue            # the paper's, not built (paper: false): a replaced entry may differ
        section = "orbits" if figures.FIGURES[fig]["owner"] == "orbits" else "studies"
        where = f"paper_figures.{fig}"
        if name not in config[section]:
            problems.add(where, name, f"{fig} is drawn from {section} entries; no such entry",
                         ", ".join(sorted(config[section])))
            continue
        names = [f if isinstance(f, str) else f["name"] for f in config[section][name]["figures"]]
        if names and fig not in names:      # (an empty list is reported with its entry)
            problems.add(where, name, f"{section}.{name} does not list {fig} in its figures",
                         f"an entry listing {fig}, or add {fig} to {section}.{name}.figures")


def check(config, own=None, *, results="results"):
    """Every cross-field relation, the limits; returns the :class:`Plan` of the build.

    ``config`` has passed :func:`validate`; ``own`` is from :func:`compose`.

    Raises
    ------
    ConfigError
        Listing every problem found, one or two lines each.
    """
    limits = config["limits"]
    problems = _Problems()
    _check_noises(config, problems)
    for name, entry in config["studies"].items():
        _check_study(config, name, entry, problems, limits)
    for name, entry in config["orbits"].items():
        _check_orbits(config, name, entry, problems, limits)
    _check_paper_figures(config, problems, None if own is None else own["paper_figures"])
    if own is not None and not any(own[s] for s in ("studies", "orbits", "paper_figures")):
        problems.add("paper", False, "your file builds nothing of its own",
                     "paper: false with at least one study or orbits entry that lists figures")
    if problems:
        raise ConfigError(problems)
    plan = make_plan(config, own, results=results)
    plan.refuse_beyond_limits()
    return plan


def load(user=None, *, root=".", user_files=()):
    """Read the paper's config, layer ``user`` on it, expand its sweeps, validate and check.

    Returns ``(config, plan)``; ``config["sweeps"]`` records each sweep's studies and values
    (:func:`expand_sweeps`).

    Parameters
    ----------
    user : dict, optional
        The user's config (what ``--configfile`` files gave Snakemake), or None.
    root : path
        The project directory (holding ``config/config.yaml`` and ``config/schema.yaml``).
    user_files : sequence of paths
        Files to read as the user's config (deep-merged in order) when ``user`` is None.
    """
    root = Path(root)
    if user is None and user_files:
        user = {}
        for path in user_files:
            user = _deep_merge(user, read_yaml(path))
    else:
        check_size(user or {}, "the config given with --configfile")
    schema = read_yaml(root / "config" / "schema.yaml", user=False)
    paper = read_yaml(root / "config" / "config.yaml", user=False)
    config, own = compose(paper, user or {})
    if own is not None and "build" not in ((user or {}).get("validation") or {}):
        # paper: false builds the file's own entries; the validation runs are the paper's
        config["validation"] = {**(config.get("validation") or {}), "build": False}
    sweeps = expand_sweeps(config, own, max_studies=_max_jobs(config, schema))
    try:
        validate(config, schema)
        config["sweeps"] = sweeps.record    # after the schema, which knows only the user's keys
        plan = check(config, own, results=root / "results")
    except ConfigError as err:
        raise sweeps.relabel(err) from None
    return config, plan


def _max_jobs(config, schema):
    """``limits.max_jobs`` of a config not yet validated (the schema's default if unusable)."""
    limits = config.get("limits")
    value = limits.get("max_jobs") if isinstance(limits, dict) else None
    if isinstance(value, int) and not isinstance(value, bool) and value >= 1:
        return value
    return schema["properties"]["limits"]["properties"]["max_jobs"]["default"]


def _deep_merge(base, extra):
    out = dict(base)
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _deep_merge(out[key], value)
        else:
            out[key] = value
    return out


# --- the plan: cells, jobs, disk and time -----------------------------------------------------

# Costs measured on the default build (results/benchmarks/*, 2 cores; README, "Job costs"):
JOB_START_S = 1.3          # interpreter, numpy, xarray (and numba) start-up of one job
NS_PER_STEP = 25.0         # simulated sample step, with impacts (~20 ns measured)
NS_PER_SAMPLE = 50.0       # noise generation
US_PER_ORBIT = 45.0        # one (1/beta, delta, type) orbit solve
FIGURE_S = 1.5             # one figure, start-up included
REPORT_S = 4.0             # one report notebook executed and rendered (papermill, nbconvert)
VALIDATION_S = 85.0        # the work-precision run and the stress sample together
# Bytes of the outputs (measured file sizes of the default build):
FILE_OVERHEAD = 20_000
FIGURE_BYTES = 400_000     # png + pdf
REPORT_BYTES = 4_000_000   # executed notebook + HTML, figures embedded


@dataclass
class Row:
    """One line of the plan: a config entry and what building it costs."""

    key: str
    detail: str
    cells: int = 0
    orbit_cells: int = 0
    jobs: int = 0
    bytes: float = 0.0
    cpu_s: float = 0.0


@dataclass
class Plan:
    """What a build will make, before anything runs (``str()`` is the printed plan)."""

    rows: list = field(default_factory=list)
    limits: dict = field(default_factory=dict)
    free_bytes: float | None = None
    results: str = "results"
    drawn: dict = field(default_factory=dict)    # built_entries(...)[0]: what `rule all` draws

    @property
    def cells(self):
        return sum(r.cells for r in self.rows)

    @property
    def orbit_cells(self):
        return sum(r.orbit_cells for r in self.rows)

    @property
    def jobs(self):
        return sum(r.jobs for r in self.rows)

    @property
    def bytes(self):
        return sum(r.bytes for r in self.rows)

    @property
    def cpu_s(self):
        return sum(r.cpu_s for r in self.rows)

    def summary(self, cores=2):
        return (f"{_n(self.cells, 'simulation cell')}, {_n(self.orbit_cells, 'orbit cell')}, "
                f"{_n(self.jobs, 'job')} (Snakemake counts {self.jobs + 1}, with its target "
                f"`all`), ~{_bytes(self.bytes)} of outputs, ~{_time(self.cpu_s)} of CPU "
                f"(~{_time(self.cpu_s / max(cores, 1))} on {_n(cores, 'core')})")

    def format(self, cores=2):
        lines = ["vibroimpact plan (every output of `rule all`, whether or not already built):"]
        width = max([len(r.key) for r in self.rows] + [10])
        lines.append(f"  {'entry':<{width}}  {'jobs':>4}  {'outputs':>8}  {'CPU':>8}  what")
        for r in self.rows:
            lines.append(f"  {r.key:<{width}}  {r.jobs:>4}  {_bytes(r.bytes):>8}  "
                         f"~{_time(r.cpu_s):>7}  {r.detail}")
        lines.append(f"  total: {self.summary(cores)}")
        lim = self.limits
        lines.append(f"  limits: {self.cells:,} of {lim['max_cells']:,} cells (limits.max_cells), "
                     f"{self.orbit_cells:,} of {lim['max_orbit_cells']:,} orbit cells "
                     f"(limits.max_orbit_cells),")
        lines.append(f"          {self.jobs} of {lim['max_jobs']} jobs (limits.max_jobs), "
                     f"{_bytes(self.bytes)} of {_num(lim['max_disk_gb'])} GB (limits.max_disk_gb)"
                     + (f"; {_bytes(self.free_bytes)} free under {self.results}"
                        if self.free_bytes is not None else "") + ",")
        lines.append(f"          ~{_time(self.cpu_s)} of {_num(lim['max_cpu_hours'])} h of CPU "
                     f"(limits.max_cpu_hours)")
        return "\n".join(lines)

    __str__ = format

    def refuse_beyond_limits(self):
        lim, problems = self.limits, []
        for value, key, what in ((self.cells, "max_cells", "simulation cells"),
                                 (self.orbit_cells, "max_orbit_cells", "orbit cells"),
                                 (self.jobs, "max_jobs", "jobs")):
            if value > lim[key]:
                problems.append(f"limits.{key} = {lim[key]:,}: this build has {value:,} "
                                f"{what}; raise limits.{key} to build it, or shrink the grids"
                                f"\n  ({self.summary()})")
        if self.cpu_s > lim["max_cpu_hours"] * 3600:
            problems.append(f"limits.max_cpu_hours = {_num(lim['max_cpu_hours'])}: this build "
                            f"needs ~{_time(self.cpu_s)} of CPU; raise limits.max_cpu_hours to "
                            f"build it (a cluster: README, \"On a SLURM cluster\"), or shrink "
                            f"the grids or records\n  ({self.summary()})")
        gb = self.bytes / 1e9
        if gb > lim["max_disk_gb"]:
            problems.append(f"limits.max_disk_gb = {_num(lim['max_disk_gb'])}: this build "
                            f"writes ~{_bytes(self.bytes)}; raise limits.max_disk_gb to build "
                            f"it, or shorten the records\n  ({self.summary()})")
        elif self.free_bytes is not None and self.bytes > self.free_bytes:
            problems.append(f"disk: this build writes ~{_bytes(self.bytes)}, only "
                            f"{_bytes(self.free_bytes)} free under {self.results}; free "
                            f"some space or shorten the records")
        if problems:
            raise ConfigError(problems)


def _n(count, word):
    """``"1 figure"``, ``"3 figures"``, ``"2 studies"``."""
    if count == 1:
        return f"1 {word}"
    return f"{count:,} " + (word[:-1] + "ies" if word.endswith(("dy", "py")) else word + "s")


def _bytes(n):
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} B"


def _time(s):
    if s >= 3600:
        return f"{s / 3600:.2g} h"
    if s >= 60:
        return f"{s / 60:.2g} min"
    return f"{s:.2g} s"


def _study_needs(entry):
    needs = {r for f in entry["figures"] for r in figures.FIGURES[
        f if isinstance(f, str) else f["name"]]["reads"]}
    if "sweep" in entry:
        needs.add("events")         # the sweep's side-by-side figure reads them
    return needs


def built_entries(config, own=None):
    """``(drawn, reads)`` of ``rule all``: ``drawn`` the entries whose figures it draws
    (``{section: names}``, paper figures included), ``reads`` every entry whose datasets
    those figures read (``{"studies", "orbits", "noises": names}``)."""
    sections = ("studies", "orbits", "paper_figures")
    drawn = {s: set(config.get(s, {})) if own is None else set(own[s]) for s in sections}
    for fig in drawn["paper_figures"]:
        section = "orbits" if figures.FIGURES[fig]["owner"] == "orbits" else "studies"
        drawn[section].add(config["paper_figures"][fig])
    reads = {"studies": set(drawn["studies"]), "orbits": set(drawn["orbits"]), "noises": set()}
    for name in drawn["studies"]:
        entry = config["studies"][name]
        for item in entry["figures"]:
            fig = item if isinstance(item, str) else item["name"]
            for kind, other in figures.figure_sources(entry, fig).items():
                reads[kind].add(other)
        if _study_needs(entry) - {"orbits"}:
            reads["noises"].add(entry["noise"])
    return drawn, reads


def make_plan(config, own=None, *, results="results"):
    """The :class:`Plan` of ``rule all``: cells, jobs, bytes and CPU seconds per entry."""
    from vibroimpact.pipeline.study import Study, orbit_rows

    drawn, build = built_entries(config, own)
    plan = Plan(limits=dict(config["limits"]), results=str(results), drawn=drawn)
    for name in sorted(build["noises"]):
        entry = config["noises"][name]
        n = int(entry["n_samples"])
        plan.rows.append(Row(f"noises.{name}", f"{n:,} samples", jobs=1,
                             bytes=8 * n + FILE_OVERHEAD,
                             cpu_s=JOB_START_S + n * NS_PER_SAMPLE * 1e-9))
    for name in sorted(build["studies"]):
        entry = config["studies"][name]
        study = Study.from_config(name, entry)
        n, dt, tau = _record(config, entry["noise"])
        needs = _study_needs(entry)
        row = Row(f"studies.{name}", "")
        parts = []
        if "events" in needs:
            cells = len(study.cells("events"))
            steps = (tau if entry.get("t_end") is None else float(entry["t_end"])) / dt
            bins = sum(int(b["n"]) for b in entry["bins"].values())
            per_cell = 12 * (bins + 100)
            _add(row, cells, study.n_tiles("events") + 1, 2 * cells * per_cell,
                 cells * steps * NS_PER_STEP * 1e-9)
            parts.append(f"events {_n(cells, 'cell')}")
        if "map" in needs:
            cells = len(study.cells("events"))
            cap = sum(len(study.delta) * min(n - 1, (float(entry["transient"]) + int(
                entry["map"]["max_periods"]) * 2 * math.pi * ib) / dt) for ib in study.inv_beta)
            _add(row, cells, study.n_tiles("events") + 1, 2 * cells * 200, cap * NS_PER_STEP
                 * 1e-9)
            parts.append(f"map {_n(cells, 'cell')} (CPU at the caps)")
        if "spectra" in needs:
            cells = len(study.cells("spectra"))
            spec = entry["spectra"]
            steps = (tau if spec.get("t_end") is None else float(spec["t_end"])) / dt
            _add(row, cells, study.n_tiles("spectra") + 1,
                 2 * cells * 16 * (int(spec["nperseg"]) // 2 + 1),
                 cells * steps * NS_PER_STEP * 1e-9)
            parts.append(f"spectra {_n(cells, 'cell')}")
        if "trace" in needs:
            steps = float(entry["trace"]["t_end"]) / dt
            _add(row, 0, 1, 40 * steps, 0.0)
            parts.append("trace")
        targets = len(figures.figure_targets(entry))
        row.jobs += targets
        row.bytes += targets * FIGURE_BYTES
        row.cpu_s += targets * FIGURE_S + row.jobs * JOB_START_S
        row.detail = ", ".join(parts) + f", {_n(targets, 'figure')}"
        plan.rows.append(row)
    for name in sorted(build["orbits"]):
        entry = config["orbits"][name]
        rows, n_tiles = orbit_rows(entry)
        cells = len(rows) * grid_size(entry["delta"])
        targets = len(figures.figure_targets(entry)) if name in drawn["orbits"] else 0
        row = Row(f"orbits.{name}", f"{_n(cells, 'cell')} x {_n(len(entry['types']), 'type')}, "
                  f"{_n(targets, 'figure')}", orbit_cells=cells, jobs=n_tiles + 1 + targets,
                  bytes=2 * cells * len(entry["types"]) * 34 + targets * FIGURE_BYTES)
        row.cpu_s = (cells * len(entry["types"]) * US_PER_ORBIT * 1e-6
                     + row.jobs * JOB_START_S + targets * FIGURE_S)
        plan.rows.append(row)
    for name in drawn_sweeps(config, drawn):
        n = len(config["sweeps"][name]["studies"])
        plan.rows.append(Row(f"sweeps.{name}", f"{_n(n, 'study')} side by side, 1 figure", jobs=1,
                             bytes=FIGURE_BYTES, cpu_s=FIGURE_S + JOB_START_S))
    reports = len(drawn["studies"]) + len(drawn["orbits"])
    if reports:
        plan.rows.append(Row("reports", f"{_n(reports, 'notebook')} executed, with HTML",
                             jobs=reports, bytes=reports * REPORT_BYTES,
                             cpu_s=reports * (REPORT_S + JOB_START_S)))
    if config["validation"]["build"]:
        plan.rows.append(Row("validation", "work-precision and stress-sample runs, 2 figures, "
                             "2 reports", jobs=6, bytes=2 * FIGURE_BYTES + 2 * REPORT_BYTES,
                             cpu_s=VALIDATION_S + 2 * (FIGURE_S + REPORT_S) + 6 * JOB_START_S))
    copies = drawn["paper_figures"]
    if copies:
        plan.rows.append(Row("paper_figures", _n(len(copies), "copy"), jobs=len(copies),
                             bytes=len(copies) * FIGURE_BYTES))
    try:
        probe = Path(results)
        while not probe.exists():
            probe = probe.parent
        import shutil

        plan.free_bytes = shutil.disk_usage(probe).free
    except OSError:
        plan.free_bytes = None
    return plan


def _add(row, cells, jobs, nbytes, cpu_s):
    row.cells += cells
    row.jobs += jobs
    row.bytes += nbytes + jobs * FILE_OVERHEAD
    row.cpu_s += cpu_s
