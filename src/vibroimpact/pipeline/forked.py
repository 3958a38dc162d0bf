"""Figure jobs run in forks of the workflow's own process, warmed once.

A figure job in a fresh Python process pays its start-up before it draws: importing numpy,
pandas, xarray, netCDF4, matplotlib and the plotting package (~0.8 CPU-s) and matplotlib's
first drawing (fonts, ~0.3 CPU-s), against ~1.2 CPU-s of drawing. The default build's 19
figures took 45 CPU-s one process each and 28 drawn four processes in all (one an owner,
`benchmarks/figure_start.py`). The figure rules run their scripts here instead: Snakemake's
own process imports those modules and draws one small figure once (:func:`warm`), then
forks for each job (:func:`run_script`). A job pays only its drawing and still runs in a
process of its own: two figures draw on two cores at once, a crash or a leak stays in its
fork, a drawing sees the state of a fresh warm process and never another figure's (every
figure is byte for byte what its own process draws).

Only the thread that forks survives in the child: a lock that another of Snakemake's threads
held at that instant stays held there. The child therefore touches nothing those threads
use: its standard streams are new files on the job's log, its signals the defaults, and it
leaves by ``os._exit`` (no interpreter shutdown, no Snakemake exit handlers). The modules the
child uses (matplotlib, xarray, netCDF4) are used by no thread of the parent besides the
warm-up, which no fork overlaps (:data:`_LOCK`).

Snakemake runs a ``run:`` job in a thread of its own process only with ``force-use-threads``
(set in ``profiles/default``); without it, it starts a whole new Snakemake for each such job,
which parses the workflow and warms up again: the 21 figure jobs of the default build then
cost 84 CPU-s against 59 as script jobs (load ~5), and 35 against 52 with it.

The job's benchmark file is written here, in Snakemake's columns, from the fork's own
resource use (``os.wait4``): Snakemake's ``benchmark:`` of a ``run:`` job would sample its
own process with every other running job under it.
"""
import contextlib
import io
import os
import runpy
import signal
import sys
import threading
import time
import traceback

from vibroimpact import _files

__all__ = ["run_script", "warm"]

#: Held while the modules are warmed, and at each fork: no fork copies a half-done warm-up.
_LOCK = threading.Lock()
_WARM = []

#: Snakemake's benchmark columns (``snakemake.benchmark``), in its order.
BENCHMARK_COLUMNS = ("s", "h:m:s", "max_rss", "max_vms", "max_uss", "max_pss", "io_in",
                     "io_out", "mean_load", "cpu_time")


def warm():
    """Import what the figure scripts import and draw one small figure in this process,
    once: what every fork then starts with."""
    with _LOCK:
        if _WARM:
            return
        from matplotlib.figure import Figure

        from vibroimpact import plotting
        from vibroimpact.pipeline import figures, tasks  # noqa: F401  (what the jobs import)

        with plotting.style():
            fig = Figure(figsize=(2, 2))
            ax = fig.add_subplot()
            ax.plot([0, 1], [0, 1], label=r"$P_{(1/1)}$")
            ax.set_xlabel(r"$1/\beta_f$")
            ax.legend()
            for fmt in ("png", "pdf"):
                fig.savefig(io.BytesIO(), format=fmt)
        _WARM.append(True)


def _child(script, job, log):
    """In the fork: the script with ``snakemake`` bound to ``job``; never returns."""
    code = 1
    try:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        os.close(fd)
        sys.stdout = open(1, "w", closefd=False)
        sys.stderr = open(2, "w", closefd=False)
        runpy.run_path(str(script), init_globals={"snakemake": job}, run_name="__main__")
        code = 0
    except BaseException:           # the fork reports every failure and exits
        with contextlib.suppress(BaseException):
            traceback.print_exc()
    finally:
        with contextlib.suppress(BaseException):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)


def run_script(script, job, benchmark=None):
    """Run workflow script ``script`` in a fork of this process, as Snakemake would run it
    in a process of its own, and wait for it.

    Parameters
    ----------
    script : path
        The script; it reads the global ``snakemake`` as a ``script:`` rule's does.
    job : object
        What the script finds as ``snakemake``: ``input``, ``output``, ``params``,
        ``wildcards``, ``log`` (its first file receives the fork's standard streams).
    benchmark : path, optional
        The job's benchmark file, written in Snakemake's columns (one row).

    Raises
    ------
    RuntimeError
        The script failed: its exit status, and the log holding its traceback.
    """
    warm()
    log = str(job.log[0])
    with _LOCK:
        start = time.perf_counter()
        pid = os.fork()
        if pid == 0:
            _child(script, job, log)
    _, status, usage = os.wait4(pid, 0)
    wall = time.perf_counter() - start
    if benchmark is not None:
        cpu = usage.ru_utime + usage.ru_stime
        row = (f"{wall:.4f}", time.strftime("%-H:%M:%S", time.gmtime(wall)),
               f"{usage.ru_maxrss / 1024:.2f}", "NA", "NA", "NA",
               f"{usage.ru_inblock * 512 / 2**20:.2f}", f"{usage.ru_oublock * 512 / 2**20:.2f}",
               f"{100 * cpu / wall if wall > 0 else 0:.2f}", f"{cpu:.2f}")
        with _files.atomic_path(benchmark) as tmp, open(tmp, "w") as out:
            out.write("\t".join(BENCHMARK_COLUMNS) + "\n" + "\t".join(row) + "\n")
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        what = f"signal {-code}" if code < 0 else f"exit {code}"
        raise RuntimeError(f"{os.path.basename(str(script))} failed ({what}); see {log}")
