"""The config reference, generated from the workflow's schema when the site is built.

The directive ``config-reference`` walks ``workflow/schemas/config.schema.yaml`` (what
`vibroimpact.pipeline.config` validates every config against) and writes one section per
block: a table of its keys with their type, allowed values, default and description, nested
blocks as their own sections. The page can then never say what the schema does not.
"""
import json
from pathlib import Path

from docutils.parsers.rst import directives
from sphinx.util.docutils import SphinxDirective
import yaml

SCHEMA = Path(__file__).resolve().parents[2] / "workflow" / "schemas" / "config.schema.yaml"
#: The words a schema keyword gives the allowed values in.
_BOUNDS = (("minimum", ">= {}"), ("exclusiveMinimum", "> {}"), ("maximum", "<= {}"),
           ("exclusiveMaximum", "< {}"), ("minItems", "at least {} items"),
           ("maxItems", "at most {} items"), ("minLength", "at least {} characters"),
           ("minProperties", "at least {} entries"))


#: The keys of a grid written as a range (`$defs.grid_range`).
_GRID = {"start", "stop", "step"}


def _resolve(schema, node):
    """``node`` with a ``$ref`` into ``$defs`` followed (once per level)."""
    while isinstance(node, dict) and "$ref" in node:
        name = node["$ref"].rsplit("/", 1)[-1]
        node = dict(schema["$defs"][name], **{k: v for k, v in node.items() if k != "$ref"})
    return node


def _cell(text):
    """Text safe in a markdown table cell (one line, no bare pipe)."""
    return " ".join(str(text).split()).replace("|", "\\|")


def _type(schema, node):
    node = _resolve(schema, node)
    if "enum" in node:
        return "one of " + ", ".join(f"`{v}`" for v in node["enum"])
    if "const" in node:
        return f"`{node['const']}`"
    for key in ("oneOf", "anyOf"):
        if key in node:
            return " or ".join(_type(schema, n) for n in node[key])
    kind = node.get("type", "any")
    kind = " or ".join(kind) if isinstance(kind, list) else kind
    if kind == "array" and "items" in node and isinstance(node["items"], dict):
        kind = f"list of ({_type(schema, node['items'])})"
    bounds = [fmt.format(node[k]) for k, fmt in _BOUNDS if k in node]
    return kind + (f" ({', '.join(bounds)})" if bounds else "")


def _default(node):
    if "default" not in node:
        return ""
    value = node["default"]
    if value == {}:
        return ""
    return f"`{json.dumps(value)}`"


def _blocks(schema, node, path, out):
    """Append ``(path, description, rows, children)`` for the object ``node`` at ``path``."""
    node = _resolve(schema, node)
    props = node.get("properties")
    entries = node.get("additionalProperties")
    if props is None and isinstance(entries, dict):     # a section of named entries
        entry = _resolve(schema, entries)
        out.append((path, node.get("description", ""), None, None))
        _blocks(schema, entry, f"{path}.<name>", out)
        return
    if not props:
        return
    rows, children = [], []
    for key, sub in props.items():
        sub = _resolve(schema, sub)
        rows.append((key, _type(schema, sub), _default(sub), sub.get("description", "")))
        nested = sub
        for alt in sub.get("oneOf", []):
            alt = _resolve(schema, alt)
            if alt.get("type") == "object" and alt.get("properties"):
                nested = alt
        if set(nested.get("properties", ())) == _GRID:
            continue            # a grid's {start, stop, step}: its type says so
        if nested.get("type") == "object" and (nested.get("properties") or isinstance(
                nested.get("additionalProperties"), dict)):
            children.append((key, nested))
    out.append((path, node.get("description", ""), rows, None))
    for key, nested in children:
        _blocks(schema, nested, f"{path}.{key}", out)


def reference_text(schema_path=SCHEMA, level=2):
    """The reference as MyST markdown: a section per block of the schema."""
    schema = yaml.safe_load(Path(schema_path).read_text())
    out = []
    _blocks(schema, schema, "config", out)
    lines = []
    for path, description, rows, _ in out:
        lines += ["#" * level + f" `{path}`", "", _cell(description), ""]
        if rows:
            lines += ["| key | type and allowed values | default | description |",
                      "|---|---|---|---|"]
            lines += [f"| `{k}` | {_cell(t)} | {_cell(d)} | {_cell(desc)} |"
                      for k, t, d, desc in rows]
            lines.append("")
    return "\n".join(lines)


class ConfigReference(SphinxDirective):
    """``{config-reference}``: the schema's blocks as sections with tables of keys."""

    option_spec = {"level": directives.positive_int}

    def run(self):
        self.env.note_dependency(str(SCHEMA))
        text = reference_text(level=self.options.get("level", 2))
        return self.parse_text_to_nodes(text, allow_section_headings=True)


def setup(app):
    app.add_directive("config-reference", ConfigReference)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
