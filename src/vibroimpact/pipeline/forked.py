"""Figure jobs run in forks of the workflow's own process, warmed once, whatever the profile.

A figure job in a fresh Python process pays its start-up before it draws: importing numpy,
pandas, xarray, netCDF4, matplotlib and the plotting package (~0.8 CPU-s) and matplotlib's
first drawing (fonts, ~0.3 CPU-s), against ~1.2 CPU-s of drawing. The default build's 19
figures took 45 CPU-s one process each and 28 drawn four processes in all (one an owner,
`benchmarks/figure_start.py`). The figure jobs are drawn in forks of Snakemake's own process
instead, which imports those modules and draws one small figure once (:func:`warm`): a job
pays only its drawing and still runs in a process of its own: two figures draw on two cores
at once, a crash or a leak stays in its fork, a drawing sees the state of a fresh warm process
and never another figure's (every figure is byte for byte what its own process draws).

The figure rules are ``script:`` rules, which Snakemake starts from a thread of its own
process whatever the profile says (a ``run:`` job runs in that process only with
``force-use-threads``; without it Snakemake starts a whole new Snakemake for each, which
parses the workflow and warms again: 84 CPU-s for the 21 figure jobs of the default build
against 35, and 13 s a figure in a host workflow that pulls this one in as a module). The
Snakefile starts a server in Snakemake's process (:func:`serve`: a thread accepting on a Unix
socket in a private temporary folder, named in the environment every job inherits); the
job's script (Snakemake's preamble, then the workflow script, which calls :func:`run`) is a
client: it sends the server the path of its own file and waits. The server forks; the fork
runs that file in the job's folder with the job's environment variables, its preamble binding
``snakemake`` again (its modules already loaded), and :func:`run` there draws. The client
exits with the fork's status (~0.1 CPU-s: Python and the preamble). A job that finds no server
of its own Python environment (on another machine; in a conda environment or a container,
whose drawing must be that environment's; a script run by hand) forks its own process: the
same drawing, paying the imports. A client that goes away (Snakemake stopping the job) has its
fork stopped.

Only the thread that forks survives in the child: a lock that another of Snakemake's threads
held at that instant stays held there. The child therefore touches nothing those threads
use: its standard streams are new files on the job's log, its signals the defaults, and it
leaves by ``os._exit`` (no interpreter shutdown, no Snakemake exit handlers). The modules the
child uses (matplotlib, xarray, netCDF4) are used by no thread of the parent besides the
warm-up, which no fork overlaps (:data:`_LOCK`).

The job's benchmark file is written here, in Snakemake's columns, from the fork's own
resource use (``os.wait4``): Snakemake's ``benchmark:`` would sample the client.
"""
import atexit
import contextlib
import io
import json
import os
import runpy
import select
import shutil
import signal
import socket
import sys
import tempfile
import threading
import time
import traceback

from vibroimpact import _files

__all__ = ["SERVER_ENV", "run", "run_script", "serve", "warm"]

#: Held while the modules are warmed, and at each fork: no fork copies a half-done warm-up.
_LOCK = threading.Lock()
_WARM = []
#: The path of this process's server socket, once :func:`serve` has started it.
_SERVER = []
#: Set in a fork that runs a job: :func:`run` draws there.
_IN_JOB = []
#: The environment variable naming the server's socket and its Python environment
#: (``sys.prefix``), for the jobs a build starts.
SERVER_ENV = "VIBROIMPACT_FIGURE_SERVER"

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


def _child(target, log):
    """In the fork: ``target()`` (a job's drawing), its output on ``log``; never returns."""
    code = 1
    try:
        _IN_JOB.append(True)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        os.close(fd)
        sys.stdout = open(1, "w", closefd=False)
        sys.stderr = open(2, "w", closefd=False)
        target()
        code = 0
    except SystemExit as stop:      # a script's own exit (tasks.logged: a damaged input)
        code = stop.code if isinstance(stop.code, int) else int(stop.code is not None)
    except BaseException:           # the fork reports every failure and exits
        with contextlib.suppress(BaseException):
            traceback.print_exc()
    finally:
        with contextlib.suppress(BaseException):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(code)


def _wait(pid, client=None):
    """``os.wait4`` of the fork ``pid``; when ``client`` (a socket) closes first, the fork is
    stopped (SIGTERM) before it is reaped."""
    if client is not None and hasattr(os, "pidfd_open"):
        with contextlib.suppress(OSError), contextlib.closing(_PidFd(pid)) as pidfd:
            while True:
                ready, _, _ = select.select([pidfd, client], [], [])
                if pidfd in ready:
                    break
                if not client.recv(4096):       # the client went away (it sends nothing more)
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(pid, signal.SIGTERM)
                    break
    return os.wait4(pid, 0)


class _PidFd:
    """A process's file descriptor (``os.pidfd_open``): readable once it has exited."""

    def __init__(self, pid):
        self.fd = os.pidfd_open(pid)

    def fileno(self):
        return self.fd

    def close(self):
        os.close(self.fd)


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
    _fork(lambda: runpy.run_path(str(script), init_globals={"snakemake": job},
                                 run_name="__main__"),
          os.path.basename(str(script)), str(job.log[0]), benchmark)


def _fork(target, name, log, benchmark, client=None):
    """``target()`` in a fork of this process (:func:`_child`), waited for; its benchmark row
    written; RuntimeError naming ``name`` and ``log`` if it failed."""
    with _LOCK:
        start = time.perf_counter()
        pid = os.fork()
        if pid == 0:
            _child(target, log)
    _, status, usage = _wait(pid, client)
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
        raise RuntimeError(f"{name} failed ({what}); see {log}")


# --- the server in Snakemake's process, and its clients: the jobs' scripts -----------------

def serve():
    """Start this process's figure server, once, and name its socket in the environment
    (:data:`SERVER_ENV`) of every process this one starts from now on.

    A daemon thread accepts on a Unix socket in a new private folder (mode 0700: this user
    only), removed when the process exits; each connection is one job, served in a thread of
    its own: the file the client names run in a fork, in the client's folder and environment.
    Nothing is imported or drawn
    before the first job asks (a dry run pays a thread and a socket). Returns the socket's
    path.
    """
    with _LOCK:
        if _SERVER:
            return _SERVER[0]
        folder = tempfile.mkdtemp(prefix="vibroimpact-figures-")
        atexit.register(shutil.rmtree, folder, True)
        path = os.path.join(folder, "socket")
        server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        server.bind(path)
        server.listen(64)
        threading.Thread(target=_accept, args=(server,), name="vibroimpact-figures",
                         daemon=True).start()
        os.environ[SERVER_ENV] = json.dumps([sys.prefix, path])
        _SERVER.append(path)
        return path


def _accept(server):
    while True:
        connection, _ = server.accept()
        threading.Thread(target=_serve_one, args=(connection,), daemon=True).start()


def _serve_one(connection):
    """One job: its request (the script file, its name, working directory, environment, log
    and benchmark), the fork, the exit status."""
    with connection:
        code = 1
        try:
            request = json.loads(_line(connection))
            script = request["script"]      # the job's file: Snakemake's preamble binds its job

            def job():
                os.chdir(request["cwd"])    # the job's working directory, its paths' base
                os.environ.clear()          # and its environment (threads, temporaries ...)
                os.environ.update(request["env"])
                runpy.run_path(script, run_name="__main__")

            warm()
            _fork(job, request["name"], request["log"], request.get("benchmark"),
                  client=connection)
            code = 0
        except RuntimeError as err:        # the job failed: its log says why
            message = str(err)
        except Exception as err:           # the client reports it
            message = f"the figure server failed: {err!r}"
        else:
            message = ""
        with contextlib.suppress(OSError):
            connection.sendall(json.dumps({"code": code, "message": message}).encode() + b"\n")


def _line(connection):
    """One line of the connection (a JSON request or reply), without its newline."""
    data = b""
    while not data.endswith(b"\n"):
        chunk = connection.recv(65536)
        if not chunk:
            break
        data += chunk
    return data.decode()


def _server_for_this_environment():
    """The socket of the build's server, if this job runs in the server's own Python
    environment; None in another one (``--sdm conda`` or ``apptainer``: the job's drawing
    is that environment's, so it draws in its own fork), or with no server."""
    try:
        prefix, path = json.loads(os.environ.get(SERVER_ENV, ""))
    except ValueError:
        return None
    return path if os.path.realpath(prefix) == os.path.realpath(sys.prefix) else None


def run(draw, job, benchmark=None):
    """Draw a figure job: ``draw(job)`` in a fork of the workflow's warm process.

    Called by a workflow script with its ``snakemake``. In the server's fork (the script run
    again there) it draws; in the job's own process it asks the server to run this script
    (:func:`serve`), or, with no server to ask in its own Python environment, runs
    ``draw(job)`` in a fork of its own.

    Parameters
    ----------
    draw : callable
        ``draw(job)`` draws and saves the figure (the script's own function).
    job : object
        The script's ``snakemake``; its ``log[0]`` receives the fork's standard streams.
    benchmark : path, optional
        The job's benchmark file, from the fork's resource use.

    Raises
    ------
    SystemExit
        The job failed (its exit status; the log says why).
    """
    if _IN_JOB:
        draw(job)
        return
    log = str(job.log[0])
    # the workflow script's name (Snakemake's preamble sets __file__ to it; argv[0] is the
    # copy it runs, preamble first)
    name = os.path.basename(getattr(sys.modules["__main__"], "__file__", None) or sys.argv[0])
    path = _server_for_this_environment()
    if path:
        try:
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as connection:
                connection.connect(path)
                request = {"script": os.path.abspath(sys.argv[0]), "name": name,
                           "cwd": os.getcwd(), "env": dict(os.environ),
                           "log": os.path.abspath(log),
                           "benchmark": benchmark and os.path.abspath(benchmark)}
                connection.sendall(json.dumps(request).encode() + b"\n")
                reply = _line(connection)
        except OSError:
            reply = None            # no server here (another machine, a container)
        if reply is not None:
            answer = json.loads(reply) if reply else {
                "code": 1, "message": f"the figure server closed without an answer; see {log}"}
            if answer["code"] != 0:
                raise SystemExit(answer["message"])
            return
    try:
        _fork(lambda: draw(job), name, log, benchmark)
    except RuntimeError as err:
        raise SystemExit(str(err)) from None
