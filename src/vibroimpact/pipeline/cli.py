"""``vibroimpact`` (also ``python -m vibroimpact``): the tool's entry point (``make`` calls
``run``), in a checkout or installed, from any working directory: the results go there, the
workflow is the one this package carries (`vibroimpact.pipeline.layout`), and the paper's
config is the base layer of the user's.

``plan``  reads and checks the config (the paper's, with ``--configfile`` files layered on
          it) and prints what a build would make: cells, jobs, disk and a rough time.
``run``   does the same checks, then prepares the directory and hands over to Snakemake:
          refuses a folder of ``results`` or ``.snakemake`` the user may not write (naming
          it, before anything changes), takes the build lock (:func:`take_build_lock`,
          held through the build; refused, naming the holder, while another build holds
          it), removes the temporaries of writers that are gone, refuses a damaged result
          file (every netCDF variable read through, its checksums checked, and every
          figure's PNG CRCs: :func:`vibroimpact.pipeline.io.check_readable`; naming it),
          clears a lock left by a killed run when no run is alive in this directory, asks
          Snakemake which outputs of the requested build are missing and adds them to
          ``--forcerun`` (Snakemake alone never rebuilds a deleted file whose consumers are
          up to date; not asked when ``results`` holds no file yet), and replaces itself
          with ``snakemake`` (the default profile, ``profiles/default``, reruns the jobs a
          crash interrupted).
``report`` writes Snakemake's own report of the build (``snakemake --report``: every figure
          once, captioned, the HTML reports, and the costs of the build's jobs by rule,
          ``results/reports/job_costs.html``, which it writes first from the benchmark
          files) to ``results/report.html``, whole or not at all: it is rendered elsewhere
          and moved into place only when complete (``make`` runs it after ``run``).
``stale``  lists (``--delete``: removes) the outputs of the config's entries that it no longer
          builds (`vibroimpact.pipeline.stale`).
``warm``   compiles every numba kernel the jobs call into numba's cache, once per installation
          (`vibroimpact.warm`, dispatched by ``vibroimpact.__main__``), so that no job and no
          notebook compiles one.
``--version`` prints the version (`vibroimpact._release`).

A config file with a YAML syntax error is reported with its file, line and column here,
before Snakemake's own loader (which drops the location) ever sees it.
"""
import argparse
import os
from pathlib import Path
import shutil
import subprocess
import sys

from vibroimpact import _files
from vibroimpact.pipeline import cluster, config, io, layout

__all__ = ["main"]


class _Version(argparse.Action):
    """``--version``: found only when asked (in a checkout it asks git)."""

    def __init__(self, option_strings, dest, **kwargs):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help="print the version and exit")

    def __call__(self, parser, namespace, values, option_string=None):
        from vibroimpact._release import version

        print(f"vibroimpact {version()}")
        parser.exit()


def _parser():
    parser = argparse.ArgumentParser(
        prog="vibroimpact",
        description="Check, plan and build the vibroimpact workflow in the working directory "
                    "(README).")
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True)
    for name, text in (("plan", "check the config and print what a build would make"),
                       ("run", "check, prepare and build (extra arguments go to snakemake)"),
                       ("report", "write Snakemake's report of the build (after run)")):
        p = sub.add_parser(name, help=text, description=text)
        p.add_argument("--configfile", action="extend", nargs="+", default=[], metavar="FILE",
                       help="your config files, layered on the paper's config "
                            "(config/config.yaml) in order (README): several after one "
                            "--configfile, as Snakemake takes them, or the option repeated; "
                            "targets go before it")
        if name == "report":
            p.add_argument("--output", default=REPORT, metavar="FILE",
                           help=f"the report, relative to the project directory (default "
                                f"{REPORT}; .html)")
        else:
            p.add_argument("--cores", type=_cores, default=None,
                           help="cores of the build: a number, or all (default: all of them; "
                                "through a SLURM profile, the profile's)")
        p.add_argument("--directory", default=".",
                       help="the working directory, where results/ is (default .)")
        p.add_argument("-v", "--verbose", action="store_true",
                       help="also print the schema validator's full output on a config error")
    # listed for --help only: main() (stale) and vibroimpact.__main__ (warm) hand them over
    # before this parser sees them, with their own options
    for name, text in (("stale", "list the outputs of the config's entries that it no longer "
                                 "builds (--delete: remove them)"),
                       ("warm", "compile every numba kernel of the jobs into numba's cache, "
                                "once per installation")):
        sub.add_parser(name, help=text, description=text, add_help=False)
    return parser


#: Endings of a config file (Snakemake reads JSON or YAML); a name after --configfile with
#: none of them that is no file is a target given in the wrong place.
CONFIG_SUFFIXES = (".yaml", ".yml", ".json")
#: Endings of the build's own outputs: a name after --configfile with one of them is a target,
#: whether or not the file exists yet.
OUTPUT_SUFFIXES = (".png", ".pdf", ".nc", ".html", ".ipynb", ".tsv")

#: Where ``report`` writes Snakemake's report (README, "Reports").
REPORT = "results/report.html"
#: The costs of the build's jobs by rule (rule ``job_costs``), written by ``report`` just
#: before Snakemake's report and shown in it.
JOB_COSTS = "results/reports/job_costs.html"


def _cores(text):
    """``--cores``: a positive number, or ``all`` (this machine's CPU count)."""
    if text == "all":
        return os.cpu_count() or 1
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"--cores {text}: allowed: a number >= 1, or all")
    return value


def profiles(extra):
    """The profile folders among Snakemake's arguments ``extra`` (``--workflow-profile X``,
    ``--profile X``, or with ``=``)."""
    found = []
    for i, arg in enumerate(extra):
        name, _, value = arg.partition("=")
        if name in ("--workflow-profile", "--profile"):
            if value:
                found.append(value)
            elif i + 1 < len(extra):
                found.append(extra[i + 1])
    return found


def _fail(message, code=2):
    for line in str(message).splitlines():
        print(f"error: {line}" if line and not line.startswith(" ") else line, file=sys.stderr)
    return code


def live_snakemake_runs(root):
    """Processes running Snakemake in directory ``root`` (not their job processes)."""
    import psutil

    root, found = Path(root).resolve(), []
    for proc in psutil.process_iter(["pid", "cmdline"]):
        try:
            cmd = proc.info["cmdline"] or []
            main = any(Path(a).name == "snakemake" for a in cmd[:2]) or (
                "-m" in cmd[:3] and "snakemake" in cmd[:4])
            if main and proc.pid != os.getpid() and Path(proc.cwd()).resolve() == root:
                found.append(proc)
        except (psutil.Error, OSError):
            continue
    return found


#: What a build writes in the project directory: the results and Snakemake's own state.
WRITTEN = ("results", ".snakemake")


def unwritable_folders(root):
    """The folders a build in ``root`` writes into that this user may not write.

    Every folder under ``results`` and ``.snakemake`` (:data:`WRITTEN`), and ``root`` itself
    when one of them is still to be made. Writing a file into a folder takes write and
    search permission on it, asked of the kernel for the real user by ``os.access`` (so
    ``root`` may write anywhere, as the build would).

    Returns
    -------
    list of pathlib.Path
        Outermost first; empty when the build can write everything it needs.
    """
    root = Path(root)
    folders = {}
    for name in WRITTEN:
        top = root / name
        walk = os.walk(top) if top.is_dir() else [(root, (), ())]
        folders.update((Path(parent), None) for parent, _, _ in walk)
    return [f for f in folders if not os.access(f, os.W_OK | os.X_OK)]


def _mount_point(folder):
    """The mount point of the file system holding ``folder`` (symbolic links resolved)."""
    path = Path(os.path.realpath(folder))
    dev = path.stat().st_dev
    while path.parent != path and path.parent.stat().st_dev == dev:
        path = path.parent
    return path


def _read_only(folder):
    """Whether ``folder`` is on a file system mounted read-only (no ``chmod`` can help)."""
    try:
        return bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except OSError:
        return False


def _unwritable_message(root, folders):
    """One line: the first folder ``root``'s build may not write, how many more, the remedy
    (``chmod`` of the outermost ones when they are the user's, else whose they are; on a
    read-only mount, which no ``chmod`` changes: remounting it, or building elsewhere)."""
    def shown(folder):
        return str(folder) if folder == root else os.path.relpath(folder)

    more = f", nor are {len(folders) - 1} more folders" if len(folders) > 1 else ""
    read_only = [f for f in folders if _read_only(f)]
    if read_only:
        first = read_only[0]
        links = [f"{shown(p)} -> {os.readlink(p)}"
                 for p in (first, *first.parents) if p.is_symlink()]
        via = f", through the link {links[-1]}" if links else ""
        return (f"{shown(first)} is on a file system mounted read-only at "
                f"{_mount_point(first)}{via}: no chmod "
                f"can change that; remount it read-write, or give the build a writable folder "
                f"in its place (e.g. replace the link by a folder on a writable disk), or build "
                f"in a copy of the project; nothing was changed")
    others = sorted({f.stat().st_uid for f in folders} - {os.getuid()})
    if others:
        import pwd

        names = []
        for uid in others:
            try:
                names.append(pwd.getpwuid(uid).pw_name)
            except KeyError:
                names.append(f"uid {uid}")
        fix = f"owned by {', '.join(names)}: ask them to make it writable"
    elif more:
        outermost = [f for f in folders if not set(f.parents) & set(folders)]
        fix = f"chmod -R u+w {' '.join(shown(f) for f in outermost)}"
    else:
        fix = f"chmod u+w {shown(folders[0])}"
    return (f"{shown(folders[0])} is not writable by you{more} ({fix}, or build in a copy of "
            f"the project); nothing was changed")


#: The lock file a ``run`` holds, with ``flock``, from its checks to the end of its build.
BUILD_LOCK = Path(".snakemake") / "vibroimpact-build.lock"


def take_build_lock(root):
    """Take the build lock of project ``root`` (:data:`BUILD_LOCK`) or learn who holds it.

    An exclusive ``flock`` of the lock file, asked without waiting: of two runs started at
    the same instant the kernel gives it to one only (the check and the taking are one
    step, unlike looking for Snakemake's locks first). The descriptor is inheritable, so the
    lock passes to Snakemake with ``exec`` and stays taken for the whole build; the kernel
    releases it when the build's process ends, however it ends (no stale lock to clear).

    Returns
    -------
    (int, None) or (None, str)
        The open descriptor holding the lock (the holder's pid written in the file), or
        the pid of the run holding it (``"?"`` when it has not written it yet).
    """
    import fcntl

    path = root / BUILD_LOCK
    if path in _HELD:                 # this process holds it already (``main`` called again)
        return _HELD[path], None
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
        os.close(fd)
        return None, holder
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    os.set_inheritable(fd, True)
    _HELD[path] = fd
    return fd, None


#: The build locks this process holds: lock file -> descriptor (kept until it exits).
_HELD = {}


def _snakemake(root):
    """Snakemake on the workflow a build in ``root`` runs (`vibroimpact.pipeline.layout`: the
    folder's own ``workflow/``, as plain ``snakemake`` there, or the one this package
    carries), this interpreter's (``python -m snakemake``, whether or not its command is on
    the PATH), ``--snakefile`` given, so that it runs from any working directory."""
    return [sys.executable, "-m", "snakemake", "--snakefile", str(layout.snakefile(root))]


def _clear_stale_lock(root, config_args):
    """``snakemake --unlock`` when a killed run left its lock and no run is alive here."""
    locks = root / ".snakemake" / "locks"
    if not locks.is_dir() or not any(locks.iterdir()):
        return 0
    alive = live_snakemake_runs(root)
    if alive:
        pids = ", ".join(str(p.pid) for p in alive)
        return _fail(f"another Snakemake run is alive in {root} (pid {pids}); wait for it to "
                     f"finish, or stop it (kill {pids}) and run again", code=1)
    print("vibroimpact: clearing the lock left by a run that did not finish (no run is alive "
          "here)", file=sys.stderr)
    out = subprocess.run([*_snakemake(root), "--unlock", *config_args], cwd=root,
                         capture_output=True, text=True)
    if out.returncode != 0:
        return _fail(f"snakemake --unlock failed:\n{out.stderr[-2000:]}", code=1)
    return 0


def missing_outputs(summary):
    """Outputs that a build would leave missing, from ``snakemake --summary``'s table.

    Snakemake runs a job whose output is missing only when that output is a target or a job
    that needs it runs: a deleted intermediate whose consumers are up to date is never
    rebuilt (its status ``missing``, its plan ``no update``). These are the files to give
    ``--forcerun``: their jobs run, and then, their outputs being newer, what uses them.

    Parameters
    ----------
    summary : str
        The standard output of ``snakemake ... --summary``.

    Returns
    -------
    list of str or None
        The missing outputs; ``None`` when ``summary`` is not that table (another mode of
        Snakemake asked for by the user took precedence over ``--summary``).
    """
    lines = summary.splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.startswith("output_file\t"))
    except StopIteration:
        return None
    rows = (line.split("\t") for line in lines[start + 1:])
    return [row[0] for row in rows if len(row) >= 6 and row[-2:] == ["missing", "no update"]]


def has_written(results):
    """Whether folder ``results`` holds a file: only then may an output be missing while
    what uses it is up to date, which ``run`` asks Snakemake about (``--summary``)."""
    return any(files for _, _, files in os.walk(results))


def with_forcerun(cmd, files):
    """``cmd`` with ``files`` added to its ``--forcerun``: Snakemake keeps only the last
    ``--forcerun``/``-R`` list given, so the user's own list is extended, not replaced (one
    value glued to its option, ``--forcerun=X`` or ``-RX``, moves to the end of ``cmd``)."""
    for i in reversed(range(len(cmd))):
        word = cmd[i]
        if word in ("-R", "--forcerun"):
            return [*cmd[:i + 1], *files, *cmd[i + 1:]]
        if word.startswith(("--forcerun=", "-R")):
            value = word.partition("=")[2] if word.startswith("--") else word[2:]
            return [*cmd[:i], *cmd[i + 1:], "--forcerun", value, *files]
    return [*cmd, "--forcerun", *files]


def write_report(root, config_args, output=REPORT):
    """The costs of the build's jobs by rule (`JOB_COSTS`, rule ``job_costs``: no input, so
    it runs alone, forced, from the benchmark files on disk), then ``snakemake --report``
    of ``rule all`` and that table into a scratch directory, moved to ``root / output`` in
    one rename (:func:`vibroimpact._files.atomic_path`): a report that fails or is
    interrupted leaves the previous ``output`` as it was, never a half-written one."""
    import tempfile

    target = root / output
    if target.suffix != ".html":
        return _fail(f"--output {output}: allowed: a file name ending in .html")
    sys.stdout.flush()
    code = subprocess.run([*_snakemake(root), "--cores", "1", "--quiet", "--forcerun",
                           "job_costs", *config_args, "--", JOB_COSTS], cwd=root).returncode
    if code != 0:
        return _fail(f"the job costs ({JOB_COSTS}) failed (exit {code}); {output} is left as "
                     f"it was", code=1)
    with tempfile.TemporaryDirectory(prefix="vibroimpact-report-") as scratch:
        draft = Path(scratch) / "report.html"
        code = subprocess.run([*_snakemake(root), "--report", str(draft), *config_args,
                               "--", "all", JOB_COSTS], cwd=root).returncode
        if code != 0 or not draft.is_file():
            return _fail(f"snakemake --report failed (exit {code}); {output} is left as it was",
                         code=1)
        with _files.atomic_path(target) as tmp:
            shutil.copyfile(draft, tmp)
    print(f"vibroimpact: Snakemake's report: {output} ({target.stat().st_size / 1e6:.1f} MB)",
          file=sys.stderr)
    return 0


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    if command == "stale":      # its own options, after the command's name
        from vibroimpact.pipeline import stale

        return stale.main(argv[argv.index(command) + 1:])
    args, extra = _parser().parse_known_args(argv)
    if args.command in ("plan", "report") and extra:
        return _fail(f"unknown arguments {extra}; {args.command} takes --configfile, "
                     f"{'--cores' if args.command == 'plan' else '--output'}, --directory, -v")
    if args.verbose:
        os.environ[config.VERBOSE_ENV] = "1"
    root = Path(args.directory).resolve()
    for name in args.configfile:
        suffix = Path(name).suffix.lower()
        if suffix in OUTPUT_SUFFIXES or (suffix not in CONFIG_SUFFIXES
                                         and not Path(name).is_file()):
            others = " ".join(f for f in args.configfile if f != name)
            hint = (f": give targets before it, e.g. run {name}"
                    + (f" --configfile {others}" if others else "")
                    if args.command == "run" else "")
            return _fail(f"--configfile {name}: no such config file; every name after "
                         f"--configfile is one (several are layered in order, as Snakemake "
                         f"takes them){hint}")
    try:
        _, plan = config.load(root=root, user_files=args.configfile)
    except config.ConfigError as err:
        return _fail(err)
    config_args = ["--configfile", *args.configfile] if args.configfile else []
    if args.command == "report":
        return write_report(root, config_args, args.output)
    slurm = any(cluster.is_slurm_profile(root / folder) for folder in profiles(extra))
    if slurm and cluster.site_problem():
        return _fail(cluster.site_problem())
    # a cluster's jobs run on its nodes: the cores of this machine are not theirs
    cores = args.cores or _cores("all")
    cores_args = [] if slurm and args.cores is None else ["--cores", str(cores)]
    print(plan.format(cores), file=sys.stderr if args.command == "run" else sys.stdout)
    if args.command == "plan":
        return 0
    unwritable = unwritable_folders(root)
    if unwritable:
        return _fail(_unwritable_message(root, unwritable), code=1)
    lock, holder = take_build_lock(root)
    if lock is None:
        return _fail(f"another build is running in {root} (pid {holder}); wait for it to "
                     f"finish, or stop it (kill {holder}) and run again", code=1)
    removed = _files.sweep_stale_temporaries(root / "results")
    if removed:
        print(f"vibroimpact: removed {len(removed)} temporary file(s) of interrupted writes",
              file=sys.stderr)
    try:
        unchecked = io.check_readable(root / "results")
    except io.CorruptFileError as err:
        return _fail(err, code=1)
    if unchecked:
        print(f"vibroimpact: {len(unchecked)} result file(s) carry no checksums (written "
              f"before them, e.g. {unchecked[0]}): read through and accepted; the build "
              f"rewrites them (their writer's code changed)", file=sys.stderr)
    code = _clear_stale_lock(root, config_args)
    if code:
        return code
    # targets before --configfile, which would take them as more config files
    cmd = [*_snakemake(root), *cores_args, *extra, *config_args]
    sys.stdout.flush()
    sys.stderr.flush()
    # a first build (no file under results yet) has no output to miss beneath an up-to-date
    # one: no question to ask (a Snakemake start, 1.3-3 s before the first job)
    missing = []
    if has_written(root / "results"):
        try:
            query = subprocess.run([*cmd, "--summary"], cwd=root, capture_output=True,
                                   text=True)
        except KeyboardInterrupt:
            return _fail("interrupted while asking Snakemake what is missing; nothing was "
                         "built", code=130)
        missing = missing_outputs(query.stdout)
        if query.returncode != 0 or missing is None:
            # Snakemake refused the arguments, or this was the user's own mode (--unlock,
            # --dag ..., which take precedence over --summary): it has run; its output, once
            sys.stdout.write(query.stdout)
            sys.stderr.write(query.stderr)
            return query.returncode
    if missing:
        names = ", ".join(missing[:5]) + (f" ... ({len(missing)} files)" if missing[5:] else "")
        print(f"vibroimpact: missing, so rebuilt with what uses them (--forcerun): {names}",
              file=sys.stderr)
        cmd = with_forcerun(cmd, missing)
        sys.stderr.flush()
    os.chdir(root)
    os.execv(cmd[0], cmd)
