"""The version of this copy of vibroimpact, from the repository's git tags.

The version follows setuptools-scm's default scheme (pyproject.toml, ``[tool.setuptools_scm]``):
a commit tagged ``vX.Y.Z`` is ``X.Y.Z``; a commit N after it ``X.Y.(Z+1).devN+g<hash>``; a tree
without tags ``0.1.devN+g<hash>``; uncommitted changes add ``.d<date>``. A wheel records the
version of the commit it was built from in its metadata, so an installed copy (no git at all)
still names that commit. A checkout (an editable install) asks git at run time instead: the
version recorded when ``make`` installed it would go stale at the next commit.

Asking git through setuptools-scm costs ~0.5 s (its import and several git calls), so a
build asks once: the Snakefile calls :func:`export` in its own process and every job it
starts reads the answer from the environment (``VIBROIMPACT_VERSION``, tied to the package's
folder, so a value exported for another copy is never taken).
"""
import functools
import os
from pathlib import Path

__all__ = ["ENV", "SOFTWARE", "version", "source_version", "checkout", "export", "software"]

PACKAGE_DIR = Path(__file__).resolve().parent
#: ``<package folder>=<version>``, set by :func:`export` for the processes a build starts.
ENV = "VIBROIMPACT_VERSION"
#: The version of a copy that neither git nor an installation can name.
UNKNOWN = "0+unknown"


def checkout(package_dir=PACKAGE_DIR):
    """The root of the git checkout whose ``src/`` holds ``package_dir``, or None (an
    installed package)."""
    root = Path(package_dir).parents[1]
    if Path(package_dir) == root / "src" / "vibroimpact" and (root / ".git").exists() \
            and (root / "pyproject.toml").is_file():
        return root
    return None


def source_version(root):
    """The version of the sources in git checkout ``root``, as a wheel built there would
    record it (setuptools-scm), or None when it cannot be found (no setuptools-scm, no git)."""
    try:
        from setuptools_scm import get_version
    except ImportError:
        return None
    try:
        return get_version(root=str(root))
    except (LookupError, OSError, ValueError):
        return None


def _installed_version():
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("vibroimpact")
    except PackageNotFoundError:        # sources on the path, never installed
        return UNKNOWN


@functools.cache
def _found():
    root = checkout()
    if root is not None:
        found = source_version(root)
        if found:
            return found
    return _installed_version()


def version():
    """The version of this copy of the package (the module docstring): the one the build
    that started this process exported, else found now (once per process)."""
    where, _, given = os.environ.get(ENV, "").rpartition("=")
    if where == str(PACKAGE_DIR) and given:
        return given
    return _found()


def export():
    """Find the version once and put it in this process's environment, for every process it
    starts (the jobs of a build). Returns it."""
    found = version()
    os.environ[ENV] = f"{PACKAGE_DIR}={found}"
    return found


#: The distributions whose version can change a number of a dataset or a figure: the arrays,
#: the special functions and filters, the kernels' compiler, the files, the drawing, the
#: workflow that decides what runs.
SOFTWARE = ("numpy", "scipy", "numba", "llvmlite", "xarray", "netCDF4", "matplotlib",
            "snakemake")


@functools.lru_cache(maxsize=1)
def software():
    """``{name: version}`` of `SOFTWARE` as installed (importlib.metadata: nothing is
    imported), ``Python``, and ``CPU``: the processor's model (numba compiles its kernels for
    it), ``"unknown"`` where the system does not say."""
    import platform
    from importlib import metadata

    found = {}
    for name in SOFTWARE:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = "not installed"
    found["Python"] = platform.python_version()
    found["CPU"] = _cpu_model()
    return found


def _cpu_model():
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return " ".join(line.split(":", 1)[1].split())
    except OSError:
        pass
    import platform

    return platform.processor() or platform.machine() or "unknown"
