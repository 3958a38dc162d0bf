"""Copies of the project and runs of its workflow, for the tests and the benchmarks.

A plain module (no fixtures: those live in ``conftest.py``). Tests import it as ``helpers``
(``pythonpath = ["tests"]`` in pyproject.toml); a benchmark run as a script puts ``tests/`` on
its path itself.

- :func:`make_workdir`: what a build needs of the repository, optionally with a finished
  build (its results and Snakemake's metadata), for builds that must not write into the
  repository.
- :func:`copy_tree`: every tracked and new file, the package's sources included, for runs
  that import the package from the copy (``PYTHONPATH=<copy>/src``); :func:`copy_kernel_cache`:
  the kernels numba has compiled for those sources, so such a run need not compile them again
  (:func:`copy_kernel_files`: between any two copies of the package).
- :func:`snakemake`, :func:`scheduled_rules`, :func:`scheduled_jobs`: the real ``snakemake``
  command in a copy.
- :func:`data_files`, :func:`data`, :func:`assert_same_data`: the datasets of two builds.
- :func:`cf_problems`, :func:`assert_cf`: the CF attributes of every file of a build, units
  parsed by UDUNITS (``cf_units``).
"""
from pathlib import Path
import re
import shutil
import subprocess
import sys

import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
#: What a build needs of the repository: the workflow (its Snakefile, rules, scripts,
#: notebooks, schema and profiles) and the configs beside it.
WORKFLOW_FILES = ("config", "workflow")
#: Snakemake's metadata of a run, not of its outputs: a copied build starts unlocked.
RUN_STATE = ("locks", "incomplete", "log")
#: The test configs' short noise record (the plane tests: tests/test_planes.py,
#: tests/test_plane_blocks.py), and the map settings their studies share: a short record,
#: so the identities they check hold whatever precision the cells reach.
TINY_NOISE = """paper: false
noises:
  tiny:
    kind: band_limited
    rms: 0.29
    dt: 0.1
    beta_c: 4.0
    n_samples: 20001
    seed: 36
"""
TINY_MAP = """    zeta: 0.05
    amplitude: 1.0
    transient: 100.0
    tile_size: 4
    map: {target_stderr: 0.1, min_time: 300.0, max_periods: 200, min_switches: 10}
"""


def make_workdir(path, build=None):
    """A copy of the workflow in ``path`` (builds of the test config overwrite the paper's
    results, so they never run in the repository itself).

    With ``build`` (a finished build's directory), its ``results`` and ``.snakemake``
    metadata (code, params and inputs of every output, so Snakemake sees them up to date)
    are copied too, without its locks, incomplete markers and logs.
    """
    path = Path(path)
    path.mkdir(parents=True, exist_ok=True)
    for item in WORKFLOW_FILES:
        src = ROOT / item
        if src.exists():
            (shutil.copytree if src.is_dir() else shutil.copy)(src, path / item)
    if build is not None:
        shutil.copytree(build / "results", path / "results")
        shutil.copytree(build / ".snakemake", path / ".snakemake", symlinks=True,
                        ignore=shutil.ignore_patterns(*RUN_STATE))
    return path


def copy_tree(path, root=ROOT):
    """Every tracked and new (not ignored) file of the working tree ``root`` in ``path``, with
    its modification time: the sources too, so a run with ``PYTHONPATH=<path>/src`` imports
    the package from the copy."""
    path = Path(path)
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=root,
                           capture_output=True, text=True, check=True).stdout.split()
    for name in files:
        if (root / name).is_file():
            (path / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(root / name, path / name)
    return path


def copy_kernel_cache(path, root=ROOT):
    """numba's cached machine code of the package's kernels (``src/**/__pycache__/*.nbi``,
    ``*.nbc``) of the working tree ``root``, copied into the copy ``path`` made by
    :func:`copy_tree`, so a build importing the package from the copy loads the kernels the
    suites have compiled instead of compiling them all again (minutes on a fresh clone).

    Safe for any edit the copy makes later: numba loads a cached kernel only while the stamp
    stored beside it matches its sources (their modification times, which :func:`copy_tree`
    keeps, and `vibroimpact._kernel_cache`'s digest of every kernel module of its package);
    an index without its data file, or one being rewritten, makes numba compile, as if
    nothing were copied. Returns the number of files copied (none before any compilation).
    """
    return copy_kernel_files(root / "src", Path(path) / "src")


def copy_kernel_files(source, target):
    """numba's cache files under folder ``source`` (``**/__pycache__/*.nbi``, ``*.nbc``)
    copied to the same places under folder ``target``; the number copied."""
    copied = 0
    for name in sorted(Path(source).rglob("__pycache__/*.nb[ic]")):
        into = Path(target) / name.relative_to(source)
        into.parent.mkdir(parents=True, exist_ok=True)
        try:
            shutil.copy2(name, into)
        except FileNotFoundError:       # replaced by a compiling process meanwhile
            continue
        copied += 1
    return copied


def snakemake(workdir, *args, config="config/test.yaml", check=True, cores=2, timeout=900):
    """``snakemake ARGS --cores N --configfile CONFIG`` in ``workdir``."""
    cmd = [SNAKEMAKE, *args, "--cores", str(cores), "--configfile", config]
    out = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True, timeout=timeout)
    if check and out.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed:\n{out.stdout[-3000:]}\n"
                             f"{out.stderr[-3000:]}")
    return out


def job_table(stdout):
    """``{rule: count}`` of the job stats table a dry run prints (``total`` left out)."""
    rules = {}
    for line in stdout.splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[1].isdigit() and parts[0] not in ("total", "job"):
            rules[parts[0]] = int(parts[1])
    return rules


def scheduled_rules(workdir, target, config="config/test.yaml"):
    """Rules a dry run would execute for ``target`` (from the job stats table)."""
    return set(job_table(snakemake(workdir, target, "-n", "--quiet", "rules",
                                   config=config).stdout))


def scheduled_jobs(workdir, *targets, config="config/test.yaml"):
    """The jobs one dry run for ``targets`` would execute: ``[{"rule", "input",
    "output"}]``, inputs and outputs as sets of paths."""
    jobs = []
    for line in snakemake(workdir, *targets, "-n", config=config).stdout.splitlines():
        line = line.strip()
        match = re.fullmatch(r"(?:local)?rule (\w+):", line)
        if match:
            jobs.append({"rule": match[1], "input": set(), "output": set()})
        elif jobs and line.startswith(("input:", "output:")):
            key, paths = line.split(":", 1)
            jobs[-1][key].update(p.strip() for p in paths.split(","))
    return jobs


def data_files(root):
    """Every dataset of a build except the per-job tiles and the validation runs (timings):
    noise, traces, studies, orbits."""
    return sorted(p.relative_to(root) for p in (root / "results").rglob("*.nc")
                  if not {"cells", "tiles", "validation"} & set(p.parts))


def data(path):
    """A dataset without its attributes (``created`` ...) and run measurements (CPU times)."""
    ds = xr.load_dataset(path)
    timings = [v for v in ds.variables if ds[v].attrs.get("run_measurement") == 1]
    return ds.drop_vars(timings).drop_attrs()


def assert_same_data(a, b):
    """The datasets of two builds hold identical data (attributes such as ``created`` aside)."""
    files = data_files(a)
    assert files == data_files(b)
    assert len(files) >= 10
    for name in files:
        xr.testing.assert_identical(data(a / name), data(b / name))


#: The global attributes every file carries (`vibroimpact.pipeline.conventions`).
CF_GLOBALS = ("Conventions", "source", "history", "references")


def cf_problems(path):
    """What a netCDF file lacks of the CF attributes: ``"<var>: no units"``, ``"<var>: no
    long_name"``, ``"<var>: units '<u>' not UDUNITS"`` (parsed by ``cf_units``, which wraps
    the UDUNITS-2 library) and ``"no <global attribute>"``."""
    import cf_units
    import netCDF4

    out = []
    with netCDF4.Dataset(path) as nc:
        for name, var in nc.variables.items():
            attrs = {k: var.getncattr(k) for k in var.ncattrs()}
            for key in ("long_name", "units"):
                if not str(attrs.get(key, "")).strip():
                    out.append(f"{name}: no {key}")
            if str(attrs.get("units", "")).strip():
                try:
                    cf_units.Unit(str(attrs["units"]))
                except ValueError:
                    out.append(f"{name}: units {attrs['units']!r} not UDUNITS")
        out += [f"no {key}" for key in CF_GLOBALS if not str(
            nc.getncattr(key) if key in nc.ncattrs() else "").strip()]
        if "Conventions" in nc.ncattrs() and not nc.getncattr("Conventions").startswith("CF-"):
            out.append(f"Conventions {nc.getncattr('Conventions')!r}")
    return out


def assert_cf(root):
    """Every netCDF file under ``root`` (datasets, noise, traces, orbits, validation, the
    per-job tiles) is CF-clean (:func:`cf_problems`); returns how many were checked."""
    paths = sorted(p for p in Path(root).rglob("*.nc") if not p.name.startswith("."))
    problems = {str(p.relative_to(root)): cf_problems(p) for p in paths}
    assert paths and not any(problems.values()), {k: v for k, v in problems.items() if v}
    return len(paths)


def assert_figure(path):
    """``path`` is a whole figure file with something drawn on it: a PNG that decodes to an
    image of more than one colour, or a PDF with its header and end-of-file marker."""
    path = Path(path)
    if path.suffix == ".pdf":
        content = path.read_bytes()
        assert content.startswith(b"%PDF-") and b"%%EOF" in content[-64:], path
        return
    from matplotlib import image

    pixels = image.imread(path)
    assert pixels.ndim == 3 and min(pixels.shape[:2]) >= 100, (path, pixels.shape)
    assert (pixels != pixels[0, 0]).any(), f"{path}: a blank image"
