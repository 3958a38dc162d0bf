"""Cell statistics against linear theory: with the wall out of reach the simulated PSD of
a(tau) is the linear |H|^2 S_f of the piecewise-linear input (docs/model.md, section 7)."""
import logging

import numpy as np
import pytest

from vibroimpact import Model, noise, stats
from vibroimpact.pipeline import cells, datasets
from vibroimpact.pipeline.study import Study


def test_psd_without_impacts_is_linear_response():
    """Near-white input (dt = 0.05, flat to beta_c = 8, far above the resonance). Welch with
    K segments has a relative standard error ~1.03/sqrt(K) per bin; averaged over the 10
    bins around each beta checked (correlated by the Hann window, so ~5 independent), the
    tolerance is 5 standard errors of that average plus 2 % for the spectral leakage at the
    resonance peak (half-width zeta = 0.05 spans ~2.5 bins of 0.02)."""
    spec = noise.NoiseSpec(kind="band_limited", rms=1.0, dt=0.05, beta_c=8.0)
    r = noise.generate_array(spec, 2_000_001, seed=7)
    out = cells.spectra_statistics(r, spec.dt, Model.paper(0.05, 0.5, 1e3), transient=200.0,
                                   nperseg=8192)
    beta, S_a = out["beta"], out["S_a"]
    S_lin = stats.linear_psd_response(beta, spec.psd_piecewise_linear(beta), 0.05)
    rel_se = 1.03 / np.sqrt(out["n_segments"]) / np.sqrt(5.0)
    for b in (0.3, 0.8, 1.0, 1.2, 2.0, 4.0):
        band = np.abs(beta - b) < 0.08
        ratio = S_a[band].mean() / S_lin[band].mean()
        assert abs(ratio - 1.0) < 5 * rel_se + 0.02, (b, ratio)
    # the input's estimated PSD is its target, in the same convention
    band = (beta > 0.2) & (beta < 6.0)
    assert abs(np.mean(out["S_f"][band] / spec.psd(beta[band])) - 1.0) < 0.02


# ------------------------------------------------------------------ events of one cell

BINS = datasets.bin_edges(dict(v_after=dict(max=2.5, n=50), interval=dict(max=20.0, n=80),
                               ratio=dict(max=4.0, n=80)))
NOISE = noise.NoiseSpec(kind="band_limited", rms=0.5, dt=0.1, beta_c=4.0)


@pytest.fixture(scope="module")
def record():
    return noise.generate_array(NOISE, 40_001, seed=3)      # tau up to 4000


def test_t_end_beyond_the_record_is_refused(record):
    # 40 001 samples at dt = 0.1 end at tau = 4000: asking for more must not be cut silently
    model = Model.paper(0.05, 0.5, 0.0)
    with pytest.raises(ValueError, match=r"t_end = 5000\.0.*40001 samples.*4000"):
        cells.event_statistics(record, NOISE.dt, model, t_end=5000.0, bins=BINS)
    with pytest.raises(ValueError, match="t_end"):
        cells.spectra_statistics(record, NOISE.dt, model, t_end=4000.5, nperseg=256)
    with pytest.raises(ValueError, match="t_end"):
        cells.trace(record, NOISE.dt, model, t_end=1e6)
    # the record's own end, written in decimal, is accepted
    out = cells.event_statistics(record, NOISE.dt, model, t_end=4000.0, bins=BINS,
                                 transient=50.0)
    assert out["simulated_time"] == pytest.approx(3950.0, rel=1e-12)


def test_ratio_statistics_only_with_a_harmonic_force(record):
    # Without a harmonic force there is no forcing period: z_j / z and the (m/n) motions
    # would be computed with a dummy beta, so they are absent from the results and datasets.
    kw = dict(transient=50.0, bins=BINS)
    plain = cells.event_statistics(record, NOISE.dt, Model.paper(0.05, 0.5, 0.0), **kw)
    forced = cells.event_statistics(record, NOISE.dt, Model.paper(0.05, 0.5, 0.0, 1.0, 1 / 1.1),
                                    **kw)
    harmonic_only = {"ratio_density", "ratio_density_stderr", "ratio_beyond",
                     "motion_probability"}
    assert not harmonic_only & set(plain) and harmonic_only <= set(forced)
    for name, study in (("plain", dict(amplitude=0.0)),
                        ("forced", dict(amplitude=1.0, inv_beta=[1.1]))):
        cell_list = Study.from_config(name, dict(zeta=0.05, eps=0.5, delta=[0.0], tile_size=16,
                                                 **study)).cells()
        tile = datasets.events_tile(cell_list, [plain if name == "plain" else forced], BINS,
                                    dict(zeta=0.05))
        present = {"ratio_density", "motion_probability", "ratio", "motion"} & set(tile.variables)
        assert present == (set() if name == "plain" else {"ratio_density", "motion_probability",
                                                          "ratio", "motion"})
        for var in tile.data_vars.values():
            assert var.attrs["long_name"] and "units" in var.attrs
    with pytest.raises(ValueError, match="mix"):
        datasets.events_tile(cell_list * 2, [plain, forced], BINS, {})


def test_batch_statistics_and_their_lag1_warning(record, caplog):
    # A forcing period of 2000 time units (amplitude 0.8) over a record of 4000 makes the
    # collision statistics drift: the 20 batch means follow the slow cycle (lag-1 ~0.55-0.7,
    # above 2/sqrt(20) = 0.45) and the cell warns. The stationary cell (delta = 0, noise only) has
    # a lag-1 correlation near 0 and stays silent.
    kw = dict(transient=50.0, bins=BINS, n_batches=20)
    with caplog.at_level(logging.WARNING, logger="vibroimpact"):
        calm = cells.event_statistics(record, NOISE.dt, Model.paper(0.05, 0.5, 0.0), **kw)
    assert not caplog.records
    assert calm["n_batches"] == 20 and abs(calm["v_after_lag1"]) < 2 / np.sqrt(20)
    # density errors are the batch-means ones of stats.density
    v_after = calm["v_after_density"]
    assert np.nansum(v_after * np.diff(BINS["v_after"])) + calm["v_after_beyond"] == \
        pytest.approx(1.0, abs=1e-12)
    with caplog.at_level(logging.WARNING, logger="vibroimpact"):
        drift = cells.event_statistics(
            record, NOISE.dt, Model.paper(0.05, 0.5, 0.5, 0.8, 2 * np.pi / 2000), **kw)
    assert drift["v_after_lag1"] > 2 / np.sqrt(20) and drift["interval_lag1"] > 2 / np.sqrt(20)
    messages = [r.getMessage() for r in caplog.records]
    assert len(messages) == 2 and all("lag-1" in m and "delta=0.5" in m for m in messages)


def test_a_cell_takes_the_cells_model_and_says_so(record):
    """The cells take a `Model` (the study's, resolved once): a tuple of numbers in its place
    is refused with the call that makes one."""
    for call in (lambda m: cells.event_statistics(record, NOISE.dt, m, bins=BINS),
                 lambda m: cells.spectra_statistics(record, NOISE.dt, m, nperseg=256),
                 lambda m: cells.trace(record, NOISE.dt, m, t_end=10.0),
                 lambda m: cells.motion_map_cell(record, NOISE.dt, m, transient=10.0),
                 lambda m: cells.escape_cell(record, NOISE.dt, m, transient=10.0,
                                             record_length=100.0)):
        with pytest.raises(ValueError, match=r"model must be a vibroimpact\.model\.Model "
                                             r"\(e\.g\. Model\.paper"):
            call((0.05, 0.5, 0.0))
