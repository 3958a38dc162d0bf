"""The one atomic-write helper: a result appears under its final name complete, or not at all."""
import contextlib
import errno
import os
from pathlib import Path
import re
import secrets
import shutil
import signal
import socket
import threading
import time

__all__ = ["atomic_path", "sweep_stale_temporaries", "TEMP_PATTERN", "DiskFullError"]

#: Temporary names: ``.<name>.<pid>.<random>@<host>.tmp`` beside the final file, so a later
#: run can tell whose they are (the writer's process, on which machine).
TEMP_PATTERN = re.compile(r"^\.(?P<name>.+)\.(?P<pid>[0-9]+)\.[0-9a-f]{12}@(?P<host>.+)\.tmp$")

#: A temporary file of another machine untouched this long is stale (its writer is gone).
STALE_ELSEWHERE_S = 2 * 24 * 3600.0


#: A write that fails (with any OS error: the netCDF library reports a full disk as a
#: permission error) where less than this is free is reported as a full disk.
DISK_FULL_MARGIN = 4 * 2**20


class DiskFullError(OSError):
    """A result could not be written: its file system is full (one line: the mount, what is
    free, what the writer had written)."""

    def __init__(self, path, written, free, cause):
        mount = Path(path).resolve().parent
        while not os.path.ismount(mount) and mount != mount.parent:
            mount = mount.parent
        super().__init__(errno.ENOSPC,
                         f"no space left on {mount}: {free / 1e6:.2f} MB free, and writing "
                         f"{Path(path).name} had taken {written / 1e6:.2f} MB when it failed "
                         f"({type(cause).__name__}: {cause}); free some space and run again "
                         f"(nothing half-written is kept)")


def _disk_full(path, tmp, err):
    """``err`` (raised while writing ``tmp``) as a :class:`DiskFullError` when the disk is full
    (ENOSPC, EDQUOT, or any OS error with less than `DISK_FULL_MARGIN` free), else None."""
    try:
        free = shutil.disk_usage(Path(path).parent).free
    except OSError:
        return None
    if err.errno not in (errno.ENOSPC, errno.EDQUOT) and free >= DISK_FULL_MARGIN:
        return None
    try:
        written = os.path.getsize(tmp)
    except OSError:
        written = 0
    return DiskFullError(path, written, free, err)


def _raise_exit(signum, frame):
    raise SystemExit(128 + signum)


@contextlib.contextmanager
def _terminate_as_exit():
    """While writing, SIGTERM unwinds like Ctrl-C (so ``finally`` removes the temporary)."""
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        yield
        return
    signal.signal(signal.SIGTERM, _raise_exit)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a fresh temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    The temporary name is in the target's directory (so :func:`os.replace` is a rename on one
    file system), starts with a dot and names its writer (:data:`TEMP_PATTERN`); it is not
    created here, so the writer creates it with the usual umask permissions. On any
    exception, an interrupt (SIGINT) or a SIGTERM, the temporary file is removed and
    ``path`` is left as it was: a failed or interrupted run never leaves a half-written file
    under a name a later run would trust. A writer killed outright (SIGKILL) leaves its
    temporary, which :func:`sweep_stale_temporaries` removes at the next start. A write
    that fails on a full disk raises :class:`DiskFullError`, which says so in one line.

    Parameters
    ----------
    path : str or os.PathLike
        The final file name; missing directories are created.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(6)}"
                         f"@{socket.gethostname()}.tmp")
    with _terminate_as_exit():
        try:
            try:
                yield str(tmp)
                os.replace(tmp, path)
            except OSError as err:
                full = _disk_full(path, tmp, err)
                if full is None:
                    raise
                raise full from err
        finally:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)


def _alive(pid):
    """Whether process ``pid`` of this machine runs: it exists and is not a zombie (a killed
    writer whose parent has not reaped it yet writes nothing any more)."""
    import psutil

    try:
        return psutil.Process(pid).status() != psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return False
    except psutil.Error:            # AccessDenied: it exists, and may still be writing
        return True


def sweep_stale_temporaries(root):
    """Remove the temporary files of writers that are gone, under directory ``root``.

    A temporary of this machine is stale when its writer's process is no longer alive (gone,
    or a zombie: killed, not yet reaped by its parent); one
    written on another machine (a cluster node) when untouched for two days. A live
    writer's temporary is never touched. Returns the removed paths.
    """
    root, host, now, removed = Path(root), socket.gethostname(), time.time(), []
    if not root.is_dir():
        return removed
    for tmp in root.rglob(".*.tmp"):
        match = TEMP_PATTERN.match(tmp.name)
        if match is None:
            continue
        stale = False
        if match["host"] == host:
            stale = not _alive(int(match["pid"]))
        else:
            with contextlib.suppress(FileNotFoundError):
                stale = now - tmp.stat().st_mtime > STALE_ELSEWHERE_S
        if stale:
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()
                removed.append(tmp)
    return removed
