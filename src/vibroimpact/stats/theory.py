"""Closed-form results: the wall-free linear response and elastic impacts under white noise
(exact, used as oracles) at one wall or in a clearance between two, and the energy-envelope
averaging for eps near 1 (approximate)."""
from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from vibroimpact import _checks

__all__ = ["linear_response_std", "elastic_impact_rate", "rayleigh_pdf", "truncated_gaussian_pdf",
           "upcrossing_rate", "clearance_mass", "clearance_impact_rates", "clearance_pdf",
           "EnvelopeTheory", "energy_envelope", "envelope_v_after_pdf",
           "envelope_energy_pdf", "ENVELOPE_EPS_MIN", "ENVELOPE_DELTA_MIN"]


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


def _log_mass(upper, lower):
    """``log(Phi(upper) - Phi(lower))`` for ``lower < upper`` (standardised), stable in
    both tails: written with the tail that keeps its digits (``Phi(-lower) - Phi(-upper)``
    when both lie above 0)."""
    from scipy.special import log_ndtr

    hi, lo = np.broadcast_arrays(np.asarray(upper, dtype=float), np.asarray(lower, dtype=float))
    flip = lo > 0.0
    a = np.where(flip, -lo, hi)          # the larger end of the piece that is kept
    b = np.where(flip, -hi, lo)
    la, lb = log_ndtr(a), log_ndtr(b)
    with np.errstate(divide="ignore"):
        return la + np.log1p(-np.exp(lb - la))


def _clearance_args(delta, gap, sigma_x):
    d = np.asarray(delta, dtype=float)
    g = np.asarray(gap, dtype=float)
    if not np.all(np.isfinite(d)):
        raise ValueError(f"delta must be finite, got {delta!r}")
    if not np.all(g > 0.0):
        raise ValueError(f"gap must be > 0 (the clearance delta - gap <= x <= delta), got "
                         f"{gap!r}")
    sigma_x = _checks.real("sigma_x", sigma_x, low=0.0, low_open=True)
    return d, d - g, sigma_x


def clearance_mass(delta, gap, sigma_x: float):
    """``Z_x = Phi(delta / sigma_x) - Phi((delta - gap) / sigma_x)``: the wall-free Gaussian's
    mass inside the clearance ``delta - gap <= x <= delta``.

    Returns a float or an array shaped as the broadcast of ``delta`` and ``gap``; ``gap``
    may be ``inf`` (one wall: ``Phi(delta / sigma_x)``).
    """
    upper, lower, sigma_x = _clearance_args(delta, gap, sigma_x)
    z = np.exp(_log_mass(upper / sigma_x, lower / sigma_x))
    return z if z.ndim else float(z)


def clearance_impact_rates(delta, gap, sigma_x: float, sigma_v: float):
    """Impact rates at the two walls of a clearance, both elastic, under white noise; exact.

    Parameters
    ----------
    delta : float or array_like
        Position of the upper wall (hit moving up).
    gap : float or array_like
        Width of the clearance: the lower wall stands at ``delta - gap`` (hit moving down);
        ``inf`` gives the one-wall rate (`elastic_impact_rate`) and a lower rate 0.
    sigma_x, sigma_v : float
        Wall-free response std's of the same force (`linear_response_std`).

    Returns
    -------
    nu_upper, nu_lower : float or ndarray
        ``nu_w = p_x(x_w) sigma_v / sqrt(2 pi) / Z_x`` impacts per unit tau at the wall at
        ``x_w`` (``delta``, ``delta - gap``), with ``p_x`` the wall-free ``N(0, sigma_x^2)``
        density and ``Z_x`` = :func:`clearance_mass`; the mean interval between impacts at
        wall w is ``1 / nu_w``, and the approach speed at either wall has the Rayleigh
        density `rayleigh_pdf` (docs/model.md, section 7, "A clearance between two walls").

    Notes
    -----
    The wall-free stationary density ``p(x, v) = N(x; 0, sigma_x^2) N(v; 0, sigma_v^2)``
    solves the Fokker-Planck equation of ``(x, v)`` under white force and is even in v.
    An elastic wall at ``x_w`` sends ``(x_w, v)`` to ``(x_w, -v)`` with unit Jacobian, so
    the probability flux ``|v| p(x_w, v)`` arriving at speed ``u`` leaves at speed ``u``
    with the same density: the boundary condition ``p(x_w, v) = p(x_w, -v)`` holds at each
    wall. The free density cut to the strip and divided by ``Z_x`` is therefore stationary
    (and, the motion being ergodic, the stationary density). The flux into wall w is
    ``int_0^inf u p(x_w, u) du = p_x(x_w) / Z_x * sigma_v / sqrt(2 pi)``. Conditions:
    ``eps = 1`` at both walls (any ``eps < 1`` breaks the evenness at the wall), a force
    white on the time scale of the motion (``(x, v)`` Markov; the repository's piecewise
    linear white force is white to ``1 - sinc^4(beta dt / 2)``), no harmonic part, and
    the stationary state (a record long against ``1 / zeta``). Computed in logarithms
    (``log_ndtr``), finite however far out the walls stand.
    """
    upper, lower, sigma_x = _clearance_args(delta, gap, sigma_x)
    sigma_v = _checks.real("sigma_v", sigma_v, low=0.0, low_open=True)
    log_z = _log_mass(upper / sigma_x, lower / sigma_x)
    scale = (sigma_v / sigma_x) / (2.0 * np.pi)
    with np.errstate(over="ignore"):
        rates = tuple(scale * np.exp(-0.5 * (x / sigma_x) ** 2 - log_z)
                      for x in (upper, lower))
    return tuple(r if r.ndim else float(r) for r in rates)


def clearance_pdf(x, delta, gap, sigma_x: float):
    """Stationary displacement density in a clearance of two elastic walls under white noise.

    ``p(x) = phi(x / sigma_x) / (sigma_x Z_x)`` on ``delta - gap <= x <= delta``, else 0:
    the wall-free Gaussian cut to the clearance (:func:`clearance_impact_rates`, Notes).
    The velocity keeps its wall-free density ``N(0, sigma_v^2)``, independent of x.
    """
    if np.ndim(delta) or np.ndim(gap):
        raise ValueError(f"delta and gap must be numbers, got {delta!r} and {gap!r}")
    upper, lower, sigma_x = _clearance_args(delta, gap, sigma_x)
    x = np.asarray(x, dtype=float)
    z = x / sigma_x
    log_p = (-0.5 * z * z - 0.5 * np.log(2.0 * np.pi) - np.log(sigma_x)
             - _log_mass(upper / sigma_x, lower / sigma_x))
    p = np.where((x >= lower) & (x <= upper), np.exp(log_p), 0.0)
    return p if p.ndim else float(p)


#: Points of the grid in the impact velocity u = sqrt(2 H - delta^2) on which the
#: energy-envelope integrals are taken (Simpson's rule; the inner integral J(u) by the
#: trapezoidal rule): relative error ~1e-12 at eps = 1, ~5e-7 below (measured against
#: 16 and 64 times finer grids).
ENVELOPE_NODES = 4097
#: The grid ends at this many sigma = sqrt(S0 / (4 zeta)) of u: the density there is below
#: exp(-12^2 / 2) ~ 5e-32 of its peak.
ENVELOPE_U_MAX = 12.0


#: The energy-envelope curves are drawn by default (figures 7 and 9) for eps at least this.
#: Against simulations at zeta = 0.05 and delta >= 0 (docs/model.md, section 7.2), its impact
#: rate and mean speed after impact are within 4 % at eps = 0.95, 7 % at eps = 0.8 (mean
#: energy 10 %); at eps = 0.5 they are 40 % and 22 % off at delta = 0 (white force).
ENVELOPE_EPS_MIN = 0.8
#: ... and for plays at least this: below, the orbits near the wall are shorter than pi, down
#: to zero at rest on it; a force correlated over ~pi/beta_c is not white on that scale,
#: and chatter (many impacts per collision) begins. The theory counts impacts, the figures
#: collisions.
ENVELOPE_DELTA_MIN = 0.0


class EnvelopeTheory(NamedTuple):
    """Energy-envelope (stochastic averaging) predictions, one value per delta.

    Every field has the shape of ``delta``. See :func:`energy_envelope`.
    """

    mean_energy: np.ndarray    #: <H>, H = (v^2 + x^2) / 2, time average
    impact_rate: np.ndarray    #: nu: impacts per unit tau (one per period above the wall)
    v_after_mean: np.ndarray   #: mean speed after impact eps <V> (impact-weighted)
    interval_mean: np.ndarray  #: mean interval between impacts, 1 / nu


def _envelope_grid(delta, eps, zeta, S0, nodes=ENVELOPE_NODES):
    """The averaged stationary density on the impacting energies, on a grid in u.

    Returns ``u`` (shape (nodes,)), ``T`` and ``w`` (shape delta.shape + (nodes,)) with
    ``w(u) = exp(-(H - H_min)/sigma^2 - kappa J(u))``, so that ``p(H) dH = T w u du / Z``
    above the wall, and the analytic part of Z and of Z <H> below it (delta > 0 only), both
    in the same units (a factor exp(-H_min / sigma^2) dropped), and H_min (the lowest
    energy: delta^2 / 2 at rest on a wall with delta < 0, else 0).
    """
    _checks.zeta(zeta)
    eps = float(eps)
    if not 0.0 <= eps <= 1.0:
        raise ValueError(f"eps must be in [0, 1], got {eps!r}")
    S0 = float(S0)
    if not np.isfinite(S0) or S0 <= 0.0:
        raise ValueError(f"S0 must be a positive number, got {S0!r}")
    d = np.asarray(delta, dtype=float)[..., None]
    if not np.all(np.isfinite(d)):
        raise ValueError(f"delta must be finite, got {delta!r}")
    s2 = S0 / (4.0 * zeta)
    u = np.linspace(0.0, ENVELOPE_U_MAX * np.sqrt(s2), nodes)
    # phase of the wall on the circle of radius a (pi/2 at delta = 0, down to u = 0)
    theta0 = np.where(d == 0.0, 0.5 * np.pi, np.arctan2(u, d))
    T = 2.0 * (np.pi - theta0)                      # period of the truncated orbit
    area = (u * u + d * d) * (np.pi - theta0) + d * u        # A(H) = oint v dx
    # (2H - delta^2) / A(H) dH = u^3 / A du: finite at u = 0 for every delta (-> 3|delta|/2,
    # 0, 2u/pi for delta <, =, > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        g = np.where(u > 0.0, u**3 / area, 0.0)
    g[..., 0] = np.where(d[..., 0] < 0.0, 1.5 * np.abs(d[..., 0]), 0.0)
    from scipy.integrate import cumulative_trapezoid

    J = cumulative_trapezoid(g, u, axis=-1, initial=0.0)
    kappa = (1.0 - eps * eps) / S0
    c = 0.5 * d[..., 0] ** 2 / s2                       # H_c / sigma^2, wall reached at H_c
    h_min = np.where(d[..., 0] < 0.0, c, 0.0)
    w = np.exp(-(0.5 * u * u / s2 + (c - h_min)[..., None]) - kappa * J)
    # below the wall (delta > 0): p(H) ~ 2 pi exp(-H / sigma^2), whole circles, no impact
    inside = d[..., 0] > 0.0
    z_low = np.where(inside, 2.0 * np.pi * s2 * -np.expm1(-c), 0.0)
    h_low = np.where(inside, 2.0 * np.pi * s2 * s2 * (1.0 - np.exp(-c) * (1.0 + c)), 0.0)
    return u, T, w, z_low, h_low, h_min * s2


def _simpson(y, u):
    from scipy.integrate import simpson

    return simpson(y, x=u, axis=-1)


def energy_envelope(delta, *, eps: float, zeta: float, S0: float) -> EnvelopeTheory:
    """Energy-envelope averaging for eps near 1 under near-white noise.

    Parameters
    ----------
    delta : float or array_like
        Play (wall position).
    eps : float
        Restitution coefficient, 0 <= eps <= 1; the theory is for ``1 - eps << 1``.
    zeta : float
        Damping ratio, 0 < zeta << 1.
    S0 : float
        Force PSD at the natural frequency, ``S_f(1)``, in the paper's convention (eq. 9,
        two-sided, angular: ``phi_f(t) = S0 delta(t)`` for white noise). For a force whose
        spectrum is flat across the resonance, ``4 zeta sigma_x^2`` of the wall-free response
        is the same number (`linear_response_std`).

    Returns
    -------
    EnvelopeTheory
        Mean energy, impact rate, mean speed after impact and mean interval 1/nu, each of
        the shape of ``delta``.

    Notes
    -----
    docs/model.md, section 7.2. With ``H = (v^2 + x^2)/2``, ``sigma^2 = S0 / (4 zeta)``,
    ``a = sqrt(2H)``, ``theta_0 = arccos(delta / a)``, the orbit of energy H above the wall
    has period ``T(H) = 2 (pi - theta_0)``, encloses ``A(H) = a^2 (pi - theta_0) +
    delta sqrt(a^2 - delta^2)`` (``dA/dH = T``) and hits at ``V = sqrt(2H - delta^2)``.
    Averaging dH over a period gives drift ``S0/2 - 2 zeta A/T - (1 - eps^2) V^2 / (2T)`` and
    diffusion ``S0 A/T``; the stationary density of H is

        p(H) ~ T(H) exp(-H / sigma^2 - (1 - eps^2)/S0 int_{H_c}^H (2H' - delta^2)/A(H') dH'),

    with ``H_c = delta^2/2`` and the integral zero below it. Then ``nu = int p / T dH`` over
    the impacting energies, and the impacts' V is weighted by ``p / T``. At ``eps = 1`` the
    density is exactly the elastic one (`elastic_impact_rate` with ``sigma_x = sigma_v =
    sigma``, `rayleigh_pdf`). Errors: ``O(zeta)`` and ``O(1 - eps)`` relative (the averaging
    assumes the energy changes little over a period), and every impact counted once:
    chatter, which needs ``eps < 1`` and a force pressing into the wall, is left out.
    """
    u, T, w, z_low, h_low, _ = _envelope_grid(delta, eps, zeta, S0)
    d2 = np.asarray(delta, dtype=float)[..., None] ** 2
    H = 0.5 * (u * u + d2)
    Z = z_low + _simpson(T * w * u, u)
    flux = _simpson(w * u, u)
    nu = flux / Z
    mean_h = (h_low + _simpson(H * T * w * u, u)) / Z
    v_after = eps * _simpson(w * u * u, u) / flux
    return EnvelopeTheory(*(np.asarray(q)[()] for q in (mean_h, nu, v_after, 1.0 / nu)))


def envelope_v_after_pdf(w, delta: float, *, eps: float, zeta: float, S0: float):
    """Density of the speed after impact, eps V, from the energy-envelope averaging.

    Parameters
    ----------
    w : float or array_like
        Speed after impact (>= 0).
    delta, eps, zeta, S0 : float
        As :func:`energy_envelope` (one delta).

    Returns
    -------
    float or ndarray
        ``p(w) = p(H) / T(H) dH/dw / nu`` at ``H = ((w/eps)^2 + delta^2)/2``, 0 for w < 0;
        at eps = 1 it is `rayleigh_pdf` with sigma_v = sigma.
    """
    if np.ndim(delta):
        raise ValueError(f"delta must be one number, got {delta!r}")
    if not float(eps) > 0.0:
        raise ValueError(f"eps must be positive for a density of eps V, got {eps!r}")
    u, _, weight, *_ = _envelope_grid(delta, eps, zeta, S0)
    flux = _simpson(weight * u, u)
    w = np.asarray(w, dtype=float)
    v = w / eps
    p = np.interp(v, u, weight * u / flux, right=0.0) / eps
    p = np.where(w >= 0.0, p, 0.0)
    return p if p.ndim else float(p)


def envelope_energy_pdf(H, delta: float, *, eps: float, zeta: float, S0: float):
    """Stationary density of the energy H = (v^2 + x^2)/2 from the energy-envelope averaging.

    Parameters
    ----------
    H : float or array_like
        Energy.
    delta, eps, zeta, S0 : float
        As :func:`energy_envelope` (one delta).

    Returns
    -------
    float or ndarray
        ``p(H)`` (docs/model.md, section 7.2), normalised on ``H >= H_min`` (``delta^2 / 2``
        for delta < 0, else 0), 0 below; at eps = 1 it is ``T(H) exp(-H / sigma^2)`` over
        ``2 pi sigma^2 Phi(delta / sigma)``, the exact elastic density.
    """
    if np.ndim(delta):
        raise ValueError(f"delta must be one number, got {delta!r}")
    u, T, weight, z_low, _, h_min = _envelope_grid(delta, eps, zeta, S0)
    s2 = float(S0) / (4.0 * zeta)
    Z = z_low + _simpson(T * weight * u, u)
    H = np.asarray(H, dtype=float)
    d = float(delta)
    v = np.sqrt(np.maximum(2.0 * H - d * d, 0.0))
    above = np.interp(v, u, T * weight, right=0.0)
    below = 2.0 * np.pi * np.exp(-np.maximum(H, 0.0) / s2)
    p = np.where(2.0 * H >= d * d, above, np.where(d > 0.0, below, 0.0)) / Z
    p = np.where(H >= h_min, p, 0.0)
    return p if p.ndim else float(p)
