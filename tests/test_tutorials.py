"""The tutorials of the documentation site (docs/tutorials/*.md) run from top to bottom.

Each tutorial is a MyST-NB text notebook that the site executes when it is built
(`make docs`); this runs the same notebooks in the fast suite, so a change to the API that
breaks one fails here first, naming the cell. A tutorial is read by myst-nb's own reader into
an nbformat notebook and executed by nbclient in a fresh kernel, in a temporary directory (so
nothing it might write lands in the repository). Each is written to run in under ~20 s on 2
busy cores (numba kernels cached); the timeout only stops a hung kernel.
"""
from pathlib import Path

import pytest

TUTORIALS = Path(__file__).resolve().parents[1] / "docs" / "tutorials"
#: The tutorials, in the order of their toctree (docs/tutorials/index.md).
NAMES = ("random_force", "periodic_motions", "basins", "two_walls", "plane_map")
#: Seconds a whole notebook may take before the kernel is taken as hung.
TIMEOUT = 300


def read_tutorial(path):
    """The MyST markdown notebook at `path` as an nbformat notebook (myst-nb's reader)."""
    from myst_nb.core.read import read_myst_markdown_notebook

    return read_myst_markdown_notebook(path.read_text(encoding="utf-8"), path=path)


def test_every_tutorial_is_listed():
    """The toctree and this test name the same tutorials as the directory holds."""
    on_disk = {p.stem for p in TUTORIALS.glob("*.md")} - {"index"}
    assert on_disk == set(NAMES)
    index = (TUTORIALS / "index.md").read_text(encoding="utf-8")
    assert all(f"\n{name}\n" in index for name in NAMES)


@pytest.mark.parametrize("name", NAMES)
def test_tutorial_runs(name, tmp_path):
    """Every cell of the tutorial executes without error (an error names the cell)."""
    nbclient = pytest.importorskip("nbclient")
    nb = read_tutorial(TUTORIALS / f"{name}.md")
    assert any(cell.cell_type == "code" for cell in nb.cells), "no code cell was read"
    client = nbclient.NotebookClient(nb, timeout=TIMEOUT, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    errors = [out for cell in nb.cells if cell.cell_type == "code"
              for out in cell.get("outputs", ()) if out.get("output_type") == "error"]
    assert not errors, errors
