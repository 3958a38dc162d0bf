"""The impact law is written once (vibroimpact.model) and every numerical layer calls it.

Checks: the law's derivative and ratio agree with the law itself (a new law must keep them
so); the compiled law rounds exactly as the plain one; no module of the orbit solver, the
attractors or the validation writes the law inline; the kernels that call it recompile when it
changes (their numba cache is stamped with model.py); and the attractors' saltation matrix,
built from the law, is the tangent of the exact flow through an impact (scipy's DOP853 with a
terminal event, finite differences).
"""
from pathlib import Path
import math
import re
import tokenize

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from vibroimpact import _law, model

SRC = Path(model.__file__).resolve().parent


@pytest.mark.parametrize("eps", [0.0, 0.3, 0.5, 1.0])
@pytest.mark.parametrize("u", [1e-3, 0.7, 4.0, -2.5])
def test_derivative_and_ratio_agree_with_the_law(eps, u):
    h = 1e-6 * max(1.0, abs(u))
    fd = (model.rebound_velocity(eps, u + h) - model.rebound_velocity(eps, u - h)) / (2 * h)
    # central difference of a law smooth in u: error O(h^2) plus round-off ~1e-16 / h
    assert model.rebound_derivative(eps, u) == pytest.approx(fd, rel=1e-8, abs=1e-9)
    assert model.rebound_ratio(eps, u) * u == pytest.approx(model.rebound_velocity(eps, u),
                                                            rel=1e-15, abs=1e-300)


def test_the_compiled_law_rounds_as_the_plain_one():
    rng = np.random.default_rng(3)
    for eps, u in zip(rng.uniform(0, 1, 200), rng.normal(0, 3, 200)):
        for name in ("rebound_velocity", "rebound_derivative", "rebound_ratio"):
            assert getattr(_law, name)(eps, u) == getattr(model, name)(eps, u)
        assert model.rebound_velocity(eps, u) == -eps * u       # Newton's law, to the bit


def _code_lines(path):
    """``(line number, code)`` of a module, its strings and comments left out."""
    lines = {}
    with open(path, "rb") as f:
        for tok in tokenize.tokenize(f.readline):
            if tok.type not in (tokenize.STRING, tokenize.COMMENT, tokenize.ENCODING):
                lines.setdefault(tok.start[0], []).append(tok.string)
    return {n: " ".join(parts) for n, parts in lines.items()}


@pytest.mark.parametrize("package", ["orbits", "attractors", "validation"])
def test_no_module_writes_the_law_inline(package):
    inline = re.compile(r"-\s*(P\s*\.\s*)?eps\s*\*\s*(u|u_a|ua|v|mpf)\b")
    for path in sorted((SRC / package).glob("*.py")):
        for n, code in _code_lines(path).items():
            assert not inline.search(code), f"{path.name}:{n}: {code}"


def test_kernels_calling_the_law_are_stamped_with_it():
    from vibroimpact.impact import _jit as impact_jit
    from vibroimpact.orbits import _jit as orbits_jit
    for pkg, modules in (("impact", impact_jit.KERNEL_MODULES),
                         ("orbits", orbits_jit.KERNEL_MODULES)):
        stamped = {(SRC / pkg / m).resolve() for m in modules}
        assert (SRC / "model.py").resolve() in stamped
        assert all(p.is_file() for p in stamped)
    callers = [p for p in SRC.rglob("*.py") if "vibroimpact._law import" in p.read_text()
               or "from vibroimpact import _law" in p.read_text()]
    assert {p.parent.name for p in callers} >= {"orbits", "attractors", "validation"}


def _through_impact(state, t0, t1, zeta, delta, eps, beta):
    """The exact flow of x'' + 2 zeta x' + x = sin(beta t) from (t0, state) to t1 across one
    impact at x = delta (DOP853, terminal event), and the impact's instant and velocity."""
    def rhs(t, y):
        return [y[1], math.sin(beta * t) - 2 * zeta * y[1] - y[0]]

    def hit(t, y):
        return y[0] - delta
    hit.terminal, hit.direction = True, 1.0
    a = solve_ivp(rhs, (t0, t1), state, method="DOP853", rtol=1e-13, atol=1e-13, events=hit)
    ts, u = a.t_events[0][0], a.y_events[0][0][1]
    b = solve_ivp(rhs, (ts, t1), [delta, model.rebound_velocity(eps, u)], method="DOP853",
                  rtol=1e-13, atol=1e-13)
    return b.y[:, -1], ts, u


@pytest.mark.parametrize("eps", [0.4, 0.85])
def test_saltation_is_the_tangent_of_the_flow_through_an_impact(eps):
    from vibroimpact.attractors.kernels import saltation
    from vibroimpact.orbits.flight import propagator
    zeta, delta, beta = 0.07, 0.3, 1.3
    t0, t1, state = 0.0, 1.6, np.array([-0.2, 1.1])
    _, ts, u = _through_impact(state, t0, t1, zeta, delta, eps, beta)
    assert t0 < ts < t1 and u > 0.3
    h = 1e-6
    jac_fd = np.empty((2, 2))
    for c in range(2):
        dy = np.zeros(2)
        dy[c] = h
        plus, _, _ = _through_impact(state + dy, t0, t1, zeta, delta, eps, beta)
        minus, _, _ = _through_impact(state - dy, t0, t1, zeta, delta, eps, beta)
        jac_fd[:, c] = (plus - minus) / (2 * h)
    wd = math.sqrt(1 - zeta * zeta)
    s11, s21, s22 = saltation(eps, u, math.sin(beta * ts), delta, zeta)
    salt = np.array([[s11, 0.0], [s21, s22]])
    before = np.array(propagator(ts - t0, zeta, wd)).reshape(2, 2)
    after = np.array(propagator(t1 - ts, zeta, wd)).reshape(2, 2)
    # DOP853 at 1e-13 over differences of 2e-6: ~1e-7 relative, O(h^2) ~ 1e-12 truncation
    np.testing.assert_allclose(after @ salt @ before, jac_fd, rtol=1e-6, atol=1e-6)
