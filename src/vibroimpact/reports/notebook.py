"""Helpers the report notebooks (``notebooks/*.ipynb``) call, so their cells stay one line.

The notebooks are executed by papermill from the workflow (``workflow/rules/reports.smk``),
every input path passed as a parameter; a path given as ``""`` means "this study has no such
dataset", and the cells that need it say so instead of failing.
"""
from pathlib import Path
import re

import numpy as np


def at_project_root():
    """Move to the project directory (the one holding the ``Snakefile``) when run by hand
    from ``notebooks/``, where the default paths of the parameters cell would not resolve."""
    import os

    here = Path.cwd()
    if not (here / "Snakefile").exists() and (here.parent / "Snakefile").exists():
        os.chdir(here.parent)


def paths(text):
    """The paths in a whitespace-separated parameter (papermill passes strings), or a list."""
    if isinstance(text, (list, tuple)):
        return [str(p) for p in text]
    return str(text or "").split()


def open_dataset(path):
    """``xarray.load_dataset(path)``, or None for an empty path (no such dataset)."""
    import xarray as xr

    return xr.load_dataset(path) if path else None


def show_figures(figures):
    """Display each figure file inline (PNG embedded, so the HTML stands alone), under its
    path."""
    from IPython.display import Image, Markdown, display

    shown = paths(figures)
    if not shown:
        display(Markdown("*This study lists no figure.*"))
    for path in shown:
        display(Markdown(f"`{path}`"), Image(filename=path))


def show_table(found):
    """The findings as a table: number, the paper's claim, this run's numbers, verdict."""
    from IPython.display import display

    from vibroimpact.reports.findings import findings_table

    table = findings_table(found)
    display(table.style.set_properties(**{"text-align": "left", "white-space": "normal"}))
    return table


def provenance(**datasets):
    """One row per dataset: where it came from (package version, commit, config digest,
    creation time, seed, record length) — the attributes every dataset carries."""
    import pandas as pd

    keys = ("package_version", "git_commit", "git_dirty", "config_digest", "created", "seed",
            "record_length", "t_end", "transient")
    rows = {name: {k: ds.attrs.get(k, "") for k in keys}
            for name, ds in datasets.items() if ds is not None}
    return pd.DataFrame.from_dict(rows, orient="index")


def study_settings(ds, name=""):
    """The physical and statistical settings of a dataset (a study's or an orbits map's),
    from its attributes and grids, as a small table."""
    import pandas as pd

    keys = ("zeta", "eps", "amplitude", "transient", "t_end", "record_length", "n_batches",
            "motion_window", "rebound_floor", "nperseg", "target_stderr", "max_periods")
    values = {"entry": name} if name else {}
    values.update({k: ds.attrs[k] for k in keys if k in ds.attrs})
    values.update({k: ds.attrs[k] for k in sorted(ds.attrs) if k.startswith("sweep")})
    values.update({f"{d} grid": _grid_text(ds[d].values) for d in ("inv_beta", "delta")
                   if d in ds.dims})
    return pd.Series(values, name="value").astype(str).to_frame()


def map_agreement(motion_map, orbits):
    """Fig. 15 against Fig. 16 per motion (:func:`vibroimpact.plotting.maps.map_agreement`),
    or None when either map is missing."""
    if motion_map is None or orbits is None:
        return None
    from vibroimpact.plotting.maps import map_agreement as agreement

    return agreement(motion_map, orbits)


def map_summary(motion_map):
    """Per motion of a probability map (Fig. 15), with free flights and, when the map has
    them, with sticking: cells with probability >= 50 %, the largest probability; and the
    cells that reached the target error or were hatched."""
    import pandas as pd
    from IPython.display import Markdown

    if motion_map is None:
        return Markdown("*This study has no probability map (Fig. 15).*")
    rows = {}
    for name, label in (("probability", "({m})"), ("stick_probability", "({m}) with sticking")):
        if name not in motion_map:
            continue
        for m in motion_map.motion.values:
            p = motion_map[name].sel(motion=m)
            rows[label.format(m=m)] = {"cells with P >= 50 %": int((p >= 0.5).sum()),
                                       "largest P": f"{float(p.max()):.2f}"}
    table = pd.DataFrame.from_dict(rows, orient="index")
    cells = motion_map.sizes["inv_beta"] * motion_map.sizes["delta"]
    table.attrs["note"] = (f"{cells} cells; {100 * float(motion_map.reached.mean()):.1f} % reached "
                           f"the target standard error, {int(motion_map.few_switches.sum())} "
                           f"hatched (too few switches)")
    return table.style.set_caption(table.attrs["note"])


def _grid_text(values):
    values = np.asarray(values, dtype=float)
    if values.size <= 6:
        return ", ".join(f"{v:.4g}" for v in values)
    return f"{values.min():.4g} ... {values.max():.4g} ({values.size} values)"


def orbit_domains(orbits):
    """Per motion type of an orbits map (Fig. 16): cells where an orbit exists, where one is
    stable, the stable share of the plane, and the degree of stability S over the stable cells."""
    import pandas as pd

    rows = {}
    total = orbits.sizes["inv_beta"] * orbits.sizes["delta"]
    for name in orbits.type.values:
        o = orbits.sel(type=name)
        stable = o.n_stable.values > 0
        S = o.S.values[stable & np.isfinite(o.S.values)]
        rows[f"({name})"] = {
            "cells with an orbit": int((o.n_solutions.values > 0).sum()),
            "cells with a stable orbit": int(stable.sum()),
            "stable share of the plane": f"{100 * stable.sum() / total:.1f} %",
            "S median (%)": f"{np.median(S):.1f}" if S.size else "",
            "S max (%)": f"{S.max():.1f}" if S.size else "",
        }
    return pd.DataFrame.from_dict(rows, orient="index")


def markdown_table(path, header):
    """The first Markdown table of file ``path`` whose header row starts with ``header``
    (e.g. the README's stress-campaign table), as a DataFrame of strings."""
    import pandas as pd

    lines = Path(path).read_text().splitlines()
    start = next((i for i, line in enumerate(lines) if line.strip().startswith(header)), None)
    if start is None:
        raise ValueError(f"{path}: no table whose header starts with {header!r}")
    rows = []
    for line in lines[start:]:
        line = line.strip()
        if not line.startswith("|"):
            break
        cells = [c.strip().replace("**", "") for c in line.strip("|").split("|")]
        if not all(re.fullmatch(r":?-+:?", c) for c in cells):
            rows.append(cells)
    return pd.DataFrame(rows[1:], columns=rows[0])


def work_precision_summary(ds):
    """Per play and method of the work-precision dataset (``results/validation/
    work_precision.nc``): the simulator's error against the round-off level, and each peer's
    most accurate run with its error and cost as multiples of the simulator's."""
    import pandas as pd

    rows = []
    for delta in ds.delta.values:
        d = ds.sel(delta=delta)
        simulator = int(np.flatnonzero(ds.method.values == "simulate")[0])
        rows.append({"delta": f"{delta:g}", "method": "simulate (this package)",
                     "setting": "exact", "error": f"{float(d.error[simulator]):.2g}",
                     "round-off": f"{float(d.roundoff):.2g}", "error / simulator's": "1",
                     "cost (s per time unit)": f"{float(d.cost[simulator]):.2g}",
                     "cost / simulator's": "1"})
        for method in dict.fromkeys(ds.method.values):
            if method == "simulate":
                continue
            runs = np.flatnonzero(ds.method.values == method)
            best = runs[int(np.nanargmin(d.error.values[runs]))]
            rows.append({"delta": f"{delta:g}", "method": str(method),
                         "setting": str(ds.setting.values[best]),
                         "error": f"{float(d.error[best]):.2g}", "round-off": "",
                         "error / simulator's": f"{float(d.error_ratio[best]):.3g}",
                         "cost (s per time unit)": f"{float(d.cost[best]):.2g}",
                         "cost / simulator's": f"{float(d.cost_ratio[best]):.3g}"})
    return pd.DataFrame(rows).set_index(["delta", "method"])


def stress_summary(ds):
    """Per stress family of a sample (``results/validation/stress_sample.nc``): cases, events
    compared, missed, spurious, exceptions, and the worst error as a fraction of its allowance
    (<= 1 passes), with the worst case."""
    import pandas as pd

    worst = ds.worst_error.values / ds.tolerance.values
    table = pd.DataFrame({
        "cases": ds.cases.values, "events compared": ds.compared.values,
        "missed": ds.missed.values, "spurious": ds.spurious.values,
        "exceptions": ds.exceptions.values,
        "worst error / allowance": [f"{w:.2g}" for w in worst],
        "worst case": ds.worst_case.values}, index=ds.family.values)
    table.index.name = "family"
    return table
