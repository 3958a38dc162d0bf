"""Helpers the report notebooks (``workflow/notebooks/*.ipynb``) call, so their cells stay one
line, and the HTML rendering of an executed notebook (:func:`render_html`).

The notebooks are executed by papermill from the workflow (``workflow/rules/reports.smk``),
every input path passed as a parameter; a path given as ``""`` means "this study has no such
dataset", and the cells that need it say so instead of failing.

``python -m vibroimpact.reports.notebook REPORT.ipynb REPORT.html`` renders a report for
reading offline: the maths turned into MathML at build time, no script or stylesheet loaded
from the network (nbconvert's template would load require.js, MathJax and mermaid from a CDN).
"""
from pathlib import Path
import json
import re
import warnings

import numpy as np


def at_project_root():
    """Move to the project directory (the one holding ``workflow/Snakefile``) when run by
    hand from ``workflow/notebooks/``, where the default paths of the parameters cell would
    not resolve."""
    import os

    here = Path.cwd()
    root = here.parents[1] if len(here.parents) > 1 else here
    if not (here / "workflow" / "Snakefile").exists() \
            and (root / "workflow" / "Snakefile").exists():
        os.chdir(root)


def paths(text):
    """The paths in a whitespace-separated parameter (papermill passes strings), or a list."""
    if isinstance(text, (list, tuple)):
        return [str(p) for p in text]
    return str(text or "").split()


def open_dataset(path, lazy=False):
    """``xarray.load_dataset(path)``, or None for an empty path (no such dataset); with
    ``lazy``, opened without reading the data (a noise record read for its attributes)."""
    import xarray as xr

    if not path:
        return None
    return xr.open_dataset(path) if lazy else xr.load_dataset(path)


def first(*datasets):
    """The first of `datasets` that is not None (None when every one is): the dataset a
    report reads a study's settings from, whichever of events, spectra, map or trace the
    study has."""
    return next((ds for ds in datasets if ds is not None), None)


def show_figures(figures):
    """Display each figure file inline (PNG embedded, so the HTML stands alone), under its
    path."""
    from IPython.display import Image, Markdown, display

    shown = paths(figures)
    if not shown:
        display(Markdown("*This study lists no figure.*"))
    for path in shown:
        display(Markdown(f"`{path}`"), Image(filename=path))


def show_table(found, omit_unavailable=False):
    """The findings as a table: number, the paper's claim, this run's numbers, verdict; a
    verdict's one-sentence summary (what holds, what does not) opens its numbers, in bold.

    With ``omit_unavailable``, the findings this study cannot measure (``n/a``) are left out
    of the table and named in one line under it, with why. Returns the table of every
    finding given (:func:`vibroimpact.reports.findings.findings_table`).
    """
    from html import escape

    from IPython.display import Markdown, display

    from vibroimpact.reports.findings import findings_table

    table = findings_table(found)
    shown = [f for f in found if not (omit_unavailable and f.holds == "n/a")]
    if shown:
        view = findings_table(shown)
        view["claim"] = [escape(c) for c in view["claim"]]
        view["measured"] = [(f"<b>{escape(f.summary)}</b><br>" if f.summary else "")
                            + escape(f.measured) for f in shown]
        display(view.style.set_properties(**{"text-align": "left", "white-space": "normal"}))
    left = [f for f in found if f not in shown]
    if left:
        reasons = {}
        for f in left:
            reasons.setdefault(f.measured, []).append(str(f.number))
        display(Markdown("*Not measured in this report:* " + "; ".join(
            f"finding{'s' if len(n) > 1 else ''} {', '.join(n)} ({why})"
            for why, n in reasons.items()) + "."))
    return table


#: The provenance attributes every dataset carries (``vibroimpact.pipeline.provenance``).
_PROVENANCE = ("package_version", "git_commit", "git_dirty", "config_digest", "created", "seed",
               "record_length", "t_end", "transient")


def provenance(**datasets):
    """Where each dataset came from (package version, commit, config digest, creation time,
    seed, record length): one row per attribute, one column per dataset, the long hashes
    wrapped in their cells, so that the table fits the page whatever the number of datasets."""
    import pandas as pd

    columns = {name: {k: _text(ds.attrs.get(k, "")) for k in _PROVENANCE}
               for name, ds in datasets.items() if ds is not None}
    table = pd.DataFrame(columns, index=list(_PROVENANCE))
    wrapped = [{"selector": "td", "props": "text-align: left; white-space: normal; "
                                           "word-break: break-all"},
               {"selector": "th.blank", "props": "width: 10em"}]     # the attributes' column
    # class names of its own: a report's findings table is read by its "data" cells
    names = {"data": "provenance", "row_heading": "provenance_attribute",
             "col_heading": "provenance_dataset"}
    return (table.style.set_table_styles(wrapped, css_class_names=names)
            .set_table_attributes('style="width: 100%; table-layout: fixed"'))


def _text(value):
    """An attribute as table text: floats in up to 10 significant digits (``1000000``, not
    ``1000000.0`` or ``1e+06``)."""
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.10g}"
    return str(value)


#: The rows of a settings table, in order: the system, the forcing, the record and the
#: statistics. Keys that only apply to a harmonic force are shown only with one.
_SYSTEM = ("zeta", "eps", "amplitude")
_NOISE = (("noise", "noise"), ("noise_kind", "kind"), ("noise_rms", "rms"),
          ("noise_beta_c", "beta_c"), ("noise_zeta_f", "zeta_f"), ("noise_dt", "dt"),
          ("seed", "seed"))
_RECORD = ("transient", "t_end", "record_length", "n_batches", "motion_window", "rebound_floor",
           "nperseg", "target_stderr", "max_periods")
_HARMONIC_ONLY = ("motion_window", "inv_beta", "beta_f")
#: The single play and forcing frequency of a trace (``results/traces/<study>.nc``).
_TRACE = (("delta", "trace delta"), ("beta_f", "trace beta_f"))


def study_settings(ds, name=""):
    """The physical and statistical settings of a dataset (a study's, a trace's or an orbits
    map's), from its attributes and grids, as a small table: the system, the random force (its
    record's name, kind, rms, cut-off, sample step and seed) and the record and statistics.
    A study without a harmonic force (``amplitude`` 0) shows no 1/beta_f grid, forcing
    frequency or motion window, which apply only to one. ``None`` (a study with no dataset
    to read them from) gives a note saying so."""
    import pandas as pd
    from IPython.display import Markdown

    if ds is None:
        return Markdown("*This study has no dataset to read its settings from.*")
    skipped = () if float(ds.attrs.get("amplitude", 1.0)) != 0.0 else _HARMONIC_ONLY
    values = {"entry": name} if name else {}
    values.update({k: ds.attrs[k] for k in _SYSTEM if k in ds.attrs})
    if "axes" in ds.attrs:      # a map over any two parameters: its plane and what is fixed
        axes = _plane(ds)
        values.update({"plane": " x ".join(axes)})
        values.update({f"{d} grid": _grid_text(ds[d].values) for d in axes})
        fixed = json.loads(ds.attrs["fixed"])
        values.update({"fixed": ", ".join(fixed)})
        values.update({k: v for k, v in fixed.items() if k not in values})
        skipped = tuple(skipped) + axes + ("noise_rms",) * ("rms" in axes)
    else:
        values.update({f"{d} grid": _grid_text(ds[d].values) for d in ("inv_beta", "delta")
                       if d in ds.dims and d not in skipped})
    values.update({label: ds.attrs[k] for k, label in _TRACE
                   if k in ds.attrs and k not in ds.dims and k not in skipped})
    values.update({"noise" if label == "noise" else f"noise {label}": ds.attrs[k]
                   for k, label in _NOISE if k in ds.attrs and k not in skipped})
    values.update({k: ds.attrs[k] for k in _RECORD if k in ds.attrs and k not in skipped})
    values.update({k: ds.attrs[k] for k in sorted(ds.attrs) if k.startswith("sweep")})
    return pd.Series({k: _text(v) for k, v in values.items()}, name="value").to_frame()


def map_agreement(motion_map, orbits):
    """Fig. 15 against Fig. 16 per motion (:func:`vibroimpact.plotting.maps.map_agreement`),
    or None when either map is missing. ``orbits``: the orbits at the map's own cells
    (``results/datasets/{study}_map_orbits.nc``, `vibroimpact.orbits.cells.orbits_at_cells`),
    so that no cell is read at a neighbour (another grid is refused); with their
    ``complex`` flags, each motion's dict also gives ``complex_share``, the share of its
    stable cells whose multipliers are a complex pair, where S does not depend on delta (NaN
    when not known, or when delta is not an axis of the map)."""
    if motion_map is None or orbits is None:
        return None
    from vibroimpact.plotting.maps import map_agreement as agreement
    from vibroimpact.reports.predictors import on_map_grid

    orbits = on_map_grid(orbits, motion_map, "orbits")
    out = agreement(motion_map, orbits)
    along_delta = "delta" in _plane(motion_map)
    for name, a in out.items():
        a["complex_share"] = np.nan
        if "complex" in orbits and along_delta:
            o = orbits.sel(type=name)
            flags = o["complex"].values[o["n_stable"].values > 0]
            if flags.size and (flags >= 0).all():
                a["complex_share"] = float((flags == 1).mean())
    return out


def _plane(motion_map):
    """The map's two grid dims (`vibroimpact.reports.switching`: its ``axes``)."""
    from vibroimpact.reports.switching import _plane as plane

    return plane(motion_map)


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
    x, y = _plane(motion_map)
    cells = motion_map.sizes[x] * motion_map.sizes[y]
    table.attrs["note"] = (f"{cells} cells; {100 * float(motion_map.reached.mean()):.1f} % "
                           f"reached the target standard error, "
                           f"{int(motion_map.few_switches.sum())} hatched (too few switches)")
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
    total = int(np.prod([orbits.sizes[d] for d in orbits.dims if d != "type"]))
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


def boundary_summary(boundaries):
    """Per motion type: the exact edge curves of its stable domain by kind (curves, points),
    and the codimension-two points where two kinds meet, one column per pair of kinds (a
    single joined column was cut by the table's width)."""
    import pandas as pd

    rows = {}
    kinds = ("grazing", "fold", "period_doubling", "existence")
    curve_kind = boundaries["kind"].values.astype(str)
    curve_type = boundaries["type"].values.astype(str)
    points = np.bincount(boundaries["curve"].values, minlength=curve_kind.size)
    c2_type = boundaries["codim2_type"].values.astype(str)
    c2_kinds = boundaries["codim2_kinds"].values.astype(str)
    pairs = sorted(set(c2_kinds.tolist()))
    for name in dict.fromkeys(curve_type.tolist() + c2_type.tolist()):
        row = {}
        for kind in kinds:
            sel = (curve_type == name) & (curve_kind == kind)
            row[kind] = (f"{int(sel.sum())} ({int(points[sel].sum())} points)"
                         if sel.any() else "")
        here = c2_kinds[c2_type == name]
        for pair in pairs:
            n = int((here == pair).sum())
            row[f"codim-2: {pair.replace('+', ' + ')}"] = str(n) if n else ""
        rows[f"({name})"] = row
    return pd.DataFrame.from_dict(rows, orient="index")


def basin_summary(basins):
    """Per motion type: where a stable orbit exists, how large its basin is (median and
    extremes of the fraction of starts), in how many cells it takes every start, and in how
    many it shares the plane with another stable type (multistable cells)."""
    import pandas as pd

    rows = {}
    n_types = basins.sizes["motion"] - 1
    types = basins["motion"].values[:n_types]
    has = basins["n_stable"].values[:n_types] > 0
    multistable = has.sum(axis=0) > 1
    for k, name in enumerate(types):
        f = basins["fraction"].values[k][has[k]]
        lo = basins["fraction_lo"].values[k][has[k]]
        hi = basins["fraction_hi"].values[k][has[k]]
        rows[f"({name})"] = {
            "cells with a stable orbit": int(has[k].sum()),
            "basin median (%)": f"{100 * np.median(f):.1f}" if f.size else "",
            "basin min - max (%)": f"{100 * f.min():.0f} - {100 * f.max():.0f}" if f.size
            else "",
            "cells where every start settles on it": int((f == 1.0).sum()),
            "of them multistable": int(multistable[has[k]].sum()),
            "median 95 % interval width (points)": f"{100 * np.median(hi - lo):.1f}"
            if f.size else "",
        }
    other = basins["fraction"].values[n_types]
    blank = dict.fromkeys(next(iter(rows.values())), "")
    rows["other (every cell)"] = blank | {
        "basin median (%)": f"{100 * np.median(other):.1f}",
        "basin min - max (%)": f"{100 * other.min():.0f} - {100 * other.max():.0f}"}
    if "class_fraction" in basins and "wall_free" in basins["class"].values:
        # the linear steady response that never reaches the wall: a motion of its own
        free = basins["class_fraction"].sel({"class": "wall_free"}).values
        rows["of other: wall-free response (every cell)"] = blank | {
            "basin median (%)": f"{100 * np.median(free):.1f}",
            "basin min - max (%)": f"{100 * free.min():.0f} - {100 * free.max():.0f}",
            "cells where every start settles on it": int((free == 1.0).sum())}
    return pd.DataFrame.from_dict(rows, orient="index")


def _exponent_range(values):
    """``"a .. b"`` of the finite values, with the cells at -inf counted (never dropped)."""
    finite = values[np.isfinite(values)]
    n_inf = int(np.isneginf(values).sum())
    parts = [f"{finite.min():.3g} .. {finite.max():.3g}"] if finite.size else []
    if n_inf:
        parts.append(f"-inf in {n_inf} cells" if finite.size else
                     f"-inf (all {n_inf} cells)")
    return "; ".join(parts)


def lyapunov_summary(lyapunov, basins):
    """How the plane divides by what its starts settle on (the cell's most frequent class),
    over all cells and over the cells where the solver finds no stable listed motion (the
    paper's D, V, X, U), with the range of the exponent of the class's own starts (per cell
    the largest over the starts of the cell's class; -inf cells counted), the share of the
    cell's starts in its class, and the cells whose largest exponent over all starts belongs
    to a start of another class (a coexisting motion of fewer starts: the colour of the
    Lyapunov figure there) with that exponent's range."""
    import pandas as pd

    n_types = basins.sizes["motion"] - 1
    none_stable = (basins["n_stable"].values[:n_types] > 0).sum(axis=0) == 0
    cls = lyapunov["cell_class"].values
    lam = lyapunov["lyapunov"].values
    names = lyapunov["cell_class"].attrs["flag_meanings"].split()
    per_start = "class_start" in lyapunov and "lyapunov_start" in lyapunov
    if per_start:
        starts = lyapunov["class_start"].values
        own = np.where(starts == cls[None], lyapunov["lyapunov_start"].values, np.nan)
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)       # cells without own start
            own = np.nanmax(own, axis=0)
    share = (lyapunov["class_fraction"].sel({"class": names}).values
             if "class_fraction" in lyapunov else None)
    owner = lyapunov["lyapunov_class"].values if "lyapunov_class" in lyapunov else None
    rows = {}
    for code, name in enumerate(names):
        sel = cls == code
        row = {"cells": int(sel.sum()),
               "of them with no stable listed orbit": int((sel & none_stable).sum())}
        if per_start:
            row["exponent of its own starts, range"] = _exponent_range(own[sel])
        else:
            row["largest exponent, range"] = _exponent_range(lam[sel])
        if share is not None:
            s = share[code][sel]
            row["starts in the class, min - median (%)"] = (
                f"{100 * s.min():.0f} - {100 * np.median(s):.0f}" if s.size else "")
        if owner is not None:
            other = sel & (owner != code) & np.isfinite(lam)
            by = sorted(((int((owner[other] == k).sum()), names[k].replace("_", " "))
                         for k in set(owner[other].tolist())), reverse=True)
            row["cells where another class holds the largest exponent"] = (
                f"{int(other.sum())}: " + ", ".join(f"{name} {n}" for n, name in by)
                if other.any() else "0")
            row["that exponent, range"] = _exponent_range(lam[other])
        rows[name.replace("_", " ")] = row
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


def csv_table(path):
    """A CSV table (e.g. ``workflow/notebooks/stress_campaign.csv``, the full stress campaign) as a
    DataFrame of strings, empty cells as ``""``."""
    import pandas as pd

    return pd.read_csv(path, dtype=str, keep_default_na=False)


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


# --- HTML rendering for reading offline ---------------------------------------------------

#: Long lines wrap inside the page: code (a papermill parameter holding a list of paths),
#: text outputs and table cells; figures shrink to the page's width.
_WRAP_CSS = """<style type="text/css">
.jp-InputArea-editor pre, .jp-OutputArea-output pre, .highlight pre {
  white-space: pre-wrap; overflow-wrap: anywhere; }
.jp-RenderedHTMLCommon td, .jp-RenderedHTMLCommon th { overflow-wrap: anywhere; }
.jp-RenderedHTMLCommon code { overflow-wrap: anywhere; }
.jp-OutputArea-output img { max-width: 100%; height: auto; }
.celltag_heading .jp-OutputPrompt { display: none; }
</style>"""

#: nbconvert's JupyterLab template without what it loads from the network: require.js (no
#: output here needs it), MathJax (the maths is MathML, rendered at build time), mermaid and
#: the widget manager; plus :data:`_WRAP_CSS`. Its stylesheets are inlined by nbconvert.
_OFFLINE_TEMPLATE = """{%- extends 'lab/index.html.j2' -%}
{%- block html_head_js -%}{%- endblock html_head_js -%}
{%- block jupyter_widgets -%}{%- endblock jupyter_widgets -%}
{%- block html_head_js_mathjax -%}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
{% block extra_css %}""" + _WRAP_CSS + """{% endblock extra_css %}
"""


def _tagged(cell, tag):
    return tag in cell.get("metadata", {}).get("tags", ())


def _title(cells):
    """The report's first ``# `` heading, from a heading cell's output or a markdown cell,
    without its markup (the page's title); None when it has none."""
    for cell in cells:
        texts = ([o.get("data", {}).get("text/markdown", "") for o in cell.get("outputs", [])]
                 if cell.cell_type == "code" else [cell.source])
        for text in texts:
            for line in text.splitlines():
                if line.startswith("# "):
                    return line[2:].replace("`", "").strip()
    return None

#: Code spans and fences (left alone), then display maths $$...$$, then inline maths $...$.
_MATH = re.compile(r"(?P<code>(`+).*?\2)|\$\$(?P<display>.+?)\$\$|\$(?P<inline>[^$\n]+?)\$",
                   re.S)


def mathml(markdown):
    """Markdown with its TeX maths (``$...$`` inline, ``$$...$$`` displayed) replaced by
    MathML, which browsers render without a script; code spans are left as they are."""
    from latex2mathml.converter import convert

    def replace(match):
        if match["code"] is not None:
            return match["code"]
        if match["display"] is not None:
            return convert(match["display"].strip(), display="block")
        return convert(match["inline"].strip())

    return _MATH.sub(replace, markdown)


def render_html(ipynb, html, figures=True):
    """Render the executed notebook ``ipynb`` to the HTML file ``html``, readable offline:
    figures embedded (they are in the notebook), the maths of markdown cells and outputs as
    MathML, and no script or stylesheet from the network (:data:`_OFFLINE_TEMPLATE`).

    Without ``figures``, the images are left out (each figure's path stays): the copy shown
    in Snakemake's report, which holds every figure once, beside it.

    The parameters are shown once: a notebook executed by papermill holds its ``parameters``
    cell (the defaults for a run by hand) and the ``injected-parameters`` cell with the values
    of this run; only the latter is rendered. Cells tagged ``heading`` (a title computed from
    the parameters) come first, their output without their code. Long lines wrap
    (:data:`_WRAP_CSS`).
    """
    import nbformat
    from jinja2 import DictLoader
    from nbconvert import HTMLExporter

    nb = nbformat.read(ipynb, as_version=4)
    if any(_tagged(cell, "injected-parameters") for cell in nb.cells):
        nb.cells = [cell for cell in nb.cells if not _tagged(cell, "parameters")]
    headings = [cell for cell in nb.cells if _tagged(cell, "heading")]
    nb.cells = headings + [cell for cell in nb.cells if not _tagged(cell, "heading")]
    title = _title(nb.cells)
    if title:
        nb.metadata["title"] = title
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            cell.source = mathml(cell.source)
        if cell.cell_type != "code":
            continue
        if not figures:
            cell.outputs = [o for o in cell.get("outputs", [])
                            if "image/png" not in o.get("data", {})]
        for output in cell.get("outputs", []):
            if "text/markdown" in output.get("data", {}):
                output.data["text/markdown"] = mathml(output.data["text/markdown"])
    exporter = HTMLExporter(template_name="lab", template_file="offline.html.j2",
                            extra_loaders=[DictLoader({"offline.html.j2": _OFFLINE_TEMPLATE})])
    if headings:
        from nbconvert.preprocessors import TagRemovePreprocessor

        exporter.register_preprocessor(TagRemovePreprocessor(remove_input_tags=("heading",)),
                                       enabled=True)
    body, _ = exporter.from_notebook_node(nb)
    Path(html).write_text(body, encoding="utf-8")


def parameter_value(text):
    """A ``-p NAME VALUE`` value as papermill's command line reads it: ``True``, ``False``,
    ``None``, an int, a float, else the string itself."""
    if text in ("True", "False", "None"):
        return {"True": True, "False": False, "None": None}[text]
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def execute(notebook, ipynb, parameters):
    """Execute the report ``notebook`` with ``parameters`` (``{name: value}``) into ``ipynb``
    with papermill's Python API, in this process (the kernel is papermill's, a child
    process), as ``papermill NOTEBOOK IPYNB --kernel python3 --log-output`` would: the cells'
    output logged, the executed notebook written once at the end (not after every cell)."""
    import logging

    import papermill

    logging.basicConfig(level=logging.INFO, format="%(message)s")
    papermill.execute_notebook(str(notebook), str(ipynb), parameters=parameters,
                               kernel_name="python3", progress_bar=False, log_output=True,
                               request_save_on_cell_execute=False)


def main(argv=None):
    """``python -m vibroimpact.reports.notebook [--execute NOTEBOOK [-p NAME VALUE]...]
    [--no-figures] [--summary SUMMARY.html] REPORT.ipynb REPORT.html``.

    ``--execute`` first executes ``NOTEBOOK`` with the ``-p`` parameters into
    ``REPORT.ipynb`` (:func:`execute`); ``--summary`` also writes the rendering without images
    (Snakemake's report's copy). The report rules run all three in this one process: papermill,
    nbformat and nbconvert start once a report.
    """
    import argparse

    parser = argparse.ArgumentParser(prog="python -m vibroimpact.reports.notebook",
                                     description="Render an executed report notebook to HTML "
                                                 "that reads offline.")
    parser.add_argument("ipynb")
    parser.add_argument("html")
    parser.add_argument("--execute", metavar="NOTEBOOK",
                        help="first execute this notebook (papermill) into REPORT.ipynb")
    parser.add_argument("-p", "--parameter", nargs=2, action="append", default=[],
                        metavar=("NAME", "VALUE"),
                        help="a parameter of --execute, typed as papermill's -p types it")
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="leave the images out (Snakemake's report shows them once)")
    parser.add_argument("--summary", metavar="SUMMARY.html",
                        help="also write the rendering without images to this file")
    args = parser.parse_args(argv)
    if args.parameter and not args.execute:
        parser.error("-p/--parameter is a parameter of --execute NOTEBOOK")
    if args.execute:
        execute(args.execute, args.ipynb,
                {name: parameter_value(value) for name, value in args.parameter})
    render_html(args.ipynb, args.html, figures=args.figures)
    if args.summary:
        render_html(args.ipynb, args.summary, figures=False)


if __name__ == "__main__":
    main()


#: A residual of the self-audit fails beyond this many of its batch-means standard errors.
#: The residual of an exact record is a boundary term, typically 1/sqrt(B) of its standard
#: error (docs/model.md, section 7.1), so 3 is far out for every cell of a sweep.
AUDIT_SIGMAS = 3.0
#: ... and beyond this fraction of its scale (<f v>, <v^2>): the numerical floor of an exact
#: record. The chatter tails the simulator sums in closed form enter the identities to
#: O(w^2), w < 5e-5 their last resolved rebound (docs/model.md, section 7.1); where the mass
#: rests on the wall nearly all the time the batch errors fall below that floor (default
#: random study, delta = -1, 93 % of the time on the wall: virial residual 6.3e-12 = 4.6e-9 of
#: its scale, standard error 5.1e-13). A residual that fails both is a wrong record.
AUDIT_FLOOR = 1e-7
#: Sweeps with more cells than this are summarised: the largest ratios, then the worst cells.
AUDIT_ROWS = 12
#: How many of the worst cells the summary (and a failed verdict) lists.
AUDIT_WORST = 5
#: The identities of the self-audit: (name, residual variable, its scale, how the scale reads).
_IDENTITIES = (("power", "power_residual", "power_input", "<f v>"),
               ("virial", "virial_residual", "virial_scale", "<v^2>"))


def identity_audit(events):
    """The events dataset's self-audit: the power-balance and virial residuals of every cell
    (docs/model.md, section 7.1) against their batch-means standard errors.

    Returns a verdict (Markdown: whether every ``|residual| <= AUDIT_SIGMAS`` standard
    errors, or which cells fail) and a table: per cell (``delta``, with ``1/beta_f`` when
    the dataset has several), for each identity the residual, its standard error, their
    ratio and the residual relative to its scale (``<f v>``, ``<v^2>``). Beyond `AUDIT_ROWS`
    cells, the `AUDIT_WORST` cells with the largest ratio. A dataset without residuals (older
    than the audit, or not an events dataset) gives a note.
    """
    import pandas as pd
    from IPython.display import Markdown, display

    if events is None or "power_residual" not in events:
        return Markdown("*This study's events dataset carries no identity residuals.*")
    table = {}
    for name, var, scale, _ in _IDENTITIES:
        residual = events[var].to_series()
        stderr = events[f"{var}_stderr"].to_series()
        table[(name, "residual")] = residual
        table[(name, "s.e.")] = stderr
        with np.errstate(divide="ignore", invalid="ignore"):
            table[(name, "residual / s.e.")] = residual / stderr
            table[(name, "residual / scale")] = residual / events[scale].to_series().abs()
    frame = pd.DataFrame(table)
    if frame.index.get_level_values("inv_beta").nunique() == 1:
        frame.index = frame.index.droplevel("inv_beta")
    ratios = frame.xs("residual / s.e.", axis=1, level=1).abs()
    worst = ratios.max(axis=1)
    display(Markdown(_audit_verdict(ratios, frame.xs("residual / scale", axis=1,
                                                     level=1).abs())))
    shown = frame
    if len(frame) > AUDIT_ROWS:
        shown = frame.loc[worst.sort_values(ascending=False).index[:AUDIT_WORST]]
        display(Markdown(f"The {AUDIT_WORST} of {len(frame)} cells with the largest "
                         "|residual| / s.e.:"))
    formats = {c: "{:.2f}" if c[1] == "residual / s.e." else "{:.2e}" for c in frame.columns}
    # class names of its own: a report's findings table is read by its "data" cells
    names = {"data": "audit", "row_heading": "audit_cell", "col_heading": "audit_column"}
    return (shown.style.format(formats).format_index("{:.4g}", axis=0)
            .set_table_styles([], css_class_names=names))


def _audit_verdict(ratios, relative):
    """One line: every residual within `AUDIT_SIGMAS` standard errors or `AUDIT_FLOOR` of its
    scale, or the failures (beyond both)."""
    values = ratios.to_numpy()
    if not np.isfinite(values).all():
        bad = ratios.columns[~np.isfinite(values).all(axis=0)].tolist()
        return (f"**Self-audit: cannot decide** ({', '.join(bad)}: a standard error of 0 or "
                "NaN; too few batches?).")
    entries = [(float(r), name, _cell_text(ratios.index, cell), float(relative.loc[cell, name]))
               for cell, row in ratios.iterrows() for name, r in row.items()]
    fails = [e[:3] for e in entries if e[0] > AUDIT_SIGMAS and e[3] > AUDIT_FLOOR]
    floor = [e for e in entries if e[0] > AUDIT_SIGMAS and e[3] <= AUDIT_FLOOR]
    if not fails:
        r, name, where, _ = max([e for e in entries if e not in floor] or entries)
        below = ("" if not floor else
                 f" {len(floor)} more beyond {AUDIT_SIGMAS:g} s.e. but within {AUDIT_FLOOR:g} "
                 "of their scale, the numerical floor of an exact record ("
                 + "; ".join(f"{n} at {w}: {q:.1f} s.e., {x:.1e} of its scale"
                             for q, n, w, x in floor[:AUDIT_WORST]) + ").")
        return (f"**Self-audit passed:** all {len(entries)} residuals (power balance and "
                f"virial, {len(ratios)} cells) within {AUDIT_SIGMAS:g} standard errors or "
                f"{AUDIT_FLOOR:g} of their scale; the largest within its errors, {r:.2f} s.e., "
                f"is the {name} at {where}.{below}")
    fails.sort(key=lambda e: -e[0])
    listed = "; ".join(f"{name} at {where} ({r:.1f} s.e.)"
                       for r, name, where in fails[:AUDIT_WORST])
    if len(fails) > AUDIT_WORST:
        listed += f"; and {len(fails) - AUDIT_WORST} more"
    return (f"**Self-audit FAILED:** {len(fails)} of {len(entries)} residuals beyond "
            f"{AUDIT_SIGMAS:g} standard errors and {AUDIT_FLOOR:g} of their scale: {listed}. "
            "The impact record disagrees with the motion there (docs/model.md, section 7.1).")


def _cell_text(index, cell):
    """``delta = 0.5`` (or ``1/beta_f = 1.1, delta = 0.5``) for a cell of the audit table."""
    cell = cell if isinstance(cell, tuple) else (cell,)
    names = ["1/beta_f" if n == "inv_beta" else n for n in index.names]
    return ", ".join(f"{n} = {float(v):.4g}" for n, v in zip(names, cell))


# --- what predicts P, and is the switching Markov (the harmonic report) ----------------------

def _styled(table, names, caption=None):
    """A table left-aligned and wrapped, with CSS classes of its own (``names``: the findings
    table's cells are read by their default classes)."""
    wrapped = [{"selector": "td", "props": "text-align: left; white-space: normal"}]
    styler = table.style.set_table_styles(wrapped, css_class_names=names)
    return styler.set_caption(caption) if caption else styler


def predictors(path):
    """The rank correlations of each candidate predictor with each motion's P, read from
    the map's predictors dataset (``results/datasets/{study}_predictors.nc``, rule
    ``map_predictors``: :func:`vibroimpact.reports.predictors.predictor_correlations`
    computed once for every report that shows the map), or None for an empty path (no
    map)."""
    if not path:
        return None
    from vibroimpact.reports.predictors import read_correlations

    return read_correlations(open_dataset(path))


def show_predictors(correlations):
    """The predictors table (a row per predictor and motion: Spearman's rho with P and its
    95 % bootstrap interval, in the stable domain and over the plane, and the cells)."""
    from IPython.display import Markdown

    if correlations is None:
        return Markdown("*This study has no probability map (Fig. 15).*")
    from vibroimpact.reports.predictors import predictors_table

    names = {"data": "predictor_value", "row_heading": "predictor_name",
             "col_heading": "predictor_column"}
    return _styled(predictors_table(correlations), names)


def markov_summary(motion_map):
    """Per state of the map: are its residence times those of a Markov chain
    (:func:`vibroimpact.reports.switching.markov_summary`), with the bookkeeping check of the
    switching rates as the caption."""
    from IPython.display import Markdown

    if motion_map is None or "residence_time" not in motion_map:
        return Markdown("*This study has no map with residence times.*")
    from vibroimpact.reports.switching import markov_summary as summary

    table = summary(motion_map)
    names = {"data": "markov_value", "row_heading": "markov_state",
             "col_heading": "markov_column"}
    return _styled(table, names, table.attrs["note"])


# --- what a harmonic report holds: a study with impact records, or a map study ------------

_FIGURE_NUMBER = re.compile(r"fig(\d+)")


def _figure_numbers(figures):
    """The paper's figure numbers among the paths ``figures`` (``fig15_vs_fig16`` gives 15
    and 16), sorted."""
    return sorted({int(n) for path in paths(figures) for n in _FIGURE_NUMBER.findall(
        Path(path).stem)})


def _figure_range(numbers):
    """``"Fig. 15"``, ``"Figs. 10-15"`` or ``"Figs. 10, 12"``; "" for none."""
    if not numbers:
        return ""
    if len(numbers) == 1:
        return f"Fig. {numbers[0]}"
    if numbers == list(range(numbers[0], numbers[-1] + 1)):
        return f"Figs. {numbers[0]}-{numbers[-1]}"
    return "Figs. " + ", ".join(map(str, numbers))


def is_map_study(events="", spectra="", map=""):
    """Whether a harmonic report is a map study's: a probability map (Fig. 15) and neither
    impact statistics nor spectra (the parameters are the notebook's paths, "" = none)."""
    return bool(map) and not events and not spectra


#: The paper's symbols of the parameters a map's plane may have (the report's words).
_SYMBOLS = {"inv_beta": "1/\\beta_f", "delta": "\\delta", "zeta": "\\zeta", "eps": "\\epsilon",
            "eps_lower": "\\epsilon_l", "gap": "g", "amplitude": "A", "rms": "\\sigma_r"}


def _plane_words(map_path):
    """``$(1/\\beta_f, \\delta)$``, or the plane the map at ``map_path`` names in its
    ``axes`` attribute (a map over any two parameters)."""
    axes = None
    if map_path:
        try:
            import xarray as xr

            with xr.open_dataset(map_path) as ds:
                axes = ds.attrs.get("axes")
        except (OSError, ValueError):
            axes = None
    if axes is None:
        return "$(1/\\beta_f, \\delta)$"
    axes = [axes] if isinstance(axes, str) else list(axes)
    return "$(" + ", ".join(_SYMBOLS.get(str(a), str(a)) for a in axes) + ")$"


def harmonic_heading(study, events="", spectra="", map="", figures=""):
    """The title and opening of a harmonic-plus-random report, from what the study has.

    A study with impact records (``events``) or spectra: section 5's figures it shows and
    findings 5-8. A map study (only ``map``): what such a study measures and reports, and
    that findings 5-7 are not among them. The figure numbers come from ``figures``.
    """
    from IPython.display import Markdown

    shown = _figure_range([n for n in _figure_numbers(figures) if n < 16])
    if is_map_study(events, spectra, map):
        against = " against Fig. 16" if 16 in _figure_numbers(figures) else ""
        return Markdown(
            f"# Harmonic plus random force: the probability map of study `{study}` "
            f"(paper section 5, {shown or 'Fig. 15'}{against})\n\n"
            f"A map study runs one record per cell of the {_plane_words(map)} plane under "
            "$A \\sin(\\beta_f \\tau) + r(\\tau)$ and keeps, per cell, the fraction of time "
            "the mass spends in each periodic $(m/n)$ motion (its probability $P$, extended "
            "until its standard error reaches the target), how often it switches between "
            "them and how long it stays. It keeps no impact record and no spectrum. This "
            "report shows the map (Fig. 15) and the map drawn over the stable domains of the "
            "noise-free orbits (Fig. 16), whether the switching is Markov, what predicts $P$, "
            "and the paper's finding 8, the one a map decides. Findings 5-7 (spectra, "
            "densities of the impacts) are measured in the report of a study with impact "
            "records, e.g. one that lists this study under `report_with`.")
    return Markdown(
        f"# Harmonic plus random force: study `{study}` (paper section 5"
        + (f", {shown}" if shown else "") + ")\n\n"
        "The same system driven by $A \\sin(\\beta_f \\tau) + r(\\tau)$ ($A$: `amplitude`, "
        "$1/\\beta_f$: `inv_beta`). This report shows the study's figures (and those of the "
        "studies it lists under `report_with`, e.g. the Fig. 15 map of the same system) and "
        "measures the paper's findings 5-8 on their datasets. Executed by the workflow "
        "(`snakemake results/reports/<study>/harmonic_random.html`); the notebook's defaults "
        "are the paper's study `harmonic` with its map `motion_map`, so after `make` it also "
        "runs by hand.")


def map_audit(motion_map):
    """The self-audit of a map study, which keeps no impact record (so no identity residual):
    per cell, the motions' probabilities are fractions of one record's time (each in [0, 1],
    their sum at most 1, the rest no listed motion), and a cell flagged as having reached the
    target standard error (attribute ``target_stderr``) has every probability's standard
    error within it. A verdict (Markdown) naming the cells that fail."""
    from IPython.display import Markdown

    if motion_map is None:
        return Markdown("*This study has neither impact records nor a probability map: "
                        "nothing to audit.*")
    p = motion_map.probability
    total = p.sum("motion")
    outside = ((p < 0) | (p > 1)).any("motion") | (total > 1 + 1e-12)
    target = float(motion_map.attrs.get("target_stderr", np.nan))
    reached = motion_map.reached == 1
    worst = float(motion_map.probability_stderr.where(reached).max()) if bool(
        reached.any()) else np.nan
    flagged = reached & (motion_map.probability_stderr > target).any("motion")
    x, y = _plane(motion_map)
    cells = motion_map.sizes[x] * motion_map.sizes[y]
    failed = int(outside.sum()) + int(flagged.sum())
    verdict = "**Self-audit passed:**" if failed == 0 else "**Self-audit FAILED:**"
    text = (f"{verdict} a map study keeps no impact record, so the two exact identities of "
            f"the events of a study are not its check (they are in the report of a study "
            f"with impact statistics). In {cells - int(outside.sum())} of its {cells} cells "
            f"every probability lies in [0, 1] and they sum to at most 1 (largest sum "
            f"{float(total.max()):.4f}); "
            f"{int(reached.sum())} cells flagged as having reached the target standard "
            f"error {target:g}, the largest standard error among them {worst:.4g}"
            + (f", {int(flagged.sum())} above the target" if int(flagged.sum()) else "")
            + ".")
    if failed:
        bad = (outside | flagged).transpose(x, y).stack(cell=(x, y))
        where = [f"({x.replace('inv_beta', '1/beta_f')} = {ib:.4g}, {y} = {d:.4g})"
                 for ib, d in bad.cell.values[bad.values][:AUDIT_WORST]]
        text += " Failing cells: " + ", ".join(where) + "."
    return Markdown(text)


# --- finding 5 read twice, and a two-wall study's own checks (the harmonic report) ----------

def finding5_readings(spectra):
    """Finding 5's numbers (one-wall harmonic studies with spectra): per 1/beta_f and play,
    the response's centroid with its lines at k beta_f and of the broadband response (lines
    taken out) with the broadband peak, their 95 % intervals from the batch spectra and the
    lines' powers; then the broadband centroid's change under each choice of the measure.
    Nothing for a two-wall study or without spectra (the findings table says why)."""
    from IPython.display import Markdown, display

    from vibroimpact.reports import findings
    from vibroimpact.stats.centroid import LINE_BINS

    if spectra is None or int(spectra.attrs.get("n_walls", 1)) == 2:
        return
    display(Markdown(
        "### Finding 5 read twice: with the lines and broadband\n\n"
        "The response's PSD holds lines at $k\\beta_f$ (the periodic part of the motion, "
        "whose power follows $\\delta$) over the broadband response to $r(\\tau)$, the part "
        "the paper's Fig. 12 shows moving. *With the lines*: the centroid of the whole "
        "response. *Broadband*: the lines taken out over "
        f"$\\pm${LINE_BINS} bins of the Welch grid (the Hann window's main lobe is $\\pm$2 "
        "bins; a line half a bin off leaves 6.1e-6 of its power beyond $\\pm$5), their bins "
        "bridged by a straight line between the neighbouring clean bins, each line's power "
        "what it adds over that bridge (`line k beta_f`). The 95 % intervals come from the "
        "spectra of the record's consecutive batches (`S_a_batch`): delete-one jackknife "
        "for the centroid, the batches' own smoothed peaks for the peak."))
    numbers = findings.finding5_readings(spectra)
    display(_styled(numbers, {"data": "f5_value", "row_heading": "f5_row",
                              "col_heading": "f5_column"}).format(precision=3, na_rep="")
            .hide(axis="index"))
    display(Markdown(
        "The broadband centroid at the smallest play less that at the largest, under each "
        "choice of the lines' half-width, of the band's upper end and of what stands in the "
        "lines' bins (bridged, or dropped: which drops the broadband under them too, and "
        "lowers the centroid where the lines sit near the resonance): finding 5 calls the "
        "move only when every choice of a 1/$\\beta_f$ reads the same way (the interval "
        "below or above 0), and prints a contradiction of the paper only then."))
    display(_styled(findings.finding5_choices(spectra),
                    {"data": "f5c_value", "row_heading": "f5c_row",
                     "col_heading": "f5c_column"}).format(precision=3)
            .format("{:g}", subset=["beta <="]).hide(axis="index"))


def two_wall_checks(events=None, spectra=None, motion_map=None):
    """A two-wall study's own checks in place of the paper's findings 1-7 (nothing for a
    one-wall study): per wall, the collision rate and velocity after impact; the symmetry
    check of mirror settings (:mod:`vibroimpact.reports.two_walls`); and where the motions
    sit against the two-wall stable domains, or what data that needs."""
    from IPython.display import Markdown, display

    from vibroimpact.reports import two_walls

    ds = first(events, motion_map, spectra)
    if not two_walls.is_two_wall(ds):
        return
    gaps = (f"{float(ds.attrs['gap']):g}" if "gap" in ds.attrs else
            f"gap (an axis of the map, {float(ds.gap.min()):g} to {float(ds.gap.max()):g})")
    display(Markdown(
        f"## A two-wall study: per wall, mirror images, stable domains\n\n"
        f"The second wall stands at $\\delta$ - {gaps}, so $\\delta$ places a clearance, not "
        f"the paper's play: findings 1-7, which read trends along the play, are not applicable "
        f"(the table above says so). What is measured instead: each wall's collisions, and "
        f"the mirror symmetry x $\\to$ -x, which swaps the walls: with one restitution the "
        f"setting at $\\delta$ is the mirror image of that at gap - $\\delta$, so the upper "
        f"wall's statistics at one must agree with the lower wall's at the other, within "
        f"their 95 % intervals. Mirror cells run on one record r($\\tau$) while a mirror image "
        f"is driven by -r($\\tau$): two realisations of one law."))
    if events is not None:
        display(Markdown("### Per wall"))
        display(_styled(two_walls.per_wall(events),
                        {"data": "wall_value", "row_heading": "wall_row",
                         "col_heading": "wall_column"}).format(precision=3)
                .hide(axis="index"))
    shifts = None
    if spectra is not None and float(spectra.attrs.get("amplitude", 0.0)) != 0.0:
        from vibroimpact.reports.findings import spectra_shifts

        shifts = spectra_shifts(spectra)
    check = two_walls.mirror_check(events, shifts, motion_map)
    display(Markdown("### Mirror images"))
    show_table([check])
    import pandas as pd

    table = pd.concat(
        [two_walls.mirror_table(events, shifts) if events is not None else None,
         two_walls.map_mirror_table(motion_map) if motion_map is not None else None])
    if not table.empty:
        numbers = {"1/beta_f": "{:.3g}", "delta": "{:g}", "mirror delta": "{:g}",
                   "value": "{:.4g}", "mirror value": "{:.4g}"}
        display(_styled(table, {"data": "mirror_value", "row_heading": "mirror_row",
                                "col_heading": "mirror_column"})
                .format({k: v for k, v in numbers.items() if k in table}).hide(axis="index"))
    display(Markdown("### Against the two-wall stable domains"))
    if motion_map is not None:
        display(Markdown(
            "Finding 8 in the table above sets this map's probabilities against the stable "
            "domains of the two-wall periodic motions (Fig. 16 of the orbits entry that "
            "`fig15_vs_fig16` names), motion by motion: its claim names no play, so it reads "
            "a clearance as it reads the paper's wall."))
    else:
        display(Markdown(
            "*Not computed here:* this study has no probability map over a plane of "
            "$(1/\\beta_f, \\delta)$, and its plays and forcing frequencies need not lie on an "
            "orbits grid, so where its motions sit against the two-wall stable domains is "
            "not measured in this report. A map study over the same walls with "
            "`fig15_vs_fig16` (as `clearance_map` in config/examples/clearance.yaml) reads it "
            "as finding 8 of its own report."))


def run_section(owners, benchmarks, **datasets):
    """The report's "Run" section: the versions that computed its numbers
    (:func:`vibroimpact.reports.run.versions`) and the CPU time, wall time and peak memory
    of the jobs behind its datasets and figures (:func:`vibroimpact.reports.run.job_costs`
    of ``owners`` under the folder ``benchmarks``)."""
    from IPython.display import Markdown, display

    from vibroimpact.reports import run

    display(Markdown("The tool's version and commit and the versions that can change a "
                     "number, as each dataset recorded them when its job wrote it, beside "
                     "the environment executing this report:"))
    display(run.versions(**datasets).style.set_table_attributes(
        'style="width: 100%; table-layout: fixed"'))
    costs = run.job_costs(owners, benchmarks)
    if costs.empty:
        display(Markdown(f"*No benchmark of the jobs behind this report under "
                         f"`{benchmarks}` (a build that kept none, or datasets copied from "
                         f"elsewhere).*"))
        return
    peak = costs["peak memory MB"]
    largest = (f"the largest peak memory {peak.max():.0f} MB "
               f"({costs.loc[peak.idxmax(), 'rule']})" if peak.notna().any()
               else "no peak memory recorded")
    display(Markdown(
        f"The {len(costs)} jobs behind its datasets and figures, as Snakemake's benchmarks "
        f"measured them: {costs['CPU s'].sum():.1f} CPU-s and {costs['wall s'].sum():.1f} s "
        f"of wall time in all (jobs run side by side, so the build took less), {largest}."))
    display(costs.style.format({"CPU s": "{:.2f}", "wall s": "{:.2f}",
                                "peak memory MB": "{:.0f}"}).hide(axis="index"))


def entry_name(path):
    """The entry a dataset's file is named after (``results/orbits/harmonic.nc``:
    ``harmonic``; a noise record's file: its ``noises`` entry), "" for none."""
    return Path(path).stem if path else ""


def map_owner(motion_map):
    """The owner of a map's jobs for :func:`run_section` (``map/<study>``: its tiles and their
    aggregation), "" for no map."""
    study = motion_map.attrs.get("study") if motion_map is not None else None
    return f"map/{study}" if study else ""


def noise_name(path):
    """The owner of a noise record's jobs for :func:`run_section` (``noise/<entry>``), ""
    for none."""
    return f"noise/{entry_name(path)}" if path else ""


def benchmarks_of(path):
    """The benchmarks folder of the build that wrote the file ``path``
    (``results/<kind>/<file>``: ``results/benchmarks``)."""
    return Path(path).parent.parent / "benchmarks"
