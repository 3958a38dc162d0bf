"""Self-checks of the mpmath reference (vibroimpact.validation.reference), independent of the
package.

The reference is checked against scipy (DOP853 restarted at every sample and impact, and
``scipy.signal.lsim``), against its own float64-like evaluation (dps=16), and against closed
forms (grazing of a linear response, chatter of a constant force).
"""
import math

import numpy as np
import pytest
from mpmath import mp, mpf
from scipy.integrate import solve_ivp
from scipy.signal import lsim

from vibroimpact.validation.reference import (agreeing_prefix, comparable_impacts, linear_peak,
                                              reference_impacts)

ZETA, EPS, DT = 0.05, 0.5, 0.1


def _ivp_impacts(zeta, eps, delta, noise, dt, amplitude, beta, x0, n_impacts):
    """Impacts by DOP853 (rtol = atol = 1e-13), restarted at every sample and every impact."""
    y = np.array([x0, 0.0])
    t = 0.0
    times, vels = [], []

    def hit(_t, yy):
        return yy[0] - delta
    hit.terminal, hit.direction = True, 1

    for k in range(len(noise) - 1):
        tk, tk1 = k * dt, (k + 1) * dt
        r0, b = noise[k], (noise[k + 1] - noise[k]) / dt

        def rhs(tt, yy, r0=r0, b=b, tk=tk):
            f = amplitude * math.sin(beta * tt) + r0 + b * (tt - tk)
            return [yy[1], f - 2 * zeta * yy[1] - yy[0]]
        while t < tk1:
            sol = solve_ivp(rhs, (t, tk1), y, method="DOP853", rtol=1e-13, atol=1e-13,
                            events=hit)
            if sol.status == 1:
                te, ye = sol.t_events[0][0], sol.y_events[0][0]
                times.append(te)
                vels.append(ye[1])
                if len(times) == n_impacts:
                    return np.array(times), np.array(vels)
                y, t = np.array([delta, -eps * ye[1]]), te
            else:
                y, t = sol.y[:, -1], tk1
    return np.array(times), np.array(vels)


@pytest.mark.parametrize("delta, amplitude", [(0.5, 0.0), (0.3, 0.4)])
def test_reference_matches_dop853(delta, amplitude):
    rng = np.random.default_rng(7)
    noise = rng.standard_normal(601)
    beta = 1.2
    ref = reference_impacts(ZETA, EPS, delta, noise, DT, amplitude=amplitude, beta=beta,
                            x0=0.0, max_impacts=8)
    t_ref, u_ref, _ = comparable_impacts(ref)
    t_ivp, u_ivp = _ivp_impacts(ZETA, EPS, delta, noise, DT, amplitude, beta, 0.0, 8)
    assert len(t_ref) >= 5
    n = min(len(t_ref), len(t_ivp))
    # DOP853 at rtol = atol = 1e-13 restarted ~300 times accumulates ~1e-11 of state error;
    # impact times and velocities inherit it divided by the (order-0.1) approach velocity.
    np.testing.assert_allclose(t_ivp[:n], t_ref[:n], rtol=0, atol=1e-8)
    np.testing.assert_allclose(u_ivp[:n], u_ref[:n], rtol=1e-8, atol=0)


def test_reference_leaving_the_wall_matches_dop853():
    """Start at rest on the wall (x0 = delta = 0) with f < delta: the mass leaves, the force
    turns towards the wall within the first step and brings it back."""
    noise = np.array([-0.5] + [0.5] * 20)
    ref = reference_impacts(ZETA, EPS, 0.0, noise, DT, x0=0.0, max_impacts=3)
    t_ivp, u_ivp = _ivp_impacts(ZETA, EPS, 0.0, noise, DT, 0.0, 1.0, 0.0, 3)
    assert not ref["stick_start"]  # f(0) - delta < 0: it leaves at once
    # a few restarts only: DOP853's ~1e-13 state error, over approach speeds >= 0.007
    np.testing.assert_allclose(t_ivp, [float(t) for t in ref["time"]], rtol=0, atol=1e-9)
    np.testing.assert_allclose(u_ivp, [float(u) for u in ref["velocity"]], rtol=1e-8)


def test_reference_precision_independent():
    """dps=34 and dps=50 agree to 1e-20: the reference is limited by its precision only."""
    rng = np.random.default_rng(3)
    noise = rng.standard_normal(501)
    a = reference_impacts(ZETA, EPS, 0.4, noise, DT, max_impacts=10, dps=34)
    b = reference_impacts(ZETA, EPS, 0.4, noise, DT, max_impacts=10, dps=50)
    assert len(a["time"]) == len(b["time"]) >= 5
    for ta, tb, ua, ub in zip(a["time"], b["time"], a["velocity"], b["velocity"]):
        assert abs(ta - tb) < 1e-20
        assert abs(ua - ub) < 1e-20 * abs(ub)


def test_reference_float64_like_agrees_on_first_impacts():
    rng = np.random.default_rng(5)
    noise = rng.standard_normal(501)
    a = reference_impacts(ZETA, EPS, 0.4, noise, DT, max_impacts=10, dps=34)
    b = reference_impacts(ZETA, EPS, 0.4, noise, DT, max_impacts=10, dps=16)
    # 16 digits lose at most a few digits on the first impacts; 1e-9 leaves a wide margin
    assert agreeing_prefix(a, b, tol=1e-9) >= 3


def test_reference_linear_response_matches_lsim():
    """Without impacts (delta huge) the recorded x is the linear response of the
    piecewise-linear input; lsim's first-order hold is exact for that input."""
    rng = np.random.default_rng(11)
    noise = rng.standard_normal(201)
    ref = reference_impacts(ZETA, EPS, 100.0, noise, DT, x0=0.0, record=True, dps=25)
    assert not ref["time"]
    t = np.arange(len(noise)) * DT
    _, y, _ = lsim(([1.0], [1.0, 2 * ZETA, 1.0]), noise, t, interp=True)
    x = np.array([float(v) for v in ref["x"]])
    assert len(x) == len(noise)
    # lsim propagates with a float64 matrix exponential: ~1e-15 per step, damped
    np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)


def test_reference_harmonic_steady_state():
    """Started on the steady harmonic orbit q sin(beta tau - phi), x stays on it."""
    beta, amp = 0.8, 0.3
    q = 1 / math.hypot(1 - beta ** 2, 2 * ZETA * beta)
    phi = math.atan2(2 * ZETA * beta, 1 - beta ** 2)
    with mp.workdps(30):
        x0 = float(amp * q * mp.sin(-mpf(phi)))
        v0 = float(amp * q * beta * mp.cos(-mpf(phi)))
    ref = reference_impacts(ZETA, EPS, 10.0, None, 0.25, amplitude=amp, beta=beta, x0=x0, v0=v0,
                            t_end=20.0, record=True, dps=30)
    t = np.array([float(v) for v in ref["grid_time"]])
    x = np.array([float(v) for v in ref["x"]])
    # x0, v0 are float64 roundings of the orbit: the free transient they start is <= 1e-16
    np.testing.assert_allclose(x, amp * q * np.sin(beta * t - phi), rtol=0, atol=1e-14)


def _tent(dt, half_width, t_end, start=2):
    """Force samples: zero, then one triangular pulse of unit height."""
    noise = np.zeros(int(round(t_end / dt)) + 1)
    for j in range(-half_width, half_width + 1):
        noise[start + half_width + j] = 1 - abs(j) / (half_width + 1)
    return noise


@pytest.mark.parametrize("overshoot", [1e-3, 1e-8, 1e-14, 1e-20, -1e-20, -1e-8])
def test_reference_catches_grazing_inside_one_step(overshoot):
    """Linear response to a pulse from rest: with the wall at max(x) - overshoot, inside a
    step whose ends stay below it, the reference finds the double crossing exactly when the
    overshoot is positive, with the approach speed of a parabola through its top."""
    dt, t_end = 0.5, 8.0
    noise = _tent(dt, 5, t_end)
    with mp.workdps(40):
        peak = linear_peak(ZETA, noise, dt, t_end=t_end, dps=40)
        delta = peak["x"] - mpf(overshoot)
        assert all(e < delta - mpf("1e-2") for e in peak["x_ends"])  # no sign change at ends
        ref = reference_impacts(ZETA, 1.0, delta, noise, dt, x0=0.0, t_end=t_end, dps=40)
        if overshoot < 0:
            assert ref["time"] == []
            return
        assert len(ref["time"]) == 1
        t_hit = ref["time"][0]
        assert peak["step"] * dt < t_hit < peak["t"]
        speed = mp.sqrt(-2 * peak["xdd"] * overshoot)
        # parabola approximation error is relative O(sqrt(overshoot))
        assert abs(ref["velocity"][0] / speed - 1) < 10 * math.sqrt(overshoot)


def test_reference_chatter_is_geometric_and_sticks():
    """Constant force F > delta: the bounces' flight times shrink like eps^k and the summed
    accumulation time is where sticking starts."""
    F, delta = 1.0, 0.5
    noise = np.full(101, F)
    ref = reference_impacts(ZETA, EPS, delta, noise, DT, x0=0.0, t_end=10.0)
    assert ref["sticking_reached"]
    t = ref["time"]
    flights = [t[j + 1] - t[j] for j in range(len(t) - 1)]
    ratios = [float(flights[j + 1] / flights[j]) for j in range(len(flights) - 1)]
    # ratio -> eps as the velocity -> 0 (corrections O(velocity))
    assert ratios[-1] == pytest.approx(EPS, abs=1e-9)
    assert float(ref["stick_start"][0]) > float(t[-1])
    assert float(ref["stick_start"][0] - t[-1]) < 1e-10
    assert ref["stuck_end"]
