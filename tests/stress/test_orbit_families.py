"""Periodic orbits near folds, period doublings and grazing, against an independent solver.

The slow tests run the three stress families of ``vibroimpact.validation.orbit_families``,
the first third of the full campaign's cases of each (``pytest -m slow tests/stress``;
``python -m vibroimpact.validation.campaign --size full`` runs them all); the fast ones show
that the API works and that the independent solver agrees with a third method (mpmath Newton,
DOP853) at ordinary points.
``KNOWN_CASES`` re-run, point by point, disagreements that the families once found (confirmed
by mpmath and DOP853 then) and that the solver now gets right: regression tests.
"""
import math
import time

import numpy as np
import pytest

from vibroimpact import periodic_orbits
from vibroimpact.validation.campaign import SLOW_ORBIT_CASES, SLOW_ORBIT_SEED
from vibroimpact.validation.orbit_families import (
    FAMILIES, check_case, dop853_return, fold_deltas_m1, mp_orbit, mu_tolerance,
    period_doubling_points, reference_orbits, run_orbit_family)
from vibroimpact.validation.report import FamilyReport

# Cases per family for the slow suite (the fold family ~0.03 s a case, period doubling
# ~0.08 s, grazing ~0.015 s; a failing case costs ~0.3 s more for the mpmath/DOP853
# re-examination).
SLOW_CASES = SLOW_ORBIT_CASES
SEED = SLOW_ORBIT_SEED


# ------------------------------------------------------------------------------------------
# fast: the API and the independent solver

@pytest.mark.parametrize("name", FAMILIES)
def test_family_api(name):
    start = time.perf_counter()
    report = run_orbit_family(name, n_cases=2, seed=1)
    elapsed = time.perf_counter() - start
    print(report.summary())
    assert isinstance(report, FamilyReport)
    assert report.family == name
    assert report.cases == 2
    assert report.tolerance == 1.0 and "tol(d)" in report.measure
    assert report.compared >= 1
    assert report.worst_case is not None and math.isfinite(report.worst_error)
    assert 0.5 * elapsed <= report.seconds <= elapsed    # the family's wall time, in s
    assert report.exceptions == 0
    assert report.extra["skipped"] <= 1
    assert set(report.as_row()) >= {"family", "cases", "compared", "missed", "spurious"}
    again = run_orbit_family(name, n_cases=2, seed=1)
    assert (again.compared, again.worst_case) == (report.compared, report.worst_case)


def test_unknown_family():
    with pytest.raises(ValueError, match="orbit_fold"):
        run_orbit_family("fold", 1, 0)


@pytest.mark.parametrize("m, n, inv_beta, delta", [
    (1, 1, 1.2, 0.5), (1, 1, 0.2, -0.6), (2, 1, 1.0, 0.1), (2, 1, 0.7, -0.3),
    (1, 2, 0.4, 0.3), (2, 2, 1.2, 2.1)])
def test_reference_agrees_with_mpmath_and_the_package(m, n, inv_beta, delta):
    """The independent solver's orbits are fixed points of a 40-digit mpmath Newton (moves
    <= 1e-12) with its multipliers (1e-10), repeat under DOP853 (1e-8), and are the package's
    orbits at these ordinary points (the same count, multipliers to 1e-9)."""
    beta, zeta, eps = 1.0 / inv_beta, 0.05, 0.5
    ref = reference_orbits(m, n, beta, delta, zeta, eps)
    pkg = periodic_orbits(m, n, beta, delta, zeta, eps)
    assert len(ref) == len(pkg) >= 1
    for r in ref:
        t, u, mu = mp_orbit(m, n, r.taus, r.us, beta, delta, zeta, eps)
        assert np.max(np.abs(t - r.taus)) < 1e-12 and np.max(np.abs(u - r.us)) < 1e-12
        assert np.max(np.abs(np.sort_complex(mu) - np.sort_complex(r.mu))) < 1e-10 * max(
            1.0, np.abs(mu).max())
        assert dop853_return(r.taus, r.us, m, n, beta, delta, zeta, eps) < 1e-8
        assert r.det == pytest.approx(eps ** (2 * m) * math.exp(-4 * math.pi * zeta * n / beta),
                                      rel=1e-10)
    assert check_case(dict(kind="fold", m=m, n=n, beta=beta, delta=delta, zeta=zeta, eps=eps,
                           distance=1.0)) == []


def test_period_doubling_located_twice():
    """The period doubling of the (1/1) motion at 1/beta = 1.3 (mu = -6 at delta = 2.3) found
    by mu = -1 of the closed form and by D(z/2) of the (2/2) parametrization (1e-10)."""
    beta, zeta, eps = 1.0 / 1.3, 0.05, 0.5
    points = period_doubling_points(beta, zeta, eps)
    assert points
    for delta_pd, _, orbit in points:
        assert orbit.mu[0].real == pytest.approx(-1.0, abs=1e-9)
        below = reference_orbits(1, 1, beta, delta_pd - 1e-3, zeta, eps)
        above = reference_orbits(1, 1, beta, delta_pd + 1e-3, zeta, eps)
        assert below and above
    report = run_orbit_family("orbit_period_doubling", 1, 3)
    assert report.extra["pd_crosscheck"] < 1e-10


def test_fold_closed_form():
    """(1/1) solutions exist for |delta| <= delta* only; just inside there are two whose
    multipliers straddle +1 by ~sqrt(d)."""
    beta, zeta, eps = 1.0 / 0.8, 0.1, 0.6
    dstar = fold_deltas_m1(1, beta, zeta, eps)
    assert reference_orbits(1, 1, beta, dstar * (1 + 1e-9), zeta, eps, True) == []
    pair = reference_orbits(1, 1, beta, dstar - 1e-8, zeta, eps, True)
    assert len(pair) == 2
    near_one = sorted(o.mu[np.argmin(np.abs(o.mu - 1))].real for o in pair)
    assert near_one[0] < 1.0 < near_one[1] and near_one[1] - near_one[0] < 1e-2


def test_tolerance_grows_like_inverse_sqrt_distance():
    assert mu_tolerance("orbit_grazing", 1e-10) == mu_tolerance("orbit_grazing", 1e-2)
    assert mu_tolerance("orbit_fold", 1e-10) == pytest.approx(
        1e-9 + 1e-12 / 1e-5)
    assert mu_tolerance("orbit_fold", 1e-10, 1e-3) == pytest.approx(1e-9 + 1e-12 / 1e-8)
    assert mu_tolerance("orbit_fold", 1e-10) > mu_tolerance("orbit_fold", 1e-6)


# ------------------------------------------------------------------------------------------
# slow: the first third of each family's full campaign

@pytest.mark.slow
@pytest.mark.parametrize("name", FAMILIES)
def test_orbit_family(name):
    report = run_orbit_family(name, SLOW_CASES[name], SEED)
    print(report.summary())
    assert report.cases == SLOW_CASES[name]
    assert report.extra["skipped"] <= 0.05 * report.cases
    assert report.ok, report.details()


# Regression points: disagreements the families found in earlier versions of the solver (seed
# 11 and others), each confirmed by mpmath Newton and DOP853 at the time, kept as exact points
# that re-run one by one: `pytest -m slow tests/stress/test_orbit_families.py -k known`.
KNOWN_CASES = {
    # (2/1) fold at delta = 0.91900401692..., pair exists below it (mu = 0.988 and 1.012,
    # taus [2.29005, 5.21955] and [2.29079, 5.22204]): both roots of the scan's circle
    # condition fell into one cell (no sign change) and the stable orbit was missed
    "fold21_missed": dict(kind="fold", m=2, n=1, beta=0.4632189831209864,
                          delta=0.9190038876942133, zeta=0.140252977051332,
                          eps=0.6902755657606898, distance=1.2923239466329618e-07),
    # the same 3e-5 from a (2/1) fold (mu = 0.961 and 1.041): the unstable orbit was missed
    "fold21_missed_far": dict(kind="fold", m=2, n=1, beta=0.8517027775096446,
                              delta=0.4942993299947039, zeta=0.03673492301695671,
                              eps=0.3439009975609669, distance=3.128751429230677e-05),
    # period doubling of the (1/1) motion at delta = -0.0245038778075...: on the (2/2) side
    # one (2/2) motion (intervals z/2 +- 6e-5, mu = 1 - 1e-9), once returned twice (two Newton
    # copies 4e-7 apart, each ~3e-7 off along the near-null direction)
    "pd22_duplicate": dict(kind="period_doubling", m=1, n=1, beta=1.1961933965658853,
                           delta=-0.024503878339668096, zeta=0.019884047202237826,
                           eps=0.542731103892917, distance=5.321381126426478e-10),
    # on the side without a (2/2) motion: the doubled (1/1) motion, once returned as two (2/2)
    # "orbits" ~6e-6 off it; none must be returned
    "pd22_doubled_returned": dict(kind="period_doubling", m=1, n=1, beta=0.49804546289989854,
                                  delta=0.9652952254202881, zeta=0.01628618781285054,
                                  eps=0.6777280430375708, distance=1.0222807972779106e-10),
    # 1.4e-5 from a period doubling: a (2/2) fold pair with mu = 1.00003 and 0.99998 (taus
    # [2.25842, 9.49078] and [2.24786, 9.49944]); the second was once missed
    "pd22_missed": dict(kind="period_doubling", m=1, n=1, beta=0.8496452856909297,
                        delta=2.0614207639521664, zeta=0.115499898297842,
                        eps=0.6821883665749093, distance=1.4048159726616551e-05),
}


@pytest.mark.slow
@pytest.mark.parametrize("key", sorted(KNOWN_CASES))
def test_known_case(key):
    messages = check_case(KNOWN_CASES[key])
    assert messages == [], "\n".join(messages)
