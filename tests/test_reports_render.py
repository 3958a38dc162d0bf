"""The reports as a referee reads them: offline, with captions docutils accepts, each figure
once, and settings that are the study's.

Fast: a notebook rendered by `vibroimpact.reports.notebook.render_html` loads nothing from the
network (nbconvert's own template does: the check is shown to fail on it), and its maths is
MathML; every figure caption of the paper's config passes through the report's template and
docutils without a system message; the settings and provenance tables of datasets carrying
the attributes the workflow writes; `python -m vibroimpact report` replaces the report whole
or not at all. `workflow`: the same on the session's build of the test config, and Snakemake's
report of it.
"""
import base64
from html.parser import HTMLParser
import json
import re
import subprocess
import sys
from types import SimpleNamespace

import nbformat
import numpy as np
import pandas as pd
import pytest
import yaml
import xarray as xr

from helpers import ROOT, make_workdir
from vibroimpact.pipeline import cli, config as configuration, figures
from vibroimpact.reports import notebook

REPORTS = ["random/random_force", "harmonic/harmonic_random", "motion_map/harmonic_random",
           "orbits/harmonic/periodic_motions", "validation/performance", "validation/stability"]


class _Loads(HTMLParser):
    """What a browser would fetch to show a page: the sources of scripts, stylesheets, images
    and frames, the ``@import`` and ``url()`` of its styles, and the modules its scripts
    import (nbconvert's mermaid loader does ``await import("https://...")``)."""

    SOURCE = {"script": "src", "img": "src", "iframe": "src", "audio": "src", "video": "src",
              "source": "src", "embed": "src", "object": "data", "link": "href"}
    LINKED = ("stylesheet", "icon", "preload", "modulepreload")
    IMPORT = re.compile(r"""(?:\bimport\s*\(|\bfrom\s+|importScripts\s*\()\s*["'`]([^"'`]+)""")
    STYLE_URL = re.compile(r"""(?:@import\s+(?:url\()?|url\()\s*["']?([^"')\s;]+)""")

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.loads, self._inside = [], None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        source = attrs.get(self.SOURCE.get(tag, ""))
        if tag == "link" and not set((attrs.get("rel") or "").split()) & set(self.LINKED):
            source = None
        if source:
            self.loads.append(source)
        self._inside = tag if tag in ("script", "style") else None

    def handle_endtag(self, tag):
        self._inside = None

    def handle_data(self, data):
        if self._inside == "script":
            self.loads += [u for u in self.IMPORT.findall(data) if "://" in u]
        elif self._inside == "style":
            self.loads += self.STYLE_URL.findall(re.sub(r"/\*.*?\*/", "", data, flags=re.S))


def fetched(html):
    """The resources an HTML page loads that it does not carry itself (not ``data:``)."""
    parser = _Loads()
    parser.feed(html)
    return [url for url in parser.loads if not url.startswith("data:")]


#: A PNG of one pixel, base64 (a figure output).
_PIXEL = ("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNkYPhfDwAChwGA60e6kgAAAABJ"
          "RU5ErkJggg==")


def _notebook(tmp_path):
    """An executed-looking notebook: maths in a markdown cell and a code span, a table."""
    nb = nbformat.v4.new_notebook()
    nb.cells = [
        nbformat.v4.new_markdown_cell("# Report\n\nDriven by $A \\sin(\\beta_f \\tau) + r(\\tau)$;"
                                      " the wall-free response $$|H|^2 S_f$$ and `a $b$ c`."),
        nbformat.v4.new_code_cell("table", outputs=[nbformat.v4.new_output(
            "display_data", data={"text/html": "<table><tr><td>1</td></tr></table>",
                                  "text/plain": "1"})]),
        nbformat.v4.new_code_cell("figure", outputs=[
            nbformat.v4.new_output("display_data", data={"text/markdown": "`fig.png`",
                                                         "text/plain": "fig.png"}),
            nbformat.v4.new_output("display_data", data={"image/png": _PIXEL,
                                                         "text/plain": "<Image>"})]),
    ]
    path = tmp_path / "report.ipynb"
    nbformat.write(nb, path)
    return path


def test_nbconverts_own_template_is_caught_loading_from_the_network(tmp_path):
    """The check below fails on what the reports were before: MathJax, require.js, mermaid."""
    from nbconvert import HTMLExporter

    body, _ = HTMLExporter().from_filename(str(_notebook(tmp_path)))
    loads = fetched(body)
    assert any("mathjax" in url.lower() for url in loads)
    assert any("require" in url for url in loads)


def test_a_rendered_report_loads_nothing_and_its_maths_is_mathml(tmp_path):
    html = tmp_path / "report.html"
    notebook.render_html(_notebook(tmp_path), html)
    text = html.read_text()
    assert fetched(text) == []
    assert text.count("<math ") == 2 and 'display="block"' in text
    assert "\\beta_f" not in text                   # converted, not left for a script
    assert "<code>a $b$ c</code>" in text           # a code span keeps its dollars
    assert "<table>" in text and text.count(_PIXEL) == 1


def _papermilled(tmp_path):
    """A notebook as papermill leaves it: the ``parameters`` cell (the defaults), the
    ``injected-parameters`` cell (this run's values: one long line of paths), a ``heading``
    cell computed from them after the imports, and a long line of output."""
    nb = nbformat.v4.new_notebook()
    paths = " ".join(f"results/figures/motion_map/fig{n}.png" for n in range(10, 30))
    nb.cells = [
        nbformat.v4.new_code_cell('study = "default_study"', metadata={"tags": ["parameters"]}),
        nbformat.v4.new_code_cell(f'study = "this_run"\nfigures = "{paths}"',
                                  metadata={"tags": ["injected-parameters"]}),
        nbformat.v4.new_code_cell("import notebook_helpers as nb"),
        nbformat.v4.new_code_cell("nb.harmonic_heading(study)", metadata={"tags": ["heading"]},
                                  outputs=[nbformat.v4.new_output(
                                      "display_data", data={"text/markdown": "# The title",
                                                            "text/plain": "title"})]),
        nbformat.v4.new_code_cell("print(figures)", outputs=[nbformat.v4.new_output(
            "stream", name="stdout", text=paths)]),
    ]
    path = tmp_path / "papermilled.ipynb"
    nbformat.write(nb, path)
    return path


def test_a_papermilled_report_shows_its_parameters_once_its_title_first_and_wraps(tmp_path):
    html = tmp_path / "report.html"
    notebook.render_html(_papermilled(tmp_path), html)
    text = html.read_text()
    assert "default_study" not in text and "this_run" in text     # the injected values only
    assert "celltag_parameters" not in text and "celltag_injected-parameters" in text
    body = text[text.index("<body"):]
    assert body.index("The title") < body.index("this_run")        # the heading comes first
    assert "nb.harmonic_heading" not in text                       # its output, not its code
    assert "<title>The title</title>" in text                      # the page's title
    style = text[:text.index("<body")]
    assert re.search(r"\.highlight pre[^}]*white-space: pre-wrap", style)  # long code wraps
    assert re.search(r"\.jp-OutputArea-output pre[^}]*white-space: pre-wrap", style, re.S)


def test_a_notebook_run_by_hand_keeps_its_parameters_cell(tmp_path):
    """Without papermill's injected cell, the defaults are the values: they stay."""
    nb = nbformat.read(_papermilled(tmp_path), as_version=4)
    nb.cells = [c for c in nb.cells if "injected-parameters" not in c.metadata.get("tags", [])]
    path = tmp_path / "by_hand.ipynb"
    nbformat.write(nb, path)
    notebook.render_html(path, tmp_path / "by_hand.html")
    assert "default_study" in (tmp_path / "by_hand.html").read_text()


def test_a_map_studys_heading_and_audit_say_what_a_map_reports():
    """A map study (a map, no events, no spectra) is titled by its figures, says it keeps no
    impact record, and its self-audit checks its probabilities; a study with events is
    titled by section 5's figures it shows."""
    figures = ("results/figures/m/fig15.png results/figures/m/fig15_vs_fig16.png "
               "results/figures/m/residence.png")
    assert notebook.is_map_study("", "", "map.nc") and not notebook.is_map_study("e.nc", "",
                                                                                 "map.nc")
    title = notebook.harmonic_heading("m", map="map.nc", figures=figures).data
    assert title.startswith("# Harmonic plus random force: the probability map of study `m` "
                            "(paper section 5, Fig. 15 against Fig. 16)")
    assert "keeps no impact record" in title and "finding 8" in title
    full = notebook.harmonic_heading("h", events="e.nc", spectra="s.nc", map="map.nc",
                                     figures=" ".join(f"x/fig{n}.png" for n in range(10, 15))
                                     + " " + figures).data
    assert full.startswith("# Harmonic plus random force: study `h` (paper section 5, "
                           "Figs. 10-15)")
    grid = dict(motion=["1/1", "2/1"], inv_beta=[1.0, 1.1], delta=[0.0, 1.0])
    p = np.array([[[0.6, 0.2], [0.1, 0.9]], [[0.3, 0.7], [0.5, 0.05]]])
    motion_map = xr.Dataset({"probability": (("motion", "inv_beta", "delta"), p),
                             "probability_stderr": (("motion", "inv_beta", "delta"),
                                                    np.full(p.shape, 0.005)),
                             "reached": (("inv_beta", "delta"), np.ones((2, 2), np.int8))},
                            coords=grid, attrs={"target_stderr": 0.01})
    audit = notebook.map_audit(motion_map).data
    assert audit.startswith("**Self-audit passed:**") and "In 4 of its 4 cells" in audit
    assert "largest sum 0.9500" in audit                           # 0.9 + 0.05 at (1.0, 1.0)
    motion_map["probability"][0, 0, 1] = 0.9              # with (2/1)'s 0.7: more than all
    motion_map["probability_stderr"][0, 1, 1] = 0.02      # above the target it claims reached
    bad = notebook.map_audit(motion_map).data
    assert bad.startswith("**Self-audit FAILED:**") and "In 3 of its 4 cells" in bad
    assert "1 above the target" in bad
    assert "(1/beta_f = 1, delta = 1), (1/beta_f = 1.1, delta = 1)" in bad


def test_the_findings_table_opens_a_verdict_with_its_sentence_and_names_what_it_leaves(
        monkeypatch):
    """The summary sentence, in bold, before the numbers; with ``omit_unavailable`` the n/a
    findings leave the table for one line under it, grouped by why; the returned table
    still holds every finding."""
    from html import escape

    import IPython.display

    from vibroimpact.reports import findings

    shown = []
    monkeypatch.setattr(IPython.display, "display", lambda *objs: shown.extend(objs))
    inside = dict(n_dominant=40, dominant_inside=0.9, domain_covered=0.8, rank_correlation=0.1)
    found = [findings.not_available(5, "no spectrum"), findings.not_available(6, "no densities"),
             findings.not_available(7, "no densities"), findings.finding8({"1/1": inside})]
    table = notebook.show_table(found, omit_unavailable=True)
    assert list(table.index) == [5, 6, 7, 8]
    html = shown[0].to_html()
    assert found[3].summary.startswith("Holds: the domains agree")
    assert f"<b>{escape(found[3].summary)}</b><br>" in html
    assert ">n/a<" not in html and ">partly<" in html
    assert shown[1].data == ("*Not measured in this report:* finding 5 (no spectrum); "
                             "findings 6, 7 (no densities).")


def test_the_summary_for_snakemakes_report_has_no_image_but_says_which(tmp_path):
    html = tmp_path / "summary.html"
    notebook.main([str(_notebook(tmp_path)), str(html), "--no-figures"])
    text = html.read_text()
    assert _PIXEL not in text and "<img" not in text
    assert "fig.png" in text and "<table>" in text and fetched(text) == []


def test_one_call_renders_both_files_as_two_calls_would(tmp_path):
    """`--summary` (the report rules' single rendering process) writes the same two files."""
    ipynb = str(_notebook(tmp_path))
    notebook.main([ipynb, str(tmp_path / "a.html")])
    notebook.main([ipynb, str(tmp_path / "a.summary.html"), "--no-figures"])
    notebook.main([ipynb, str(tmp_path / "b.html"), "--summary", str(tmp_path / "b.summary.html")])
    for name in ("html", "summary.html"):
        assert (tmp_path / f"b.{name}").read_text() == (tmp_path / f"a.{name}").read_text()
    assert "<img" in (tmp_path / "b.html").read_text()


def _paper_captions():
    """``(target, caption rst)`` of every figure of every entry of the paper's config."""
    config, _ = configuration.load(root=ROOT)
    for kind, section in (("study", "studies"), ("orbits", "orbits")):
        for name, entry in config[section].items():
            for target in figures.figure_targets(entry):
                yield target, figures.caption(kind, name, entry, target)


def test_every_caption_passes_docutils_without_a_system_message():
    """Through `workflow/report/figure.rst` as `snakemake --report` renders it (jinja, then
    docutils' HTML writer): no error box, and the text reads as written (Fig. 6's |H|^2 S_f
    is not a substitution reference)."""
    import jinja2
    from docutils.core import publish_parts

    template = jinja2.Template((ROOT / "workflow" / "report" / "figure.rst").read_text())
    captions = list(_paper_captions())
    assert len(captions) >= 15
    for target, caption in captions:
        png = f"results/figures/x/{target}.png"
        rst = template.render(snakemake=SimpleNamespace(
            config={"figure_captions": {png: caption}}, output=SimpleNamespace(png=png)))
        body = publish_parts(rst, writer="html",
                             settings_overrides={"warning_stream": False})["body"]
        assert "system-message" not in body and "System Message" not in body, (target, body)
        assert "\\" not in body, (target, body)
        if target == "fig06":
            assert "|H|^2 S_f" in body


def _study_dataset(amplitude, inv_beta):
    """A dataset with the attributes and grids the workflow writes for a study
    (``vibroimpact.pipeline.tasks``: the study's, its noise record's, the record's)."""
    ds = xr.Dataset(coords={"inv_beta": np.asarray(inv_beta, dtype=float),
                            "delta": np.arange(-1.0, 3.01, 0.5)})
    ds.attrs.update(package_version="0.1.0", git_commit="2a54d9f2bded09952c6be3ea35153a49fba0687a",
                    git_dirty=0, config_digest="9f612d59ee544ebb3fd4662dfbcc013cbe33c5fa50c9a1d7"
                                               "3d24b3a877555b28",
                    created="2026-11-24T10:13:53+00:00", seed=19740914, study="s", zeta=0.05,
                    eps=0.5, amplitude=amplitude, noise="random_input", dt=0.1,
                    noise_kind="band_limited", noise_rms=0.5, noise_dt=0.1, noise_beta_c=4.0,
                    transient=200.0, t_end=1e6, record_length=999800.0, n_batches=20,
                    motion_window=0.1, rebound_floor=0.01)
    return ds


def test_a_random_study_shows_its_noise_and_no_harmonic_keys():
    rows = notebook.study_settings(_study_dataset(0.0, [1.0]), name="random")["value"]
    assert {"noise": "random_input", "noise kind": "band_limited", "noise rms": "0.5",
            "noise beta_c": "4", "noise dt": "0.1", "noise seed": "19740914",
            "t_end": "1000000"}.items() <= rows.to_dict().items()
    assert not {"inv_beta grid", "motion_window"} & set(rows.index)


def test_a_harmonic_study_shows_its_noise_its_1_over_beta_grid_and_motion_window():
    rows = notebook.study_settings(_study_dataset(1.0, [1 / 1.1, 1.1]))["value"]
    assert rows["inv_beta grid"] == "0.9091, 1.1" and rows["motion_window"] == "0.1"
    assert rows["noise rms"] == "0.5" and rows["noise seed"] == "19740914"


def test_the_provenance_table_has_a_column_per_dataset_and_wraps_its_hashes():
    ds = _study_dataset(0.0, [1.0])
    styler = notebook.provenance(events=ds, spectra=ds, map=None, noise=ds)
    table = styler.data
    assert list(table.columns) == ["events", "spectra", "noise"]
    assert table.loc["config_digest", "noise"] == ds.attrs["config_digest"]
    assert table.loc["seed", "events"] == "19740914"
    html = styler.to_html()
    assert "word-break: break-all" in html and "table-layout: fixed" in html


def _fake_snakemake(tmp_path, body, code, costs=0):
    """A `snakemake` command (`cli._snakemake`'s words) that writes ``body`` to its ``--report``
    file and exits with ``code``; called without ``--report`` (the job costs, written first),
    exits with ``costs``."""
    script = tmp_path / "snakemake"
    script.write_text(f"#!{sys.executable}\nimport sys\n"
                      f"if '--report' not in sys.argv: sys.exit({costs})\n"
                      f"path = sys.argv[sys.argv.index('--report') + 1]\n"
                      f"open(path, 'w').write({body!r})\nsys.exit({code})\n")
    script.chmod(0o755)
    return [str(script)]


def test_a_failed_report_leaves_the_previous_one_whole(tmp_path, monkeypatch):
    workdir = make_workdir(tmp_path / "wd")
    (workdir / "results").mkdir()
    report = workdir / "results" / "report.html"
    monkeypatch.setattr(cli, "_snakemake", lambda root: _fake_snakemake(tmp_path, "<html>half", 1))
    assert cli.main(["report", "--directory", str(workdir)]) == 1
    assert not report.exists()
    assert list((workdir / "results").iterdir()) == []     # no temporary either
    monkeypatch.setattr(cli, "_snakemake",
                        lambda root: _fake_snakemake(tmp_path, "<html>whole</html>", 0))
    assert cli.main(["report", "--directory", str(workdir)]) == 0
    assert report.read_text() == "<html>whole</html>"
    monkeypatch.setattr(cli, "_snakemake", lambda root: _fake_snakemake(tmp_path, "<html>half", 1))
    assert cli.main(["report", "--directory", str(workdir)]) == 1
    assert report.read_text() == "<html>whole</html>"
    monkeypatch.setattr(cli, "_snakemake",
                        lambda root: _fake_snakemake(tmp_path, "<html>new</html>", 0, costs=1))
    assert cli.main(["report", "--directory", str(workdir)]) == 1     # the job costs failed
    assert report.read_text() == "<html>whole</html>"
    assert [p.name for p in (workdir / "results").iterdir()] == ["report.html"]


# --- the session's build of the test config ---------------------------------------------

def _output_html(ipynb, call):
    """The HTML output of the code cell of report ``ipynb`` whose source starts with
    ``call``."""
    nb = nbformat.read(ipynb, as_version=4)
    cell = next(c for c in nb.cells if c.cell_type == "code" and c.source.startswith(call))
    return next(o.data["text/html"] for o in cell.outputs if "text/html" in o.get("data", {}))


#: A figure shown inline (not the template's icons, which are in its stylesheet).
_IMAGE = re.compile(r"<img [^>]*src=\"data:image/png")


def _row_labels(html):
    """The row labels of a table: a styled one's (``level0 rowN`` headings) or a plain one's."""
    return set(re.findall(r'<th id="[^"]*" class="[^"]* level0 row\d+"[^>]*>([^<]*)</th>', html)
               or re.findall(r"<tr>\s*<th>([^<]*)</th>", html))


@pytest.mark.workflow
@pytest.mark.parametrize("report", REPORTS)
def test_every_report_of_the_build_reads_offline(built, report):
    text = (built / "results" / "reports" / f"{report}.html").read_text()
    assert fetched(text) == []
    assert _IMAGE.search(text)
    if report.endswith(("random_force", "harmonic_random", "periodic_motions")):
        assert "<math " in text
    summary = (built / "results" / "reports" / f"{report}.summary.html").read_text()
    assert fetched(summary) == [] and not _IMAGE.search(summary)


@pytest.mark.workflow
def test_the_random_reports_settings_show_the_noise_and_no_harmonic_keys(built):
    reports = built / "results" / "reports"
    random = _row_labels(_output_html(reports / "random" / "random_force.ipynb",
                                      "nb.study_settings"))
    assert {"noise", "noise kind", "noise rms", "noise beta_c", "noise dt",
            "noise seed"} <= random
    assert not {"inv_beta grid", "motion_window"} & random
    harmonic = _row_labels(_output_html(reports / "harmonic" / "harmonic_random.ipynb",
                                        "nb.study_settings"))
    assert {"inv_beta grid", "motion_window", "noise rms", "noise seed"} <= harmonic


@pytest.mark.workflow
def test_the_harmonic_reports_provenance_has_its_noise_record(built):
    html = _output_html(built / "results" / "reports" / "harmonic" / "harmonic_random.ipynb",
                        "nb.provenance")
    columns = re.findall(r'<th [^>]*class="[^"]* level0 col\d+"[^>]*>([^<]*)</th>', html)
    assert "noise" in columns and "events" in columns
    assert {"git_commit", "config_digest", "seed"} <= _row_labels(html)


@pytest.mark.workflow
def test_snakemake_report_has_each_figure_once_and_no_docutils_error(built):
    out = subprocess.run([sys.executable, "-m", "vibroimpact", "report", "--configfile",
                          "config/test.yaml", "--output", "results/referee.html"],
                         cwd=built, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-3000:]
    text = (built / "results" / "referee.html").read_text()
    assert "system-message" not in text and "System Message" not in text
    assert fetched(text) == []
    pngs = sorted((built / "results" / "figures").rglob("*.png"))
    paper_figures = yaml.safe_load((built / "config" / "test.yaml").read_text())["paper_figures"]
    copies = [p for p in pngs if p.parent.name == "figures" and p.stem in paper_figures]
    assert len(copies) == len(paper_figures) >= 15
    for png in pngs:
        assert text.count(base64.b64encode(png.read_bytes()).decode()) == 1, png
    categories = json.loads(re.search(r"var categories = (\{.*?\});\n", text)[1])
    shown = [path for subs in categories.values() for paths in subs.values() for path in paths]
    assert len(shown) == len(set(shown))
    paper = [path for paths in categories["paper"].values() for path in paths]
    assert len(paper) == len(copies) and all(p.startswith("results/figures/") for p in paper)
    reports = [p for p in shown if p.startswith("results/reports/")
               and p != "results/reports/job_costs.html"]
    assert len(reports) == len(REPORTS) and all(p.endswith(".summary.html") for p in reports)
    # the build's jobs by rule, every benchmark file of the build counted once
    assert categories["run"] and "results/reports/job_costs.html" in shown
    costs = pd.read_csv(built / "results" / "reports" / "job_costs.tsv", sep="\t",
                        index_col="rule")
    files = list((built / "results" / "benchmarks").rglob("*.tsv"))
    assert costs.loc["all", "jobs"] == len(files) == costs["jobs"].drop("all").sum()
    assert (costs["jobs"].drop("all") == costs["planned jobs"].drop("all")).all()
    assert {"simulate_events", "report", "draw_figure"} <= set(costs.index)


def test_report_parameters_are_typed_as_papermills_command_line_types_them():
    """The report rules run the notebook with papermill's Python API in the rendering process
    (`notebook.main --execute`): each ``-p NAME VALUE`` must reach the notebook as papermill's
    own command line would pass it (its `_resolve_type`, the reference here)."""
    from papermill.cli import _resolve_type

    values = ["True", "False", "None", "0", "-3", "1.1", "-0.5", "1e-3", "nan", "",
              "results/datasets/random_events.nc", "a b", "0.5 0.0", "true"]
    for value in values:
        got, want = notebook.parameter_value(value), _resolve_type(value)
        assert type(got) is type(want) and (got == want or (got != got and want != want)), value


def test_report_parameters_need_a_notebook_to_execute(tmp_path, capsys):
    with pytest.raises(SystemExit):
        notebook.main(["-p", "study", "random", str(tmp_path / "r.ipynb"),
                       str(tmp_path / "r.html")])
    assert "--execute" in capsys.readouterr().err
