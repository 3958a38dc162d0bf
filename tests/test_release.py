"""A release another lab can adopt: the exact environment (requirements.lock and what is made
from it), the version from git tags, the wheel that carries the workflow, the ``vibroimpact``
command in an empty folder, and the workflow pulled into a host's Snakefile as a module.

The fast tests check the lock, the version and the wheel's contents; the two end-to-end tests
(``workflow``) build a figure and a report of the test config through the installed wheel
and through a host workflow, and compare them with the session's build of the same config
(``built``): the same data bit for bit, the same pixels, the same report.
"""
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys
import sysconfig
import tomllib

import matplotlib.image
import nbformat
import numpy as np
import pytest
import xarray as xr
import yaml

from helpers import ROOT, copy_kernel_files
from vibroimpact import _release
from vibroimpact.pipeline import layout

sys.path.insert(0, str(ROOT / "tools"))
import environment  # tools/environment.py: the lock's reader

PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


# --- the exact environment ------------------------------------------------------------------

def test_the_venv_holds_exactly_the_lock():
    """Every distribution this interpreter sees is a pin of requirements.lock at its version,
    and every pin that applies here is installed (`make` runs `uv pip sync`)."""
    assert environment.differences(environment.pins(), environment.installed()) == []


def test_every_pin_is_exact_with_hashes_and_every_direct_requirement_is_locked():
    from packaging.requirements import Requirement

    entries = environment.entries()
    assert len(entries) > 100
    for text, lines in entries:
        assert re.fullmatch(r"[A-Za-z0-9_.-]+==[^ ;]+( ; .+)?", text), text
        assert any(line.strip().startswith("--hash=sha256:") for line in lines), text
    locked = environment.pins(environment={"python_full_version": "3.11.7",
                                            "python_version": "3.11", "sys_platform": "linux",
                                            "platform_machine": "x86_64",
                                            "implementation_name": "cpython",
                                            "platform_system": "Linux", "os_name": "posix",
                                            "platform_python_implementation": "CPython"})
    project = PYPROJECT["project"]
    direct = [*project["dependencies"], *project["optional-dependencies"]["slurm"],
              *PYPROJECT["dependency-groups"]["dev"], *PYPROJECT["dependency-groups"]["docs"]]
    for text in direct:        # pyproject.toml changed without `make lock`: fails here
        req = Requirement(text)
        name = environment.canonical(req.name)
        assert name in locked, f"{text}: not in requirements.lock (make lock)"
        assert req.specifier.contains(locked[name], prereleases=True), \
            f"{text}: the lock pins {locked[name]} (make lock)"


def test_the_conda_environment_follows_the_lock_and_names_no_path():
    text = environment.CONDA_ENV.read_text()
    assert text == environment.conda_env(), "workflow/envs/vibroimpact.yaml: run `make lock`"
    env = yaml.safe_load(text)
    pip = next(d["pip"] for d in env["dependencies"] if isinstance(d, dict))
    assert [p.split(" ;")[0] for p in pip] == [t.split(" ;")[0] for t, _ in environment.entries()]
    assert not any(p.startswith(("-", ".", "/")) or "../" in p for p in pip)


def test_the_package_alone_is_importable_from_its_path_folder(tmp_path):
    """`--sdm conda` jobs import the running package through PYTHONPATH: that folder holds
    this package and nothing else of the environment beside it."""
    folder = layout.importable_alone(tmp_path / "path")
    assert layout.importable_alone(tmp_path / "path") == folder      # again: unchanged
    # no site-packages at all (-S): what imports comes from the folder alone
    out = subprocess.run(
        [sys.executable, "-I", "-S", "-c",
         "import sys; sys.path[:0] = [sys.argv[1]]; import vibroimpact.pipeline.layout as l, "
         "importlib.util as u; print(l.PACKAGE_DIR); print(u.find_spec('numpy'))", folder],
        capture_output=True, text=True, check=True).stdout.split()
    assert out == [str(layout.PACKAGE_DIR), "None"]


# --- the version ----------------------------------------------------------------------------

def _git(clone, *args):
    return subprocess.run(["git", "-c", "user.name=t", "-c", "user.email=t@example.org", *args],
                          cwd=clone, capture_output=True, text=True, check=True).stdout.strip()


def test_the_version_comes_from_the_tags(tmp_path):
    """setuptools-scm's scheme, read from git as a wheel built there would record it: no tag
    names the commit, a tag is the version, a commit after it the next dev version, uncommitted
    changes add the date."""
    clone = tmp_path / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    for tag in _git(clone, "tag", "-l").split():
        _git(clone, "tag", "-d", tag)
    head = _git(clone, "rev-parse", "HEAD")
    count = _git(clone, "rev-list", "--count", "HEAD")
    untagged = _release.source_version(clone)
    assert re.fullmatch(rf"0\.1\.dev{count}\+g{head[:7]}[0-9a-f]*", untagged), untagged
    _git(clone, "tag", "v2.3.4")
    assert _release.source_version(clone) == "2.3.4"
    _git(clone, "commit", "-q", "--allow-empty", "-m", "after the release")
    after = _release.source_version(clone)
    assert re.fullmatch(rf"2\.3\.5\.dev1\+g{_git(clone, 'rev-parse', 'HEAD')[:7]}[0-9a-f]*",
                        after), after
    (clone / "README.md").write_text("changed\n")
    assert re.fullmatch(r"2\.3\.5\.dev1\+g[0-9a-f]+\.d\d{8}", _release.source_version(clone))


def test_a_build_finds_the_version_once_for_its_jobs(monkeypatch):
    """The Snakefile exports the version; a job of this package reads it, a value exported
    for another copy of the package is not taken."""
    monkeypatch.delenv(_release.ENV, raising=False)
    found = _release.export()
    assert os.environ[_release.ENV] == f"{_release.PACKAGE_DIR}={found}"
    assert _release.version() == found
    monkeypatch.setenv(_release.ENV, f"{_release.PACKAGE_DIR}=9.9.9")
    assert _release.version() == "9.9.9"
    monkeypatch.setenv(_release.ENV, "/another/copy/vibroimpact=9.9.9")
    assert _release.version() == found


def test_the_command_names_its_version_and_plans_from_an_empty_folder(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != _release.ENV}
    out = subprocess.run([sys.executable, "-m", "vibroimpact", "--version"], env=env,
                         capture_output=True, text=True, check=True).stdout
    assert out == f"vibroimpact {_release.version()}\n"
    plan = subprocess.run([sys.executable, "-m", "vibroimpact", "plan"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert plan.returncode == 0, plan.stderr
    assert "motion_map" in plan.stdout          # the paper's entries, from the package's config
    assert not any(tmp_path.iterdir())              # a plan writes nothing


# --- the wheel ----------------------------------------------------------------------------

def _wheel(folder, tree=ROOT):
    """The wheel of ``tree``, built without network (uv, setuptools and setuptools-scm of
    this environment: the lock's)."""
    uv = Path(sys.executable).with_name("uv")
    subprocess.run([str(uv), "build", "--python", sys.executable, "--wheel",
                    "--no-build-isolation", "--quiet", "-o", str(folder), str(tree)],
                   check=True, capture_output=True)
    shutil.rmtree(Path(tree) / "build", ignore_errors=True)      # setuptools' scratch
    (wheel,) = Path(folder).glob("vibroimpact-*.whl")
    return wheel


def test_a_release_tarball_without_git_names_its_version(tmp_path):
    """`git archive` (a release tarball: no .git) fills .git_archival.txt, from which the
    wheel built there takes the version of the commit archived."""
    clone = tmp_path / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    for tag in _git(clone, "tag", "-l").split():       # the repository's own releases
        _git(clone, "tag", "-d", tag)
    _git(clone, "tag", "v2.3.4")
    _git(clone, "commit", "-q", "--allow-empty", "-m", "after the release")
    head = _git(clone, "rev-parse", "HEAD")
    tree = tmp_path / "tarball"
    tree.mkdir()
    archive = subprocess.run(["git", "archive", "HEAD"], cwd=clone, capture_output=True,
                             check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    assert not (tree / ".git").exists()
    wheel = _wheel(tmp_path / "dist", tree)
    assert re.fullmatch(rf"vibroimpact-2\.3\.5\.dev1\+g{head[:7]}[0-9a-f]*-py3-none-any\.whl",
                        wheel.name), wheel.name


def test_the_wheel_carries_the_package_and_the_whole_workflow(tmp_path):
    import zipfile

    wheel = zipfile.ZipFile(_wheel(tmp_path))
    names = set(wheel.namelist())
    tracked = subprocess.run(["git", "ls-files", "src", "workflow", "config"], cwd=ROOT,
                             capture_output=True, text=True, check=True).stdout.split()
    # src/vibroimpact/... as the package; workflow/... and config/... as its package data
    expected = {path[len("src/"):] if path.startswith("src/") else f"vibroimpact/{path}"
                for path in tracked}
    assert expected - names == set()
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    metadata = wheel.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
    assert "License-Expression: BSD-3-Clause" in metadata
    required = {re.split(r"[<>=!~; ]", line.split(": ", 1)[1])[0].lower()
                for line in metadata.splitlines() if line.startswith("Requires-Dist: ")}
    assert {"snakemake", "papermill", "nbconvert", "numba"} <= required
    entry_points = wheel.read(next(n for n in names if n.endswith("entry_points.txt"))).decode()
    assert "vibroimpact = vibroimpact.__main__:main" in entry_points


# --- end to end: the installed application, and the workflow as a module -------------------

def _same_data(a, b):
    """Datasets ``a`` and ``b`` hold the same data, their provenance aside."""
    xr.testing.assert_identical(xr.load_dataset(a).drop_attrs(), xr.load_dataset(b).drop_attrs())


def _same_pixels(a, b):
    assert np.array_equal(matplotlib.image.imread(a), matplotlib.image.imread(b)), (a, b)


#: The outputs of a report that differ between any two runs of the same data: the styled
#: tables' random ids, object addresses, the provenance table (creation times) and the Run
#: section (the jobs' CPU and wall seconds).
_RUN_ONLY = (re.compile(r"T_[0-9a-f]{5}"), re.compile(r" at 0x[0-9a-f]+"))


def _report_outputs(ipynb):
    """The outputs of a report's cells but for its parameters, provenance and Run section, as
    text."""
    nb = nbformat.read(ipynb, as_version=4)
    out = []
    for cell in nb.cells:
        if cell.cell_type != "code" or "parameters" in cell.metadata.get("tags", []) \
                or cell.source.startswith(("nb.provenance(", "nb.run_section(", "# Parameters")):
            continue
        for output in cell.get("outputs", []):
            for kind, value in sorted(output.get("data", {}).items()):
                text = "".join(value) if isinstance(value, list) else str(value)
                for pattern in _RUN_ONLY:
                    text = pattern.sub("", text)
                out.append((cell.source.splitlines()[0], kind, text))
    return out


def _clean_env():
    """This environment without what a build here exports (the version, the figure server)
    or points at the checkout (PYTHONPATH)."""
    return {k: v for k, v in os.environ.items()
            if not k.startswith("VIBROIMPACT_") and k != "PYTHONPATH"}


def _compare_with_built(folder, built):
    """fig07 of study random and the data it is drawn from, as the session's build made
    them."""
    for path in ("results/datasets/random_events.nc", "results/noise/random_input.nc"):
        _same_data(folder / path, built / path)
    _same_pixels(folder / "results/figures/random/fig07.png",
                 built / "results/figures/random/fig07.png")


def _seed_kernel_cache(installed):
    """numba's cache of this tree's kernels, made valid for the installed copy of the package:
    its sources' modification times set to this tree's (numba stamps a cached kernel with
    its source's time and size; `vibroimpact._kernel_cache` with the bytes of every kernel
    module, equal here) and the cache files copied beside them, as
    `helpers.copy_kernel_cache` does for a copy of the tree. A fresh installation compiles
    each kernel once, into the same place (~1 min of CPU for all: README, "As an
    application"); the tests need not pay it again. Returns the number of files copied."""
    src = ROOT / "src" / "vibroimpact"
    for path in installed.rglob("*.py"):
        twin = src / path.relative_to(installed)
        if twin.is_file() and twin.read_bytes() == path.read_bytes():
            stat = twin.stat()
            os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    return copy_kernel_files(src, installed)


@pytest.mark.workflow
def test_the_installed_application_builds_a_study_in_an_empty_folder(built, tmp_path):
    """The wheel in a fresh venv (which sees this environment's distributions through a path
    file: no network), its `vibroimpact` command in an empty folder: the test config layered
    on the paper's, one figure built there, identical to the session's build; a new process
    loads the kernels from the installed package's own numba cache (seeded from this tree's:
    `_seed_kernel_cache`), compiling nothing."""
    wheel = _wheel(tmp_path / "dist")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    site = Path(subprocess.run([str(venv / "bin" / "python"), "-c",
                                "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    (site / "environment.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    env = _clean_env()
    python = str(venv / "bin" / "python")
    subprocess.run([python, "-m", "pip", "install", "--quiet", "--no-index",
                    "--disable-pip-version-check", str(wheel)], check=True, env=env)
    check = subprocess.run([python, "-m", "pip", "check"], capture_output=True, text=True,
                           env=env)
    assert check.returncode == 0, check.stdout          # every requirement met
    installed = site / "vibroimpact"
    assert _seed_kernel_cache(installed) > 0
    app = str(venv / "bin" / "vibroimpact")
    version = subprocess.run([app, "--version"], capture_output=True, text=True, env=env,
                             check=True).stdout.split()[-1]
    assert version == _release.version()              # the commit this tree is at
    folder = tmp_path / "my_study"
    folder.mkdir()
    (folder / "my_study.yaml").write_text((ROOT / "config" / "test.yaml").read_text())
    run = subprocess.run([app, "run", "results/figures/random/fig07.png", "--cores", "2",
                          "--configfile", "my_study.yaml"], cwd=folder, env=env,
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "site-packages/vibroimpact/workflow/Snakefile" in run.stderr
    _compare_with_built(folder, built)
    ds = xr.open_dataset(folder / "results/datasets/random_events.nc")
    assert ds.attrs["package_version"] == version
    # a new process loads the kernels from the installed package's cache: nothing compiled
    first_call = ("import numpy as np; from numba.core import event; "
                  "from vibroimpact import simulate; "
                  "noise = 0.3 * np.random.default_rng(1).standard_normal(2000)\n"
                  "with event.install_recorder('numba:compile') as rec:\n"
                  "    simulate(0.05, 0.5, 0.5, noise, dt=0.1)\n"
                  "print(len(rec.buffer))")
    compiled = subprocess.run([python, "-c", first_call], capture_output=True, text=True,
                              env=env, check=True).stdout
    assert compiled == "0\n"


@pytest.mark.workflow
def test_a_host_workflow_pulls_this_one_in_as_a_module(built, tmp_path):
    """A host Snakefile in a folder of its own, with its own config holding the test config
    under a key of its own, pulls the workflow in with `module` from this checkout's path and
    `use rule * ... as vi_*`, and builds one figure and one report with no profile (so no
    force-use-threads): they are those of the session's build."""
    host = tmp_path / "host"
    host.mkdir()
    test = yaml.safe_load((ROOT / "config" / "test.yaml").read_text())
    (host / "config.yaml").write_text(yaml.safe_dump({"vibroimpact": test}))
    (host / "Snakefile").write_text(f'''configfile: "config.yaml"


rule all:
    input:
        "results/figures/random/fig07.png",
        "results/reports/random/random_force.html",


module vibroimpact:
    snakefile:
        "{ROOT / 'workflow' / 'Snakefile'}"
    config:
        config["vibroimpact"]


use rule * from vibroimpact as vi_*
''')
    run = subprocess.run([str(Path(sys.executable).with_name("snakemake")), "--cores", "2"],
                         cwd=host, env=_clean_env(), capture_output=True, text=True,
                         timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "force-use-threads" not in run.stderr and "workflow specific profile" not in run.stderr
    _compare_with_built(host, built)
    assert _report_outputs(host / "results/reports/random/random_force.ipynb") == \
        _report_outputs(built / "results/reports/random/random_force.ipynb")
    # each figure drawn in a fork of the host's Snakemake (its benchmark written by the fork)
    assert (host / "results/benchmarks/draw_figure/random/fig07.tsv").is_file()
