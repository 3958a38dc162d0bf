"""Shared by the workflow suites: a copy of the workflow and one build of the test config.

`make test` runs the `workflow` and `slurm` markers in one pytest session, so the test config
is built once (`built`) and every end-to-end test (datasets, findings, reports, the SLURM run)
reads or compares against that build. The numba cache lives beside the installed (editable)
package, so every build in every copy reuses the kernels compiled by the first.
"""
from pathlib import Path
import shutil
import subprocess
import sys

import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
#: What a build needs of the repository (README.md: the stability report quotes its table).
WORKFLOW_FILES = ("Snakefile", "config", "workflow", "profiles", "notebooks", "README.md")


def make_workdir(path):
    """A copy of the workflow in ``path`` (builds of the test config overwrite the paper's
    results, so they never run in the repository itself)."""
    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    for item in WORKFLOW_FILES:
        src = ROOT / item
        if src.exists():
            (shutil.copytree if src.is_dir() else shutil.copy)(src, path / item)
    return path


def snakemake(workdir, *args, config="config/test.yaml", check=True, cores=2, timeout=900):
    """``snakemake ARGS --cores N --configfile CONFIG`` in ``workdir``."""
    cmd = [SNAKEMAKE, *args, "--cores", str(cores), "--configfile", config]
    out = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True, timeout=timeout)
    if check and out.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed:\n{out.stdout[-3000:]}\n{out.stderr[-3000:]}")
    return out


def scheduled_rules(workdir, target):
    """Rules a dry run would execute for ``target`` (from the job stats table)."""
    out = snakemake(workdir, target, "-n", "--quiet", "rules")
    rules = set()
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[1].isdigit() and parts[0] not in ("total", "job"):
            rules.add(parts[0])
    return rules


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """The test config built end to end, once per session (tests marked ``workflow`` or
    ``slurm``): every dataset, figure and report of ``config/test.yaml``."""
    workdir = make_workdir(tmp_path_factory.mktemp("built"))
    snakemake(workdir)
    return workdir


def _data_files(root):
    """Every dataset of a build except the per-job tiles and the validation runs (timings):
    noise, traces, studies, orbits."""
    return sorted(p.relative_to(root) for p in (root / "results").rglob("*.nc")
                  if not {"cells", "tiles", "validation"} & set(p.parts))


def _data(path):
    """A dataset without its attributes (``created`` ...) and run measurements (CPU times)."""
    ds = xr.load_dataset(path)
    timings = [v for v in ds.variables if ds[v].attrs.get("run_measurement") == 1]
    return ds.drop_vars(timings).drop_attrs()


def assert_same_data(a, b):
    """The datasets of two builds hold identical data (attributes such as ``created`` aside)."""
    files = _data_files(a)
    assert files == _data_files(b)
    assert len(files) >= 10
    for name in files:
        xr.testing.assert_identical(_data(a / name), _data(b / name))
