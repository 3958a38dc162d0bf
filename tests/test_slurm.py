"""The test config's datasets through a real SLURM cluster: one node on this host, started by
tests/slurm/cluster.sh, driven by the workflow's SLURM profile (workflow/profiles/slurm).

The jobs must really run as SLURM jobs (SLURM itself reports them completed, their SLURM logs
exist, simulation and orbit tiles were grouped, aggregation and figures stayed local), and
their datasets must equal the session's local build bit for bit (provenance attributes
aside, as tests/test_workflow.py compares one and two cores). The build is the datasets of
each kind of SLURM job the profile submits (`SLURM_TARGETS`: a noise record, a group of
simulation tiles, a group of orbit and attractor tiles), not all of the test config's: every
other dataset is the same local code on one more scheduler, and a SLURM job waits its
status checks (``slurm-init-seconds-before-status-checks``), so each extra job costs tens of
seconds of waiting and proves nothing more.
"""
import os
import re
import signal
import subprocess
import sys

import pytest
import xarray as xr

from helpers import ROOT, data, data_files, make_workdir
from vibroimpact.pipeline import cluster as cluster_site
from vibroimpact.pipeline.config import costs

pytestmark = pytest.mark.slurm

CLUSTER = ROOT / "tests" / "slurm" / "cluster.sh"
#: The test cluster's one partition, and its node's CPUs (all of this host's).
PARTITION, NODE_CPUS = "debug", os.cpu_count()
#: Seconds the SLURM build may take; then SIGINT (snakemake cancels its SLURM jobs and
#: exits), and SIGKILL GRACE seconds later.
TIMEOUT, GRACE = 900, 60
#: The one-node test cluster answers at once: its status is asked 2 s after a submission
#: and every 2 s after (the profile's 40 s and Snakemake's 10 s suit a loaded scheduler;
#: they made most of this build's wall time).
QUICK_STATUS = ("--slurm-init-seconds-before-status-checks", "2",
                "--seconds-between-status-checks", "2")
#: Snakemake's command line, with the SLURM executor's status checks kept every 2 s: the
#: executor adds 10 s to its interval after every check that finds no job finished (its
#: `check_active_jobs`, for a busy slurmctld), so on a loaded test machine, where a job takes
#: a few checks, each stage of the build waited tens of seconds for nothing. Only the waiting
#: between checks changes; submission, the status query and its reading are the executor's
#: own.
SNAKEMAKE_POLLING = (
    sys.executable, "-c",
    "import asyncio, sys\n"
    "from snakemake_executor_plugin_slurm import Executor\n"
    "async def sleep(self):\n"
    "    await asyncio.sleep(2)\n"
    "Executor.sleep = sleep\n"
    "from snakemake.cli import main\n"
    "sys.argv[0] = 'snakemake'\n"
    "sys.exit(main())\n")
#: The datasets built through SLURM: their noise records (rule generate_noise), the events
#: tiles (group ``cells``), the orbit and attractor tiles (group ``orbit_tiles``).
SLURM_TARGETS = ("results/datasets/random_events.nc", "results/orbits/harmonic.nc",
                 "results/orbits/harmonic_basins.nc")


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


def run_bounded(cmd, cwd, timeout=TIMEOUT, env=None):
    """``cmd`` in ``cwd`` (``env``: its environment): (return code, stdout and stderr); past
    ``timeout`` seconds, SIGINT (snakemake cancels its SLURM jobs and exits), SIGKILL if it
    still runs, and a failure."""
    proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env=env)
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


def slurm_jobs(run_id):
    """``{jobid: (state, CPUs, memory MB)}`` of this run's SLURM jobs, from squeue (finished
    jobs stay listed for MinJobAge, 600 s in tests/slurm/cluster.sh)."""
    out = subprocess.run(["squeue", "--noheader", "--states=all", "--format=%i|%T|%C|%m",
                          "--name", run_id], capture_output=True, text=True, timeout=60,
                         check=True)
    jobs = {}
    for line in out.stdout.split():
        jobid, state, cpus, mem = line.split("|")
        jobs[jobid] = (state, int(cpus), _mb(mem))
    return jobs


def _mb(text):
    """MB of squeue's memory (``1754M``, ``2G``)."""
    scale = {"K": 1 / 1024, "M": 1, "G": 1024, "T": 1024**2}.get(text[-1:], None)
    return float(text[:-1]) * scale if scale else float(text)


def test_the_datasets_through_slurm_equal_the_local_build(cluster, built, tmp_path):
    workdir = make_workdir(tmp_path / "slurm")
    targets = list(SLURM_TARGETS)
    # what a user of this cluster gives: its partition, no account (it has none), and its
    # node's CPUs, fewer than the profile's `cores`
    env = {**os.environ, cluster_site.ACCOUNT_ENV: cluster_site.NO_ACCOUNT,
           cluster_site.PARTITION_ENV: PARTITION}
    cmd = [*SNAKEMAKE_POLLING, *targets, "--workflow-profile", "workflow/profiles/slurm",
           "--cores", str(NODE_CPUS), "--configfile", "config/test.yaml", *QUICK_STATUS]
    code, out = run_bounded(cmd, cwd=workdir, env=env)
    assert code == 0, out[-5000:]

    # SLURM ran them: every submitted job id is a completed job of this run, with its log
    run_id = re.search(r"SLURM run ID: (\S+)", out).group(1)
    submitted = set(re.findall(r"submitted with SLURM jobid (\d+)", out))
    assert submitted, out[-3000:]
    jobs = slurm_jobs(run_id)
    assert {j: jobs.get(j, ("missing",))[0] for j in submitted} == {
        j: "COMPLETED" for j in submitted}
    logs = workdir / "results" / "logs" / "slurm"
    assert {p.stem for p in logs.rglob("*.log")} == submitted
    # What SLURM was asked: each job at least the memory of one job of the cost model, and
    # the threaded orbit tiles their profile's threads (set-threads: 4), capped at --cores
    kind = {p.stem: p.relative_to(logs).parts[0] for p in logs.rglob("*.log")}
    assert all(mem >= costs.BASE_MEM_MB for _, _, mem in jobs.values()), jobs
    tiles = [jobs[j][1] for j in submitted if kind[j].startswith("group_orbit_tiles")]
    assert tiles and set(tiles) == {min(4, NODE_CPUS)}, (tiles, kind)
    # The profile's groups batched the tiles (a group's log directory is named after the group
    # and its rules); the localrules kept aggregation and figures on the submit host.
    kinds = sorted(p.name for p in logs.iterdir())
    assert "rule_generate_noise" in kinds, kinds
    assert any(k.startswith("group_cells_") for k in kinds), kinds
    assert any(k.startswith("group_orbit_tiles_") for k in kinds), kinds
    alone = (r"rule_(simulate|solve_orbit_tile|solve_attractor_tile|trace_boundaries|aggregate"
             r"|draw_figure|copy_paper_figure)")
    assert not [k for k in kinds if re.match(alone, k)], kinds

    files = data_files(workdir)
    assert {str(f) for f in files} >= set(SLURM_TARGETS), files
    assert any(f.parts[1] == "noise" for f in files), files
    for name in files:
        xr.testing.assert_identical(data(built / name), data(workdir / name))
