"""Outputs of earlier configs left beside the current ones: ``python -m
vibroimpact.pipeline.stale [--configfile FILE ...] [--delete]`` (``make stale``, ``make
clean-stale``; README, "Outputs").

Snakemake never removes an output its config no longer asks for: a study that listed
``fig13`` at three forcing periods and now at two keeps ``fig13-2.png`` in
``results/figures/<study>/``, beside the current figures, with nothing marking it. The files
the current config builds are known before anything runs
(`vibroimpact.pipeline.targets.needed_files`, what the plan counts); this lists, under the
directories of the entries the config draws (``results/figures/<study>/``,
``results/figures/orbits/<name>/``, ``results/reports/<study>/``, ...) and their datasets
(``results/datasets/<study>_events.nc`` ...), every file that is not among them, and with
``--delete`` removes them. Other entries' outputs (with ``paper: false``, the paper's) are
never listed: they belong to another config.
"""
import argparse
from pathlib import Path
import sys

from vibroimpact.pipeline import targets

__all__ = ["stale_files", "owned_datasets", "main"]

def owned_datasets(section):
    """The path patterns of the datasets an entry of ``section`` (``"studies"`` or
    ``"orbits"``) may own, from the one table of them (`targets.DATASETS`): a study's under
    ``results/datasets/`` and its trace, an orbits entry's under ``results/orbits/``; the
    noise records are shared, no entry's."""
    under = ("results/orbits/",) if section == "orbits" else ("results/datasets/",
                                                             "results/traces/")
    return sorted({pattern for pattern in targets.DATASETS.values()
                   if "{name}" in pattern and pattern.startswith(under)})


def summary(files):
    """One line on the files :func:`stale_files` found (a build's end says it)."""
    shown = ", ".join(files[:3]) + (f" and {len(files) - 3} more" if files[3:] else "")
    return (f"vibroimpact: {len(files)} file(s) beside this config's outputs are not built by "
            f"it (an earlier config's): {shown}; `vibroimpact stale` lists them, "
            f"`vibroimpact stale --delete` (make clean-stale) removes them")


def stale_files(config, drawn, root="."):
    """Files under ``root``/results of the entries in ``drawn`` that the config does not
    build (sorted paths relative to ``root``)."""
    root = Path(root)
    needed = targets.needed_files(config, drawn)
    places = []                     # (directory, glob) owned by a drawn entry
    def datasets(section, name):
        return [tuple(pattern.format(name=name).rsplit("/", 1))
                for pattern in owned_datasets(section)]

    def folders(owner):             # its figures' and its reports' (`targets.PRODUCTS`)
        return [(targets.product(kind, owner=owner, figure="*", report="*").rsplit("/", 1)[0],
                 "*") for kind in ("figure", "report")]

    for name in drawn["studies"]:
        places += folders(name) + datasets("studies", name)
    for name in drawn["orbits"]:
        places += folders(f"orbits/{name}") + datasets("orbits", name)
    for name in config.get("sweeps", {}):
        if set(config["sweeps"][name]["studies"]) <= drawn["studies"]:
            folder, png = targets.product("sweep_figure", name=name).rsplit("/", 1)
            places.append((folder, png.rsplit(".", 1)[0] + ".*"))
    stale = set()
    for folder, pattern in places:
        for path in (root / folder).glob(pattern):
            if not path.is_file():
                continue
            rel = path.relative_to(root).as_posix()
            suffix = next((s for s in targets.TWINS if rel.endswith(s)), "")
            twin = rel[:len(rel) - len(suffix)] + targets.TWINS[suffix] if suffix else rel
            if twin not in needed:
                stale.add(rel)
    return sorted(stale)


def main(argv=None):
    from vibroimpact.pipeline import config as configuration

    parser = argparse.ArgumentParser(
        prog="vibroimpact stale",
        description="list (or delete) the outputs of the config's entries that the config "
                    "no longer builds")
    parser.add_argument("--configfile", action="append", default=[], metavar="FILE",
                        help="your config file, layered on the paper's config; repeat")
    parser.add_argument("--directory", default=".",
                        help="the working directory, where results/ is (default .)")
    parser.add_argument("--delete", action="store_true", help="remove the listed files")
    args = parser.parse_args(argv)
    try:
        config, plan = configuration.load(root=args.directory, user_files=args.configfile)
    except configuration.ConfigError as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    files = stale_files(config, plan.drawn, args.directory)
    for rel in files:
        print(rel)
        if args.delete:
            (Path(args.directory) / rel).unlink()
    what = "removed" if args.delete else ("not built by this config (make clean-stale, or "
                                          "vibroimpact stale --delete, removes them)")
    print(f"{len(files)} file(s) {what}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
