"""The (1/n) motions in closed form: both roots of ``cos(psi_0 - chi) = kappa``.

Closed form *because* Newton's law is linear in the velocity (``v_+ = -eps u``): the
equations are linear in ``(sin psi_0, cos psi_0, u)``. A velocity-dependent law has no such
form; its (1/n) motions come from the general Newton of :mod:`vibroimpact.orbits.newton`
seeded elsewhere (docs/architecture.md, "Adding physics").
"""
from math import acos, atan2, cos, exp, floor, hypot, pi, sin

from vibroimpact.orbits._jit import kernel
from vibroimpact.orbits.flight import harmonic_constants, propagator


@kernel
def solve_m1(n, beta, delta, zeta, eps, sols):
    """All (1/n) solutions in closed form: ``(tau_0, u_0)`` rows into ``sols``; returns the count.

    Notes
    -----
    With ``z = 2 pi n / beta`` the particular solution returns to itself, so eqs. (10)-(11) are
    linear in ``(S0, C0, u) = (q sin psi_0, q cos psi_0, u)``. Eliminating ``u`` leaves one
    equation in the impact phase,
    ``a_S sin psi_0 + a_C cos psi_0 = delta a_S / q`` with
    ``a_S = 1 - P11 + eps (P22 - exp(-2 zeta z))`` and ``a_C = -beta (1 + eps) P12``,
    i.e. ``cos(psi_0 - chi) = kappa``: two roots when ``|kappa| < 1``, none when ``|kappa| > 1``.
    """
    wd, q, phi = harmonic_constants(beta, zeta)
    z = 2.0 * pi * n / beta
    p11, p12, p21, p22 = propagator(z, zeta, wd)
    e2 = exp(-2.0 * zeta * z)
    a_s = 1.0 - p11 + eps * (p22 - e2)
    a_c = -beta * (1.0 + eps) * p12
    r = hypot(a_s, a_c)
    count = 0
    if r == 0.0:
        return 0
    kappa = delta * a_s / (q * r)
    if abs(kappa) > 1.0:
        return 0
    chi = atan2(a_s, a_c)
    dpsi = acos(kappa)
    nroot = 1 if dpsi == 0.0 else 2
    tf = 2.0 * pi / beta
    for k in range(nroot):
        psi = chi + dpsi if k == 0 else chi - dpsi
        s0 = q * sin(psi)
        c0 = q * cos(psi)
        # u from whichever of the two equations depends on it more strongly
        den2 = 1.0 + eps * p22
        den1 = -eps * p12
        if abs(den2) >= abs(den1):
            u = (-p21 * s0 + beta * (1.0 - p22) * c0 + delta * p21) / den2
        else:
            u = ((1.0 - p11) * (delta - s0) + beta * p12 * c0) / den1
        if not (u > 0.0):
            continue
        tau = (psi + phi) / beta
        tau -= tf * floor(tau / tf)
        if tau >= tf:
            tau -= tf
        sols[count, 0] = tau
        sols[count, 1] = u
        count += 1
    return count
