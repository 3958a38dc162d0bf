"""The CF attributes of the files the pipeline writes (`vibroimpact.pipeline.conventions`):
every unit in the tables the datasets take their words from is a UDUNITS unit, and
`pipeline.io.write_dataset` refuses a variable without long_name or units and gives every
file the CF global attributes. The files of a whole build are checked by the workflow suite
(tests/test_workflow.py, `helpers.assert_cf`)."""
import cf_units
import numpy as np
import pytest
import xarray as xr

from helpers import cf_problems
from vibroimpact import PAPER_REFERENCE
from vibroimpact.orbits import plane
from vibroimpact.pipeline import conventions, datasets, io

TABLES = {"META": datasets.META, "PLANE_META": datasets.PLANE_META,
          "ORBIT_META": datasets.ORBIT_META, "BOUNDARY_META": datasets.BOUNDARY_META,
          "ATTRACTOR_META": datasets.ATTRACTOR_META, "ESCAPE_META": datasets.ESCAPE_META,
          "orbits.plane.META": plane.META}


@pytest.mark.parametrize("table", TABLES)
def test_every_unit_of_the_tables_is_udunits(table):
    """cf_units (UDUNITS-2) parses each; the model's quantities are dimensionless ("1"),
    the degree of stability a percentage, CPU time seconds."""
    for name, (long_name, units) in TABLES[table].items():
        assert long_name.strip(), name
        cf_units.Unit(units)
        assert units in ("1", "%", "s"), (name, units)


def test_udunits_refuses_what_the_files_used_to_say():
    with pytest.raises(ValueError):
        cf_units.Unit("1/tau")


def test_write_dataset_refuses_a_variable_without_words(tmp_path):
    ds = xr.Dataset({"x": ("i", np.arange(3.0), {"long_name": "x", "units": "1"})},
                    coords={"i": [0, 1, 2]})
    with pytest.raises(ValueError, match=r"missing: i\.long_name, i\.units"):
        io.write_dataset(ds, tmp_path / "a.nc")
    assert not (tmp_path / "a.nc").exists()
    ds["i"].attrs.update(long_name="index", units="")
    with pytest.raises(ValueError, match=r"missing: i\.units$"):
        io.write_dataset(ds, tmp_path / "a.nc")


def test_write_dataset_gives_the_cf_global_attributes(tmp_path):
    ds = datasets.annotate(xr.Dataset(
        {"collision_rate": ("delta", [0.1, 0.2])}, coords={"delta": [0.5, 1.0]},
        attrs=dict(package_version="9.9", git_commit="abc", git_dirty=1,
                   created="2026-01-01T00:00:00+00:00", history="earlier line")))
    io.write_dataset(ds, tmp_path / "rates.nc")
    assert cf_problems(tmp_path / "rates.nc") == []
    attrs = io.load_dataset(tmp_path / "rates.nc").attrs
    assert attrs["Conventions"] == conventions.CONVENTIONS
    assert attrs["source"] == "vibroimpact 9.9 (git abc with uncommitted changes)"
    assert attrs["references"] == PAPER_REFERENCE
    first, before = attrs["history"].split("\n")
    assert first.startswith("2026-01-01T00:00:00+00:00 ") and first.endswith(": wrote rates.nc")
    assert before == "earlier line"


def test_the_command_names_a_rule_script():
    """Snakemake runs a rule's script as a copy ``.snakemake/scripts/tmp<random>.<name>``."""
    assert conventions.command(["/w/.snakemake/scripts/tmpa1_b2.aggregate_events.py"]) == (
        "workflow/scripts/aggregate_events.py (Snakemake)")
    assert conventions.command(["/usr/bin/vibroimpact", "run"]) == "vibroimpact run"
