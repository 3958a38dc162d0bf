"""Reading a config file strictly, and layering a user's config on the paper's.

- :func:`read_yaml` reads a config file; a syntax error, a key given twice or aliases that
  expand beyond `MAX_VALUES` name the file, line and column.
- :func:`compose` layers a user's file on the paper's config (``config/config.yaml``): its
  entries are added; an entry named like a paper entry but different is refused unless the
  file lists it under ``replace`` (it would overwrite the paper's results); with
  ``paper: false`` only the file's own entries are built (the paper's stay available by
  name, e.g. a noise record or an orbits map). Every other top-level block follows the same
  rule (`BLOCKS`): a block that makes results (``validation``) is the paper's unless the
  file lists it under ``replace``; only the build's settings (`SETTINGS`: ``paper``,
  ``replace``, ``limits``, ``container``, ``validation.build``) are the file's own.
"""
import copy
import json
from pathlib import Path
import re

import yaml

from vibroimpact.pipeline.config.messages import ConfigError, _short

__all__ = ["SECTIONS", "BLOCKS", "SETTINGS", "MAX_VALUES", "read_yaml", "check_size",
           "expanded_size", "compose", "deep_merge"]

#: Sections whose entries are named; a user's entry replaces a paper entry whole.
SECTIONS = ("noises", "studies", "orbits", "paper_figures")

#: Top-level blocks that are not named entries but make results of their own (``validation``:
#: results/validation/*.nc, results/figures/work_precision.png, stress.png and the reports
#: under results/reports/validation/): a user's block that differs from the paper's is
#: refused unless the file lists it under ``replace`` (``replace: [validation]``), like an
#: entry of `SECTIONS`. Value: the keys of the block that are settings of the build, not
#: of its results (the user's own).
BLOCKS = {"validation": ("build",)}

#: Top-level keys that set how this build runs, not what a result holds: the user's own.
SETTINGS = ("paper", "replace", "limits", "container")

#: Values a config may hold once YAML aliases are expanded (the paper's config holds ~600);
#: a file beyond it (nested aliases: a "billion laughs") is refused before anything walks it.
MAX_VALUES = 1_000_000


#: Plain scalars YAML 1.1 reads otherwise than a reader of the file would: a leading 0 makes
#: an integer octal (``010`` is 8), colons make a number base 60 (``3:20`` is 200).
_OCTAL = re.compile(r"[-+]?0[0-7_]+")
_BASE60 = re.compile(r"[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?")
#: What a key YAML reads as something else than text is read as.
_KINDS = {bool: "the boolean", int: "the integer", float: "the number"}


def _kind(value):
    if value is None:
        return "null (no value)"
    for cls, text in _KINDS.items():
        if type(value) is cls:
            return f"{text} {_short(value)}"
    return f"a {type(value).__name__} ({_short(value)})"


class _StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses what PyYAML reads silently otherwise than meant: a
    key given twice in one mapping (PyYAML keeps the last), two ``<<:`` merge keys in one
    mapping (the second wins), a key that is not text (``yes:`` a boolean, ``123:`` an
    integer, ``~:`` null, ``2024-01-01:`` a date), an integer with a leading 0 (YAML 1.1
    octal: ``010`` is 8) and a number with colons (base 60: ``3:20`` is 200), naming the
    lines."""

    def construct_mapping(self, node, deep=False):
        seen, merge = {}, None
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                if merge is not None:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"a second `<<:` merge key in one mapping (the first on "
                        f"line {merge + 1}); YAML keeps one silently: merge both in one, "
                        f"<<: [*first, *second] (the first listed wins a key both give)",
                        key_node.start_mark)
                merge = key_node.start_mark.line
                continue
            key = self.construct_object(key_node, deep=True)
            if not isinstance(key, str) and isinstance(key_node, yaml.ScalarNode):
                raise yaml.constructor.ConstructorError(
                    None, None, f"the key {key_node.value!r} is read by YAML as "
                    f"{_kind(key)}, not as a name; keys are text: quote it "
                    f"(\"{key_node.value}\") or rename it", key_node.start_mark)
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

    def construct_yaml_int(self, node):
        value = super().construct_yaml_int(node)
        text = node.value
        if _BASE60.fullmatch(text):
            self._misread(node, value, "base 60 (each colon: sixties, as on a clock)")
        if _OCTAL.fullmatch(text) and value != int(text.replace("_", ""), 10):
            self._misread(node, value, "octal (the leading 0)")
        return value

    def construct_yaml_float(self, node):
        value = super().construct_yaml_float(node)
        if _BASE60.fullmatch(node.value):
            self._misread(node, value, "base 60 (each colon: sixties, as on a clock)")
        return value

    @staticmethod
    def _misread(node, value, rule):
        digits = node.value.replace("_", "")
        if ":" in digits:
            fix = f"{_short(value)} if that is meant, or the number meant without colons"
        else:
            sign = digits[0] if digits[0] in "+-" else ""
            fix = f"{sign}{digits.lstrip('+-').lstrip('0') or '0'} without the leading 0"
        raise yaml.constructor.ConstructorError(
            None, None, f"{node.value} is read by YAML 1.1 as {_short(value)}, a number "
            f"in {rule}; write {fix} (or quote it for text)", node.start_mark)


_StrictLoader.add_constructor("tag:yaml.org,2002:int", _StrictLoader.construct_yaml_int)
_StrictLoader.add_constructor("tag:yaml.org,2002:float", _StrictLoader.construct_yaml_float)


def _json_object(pairs):
    """A JSON object, refusing a key given twice (``json`` keeps the last silently)."""
    out = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"the key {key!r} is given twice in one object; JSON readers "
                             f"keep one silently: delete or rename the other")
        out[key] = value
    return out


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


_NOT_JSON = object()


def read_yaml(path, *, user=True):
    """The mapping in a config file: JSON if it reads as JSON (as Snakemake reads it), else
    YAML read strictly (`_StrictLoader`).

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
        # JSON first, as Snakemake reads a config file (YAML 1.1 would read 5e-2 as text)
        data = json.loads(text, object_pairs_hook=_json_object)
    except json.JSONDecodeError:
        data = _NOT_JSON
    except ValueError as err:
        raise ConfigError(f"{path}: JSON: {err}") from None
    try:
        if data is _NOT_JSON:
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


def _replaced(user, section, name=None):
    replace = user.get("replace", False)
    if replace is True:
        return True
    item = section if name is None else f"{section}.{name}"
    return isinstance(replace, list) and item in replace


def _layer_block(config, user, key, problems):
    """Layer the user's top-level block ``key`` (of `BLOCKS`) on the paper's: its settings
    are the user's; a part that differs from the paper's is refused unless replaced."""
    mine, paper = user[key], config.get(key)
    if not isinstance(mine, dict) or not isinstance(paper, dict) or _replaced(user, key):
        config[key] = copy.deepcopy(mine)        # replaced whole; the schema checks it
        return
    settings = BLOCKS[key]
    differ = sorted(k for k, v in mine.items() if k not in settings and paper.get(k) != v)
    for part in differ:
        problems.append(
            f"{key}.{part}: the paper's config (config/config.yaml) has this block; yours "
            f"differs and would overwrite its results ({_BLOCK_RESULTS[key]}).\n"
            f"  Leave it out (only {', '.join(f'{key}.{s}' for s in settings)} is yours to "
            f"set), or list it to replace the paper's: replace: [{key}] (or replace: true)")
    config[key] = {**paper, **copy.deepcopy(mine)}


_BLOCK_RESULTS = {"validation": "results/validation/, results/figures/work_precision.png and "
                                "stress.png, results/reports/validation/"}


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
        if key in BLOCKS:
            _layer_block(config, user, key, problems)
        elif key not in SECTIONS:
            config[key] = copy.deepcopy(value)      # SETTINGS: the user's (others: the
                                                    # schema names them)
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
            if str(item) in BLOCKS and isinstance(user.get(str(item)), dict):
                continue
            if section not in SECTIONS or name not in (user.get(section) or {}):
                problems.append(f"replace: {item!r} names no entry of your file; allowed: "
                                f"<section>.<name> with section in {list(SECTIONS)}, or a "
                                f"block of your file in {list(BLOCKS)}")
    if problems:
        raise ConfigError(problems)
    own = None
    if user.get("paper", True) is False:
        own = {s: set(user.get(s) or {}) if isinstance(user.get(s), dict) else set()
               for s in SECTIONS}
    return config, own


def deep_merge(base, extra):
    """``base`` with ``extra`` merged in key by key (mappings recursively), as Snakemake
    merges several ``--configfile`` files; neither is changed."""
    out = dict(base)
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = deep_merge(out[key], value)
        else:
            out[key] = value
    return out
