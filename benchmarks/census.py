"""How the physical model travels through a source tree, counted by static analysis.

The model (damping ``zeta``, restitution ``eps``, the second wall's ``gap`` / ``eps_lower``,
the plane of a map) can travel as loose arguments, as one ``model`` object, as a parameter
vector filled slot by slot, or as branches on what the model has. This reads the source of
a checkout with :mod:`ast` (nothing of the package is imported) and counts each of those
ways, so that two revisions can be compared:

    python benchmarks/census.py ROOT [ROOT2]

It reads ``ROOT/src/vibroimpact/**/*.py``, ``ROOT/workflow/**/*.py``, ``*.smk`` and
``ROOT/workflow/Snakefile``. Snakemake files are translated to Python by Snakemake's own
parser (when snakemake is importable; otherwise they are skipped with a warning), and the
functions that translation generates for a rule's job are not counted. With two roots the
table gives both counts and ROOT2 - ROOT; the definition of every row is printed under it,
and the items behind the listed metrics (which functions, files or imports) follow.
"""
import ast
from collections import Counter
from pathlib import Path
import sys
import types

TWO_WALL_WORDS = {"gap", "n_walls", "two", "two_walls", "walls", "eps_lower", "clearance",
                  "lower"}
PLANE_WORDS = {"plane"}
SECOND_WALL_PARAMS = {"gap", "eps_lower", "clearance"}
KINDS = {"events", "map", "spectra", "trace", "escape", "predictors", "basins", "lyapunov",
         "orbits", "boundaries"}
MANY_PARAMS = 15
TOP_FILES = 10


# --- reading a tree ---------------------------------------------------------------------

def snakemake_source(path):
    """The Python that Snakemake's parser makes of a Snakefile, or None without snakemake."""
    try:
        from snakemake import parser
    except ImportError:
        return None

    class Source:
        def get_path_or_uri(self, secret_free=True):
            return str(path)

    workflow = types.SimpleNamespace(
        sourcecache=types.SimpleNamespace(open=lambda source: open(path)))
    code, _ = parser.parse(Source(), workflow, {})
    return code


def read_tree(root):
    """The files of a checkout, each with ``path`` (relative to the root), ``area`` ("src"
    or "workflow"), ``tree`` (its ast.Module), ``nodes`` (every node of it) and ``defs``
    (:func:`functions`)."""
    root = Path(root)
    paths = [("src", p) for p in sorted((root / "src" / "vibroimpact").rglob("*.py"))]
    flow = root / "workflow"
    paths += [("workflow", p) for p in sorted(flow.rglob("*.py")) + sorted(flow.rglob("*.smk"))]
    if (flow / "Snakefile").is_file():
        paths.append(("workflow", flow / "Snakefile"))
    files = []
    for area, path in paths:
        if "__pycache__" in path.parts:
            continue
        code = path.read_text() if path.suffix == ".py" else snakemake_source(path)
        if code is None:
            print(f"warning: snakemake not importable, {path} skipped", file=sys.stderr)
            continue
        tree = ast.parse(code, str(path))
        files.append(types.SimpleNamespace(root=root, path=str(path.relative_to(root)),
                                           area=area,
                                           tree=tree, nodes=list(ast.walk(tree)),
                                           defs=functions(tree)))
    return files


def functions(tree):
    """``(qualified name, def node)`` of every def of a module, methods and nested defs
    included, but not the job functions Snakemake generates for its rules."""
    found = []

    def visit(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                if not child.name.startswith("__rule_"):
                    found.append((prefix + child.name, child))
                visit(child, prefix + child.name + ".")
            elif isinstance(child, ast.ClassDef):
                visit(child, prefix + child.name + ".")
            else:
                visit(child, prefix)
    visit(tree, "")
    return found


def params(fn):
    """The parameters of a def: positional-only, ordinary, keyword-only, ``*args``,
    ``**kwargs``."""
    a = fn.args
    return a.posonlyargs + a.args + a.kwonlyargs + [p for p in (a.vararg, a.kwarg) if p]


def names_in(expr):
    """The Name ids and Attribute attrs of an expression (not the method of a call)."""
    methods = {id(n.func) for n in ast.walk(expr) if isinstance(n, ast.Call)}
    for n in ast.walk(expr):
        if isinstance(n, ast.Name):
            yield n.id
        elif isinstance(n, ast.Attribute) and id(n) not in methods:
            yield n.attr


def keys_in(expr):
    """The string keys of an expression: ``x["k"]``, ``x.get("k")``, ``"k" in x``,
    ``getattr(x, "k")`` / ``hasattr(x, "k")``."""
    for n in ast.walk(expr):
        candidates = []
        if isinstance(n, ast.Subscript):
            candidates = [n.slice]
        elif isinstance(n, ast.Call) and n.args:
            if isinstance(n.func, ast.Attribute) and n.func.attr == "get":
                candidates = n.args[:1]
            elif isinstance(n.func, ast.Name) and n.func.id in ("getattr", "hasattr"):
                candidates = n.args[1:2]
        elif isinstance(n, ast.Compare) and isinstance(n.ops[0], (ast.In, ast.NotIn)):
            candidates = [n.left]
        for c in candidates:
            if isinstance(c, ast.Constant) and isinstance(c.value, str):
                yield c.value


# --- the metrics: each returns a Counter of item -> count (its total: the row's value) ---

def with_params(files, test):
    """The defs whose parameters pass ``test(set of names, list of ast.arg)``."""
    found = Counter()
    for f in files:
        for name, fn in f.defs:
            args = params(fn)
            if test({a.arg for a in args}, args):
                found[f"{f.path}:{name}"] += 1
    return found


def loose_zeta_eps(files):
    """1. Defs taking both ``zeta`` and ``eps``."""
    return with_params(files, lambda names, _: {"zeta", "eps"} <= names)


def second_wall_params(files):
    """2. Defs taking ``gap``, ``eps_lower`` or ``clearance``."""
    return with_params(files, lambda names, _: bool(SECOND_WALL_PARAMS & names))


def annotated_model(arg):
    """Whether a parameter's annotation names ``Model`` (``Model``, ``model.Model``,
    ``"Model"``)."""
    note = arg.annotation
    return note is not None and ("Model" in names_in(note) or
                                 isinstance(note, ast.Constant) and note.value == "Model")


def model_params(files):
    """3. Defs taking ``model``, or a parameter annotated ``Model``."""
    return with_params(files, lambda names, args: "model" in names or
                       any(map(annotated_model, args)))


def vector_builders(files):
    """4. Defs (or a module's top level) that store into ``x[...]`` with an index naming a
    ``P_*`` constant (``P[P_ZETA] = ...``, ``P[n + kernels.P_EPS] = ...``,
    ``P[[kernels.P_A, ...]] = ...``); a store counts for the innermost def around it."""
    found = Counter()
    for f in files:
        for node in f.nodes:
            targets = (node.targets if isinstance(node, ast.Assign) else
                       [node.target] if isinstance(node, (ast.AugAssign, ast.AnnAssign))
                       else [])
            stores = [t for target in targets for t in ast.walk(target)
                      if isinstance(t, ast.Subscript)]
            if any(n.startswith("P_") for s in stores for n in names_in(s.slice)):
                around = [(fn.lineno, name) for name, fn in f.defs
                          if fn.lineno <= node.lineno <= fn.end_lineno]
                found[f"{f.path}:{max(around)[1] if around else '<module>'}"] = 1
    return found


def branches(files, words):
    """Per file, the ``if`` / ``elif`` / ternary tests that mention one of ``words``."""
    found = Counter()
    for f in files:
        for node in f.nodes:
            if isinstance(node, (ast.If, ast.IfExp)) and (
                    words & set(names_in(node.test)) or words & set(keys_in(node.test))):
                found[f.path] += 1
    return found


def two_wall_branches(files):
    """5. Tests mentioning the second wall."""
    return branches(files, TWO_WALL_WORDS)


def plane_branches(files):
    """6. Tests mentioning the plane."""
    return branches(files, PLANE_WORDS)


def many_params(files):
    """7. Defs with more than ``MANY_PARAMS`` parameters, item -> its parameter count."""
    found = Counter()
    for f in files:
        for name, fn in f.defs:
            found[f"{f.path}:{name}"] = len(params(fn))
    return found


def kind_listings(files):
    """8. Per file, the tuple, list, set literals and dict literals' keys holding at least
    three product kinds as string elements."""
    found = Counter()
    for f in files:
        for node in f.nodes:
            elements = (node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else
                        node.keys if isinstance(node, ast.Dict) else [])
            kinds = [e for e in elements if isinstance(e, ast.Constant) and e.value in KINDS]
            if len(kinds) >= 3:
                found[f.path] += 1
    return found


def results_literals(files, area):
    """9. Per file of ``area``, the string literals starting with ``results/`` (an
    f-string: its first constant part)."""
    found = Counter()
    for f in files:
        if f.area != area:
            continue
        parts = {id(v) for n in f.nodes if isinstance(n, ast.JoinedStr) for v in n.values}
        for node in f.nodes:
            if isinstance(node, ast.JoinedStr) and node.values:
                node = node.values[0]
            elif id(node) in parts:
                continue
            if (isinstance(node, ast.Constant) and isinstance(node.value, str)
                    and node.value.startswith("results/")):
                found[f.path] += 1
    return found


def importer_package(path):
    """The package of a file: the first component under ``src/vibroimpact`` (a top-level
    module's name), or "workflow"."""
    parts = Path(path).parts
    return Path(parts[2]).stem if parts[0] == "src" else "workflow"


def imports(f):
    """``(target, text, bound name)`` of every import of a file: the target as components
    (``from vibroimpact.a import _b`` -> ``["vibroimpact", "a", "_b"]``, a relative import
    resolved), the statement for that name, and the local name it binds."""
    for node in f.nodes:
        if isinstance(node, ast.ImportFrom):
            module = (node.module or "").split(".")
            if node.level:
                here = ["vibroimpact"] + list(Path(f.path).parts[2:-1])
                module = here[:len(here) - node.level + 1] + [m for m in module if m]
            for a in node.names:
                yield (module + [a.name], f"from {'.'.join(module)} import {a.name}",
                       a.asname or a.name)
        elif isinstance(node, ast.Import):
            for a in node.names:
                yield a.name.split("."), "import " + a.name, a.asname


def is_private(name):
    """Whether a name starts with one underscore (not a dunder)."""
    return name.startswith("_") and not name.startswith("__")


def foreign(target, package):
    """Whether ``target`` lies in another package of vibroimpact than ``package``."""
    return target[0] == "vibroimpact" and len(target) > 1 and target[1] != package


def private_imports(files):
    """10. Imports of a private name or module of another package: the target is
    ``vibroimpact.X[.Y...]`` plus the imported name, X is not the importer's package, X is
    public and a component after it starts with one underscore."""
    found = Counter()
    for f in files:
        package = importer_package(f.path)
        for target, text, _ in imports(f):
            if (foreign(target, package) and not is_private(target[1])
                    and any(map(is_private, target[2:]))):
                found[f"{f.path}: {text}"] += 1
    return found


def root_private_imports(files):
    """Imports of the top level's private modules (``from vibroimpact import _checks``) by
    another package."""
    found = Counter()
    for f in files:
        for target, text, _ in imports(f):
            if foreign(target, importer_package(f.path)) and is_private(target[1]):
                found[f"{f.path}: {text}"] += 1
    return found


def private_attributes(files):
    """Private names of another package's module reached as attributes of the name it is
    imported under (``from vibroimpact import noise as _noise`` ... ``_noise._taps``):
    each (file, name) once."""
    found = Counter()
    for f in files:
        package = importer_package(f.path)
        modules = {}
        for target, _, bound in imports(f):
            where = f.root / "src" / Path(*target)
            if bound and (where.is_dir() or where.with_suffix(".py").is_file()):
                modules[bound] = target
        for node in f.nodes:
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                    and node.value.id in modules and is_private(node.attr)):
                target = modules[node.value.id] + [node.attr]
                if foreign(target, package) and not is_private(target[1]):
                    found[f"{f.path}: {'.'.join(target)}"] = 1
    return found


# --- the table ----------------------------------------------------------------------------

def total(c):
    """A row's value: the sum of its metric's counts."""
    return sum(c.values())


def count_items(c):
    """A row's value: how many items (files, defs) its metric found."""
    return len(c)


#: (row label, metric, how the row reads the metric's Counter, definition, detail); detail:
#: "items" lists every item, "top" the TOP_FILES files with the most, "many" the defs with
#: more than MANY_PARAMS parameters, None nothing.
ROWS = [
    ("1. loose zeta, eps", loose_zeta_eps, total,
     "defs (methods, nested defs included) whose parameters include both zeta and eps", None),
    ("2. gap/eps_lower/clearance", second_wall_params, total,
     "defs whose parameters include gap, eps_lower or clearance", None),
    ("3. model parameter", model_params, total,
     "defs with a parameter named model or annotated Model", None),
    ("4. P-vector builders", vector_builders, total,
     "defs (or module top levels) assigning x[...] = with an index naming a P_* constant "
     "(Name or Attribute)", "items"),
    ("5. two-wall branches", two_wall_branches, total,
     "if/elif/ternary tests naming " + "/".join(sorted(TWO_WALL_WORDS)) + " (Name, attribute "
     "not called as a method, or string key: x['k'], x.get('k'), 'k' in x, getattr/hasattr); "
     "comprehension filters and while loops not counted", "top"),
    ("   files with them", two_wall_branches, count_items,
     "files holding at least one such test", None),
    ("6. plane branches", plane_branches, total,
     "if/elif/ternary tests naming plane in the same ways as row 5", "top"),
    (f"7. defs > {MANY_PARAMS} params", many_params,
     lambda c: sum(1 for n in c.values() if n > MANY_PARAMS),
     f"defs with more than {MANY_PARAMS} parameters (positional-only, ordinary, keyword-only, "
     "*args, **kwargs, self all count)", "many"),
    ("   largest param count", many_params, lambda c: max(c.values(), default=0),
     "the most parameters of any def", None),
    ("8. kind listings", kind_listings, total,
     "tuple/list/set literals or dict literals' keys with >= 3 elements among "
     + ", ".join(sorted(KINDS)), "items"),
    ("   files with listings", kind_listings, count_items,
     "files holding at least one such listing", None),
    ("9. results/ literals, src", lambda f: results_literals(f, "src"), total,
     "string literals (an f-string counted once, by its first constant part) starting "
     "with results/, under src/vibroimpact", None),
    ("   results/ literals, workflow", lambda f: results_literals(f, "workflow"), total,
     "the same under workflow/ (scripts, rules, Snakefile)", None),
    ("10. cross-package private imports", private_imports, total,
     "imports of vibroimpact.X...[._name] (relative imports resolved) where X is not the "
     "importer's package (workflow/ is a package of its own) and a component after X starts "
     "with _", "items"),
    ("   private attributes", private_attributes, total,
     "not in row 10: other packages' private names reached as module attributes "
     "(from vibroimpact import noise as _noise; _noise._taps), each file and name once",
     "items"),
    ("   root private-module imports", root_private_imports, total,
     "not in row 10: imports of the top level's private modules (vibroimpact._checks, "
     "_law, ...) by another package", None),
]


def detail(label, kind, counters):
    """The lines listing the items behind a row, each with its count per root."""
    if kind == "many":
        counters = [Counter({k: v for k, v in c.items() if v > MANY_PARAMS}) for c in counters]
    keys = set().union(*counters)
    if not keys:
        return []
    if kind == "top":
        keys = sorted(keys, key=lambda k: (-counters[-1][k], -counters[0][k], k))[:TOP_FILES]
    lines = [f"{label}" + (f" (top {TOP_FILES} files)" if kind == "top" else "")]
    for key in (keys if kind == "top" else sorted(keys)):
        counts = "  ".join(f"{c[key]:>4}" for c in counters)
        lines.append(f"  {counts}  {key}")
    return lines


def main(roots):
    """Print the table for one or two roots, the rows' definitions, then the items."""
    trees = [read_tree(r) for r in roots]
    results, table, details = {}, [], []
    for label, metric, read, _, kind in ROWS:
        if metric not in results:
            results[metric] = [metric(t) for t in trees]
        values = [read(c) for c in results[metric]]
        diff = [f"{values[1] - values[0]:+d}"] if len(values) == 2 else []
        table.append([label] + [str(v) for v in values] + diff)
        if kind:
            details.append(detail(label.strip(), kind, results[metric]))
    header = ["metric"] + [f"ROOT{i + 1 if i else ''}" for i in range(len(roots))]
    header += ["ROOT2-ROOT"] if len(roots) == 2 else []
    widths = [max(len(row[i]) for row in [header] + table) for i in range(len(header))]
    for i, root in enumerate(roots):
        print(f"{header[i + 1]} = {root}")
    print()
    for row in [header] + table:
        print("  ".join([row[0].ljust(widths[0])] +
                        [cell.rjust(width) for cell, width in zip(row[1:], widths[1:])]))
    print()
    for label, _, _, definition, _ in ROWS:
        print(f"{label}: {definition}")
    for lines in details:
        if lines:
            print()
            print("\n".join(lines))


if __name__ == "__main__":
    if not 2 <= len(sys.argv) <= 3:
        sys.exit(__doc__)
    main(sys.argv[1:])
