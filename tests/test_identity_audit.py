"""The reports' self-audit table (`reports.notebook.identity_audit`) on an events dataset made
by the workflow's own tasks: it passes on the real record, names the cell and identity a
corrupted residual fails at, summarises a long sweep by its worst cells, and keeps its HTML
cells out of the findings table's class names (which the report tests read)."""
from unittest import mock

import IPython.display
import numpy as np
import pytest
import xarray as xr

from vibroimpact.pipeline import tasks
from vibroimpact.reports import notebook as nb

NOISE = dict(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0, n_samples=30_001,
             seed=19740914, nperseg=1024)
STUDY = dict(noise="band", zeta=0.05, eps=0.5, amplitude=0.0, delta=[-0.5, 0.0, 1.0],
             transient=100.0, tile_size=10, n_batches=20, motion_window=0.1,
             motions=[[1, 1], [2, 1], [1, 2]],
             bins=dict(v_after=dict(max=2.5, n=20), interval=dict(max=10.0, n=20),
                       ratio=dict(max=4.0, n=20)))


@pytest.fixture(scope="module")
def events(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("audit")
    tasks.make_noise(NOISE, tmp / "band.nc")
    tasks.events_tile("random", STUDY, 0, tmp / "band.nc", tmp / "tile.nc")
    tasks.aggregate("random", STUDY, "events", [tmp / "tile.nc"], tmp / "events.nc",
                    noise_path=tmp / "band.nc")
    return xr.load_dataset(tmp / "events.nc")


def _audit(ds):
    shown = []
    with mock.patch.object(IPython.display, "display", lambda *a: shown.extend(a)):
        table = nb.identity_audit(ds)
    return [s.data for s in shown], table


def test_a_real_record_passes_and_the_table_has_every_cell(events):
    (verdict,), table = _audit(events)
    assert verdict.startswith("**Self-audit passed:** all 6 residuals")
    frame = table.data
    assert list(frame.index) == [-0.5, 0.0, 1.0]
    cell = events.isel(inv_beta=0).sel(delta=1.0)
    row = frame.loc[1.0]
    assert row[("power", "residual")] == float(cell["power_residual"])
    assert row[("virial", "residual / s.e.")] == pytest.approx(
        float(cell["virial_residual"]) / float(cell["virial_residual_stderr"]), rel=1e-12)
    assert row[("power", "residual / scale")] == pytest.approx(
        float(cell["power_residual"]) / abs(float(cell["power_input"])), rel=1e-12)
    html = table.to_html()
    assert 'class="audit' in html and "data row" not in html and "row_heading" not in html


def test_a_wrong_residual_fails_by_name_and_a_long_sweep_shows_its_worst_cells(events):
    bad = events.copy(deep=True)
    bad["virial_residual"][0, 1] = 10 * float(bad["virial_residual_stderr"][0, 1])
    (verdict,), _ = _audit(bad)
    assert "FAILED" in verdict and "virial at delta = 0 (10.0 s.e.)" in verdict
    long = xr.concat([bad.assign_coords(delta=bad["delta"] + 10 * k) for k in range(5)],
                     dim="delta")
    verdict, table = _audit(long)
    assert len(table.data) == nb.AUDIT_WORST and len(long["delta"]) > nb.AUDIT_ROWS
    assert table.data.index[0] == 0.0 and "5 of 30 residuals" in verdict[0]
    assert verdict[0].count("(10.0 s.e.)") == nb.AUDIT_WORST
    assert np.isfinite(table.data.to_numpy()).all()


def test_a_residual_below_the_numerical_floor_passes_and_is_named(events):
    """Beyond 3 s.e. but within AUDIT_FLOOR of its scale (the mass resting on the wall, its
    batch errors below the accuracy of the closed-form chatter tails): passed, and said."""
    low = events.copy(deep=True)
    scale = abs(float(low["virial_scale"][0, 0]))
    low["virial_residual"][0, 0] = 0.5 * nb.AUDIT_FLOOR * scale
    low["virial_residual_stderr"][0, 0] = 0.01 * nb.AUDIT_FLOOR * scale
    (verdict,), _ = _audit(low)
    assert verdict.startswith("**Self-audit passed:**")
    assert "1 more beyond 3 s.e. but within 1e-07 of their scale" in verdict
    assert "virial at delta = -0.5: 50.0 s.e., 5.0e-08 of its scale" in verdict
    low["virial_residual"][0, 0] = 2 * nb.AUDIT_FLOOR * scale
    (verdict,), _ = _audit(low)
    assert "FAILED" in verdict and "virial at delta = -0.5 (200.0 s.e.)" in verdict


def test_no_residuals_no_table():
    assert "no identity residuals" in nb.identity_audit(None).data
