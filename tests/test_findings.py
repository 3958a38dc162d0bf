"""The findings table of the reports (vibroimpact.reports.findings) follows the data.

Each finding is measured on small datasets of the workflow's layout (docs/datasets.md) built
here with the behaviour the paper describes, then on the same datasets altered so that the
claim fails: the verdict must change with the data. The end-to-end check on a real build is in
tests/test_reports.py.
"""
import numpy as np
import pytest
import xarray as xr

from vibroimpact.reports import findings, sensitivity, two_walls

DELTA = np.array([-1.0, -0.5, 0.0, 0.5, 1.0, 2.0, 3.0])


def random_events(v=None, z=None, rate=None):
    """One 1/beta row of a random-force events dataset: means rising with delta."""
    v = np.array([0.01, 0.03, 0.12, 0.3, 0.45, 0.6, 0.7]) if v is None else v
    z = np.array([0.4, 0.35, 1.0, 3.0, 8.0, 40.0, 300.0]) if z is None else z
    rate = np.array([3.0, 2.9, 1.0, 0.3, 0.1, 0.01, 0.001]) if rate is None else rate
    n = np.full(DELTA.size, 50_000)
    data = dict(v_after_mean=v, interval_mean=z, collision_rate=rate, n_collisions=n,
                contact_fraction=np.array([0.9, 0.6, 0, 0, 0, 0, 0.0]))
    return xr.Dataset({k: (("inv_beta", "delta"), np.asarray(x, float)[None])
                       for k, x in data.items()}, coords=dict(inv_beta=[1.0], delta=DELTA))


def random_spectra(peaks=(1.0, 1.2, 1.4), levels=(20.0, 5.0, 2.0), flat_at_zero=True):
    beta = np.linspace(0.0, 4.0, 401)
    deltas = np.array([0.0, 3.0, 1.0, 0.5])
    S = []
    for d in deltas:
        if d == 0.0:
            S.append(1.0 + (0.0 if flat_at_zero else 5.0) * np.exp(-((beta - 2.0) / 0.05) ** 2))
        else:
            k = {3.0: 0, 1.0: 1, 0.5: 2}[d]
            S.append(0.1 + levels[k] * np.exp(-((beta - peaks[k]) / 0.1) ** 2))
    return xr.Dataset({"S_a": (("inv_beta", "delta", "beta"), np.array(S)[None])},
                      coords=dict(inv_beta=[1.0], delta=deltas, beta=beta))


def test_findings_1_to_4_hold_on_the_papers_behaviour():
    verdicts = [f.holds for f in findings.random_force(random_events(), random_spectra())]
    assert verdicts == ["yes", "yes", "partly", "yes"]   # 3: the interval rises again below -0.5


@pytest.mark.parametrize("change, number", [
    (dict(v=np.array([0.01, 0.03, 0.12, 0.3, 0.25, 0.6, 0.7])), 2),      # not monotone
    (dict(v=np.array([0.3, 0.35, 0.4, 0.5, 0.6, 0.7, 0.8])), 2),         # not marked below 0
    (dict(z=np.array([0.4, 0.35, 1.0, 3.0, 2.0, 40.0, 300.0])), 3),
    (dict(rate=np.array([3.0, 2.9, 1.0, 0.3, 0.5, 0.01, 0.001])), 4),   # rises at delta = 1
    (dict(rate=np.array([3.0, 2.9, 1.0, 0.9, 0.8, 0.7, 0.6])), 4),      # falls < 2 orders
])
def test_findings_1_to_4_fail_when_the_data_contradict_them(change, number):
    found = {f.number: f for f in findings.random_force(random_events(**change), None)}
    assert found[number].holds == "no", found[number].measured
    assert found[1].holds == "n/a" and "spectrum" in found[1].measured


def test_finding1_fails_with_a_falling_peak_frequency_or_a_peak_at_zero():
    assert findings.finding1(random_spectra(peaks=(1.4, 1.2, 1.0))).holds == "no"
    assert findings.finding1(random_spectra(flat_at_zero=False)).holds == "no"


def harmonic_events(p11=(0.0, 0.1, 0.2, 0.9, 0.95, 0.6, 0.3), p21=(0.0, 0.7, 0.8, 0.05, 0, 0, 0),
                    cv=(1.5, 0.7, 0.6, 0.2, 0.15, 0.2, 0.22)):
    """One row at 1/beta_f = 1.1: (2/1) at small plays, (1/1) at large ones."""
    ratio = np.linspace(0.0125, 3.9875, 160)
    v = np.linspace(0.0125, 4.9875, 200)
    dens_r, dens_v = [], []
    for a, b, c in zip(p11, p21, cv):
        peak_11 = a * np.exp(-((ratio - 1.0) / 0.03) ** 2)
        peak_21 = b * (np.exp(-((ratio - 0.3) / 0.03) ** 2) + np.exp(-((ratio - 0.7) / 0.03) ** 2))
        dens_r.append(peak_11 + peak_21 + 1e-3)
        dens_v.append(np.exp(-0.5 * ((v - 2.0) / (2.0 * c)) ** 2))
    p = np.stack([p11, p21, np.zeros(DELTA.size)], axis=-1)
    ds = xr.Dataset(
        {"n_collisions": (("inv_beta", "delta"), np.full((1, DELTA.size), 10_000)),
         "ratio_density": (("inv_beta", "delta", "ratio"), np.array(dens_r)[None]),
         "v_after_density": (("inv_beta", "delta", "v_after"), np.array(dens_v)[None]),
         "motion_probability": (("inv_beta", "delta", "motion"), p[None])},
        coords=dict(inv_beta=[1.1], delta=DELTA, ratio=ratio, v_after=v,
                    motion=["1/1", "2/1", "1/2"]))
    return ds


def test_findings_6_and_7_hold_and_fail_with_the_data():
    assert findings.finding6(harmonic_events()).holds == "yes"
    assert findings.finding7(harmonic_events()).holds == "yes"
    no_21 = harmonic_events(p21=(0, 0.2, 0.3, 0.05, 0, 0, 0))        # (2/1) never dominant
    assert findings.finding6(no_21).holds == "no"
    wide = harmonic_events(cv=(0.3, 0.3, 0.35, 0.6, 0.7, 0.6, 0.4))   # widest where (1/1) is
    assert findings.finding7(wide).holds == "no"
    # narrow where (1/1) dominates, but wide at the largest play, where it does not
    wide_large = harmonic_events(cv=(1.5, 0.7, 0.6, 0.2, 0.15, 0.2, 0.6))
    found = findings.finding7(wide_large)
    assert found.holds == "partly" and f"wide at delta = {DELTA[-1]:.3g}," in found.measured
    # read only over the plays a figure draws: without the largest, it holds
    assert findings.finding7(wide_large, deltas=DELTA[:-1]).holds == "yes"


def test_finding8_where_and_how_strongly():
    inside = dict(n_dominant=40, dominant_inside=0.9, domain_covered=0.8, rank_correlation=0.1)
    assert findings.finding8({"1/1": inside}).holds == "partly"
    assert findings.finding8({"1/1": dict(inside, rank_correlation=0.7)}).holds == "yes"
    assert findings.finding8({"1/1": dict(inside, dominant_inside=0.3)}).holds == "no"
    assert findings.finding8({"1/1": dict(inside, n_dominant=2)}).holds == "n/a"


def test_every_partly_verdict_opens_with_what_holds_and_what_not():
    """The summary sentence is computed from the data: its numbers are the dataset's."""
    found = findings.finding3(random_events())
    assert found.holds == "partly"
    assert found.summary == ("Holds: the mean interval grows with delta from delta = -0.5 up "
                             "(0.35 -> 300); does not: below delta = -0.5 it grows again as "
                             "delta falls (to 0.4 at delta = -1), where the mass rests on the "
                             "wall for a fraction 0.90 of the time.")
    wide_large = findings.finding7(harmonic_events(cv=(1.5, 0.7, 0.6, 0.2, 0.15, 0.2, 0.6)))
    assert wide_large.summary.startswith("Holds: the spread of the velocity after impact falls")
    cv = findings._cv(harmonic_events(cv=(1.5, 0.7, 0.6, 0.2, 0.15, 0.2, 0.6)).isel(inv_beta=0),
                      3.0)                                   # the density's, truncated at v = 0
    assert f"does not: it is wide (CV {cv:.2f} >= " in wide_large.summary
    assert "at delta = 3, where P(1/1) = 0.30" in wide_large.summary
    inside = dict(n_dominant=40, dominant_inside=0.9, domain_covered=0.8, rank_correlation=0.1)
    two = {"1/1": inside, "2/1": dict(inside, dominant_inside=0.8, rank_correlation=0.7)}
    found = findings.finding8(two)
    assert found.holds == "partly"
    assert found.summary == ("Holds: the domains agree: 80-90 % of the cells where a motion has "
                             "P >= 50 % lie inside its stable domain (>= 75 % asked); does not: "
                             "S does not rank P inside them (rho = 0.10 for (1/1); >= 0.5 "
                             "asked).")
    assert findings.finding8({"1/1": dict(inside, rank_correlation=0.7)}).summary == ""
    no = findings.finding8({"1/1": dict(inside, dominant_inside=0.3)})
    assert no.summary.startswith("Does not hold: the domains do not agree: of the cells")
    # the table opens the measured cell with it
    table = findings.findings_table([found])
    assert table.loc[8, "measured"].startswith(found.summary + " (1/1) 40 cells")


def harmonic_spectra(plays, inv_beta=1.1):
    """One 1/beta_f row of a harmonic spectra dataset from Welch estimates with batches
    (tests/test_centroid.py's records: ``{delta: (resonance, line amplitude)}``), its input
    a line of power 0.5 over a weak random part."""
    from test_centroid import spectra_row

    row = spectra_row(plays)
    spectra = xr.concat([row], dim="inv_beta").assign_coords(inv_beta=[inv_beta])
    spectra["S_f"] = (("inv_beta", "beta"), np.full((1, row.beta.size), 1e-4))
    return spectra


def test_finding5_reads_the_broadband_not_the_lines():
    """The study's case: the broadband resonance moves down (1.3 -> 1.0) as delta falls,
    while the line at beta_f, strong at the large play and weak at the small one, makes the
    centroid with the lines rise. Finding 5 reads the broadband (it holds), and gives both
    readings. Counting the lines (the earlier measure) would print the contradiction."""
    spectra = harmonic_spectra({2.0: (1.3, 1.7), 1.0: (1.2, 0.8), -0.5: (1.0, 0.2)})
    found = findings.finding5(spectra)
    assert found.holds == "yes", found.measured
    table = findings.finding5_readings(spectra).set_index("delta")
    with_lines = table["centroid with the lines (beta <= 3)"]
    assert with_lines[-0.5] > with_lines[2.0]                # the lines' reading rises
    assert table["broadband centroid"][-0.5] < table["broadband centroid"][2.0] - 0.1
    assert (f"with the lines {with_lines[2.0]:.2f} -> {with_lines[-0.5]:.2f}; broadband "
            f"{table['broadband centroid'][2.0]:.2f} [" in found.measured)
    assert "opposite" not in found.measured + found.summary
    choices = findings.finding5_choices(spectra)
    assert len(choices) == 18 and set(choices.reads) == {"falls"}
    main = choices[(choices["half-width (bins)"] == 5) & (choices["beta <="] == 3.0)
                   & (choices["lines' bins"] == "bridged")].iloc[0]
    assert main["centroid at delta = 2"] == pytest.approx(table["broadband centroid"][2.0])
    assert main["change"] == pytest.approx(main["at delta = -0.5"] - main["centroid at delta = 2"])


def test_finding5_prints_a_contradiction_only_under_every_choice():
    """A broadband that rises under every choice: "partly", against the paper, named with its
    centroids. One that does not move (the same resonance on other noise): not resolved, and
    no contradiction printed."""
    rises = findings.finding5(harmonic_spectra({2.0: (1.0, 1.7), -0.5: (1.3, 0.2)}))
    assert rises.holds == "partly", rises.measured
    assert ("the broadband response moves to higher frequency, opposite to the paper"
            in rises.summary)
    assert "under every choice of half-width 3, 5, 8 bins x beta <= 2, 3, 4" in rises.summary
    still = findings.finding5(harmonic_spectra({2.0: (1.2, 1.7), -0.5: (1.2, 0.2)}))
    assert still.holds == "partly" and "opposite" not in still.summary + still.measured
    assert "the broadband centroid's move is not resolved" in still.summary
    # without batch spectra: no interval, so no verdict on the move either way
    bare = harmonic_spectra({2.0: (1.0, 1.7), -0.5: (1.3, 0.2)}).drop_vars("S_a_batch")
    found = findings.finding5(bare)
    assert "opposite" not in found.summary and "no batch spectra" in found.measured


def test_the_table_has_one_row_per_finding_with_claim_measure_and_verdict():
    table = findings.findings_table(findings.random_force(random_events(), random_spectra()))
    assert list(table.index) == [1, 2, 3, 4]
    assert list(table.columns) == ["claim", "measured", "holds"]
    assert "0.45" in table.loc[2, "measured"] or "0.7" in table.loc[2, "measured"]


def test_finding4_tells_the_reach_of_a_record_from_a_threshold():
    """Impacts that stop where Rice's rate expects < 3 in the record are its reach ("partly");
    stopping where it expects many would be a threshold the Gaussian response does not have."""
    events = random_events(rate=np.array([3.0, 2.9, 1.0, 0.3, 0.1, 0.01, 0.0]))
    events["n_collisions"][0, -1] = 0                        # none at delta = 3
    assert findings.finding4(events).holds == "yes"         # no theory attached: only the fall
    sigma = 0.6
    # Rice: nu+(3) = exp(-3^2 / 2 sigma^2) / 2 pi = 5.9e-7 for sigma_x = sigma_v = 0.6
    nu = np.exp(-9.0 / (2 * sigma**2)) / (2 * np.pi)
    reach = events.assign_attrs(linear_sigma_x=sigma, linear_sigma_v=sigma,
                                record_length=1.0 / nu)     # one expected in the record
    found = findings.finding4(reach)
    assert found.holds == "partly" and "an expected 1 up-crossings" in found.measured
    # the rate and the count it gives, each with its unit
    assert f"{nu:.3g} per unit time at delta = 3" in found.measured
    assert "by 2.5 orders of magnitude" in found.summary       # 3 / 0.01: the last rate > 0
    assert found.summary.startswith("Holds: ") and "does not: a critical delta" in found.summary
    threshold = reach.assign_attrs(record_length=100.0 / nu)   # 100 expected, none seen
    assert findings.finding4(threshold).holds == "yes"


def test_finding2_with_plastic_impact_is_not_available():
    """eps = 0 (allowed: plastic impact): every mean velocity after impact is 0; finding 2
    (velocities fall as delta decreases) has nothing to compare, not a division by 0."""
    result = findings.finding2(random_events(v=np.zeros(DELTA.size)))
    assert result.holds == "n/a"
    assert "eps = 0" in result.measured
    # a play whose mean is 0 among positive ones: the slope comparison is skipped, the
    # monotonicity still decides
    v = np.array([0.0, 0.03, 0.12, 0.3, 0.45, 0.6, 0.7])
    assert findings.finding2(random_events(v=v)).holds == "yes"


# --- a two-wall study: its own checks in place of findings 1-7 ---------------------------------

WALL_DELTA = np.array([0.0, 0.5, 1.0, 1.5, 2.0, 2.5])


def two_wall_events(eps_lower=0.5):
    """A two-wall events dataset (gap 2, restitution 0.5 above, ``eps_lower`` below), mirror
    symmetric: the upper wall at delta behaves as the lower wall at 2 - delta; intervals
    +-2 %."""
    rate_upper = np.array([0.30, 0.18, 0.17, 0.06, 0.003, 0.0])
    v_upper = np.array([0.65, 0.90, 0.56, 0.35, 0.29, np.nan])
    # the lower wall at delta is the upper at 2 - delta (2.5 has no mirror in the grid)
    mirror = {0.0: 4, 0.5: 3, 1.0: 2, 1.5: 1, 2.0: 0}
    rate_lower = np.array([rate_upper[mirror[d]] if d in mirror else 0.34 for d in WALL_DELTA])
    v_lower = np.array([v_upper[mirror[d]] if d in mirror else 0.4 for d in WALL_DELTA])
    rate = np.stack([rate_upper, rate_lower], axis=-1)[None]
    v = np.stack([v_upper, v_lower], axis=-1)[None]
    n = np.rint(rate * 20000).astype(int)
    dims = ("inv_beta", "delta", "wall")
    data = {"wall_collision_rate": rate, "wall_collision_rate_lo": 0.98 * rate,
            "wall_collision_rate_hi": 1.02 * rate, "wall_v_after_mean": v,
            "wall_v_after_mean_lo": 0.98 * v, "wall_v_after_mean_hi": 1.02 * v,
            "wall_n_collisions": n,
            "wall_interval_mean": np.divide(1.0, rate, where=rate > 0,
                                            out=np.full_like(rate, np.inf)),
            "wall_stuck_fraction": 0 * rate}
    ds = xr.Dataset({k: (dims, x) for k, x in data.items()},
                    coords=dict(inv_beta=[1.1], delta=WALL_DELTA, wall=["upper", "lower"]),
                    attrs=dict(n_walls=2, gap=2.0, eps=0.5, eps_lower=eps_lower))
    ds["n_collisions"] = ds.wall_n_collisions.sum("wall")
    return ds


def test_two_wall_study_gets_no_verdict_on_the_papers_play():
    """Findings 1-7 compare plays of the paper's one wall: on a two-wall dataset each is n/a
    and says why; the collision-rule table does not re-read findings 2 and 3 there."""
    events = two_wall_events().assign(v_after_mean=lambda d: d.wall_v_after_mean.mean("wall"))
    spectra = harmonic_spectra({2.0: (1.3, 1.7), -0.5: (1.0, 0.2)}).assign_attrs(
        n_walls=2, gap=2.0)
    found = (findings.random_force(events=events, spectra=spectra)
             + findings.harmonic_random(events=events, spectra=spectra)[:3])
    assert [f.number for f in found] == [1, 2, 3, 4, 5, 6, 7]
    assert all(f.holds == "n/a" and "two-wall study" in f.measured
               and "mirror images" in f.measured for f in found), found
    assert sensitivity.finding_sensitivity(events.assign_coords(rule=["physical"])).empty


def test_mirror_check_names_the_pairs_and_what_disagrees():
    events = two_wall_events()
    assert two_walls.mirror_pairs(events) == [(0.0, 2.0), (0.5, 1.5), (1.0, 1.0)]
    agree = two_walls.mirror_check(events)
    assert agree.holds == "yes", agree.measured
    assert "mirror pairs delta = 0 and 2, delta = 0.5 and 1.5, delta = 1 (its two walls)" \
        in agree.measured
    # rows: (0, 2) and (0.5, 1.5) each wall both ways; delta = 2 lower-rate 0.003 x 20000 =
    # 60 collisions < 1000 leaves (0, upper)-(2, lower) in, (0, lower)-(2, upper) out
    table = two_walls.mirror_table(events)
    assert len(table) == 2 * (1 + 2 + 1) and table.agree.all()
    # the upper wall at 0.5 faster by 10 %: its mirror (the lower wall at 1.5) disagrees
    broken = two_wall_events().copy(deep=True)
    broken["wall_v_after_mean"].loc[dict(delta=0.5, wall="upper")] = 0.99
    for bound, factor in (("wall_v_after_mean_lo", 0.98), ("wall_v_after_mean_hi", 1.02)):
        broken[bound].loc[dict(delta=0.5, wall="upper")] = 0.99 * factor
    found = two_walls.mirror_check(broken)
    assert found.holds == "partly" and "7 of 8 mirror comparisons agree" in found.summary
    assert ("mean velocity after impact at delta = 0.5 (upper): 0.99 [0.97, 1.01] against "
            "0.9 [0.882, 0.918] at delta = 1.5 (lower)") in found.measured
    # no mirror image without one restitution
    assert two_walls.mirror_check(two_wall_events(eps_lower=0.8)).holds == "n/a"
    assert "restitutions differ" in two_walls.mirror_check(two_wall_events(eps_lower=0.8)).measured
    rows = two_walls.per_wall(events)
    assert len(rows) == 2 * WALL_DELTA.size and set(rows.wall) == {"upper", "lower"}


def test_mirror_check_on_a_map_swaps_the_motions_walls():
    """On a map, P((1,0)/1) at delta is compared with P((0,1)/1) at gap - delta; a
    probability with no error (never seen) is not compared."""
    motions = ["(1,1)/1", "(1,0)/1", "(0,1)/1"]
    delta = np.array([0.0, 1.0, 2.0])
    p = np.array([[0.2, 0.9, 0.2], [0.7, 0.05, 0.0], [0.0, 0.05, 0.7]])[:, None, :]
    se = np.where(p > 0, 0.01, 0.0)
    ds = xr.Dataset({"probability": (("motion", "inv_beta", "delta"), p),
                     "probability_stderr": (("motion", "inv_beta", "delta"), se)},
                    coords=dict(motion=motions, inv_beta=[1.0], delta=delta),
                    attrs=dict(n_walls=2, gap=2.0, eps=0.5, eps_lower=0.5))
    table = two_walls.map_mirror_table(ds)
    assert set(table.statistic) == {"P((1,1)/1)", "P((1,0)/1) against P((0,1)/1)"}
    assert table.agree.all() and len(table) == 3     # (1,1)/1 at 0-2; (1,0)/(0,1) at 0-2, 1-1
    # the same plane written [delta, inv_beta] (a plane study's axes, either order)
    swapped = ds.transpose("motion", "delta", "inv_beta").assign_attrs(axes=["delta", "inv_beta"])
    assert two_walls.map_mirror_table(swapped).equals(table)
    assert two_walls.mirror_check(motion_map=swapped).holds == "yes"
    ds["probability"].loc[dict(motion="(0,1)/1", delta=2.0)] = 0.5
    found = two_walls.mirror_check(motion_map=ds)
    assert found.holds == "no"                       # 2 of 3 agree (< 3 in 4)
    assert "P((1,0)/1) against P((0,1)/1) at delta = 0: 0.7" in found.measured


def test_mirror_check_on_a_map_over_another_plane_says_why_not():
    """A two-wall map over (zeta, eps_lower) has no plays to pair (eps_lower an axis, not an
    attribute): n/a, naming its plane (it raised KeyError in the report)."""
    ds = xr.Dataset({"probability": (("motion", "zeta", "eps_lower"), np.full((1, 2, 2), 0.5)),
                     "probability_stderr": (("motion", "zeta", "eps_lower"),
                                            np.full((1, 2, 2), 0.01))},
                    coords=dict(motion=["(1,1)/1"], zeta=[0.03, 0.05], eps_lower=[0.3, 0.5]),
                    attrs=dict(n_walls=2, gap=4.0, eps=0.5, delta=1.0, inv_beta=1.1,
                               axes=["zeta", "eps_lower"]))
    found = two_walls.mirror_check(motion_map=ds)
    assert found.holds == "n/a" and "over (zeta, eps_lower)" in found.measured
    assert two_walls.mirror_pairs(ds) == [] and two_walls.map_mirror_table(ds).empty


def test_a_two_wall_report_over_a_gap_axis(monkeypatch):
    """The report's two-wall section on a map over (delta, gap): the gap is an axis, not an
    attribute; the section says so and the mirror check is n/a (it raised KeyError 'gap')."""
    from vibroimpact.reports import notebook as nb

    shape = (1, 2, 2)
    ds = xr.Dataset({"probability": (("motion", "delta", "gap"), np.full(shape, 0.5)),
                     "probability_stderr": (("motion", "delta", "gap"), np.full(shape, 0.01))},
                    coords=dict(motion=["(1/1)"], delta=[0.0, 1.0], gap=[4.0, 5.0]),
                    attrs=dict(n_walls=2, eps=0.5, eps_lower=0.5, inv_beta=1.1,
                               axes=["delta", "gap"]))
    shown = []
    monkeypatch.setattr("IPython.display.display", lambda *objs: shown.extend(objs))
    nb.two_wall_checks(motion_map=ds)
    out = " ".join(o.data.to_csv() if hasattr(o.data, "to_csv") else str(o.data)
                   for o in shown)          # Markdown's text, a table's frame
    assert "gap (an axis of the map, 4 to 5)" in out and "runs over (delta, gap)" in out
