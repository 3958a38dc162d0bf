"""Figure jobs in forks of the workflow's process (`vibroimpact.pipeline.forked`): the script
runs as in a process of its own, writes what it writes, reports its failure in its log, and
draws the same bytes as a fresh process."""
import csv
import os
from pathlib import Path
import subprocess
import sys
import threading
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
