"""Where a spectrum's power lies: its centroid over a band (the paper's section 5, finding 5:
the response's power "moves to lower frequency as delta decreases").

A module of its own, not in `vibroimpact.stats.spectra`: only the figures and the reports
read it, and the simulation jobs that reach `spectra` keep their code digests.
"""
import numpy as np

__all__ = ["CENTROID_BAND", "spectral_centroid"]

#: Upper end of the band over which a response's centroid is taken (`spectral_centroid`): the
#: resonance and the forcing frequencies of the paper's section 5, not the round-off tail.
CENTROID_BAND = 3.0


def spectral_centroid(beta, S, band: float = CENTROID_BAND) -> float:
    """Mean frequency of a PSD over ``0 < beta <= band``: ``sum(beta S) / sum(S)``.

    Parameters
    ----------
    beta, S : array_like
        PSD on an evenly spaced grid beta >= 0 (`vibroimpact.stats.spectra.welch_psd`).
    band : float
        Upper end of the frequencies taken.

    Returns
    -------
    float
        Where the power of ``S`` lies on average in the band (the paper's "moves to lower
        frequency", section 5, read as this centroid falling); NaN when ``S`` has no power
        there.
    """
    beta = np.asarray(beta, dtype=float)
    S = np.asarray(S, dtype=float)
    inside = (beta > 0) & (beta <= band)
    total = float(S[inside].sum())
    return float((beta[inside] * S[inside]).sum() / total) if total > 0 else float("nan")
