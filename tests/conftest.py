"""Fixtures shared by the workflow suites: one build of the test config (helpers.py holds the
functions that copy the project and run the workflow).

`make test` runs the `slow`, `workflow` and `slurm` markers in one pytest session on two xdist
workers with ``--dist loadgroup`` (xdist hands out the largest group first, then the rest one
test at a time to whichever worker is free). Every test that reads the build of the test config
(the ``built`` fixture, directly or through another fixture) is put in one xdist group,
``built``, so one worker builds the test config once and runs all of them in turn, while the
other worker runs the suites that build their own copies (faults, sweeps, degenerate and
escape studies) and the slow tests, each test on whichever worker is free. The rebuild-scope
cases (test_rebuild_scope.py) start from a copy of ``built`` with Snakemake's records, not from
a build of their own. The cheap module-scoped copies (test_config_errors.py's ``copy_dir``) are
made once per worker, and their tests spread over both. Without ``--dist loadgroup`` (plain
``-n 2``, or no xdist) the groups are inert and ``built`` is still built once per session.
The numba cache lives beside the installed (editable) package, so every build in every copy
reuses the kernels compiled by the first; a copy that imports the package from its own sources
(test_rebuild_scope.py) gets that cache copied (helpers.copy_kernel_cache).
"""
from _pytest.nodeid import coerce_node_id
import pytest

from helpers import make_workdir, snakemake

#: The xdist group of every test that needs the built test config (one build per session).
BUILT_GROUP = "built"
#: The markers of the long suites (pyproject.toml): their tests are scheduled first.
LONG_MARKERS = ("slow", "workflow", "slurm")


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(config, items):
    """Tests needing ``built`` share one xdist worker, so the test config is built once.

    xdist's ``--dist loadgroup`` schedules by a ``@group`` suffix that its worker appends to
    each marked test's node id (``item._nodeid``); pytest 9 computes ``nodeid`` from
    ``item._id`` instead, so that suffix is lost and every group spreads over both workers
    (measured: the test config built twice). The suffix is set here, on ``_id``, after xdist's
    own hook (``trylast``); the check on the ids' suffix keeps it correct if xdist fixes it.

    The tests of the long suites (``slow``, ``workflow``, ``slurm``) come first, the fast
    ones after them, each in the order collected: in one session of both (``make test``) the
    workers start the long tests at once and end on short ones, instead of one worker
    finishing a minute-long test while the other has nothing left to take.
    """
    items.sort(key=lambda item: not any(item.get_closest_marker(m) for m in LONG_MARKERS))
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


# --- CPU seconds per test (`--cpu-durations=N`): the measure of a test's cost on a shared
# machine, where wall times (`--durations`) follow the load. A phase's CPU time is that of
# the worker's process and of every child it waited for (the snakemake builds and their jobs;
# not SLURM's jobs, run by slurmd). Reported by the controller of an xdist session too.

def pytest_addoption(parser):
    parser.addoption("--cpu-durations", type=int, default=None, metavar="N",
                     help="show the N tests of most CPU seconds, setup + call + teardown, "
                          "children included (0: all)")


def _cpu_seconds():
    import os

    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    if item.config.getoption("cpu_durations") is None:
        yield
        return
    item.stash[_CPU_START] = _cpu_seconds()
    yield


_CPU_START = pytest.StashKey[float]()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    if item.config.getoption("cpu_durations") is None or _CPU_START not in item.stash:
        return
    now = _cpu_seconds()
    report = outcome.get_result()
    report.user_properties.append(("cpu_seconds", now - item.stash[_CPU_START]))
    item.stash[_CPU_START] = now


def pytest_terminal_summary(terminalreporter, config):
    count = config.getoption("cpu_durations")
    if count is None or getattr(config, "workerinput", None) is not None:
        return
    per_test, total = {}, 0.0
    for reports in terminalreporter.stats.values():
        for report in reports:
            for key, value in getattr(report, "user_properties", ()):
                if key == "cpu_seconds":
                    per_test[report.nodeid] = per_test.get(report.nodeid, 0.0) + value
                    total += value
    rows = sorted(per_test.items(), key=lambda kv: -kv[1])
    terminalreporter.write_sep("=", f"CPU seconds per test (children included): "
                                    f"{total:.1f} in all, {len(rows)} tests")
    for nodeid, seconds in rows[:count or None]:
        terminalreporter.write_line(f"{seconds:9.2f}  {nodeid}")
