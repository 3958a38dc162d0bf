"""Does the installation's warm-up compile every kernel a build calls? (issue 37)

``make`` compiles the package's numba kernels when it installs (``python -m
vibroimpact.warm``). A kernel specialization it misses is compiled by the first job
that calls it, which costs that job (and the build) the compile time, nothing else. This script
lists the machine code in numba's cache (the ``.nbc`` files beside the package, or under
``NUMBA_CACHE_DIR``) before and after a build and prints what the build had to compile::

    python benchmarks/warm_coverage.py snapshot /tmp/before.txt    # after make .venv/.installed
    make                                                           # the build
    python benchmarks/warm_coverage.py compare /tmp/before.txt     # what the build compiled

Exit status 1 when the build compiled anything.
"""
import argparse
import os
from pathlib import Path
import sys

REPO = Path(__file__).resolve().parent.parent


def cache_files():
    """``{path: mtime_ns}`` of every compiled specialization in the cache."""
    root = Path(os.environ["NUMBA_CACHE_DIR"]) if os.environ.get("NUMBA_CACHE_DIR") else (
        REPO / "src" / "vibroimpact")
    return {str(p): p.stat().st_mtime_ns for p in root.rglob("*.nbc")}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("command", choices=("snapshot", "compare"))
    parser.add_argument("file", type=Path, help="the snapshot written, or compared against")
    args = parser.parse_args(argv)
    now = cache_files()
    if args.command == "snapshot":
        args.file.write_text("".join(f"{p}\t{m}\n" for p, m in sorted(now.items())))
        print(f"{len(now)} compiled specializations in the cache")
        return 0
    before = dict(line.split("\t") for line in args.file.read_text().splitlines())
    new = sorted(p for p, m in now.items() if before.get(p) != str(m))
    for path in new:
        print(f"compiled by the build: {Path(path).name}")
    print(f"{len(before)} specializations before, {len(now)} after; {len(new)} compiled by "
          f"the build")
    return 1 if new else 0


if __name__ == "__main__":
    sys.exit(main())
