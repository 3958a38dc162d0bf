"""The documentation site and what its pages show: every code block runs.

- Every ```python block of the pages runs, in order, each page in a namespace of its own (the
  API guide's examples build on one another).
- The getting-started page's study plans as it says, and the error it shows is the message a
  user gets, word for word.
- The config reference is generated from the schema: every key of a study is in it.
- The public entry points' docstrings have an Examples section, which runs (doctest).
- The ``slow`` suite builds the whole site as ``make docs`` does (``sphinx-build -W``: any
  warning fails), the tutorials executed.
"""
import doctest
import re
import subprocess
import sys

import pytest
import yaml

from helpers import ROOT

DOCS = ROOT / "docs"
PAGES = sorted(DOCS.glob("*.md")) + sorted((DOCS / "tutorials").glob("*.md"))
PYTHON_PAGES = [p for p in PAGES if "```python" in p.read_text()]
#: The public entry points: each docstring has an Examples section that runs.
ENTRY_POINTS = ("simulate", "simulate_chunks", "periodic_orbits", "periodic_motions",
                "orbit_map", "domain_boundaries", "attractor_map")


def _blocks(text, lang):
    return re.findall(rf"^```{lang}\n(.*?)^```", text, re.S | re.M)


@pytest.mark.parametrize("page", PYTHON_PAGES, ids=[p.name for p in PYTHON_PAGES])
def test_every_python_block_of_a_page_runs(page):
    namespace = {"__name__": f"docs.{page.stem}"}
    blocks = _blocks(page.read_text(), "python")
    assert blocks
    for k, block in enumerate(blocks):
        exec(compile(block, f"{page.name}, block {k}", "exec"), namespace)


def test_the_getting_started_study_plans_and_its_error_is_the_real_one(tmp_path):
    from vibroimpact.pipeline import config as configuration
    from vibroimpact.pipeline.config.messages import ConfigError

    text = (DOCS / "getting-started.md").read_text()
    (study,) = _blocks(text, "yaml")
    config, plan = configuration.load(yaml.safe_load(study), root=ROOT)
    assert "stiff" in config["studies"] and plan.cells > 0
    shown = re.search(r"^error: studies\.stiff\.zeta.*$", text, re.M).group(0)
    with pytest.raises(ConfigError) as info:
        configuration.load(yaml.safe_load(study.replace("zeta: 0.1", "zeta: 1.5")), root=ROOT)
    assert shown == f"error: {info.value}"


def test_the_config_reference_lists_every_study_key():
    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        import config_reference
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    schema = yaml.safe_load((ROOT / "workflow/schemas/config.schema.yaml").read_text())
    text = config_reference.reference_text()
    section = text.split("## `config.studies.<name>`")[1].split("\n## ")[0]
    for key in schema["$defs"]["study"]["properties"]:
        assert f"| `{key}` |" in section, key


@pytest.mark.parametrize("name", ENTRY_POINTS)
def test_an_entry_point_has_examples_that_run(name):
    import vibroimpact

    func = getattr(vibroimpact, name)
    assert "Examples\n    --------" in func.__doc__, f"{name}: no Examples section"
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    (test,) = finder.find(func, name, globs={})
    assert test.examples, f"{name}: no example to run"
    result = runner.run(test)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed"


@pytest.mark.slow
def test_the_site_builds_without_a_warning(tmp_path):
    """``make docs``: every page and the references, offline, without a warning. The
    tutorials' pages are built without running their cells (``nb_execution_mode=off``):
    tests/test_tutorials.py runs every cell of each, in the same session, so running them
    here again only doubled their cost."""
    out = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b",
                          "html", "-D", "nb_execution_mode=off", str(DOCS),
                          str(tmp_path / "html")],
                         capture_output=True, text=True, timeout=1200, cwd=ROOT)
    assert out.returncode == 0, out.stderr[-5000:]
    assert (tmp_path / "html" / "index.html").exists()
    for page in ("getting-started", "config", "reference", "tutorials/index"):
        assert (tmp_path / "html" / f"{page}.html").exists(), page
