"""What a newcomer breaks by hand: a deleted result, a folder the build may not write.

`python -m vibroimpact run` (what `make` runs) rebuilds every missing output of the requested
build, even one whose consumers are up to date (Snakemake alone would not), and refuses a
folder of `results` or `.snakemake` the user may not write, in one line, before it changes
anything.
"""
import os
from pathlib import Path
import stat
import subprocess
import sys
import time

import numpy as np
import pytest
import xarray as xr

from helpers import assert_same_data, data, make_workdir
from vibroimpact.pipeline import cli, io

RUN = [sys.executable, "-m", "vibroimpact", "run", "--cores", "2", "--configfile",
       "config/test.yaml"]


@pytest.fixture(autouse=True)
def _release_build_locks():
    """`cli.main` run in this process keeps the build lock it took (a real `run` hands it to
    Snakemake): released after each test."""
    yield
    while cli._HELD:
        os.close(cli._HELD.popitem()[1])


def _run(workdir, *args):
    out = subprocess.run([*RUN, *args], cwd=workdir, capture_output=True, text=True,
                         timeout=900)
    assert out.returncode == 0, out.stdout[-3000:] + out.stderr[-3000:]
    return out


@pytest.mark.workflow
def test_a_deleted_dataset_and_tile_are_rebuilt_by_the_run_command(built, tmp_path):
    """The events dataset of study `random` and one of its simulation tiles deleted from a
    finished build: a dry run plans them, the README's command rebuilds them (and what uses
    them), with the same data, and then nothing is left to do."""
    copy = make_workdir(tmp_path, build=built)
    found = sorted(str(p.relative_to(copy)) for p in (copy / "results").rglob("*.nc"))
    events = [name for name in found if "random" in name and "events" in name]
    tiled = [name for name in events if {"cells", "tiles"} & set(Path(name).parts)]
    names = [next(name for name in events if name not in tiled), tiled[0]]
    originals = {name: data(copy / name) for name in names}
    for name in names:
        (copy / name).unlink()

    planned = _run(copy, "-n")
    assert all(name in planned.stdout for name in names), planned.stdout[-3000:]
    assert not any((copy / name).exists() for name in names), "a dry run rebuilt"

    rebuilt = _run(copy)
    line = next(l for l in rebuilt.stderr.splitlines() if "--forcerun" in l)
    assert all(name in line for name in names), line
    for name, kept in originals.items():
        xr.testing.assert_identical(data(copy / name), kept)
    assert_same_data(built, copy)
    assert "Nothing to be done" in _run(copy, "-n").stdout


# --- a folder the build may not write ------------------------------------------------------------

@pytest.fixture
def as_a_user(monkeypatch):
    """`os.access` as for a user other than root: root may write anywhere, so as root the
    folder's owner permission bits decide, as they would for its (non-root) owner."""
    if os.geteuid() == 0:
        real = os.access

        def access(path, mode, **kwargs):
            if mode & os.W_OK and not os.stat(path).st_mode & stat.S_IWUSR:
                return False
            return real(path, mode, **kwargs)

        monkeypatch.setattr(os, "access", access)


def _tree(root):
    """Every path under ``root`` with its mode and modification time."""
    return {p: (p.lstat().st_mode, p.lstat().st_mtime_ns) for p in sorted(root.rglob("*"))}


@pytest.mark.parametrize("folder", ["results", "results/datasets", ".snakemake", "."])
def test_a_folder_the_build_may_not_write_is_refused_in_one_line(
        folder, tmp_path, monkeypatch, capsys, as_a_user):
    work = make_workdir(tmp_path / "project")
    if folder != ".":
        (work / "results" / "datasets").mkdir(parents=True)
        (work / "results" / "datasets" / "random_events.nc").write_bytes(b"not read")
        (work / ".snakemake" / "locks").mkdir(parents=True)
        (work / ".snakemake" / "locks" / "0.input.lock").write_text("killed run\n")
        gone = subprocess.Popen(["true"])
        gone.wait()                         # a stale temporary, which `run` would remove
        (work / "results" / f".fig.png.{gone.pid}.0a1b2c3d4e5f@{os.uname().nodename}.tmp"
         ).write_bytes(b"")
    before = _tree(work)
    monkeypatch.chdir(work)
    monkeypatch.setattr(os, "execv", lambda *a: pytest.fail("handed over to snakemake"))
    (work / folder).chmod(0o555)
    try:
        code = cli.main(["run", "--cores", "1", "--configfile", "config/test.yaml"])
    finally:
        (work / folder).chmod(0o755)
    lines = capsys.readouterr().err.splitlines()
    shown = str(work) if folder == "." else folder
    assert code == 1
    assert lines[-1] == (f"error: {shown} is not writable by you (chmod u+w {shown}, or build "
                         f"in a copy of the project); nothing was changed")
    assert not any("Traceback" in l for l in lines)
    assert _tree(work) == before


def test_several_folders_the_build_may_not_write_are_counted(tmp_path, monkeypatch, as_a_user):
    monkeypatch.chdir(tmp_path)
    for name in ("results/a/b", "results/c", ".snakemake/locks"):
        (tmp_path / name).mkdir(parents=True)
    unwritable = ("results/a/b", "results/a", ".snakemake")      # inner ones first
    for name in unwritable:
        (tmp_path / name).chmod(0o555)
    try:
        folders = cli.unwritable_folders(tmp_path)
        message = cli._unwritable_message(tmp_path, folders)
    finally:
        for name in reversed(unwritable):
            (tmp_path / name).chmod(0o755)
    assert folders == [tmp_path / "results/a", tmp_path / "results/a/b", tmp_path / ".snakemake"]
    assert message == ("results/a is not writable by you, nor are 2 more folders (chmod -R u+w "
                       "results/a .snakemake, or build in a copy of the project); nothing was "
                       "changed")


# --- the missing-output query --------------------------------------------------------------------

SUMMARY = """\
output_file\tdate\trule\tlog-file(s)\tstatus\tplan
results/figures/fig09.png\tMon Jan  5 10:00:00 2026\tdraw_figure\t-\tok\tno update
results/datasets/random_events.nc\t-\taggregate_events\t-\tmissing\tno update
results/cells/random/events/0.nc\t-\tsimulate_events\t-\tmissing\tno update
results/figures/fig15.png\t-\tdraw_figure\t-\tmissing\tupdate pending
"""


def test_missing_outputs_are_the_missing_ones_snakemake_would_not_rebuild():
    assert cli.missing_outputs("Building DAG of jobs...\n" + SUMMARY) == [
        "results/datasets/random_events.nc", "results/cells/random/events/0.nc"]
    assert cli.missing_outputs("digraph snakemake_dag {\n}\n") is None


@pytest.mark.parametrize("cmd, expected", [
    (["snakemake", "-n", "--configfile", "a.yaml"],
     ["snakemake", "-n", "--configfile", "a.yaml", "--forcerun", "x.nc", "y.nc"]),
    (["snakemake", "-R", "draw_figure", "--configfile", "a.yaml"],
     ["snakemake", "-R", "x.nc", "y.nc", "draw_figure", "--configfile", "a.yaml"]),
    (["snakemake", "--forcerun=draw_figure", "fig.png"],
     ["snakemake", "fig.png", "--forcerun", "draw_figure", "x.nc", "y.nc"]),
    (["snakemake", "-Rdraw_figure", "-n"],
     ["snakemake", "-n", "--forcerun", "draw_figure", "x.nc", "y.nc"]),
])
def test_the_missing_outputs_extend_the_users_own_forcerun(cmd, expected):
    assert cli.with_forcerun(cmd, ["x.nc", "y.nc"]) == expected


# --- data damaged on disk: every variable carries a Fletcher-32 checksum -------------------------

def _events_dataset(tmp_path):
    """A noise record and the events dataset of a short random study, through the workflow's
    own tasks (``tasks.make_noise``, ``events_tile``, ``aggregate``), so every writer of the
    pipeline is the one on test."""
    from test_plotting import NOISE, RANDOM
    from vibroimpact.pipeline import tasks

    noise = tmp_path / "results" / "noise" / "band.nc"
    tasks.make_noise(dict(NOISE, n_samples=20_001), noise)
    block = dict(RANDOM, delta=[round(-1.0 + 0.5 * k, 6) for k in range(16)])
    tile = tmp_path / "results" / "cells" / "random" / "events" / "0.nc"
    tasks.events_tile("random", block, 0, noise, tile)
    events = tmp_path / "results" / "datasets" / "random_events.nc"
    tasks.aggregate("random", block, "events", [tile], events, noise_path=noise)
    return noise, tile, events


def _overwrite(path, values, value=10.0):
    """Overwrite 128 bytes of ``values``' data in ``path`` (found by their bytes) with the
    float ``value``, as the newcomer did, and put the file's timestamps back."""
    raw = np.ascontiguousarray(values, dtype="<f8")
    blob, before = path.read_bytes(), path.stat()
    start = blob.find(raw.tobytes()[:128])
    assert start > 0 and blob.count(raw.tobytes()[:128]) == 1
    with open(path, "r+b") as f:
        f.seek(start)
        f.write(np.full(16, value, "<f8").tobytes())
    os.utime(path, ns=(before.st_atime_ns, before.st_mtime_ns))


def test_every_variable_the_pipeline_writes_carries_a_checksum(tmp_path):
    """Noise record, tile and dataset: every array variable (data, coordinates, strings,
    integers) has Fletcher-32; only scalars cannot (HDF5 stores them unchunked)."""
    import netCDF4

    for path in _events_dataset(tmp_path):
        with netCDF4.Dataset(path) as nc:
            arrays = [v for v in nc.variables.values() if v.ndim]
            assert len(arrays) >= 5, path
            assert [v.name for v in arrays if not v.filters()["fletcher32"]] == [], path
        assert io.verify(path) is True


def test_damaged_data_bytes_are_refused_by_the_run_and_by_every_reader(
        tmp_path, monkeypatch, capsys):
    """128 bytes of `v_after_mean` in the events dataset overwritten by 10.0, the file's
    timestamp put back (so Snakemake sees nothing): `run` refuses it in one line naming the
    file and the variable, before Snakemake, and deletes nothing; a job's read refuses it too.
    The same damage in a file written without checksums reads back as 10.0, unseen: the
    checksum is what finds it."""
    import netCDF4

    work = make_workdir(tmp_path / "project")
    noise, tile, events = _events_dataset(work)
    v_after_mean = xr.load_dataset(events).v_after_mean.values
    assert v_after_mean.size >= 16
    legacy = tmp_path / "legacy.nc"
    xr.load_dataset(events).drop_encoding().to_netcdf(legacy, engine="netcdf4")  # no sums
    _overwrite(events, v_after_mean)
    _overwrite(legacy, v_after_mean)

    monkeypatch.chdir(work)
    monkeypatch.setattr(os, "execv", lambda *a: pytest.fail("handed over to snakemake"))
    code = cli.main(["run", "--cores", "1", "--configfile", "config/test.yaml"])
    lines = capsys.readouterr().err.splitlines()
    assert code == 1
    assert lines[-1].startswith("error: results/datasets/random_events.nc: the data of variable "
                                "v_after_mean fail their Fletcher-32 checksum"), lines[-1]
    assert "delete it and run make" in lines[-1]
    assert not any("Traceback" in line for line in lines)
    assert events.exists()
    with pytest.raises(io.CorruptFileError, match="random_events.nc"):
        io.load_dataset(events)
    with netCDF4.Dataset(events) as nc:            # the other variables still read
        nc["n_collisions"][:]

    seen = xr.load_dataset(legacy).v_after_mean.values
    assert np.count_nonzero(seen.ravel() == 10.0) >= 16 and io.verify(legacy) is False


def test_damaged_noise_samples_are_refused(tmp_path, monkeypatch):
    """The noise record (written chunk by chunk by `write_noise`) is checked the same way."""
    noise, _, _ = _events_dataset(tmp_path)
    samples = xr.load_dataset(noise).r.values
    _overwrite(noise, samples[5000:5016])
    monkeypatch.chdir(tmp_path)
    with pytest.raises(io.CorruptFileError, match="results/noise/band.nc: the data of "
                       "variable r fail their Fletcher-32 checksum"):
        io.check_readable(tmp_path / "results")


def test_a_file_written_before_the_checksums_is_accepted_and_listed(tmp_path, monkeypatch):
    """The rule for a build from before the checksums: read through, accepted, listed (its
    writer's code digest changed, so the build rewrites it)."""
    monkeypatch.chdir(tmp_path)
    words = {"long_name": "a value", "units": "1"}
    ds = xr.Dataset({"x": ("i", np.arange(10.0), words), "s": ((), 1.0, words)})
    ds.to_netcdf(tmp_path / "old.nc", engine="netcdf4")
    io.write_dataset(ds, tmp_path / "new.nc")
    assert io.check_readable(tmp_path) == ["old.nc"]


# --- temporaries of killed writers ---------------------------------------------------------------

def test_a_zombie_writers_temporary_is_swept(tmp_path):
    """A writer killed but not yet reaped (a zombie) writes nothing more: its temporary is
    stale; a live writer's is kept."""
    import psutil

    from vibroimpact import _files

    host = os.uname().nodename
    killed = subprocess.Popen(["sleep", "60"])
    live = subprocess.Popen(["sleep", "60"])
    try:
        killed.kill()
        deadline = time.monotonic() + 10
        while psutil.Process(killed.pid).status() != psutil.STATUS_ZOMBIE:
            assert time.monotonic() < deadline
            time.sleep(0.01)
        stale = tmp_path / f".a.nc.{killed.pid}.0a1b2c3d4e5f@{host}.tmp"
        kept = tmp_path / f".b.nc.{live.pid}.0a1b2c3d4e5f@{host}.tmp"
        stale.write_bytes(b"half")
        kept.write_bytes(b"half")
        assert _files.sweep_stale_temporaries(tmp_path) == [stale]
        assert kept.exists() and not stale.exists()
        assert psutil.Process(killed.pid).status() == psutil.STATUS_ZOMBIE   # still unreaped
    finally:
        live.kill()
        live.wait()
        killed.wait()


# --- one build at a time -------------------------------------------------------------------------

def _race(root, barrier, results):
    barrier.wait()
    fd, holder = cli.take_build_lock(root)
    results.put(fd is not None)
    barrier.wait()                     # hold it until both have tried


def test_of_two_builds_started_at_the_same_instant_one_takes_the_lock(tmp_path):
    """The guard is one atomic step (flock): two processes released together by a barrier,
    many times over, never both get the build lock."""
    import multiprocessing

    ctx = multiprocessing.get_context("fork")
    for attempt in range(20):
        root = tmp_path / str(attempt)
        root.mkdir()
        barrier, results = ctx.Barrier(2), ctx.Queue()
        procs = [ctx.Process(target=_race, args=(root, barrier, results)) for _ in range(2)]
        for p in procs:
            p.start()
        got = sorted(results.get(timeout=60) for _ in procs)
        for p in procs:
            p.join(60)
        assert got == [False, True], attempt


def _cmdline(pid):
    import psutil

    return psutil.Process(pid).cmdline()


def test_a_run_is_refused_while_a_build_holds_the_lock_through_exec(
        tmp_path, monkeypatch, capsys):
    """A build that took the lock and replaced itself (exec) keeps it: a second `run` is
    refused in one line naming its pid, before it changes anything (a stale temporary
    stays); the lock is the kernel's, so it is free again once that build has ended."""
    work = make_workdir(tmp_path / "project")
    holder = subprocess.Popen(
        [sys.executable, "-c", "import os, sys; from pathlib import Path; "
         "from vibroimpact.pipeline import cli; "
         "assert cli.take_build_lock(Path(sys.argv[1]))[0] is not None; "
         "os.execv('/bin/sleep', ['sleep', '60'])", str(work)])
    try:
        lock = work / cli.BUILD_LOCK
        deadline = time.monotonic() + 60
        while not (lock.exists() and lock.read_text().strip() == str(holder.pid)):
            assert holder.poll() is None and time.monotonic() < deadline
            time.sleep(0.05)
        gone = subprocess.Popen(["true"])
        gone.wait()
        stale = work / "results" / f".fig.png.{gone.pid}.0a1b2c3d4e5f@{os.uname().nodename}.tmp"
        stale.parent.mkdir(parents=True)
        stale.write_bytes(b"")
        monkeypatch.chdir(work)
        monkeypatch.setattr(os, "execv", lambda *a: pytest.fail("handed over to snakemake"))
        deadline = time.monotonic() + 10
        while _cmdline(holder.pid)[:1] != ["sleep"]:        # it has replaced itself
            assert time.monotonic() < deadline
            time.sleep(0.05)
        code = cli.main(["run", "--cores", "1", "--configfile", "config/test.yaml"])
        lines = capsys.readouterr().err.splitlines()
        assert code == 1
        assert lines[-1] == (f"error: another build is running in {work} (pid {holder.pid}); "
                             f"wait for it to finish, or stop it (kill {holder.pid}) and run "
                             f"again")
        assert stale.exists()
    finally:
        holder.kill()
        holder.wait()
    fd, _ = cli.take_build_lock(work)
    assert fd is not None


# --- a read-only mount ---------------------------------------------------------------------------

def test_results_linked_into_a_read_only_mount_is_refused_without_chmod_advice(
        tmp_path, monkeypatch, capsys, as_a_user):
    """`results` a symbolic link into a file system mounted read-only (`os.statvfs` reports
    ST_RDONLY, as the kernel does for `mount -o ro`): the line says chmod cannot help and what
    can (remount, a writable folder in the link's place, a copy of the project)."""
    work = make_workdir(tmp_path / "project")
    mount = tmp_path / "mnt"
    (mount / "results" / "datasets").mkdir(parents=True)
    (work / "results").symlink_to(mount / "results")
    real_statvfs = os.statvfs

    class ReadOnly:
        def __init__(self, real):
            self.real = real
            self.f_flag = real.f_flag | os.ST_RDONLY

        def __getattr__(self, name):
            return getattr(self.real, name)

    def statvfs(path):
        real = real_statvfs(path)
        inside = Path(os.path.realpath(path)).is_relative_to(mount)
        return ReadOnly(real) if inside else real

    monkeypatch.setattr(os, "statvfs", statvfs)
    monkeypatch.chdir(work)
    monkeypatch.setattr(os, "execv", lambda *a: pytest.fail("handed over to snakemake"))
    for folder in (mount / "results", mount / "results" / "datasets"):
        folder.chmod(0o555)                 # what a read-only mount gives os.access
    try:
        code = cli.main(["run", "--cores", "1", "--configfile", "config/test.yaml"])
    finally:
        for folder in (mount / "results", mount / "results" / "datasets"):
            folder.chmod(0o755)
    line = capsys.readouterr().err.splitlines()[-1]
    assert code == 1
    assert line.startswith("error: results is on a file system mounted read-only at "), line
    assert f"through the link results -> {mount / 'results'}" in line
    assert "no chmod can change that; remount it read-write" in line
    assert "chmod -R" not in line and "chmod u+w" not in line
    assert line.endswith("nothing was changed")


def test_a_damaged_figure_is_refused(tmp_path, monkeypatch):
    """A figure's PNG (which Snakemake's report embeds) with 16 bytes of its image data
    overwritten fails its chunk CRC: named; the intact figure passes."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from vibroimpact.plotting import save

    fig = Figure()
    fig.add_subplot().plot(np.sin(np.linspace(0, 10, 200)))
    png, _ = save(fig, tmp_path / "results" / "figures" / "fig99.png")
    monkeypatch.chdir(tmp_path)
    assert io.check_readable("results") == []
    blob = bytearray(png.read_bytes())
    start = blob.index(b"IDAT") + 200
    blob[start:start + 16] = np.full(2, 10.0).tobytes()
    png.write_bytes(blob)
    with pytest.raises(io.CorruptFileError, match="^results/figures/fig99.png: fails its PNG "
                       "chunk checks"):
        io.check_readable("results")


def test_a_real_read_only_mount_is_refused(tmp_path):
    """The same with a real `mount -o ro` (a tmpfs in a private mount namespace, `unshare -m`;
    skipped where that is not allowed)."""
    import shutil

    if shutil.which("unshare") is None or subprocess.run(
            ["unshare", "-m", "true"], capture_output=True).returncode != 0:
        pytest.skip("no private mount namespace here (unshare -m)")
    work = make_workdir(tmp_path / "project")
    mount = tmp_path / "mnt"
    mount.mkdir()
    (work / "results").symlink_to(mount / "results")
    script = (f"mount -t tmpfs tmpfs {mount} && mkdir {mount}/results && "
              f"mount -o remount,ro {mount} && exec {' '.join(RUN)}")
    out = subprocess.run(["unshare", "-m", "sh", "-c", script], cwd=work, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 1, out.stderr[-2000:]
    assert out.stderr.splitlines()[-1] == (
        f"error: results is on a file system mounted read-only at {mount}, through the link "
        f"results -> {mount / 'results'}: no chmod can change that; remount it read-write, or "
        f"give the build a writable folder in its place (e.g. replace the link by a folder on "
        f"a writable disk), or build in a copy of the project; nothing was changed")


# --- the pre-pass: asked only when something was built ------------------------------------------

@pytest.mark.parametrize("written", [False, True])
def test_the_run_asks_snakemake_what_is_missing_only_when_results_hold_a_file(
        written, tmp_path, monkeypatch):
    """A first build has no output to miss beneath an up-to-date one: `run` hands over to
    Snakemake without the `--summary` start; once `results` holds a file it asks, and a
    missing output it names goes to `--forcerun`."""
    work = make_workdir(tmp_path / "project")
    if written:
        (work / "results" / "logs").mkdir(parents=True)
        (work / "results" / "logs" / "a.log").write_text("")
    asked, handed = [], []

    def query(cmd, **kwargs):
        asked.append(cmd)
        return subprocess.CompletedProcess(cmd, 0, "Building DAG of jobs...\n" + SUMMARY, "")

    class HandedOver(Exception):
        pass

    def execv(path, cmd):
        handed.append(cmd)
        raise HandedOver

    monkeypatch.setattr(cli.subprocess, "run", query)
    monkeypatch.setattr(os, "execv", execv)
    monkeypatch.chdir(work)
    with pytest.raises(HandedOver):
        cli.main(["run", "--cores", "1", "--configfile", "config/test.yaml"])
    assert [cmd[-1] for cmd in asked] == (["--summary"] if written else [])
    assert ("--forcerun" in handed[0]) == written
    assert cli.has_written(work / "results") == written


def test_a_full_disk_is_said_in_one_line_and_keeps_nothing(tmp_path, monkeypatch, capsys):
    """A write that fails on a full disk (ENOSPC, or the netCDF library's permission error
    where nothing is free) ends the job with one line on the console naming the mount, what
    is free and what the write had taken; no temporary is left, the log holds the same."""
    import errno
    import shutil
    from collections import namedtuple

    from vibroimpact import _files
    from vibroimpact.pipeline import tasks

    ds = xr.Dataset({"x": ("i", np.arange(1000.0), {"long_name": "a value", "units": "1"})})
    target = tmp_path / "out" / "d.nc"
    real_to_netcdf = xr.Dataset.to_netcdf

    def fails_after_writing(self, path, *args, error=None, **kw):
        real_to_netcdf(self, path, *args, **kw)      # something written, then the failure
        raise error

    usage = namedtuple("usage", "total used free")
    for error, free in ((OSError(errno.ENOSPC, "No space left on device"), 10 * 2**20),
                        (PermissionError(errno.EACCES, "Permission denied"), 2**16)):
        monkeypatch.setattr(xr.Dataset, "to_netcdf",
                            lambda self, p, *a, e=error, **k: fails_after_writing(
                                self, p, *a, error=e, **k))
        monkeypatch.setattr(shutil, "disk_usage", lambda p, f=free: usage(1, 1, f))
        log = tmp_path / "job.log"
        with pytest.raises(SystemExit):
            with tasks.logged(str(log)):
                io.write_dataset(ds, target)
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and err.startswith("error: no space left on /")
        assert f"{free / 1e6:.2f} MB free" in err and "d.nc had taken" in err
        assert "no space left on" in log.read_text()
        assert list(target.parent.iterdir()) == []
    # a permission error with room on the disk is what it says
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(1, 1, 10 * 2**30))
    with pytest.raises(PermissionError):
        with _files.atomic_path(target) as tmp:
            raise PermissionError(errno.EACCES, "Permission denied", tmp)


def test_the_free_space_check_counts_what_is_left_to_write(tmp_path):
    """The plan refuses a build whose outputs do not fit the free space, counting what an
    earlier build left under results/ as written: a finished build missing one dataset is
    not refused for the whole build's bytes."""
    from vibroimpact.pipeline import config as configuration
    from vibroimpact.pipeline.config.messages import ConfigError

    _, plan = configuration.load(root=Path(__file__).resolve().parents[1])
    plan.results = str(tmp_path / "results")
    plan.free_bytes = 0.5 * plan.bytes
    with pytest.raises(ConfigError, match="this build writes"):
        plan.refuse_beyond_limits()
    built = tmp_path / "results" / "datasets" / "old.nc"
    built.parent.mkdir(parents=True)
    with open(built, "wb") as f:            # an earlier build's outputs: 60 % of the total
        f.truncate(int(0.6 * plan.bytes))
    logs = tmp_path / "results" / "logs" / "big.log"
    logs.parent.mkdir(parents=True)
    plan.refuse_beyond_limits()
    built.unlink()
    with open(logs, "wb") as f:             # logs are not outputs
        f.truncate(int(0.6 * plan.bytes))
    with pytest.raises(ConfigError, match=r"in all, 0 B of it already"):
        plan.refuse_beyond_limits()
