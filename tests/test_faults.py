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

import pytest
import xarray as xr

from helpers import assert_same_data, data, make_workdir
from vibroimpact.pipeline import cli

RUN = [sys.executable, "-m", "vibroimpact", "run", "--cores", "2", "--configfile",
       "config/test.yaml"]


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


# --- a folder the build may not write ----------------------------------------------------------

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


# --- the missing-output query -----------------------------------------------------------------

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
