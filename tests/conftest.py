"""Fixtures shared by the workflow suites: one build of the test config (helpers.py holds the
functions that copy the project and run the workflow).

`make test` runs the `workflow` and `slurm` markers in one pytest session on two xdist workers
with ``--dist loadgroup``. Every test that reads the build of the test config (the ``built``
fixture, directly or through another fixture) is put in one xdist group, ``built``, so one
worker builds the test config once and runs all of them in turn, while the other worker runs
the suites that build their own copies (rebuild scope, faults, sweeps, degenerate and escape
studies), each test on whichever worker is free. A module whose module-scoped fixture is a
build of its own (test_rebuild_scope.py) puts its tests in one group itself
(``pytest.mark.xdist_group``), so that build is made on one worker only; the cheap
module-scoped copies (test_config_errors.py's ``copy_dir``) are made once per worker, and
their tests spread over both. Without ``--dist loadgroup`` (plain ``-n 2``, or no xdist) the
groups are inert and ``built`` is still built once per session.
The numba cache lives beside the installed (editable) package, so every build in every copy
reuses the kernels compiled by the first.
"""
from _pytest.nodeid import coerce_node_id
import pytest

from helpers import make_workdir, snakemake

#: The xdist group of every test that needs the built test config (one build per session).
BUILT_GROUP = "built"


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Tests needing ``built`` share one xdist worker, so the test config is built once.

    xdist's ``--dist loadgroup`` schedules by a ``@group`` suffix that its worker appends to
    each marked test's node id (``item._nodeid``); pytest 9 computes ``nodeid`` from
    ``item._id`` instead, so that suffix is lost and every group spreads over both workers
    (measured: the test config built twice). The suffix is set here, on ``_id``, after xdist's
    own hook (``trylast``); the check on the ids' suffix keeps it correct if xdist fixes it.
    """
    for item in items:
        if "built" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.xdist_group(BUILT_GROUP))
    if not getattr(config.option, "loadgroup", False):      # xdist worker, --dist loadgroup
        return
    for item in items:
        names = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default"))
                        for m in item.iter_markers("xdist_group")})
        if names and "@" not in item.nodeid:
            item._id = coerce_node_id(f"{item.nodeid}@{'_'.join(names)}")


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """The test config built end to end, once per session (tests marked ``workflow`` or
    ``slurm``): every dataset, figure and report of ``config/test.yaml``."""
    workdir = make_workdir(tmp_path_factory.mktemp("built"))
    snakemake(workdir)
    return workdir
