"""Provenance: what every output records about how it was made, and the code digests.

`provenance` is called by each job at run time (never passed through the workflow's params,
so a commit alone reruns nothing) and records the package version, the git commit of the
package's source tree with a dirty flag, the config block the job read (YAML text and
digest), the creation time, the seed and the paper's reference, and, for a study expanded
from a sweep, its combination (`sweep_attrs`). `code_digest` is what the workflow puts in
params instead: a digest of the code a job runs (the import closure of its script, docstrings
and comments left out), so editing it (committed or not) reruns exactly the jobs it feeds.
"""
import ast
import functools
import gc
import hashlib
import json
from pathlib import Path
import subprocess

__all__ = ["code_closure", "code_digest", "config_digest", "config_text", "git_state",
           "provenance", "sweep_attrs"]

PACKAGE_DIR = Path(__file__).resolve().parents[1]


def config_digest(obj):
    """SHA-256 of the canonical JSON form of a config fragment."""
    text = json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


@functools.cache
def git_state():
    """``(commit, dirty)`` of the git tree holding the package sources, or ``("unknown", -1)``.

    ``dirty`` is 1 when tracked files differ from the commit (the output may come from
    uncommitted code), 0 when clean; an installed copy outside git gives ``("unknown", -1)``.
    """
    def git(*args):
        out = subprocess.run(["git", *args], cwd=PACKAGE_DIR, capture_output=True, text=True,
                             timeout=30)
        if out.returncode != 0:
            raise OSError(out.stderr)
        return out.stdout.strip()
    try:
        commit = git("rev-parse", "HEAD")
        dirty = int(bool(git("status", "--porcelain", "--untracked-files=no")))
    except (OSError, subprocess.SubprocessError):
        return "unknown", -1
    return commit, dirty


def config_text(obj):
    """The YAML text of a config fragment, keys sorted (what a dataset's ``config`` holds)."""
    import yaml

    return yaml.safe_dump(obj, sort_keys=True, default_flow_style=None, width=100)


def sweep_attrs(config_block):
    """``sweep``, ``sweep_index`` and ``sweep_<key>`` (e.g. ``sweep_eps``, ``sweep_rms``) of a
    study expanded from a sweep (its block's ``sweep`` key,
    `vibroimpact.pipeline.config.sweeps.expand_sweeps`); empty for any other block."""
    sweep = config_block.get("sweep") if isinstance(config_block, dict) else None
    if not sweep:
        return {}
    attrs = {"sweep": str(sweep["name"]), "sweep_index": int(sweep["index"])}
    attrs.update({f"sweep_{key}": value for key, value in sweep["values"].items()})
    return attrs


def provenance(config_block, seed=None):
    """Global attributes every output carries, collected now (at run time).

    ``config`` (the block as YAML text: the same block the rule's params carry, so the
    dataset says what it was computed from), ``config_digest``, ``created`` (UTC, ISO
    8601), ``package_version``, ``git_commit`` and ``git_dirty``, ``software`` (JSON: the
    versions that can change a number and the CPU, `vibroimpact._release.software`),
    ``paper_reference``; and
    :func:`sweep_attrs` for a study of a sweep.

    Parameters
    ----------
    config_block : mapping
        The config the job read.
    seed : int, optional
        The seed of the random input the output derives from.
    """
    from datetime import datetime, timezone

    # the function, not the lazy ``__version__``: a code digest follows a named function,
    # while a name that only the package's ``__getattr__`` knows reaches all of it
    from vibroimpact import PAPER_REFERENCE, _version
    from vibroimpact._release import software

    commit, dirty = git_state()
    attrs = dict(package_version=_version(), git_commit=commit, git_dirty=dirty,
                 software=json.dumps(software()),
                 config=config_text(config_block), config_digest=config_digest(config_block),
                 created=datetime.now(timezone.utc).isoformat(timespec="seconds"),
                 paper_reference=PAPER_REFERENCE)
    if seed is not None:
        attrs["seed"] = int(seed)
    attrs.update(sweep_attrs(config_block))
    return attrs


# --- code digests: the import closure of what a rule runs, blind to docstrings and comments --


def _is_docstring(stmt):
    return isinstance(stmt, ast.Expr) and isinstance(stmt.value, ast.Constant) \
        and isinstance(stmt.value.value, str)


def _runs_code(node):
    """Whether evaluating ``node`` (a top-level assignment's value) may call anything."""
    return any(isinstance(n, (ast.Call, ast.Lambda, ast.comprehension)) for n in ast.walk(node))


_BODIES = (ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)


def _unit_name(stmt):
    """The name of the part a top-level statement belongs to (None: run on import)."""
    if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
        return stmt.name
    if isinstance(stmt, (ast.Assign, ast.AnnAssign)) and not _runs_code(stmt.value):
        targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
        if len(targets) == 1 and isinstance(targets[0], ast.Name):
            return targets[0].id
    return None


class _Module:
    """One module of the package: its code digest and its parts (``units``).

    A unit is a top-level function, class or literal assignment (run only when something
    reaches its name), or ``None``: every other top-level statement, run on import.
    ``bindings`` maps each name an import statement binds, anywhere in the module, to
    ``(module, None)`` or ``(module, attribute)``; ``defined``: every name it assigns.
    """

    def __init__(self, name, tree, is_package):
        self.name, self.is_package = name, is_package
        self.bindings, self.defined, self.units, self.facts = {}, set(), {None: []}, {}
        if tree.body and _is_docstring(tree.body[0]):
            tree.body = tree.body[1:]
        for stmt in tree.body:
            self.units.setdefault(_unit_name(stmt), []).append(stmt)
            self.facts[id(stmt)] = self._scan(stmt)
        self.digest = hashlib.sha256(ast.dump(tree).encode()).hexdigest()

    def _scan(self, stmt):
        """Take the docstrings out of ``stmt`` and list what it names: one pass over it."""
        facts = []
        for node in ast.walk(stmt):
            if isinstance(node, _BODIES):
                if node.body and _is_docstring(node.body[0]):
                    node.body = node.body[1:] or [ast.Pass()]
            elif isinstance(node, ast.Name):
                if isinstance(node.ctx, ast.Store):
                    self.defined.add(node.id)
                else:
                    facts.append(("name", node.id))
            elif isinstance(node, ast.Attribute):
                facts.append(("attribute", node))
            elif isinstance(node, (ast.Import, ast.ImportFrom)):
                for bound, target, attr in _imported(node, self.package):
                    self.bindings.setdefault(bound, []).append((target, attr))
                    facts.append(("import", target, attr))
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                facts.append(("string", node.value))
            elif isinstance(node, ast.Call) and _dynamic(node):
                facts.append(("dynamic", node))
        return facts

    @property
    def package(self):
        return self.name if self.is_package else self.name.rpartition(".")[0]


def _imported(node, package):
    """``(bound name, module, attribute or None)`` of each name an import statement binds."""
    if isinstance(node, ast.Import):
        for alias in node.names:
            if alias.asname:
                yield alias.asname, alias.name, None
            else:       # `import a.b` binds a
                yield alias.name.split(".")[0], alias.name.split(".")[0], None
    elif isinstance(node, ast.ImportFrom):
        base = node.module or ""
        if node.level:
            parts = package.split(".")[:len(package.split(".")) - node.level + 1]
            base = ".".join(parts + ([base] if base else []))
        for alias in node.names:
            yield alias.asname or alias.name, base, alias.name


class _Graph:
    """The modules of package ``vibroimpact`` and what each part of each one reaches."""

    def __init__(self, package_dir):
        self._reaches = {}
        self.modules = {}
        for path in sorted(package_dir.rglob("*.py")):
            parts = path.relative_to(package_dir.parent).with_suffix("").parts
            is_package = parts[-1] == "__init__"
            name = ".".join(parts[:-1] if is_package else parts)
            self.modules[name] = _Module(name, ast.parse(path.read_text(), str(path)),
                                         is_package)

    def closure(self, tree):
        """The modules of the package that code ``tree`` (a script) reaches, sorted."""
        entry = _Module("__main__", tree, False)
        seen, todo = set(), [(entry, None)]
        while todo:
            module, unit = todo.pop()
            if (module.name, unit) in seen or unit not in module.units:
                continue
            seen.add((module.name, unit))
            todo += self._unit_reaches(module, unit)
        return sorted({name for name, _ in seen} - {"__main__"})

    def _unit_reaches(self, module, unit):
        """What part ``unit`` of ``module`` reaches (once per part of the package)."""
        key = (module.name, unit)
        if key not in self._reaches or module.name == "__main__":
            self._reaches[key] = [part for stmt in module.units[unit]
                                  for part in self._reached(module, stmt)]
        return self._reaches[key]

    def _top(self, name):
        """The top-level parts of module ``name`` and of the packages above it."""
        parts = name.split(".")
        return [(self.modules[m], None) for m in (".".join(parts[:k + 1])
                                                   for k in range(len(parts)))
                if m in self.modules]

    def _attribute(self, module_name, attr):
        """What ``module.attr`` reaches: a submodule, a unit, or the module's ``__getattr__``."""
        module = self.modules.get(module_name)
        if module is None:
            return []
        if f"{module_name}.{attr}" in self.modules:
            return self._top(f"{module_name}.{attr}")
        if attr in module.units:
            return [(module, attr)]
        if attr in module.defined:
            return [(module, None)]
        for target, name in module.bindings.get(attr, []):  # a name the module imports
            if target in self.modules and target != module_name:
                return self._top(target) + (self._attribute(target, name) if name else [])
        return self._lazy(module, attr) or [(module, "__getattr__")]

    def _lazy(self, module, attr):
        """Where a lazy ``__getattr__`` of ``module`` loads ``attr`` from, by the entry for it
        in a dict literal it reads (``{"simulate": "vibroimpact.impact.simulate"}``,
        ``{"density": "events"}``); empty if none names it."""
        getter = module.units.get("__getattr__", [])
        tables = {fact[1] for stmt in getter for fact in module.facts[id(stmt)]
                  if fact[0] == "name"} & set(module.units)
        for stmt in (s for table in sorted(tables) for s in module.units[table]):
            if not isinstance(getattr(stmt, "value", None), ast.Dict):
                continue    # a function or an import the getter calls: not a table
            for key, value in zip(stmt.value.keys, stmt.value.values):
                if isinstance(key, ast.Constant) and key.value == attr \
                        and isinstance(value, ast.Constant) and isinstance(value.value, str):
                    for name in (value.value, f"{module.package}.{value.value}"):
                        if name in self.modules:
                            return self._top(name) + self._attribute(name, attr)
        return []

    def _resolve(self, module, expr):
        """The package module an expression names (``stats``, ``stats.events``), or None."""
        if isinstance(expr, ast.Name):
            targets = [(t, n) for t, n in module.bindings.get(expr.id, []) if t in self.modules]
            for target, name in targets:
                full = f"{target}.{name}" if name else target
                if full in self.modules:
                    return full
        elif isinstance(expr, ast.Attribute):
            base = self._resolve(module, expr.value)
            if base and f"{base}.{expr.attr}" in self.modules:
                return f"{base}.{expr.attr}"
        return None

    def _reached(self, module, stmt):
        """The parts of the package that statement ``stmt`` of ``module`` reaches."""
        out = []
        for kind, *fact in module.facts[id(stmt)]:
            if kind == "import" and fact[0] in self.modules:
                out += self._top(fact[0]) + (self._attribute(*fact) if fact[1] else [])
            elif kind == "name" and fact[0] in module.units:
                out.append((module, fact[0]))
            elif kind == "attribute":
                base = self._resolve(module, fact[0].value)
                if base:
                    out += self._attribute(base, fact[0].attr)
            elif kind == "string" and fact[0] in self.modules:
                out += self._top(fact[0])
            elif kind == "dynamic":
                out += self._dynamic_import(module, fact[0], stmt)
        return out

    def _dynamic_import(self, module, call, stmt):
        """``importlib.import_module(<not a constant>)`` or ``getattr(<module>, <not a
        constant>)``: the modules under the constant prefix of an f-string name, else those
        named by the strings of the tables ``stmt`` reads (a lazy ``__getattr__``), else
        every module of the package."""
        if isinstance(call.func, ast.Name) and call.func.id == "getattr":
            base = self._resolve(module, call.args[0])
            if base is None:
                return []
            return [(self.modules[base], unit) for unit in self.modules[base].units]
        arg = call.args[0]
        if isinstance(arg, ast.JoinedStr) and arg.values and isinstance(arg.values[0],
                                                                         ast.Constant):
            # import_module(f"vibroimpact.plotting.{name}"): the modules under that prefix
            prefix = arg.values[0].value
            found = [m for m in self.modules if m.startswith(prefix)]
            if found:
                return [part for m in found for part in self._top(m)]
        tables = {n.id for n in ast.walk(stmt) if isinstance(n, ast.Name)} & set(module.units)
        names = [c.value for t in tables for s in module.units[t] for c in ast.walk(s)
                 if isinstance(c, ast.Constant) and isinstance(c.value, str)]
        found = [m for s in names for m in (s, f"{module.package}.{s}") if m in self.modules]
        if not found:
            found = [m for m in self.modules if m.startswith(f"{module.package}.")]
        return [part for m in found for part in self._top(m)]


def _dynamic(call):
    """Whether ``call`` imports or looks up by a name computed at run time."""
    func = call.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
    if name == "getattr" and len(call.args) >= 2:
        return not isinstance(call.args[1], ast.Constant)
    return name == "import_module" and bool(call.args) \
        and not isinstance(call.args[0], ast.Constant)


@functools.cache
def _graph(package_dir):
    enabled = gc.isenabled()
    gc.disable()        # some 10^5 tree nodes, none cyclic garbage: no collections meanwhile
    try:
        return _Graph(Path(package_dir))
    finally:
        if enabled:
            gc.enable()


def _script_tree(path):
    """The code of a script, or of a notebook's code cells (IPython magics left out)."""
    path = Path(path)
    text = path.read_text()
    if path.suffix == ".ipynb":
        cells = json.loads(text)["cells"]
        text = "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
        text = "\n".join(line for line in text.splitlines()
                         if not line.lstrip().startswith(("%", "!")))
    return ast.parse(text, str(path))


def code_closure(script, package_dir=PACKAGE_DIR):
    """The modules of vibroimpact that ``script`` (a ``.py`` file or an ``.ipynb`` notebook)
    imports, transitively, found statically from the sources in ``package_dir``: every
    import statement, at the top of a module or inside a function, of the functions and
    classes the script's code reaches (a name looked up at run time, as in a lazy
    ``__getattr__``, reaches the modules its table names, or else the whole package)."""
    return _graph(package_dir).closure(_script_tree(script))


@functools.cache
def code_digest(script, package_dir=PACKAGE_DIR):
    """Digest of the code ``script`` runs: each module of :func:`code_closure` by name and
    abstract syntax tree, docstrings removed (comments are not in the tree), so editing a
    docstring or a comment changes no digest and editing code changes the digests of
    exactly the scripts that reach it. Computed once per script and process."""
    modules = _graph(package_dir).modules
    digest = hashlib.sha256()
    for name in code_closure(script, package_dir):
        digest.update(f"{name}\0{modules[name].digest}\0".encode())
    return digest.hexdigest()[:16]
