"""The closed-form motion between impacts, and the float arithmetic it rests on.

Between samples and impacts the motion is ``x = p_lin + p_h + y``: ``p_lin(s) = r0 + b s -
2 zeta b`` for the linear force, ``p_h = A q sin(beta tau - phi)`` for the harmonic force and
the damped free response ``y = exp(-zeta s) (c1 cos(omega s) + c2 sin(omega s))``,
``omega = sqrt(1 - zeta^2)`` (docs/model.md; paper eqs. 2-6). :func:`segment` fits it to a
state, :func:`seg_eval` and :func:`push_eval` evaluate it in difference form, and
:func:`bounds` bounds its derivatives for the searches of :mod:`vibroimpact.impact.events`.

Time is kept as a sample index ``k`` plus an offset ``s`` in ``[0, h]``; the harmonic phase
``beta (k h + s) mod 2 pi`` is computed in double-double arithmetic (:func:`phase`) so that it
stays exact on records of 1e9 samples.
"""
import math

from vibroimpact.impact._jit import kernel
from vibroimpact.impact.layout import (C_B, C_C2, C_COS_T, C_CP, C_D2, C_F0, C_F_LIN,
                                       C_R, C_SIN_T, C_SP, C_V0, C_XD, C_Y0, C_YV0, P_A, P_AQ,
                                       P_BETA, P_COS_PHI, P_DELTA, P_OMEGA, P_PHI, P_SIN_PHI,
                                       P_ZETA)
from vibroimpact.impact.tolerances import BOUND_SAFETY, TINY

#: 2 pi in double-double: ``TWO_PI_HI + TWO_PI_LO`` is 2 pi to ~1e-32.
TWO_PI_HI = 6.283185307179586
TWO_PI_LO = 2.4492935982947064e-16
#: Dekker's splitting constant ``2^27 + 1``: splits a float64 into two 26-bit halves.
DEKKER_SPLIT = 134217729.0
#: Largest argument of the Taylor polynomials of :func:`sincos` and :func:`expm1` (their
#: truncation error there is below 1e-19, under round-off); libm beyond.
SINCOS_TAYLOR_MAX = 0.25
EXPM1_TAYLOR_MAX = 0.0625


@kernel
def _split(a):
    c = DEKKER_SPLIT * a
    hi = c - (c - a)
    return hi, a - hi


@kernel
def two_prod(a, b):
    """Error-free product: ``a * b = p + e`` exactly (Dekker)."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    return p, e


@kernel
def phase(k, s, bh_hi, bh_lo, beta):
    """``beta * (k h + s)`` reduced to about ``[-pi, pi]``, exact to round-off for any ``k``.

    ``bh_hi + bh_lo`` is the exact product ``beta * h`` (double-double).
    """
    kf = float(k)
    p, e = two_prod(kf, bh_hi)
    e += kf * bh_lo
    n = math.floor(p / TWO_PI_HI + 0.5)
    q, qe = two_prod(n, TWO_PI_HI)
    return ((p - q) - qe) + (e - n * TWO_PI_LO) + beta * s


@kernel
def sincos(x):
    """``(sin x, cos x)``: Taylor polynomials for ``|x| <= 0.25`` (error < 1e-19 relative,
    below round-off), libm beyond. Flights between samples have small arguments, and one
    polynomial pair costs a fraction of two libm calls in the hot root search."""
    if abs(x) > SINCOS_TAYLOR_MAX:
        return math.sin(x), math.cos(x)
    x2 = x * x
    s = x * (1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (
        1.0 / 362880 + x2 * (-1.0 / 39916800 + x2 * (1.0 / 6227020800)))))))
    c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320 + x2 * (
        -1.0 / 3628800 + x2 * (1.0 / 479001600 + x2 * (-1.0 / 87178291200)))))))
    return s, c


@kernel
def expm1(x):
    """``exp(x) - 1``: Taylor polynomial for ``|x| <= 0.0625`` (error < 1e-19), libm beyond."""
    if abs(x) > EXPM1_TAYLOR_MAX:
        return math.expm1(x)
    return x * (1.0 + x * (0.5 + x * (1.0 / 6 + x * (1.0 / 24 + x * (1.0 / 120 + x * (
        1.0 / 720 + x * (1.0 / 5040 + x * (1.0 / 40320 + x * (1.0 / 362880)))))))))


@kernel
def segment(x0, v0, s, r0, b, theta_k, P):
    """Coefficients of the closed-form motion from state ``(x0, v0)`` at offset ``s`` of a step.

    ``P`` is the parameter vector built by
    :func:`vibroimpact.impact.simulate.model_parameters`. Returns the segment tuple ``c``
    (its slots: :data:`vibroimpact.impact.layout.C_FIELDS`), read by :func:`seg_eval`,
    :func:`push_eval` and the searches.
    """
    if P[P_AQ] != 0.0:
        psi0 = theta_k + P[P_BETA] * s - P[P_PHI]
        sp = math.sin(psi0)
        cp = math.cos(psi0)
    else:
        sp = 0.0
        cp = 1.0
    return segment_at(x0, v0, s, r0, b, sp, cp, P)


@kernel(inline="always")
def segment_at(x0, v0, s, r0, b, sp, cp, P):
    """:func:`segment` with ``sp, cp = sin psi0, cos psi0`` given (``psi0 = theta_k + beta s -
    phi``, as :func:`segment` computes it; ``0, 1`` without a harmonic force): the stepping
    loop hands on the values it already has at a sample point, bit for bit the same.
    Inlined by numba (``inline="always"``): LLVM's own inliner leaves some calls of the
    kernels' helpers as calls, and this one returns the 17-slot tuple."""
    zeta, omega, delta = P[P_ZETA], P[P_OMEGA], P[P_DELTA]
    A, beta, Aq = P[P_A], P[P_BETA], P[P_AQ]
    P0 = r0 + b * s - 2.0 * zeta * b
    y0 = x0 - P0 - Aq * sp
    yv0 = v0 - b - Aq * beta * cp
    c2 = (yv0 + zeta * y0) / omega
    d2 = (y0 + zeta * yv0) / omega
    R = math.sqrt(y0 * y0 + c2 * c2) * BOUND_SAFETY
    # force at the segment start: sin(theta) = sin(psi0 + phi)
    sin_t = sp * P[P_COS_PHI] + cp * P[P_SIN_PHI]
    cos_t = cp * P[P_COS_PHI] - sp * P[P_SIN_PHI]
    F0 = r0 + b * s + A * sin_t - delta       # f - delta: the push into the wall at x = delta
    dF0 = b + A * beta * cos_t
    g2 = F0 + delta - 2.0 * zeta * v0 - x0      # x'' at the start
    g3 = dF0 - 2.0 * zeta * g2 - v0            # x''' at the start
    # in the order of layout.C_FIELDS
    return (x0 - delta, v0, b, sp, cp, y0, yv0, c2, d2, R, g2, g3, F0, dF0, sin_t, cos_t,
            r0 + b * s)


@kernel
def seg_eval(sig, c, P):
    """``(x - delta, x', x'')`` at ``sig`` after the segment start, in difference form.

    Written as ``x(sig) - x0`` plus ``x0 - delta`` with ``expm1`` and half-angle sines so that
    short flights (chatter) keep full relative accuracy; ``x''`` follows from eq. (2).
    """
    zeta, omega, delta = P[P_ZETA], P[P_OMEGA], P[P_DELTA]
    A, beta, Aq = P[P_A], P[P_BETA], P[P_AQ]
    g0, b, sp, cp = c[C_XD], c[C_B], c[C_SP], c[C_CP]
    y0, yv0, c2, d2 = c[C_Y0], c[C_YV0], c[C_C2], c[C_D2]
    em1 = expm1(-zeta * sig)
    E = em1 + 1.0
    sh, ch = sincos(0.5 * omega * sig)
    S = 2.0 * sh * ch
    C = 1.0 - 2.0 * sh * sh
    dx = b * sig + y0 * (em1 * C - 2.0 * sh * sh) + c2 * E * S
    v = b + E * (yv0 * C - d2 * S)
    f = c[C_F_LIN] + b * sig
    if Aq != 0.0:
        sb, cb = sincos(0.5 * beta * sig)
        cos_b = 1.0 - 2.0 * sb * sb
        sin_b = 2.0 * sb * cb
        dx += 2.0 * Aq * (cp * cb - sp * sb) * sb
        v += Aq * beta * (cp * cos_b - sp * sin_b)
        f += A * (c[C_SIN_T] * cos_b + c[C_COS_T] * sin_b)
    g = g0 + dx
    return g, v, f - 2.0 * zeta * v - (g + delta)


@kernel
def bounds(c, P):
    """Bounds on ``|x''|, |x'''|, |x''''|`` over a segment, and scales for tolerances."""
    Aq, beta = abs(P[P_AQ]), P[P_BETA]
    R = c[C_R]
    M2 = Aq * beta * beta * BOUND_SAFETY + R
    M3 = Aq * beta * beta * beta * BOUND_SAFETY + R
    M4 = Aq * beta * beta * beta * beta * BOUND_SAFETY + R
    vscale = abs(c[C_B]) + Aq * beta + R + abs(c[C_V0]) + TINY
    return M2, M3, M4, vscale


@kernel
def push_eval(sig, c, P):
    """``F = f - delta`` and ``dF/dtau`` at ``sig`` after the segment start, in difference form."""
    A, beta = P[P_A], P[P_BETA]
    F = c[C_F0] + c[C_B] * sig
    dF = c[C_B]
    if A != 0.0:
        sb = math.sin(beta * sig)
        cb = math.cos(beta * sig)
        F += A * (c[C_COS_T] * sb - c[C_SIN_T] * (1.0 - cb))
        dF += A * beta * (c[C_COS_T] * cb - c[C_SIN_T] * sb)
    return F, dF
