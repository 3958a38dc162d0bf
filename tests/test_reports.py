"""The report notebooks, executed by the workflow on the test config (the session's build).

Every report exists as an executed notebook and its HTML; no cell produced an error or wrote
to stderr; the findings table in a report is the one `vibroimpact.reports.findings` computes
from the build's datasets, and it changes when a dataset does. `snakemake --report` gives one
self-contained HTML of every figure, captioned, by study.
"""
from html import escape as html_escape
from pathlib import Path
import re

import nbformat
import pytest
import xarray as xr

from helpers import make_workdir, snakemake
from vibroimpact.reports import findings

pytestmark = pytest.mark.workflow

REPORTS = ["random/random_force", "harmonic/harmonic_random", "motion_map/harmonic_random",
           "orbits/harmonic/periodic_motions", "validation/performance", "validation/stability"]


def _outputs(path):
    nb = nbformat.read(path, as_version=4)
    return [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]


def _verdicts(html):
    """The findings table of a report's HTML (the one headed claim, measured, holds; the
    rule-sensitivity tables after it have numbered rows too): ``{number: verdict}``."""
    tables = re.split(r"(?=<table)", Path(html).read_text())
    (text,) = [t for t in tables if re.search(r'class="col_heading[^"]*"[^>]*>holds</th>', t)]
    numbers = re.findall(r'<th class="row_heading level0 row(\d+)"[^>]*>(\d)</th>', text)
    verdicts = dict(re.findall(r'<td class="data row(\d+) col2"[^>]*>([^<]*)</td>', text))
    return {int(n): verdicts[row] for row, n in numbers}


@pytest.mark.parametrize("report", REPORTS)
def test_every_report_is_executed_without_error_output(built, report):
    ipynb = built / "results" / "reports" / f"{report}.ipynb"
    html = ipynb.with_suffix(".html")
    assert html.stat().st_size > 10_000
    outputs = _outputs(ipynb)
    assert not [o for o in outputs if o.output_type == "error"]
    assert not [o.text for o in outputs if o.output_type == "stream" and o.name == "stderr"]
    assert any("image/png" in o.get("data", {}) for o in outputs), "no figure inline"
    assert not list(ipynb.parent.glob(".report.*")), "temporary directory left behind"


def test_the_tables_are_the_findings_of_the_datasets(built):
    data = built / "results" / "datasets"
    expected = findings.random_force(events=xr.load_dataset(data / "random_events.nc"),
                                     spectra=xr.load_dataset(data / "random_spectra.nc"))
    table = _verdicts(built / "results" / "reports" / "random" / "random_force.html")
    assert table == {f.number: f.holds for f in expected}
    harmonic = _verdicts(built / "results" / "reports" / "harmonic" / "harmonic_random.html")
    assert sorted(harmonic) == [5, 6, 7, 8] and "n/a" not in harmonic.values()


def test_a_map_studys_report_is_titled_and_audited_as_one_and_shows_parameters_once(built):
    """The map study (test config: `motion_map`, a map and no impact record) is titled by
    what it holds, tables only finding 8 and names 5-7 under it, and audits its map; every
    report shows papermill's parameters once (the injected values), and a partly verdict of
    the harmonic report opens with its sentence."""
    reports = built / "results" / "reports"
    text = (reports / "motion_map" / "harmonic_random.html").read_text()
    assert "<title>Harmonic plus random force: the probability map of study motion_map" in text
    assert "Figs. 10-15" not in text and "keeps no impact record" in text
    assert sorted(_verdicts(reports / "motion_map" / "harmonic_random.html")) == [8]
    assert "Not measured in this report:" in text and "findings 6, 7" in text
    assert "Self-audit passed:</strong> a map study keeps no impact record" in text
    for report in REPORTS:
        html = (reports / f"{report}.html").read_text()
        assert "celltag_parameters" not in html and html.count("# Parameters") == 1, report
    data = built / "results" / "datasets"
    found = findings.random_force(events=xr.load_dataset(data / "random_events.nc"),
                                  spectra=xr.load_dataset(data / "random_spectra.nc"))
    random = (reports / "random" / "random_force.html").read_text()
    for f in found:
        assert f.holds != "partly" or f.summary, f
        if f.summary:
            assert f"<b>{html_escape(f.summary)}</b>" in random


def _predictor_cells(html):
    """The predictors table of a report's HTML: ``{(row, col): text}``."""
    cells = re.findall(r'<td class="predictor_value row(\d+) col(\d+)"[^>]*>([^<]*)</td>',
                       Path(html).read_text())
    return {(int(r), int(c)): text.strip() for r, c, text in cells}


def test_the_harmonic_reports_show_what_predicts_p_and_whether_it_is_markov(built):
    """Both harmonic reports show the predictors table (4 predictors x 3 motions, the basins
    and exponents of the test config's attractors on the map's grid) with the correlations
    `reports.predictors` computes, and the Markov table with the bookkeeping check."""
    from vibroimpact.reports import predictors

    root = built / "results"
    motion_map, basins, exponents = (xr.load_dataset(root / p) for p in (
        "datasets/motion_map_map.nc", "orbits/harmonic_basins.nc",
        "orbits/harmonic_lyapunov.nc"))
    expected = predictors.predictor_correlations(
        motion_map, xr.load_dataset(root / "datasets" / "motion_map_map_orbits.nc"), basins,
        exponents)
    table = predictors.predictors_table(expected)
    # computed once (rule map_predictors), read back by the reports value for value
    stored = predictors.read_correlations(
        xr.load_dataset(root / "datasets" / "motion_map_predictors.nc"))
    assert predictors.predictors_table(stored).equals(table)
    for study in ("harmonic", "motion_map"):
        html = root / "reports" / study / "harmonic_random.html"
        cells = _predictor_cells(html)
        assert max(r for r, _ in cells) + 1 == len(table) == 12
        assert [cells[(r, 0)] for r in range(len(table))] == list(
            table["stable domain: rho [95 %]"])
        assert any(cells[(r, 2)] for r in range(3, 9)), "no basin or Lyapunov correlation"
        text = html.read_text()
        assert "markov_value" in text and "(the bookkeeping, Markov or not)" in text


def test_a_changed_dataset_changes_the_table(built, tmp_path):
    """Finding 2 on the test config holds; with the mean velocities reversed the rebuilt
    report says it does not (only the report and the figures of that dataset rerun)."""
    copy = make_workdir(tmp_path / "copy", build=built)
    report = copy / "results" / "reports" / "random" / "random_force.html"
    assert _verdicts(report)[2] == "yes"
    path = copy / "results" / "datasets" / "random_events.nc"
    ds = xr.load_dataset(path)
    for name in ("v_after_mean", "v_after_mean_lo", "v_after_mean_hi", "v_after_stderr"):
        ds[name].values = ds[name].values[:, ::-1].copy()     # the mean with its interval
    ds.to_netcdf(path)
    out = snakemake(copy, "results/reports/random/random_force.html")
    assert "aggregate_events" not in out.stdout + out.stderr
    assert _verdicts(report)[2] == "no"


def test_snakemake_report_has_every_figure_captioned_by_study(built, tmp_path):
    target = tmp_path / "report.html"
    snakemake(built, "--report", str(target))
    text = target.read_text(errors="replace")
    assert target.stat().st_size > 100_000
    for category in ("random", "harmonic", "motion_map", "paper", "validation"):
        assert category in text
    assert "probability density of the velocity after impact" in text     # a caption
    assert "zeta = 0.05" in text                                          # its parameters
