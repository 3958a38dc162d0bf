"""How a problem of a config is worded: one or two lines naming the key path, the value and
what is allowed, for the schema's errors and for the cross-field checks alike.

:func:`validate` checks a config against its schema
(``workflow/schemas/config.schema.yaml``) with jsonschema, filling the schema's defaults in
place, and turns each jsonschema error into such a line. jsonschema gives the key path
(``error.absolute_path``), the failing keyword (``error.validator``) and the failing schema
node (``error.schema``); written here is only what it does not give: the allowed values in
words, which branch of a ``oneOf`` (a number, or a list of numbers: a sweep) the value
meant, and a number YAML read as text.
"""
import copy
import math
import os
import re
import unicodedata

import yaml

__all__ = ["ConfigError", "VERBOSE_ENV", "validate", "non_text_keys"]

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


class _Problems(list):
    """The problems found so far, each ``<where> = <value>: <problem>; allowed: <allowed>``."""

    def add(self, where, value, problem, allowed_):
        shown = f" = {_short(value)}" if value is not None else ""
        self.append(f"{where}{shown}: {problem}; allowed: {allowed_}")


def _path(parts):
    """``studies.random.delta[2]`` of the key path ``["studies", "random", "delta", 2]``."""
    text = ""
    for p in parts:
        text += f"[{p}]" if isinstance(p, int) else (f".{_key(p)}" if text else _key(p))
    return text or "<top level>"


def _num(x):
    return f"{x:g}" if isinstance(x, float) else str(x)


#: Characters of an "allowed" text beyond which a message keeps only its start (and names
#: where the rest is): a message stays one readable line.
ALLOWED_MAX = 240


def brief(text, parts=()):
    """``text`` as it is when short, else its words within `ALLOWED_MAX` and where the whole
    is: the schema's entry for ``parts``."""
    if len(text) <= ALLOWED_MAX:
        return text
    head = text[:text.rfind(" ", 0, ALLOWED_MAX)].rstrip(",;(") + " ..."
    where = ".".join(str(p) for p in parts if not isinstance(p, int))
    return (f"{head} (the whole description: workflow/schemas/config.schema.yaml"
            + (f", {where})" if where else ")"))


def _short(value):
    """``value`` as YAML on one line, cut to 60 characters."""
    if isinstance(value, str) and _invisible(value):
        return _key(value)
    text = yaml.safe_dump(value, default_flow_style=True, width=10**6).strip()
    text = text.removesuffix("...").strip()
    return text if len(text) <= 60 else text[:57] + "..."


def _read_as_text(value, integer=False):
    """Why a value that reads as a number is text, with how to write it (``integer``: as
    the integer, ``4e5`` -> 400000); None for any other value. The causes: quotes (the text
    YAML would read as a number unquoted), YAML 1.1's exponent rule (``1.0e6``: it wants
    ``1.0e+6``), a leading 0 (``08``: not octal, so text), digits that are not ASCII
    (fullwidth ``１２``)."""
    if not isinstance(value, str):
        return None
    try:
        number = float(value.replace("_", ""))
    except ValueError:
        return None
    if not math.isfinite(number):
        return None
    plain = f"{int(number)}" if integer and number.is_integer() else _num(number)
    odd = sorted({c for c in value if c.isdigit() and c not in "0123456789"})
    if odd:
        names = ", ".join(f"U+{ord(c):04X} {unicodedata.name(c, '?')}" for c in odd)
        return (f"read as the text {value!r}: its digits are not ASCII ({names}); write "
                f"{plain} in ASCII digits")
    try:
        unquoted = yaml.safe_load(value)
    except yaml.YAMLError:
        unquoted = value
    if isinstance(unquoted, (int, float)) and not isinstance(unquoted, bool):
        return f"read as the text {value!r} (it is quoted); write the number without quotes"
    exponent = re.fullmatch(r"\s*([-+]?[0-9_]*\.?[0-9_]*)[eE]([-+]?)([0-9]+)\s*", value)
    if exponent is not None:
        mantissa, sign, digits = exponent.groups()
        if integer and number.is_integer():
            fix = f"{int(number)}"
        else:
            fix = f"{mantissa if '.' in mantissa else mantissa + '.0'}e{sign or '+'}{digits}"
        return (f"read as the text {value!r}: YAML 1.1 reads a number with an exponent only "
                f"with a dot and a signed exponent; write {fix}")
    if re.fullmatch(r"[-+]?0[0-9_]+", value.strip()):
        return (f"read as the text {value!r}: YAML 1.1 reads an integer with a leading 0 as "
                f"octal, and 8, 9 are no octal digits; write {plain} without the leading 0")
    return f"read as the text {value!r}, not as a number; write {plain}"


def _invisible(name):
    """The characters of ``name`` that do not print (a zero-width or no-break space), in
    words, or ''."""
    odd = sorted({c for c in str(name) if not c.isprintable()})
    return ", ".join(f"U+{ord(c):04X} {unicodedata.name(c, 'control character')}"
                     for c in odd)


def _key(part):
    """A key of a path as it is written, or quoted with escapes when it holds a character
    that does not print (``"n\\u200bbatches"``), so two names that print alike differ."""
    if isinstance(part, str) and _invisible(part):
        return '"' + part.encode("unicode_escape").decode("ascii") + '"'
    return str(part)


def _scalar(node):
    """The number branch of a number-or-list node (``zeta``: a value or a sweep), else ``node``."""
    for branch in node.get("oneOf", ()):
        if branch.get("type") in ("number", "integer"):
            return branch
    return node


class _Words:
    """The words for the nodes of one schema, ``root``, which its ``$ref`` keys point into."""

    def __init__(self, root):
        self.root = root

    def target(self, ref):
        """The node ``#/$defs/...`` names."""
        node = self.root
        for part in ref.lstrip("#/").split("/"):
            node = node[part]
        return node

    def resolve(self, node):
        """``node`` with its ``$ref`` followed (to the end of a chain)."""
        while "$ref" in node:
            node = self.target(node["$ref"])
        return node

    def allowed(self, schema):
        """The allowed values of a schema node, in words (``a number > 0 and < 1``)."""
        if "$ref" in schema:
            schema = {**self.target(schema["$ref"]),
                      **{k: v for k, v in schema.items() if k != "$ref"}}
        if "enum" in schema:
            return "one of " + ", ".join(map(str, schema["enum"]))
        if "oneOf" in schema:
            return schema.get("description") or " or ".join(
                self.allowed(s) for s in schema["oneOf"])
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
            lo, hi = schema.get("minItems"), schema.get("maxItems")
            if lo is not None and lo == hi:
                text += f" of exactly {lo} item(s)"
            elif lo is not None:
                text += f" of at least {lo} item(s)"
            elif hi is not None:
                text += f" of at most {hi} item(s)"
            if schema.get("uniqueItems"):
                text += ", all different"
        elif kind == "object":
            props = list(schema.get("properties", {}))
            text = "a mapping" + (f" with keys {', '.join(props)}" if props
                                  else " of named entries")
        else:
            text = "a value"
        if null:
            text += ", or null"
        return text

    def at(self, parts):
        """The schema node describing the config value at the key path ``parts`` (best
        effort: a value jsonschema did not reach, such as a non-finite number)."""
        node = self.root
        for p in parts:
            node = self.resolve(node)
            if "oneOf" in node:
                branch = [b for b in node["oneOf"]
                          if (b.get("type") == "array") == isinstance(p, int)]
                node = self.resolve(branch[0] if branch else node["oneOf"][0])
            if isinstance(p, int):
                node = node.get("items", {})
            elif p in node.get("properties", {}):
                node = node["properties"][p]
            elif isinstance(node.get("additionalProperties"), dict):
                node = node["additionalProperties"]
            else:
                return {}
        return self.resolve(node)

    def describe(self, parts, node=None):
        """What the node at ``parts`` (or ``node``) allows, with its description (its start
        where it is long: `brief`)."""
        node = node if node is not None else self.at(parts)
        text = self.allowed(node) if node else "see workflow/schemas/config.schema.yaml"
        desc = node.get("description", "").strip() if node else ""
        if desc and desc != text and "oneOf" not in node:
            text += f" ({desc})"
        return brief(text, parts)

    def not_allowed(self, parts, value, node=None):
        """``<key path> = <value>: not allowed; allowed: ...`` (``node``: the schema node
        that failed, else the one at ``parts``), saying when a number was read as text."""
        node = node if node is not None else self.at(parts)
        problem = _read_as_text(value, integer=node.get("type") == "integer")
        if (node.get("type") == "integer" and isinstance(value, float) and math.isfinite(value)
                and value.is_integer()):
            problem = (f"a number with a dot or an exponent, not an integer; write "
                       f"{int(value)}")
        return (f"{_path(parts)} = {_short(value)}: {problem or 'not allowed'}; "
                f"allowed: {self.describe(parts, node)}")

    def nonfinite(self, parts, value):
        """The line of a non-finite number (JSON Schema lets ``.nan`` through)."""
        return (f"{_path(parts)} = {value}: not a finite number; allowed: "
                f"{self.describe(parts, _scalar(self.at(parts)))}")

    def messages(self, error):
        """One or two lines for one jsonschema error (descending into oneOf branches)."""
        parts = list(error.absolute_path)
        kind = error.validator
        if kind in ("oneOf", "anyOf") and error.context:
            return self._branch_messages(error, parts)
        if kind == "required":
            missing = [k for k in error.validator_value if k not in error.instance]
            key = missing[0] if missing else error.message.split("'")[1]
            node = self.resolve(error.schema.get("properties", {}).get(key, {}))
            return [f"{_path(parts + [key])}: missing; allowed: "
                    f"{self.describe(parts + [key], node or None)}"]
        if kind == "additionalProperties":
            known = list(error.schema.get("properties", {}))
            extra = [k for k in error.instance if k not in known]
            return [f"{_path(parts + [k])}: unknown key"
                    + (f" (it holds {_invisible(k)}, which does not print)" if _invisible(k)
                       else "") + f"; allowed keys here: {', '.join(known)}"
                    for k in extra]
        names = self.resolve(self.at(parts).get("propertyNames", {}))
        if "propertyNames" in error.schema_path and names.get("description"):
            return [f"{_path(parts)}: the name {error.instance!r} is not allowed; allowed: "
                    f"{self.describe(parts, names)}"]
        if "propertyNames" in error.schema_path:
            return [f"{_path(parts)}: the name {error.instance!r} is not allowed; allowed: "
                    f"letters, digits and _, starting with a letter, at most 120 characters "
                    f"(a file name)"]
        if kind in ("minProperties", "minItems") and not error.instance:
            return [f"{_path(parts)}: empty; allowed: {self.describe(parts)}"]
        # the failing node itself (a figure name's pattern, not the figure item's oneOf)
        node = (error.schema if isinstance(error.schema, dict) and "oneOf" not in error.schema
                else None)
        return [self.not_allowed(parts, error.instance, node)]

    def _branch_messages(self, error, parts):
        """The lines of the ``oneOf`` branch of the value's own type (a mapping, a list, a
        string or a number) when the value has that type and fails inside it; else one line
        naming every branch. (jsonschema's ``best_match`` picks one error: a branch can hold
        several, each worth a line.)"""
        by_branch = {}
        for sub in error.context:
            by_branch.setdefault(sub.relative_schema_path[0], []).append(sub)
        for branch, subs in sorted(by_branch.items()):
            want = self.resolve(error.validator_value[branch]).get("type")
            same = ((want == "object" and isinstance(error.instance, dict))
                    or (want == "array" and isinstance(error.instance, list))
                    or (want == "string" and isinstance(error.instance, str))
                    or (want in ("number", "integer")
                        and isinstance(error.instance, (int, float))))
            if same and not any(s.validator == "type" and not s.relative_path for s in subs):
                return [m for s in subs for m in self.messages(s)]
        node = self.resolve(error.schema)
        return [self.not_allowed(parts, error.instance,
                                 _scalar(node) if _read_as_text(error.instance) else node)]


def _filling_validator(schema):
    """A Draft 2020-12 validator of ``schema`` that fills in each missing key's ``default``
    (a copy of it) as it validates.

    Not ``snakemake.utils.validate(set_default=True)``: it takes a schema file, stops at the
    first error (the config's other problems would be hidden one by one), and fills each
    entry with the same default object (a ``figures: []`` shared by every study).
    """
    import jsonschema

    base = jsonschema.Draft202012Validator
    properties = base.VALIDATORS["properties"]

    def set_defaults(validator, props, instance, schema_):
        if isinstance(instance, dict):
            for name, sub in props.items():
                if "default" in sub and name not in instance:
                    instance[name] = copy.deepcopy(sub["default"])
        yield from properties(validator, props, instance, schema_)

    def whole_pattern(validator, pattern, instance, schema_):
        # JSON Schema's `pattern` is a search, and Python's `$` matches before a final
        # newline: "s1\n" would pass ^[A-Za-z][A-Za-z0-9_]*$; a name must match whole
        if validator.is_type(instance, "string") and not re.fullmatch(pattern, instance):
            yield jsonschema.ValidationError(f"{instance!r} does not match {pattern!r} whole")

    # an integer is an int: JSON Schema 2020-12 counts 1.0 as one, which would reach
    # range(), file names and SeedSequence as a float
    types = base.TYPE_CHECKER.redefine(
        "integer", lambda _, value: isinstance(value, int) and not isinstance(value, bool))
    return jsonschema.validators.extend(
        base, {"properties": set_defaults, "pattern": whole_pattern},
        type_checker=types)(schema)


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


def non_text_keys(value, parts=()):
    """A line for each key of ``value`` that is not text (what YAML reads ``yes:``, ``123:``,
    ``~:`` as, in a config given as a dict; `read_yaml` refuses them with their line)."""
    lines = []
    if isinstance(value, dict):
        for k, v in value.items():
            if not isinstance(k, str):
                kind = {bool: "a boolean", int: "an integer", float: "a number"}.get(
                    type(k), "null" if k is None else f"a {type(k).__name__}")
                lines.append(f"{_path(list(parts))}: the key {k!r} is {kind}, not a name "
                             f"(YAML reads yes:, 123:, ~: so); allowed: text: quote it, or "
                             f"rename it")
            else:
                lines += non_text_keys(v, (*parts, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            lines += non_text_keys(v, (*parts, i))
    return lines


def validate(config, schema):
    """Check ``config`` against the JSON Schema ``schema``, filling defaults in place.

    Raises
    ------
    ConfigError
        One or two lines per problem (the full validator output with
        ``VIBROIMPACT_VERBOSE=1``).
    """
    words = _Words(schema)
    problems = non_text_keys(config)
    problems += [words.nonfinite(p, v) for p, v in _nonfinite(config)]
    if problems:
        raise ConfigError(problems)
    errors = sorted(_filling_validator(schema).iter_errors(config),
                    key=lambda e: list(map(str, e.path)))
    if errors:
        lines = []
        for error in errors:
            for line in words.messages(error):
                if line not in lines:
                    lines.append(line)
        raise ConfigError(lines, details="\n\n".join(str(e) for e in errors))
