"""What predicts P (`vibroimpact.reports.predictors`), and the Markov summary of a map
(`vibroimpact.reports.switching`), on small synthetic datasets of the workflow's layout
(docs/datasets.md)."""
import numpy as np
import pytest
import xarray as xr

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


def orbit_map(S11):
    """Fig. 16's orbit map on a grid twice as fine: (1/1) stable where S11 > 0."""
    ib, d = np.linspace(0.5, 2.5, 11), np.linspace(-1.0, 3.0, 15)
    S = np.zeros((3, ib.size, d.size))
    S[0, ::2, ::2] = S11
    return xr.Dataset(dict(S=(("type", *PLANE), S),
                           n_stable=(("type", *PLANE), (S > 0).astype(int))),
                      coords=dict(type=MOTIONS, inv_beta=ib, delta=d))


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
    ranks P best."""
    C = predictors.Correlation
    agreement = {"1/1": dict(n_dominant=40, dominant_inside=0.9, domain_covered=0.8,
                             rank_correlation=0.7)}
    weak = [C("S", "1/1", "domain", 0.7, -0.1, 0.9, 12),
            C("basin", "1/1", "domain", 0.9, 0.8, 0.95, 12),
            C("residence", "1/1", "domain", 0.99, 0.97, 1.0, 12)]
    found = findings.finding8(agreement, predictors=weak)
    assert found.holds == "partly"
    assert "S +0.70 [-0.10, +0.90]" in found.measured
    assert "best noise-free predictor basin" in found.measured
    sure = [C("S", "1/1", "domain", 0.7, 0.5, 0.9, 12)] + weak[1:]
    assert findings.finding8(agreement, predictors=sure).holds == "yes"


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
