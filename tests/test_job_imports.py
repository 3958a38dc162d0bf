"""What each kind of workflow job loads, and the figure table's link to its functions.

Every job is a fresh interpreter, so what it imports it pays at every run (``benchmarks/
imports.py`` times it). Asserted here are sets of heavy modules, never times: a job that
draws or aggregates never loads numba (STYLE.md, "Imports point one way"), importing the
plotting package loads no scipy (a figure that needs scipy imports it when it draws), and the
figure table, read at every workflow parse, loads no matplotlib.
"""
import ast
import functools
import json
import os
from pathlib import Path
import subprocess
import sys

import numpy as np
import pytest
import scipy.stats

from vibroimpact import plotting
from vibroimpact.pipeline import figures, tasks
from vibroimpact.stats.events import t_quantile

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted((ROOT / "workflow" / "scripts").glob("*.py"))
HEAVY = ("numba", "scipy", "xarray", "matplotlib")
#: The validation jobs import the simulator and its peers at the top: not checked here.
SIMULATE_AT_IMPORT = {"measure_work_precision", "sample_stress_families"}

NOISE = dict(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0, n_samples=20_001,
             seed=19740914, nperseg=256)
RANDOM = dict(noise="band", zeta=0.05, eps=0.5, amplitude=0.0, delta=[0.0, 1.0],
              transient=100.0, tile_size=100, n_batches=20, motion_window=0.1,
              bins=dict(v_after=dict(max=2.5, n=20), interval=dict(max=10.0, n=20),
                        ratio=dict(max=4.0, n=20)))


@functools.lru_cache(maxsize=None)      # most scripts import the same: one interpreter each
def _heavy_after(code):
    """The modules of `HEAVY` a fresh interpreter has loaded after running ``code``."""
    env = {**os.environ, "MPLBACKEND": "Agg",
           "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT / "src"),
                                                       os.environ.get("PYTHONPATH")]))}
    report = f"\nimport sys\nprint(*[m for m in {HEAVY!r} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code + report], capture_output=True, text=True,
                         env=env)
    assert out.returncode == 0, out.stderr[-3000:]
    return set(out.stdout.split())


def _script_imports(path):
    tree = ast.parse(path.read_text())
    return "\n".join(ast.unparse(node) for node in tree.body
                     if isinstance(node, (ast.Import, ast.ImportFrom)))


@pytest.mark.parametrize("script", [s for s in SCRIPTS if s.stem not in SIMULATE_AT_IMPORT],
                         ids=lambda p: p.stem)
def test_a_script_loads_no_numba_before_its_job_runs(script):
    loaded = _heavy_after(_script_imports(script))
    # the simulating jobs load it in their task, when they run
    assert "numba" not in loaded
    assert "scipy" not in loaded
    if script.stem.startswith(("aggregate_", "simulate_", "solve_", "generate_")):
        assert "matplotlib" not in loaded


def test_plotting_loads_matplotlib_and_no_scipy():
    assert _heavy_after("import vibroimpact.plotting") == {"matplotlib"}


def test_the_figure_table_loads_no_plotting_library():
    # the Snakefile parse reads it (workflow/rules/common.smk)
    assert not _heavy_after("from vibroimpact.pipeline import figures") & {"matplotlib",
                                                                          "scipy", "numba"}


@pytest.mark.parametrize("name", [*figures.FIGURES, *figures.VALIDATION_FIGURES])
def test_every_figure_of_the_table_resolves_to_its_plotting_function(name):
    assert figures.drawing_function(name) is getattr(plotting, name)


def test_an_unknown_figure_is_named_with_the_known_ones():
    with pytest.raises(ValueError, match=r"no figure 'fig99'.*'fig07'.*'stress'"):
        figures.drawing_function("fig99")


def test_t_quantile_is_scipy_stats_t_ppf_bit_for_bit():
    batches = np.arange(0, 500)
    for level in (0.5, 0.9, 0.95, 0.99):
        expected = np.where(batches >= 2, scipy.stats.t.ppf(0.5 + 0.5 * level,
                                                            np.maximum(batches - 1.0, 1.0)),
                            np.nan)
        np.testing.assert_array_equal(t_quantile(batches, level), expected)
    assert t_quantile(20) == scipy.stats.t.ppf(0.975, 19)


@pytest.fixture(scope="module")
def tile(tmp_path_factory):
    """A noise record and one events tile of a two-cell random study, written by the tasks."""
    tmp = tmp_path_factory.mktemp("job_imports")
    tasks.make_noise(NOISE, tmp / "band.nc")
    tasks.events_tile("random", RANDOM, 0, tmp / "band.nc", tmp / "tile.nc")
    return tmp


def test_aggregating_and_drawing_jobs_load_no_numba_when_they_run(tile):
    """The task calls of rules aggregate_events and draw_figure (fig09, with its t quantile
    and Rice's asymptotes; fig05 from the noise record), each in a fresh interpreter."""
    block = json.dumps(RANDOM)
    loaded = _heavy_after(
        "import json\nfrom vibroimpact.pipeline import tasks\n"
        f"tasks.aggregate('random', json.loads({block!r}), 'events', [{str(tile / 'tile.nc')!r}],"
        f" {str(tile / 'events.nc')!r})")
    assert "numba" not in loaded and "matplotlib" not in loaded
    for fig, data in (("fig09", "events.nc"), ("fig05", "band.nc")):
        loaded = _heavy_after(
            "from vibroimpact.pipeline import tasks\n"
            f"tasks.figure({fig!r}, [{str(tile / data)!r}], {str(tile / fig)!r} + '.png', {{}})")
        assert "numba" not in loaded and "matplotlib" in loaded
        assert (tile / f"{fig}.png").stat().st_size > 0
