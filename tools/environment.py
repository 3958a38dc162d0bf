"""The exact environment: what requirements.lock pins, and the files made from it.

``requirements.lock`` is written by uv (``make lock``) from the direct requirements of
pyproject.toml (the package's, the ``slurm`` extra, the ``dev`` and ``docs`` groups): every
distribution of the development environment, its version, the platforms it applies to (a
marker) and the hashes of every file PyPI serves for it. ``make`` installs it with ``uv pip sync
--require-hashes``. This script reads it with ``packaging`` (what pip and uv implement) for
what the lock itself cannot do:

- ``conda``: write the conda environment of the rules (``workflow/envs/vibroimpact.yaml``),
  its pip section the lock's pins, so that ``--sdm conda`` installs the versions ``make``
  does; from any folder (no relative path in it). ``--check`` fails if the file differs.
- ``check``: compare the distributions this interpreter sees with the lock (pinned versions,
  markers evaluated here); a line per difference, exit status 1 if any.
- ``entry NAME``: print the lock's entry for NAME with its hashes (``make`` installs uv
  itself from it with pip's ``--require-hashes``).

``entry`` needs the standard library only: it runs in a venv that holds nothing yet; the others
read markers with ``packaging``, which the lock installs.
"""
import argparse
from importlib import metadata
from pathlib import Path
import re
import sys

ROOT = Path(__file__).resolve().parents[1]
LOCK = ROOT / "requirements.lock"
CONDA_ENV = ROOT / "workflow" / "envs" / "vibroimpact.yaml"
#: The package itself: installed from its sources (editable), never from the lock.
PROJECT = "vibroimpact"


def entries(lock=LOCK):
    """``[(requirement text, lines)]`` of the lock, in its order: each pin with its marker
    (``numpy==2.4.6``, ``appnope==1.0.0 ; sys_platform == 'darwin'``) and its whole entry,
    hashes included (comments left out)."""
    out, current = [], None
    for line in Path(lock).read_text().splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if not line.startswith((" ", "\t")):
            current = (line.rstrip(" \\").strip(), [line])
            out.append(current)
        elif current is not None:
            current[1].append(line)
    return out


def canonical(name):
    """A distribution's name as PEP 503 compares them (``PyYAML``, ``pyyaml``: one)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def pins(lock=LOCK, environment=None):
    """``{canonical name: version}`` of the lock's pins that apply to ``environment`` (a
    marker environment; None: this interpreter's)."""
    from packaging.requirements import Requirement

    found = {}
    for text, _ in entries(lock):
        req = Requirement(text)
        if req.marker is not None and not req.marker.evaluate(environment):
            continue
        (spec,) = req.specifier
        if spec.operator != "==":
            raise ValueError(f"{lock}: {text}: not an exact pin")
        found[canonical(req.name)] = spec.version
    return found


def installed(paths=None):
    """``{canonical name: version}`` of the distributions on ``paths`` (default sys.path),
    the package itself left out."""
    found = {}
    for dist in metadata.distributions(path=sys.path if paths is None else paths):
        name = canonical(dist.metadata["Name"])
        if name != PROJECT:
            found.setdefault(name, dist.version)
    return found


def differences(locked, present):
    """One line per distribution missing, extra or at another version than the lock's."""
    lines = [f"missing: {name}=={locked[name]}" for name in sorted(set(locked) - set(present))]
    lines += [f"not in the lock: {name}=={present[name]}"
              for name in sorted(set(present) - set(locked))]
    lines += [f"{name}: {present[name]} installed, {locked[name]} locked"
              for name in sorted(set(locked) & set(present)) if locked[name] != present[name]]
    return lines


def conda_env(lock=LOCK):
    """The text of the conda environment file: Python 3.11 (the lock's, `make lock`) and pip
    from conda-forge, and every pin of the lock (its marker kept) installed by pip."""
    lines = [
        "# The software of every rule under `snakemake --sdm conda` (README, \"Containers and",
        "# conda\"): the pins of requirements.lock, written by `make lock` (tools/environment.py",
        "# conda); do not edit. The jobs import vibroimpact from the copy the Snakemake process",
        "# runs (workflow/rules/common.smk, PYTHONPATH), so this file holds no path and works",
        "# from any folder, and its content, which names Snakemake's environment, follows the",
        "# lock.",
        "channels:",
        "  - conda-forge",
        "  - nodefaults",
        "dependencies:",
        "  - python=3.11",
        "  - pip",
        "  - pip:",
    ]
    lines += [f"      - \"{text}\"" for text, _ in entries(lock)]
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(prog="tools/environment.py", description=__doc__.split(
        "\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    conda = sub.add_parser("conda", help=f"write {CONDA_ENV.relative_to(ROOT)} from the lock")
    conda.add_argument("--check", action="store_true", help="only compare; exit 1 if stale")
    sub.add_parser("check", help="compare this interpreter's distributions with the lock")
    entry = sub.add_parser("entry", help="print the lock's entry for a distribution")
    entry.add_argument("name")
    args = parser.parse_args(argv)
    if args.command == "conda":
        text = conda_env()
        if args.check:
            same = CONDA_ENV.is_file() and CONDA_ENV.read_text() == text
            if not same:
                print(f"{CONDA_ENV.relative_to(ROOT)} does not follow requirements.lock: "
                      f"run `make lock`", file=sys.stderr)
            return 0 if same else 1
        CONDA_ENV.write_text(text)
        return 0
    if args.command == "check":
        lines = differences(pins(), installed())
        for line in lines:
            print(line)
        return 1 if lines else 0
    found = [lines for text, lines in entries()
             if canonical(re.split(r"[=<>!~; \[]", text, maxsplit=1)[0]) == canonical(args.name)]
    if not found:
        print(f"{args.name}: not in {LOCK.name}", file=sys.stderr)
        return 1
    print("\n".join(line for line in found[0] if not line.lstrip().startswith("#")))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
