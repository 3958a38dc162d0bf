"""Exact results used as oracles: the wall-free linear response and elastic impacts under white
noise."""
from __future__ import annotations

from typing import Callable

import numpy as np

from vibroimpact import _checks

__all__ = ["linear_response_std", "elastic_impact_rate", "rayleigh_pdf", "truncated_gaussian_pdf"]


def linear_response_std(S_f: float | Callable[[float], float], zeta: float) -> tuple[float, float]:
    """Standard deviations of the wall-free displacement and velocity, sigma_x and sigma_v.

    Parameters
    ----------
    S_f : float or callable
        Force PSD in the paper's convention (eq. 9). A number S0 means white noise,
        ``phi_f(t) = S0 delta(t)``; a callable ``S_f(beta)`` (even in beta) is integrated
        numerically over beta >= 0 with ``scipy.integrate.quad``.
    zeta : float
        Damping ratio, 0 < zeta < 1.

    Returns
    -------
    sigma_x, sigma_v : float

    Notes
    -----
    ``sigma_x^2 = (1/pi) int_0^inf |H|^2 S_f dbeta``,
    ``sigma_v^2 = (1/pi) int_0^inf beta^2 |H|^2 S_f dbeta``, with
    ``|H|^2 = 1 / ((1 - beta^2)^2 + (2 zeta beta)^2)``. For white noise,
    ``int_{-inf}^{inf} |H|^2 dbeta = int beta^2 |H|^2 dbeta = pi / (2 zeta)``, hence
    ``sigma_x^2 = sigma_v^2 = S0 / (4 zeta)``.
    """
    _checks.zeta(zeta)
    if not callable(S_f):
        S0 = float(S_f)
        if not np.isfinite(S0) or S0 < 0.0:
            raise ValueError(f"S_f must be a non-negative number or a callable, got {S_f!r}")
        s = np.sqrt(S0 / (4.0 * zeta))
        return float(s), float(s)

    from scipy import integrate   # only the white-noise-free case integrates

    def response(b, power):
        return b**power * float(S_f(b)) / ((1.0 - b * b) ** 2 + (2.0 * zeta * b) ** 2)

    # The resonance peak (width ~ zeta at beta ~ 1) gets its own pieces so quad resolves it.
    edges = sorted({0.0, max(0.0, 1.0 - 5.0 * zeta), 1.0, 1.0 + 5.0 * zeta, 8.0})
    var = []
    for power in (0, 2):
        pieces = [integrate.quad(response, a, b, args=(power,), limit=200)[0]
                  for a, b in zip(edges, edges[1:])]
        tail = integrate.quad(response, edges[-1], np.inf, args=(power,), limit=200)[0]
        var.append((sum(pieces) + tail) / np.pi)
    return float(np.sqrt(var[0])), float(np.sqrt(var[1]))


def elastic_impact_rate(delta, sigma_x: float, sigma_v: float):
    """Mean impact rate for elastic impacts (eps = 1) under white noise, exact.

    Parameters
    ----------
    delta : float or array_like
        Play (wall position).
    sigma_x, sigma_v : float
        Wall-free response std's (`linear_response_std`).

    Returns
    -------
    float or ndarray
        ``nu(delta) = (1/2pi) (sigma_v/sigma_x) exp(-delta^2/2 sigma_x^2) / Phi(delta/sigma_x)``
        impacts per unit tau; the mean interval between impacts is ``1 / nu``.

    Notes
    -----
    With eps = 1 the reflection ``v -> -v`` preserves the stationary density of the wall-free
    oscillator, ``p(x, v) ~ exp(-x^2/2 sigma_x^2 - v^2/2 sigma_v^2)``, which is therefore the
    stationary density on ``x <= delta`` once renormalised (`truncated_gaussian_pdf`). The
    impact rate is the probability flux into the wall, ``int_0^inf v p(delta, v) dv``: Rice's
    up-crossing rate divided by ``Phi(delta / sigma_x)``. Computed with ``log_ndtr`` so it
    stays finite for large negative delta.
    """
    return _rice_rate(delta, sigma_x, sigma_v, elastic=True)


def upcrossing_rate(delta, sigma_x: float, sigma_v: float):
    """Rice's rate of up-crossings of the level delta by the wall-free Gaussian response.

    Parameters
    ----------
    delta : float or array_like
        Level (the play).
    sigma_x, sigma_v : float
        Wall-free response std's (`linear_response_std`).

    Returns
    -------
    float or ndarray
        ``nu+(delta) = (1/2pi) (sigma_v/sigma_x) exp(-delta^2 / 2 sigma_x^2)`` per unit tau.

    Notes
    -----
    For any restitution, once the play is large against sigma_x an impact is a rare
    excursion of a response the wall has not disturbed since the last one (its memory, 1/zeta,
    is short against 1/nu+): the collision rate tends to nu+(delta), the mean interval
    between collisions to ``1 / nu+``, and the approach velocity to the flux-weighted
    (Rayleigh) density `rayleigh_pdf`, mean ``sigma_v sqrt(pi/2)`` (Rice 1944). Several
    collisions of one excursion, and the wall's memory at smaller plays, make the measured
    interval shorter than ``1 / nu+``.
    """
    return _rice_rate(delta, sigma_x, sigma_v, elastic=False)


def _rice_rate(delta, sigma_x, sigma_v, elastic):
    """Rice's up-crossing rate of delta, divided by Phi(delta / sigma_x) when ``elastic``
    (in the exponent, so that it stays finite for large negative delta)."""
    d = np.asarray(delta, dtype=float) / sigma_x
    exponent = -0.5 * d * d - (_log_ndtr(d) if elastic else 0.0)
    rate = (sigma_v / sigma_x) / (2.0 * np.pi) * np.exp(exponent)
    return rate if rate.ndim else float(rate)


def _log_ndtr(x):
    """``log Phi(x)``: scipy.special, imported here so that `upcrossing_rate` (figures,
    reports) does not load it."""
    from scipy.special import log_ndtr

    return log_ndtr(x)


def rayleigh_pdf(u, sigma_v: float):
    """Density of the approach velocity at impact for elastic impacts under white noise.

    ``p(u) = (u / sigma_v^2) exp(-u^2 / 2 sigma_v^2)`` for u >= 0, else 0: the flux-weighted
    velocity ``u p_v(u)`` at the wall, independent of delta. After impact with restitution eps
    the speed is ``eps u``.
    """
    u = np.asarray(u, dtype=float)
    p = np.where(u >= 0.0, u / sigma_v**2 * np.exp(-0.5 * (u / sigma_v) ** 2), 0.0)
    return p if p.ndim else float(p)


def truncated_gaussian_pdf(x, sigma_x: float, delta: float):
    """Stationary displacement density for elastic impacts under white noise.

    ``p(x) = phi(x / sigma_x) / (sigma_x Phi(delta / sigma_x))`` for ``x <= delta``, else 0:
    the wall-free Gaussian N(0, sigma_x^2) cut at the wall and renormalised. The velocity
    keeps its wall-free density N(0, sigma_v^2), independent of x.
    """
    x = np.asarray(x, dtype=float)
    z = x / sigma_x
    log_p = -0.5 * z * z - 0.5 * np.log(2.0 * np.pi) - np.log(sigma_x) - _log_ndtr(
        delta / sigma_x)
    p = np.where(x <= delta, np.exp(log_p), 0.0)
    return p if p.ndim else float(p)
