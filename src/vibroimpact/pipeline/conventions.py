"""The CF conventions of every file the pipeline writes: global attributes and the check.

Every variable and coordinate of a dataset carries ``long_name`` and ``units`` (a UDUNITS
unit: ``"1"`` for the model's dimensionless quantities, its time tau and frequencies too, and
for counts, fractions and labels; the dimensionless unit is said in ``long_name`` where it
matters, e.g. "per unit of non-dimensional time tau"). :func:`missing` lists the variables
that lack either, and `pipeline.io.write_dataset` refuses to write such a dataset.

The global attributes CF asks for are given at the one place that writes a file
(:func:`global_attributes`, called by `pipeline.io`): ``Conventions``, ``source`` (the package,
its version and commit), ``references`` (the paper) and ``history`` (when, by which command:
the creation time of the job's provenance, so a rebuild differs there as it does in
``created``; the datasets' data, which every comparison of two builds reads, do not).
"""
from pathlib import Path
import re
import sys

__all__ = ["CONVENTIONS", "global_attributes", "missing", "command"]

#: The CF version the files follow.
CONVENTIONS = "CF-1.11"

#: A rule's script as Snakemake runs it: a copy named ``tmp<random>.<script>.py``.
_SNAKEMAKE_SCRIPT = re.compile(r"tmp[^.]+\.(?P<script>.+\.py)")


def missing(ds):
    """``[(name, attribute), ...]``: every variable or coordinate of ``ds`` without a
    non-empty ``long_name`` or ``units`` (in its attributes, or its encoding: where xarray
    keeps the units of the times it decoded)."""
    out = []
    for name, var in ds.variables.items():
        for key in ("long_name", "units"):
            if not str(var.attrs.get(key) or var.encoding.get(key) or "").strip():
                out.append((str(name), key))
    return out


def command(argv=None):
    """The command this process runs, in words: ``workflow/scripts/<script>.py`` for a
    rule's script (Snakemake's temporary copy named back), else the command line."""
    argv = list(sys.argv if argv is None else argv) or ["python"]
    match = _SNAKEMAKE_SCRIPT.fullmatch(Path(argv[0]).name)
    if match:
        return f"workflow/scripts/{match['script']} (Snakemake)"
    return " ".join([Path(argv[0]).name, *argv[1:]])


def global_attributes(attrs, path):
    """The CF global attributes of a file written to ``path`` with the attributes ``attrs``
    (a job's `provenance` among them): ``Conventions``, ``source``, ``references`` and
    ``history``, a line ``<created> <command>: wrote <file name>`` before any ``history``
    the attributes brought along (a dataset joined from tiles keeps theirs)."""
    from datetime import datetime, timezone

    from vibroimpact import PAPER_REFERENCE, _version

    version = attrs.get("package_version") or _version()
    source = f"vibroimpact {version}"
    commit = str(attrs.get("git_commit", ""))
    if commit and commit != "unknown":
        dirty = " with uncommitted changes" if int(attrs.get("git_dirty", 0)) == 1 else ""
        source += f" (git {commit}{dirty})"
    created = (attrs.get("created")
               or datetime.now(timezone.utc).isoformat(timespec="seconds"))
    line = f"{created} {command()}: wrote {Path(path).name}"
    before = str(attrs.get("history", "")).strip()
    return {"Conventions": CONVENTIONS, "source": source,
            "references": attrs.get("paper_reference", PAPER_REFERENCE),
            "history": line + ("\n" + before if before else "")}
