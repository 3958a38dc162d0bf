"""Two builds hold the same results: every dataset's data bit for bit, every figure pixel for
pixel.

A refactoring that must not change behaviour (issue 23) is checked by building a config with
the old code and with the new, then::

    .venv/bin/python benchmarks/same_build.py OLD_ROOT NEW_ROOT

where each root holds a ``results/`` folder. Datasets are compared with
``xarray.testing.assert_identical`` after dropping what differs between any two runs of the
same code: the attributes (creation time, commit, dirty flag) and the variables marked
``run_measurement`` (CPU and wall times). Figures are compared as decoded RGBA arrays: a PNG's
bytes hold matplotlib's version string and compression choices, its pixels are the figure.
Per-job tiles (``cells/``, ``tiles/``) are compared too: they are what the datasets join.
Exit status 0 when everything matches, 1 with one line per difference otherwise.
"""
import argparse
from pathlib import Path
import sys

import matplotlib.image
import numpy as np
import xarray as xr


def _files(root, pattern):
    return sorted(p.relative_to(root) for p in (root / "results").rglob(pattern))


def _data(path):
    """A dataset without its attributes and run measurements (what two runs may differ in)."""
    ds = xr.load_dataset(path)
    timings = [v for v in ds.variables if ds[v].attrs.get("run_measurement") == 1]
    ds = ds.drop_vars(timings).drop_attrs()
    return ds


SKIP = ("validation", "work_precision.png", "stress.png")


def differences(old, new, *, skip=SKIP):
    """Lines naming each dataset or figure that is missing from one build or differs.

    ``skip``: folders or file names under results/ left out (the validation runs and their
    two figures show wall times).
    """
    out = []
    for pattern, same in (("*.nc", _same_dataset), ("*.png", _same_image)):
        a = {p for p in _files(old, pattern) if not set(skip) & set(p.parts)}
        b = {p for p in _files(new, pattern) if not set(skip) & set(p.parts)}
        out += [f"only in {old}: {p}" for p in sorted(a - b)]
        out += [f"only in {new}: {p}" for p in sorted(b - a)]
        for path in sorted(a & b):
            problem = same(old / path, new / path)
            if problem:
                out.append(f"{path}: {problem}")
    return out


def _same_dataset(a, b):
    try:
        xr.testing.assert_identical(_data(a), _data(b))
    except AssertionError as err:
        return str(err).splitlines()[0]
    return None


def _same_image(a, b):
    x, y = matplotlib.image.imread(a), matplotlib.image.imread(b)
    if x.shape != y.shape:
        return f"size {x.shape} != {y.shape}"
    n = int(np.count_nonzero(np.any(x != y, axis=-1)))
    return f"{n} pixels differ" if n else None


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path, help="root of the first build (holds results/)")
    parser.add_argument("new", type=Path, help="root of the second build (holds results/)")
    args = parser.parse_args(argv)
    problems = differences(args.old, args.new)
    counts = [sum(1 for f in _files(args.old, p) if not set(SKIP) & set(f.parts))
              for p in ("*.nc", "*.png")]
    for line in problems:
        print(line)
    print(f"{counts[0]} datasets and {counts[1]} figures of {args.old} compared: "
          + (f"{len(problems)} differences" if problems else "identical"))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
