"""Limits of the numerical code that a config is checked against before any job runs.

Importing this module loads neither numba nor scipy (nor any kernel), so that reading a
config (`vibroimpact.pipeline.config`, at every Snakefile parse) stays light; the orbit
solver (`vibroimpact.orbits.api`) and the noise generator (`vibroimpact.noise`) import their
limits from here, so a config is refused by the same rule the code applies.
"""
import math

__all__ = ["MAX_M", "ATTRACTOR_MATCH_TOL", "attractor_min_time", "FIR_ATTENUATION_DB",
           "FIR_TRANSITION_FRACTION", "FIR_MAX_TAPS", "FULL_BAND_RTOL", "fir_taps", "cutoff"]

#: Largest number of impacts m a period of the (m/n) motions the orbit solver finds.
MAX_M = 3

#: A start has settled on a periodic orbit when its collisions match the orbit's impacts
#: (phase over the forcing period, velocity relative) within this tolerance
#: (`vibroimpact.attractors`).
ATTRACTOR_MATCH_TOL = 1e-6


def attractor_min_time(zeta, match_tol=ATTRACTOR_MATCH_TOL):
    """Shortest cap on a start's time that can let it settle: ``ln(1/match_tol) / zeta``, the
    time the damping alone takes to bring a perturbation of order one under the tolerance."""
    return math.log(1.0 / match_tol) / zeta


#: Stop-band attenuation (dB) of the Kaiser-window FIR of ``kind="band_limited"``; the pass
#: band ripple of the amplitude is the same 10**(-80/20) = 1e-4.
FIR_ATTENUATION_DB = 80.0
#: Width of the FIR transition band as a fraction of the cut-off beta_c.
FIR_TRANSITION_FRACTION = 0.02
#: Longest FIR accepted (a band_limited spec needing more taps is rejected).
FIR_MAX_TAPS = 2**18 + 1
#: beta_c * dt within this relative distance of pi counts as the full band (white).
FULL_BAND_RTOL = 1e-12


def fir_taps(theta_c):
    """Length (odd) of the Kaiser-window FIR of cut-off ``theta_c`` (rad/sample).

    Notes
    -----
    Kaiser's formula for the order, ``(A - 7.95) / (2.285 * width)`` plus one, with ``A =
    FIR_ATTENUATION_DB`` and the transition width ``FIR_TRANSITION_FRACTION * theta_c``
    (narrower near pi), written as ``scipy.signal.kaiserord`` evaluates it, operation for
    operation, so that the count is the same without importing scipy.
    """
    width = min(FIR_TRANSITION_FRACTION * theta_c, 2.0 * (math.pi - theta_c)) / math.pi
    order = (FIR_ATTENUATION_DB - 7.95) / 2.285 / (math.pi * width) + 1
    return int(math.ceil(order)) | 1


def cutoff(kind, beta_c, dt):
    """``beta_c`` (a float > 0) clipped to the Nyquist frequency ``pi/dt``.

    Raises
    ------
    ValueError
        If ``beta_c`` is above ``pi/dt``, or a ``band_limited`` record of this ``beta_c dt``
        (neither tiny nor this close to pi) needs an FIR longer than `FIR_MAX_TAPS`.
    """
    nyquist = math.pi / dt
    if beta_c > nyquist * (1.0 + FULL_BAND_RTOL):
        raise ValueError(f"beta_c must be in (0, pi/dt] = (0, {nyquist!r}], got {beta_c!r}")
    beta_c = min(beta_c, nyquist)
    full_band = beta_c * dt >= math.pi * (1.0 - FULL_BAND_RTOL)
    if kind == "band_limited" and not full_band:
        numtaps = fir_taps(beta_c * dt)
        if numtaps > FIR_MAX_TAPS:
            raise ValueError(
                f"beta_c = {beta_c!r} needs a {numtaps:.3g}-tap FIR (more than "
                f"{FIR_MAX_TAPS}): beta_c*dt = {beta_c * dt!r} must be neither "
                f"tiny nor this close to pi; use a larger dt, or beta_c = pi/dt (white)")
    return beta_c


#: Fewest noise levels an escape fit is made from (`vibroimpact.stats.escape_fit`; the config
#: checks ask for them): a line through two points has no residual degree of freedom, so
#: neither its scatter nor a t interval can be estimated.
MIN_FIT_LEVELS = 3
