"""Figure jobs in forks of the workflow's process (`vibroimpact.pipeline.forked`): the script
runs as in a process of its own, writes what it writes, reports its failure in its log, and
draws the same bytes as a fresh process; a job's script asks the server in Snakemake's process
to run it in a fork there, in the job's folder, or draws in a fork of its own where there is
no server of its Python environment, and a job stopped stops its fork."""
import csv
import json
import os
from pathlib import Path
import re
import signal
import subprocess
import sys
import threading
import time
from types import SimpleNamespace

import pytest

from vibroimpact.pipeline import forked

#: A figure with text, mathematics and a legend, saved as the figure jobs save (PNG and PDF).
FIGURE_SCRIPT = '''\
import sys
from matplotlib.figure import Figure
from vibroimpact import plotting

with plotting.style():
    fig = Figure()
    ax = fig.add_subplot()
    ax.plot([0, 1, 2], [1, 0, 2], label=r"$P_{(2/1)}$, $\\delta = 0.5$")
    ax.set_xlabel(r"$1/\\beta_f$")
    ax.set_title("one figure")
    ax.legend()
    plotting.save(fig, snakemake.output.png)
print("drawn", snakemake.wildcards.fig)
'''


def _job(tmp_path, name="fig"):
    return SimpleNamespace(input=[], output=SimpleNamespace(png=str(tmp_path / f"{name}.png")),
                           params=SimpleNamespace(), wildcards=SimpleNamespace(fig=name),
                           log=[str(tmp_path / f"{name}.log")])


def _script(tmp_path, text, name="script.py"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_a_figure_drawn_in_a_fork_is_the_bytes_a_fresh_process_draws(tmp_path):
    script = _script(tmp_path, FIGURE_SCRIPT)
    fresh = tmp_path / "fresh"
    fresh.mkdir()
    runner = ("import runpy, sys; from types import SimpleNamespace as N; "
              "runpy.run_path(sys.argv[1], init_globals={'snakemake': N("
              "output=N(png=sys.argv[2]), wildcards=N(fig='fig'))}, run_name='__main__')")
    subprocess.run([sys.executable, "-c", runner, str(script), str(fresh / "fig.png")],
                   check=True, capture_output=True)
    bench = tmp_path / "bench" / "fig.tsv"
    forked.run_script(script, _job(tmp_path), benchmark=bench)
    for suffix in (".png", ".pdf"):
        assert (tmp_path / f"fig{suffix}").read_bytes() == (fresh / f"fig{suffix}").read_bytes()
    assert "drawn fig" in (tmp_path / "fig.log").read_text()
    rows = list(csv.DictReader(bench.open(), delimiter="\t"))
    assert list(rows[0]) == list(forked.BENCHMARK_COLUMNS) and len(rows) == 1
    assert float(rows[0]["s"]) > 0 and 0 < float(rows[0]["cpu_time"]) < 60


def test_a_failing_script_raises_naming_its_log_which_holds_the_traceback(tmp_path):
    script = _script(tmp_path, "x = 1\nraise ValueError('no such motion: (7/3)')\n")
    bench = tmp_path / "fig.tsv"
    with pytest.raises(RuntimeError, match=r"script.py failed \(exit 1\); see .*fig.log"):
        forked.run_script(script, _job(tmp_path), benchmark=bench)
    log = (tmp_path / "fig.log").read_text()
    assert "Traceback" in log and "ValueError: no such motion: (7/3)" in log
    assert bench.is_file()                     # its cost is recorded, as Snakemake's would be
    print("the parent's streams still work")   # the fork's redirection stayed in the fork


def test_a_script_killed_by_a_signal_is_reported_and_the_parent_goes_on(tmp_path):
    script = _script(tmp_path, "import os, signal\nos.kill(os.getpid(), signal.SIGKILL)\n")
    with pytest.raises(RuntimeError, match=r"failed \(signal 9\)"):
        forked.run_script(script, _job(tmp_path))
    assert os.getpid() and threading.main_thread().is_alive()


def test_what_a_fork_changes_stays_in_it(tmp_path):
    import matplotlib

    before = matplotlib.rcParams["lines.linewidth"]
    script = _script(tmp_path, "import matplotlib, sys\n"
                               "matplotlib.rcParams['lines.linewidth'] = 9.5\n"
                               "sys.modules['vibroimpact'].CHANGED = True\n")
    forked.run_script(script, _job(tmp_path))
    import vibroimpact

    assert matplotlib.rcParams["lines.linewidth"] == before
    assert not hasattr(vibroimpact, "CHANGED")


def test_figure_jobs_started_from_two_threads_at_once_both_finish(tmp_path):
    """Snakemake runs two local jobs in two threads: each forks and waits for its own."""
    script = _script(tmp_path, FIGURE_SCRIPT)
    errors = []

    def job(name):
        try:
            forked.run_script(script, _job(tmp_path, name), benchmark=tmp_path / f"{name}.tsv")
        except Exception as err:    # reported by the assertion below
            errors.append(err)

    threads = [threading.Thread(target=job, args=(f"fig{i}",)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not errors
    pngs = {Path(tmp_path / f"fig{i}.png").read_bytes() for i in range(2)}
    assert len(pngs) == 1


# --- the server in Snakemake's process and its clients, the figure jobs' scripts ------------

#: A figure job's script as Snakemake runs it: its "preamble" binds ``snakemake`` (as
#: Snakemake's does, from values written into the file), then the workflow script calls
#: `forked.run`. The drawing records where it ran: its process, its parent and its working
#: directory.
CLIENT_SCRIPT = '''\
import json, os, sys, time
from types import SimpleNamespace as N
snakemake = N(log=[LOG], output=N(png="fig.png"), wildcards=N(fig="fig"))

from vibroimpact.pipeline import forked


def draw(job):
    where = {"pid": os.getpid(), "parent": os.getppid(), "cwd": os.getcwd()}
    with open(job.output.png, "w") as out:
        json.dump(where, out)
    print("drawn")
    if os.environ.get("FAIL"):
        raise ValueError("no such motion: (7/3)")
    time.sleep(float(os.environ.get("SLEEP", "0")))


forked.run(draw, snakemake, benchmark=os.environ.get("BENCH"))
'''


@pytest.fixture
def server(monkeypatch):
    """This process's figure server, its variable removed from the environment afterwards
    (the server itself, a daemon thread, stays for the session)."""
    monkeypatch.setenv(forked.SERVER_ENV, "")
    path = forked.serve()
    monkeypatch.setenv(forked.SERVER_ENV, json.dumps([sys.prefix, path]))
    return path


def _client(tmp_path, env=None, **kwargs):
    script = _script(tmp_path, CLIENT_SCRIPT.replace("LOG", repr(str(tmp_path / "fig.log"))),
                     "tmp.draw_figure.py")
    work = tmp_path / "work"
    work.mkdir(exist_ok=True)
    return subprocess.Popen([sys.executable, str(script)],
                            cwd=work, env={**os.environ, **(env or {})},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kwargs)


def test_a_job_script_draws_in_a_fork_of_the_server_in_its_own_folder(tmp_path, server):
    client = _client(tmp_path, {"BENCH": str(tmp_path / "bench.tsv")})
    assert client.wait(60) == 0, client.stderr.read()
    where = json.loads((tmp_path / "work" / "fig.png").read_text())
    assert where["parent"] == os.getpid()            # a fork of the serving process
    assert where["cwd"] == str(tmp_path / "work")    # in the job's working directory
    assert "drawn" in (tmp_path / "fig.log").read_text()
    rows = list(csv.DictReader((tmp_path / "bench.tsv").open(), delimiter="\t"))
    assert len(rows) == 1 and float(rows[0]["cpu_time"]) >= 0


def test_without_a_server_a_job_draws_in_a_fork_of_its_own(tmp_path, monkeypatch):
    monkeypatch.delenv(forked.SERVER_ENV, raising=False)
    client = _client(tmp_path)
    assert client.wait(60) == 0, client.stderr.read()
    where = json.loads((tmp_path / "work" / "fig.png").read_text())
    assert where["parent"] == client.pid


def test_a_server_of_another_python_environment_is_not_asked(tmp_path, server, monkeypatch):
    """A job in a conda environment or a container draws with its own environment."""
    monkeypatch.setenv(forked.SERVER_ENV, json.dumps(["/another/environment", server]))
    client = _client(tmp_path)
    assert client.wait(60) == 0, client.stderr.read()
    assert json.loads((tmp_path / "work" / "fig.png").read_text())["parent"] == client.pid


def test_a_failed_drawing_fails_the_job_naming_its_log(tmp_path, server):
    client = _client(tmp_path, {"FAIL": "1"})
    assert client.wait(60) == 1
    assert re.search(r"tmp\.draw_figure\.py failed \(exit 1\); see .*fig\.log",
                     client.stderr.read())
    log = (tmp_path / "fig.log").read_text()
    assert "Traceback" in log and "ValueError: no such motion: (7/3)" in log


def test_a_job_stopped_by_snakemake_stops_its_fork(tmp_path, server):
    client = _client(tmp_path, {"SLEEP": "60"})
    drawing = tmp_path / "work" / "fig.png"
    deadline = time.monotonic() + 30
    while not drawing.is_file() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.2)                         # the fork is sleeping in its drawing now
    fork = json.loads(drawing.read_text())["pid"]
    client.send_signal(signal.SIGTERM)      # what Snakemake does to a job it cancels
    client.wait(10)
    deadline = time.monotonic() + 10
    while _alive(fork) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(fork)


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as stat:         # a zombie not yet reaped is gone
        return stat.read().split(") ")[-1].split()[0] != "Z"
