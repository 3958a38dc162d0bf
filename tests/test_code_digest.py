"""Code digests (`provenance.code_digest`): the import closure of a script, blind to
docstrings and comments (README, "What reruns").

A small package ``vibroimpact`` written in a temporary directory: a dispatcher whose functions
import their modules lazily, as `pipeline.tasks` does, and a lazy ``__getattr__`` table.
"""
import json
import textwrap

import pytest

from vibroimpact.pipeline import provenance

MODULES = {
    "__init__.py": '"""The package."""\nVERSION = "1"\n',
    "tasks.py": '''\
        """Jobs."""
        from vibroimpact import common


        def draw():
            """Draws."""
            from vibroimpact import drawing
            return drawing.figure(common.LIMIT)


        def simulate():
            from vibroimpact.sim import kernel   # the simulator: only here
            return kernel.run()
        ''',
    "common.py": 'LIMIT = 3\n',
    "drawing.py": 'def figure(n):\n    return n\n',
    "sim/__init__.py": '''\
        import importlib

        _WHERE = {"run": "kernel"}


        def __getattr__(name):
            return getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
        ''',
    "sim/kernel.py": 'def run():\n    """Runs."""\n    return 1  # one\n',
    "sim/unused.py": 'X = 1\n',
}


@pytest.fixture()
def package(tmp_path):
    root = tmp_path / "src" / "vibroimpact"
    for name, text in MODULES.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(textwrap.dedent(text))
    scripts = {"draw": "from vibroimpact import tasks\ntasks.draw()\n",
               "simulate": "from vibroimpact import tasks\ntasks.simulate()\n",
               "lazy": "from vibroimpact import sim\nsim.run()\n"}
    for name, text in scripts.items():
        (tmp_path / f"{name}.py").write_text(text)
    return tmp_path, root


def _digests(tmp_path, root):
    provenance._graph.cache_clear()
    provenance.code_digest.cache_clear()
    return {name: provenance.code_digest(tmp_path / f"{name}.py", root)
            for name in ("draw", "simulate", "lazy")}


def test_the_closure_follows_the_functions_a_script_calls(package):
    tmp_path, root = package
    provenance._graph.cache_clear()
    closure = {name: provenance.code_closure(tmp_path / f"{name}.py", root)
               for name in ("draw", "simulate", "lazy")}
    assert closure["draw"] == ["vibroimpact", "vibroimpact.common", "vibroimpact.drawing",
                               "vibroimpact.tasks"]
    assert closure["simulate"] == ["vibroimpact", "vibroimpact.common", "vibroimpact.sim",
                                   "vibroimpact.sim.kernel", "vibroimpact.tasks"]
    # a lazy __getattr__ reaches the modules its table names, not the whole subpackage
    assert closure["lazy"] == ["vibroimpact", "vibroimpact.sim", "vibroimpact.sim.kernel"]


def test_docstring_and_comment_edits_change_no_digest(package):
    tmp_path, root = package
    before = _digests(tmp_path, root)
    kernel = root / "sim" / "kernel.py"
    kernel.write_text('# a comment\n\ndef run():\n    """Runs, reworded."""\n    return 1\n')
    (root / "tasks.py").write_text((root / "tasks.py").read_text().replace('"""Jobs."""',
                                                                           '"""Jobs!"""'))
    assert _digests(tmp_path, root) == before


def test_a_code_edit_changes_the_digests_of_the_scripts_that_reach_it(package):
    tmp_path, root = package
    before = _digests(tmp_path, root)
    (root / "sim" / "kernel.py").write_text("def run():\n    return 2\n")
    after = _digests(tmp_path, root)
    assert after["draw"] == before["draw"]
    assert after["simulate"] != before["simulate"] and after["lazy"] != before["lazy"]
    (root / "sim" / "unused.py").write_text("X = 2\n")
    assert _digests(tmp_path, root) == after


def test_the_workflow_scripts_reach_what_they_run():
    from pathlib import Path

    scripts = Path(__file__).resolve().parents[1] / "workflow" / "scripts"
    provenance._graph.cache_clear()

    def closure(name):
        return provenance.code_closure(scripts / f"{name}.py")

    assert "vibroimpact.impact.kernels" in closure("simulate_events")
    assert not any(m.startswith("vibroimpact.plotting") for m in closure("simulate_events"))
    assert "vibroimpact.plotting.random" in closure("draw_figure")
    assert not any(m.startswith(("vibroimpact.impact", "vibroimpact.orbits"))
                   for m in closure("draw_figure"))
    assert not any(m.startswith("vibroimpact.impact") for m in closure("solve_orbit_tile"))


def test_every_script_and_notebook_of_the_workflow_has_a_digest():
    # what each rule's params carry: computed at every parse, so a module the walk cannot
    # read (a lazy __getattr__ that calls a function) must not stop the workflow
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    provenance._graph.cache_clear()
    sources = [*sorted((root / "workflow" / "scripts").glob("*.py")),
               *sorted((root / "workflow" / "notebooks").glob("*.ipynb"))]
    assert len(sources) >= 20
    digests = {path.name: provenance.code_digest(path) for path in sources}
    assert all(len(d) == 16 and int(d, 16) >= 0 for d in digests.values())
    closure = provenance.code_closure(root / "workflow" / "scripts" / "simulate_events.py")
    assert {"vibroimpact.impact.stepping", "vibroimpact.impact.events",
            "vibroimpact.impact.tolerances"} <= set(closure)      # the kernels, split by concept


# --- digests kept between runs (`digest_cache`): every Snakemake start reads them ---------


def _cached(tmp_path, root, cache):
    from vibroimpact.pipeline import digest_cache

    digest_cache._sources_key.cache_clear()     # a new process: nothing known but the file
    digest_cache._TABLES.clear()
    provenance._graph.cache_clear()
    provenance.code_digest.cache_clear()
    return {name: digest_cache.cached_code_digest(tmp_path / f"{name}.py", cache, root)
            for name in ("draw", "simulate", "lazy")}


def test_a_kept_digest_is_the_computed_one_and_is_read_not_recomputed(package, monkeypatch):
    from vibroimpact.pipeline import digest_cache

    tmp_path, root = package
    cache = tmp_path / "project" / ".snakemake" / "digests.json"
    assert _cached(tmp_path, root, cache) == _digests(tmp_path, root)
    assert cache.is_file()

    def never(*args):
        raise AssertionError("computed again although the sources are unchanged")

    monkeypatch.setattr(digest_cache, "code_digest", never)
    assert _cached(tmp_path, root, cache) == _digests(tmp_path, root)


def test_an_edit_of_the_package_or_the_script_is_a_miss_with_the_new_digest(package):
    tmp_path, root = package
    cache = tmp_path / "digests.json"
    before = _cached(tmp_path, root, cache)
    (root / "sim" / "kernel.py").write_text("def run():\n    return 2\n")
    after = _cached(tmp_path, root, cache)
    assert after == _digests(tmp_path, root)
    assert after["simulate"] != before["simulate"] and after["draw"] == before["draw"]
    (tmp_path / "draw.py").write_text("from vibroimpact import tasks\ntasks.simulate()\n")
    assert _cached(tmp_path, root, cache)["draw"] == after["simulate"]
    assert len(json.loads(cache.read_text())) == 3        # only the current sources' entries


def test_an_unreadable_or_unwritable_cache_is_a_miss_not_an_error(package):
    tmp_path, root = package
    expected = _digests(tmp_path, root)
    (tmp_path / "damaged.json").write_text('{"truncated": ')
    assert _cached(tmp_path, root, tmp_path / "damaged.json") == expected
    (tmp_path / "a_file").write_text("")               # its folder cannot be made
    assert _cached(tmp_path, root, tmp_path / "a_file" / "digests.json") == expected
    assert not (tmp_path / "a_file").is_dir()


def test_the_installation_keeps_the_digest_of_every_script(tmp_path):
    """`python -m vibroimpact.pipeline.digest_cache` (make's installation step): the digest
    of each workflow script and notebook of the project, as the rules compute it."""
    from vibroimpact.pipeline import digest_cache

    scripts = tmp_path / "workflow" / "scripts"
    scripts.mkdir(parents=True)
    (scripts / "draw.py").write_text("from vibroimpact.pipeline import tasks\n")
    (scripts / "noise.py").write_text("from vibroimpact import stats\n")
    digest_cache._TABLES.clear()
    digest_cache.main(tmp_path, workflow=tmp_path / "workflow")
    kept = json.loads((tmp_path / ".snakemake" / "vibroimpact-code-digests.json").read_text())
    provenance._graph.cache_clear()
    provenance.code_digest.cache_clear()
    assert sorted(kept.values()) == sorted(provenance.code_digest(scripts / name)
                                           for name in ("draw.py", "noise.py"))
