"""The report notebooks' papermill arguments (`vibroimpact.reports.arguments`) and the full
stress campaign's table, which the stability report reads and the README quotes."""
from pathlib import Path

import pandas as pd

from vibroimpact.reports import arguments
from vibroimpact.reports.notebook import csv_table, markdown_table

ROOT = Path(__file__).resolve().parents[1]


def test_a_harmonic_study_gets_the_paper_s_1_over_beta_nearest_on_its_grid():
    entry = {"amplitude": 1.0, "density_delta": [0.5, 1]}
    inputs = {"notebook": "notebooks/harmonic_random.ipynb", "events": "e.nc",
              "figures": ["a.png", "b.png"]}
    got = arguments.notebook_parameters("harmonic_random", inputs, study="harmonic",
                                        entry=entry, inv_beta=[0.5, 1.0, 1.25])
    assert list(got) == list(arguments.REPORT_PARAMETERS["harmonic_random"])
    assert got["inv_beta"] == "1.0"             # |1.0 - 1.1| < |1.25 - 1.1|
    assert got["figures"] == "a.png b.png" and got["events"] == "e.nc"
    assert got["density_delta"] == "0.5 1.0" and got["amplitude"] == "1.0"
    assert got["map"] == "" and got["study"] == "harmonic"
    assert arguments.study_report_kind(entry) == "harmonic_random"
    assert arguments.study_report_kind({"amplitude": 0}) == "random_force"


def test_arguments_are_quoted_for_the_shell():
    got = arguments.papermill_arguments({"study": "a b", "map": ""})
    assert got == "-p study 'a b' -p map ''"


def test_an_orbits_report_is_named_by_its_entry():
    got = arguments.notebook_parameters("periodic_motions", {"orbits": "o.nc"}, orbits="h")
    assert got == {"name": "h", "orbits": "o.nc", "boundaries": "", "basins": "",
                   "lyapunov": "", "map": "", "map_orbits": "", "predictors": "",
                   "figures": ""}


def test_the_readme_quotes_the_campaign_table_of_docs():
    quoted = markdown_table(ROOT / "README.md", "| family |")
    campaign = ROOT / "workflow" / "notebooks" / "stress_campaign.csv"
    pd.testing.assert_frame_equal(quoted, csv_table(campaign))
