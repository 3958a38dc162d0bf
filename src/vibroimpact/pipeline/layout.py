"""Where the workflow's own files are, in a checkout and in an installed package.

The workflow follows the Snakemake catalog's standardized layout: ``workflow/Snakefile``,
``workflow/rules``, ``workflow/scripts``, ``workflow/notebooks``, ``workflow/schemas``,
``workflow/profiles`` and, beside ``workflow/``, ``config/`` (the paper's ``config.yaml``, the
test config, the examples). A checkout holds them at its root; an installed vibroimpact holds
the same files as package data at ``vibroimpact/workflow`` and ``vibroimpact/config``
(pyproject.toml's ``package-dir``), placed the same way relative to each other. Every path
inside the workflow is therefore one relative to its Snakefile, whichever copy runs; the
results go to the working directory, never beside the workflow.

The Snakefile takes these paths from its own location (``workflow.current_basedir``), so
that a host workflow that pulls it in as a module reads this workflow's files, not its own;
this module answers the same question for the command line, which has no Snakefile yet: in a
folder that holds the workflow (a checkout), that workflow, as plain ``snakemake`` would run
there; anywhere else, the one this package carries.
"""
import os
from pathlib import Path

__all__ = ["PACKAGE_DIR", "SCHEMA", "PAPER_CONFIG", "workflow_dir", "snakefile", "input_path",
           "importable_alone", "import_alone_in_jobs"]

PACKAGE_DIR = Path(__file__).resolve().parents[1]

#: The config's JSON Schema, relative to the workflow folder.
SCHEMA = "schemas/config.schema.yaml"
#: The paper's config, the base layer of every user's config, relative to the workflow folder.
PAPER_CONFIG = "../config/config.yaml"


def workflow_dir(root=None):
    """The folder holding the Snakefile a build runs.

    In working directory ``root``, when it holds a ``workflow/Snakefile`` of its own (a
    checkout, or a copy of the workflow), that one: the workflow plain ``snakemake`` finds
    there. Else the one of this copy of the package: ``<checkout>/workflow`` when the package
    is imported from a checkout's ``src/`` (an editable install), else the package data of the
    installed package, ``<site-packages>/vibroimpact/workflow``.
    """
    if root is not None and (Path(root) / "workflow" / "Snakefile").is_file():
        return Path(root).resolve() / "workflow"
    checkout = PACKAGE_DIR.parents[1]
    if PACKAGE_DIR == checkout / "src" / "vibroimpact" \
            and (checkout / "workflow" / "Snakefile").is_file():
        return checkout / "workflow"
    return PACKAGE_DIR / "workflow"


def snakefile(root=None):
    """The workflow's Snakefile (:func:`workflow_dir`): what ``vibroimpact run`` in ``root``
    hands to Snakemake, and (no ``root``) what a host workflow names in ``module ...:
    snakefile:`` to pull in the installed release (README, "As a Snakemake module")."""
    return workflow_dir(root) / "Snakefile"


def input_path(path, root="."):
    """``path`` as a job's input: relative to working directory ``root`` when it lies under it
    (a checkout's own workflow files: the same path in any copy of the project), else
    absolute (an installed package's, a module's)."""
    path, root = Path(path).resolve(), Path(root).resolve()
    return str(path.relative_to(root)) if path.is_relative_to(root) else str(path)


def importable_alone(folder):
    """``folder``, made to hold this package alone (a link named ``vibroimpact`` to it), for
    ``PYTHONPATH``: a job in another environment (``--sdm conda``) then imports the very
    package this process runs and none of the other distributions installed beside it.
    Returns the folder's absolute path."""
    folder = Path(folder).resolve()
    folder.mkdir(parents=True, exist_ok=True)
    link = folder / "vibroimpact"
    if not (link.is_symlink() and link.resolve() == PACKAGE_DIR):
        temporary = folder / f".vibroimpact.{os.getpid()}"
        temporary.unlink(missing_ok=True)
        temporary.symlink_to(PACKAGE_DIR, target_is_directory=True)
        os.replace(temporary, link)         # one rename: a job never sees no link
    return str(folder)


def import_alone_in_jobs(folder):
    """Make the processes this one starts from now on (a build's jobs) import this package,
    alone, from ``folder`` (:func:`importable_alone`): ``PYTHONPATH`` is that folder."""
    os.environ["PYTHONPATH"] = importable_alone(folder)
