"""The weight of the collision rule (docs/figures.md, "Collisions"): the events and map cells
store each figure statistic under the physical rule, the impacts-only rule and per rebound
above the floor; the reports tabulate them and re-read findings 2 and 3 under each."""
import numpy as np
import pytest

from vibroimpact import Model, noise, simulate, stats
from vibroimpact.pipeline import cells, datasets
from vibroimpact.pipeline.study import Study
from vibroimpact.reports import sensitivity

NOISE = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)
BINS = {"v_after": np.linspace(0, 2.5, 51), "interval": np.linspace(0, 20, 41),
        "ratio": np.linspace(0, 4, 41)}
KW = dict(transient=50.0, bins=BINS, n_batches=10)


@pytest.fixture(scope="module")
def record():
    return noise.generate_array(NOISE, 30_001, seed=7)      # tau up to 3000


@pytest.fixture(scope="module")
def pressed_cells(record):
    """Random-force cells at negative play, where the rules differ (and one at 0.5)."""
    return {d: cells.event_statistics(record, NOISE.dt, Model.paper(0.05, 0.5, d), **KW)
            for d in (-1.0, -0.5, -0.2, 0.5)}


def test_each_rule_row_is_what_its_grouping_gives(record, pressed_cells):
    out = pressed_cells[-0.5]
    assert list(stats.RULES) == ["physical", "impacts", "rebounds"]
    # the physical row is the cell's own statistics, bit for bit
    assert out["rule_n_events"][0] == out["n_collisions"]
    for name in ("collision_rate", "v_after_mean", "interval_mean"):
        assert out[f"rule_{name}"][0] == out[name], name
    # the per-rebound row is the per-rebound view above the floor
    assert out["rule_n_events"][2] == out["n_rebounds"]
    # (the rule rows are the plain mean of every value, as v_after_mean and
    # rebound_v_after_mean: equal up to the summation order)
    assert out["rule_v_after_mean"][2] == pytest.approx(out["rebound_v_after_mean"], rel=1e-12)
    # the impacts-only row regroups the same record by the earlier rule
    res = simulate(0.05, 0.5, -0.5, noise=record, dt=NOISE.dt)
    old = res.grouped("impacts").after(50.0)
    assert out["rule_n_events"][1] == old.time.size
    # the mean interval is T/N (the record after the transient over the count), every rule
    assert out["rule_interval_mean"][1] == pytest.approx(out["simulated_time"] / old.time.size,
                                                         rel=1e-12)
    # the rules differ at negative play: the test bites
    assert len(set(out["rule_n_events"].tolist())) == 3


def test_the_harmonic_and_map_cells_carry_the_motions_under_each_rule(record):
    motions = ((1, 1), (2, 1), (1, 2))
    model = Model.paper(0.05, 0.5, -0.5, 1.0, 0.5)
    out = cells.event_statistics(record, NOISE.dt, model, motions=motions, **KW)
    assert out["rule_motion_probability"].shape == (3, 3)
    assert np.array_equal(out["rule_motion_probability"][0], out["motion_probability"])
    assert np.array_equal(out["rule_motion_stick_probability"][0],
                          out["motion_stick_probability"])
    m = cells.motion_map_cell(record, NOISE.dt, model, transient=50.0, motions=motions,
                              min_time=1000.0, max_periods=100)
    assert np.array_equal(m["rule_probability"][0], m["probability"])
    assert np.array_equal(m["rule_stick_probability"][0], m["stick_probability"])
    cell_list = Study.from_config("map", dict(zeta=0.05, eps=0.5, amplitude=1.0,
                                              inv_beta=[2.0], delta=[-0.5],
                                              tile_size=4)).cells()
    tile = datasets.map_tile(cell_list, [dict(m, cpu_time=0.0)], motions, {})
    assert tile["rule_stick_probability"].dims == ("cell", "rule", "motion")
    assert list(tile.rule.values) == list(stats.RULES)


def _events(pressed_cells):
    deltas = sorted(pressed_cells)
    cell_list = Study.from_config("random", dict(zeta=0.05, eps=0.5, amplitude=0.0,
                                                 delta=deltas, tile_size=16)).cells()
    tile = datasets.events_tile(cell_list, [pressed_cells[d] for d in deltas], BINS, {})
    study = Study.from_config("random", dict(zeta=0.05, eps=0.5, amplitude=0.0, delta=deltas,
                                             tile_size=16))
    return datasets.aggregate_events([tile], study, {})


def test_the_reports_table_names_the_largest_difference(pressed_cells):
    ev = _events(pressed_cells)
    assert ev["rule_interval_mean"].dims == ("inv_beta", "delta", "rule")
    table = sensitivity.rule_sensitivity(ev, deltas=[-0.5, 0.5])
    assert set(table.statistic) == {"collision rate", "mean velocity after impact",
                                    "mean interval"}
    assert len(table) == 6
    row = table[(table.delta == -0.5) & (table.statistic == "mean interval")].iloc[0]
    cols = list(sensitivity.RULE_NAMES.values())
    values = np.array([row[c] for c in cols])
    assert row[cols[0]] == float(ev.interval_mean.sel(delta=-0.5).squeeze())
    assert row["largest difference"] == pytest.approx(np.max(abs(values[1:] - values[0])))
    assert row["largest difference (%)"] == pytest.approx(
        100 * row["largest difference"] / values[0])
    found = sensitivity.finding_sensitivity(ev)
    assert list(found.finding) == [2, 3]
    assert set(found.columns) >= set(cols)
    assert all(v in ("yes", "partly", "no", "n/a") for c in cols for v in found[c])
    text = found["largest difference at negative play"].iloc[1]
    assert text.startswith("mean interval at delta = ") and "%" in text
    # datasets made before the rules were stored: empty tables, no error
    old = ev.drop_vars([v for v in ev.variables if str(v).startswith("rule")])
    assert sensitivity.rule_sensitivity(old).empty and sensitivity.finding_sensitivity(old).empty
