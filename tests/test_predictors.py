"""What predicts P (`vibroimpact.reports.predictors`), and the Markov summary of a map
(`vibroimpact.reports.switching`), on small synthetic datasets of the workflow's layout
(docs/datasets.md)."""
import numpy as np
import pytest
import xarray as xr

from vibroimpact.orbits.cells import orbits_at_cells
from vibroimpact.reports import findings, predictors, switching

INV_BETA = np.linspace(0.5, 2.5, 6)
DELTA = np.linspace(-1.0, 3.0, 8)
MOTIONS = ["1/1", "2/1", "1/2"]
STATES = MOTIONS + ["none"]
PLANE = ("inv_beta", "delta")


def _plane(seed):
    return np.random.default_rng(seed).random((INV_BETA.size, DELTA.size))


def _stored(name, values):
    """``values`` over (state, inv_beta, delta) as the map stores them: the motions over
    `motion`, "none" under ``<name>_none``."""
    return {name: (("motion", *PLANE), values[:-1]), f"{name}_none": (PLANE, values[-1])}


def motion_map(p11, seed=0):
    """A map whose (1/1) probability is ``p11`` (the others small and random), with
    residence times and switching of a two-state record in every cell."""
    rng = np.random.default_rng(seed)
    shape = (INV_BETA.size, DELTA.size)
    p = np.stack([p11, 0.2 * rng.random(shape), 0.1 * rng.random(shape)])
    n = np.full((4, *shape), 50)
    t = np.stack([1.0 + 20 * p11, 2 + rng.random(shape), 3 + rng.random(shape),
                  2 + rng.random(shape)])
    rate = np.zeros((4, 4, *shape))
    rate[0, 3], rate[3, 0] = 1.0 / t[0], 1.0 / t[3]
    rate[1:3] = np.nan
    return xr.Dataset(
        dict(probability=(("motion", *PLANE), p),
             probability_stderr=(("motion", *PLANE), np.full(p.shape, 0.01)),
             stick_probability=(("motion", *PLANE), np.zeros(p.shape)),
             stick_probability_stderr=(("motion", *PLANE), np.zeros(p.shape)),
             **_stored("residence_time", t), **_stored("residence_time_stderr", t / np.sqrt(n)),
             **_stored("n_stretches", n), **_stored("n_censored", n * 0 + 2),
             switch_rate=(("from_motion", "to_motion", *PLANE), rate),
             switch_count=(("from_motion", "to_motion", *PLANE),
                           np.where(np.nan_to_num(rate) > 0, 50, 0))),
        coords=dict(motion=MOTIONS, from_motion=STATES, to_motion=STATES,
                    inv_beta=INV_BETA, delta=DELTA))


def orbit_map(S11, inv_beta=INV_BETA, delta=DELTA):
    """The orbits at the map's cells (`predictors.orbits_at_cells`' layout): (1/1) stable
    where S11 > 0."""
    S = np.zeros((3, inv_beta.size, delta.size))
    S[0] = S11
    return xr.Dataset(dict(S=(("type", *PLANE), np.where(S > 0, S, np.nan)),
                           n_stable=(("type", *PLANE), (S > 0).astype(int))),
                      coords=dict(type=MOTIONS, inv_beta=inv_beta, delta=delta))


def basins(fraction11, inv_beta=INV_BETA, delta=DELTA):
    f = np.zeros((4, inv_beta.size, delta.size))
    f[0] = fraction11
    return xr.Dataset(dict(fraction=(("motion", *PLANE), f),
                           n_stable=(("motion", *PLANE), (f > 0).astype(int))),
                      coords=dict(motion=MOTIONS + ["other"], inv_beta=inv_beta, delta=delta))


def lyapunov(values, inv_beta=INV_BETA, delta=DELTA):
    return xr.Dataset(dict(lyapunov=(PLANE, values)),
                      coords=dict(inv_beta=inv_beta, delta=delta))


def _get(found, predictor, motion="1/1", where="plane"):
    return next(c for c in found if (c.predictor, c.motion, c.where) == (predictor, motion,
                                                                         where))


def test_a_planted_monotone_relation_gives_one_with_a_narrow_interval():
    x = _plane(1)
    rho, low, high, n = predictors.rank_correlation(x, x ** 3)
    assert (rho, n) == (pytest.approx(1.0), x.size)
    assert low == pytest.approx(1.0) and high == pytest.approx(1.0)
    rho, low, high, _ = predictors.rank_correlation(x, -np.exp(x))
    assert rho == pytest.approx(-1.0) and high == pytest.approx(-1.0)


def test_noise_gives_an_interval_covering_zero_and_the_seed_fixes_it():
    """Independent values: the 95 % interval covers 0 (seeded); the same seed, the same
    interval; a NaN pair is left out, -inf ranked lowest."""
    x, p = _plane(2).ravel(), _plane(3).ravel()
    rho, low, high, n = predictors.rank_correlation(x, p)
    assert low < 0 < high and abs(rho) < 0.3 and high - low > 0.3
    assert predictors.rank_correlation(x, p) == (rho, low, high, n)
    x[0], x[1] = np.nan, -np.inf
    assert predictors.rank_correlation(x, p)[3] == n - 1
    assert np.isnan(predictors.rank_correlation(x[:4], p[:4])[0])       # too few cells


def test_every_predictor_on_the_map_s_grid_inside_and_over_the_plane():
    """P(1/1) rises with S, the basin and the residence time, falls with the exponent: each
    correlation is +-1; inside the domain only its cells count."""
    x = _plane(4)
    S = np.where(x > 0.3, 100 * x, 0.0)
    found = predictors.predictor_correlations(
        motion_map(x), orbit_map(S), basins(x ** 2), lyapunov(-x))
    assert [c.predictor for c in found[::6]] == list(predictors.PREDICTORS)
    for name, sign in (("basin", 1), ("lyapunov", -1), ("residence", 1)):
        c = _get(found, name)
        assert c.rho == pytest.approx(sign) and c.n_cells == x.size and not c.note
    inside = _get(found, "S", where="domain")
    assert inside.rho == pytest.approx(1.0) and inside.n_cells == (x > 0.3).sum()
    assert _get(found, "basin", where="domain").n_cells == (x > 0.3).sum()
    # (2/1) has no stable cell: its domain rows say why
    assert "fewer than" in _get(found, "S", "2/1", "domain").note
    table = predictors.predictors_table(found)
    assert table.shape[0] == 4 * 3
    assert table.loc[(predictors.PREDICTORS["basin"], "(1/1)"),
                     "whole plane: rho [95 %]"] == "+1.00 [+1.00, +1.00]"


def test_missing_datasets_leave_their_rows_not_available():
    x = _plane(5)
    found = predictors.predictor_correlations(motion_map(x))
    for c in found:
        if c.predictor == "residence" and c.where == "plane":
            assert np.isfinite(c.rho)
        else:
            assert np.isnan(c.rho) and c.note, c
    assert "no orbit map" in _get(found, "S").note
    assert "no attractors dataset" in _get(found, "basin").note
    # without an orbit map the basins' stable cells are the domain
    found = predictors.predictor_correlations(motion_map(x), basins=basins(x))
    assert _get(found, "basin", where="domain").rho == pytest.approx(1.0)


def test_a_basins_grid_other_than_the_map_s_is_refused_by_name():
    x = _plane(6)
    coarse = basins(x[::2], inv_beta=INV_BETA[::2])
    with pytest.raises(ValueError, match=r"basin grid \(1/beta_f 0.5 to 2.1 \(3 values\).*"
                                         r"not the map's \(1/beta_f 0.5 to 2.5 \(6 values\)"):
        predictors.on_map_grid(coarse, motion_map(x), "basin")
    found = predictors.predictor_correlations(
        motion_map(x), basins=coarse, lyapunov=lyapunov(-x, delta=DELTA + 0.05))
    assert "not used: the basin grid" in _get(found, "basin").note
    assert "not used: the lyapunov grid" in _get(found, "lyapunov").note
    assert np.isnan(_get(found, "lyapunov").rho)


def test_finding8_reads_the_interval_of_s_and_names_the_best_noise_free_predictor():
    """S's correlation 0.7 but its interval reaching below 0: partly, not yes; the basin
    ranks P best (its interval clear of S's and of weak)."""
    C = predictors.Correlation
    agreement = {"1/1": dict(n_dominant=40, dominant_inside=0.9, domain_covered=0.8,
                             rank_correlation=0.7)}
    weak = [C("S", "1/1", "domain", 0.7, -0.1, 0.9, 12),
            C("basin", "1/1", "domain", 0.9, 0.8, 0.95, 12),
            C("residence", "1/1", "domain", 0.99, 0.97, 1.0, 12)]
    found = findings.finding8(agreement, predictors=weak)
    assert found.holds == "partly"
    assert "S +0.70 [-0.10, +0.90]" in found.measured
    assert "basin ranks P best among the noise-free predictors (P rises" in found.measured
    sure = [C("S", "1/1", "domain", 0.7, 0.5, 0.9, 12)] + weak[1:]
    assert findings.finding8(agreement, predictors=sure).holds == "yes"


def test_finding8_names_no_best_predictor_where_its_interval_reaches_weak_or_meets_another():
    """The issue's case, S -0.57 [-0.75, -0.26] against an exponent -0.40 [-0.60, -0.15]: S
    has the largest |rho| but its interval reaches a weak |rho| (0.26 < 0.3), and it falls
    as S grows: no best predictor is named, the direction is. Two strong overlapping
    intervals: alike. The share of complex multipliers is said with what it means."""
    C = predictors.Correlation
    agreement = {"2/1": dict(n_dominant=30, dominant_inside=0.9, domain_covered=0.5,
                             rank_correlation=-0.57, complex_share=0.25)}
    case = [C("S", "2/1", "domain", -0.57, -0.75, -0.26, 80),
            C("lyapunov", "2/1", "domain", -0.40, -0.60, -0.15, 80)]
    text = findings.finding8(agreement, predictors=case).measured
    assert "best" not in text
    assert ("no noise-free predictor ranks P clearly: the strongest, S (P falls as S grows, "
            "against the expected direction), has an interval reaching |rho| < 0.3") in text
    assert ("multipliers a complex pair in 25 % of the domain's cells, where S = 100 "
            "(1 - eps exp(-zeta z/m)), z = 2 pi n/beta_f, does not depend on delta: "
            "rho(P, S) cannot rank P along delta there") in text
    alike = [C("S", "2/1", "domain", 0.70, 0.55, 0.82, 80),
             C("basin", "2/1", "domain", 0.60, 0.45, 0.72, 80)]
    text = findings.finding8(agreement, predictors=alike).measured
    assert ("S ranks P most strongly (P rises as S grows), not clearly more than basin (their "
            "95 % intervals overlap)") in text and "best" not in text


def test_markov_summary_judges_the_motions_and_checks_the_bookkeeping():
    """Exponential stays (CV 1 against a Markov CV sqrt(1 - 1/T) near 1) are Markov; "none"
    is shown, not judged; the two-state rates' stationary distribution is the stays' share,
    not the probabilities here, and the caption counts it."""
    m = motion_map(_plane(7))
    table = switching.markov_summary(m)
    assert table.loc["(1/2)", "close to Markov"] == 0            # CV 1 vs sqrt(1 - 2/3.5)
    assert table.loc["(1/2)", "too irregular"] == INV_BETA.size * DELTA.size
    assert table.loc["none", "median Markov CV"] == "not judged"
    assert "in the 48 cells with 10 switches or more" in table.attrs["note"]
    check = switching.stationary_check(m)
    assert check["pi"].shape == (6, 8, 4)
    np.testing.assert_allclose(check["pi"].sum(axis=-1), 1.0)


def test_resampled_ranks_are_scipys_average_ranks_bit_for_bit():
    """The bootstrap ranks each resample by counting its dense codes (O(n) a row) instead of
    sorting it: the same average ranks as scipy's rankdata, exactly, ties and infinities
    included, so every interval the reports print is unchanged."""
    from scipy.stats import rankdata

    from vibroimpact.reports.predictors import _codes, _resample_ranks

    rng = np.random.default_rng(5)
    for n in (5, 64, 2000):
        x = np.round(rng.normal(size=n), 1)          # many ties
        x[::9] = -np.inf
        idx = rng.integers(0, n, size=(30, n))
        np.testing.assert_array_equal(_resample_ranks(_codes(x), idx),
                                      rankdata(x[idx], axis=-1))


def _same(a, b):
    """Two lists of Correlation equal field by field, NaN equal to NaN."""
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert (x.predictor, x.motion, x.where, x.n_cells, x.note) == (
            y.predictor, y.motion, y.where, y.n_cells, y.note)
        for field in ("rho", "low", "high"):
            u, v = getattr(x, field), getattr(y, field)
            assert (np.isnan(u) and np.isnan(v)) or u == v, (x, y)


def test_the_predictors_job_writes_what_the_reports_read_back_value_for_value(tmp_path):
    """Rule map_predictors (`tasks.map_predictors`) computes the correlations once; the
    reports read them from its dataset (`notebook.predictors`): the same Correlation list,
    bit for bit, its rows not computed (NaN, with the reason) included, in the same order."""
    from vibroimpact.pipeline import tasks
    from vibroimpact.reports import notebook

    x = _plane(7)
    paths = {}
    for name, ds in (("map", motion_map(x)), ("orbits", orbit_map(np.where(x > 0.3, x, 0))),
                     ("basins", basins(x[::2], inv_beta=INV_BETA[::2]))):   # refused grid
        paths[name] = tmp_path / f"{name}.nc"
        ds.to_netcdf(paths[name])
    out = tmp_path / "predictors.nc"
    tasks.map_predictors(paths["map"], out, paths["orbits"], paths["basins"], None)
    expected = predictors.predictor_correlations(
        motion_map(x), orbit_map(np.where(x > 0.3, x, 0)), basins(x[::2], INV_BETA[::2]))
    got = notebook.predictors(str(out))
    _same(got, expected)
    assert any(np.isnan(c.rho) and "not used: the basin grid" in c.note for c in got)
    assert any(np.isfinite(c.rho) for c in got)
    assert predictors.predictors_table(got).equals(predictors.predictors_table(expected))
    assert notebook.predictors("") is None
    ds = xr.load_dataset(out)
    assert ds.attrs["n_resamples"] == predictors.N_RESAMPLES and "git_commit" in ds.attrs
    with pytest.raises(ValueError, match="not a predictors dataset: no variable note"):
        predictors.read_correlations(ds.drop_vars("note"))


def fig16(inv_beta, delta, types=((1, 1), (2, 1), (1, 2)), zeta=0.05, eps=0.5):
    """A Fig. 16 orbit map as rule aggregate_orbits writes it (`orbit_map`, attrs zeta, eps,
    amplitude)."""
    from vibroimpact.orbits import orbit_map as solve
    from vibroimpact.pipeline import datasets

    return datasets.orbit_map_dataset(solve(inv_beta, delta, types=types, zeta=zeta, eps=eps),
                                      dict(zeta=zeta, eps=eps, amplitude=1.0))


def probability_map(inv_beta, delta, seed=0, attrs=None, axes=PLANE):
    """A map of the three motions' P (random) over ``axes``."""
    p = np.random.default_rng(seed).random((3, inv_beta.size, delta.size))
    return xr.Dataset(dict(probability=(("motion", *axes), p)),
                      coords={"motion": MOTIONS, axes[0]: inv_beta, axes[1]: delta},
                      attrs=attrs or {})


#: Rows and plays of Fig. 15's map (steps 0.05) where its cells sit halfway between Fig.
#: 16's (steps 0.02): 1/beta_f = 1.05 between 1.04 and 1.06, delta = -0.45 ... 2.95 likewise.
TIE_ROWS = np.array([0.95, 1.05, 1.1, 2.05])
TIE_PLAYS = np.round(np.arange(-1.45, 3.0, 0.1), 10)


def test_the_orbits_of_a_map_cell_are_those_of_its_own_centre():
    """`orbits_at_cells`: at every cell and type, the stable orbits and S are those
    `periodic_orbits` finds at the cell's own (1/beta_f, delta), to 1e-9 in S (Newton
    converged to ~1e-12 on either side; the scan and the followed branch find the same
    orbits); Fig. 16's nearest cell (a tie between two) gives another S at some of them, so
    a lookup that broke the tie would fail here. Where the flag says the multipliers are a
    complex pair, S is the closed form 100 (1 - eps exp(-zeta z / m)), z = 2 pi n / beta_f,
    of |mu|^2 = det T = eps^(2m) exp(-2 zeta z) (the flow's determinant times eps^2 per
    impact): the same along a row; where they are real, S is below it."""
    from vibroimpact.orbits import periodic_orbits

    grid = probability_map(TIE_ROWS, TIE_PLAYS)
    fine = fig16(np.round(np.arange(0.94, 2.07, 0.02), 10),
                 np.round(np.arange(-1.5, 3.01, 0.02), 10))
    at = orbits_at_cells(grid, fine)
    assert list(at["type"].values) == MOTIONS
    differs, flagged = 0, {0: 0, 1: 0}
    for t in MOTIONS:
        m, n = (int(v) for v in t.split("/"))
        near = fine.sel(type=t).sel(inv_beta=grid.inv_beta, delta=grid.delta,
                                    method="nearest")
        for i, ib in enumerate(TIE_ROWS):
            for j, d in enumerate(TIE_PLAYS):
                cell = at.sel(type=t).isel(inv_beta=i, delta=j)
                stable = [o for o in periodic_orbits(m, n, 1 / ib, d, 0.05, 0.5) if o.stable]
                assert int(cell.n_stable) == len(stable), (t, ib, d)
                if not stable:
                    assert np.isnan(float(cell.S)) and int(cell.complex) == -1
                    continue
                S = float(cell.S)
                assert S == pytest.approx(max(o.S for o in stable), abs=1e-9), (t, ib, d)
                old = float(near.S[i, j]) if int(near.n_stable[i, j]) > 0 else 0.0
                differs += abs(old - S) > 1e-3
                closed = 100 * (1 - 0.5 * np.exp(-0.05 * 2 * np.pi * n * ib / m))
                flag = int(cell.complex)
                flagged[flag] += 1
                if flag == 1:
                    assert S == pytest.approx(closed, abs=1e-9), (t, ib, d)
                else:
                    assert flag == 0 and S < closed + 1e-9, (t, ib, d)
    assert differs > 10 and flagged[0] > 10 and flagged[1] > 10, (differs, flagged)


def test_finding8_and_the_predictors_table_count_the_same_cells(tmp_path):
    """Rule solve_map_orbits writes the orbits at the map's cells (`tasks.map_orbits`); the
    predictors job correlates with them and finding 8 reads them: each motion's stable
    domain has as many cells in the agreement (Fig. 15 against Fig. 16) as in the
    predictors table's S row, and the complex share is that of the stored flags."""
    from vibroimpact.pipeline import tasks
    from vibroimpact.reports import notebook

    grid = probability_map(TIE_ROWS, TIE_PLAYS, seed=3)
    paths = {"map": tmp_path / "map.nc", "orbits": tmp_path / "orbits.nc",
             "cells": tmp_path / "map_orbits.nc"}
    grid.to_netcdf(paths["map"])
    fig16(np.round(np.arange(0.94, 2.07, 0.02), 10),
          np.round(np.arange(-1.5, 3.01, 0.02), 10)).to_netcdf(paths["orbits"])
    tasks.map_orbits(paths["map"], paths["orbits"], paths["cells"])
    out = tmp_path / "predictors.nc"
    tasks.map_predictors(paths["map"], out, paths["cells"], None, None)
    stored = notebook.open_dataset(str(paths["cells"]))
    assert "git_commit" in stored.attrs
    agreement = notebook.map_agreement(grid, stored)
    found = notebook.predictors(str(out))
    for t in MOTIONS:
        domain = int((stored["n_stable"].sel(type=t) > 0).sum())
        assert domain >= MIN_DOMAIN_CELLS
        assert agreement[t]["n_domain"] == _get(found, "S", t, "domain").n_cells == domain
        flags = stored["complex"].sel(type=t).values[stored["n_stable"].sel(type=t) > 0]
        assert agreement[t]["complex_share"] == pytest.approx((flags == 1).mean())
    # an orbit map on another grid than the map's is never read at a nearby cell
    found = predictors.predictor_correlations(
        grid, fig16(np.round(np.arange(0.94, 2.07, 0.02), 10), TIE_PLAYS))
    assert "not used: the orbits grid" in _get(found, "S", where="domain").note
    with pytest.raises(ValueError, match="the orbits grid"):
        notebook.map_agreement(grid, fig16(TIE_ROWS[:2], TIE_PLAYS))


#: Fewest stable cells a motion of `TIE_ROWS` x `TIE_PLAYS` has (measured: (2/1) has 8).
MIN_DOMAIN_CELLS = 5


def test_a_two_wall_orbit_map_is_read_at_the_map_s_cells_or_refused():
    """Two walls (the shooting solver, seeded by the simulator, is not rerun): the orbit
    map's values at the map's own cells, or a ValueError when a map cell is not one of its
    cells."""
    ib, d = np.array([0.5, 0.75, 1.0]), np.array([0.0, 0.25, 0.5, 0.75])
    types = ["(1,1)/1", "(1,0)/1"]
    rng = np.random.default_rng(4)
    S = 100 * rng.random((2, ib.size, d.size))
    n_stable = (S > 40).astype(int)
    orbits = xr.Dataset(dict(S=(("type", *PLANE), S), n_stable=(("type", *PLANE), n_stable)),
                        coords=dict(type=types, inv_beta=ib, delta=d),
                        attrs=dict(zeta=0.05, eps=0.5, amplitude=1.0, gap=2.0,
                                   eps_lower=0.5))
    grid = xr.Dataset(dict(probability=(("motion", *PLANE), rng.random((2, 2, 3)))),
                      coords=dict(motion=types, inv_beta=ib[1:], delta=d[1:]))
    at = orbits_at_cells(grid, orbits)
    np.testing.assert_array_equal(at["n_stable"].values, n_stable[:, 1:, 1:])
    np.testing.assert_array_equal(at["S"].values, np.where(n_stable > 0, S, np.nan)[:, 1:, 1:])
    assert (at["complex"].values == -1).all()
    off = grid.assign_coords(delta=d[1:] + 0.1)
    with pytest.raises(ValueError,
                       match=r"two-wall orbit map.s cells nearest .* are not the map.s"):
        orbits_at_cells(off, orbits)


def test_a_named_plane_s_orbits_and_attractors_on_its_own_axes():
    """A map over (eps, delta) (the planes example's restitution study): the orbits solved
    at its cells with the orbit map's fixed values are `periodic_orbits`' there; its own
    basins and exponents, on the same (eps, delta) cells, are used (not refused for want of
    an inv_beta axis)."""
    from vibroimpact.orbits import periodic_orbits
    from vibroimpact.orbits.plane import orbit_plane

    eps, delta = np.array([0.3, 0.5]), np.array([-0.75, 0.25, 1.25, 2.25])
    axes = ("eps", "delta")
    fixed = dict(zeta=0.05, inv_beta=1.1, amplitude=1.0)
    orbits = orbit_plane("eps", np.arange(0.1, 0.91, 0.02), "delta",
                         np.arange(-1.0, 3.01, 0.02), fixed)
    grid = probability_map(eps, delta, attrs=dict(axes='["eps", "delta"]'), axes=axes)
    at = orbits_at_cells(grid, orbits)
    for i, e in enumerate(eps):
        for j, d in enumerate(delta):
            stable = [o for o in periodic_orbits(1, 1, 1 / 1.1, d, 0.05, e) if o.stable]
            cell = at.sel(type="1/1").isel(eps=i, delta=j)
            assert int(cell.n_stable) == len(stable)
            if stable:
                assert float(cell.S) == pytest.approx(max(o.S for o in stable), abs=1e-9)
    f = np.random.default_rng(5).random((4, eps.size, delta.size))
    own = xr.Dataset(dict(fraction=(("motion", *axes), f), n_stable=(("motion", *axes), f > 0.5)),
                     coords=dict(motion=MOTIONS + ["other"], eps=eps, delta=delta))
    found = predictors.predictor_correlations(grid, at, basins=own)
    c = _get(found, "basin")
    assert np.isfinite(c.rho) and c.n_cells == eps.size * delta.size and not c.note
