"""Fixtures shared by the workflow suites: one build of the test config (helpers.py holds the
functions that copy the project and run the workflow).

`make test` runs the `workflow` and `slurm` markers in one pytest session, so the test config
is built once (`built`) and every end-to-end test (datasets, findings, reports, the SLURM run)
reads or compares against that build. The numba cache lives beside the installed (editable)
package, so every build in every copy reuses the kernels compiled by the first.
"""
import pytest

from helpers import make_workdir, snakemake


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """The test config built end to end, once per session (tests marked ``workflow`` or
    ``slurm``): every dataset, figure and report of ``config/test.yaml``."""
    workdir = make_workdir(tmp_path_factory.mktemp("built"))
    snakemake(workdir)
    return workdir
