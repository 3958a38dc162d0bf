"""The test config's datasets through a real SLURM cluster: one node on this host, started by
tests/slurm/cluster.sh, driven by the workflow's SLURM profile (workflow/profiles/slurm).

The jobs must really run as SLURM jobs (SLURM itself reports them completed, their SLURM logs
exist, simulation and orbit tiles were grouped, aggregation and figures stayed local), and
every dataset must equal the session's local build bit for bit (provenance attributes
aside, as tests/test_workflow.py compares one and two cores).
"""
import os
import re
import signal
import subprocess

import pytest

from helpers import ROOT, SNAKEMAKE, assert_same_data, data_files, make_workdir

pytestmark = pytest.mark.slurm

CLUSTER = ROOT / "tests" / "slurm" / "cluster.sh"
#: Seconds the SLURM build may take; then SIGINT (snakemake cancels its SLURM jobs and
#: exits), and SIGKILL GRACE seconds later.
TIMEOUT, GRACE = 900, 60


def _cluster(action, timeout):
    return subprocess.run(["bash", str(CLUSTER), action], capture_output=True, text=True,
                          timeout=timeout)


@pytest.fixture(scope="module")
def cluster():
    """A usable single-node cluster; started (and stopped afterwards) if it was not running.
    Never skipped: a machine that cannot run it fails here, saying why."""
    if os.geteuid() != 0:
        pytest.fail("the slurm suite starts a SLURM cluster on this host (Debian packages, "
                    "daemons, /etc/slurm): it needs root; run it as root, or deselect it "
                    "with -m 'not slurm'")
    was_running = _cluster("status", 60).returncode == 0
    out = _cluster("start", 900)
    if out.returncode != 0:
        pytest.fail(f"tests/slurm/cluster.sh start failed:\n{out.stdout}{out.stderr}")
    yield
    if not was_running:
        _cluster("stop", 120)


def run_bounded(cmd, cwd, timeout=TIMEOUT):
    """``cmd`` in ``cwd``: (return code, stdout and stderr); past ``timeout`` seconds, SIGINT
    (snakemake cancels its SLURM jobs and exits), SIGKILL if it still runs, and a failure."""
    proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGINT)
        try:
            out, _ = proc.communicate(timeout=GRACE)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
        pytest.fail(f"{' '.join(cmd)} did not finish in {timeout} s (interrupted):\n"
                    f"{out[-3000:]}")
    return proc.returncode, out


def slurm_states(run_id):
    """``{jobid: state}`` of this run's SLURM jobs, from squeue (finished jobs stay listed
    for MinJobAge, 600 s in tests/slurm/cluster.sh)."""
    out = subprocess.run(["squeue", "--noheader", "--states=all", "--format=%i|%T",
                          "--name", run_id], capture_output=True, text=True, timeout=60,
                         check=True)
    return dict(line.split("|") for line in out.stdout.split())


def test_the_datasets_through_slurm_equal_the_local_build(cluster, built, tmp_path):
    workdir = make_workdir(tmp_path / "slurm")
    targets = [str(p) for p in data_files(built)]
    cmd = [SNAKEMAKE, *targets, "--workflow-profile", "workflow/profiles/slurm",
           "--configfile", "config/test.yaml"]
    code, out = run_bounded(cmd, cwd=workdir)
    assert code == 0, out[-5000:]

    # SLURM ran them: every submitted job id is a completed job of this run, with its log
    run_id = re.search(r"SLURM run ID: (\S+)", out).group(1)
    submitted = set(re.findall(r"submitted with SLURM jobid (\d+)", out))
    assert submitted, out[-3000:]
    states = slurm_states(run_id)
    assert {j: states.get(j) for j in submitted} == {j: "COMPLETED" for j in submitted}
    logs = workdir / "results" / "logs" / "slurm"
    assert {p.stem for p in logs.rglob("*.log")} == submitted
    # The profile's groups batched the tiles (a group's log directory is named after the group
    # and its rules); the localrules kept aggregation and figures on the submit host.
    kinds = sorted(p.name for p in logs.iterdir())
    assert "rule_generate_noise" in kinds, kinds
    assert any(k.startswith("group_cells_") for k in kinds), kinds
    assert any(k.startswith("group_orbit_tiles_") for k in kinds), kinds
    alone = (r"rule_(simulate|solve_orbit_tile|solve_attractor_tile|trace_boundaries|aggregate"
             r"|draw_figure|copy_paper_figure)")
    assert not [k for k in kinds if re.match(alone, k)], kinds

    assert_same_data(built, workdir)
