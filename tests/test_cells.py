"""Cell statistics against linear theory: with the wall out of reach the simulated PSD of
a(tau) is the linear |H|^2 S_f of the piecewise-linear input (MODEL.md)."""
import numpy as np

from vibroimpact import noise, stats
from vibroimpact.pipeline import cells


def test_psd_without_impacts_is_linear_response():
    """Near-white input (dt = 0.05, flat to beta_c = 8, far above the resonance). Welch with
    K segments has a relative standard error ~1.03/sqrt(K) per bin; averaged over the 10
    bins around each beta checked (correlated by the Hann window, so ~5 independent), the
    tolerance is 5 standard errors of that average plus 2 % for the spectral leakage at the
    resonance peak (half-width zeta = 0.05 spans ~2.5 bins of 0.02)."""
    spec = noise.NoiseSpec(kind="band_limited", rms=1.0, dt=0.05, beta_c=8.0)
    r = noise.generate_array(spec, 2_000_001, seed=7)
    out = cells.spectra_statistics(r, spec.dt, zeta=0.05, eps=0.5, delta=1e3, transient=200.0,
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
