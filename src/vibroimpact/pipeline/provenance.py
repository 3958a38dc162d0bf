"""Provenance: what every output records about how it was made, and the code digests.

`provenance` is called by each job at run time (never passed through the workflow's params,
so a commit alone reruns nothing) and records the package version, the git commit of the
package's source tree with a dirty flag, the config block the job read (YAML text and
digest), the creation time, the seed and the paper's reference, and, for a study expanded
from a sweep, its combination (`sweep_attrs`). `source_digest` is what the workflow puts in
params instead: a digest of the package sources an output depends on, so editing them
(committed or not) reruns exactly the jobs they feed.
"""
import functools
import hashlib
import json
from pathlib import Path
import subprocess

__all__ = ["config_digest", "config_text", "source_digest", "git_state", "provenance",
           "sweep_attrs"]

PACKAGE_DIR = Path(__file__).resolve().parents[1]


def config_digest(obj):
    """SHA-256 of the canonical JSON form of a config fragment."""
    text = json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def source_digest(*modules):
    """SHA-256 over the source files of package modules, given as paths inside the package.

    ``"impact"`` is the subpackage (every ``.py`` file under it), ``"pipeline/io"`` one
    module. Files are hashed by relative path and content, so a rename counts too.

    Raises
    ------
    ValueError
        If a name is neither a module nor a subpackage of vibroimpact.
    """
    digest = hashlib.sha256()
    for name in sorted(modules):
        package, module = PACKAGE_DIR / name, PACKAGE_DIR / f"{name}.py"
        if package.is_dir():
            files = sorted(package.rglob("*.py"))
        elif module.is_file():
            files = [module]
        else:
            raise ValueError(f"source_digest: no module or subpackage {name!r} in {PACKAGE_DIR}")
        for path in files:
            digest.update(str(path.relative_to(PACKAGE_DIR)).encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


@functools.cache
def git_state():
    """``(commit, dirty)`` of the git tree holding the package sources, or ``("unknown", -1)``.

    ``dirty`` is 1 when tracked files differ from the commit (the output may come from
    uncommitted code), 0 when clean; an installed copy outside git gives ``("unknown", -1)``.
    """
    def git(*args):
        out = subprocess.run(["git", *args], cwd=PACKAGE_DIR, capture_output=True, text=True,
                             timeout=30)
        if out.returncode != 0:
            raise OSError(out.stderr)
        return out.stdout.strip()
    try:
        commit = git("rev-parse", "HEAD")
        dirty = int(bool(git("status", "--porcelain", "--untracked-files=no")))
    except (OSError, subprocess.SubprocessError):
        return "unknown", -1
    return commit, dirty


def config_text(obj):
    """The YAML text of a config fragment, keys sorted (what a dataset's ``config`` holds)."""
    import yaml

    return yaml.safe_dump(obj, sort_keys=True, default_flow_style=None, width=100)


def sweep_attrs(config_block):
    """``sweep``, ``sweep_index`` and ``sweep_<key>`` (e.g. ``sweep_eps``, ``sweep_rms``) of a
    study expanded from a sweep (its block's ``sweep`` key,
    `vibroimpact.pipeline.config.sweeps.expand_sweeps`); empty for any other block."""
    sweep = config_block.get("sweep") if isinstance(config_block, dict) else None
    if not sweep:
        return {}
    attrs = {"sweep": str(sweep["name"]), "sweep_index": int(sweep["index"])}
    attrs.update({f"sweep_{key}": value for key, value in sweep["values"].items()})
    return attrs


def provenance(config_block, seed=None):
    """Global attributes every output carries, collected now (at run time).

    ``config`` (the block as YAML text: the same block the rule's params carry, so the
    dataset says what it was computed from), ``config_digest``, ``created`` (UTC, ISO
    8601), ``package_version``, ``git_commit`` and ``git_dirty``, ``paper_reference``; and
    :func:`sweep_attrs` for a study of a sweep.

    Parameters
    ----------
    config_block : mapping
        The config the job read.
    seed : int, optional
        The seed of the random input the output derives from.
    """
    from datetime import datetime, timezone

    from vibroimpact import PAPER_REFERENCE, __version__

    commit, dirty = git_state()
    attrs = dict(package_version=__version__, git_commit=commit, git_dirty=dirty,
                 config=config_text(config_block), config_digest=config_digest(config_block),
                 created=datetime.now(timezone.utc).isoformat(timespec="seconds"),
                 paper_reference=PAPER_REFERENCE)
    if seed is not None:
        attrs["seed"] = int(seed)
    attrs.update(sweep_attrs(config_block))
    return attrs
