"""The one atomic-write helper: a result appears under its final name complete, or not at all."""
import contextlib
import os
import secrets
from pathlib import Path

__all__ = ["atomic_path"]


@contextlib.contextmanager
def atomic_path(path):
    """Yield a fresh temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    The temporary name is in the target's directory (so :func:`os.replace` is a rename on one
    file system) and starts with a dot; it is not created here, so the writer creates it with
    the usual umask permissions. On any exception, including an interrupt, the temporary file
    is removed and ``path`` is left as it was: a failed or interrupted run never leaves a
    half-written file under a name a later run would trust.

    Parameters
    ----------
    path : str or os.PathLike
        The final file name; missing directories are created.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(6)}.tmp")
    try:
        yield str(tmp)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
