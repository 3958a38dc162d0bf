"""The code digests of the workflow's scripts, kept between runs.

Every Snakemake start (`make`'s pre-pass, its build, its report, each ``snakemake -n``)
computes the code digest of every script and notebook of the workflow for the rules' params
(`vibroimpact.pipeline.provenance.code_digest`), which parses and walks the whole package:
about 2.3 CPU-s a start. :func:`cached_code_digest` keeps the digests in a file under the
project's ``.snakemake`` folder, by the bytes of the package's sources and of the script.

A module of its own, reached by no job's script: editing it changes no job's code digest.
"""
import functools
import hashlib
import json
from pathlib import Path
import sys

from vibroimpact import _files
from vibroimpact.pipeline import layout
from vibroimpact.pipeline.provenance import PACKAGE_DIR, code_digest

__all__ = ["cached_code_digest"]


@functools.cache
def _sources_key(package_dir):
    """SHA-256 of everything :func:`code_digest` reads besides the script: Python's version
    (the form of ``ast.dump``) and every ``*.py`` under ``package_dir``, by relative path and
    bytes. Equal keys and equal scripts give equal digests. Computed once per process."""
    package_dir = Path(package_dir)
    digest = hashlib.sha256(f"{sys.version}\0".encode())
    for path in sorted(package_dir.rglob("*.py")):
        digest.update(f"{path.relative_to(package_dir).as_posix()}\0".encode())
        digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.hexdigest()


#: The table each cache file held when this process first read it, with what it added since.
_TABLES = {}


def _table(cache_file):
    if cache_file not in _TABLES:
        try:
            table = json.loads(Path(cache_file).read_text())
        except (OSError, ValueError):
            table = {}
        _TABLES[cache_file] = table if isinstance(table, dict) else {}
    return _TABLES[cache_file]


def cached_code_digest(script, cache_file, package_dir=PACKAGE_DIR):
    """:func:`~vibroimpact.pipeline.provenance.code_digest` of ``script``, kept in the JSON
    file ``cache_file`` between runs.

    The file maps the digest of the package's sources (every module by path and bytes, and
    Python's version) and of the script's bytes to the script's code digest; only the
    entries of the current sources are kept. A hit reads and hashes the package's ~130
    files (milliseconds) where ``code_digest`` parses and walks all of them. A miss computes
    the digest and rewrites the file in one rename (`vibroimpact._files.atomic_path`), so
    two processes writing at once leave one whole table, never a mixed one; a file that
    cannot be read or written (a read-only project) is a miss, never an error. A hit equals
    what ``code_digest`` computes from the same files.
    """
    script, package_dir = Path(script), Path(package_dir).resolve()
    sources = _sources_key(package_dir)
    script_key = hashlib.sha256(script.suffix.encode() + b"\0" + script.read_bytes())
    entry = f"{sources}:{script_key.hexdigest()}"
    table = _table(str(cache_file))
    if entry in table:
        return table[entry]
    value = code_digest(script, package_dir)
    for stale in [key for key in table if not key.startswith(f"{sources}:")]:
        del table[stale]
    table[entry] = value
    try:
        with _files.atomic_path(cache_file) as tmp:
            Path(tmp).write_text(json.dumps(table, sort_keys=True, indent=0))
    except OSError:
        pass        # a read-only project: the digest stands, it is only not kept
    return value


def main(root=".", workflow=None):
    """``python -m vibroimpact.pipeline.digest_cache``: keep the digests of every script and
    report notebook of ``workflow`` (by default the workflow a build in ``root`` runs,
    `vibroimpact.pipeline.layout.workflow_dir`) in working directory ``root`` (what `make`'s
    installation step runs, so that a first build's Snakemake start finds them)."""
    root = Path(root).resolve()
    cache = root / ".snakemake" / "vibroimpact-code-digests.json"
    workflow = Path(workflow) if workflow is not None else layout.workflow_dir(root)
    sources = [*sorted((workflow / "scripts").glob("*.py")),
               *sorted((workflow / "notebooks").glob("*.ipynb"))]
    for script in sources:
        cached_code_digest(script, cache)
    print(f"vibroimpact: code digests of {len(sources)} scripts and notebooks kept in "
          f"{cache.relative_to(root)}", file=sys.stderr)


if __name__ == "__main__":
    main(*sys.argv[1:2])
