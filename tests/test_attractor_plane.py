"""Basins and Lyapunov exponents over any plane (`attractors.plane.attractor_plane`, issue 36):
the paper's plane is `attractor_map` itself, and a column of another plane is the paper's map
at that column's parameters, bit for bit (same Sobol starts, same seed)."""
import numpy as np
import pytest

from vibroimpact.attractors import attractor_map
from vibroimpact.attractors.plane import _ARRAYS, attractor_plane

ZETA, EPS = 0.05, 0.5
INV_BETA = np.array([0.9, 1.1])
DELTA = np.array([-0.5, 0.25, 1.0, 2.5])
#: Small but real: 6 starts a cell, the shortest cap the damping allows (ln(1e6)/zeta = 276).
KW = dict(n_starts=6, max_time=300.0, seed=3)


def _same(a, b, where):
    for name in _ARRAYS:
        np.testing.assert_array_equal(a[name], b[name], err_msg=f"{where}: {name}")
        assert a[name].dtype == b[name].dtype, (where, name)


@pytest.fixture(scope="module")
def paper():
    return attractor_map(INV_BETA, DELTA, ZETA, EPS, **KW)


def test_paper_plane_is_attractor_map(paper):
    r = attractor_plane("inv_beta", INV_BETA, "delta", DELTA, {"zeta": ZETA, "eps": EPS}, **KW)
    _same(r, paper, "(inv_beta, delta)")
    assert r["axes"] == ["inv_beta", "delta"]
    assert r["fixed"] == {"zeta": ZETA, "eps": EPS, "amplitude": 1.0}
    # the axes the other way round: the same arrays, transposed
    t = attractor_plane("delta", DELTA, "inv_beta", INV_BETA, {"zeta": ZETA, "eps": EPS}, **KW)
    for name in _ARRAYS:
        np.testing.assert_array_equal(np.swapaxes(t[name], -1, -2), paper[name])


def test_eps_delta_column_equals_paper_column(paper):
    """The issue's test: the (eps, delta) plane's column at the paper's eps is the (1/beta,
    delta) map's column at the fixed 1/beta, bit for bit."""
    eps = np.array([0.3, EPS, 0.8])
    r = attractor_plane("eps", eps, "delta", DELTA, {"zeta": ZETA, "inv_beta": 1.1}, **KW)
    assert r["lyapunov"].shape == (3, DELTA.size)
    column = {name: r[name][..., 1, :] for name in _ARRAYS}
    row = {name: paper[name][..., 1, :] for name in _ARRAYS}
    _same(column, row, "eps = 0.5 column")
    # the other eps are other systems: the exponents' sum of a settled start is
    # -2 zeta + 2 nu ln eps, so the columns differ wherever a start impacts
    assert not np.array_equal(r["lyapunov_start"][..., 0, :], r["lyapunov_start"][..., 1, :])
    # and each column is attractor_map at its own eps
    own = attractor_map([1.1], DELTA, ZETA, 0.8, **KW)
    _same({n: r[n][..., 2, :] for n in _ARRAYS}, {n: own[n][..., 0, :] for n in _ARRAYS},
          "eps = 0.8 column")


def test_one_call_per_cell_without_a_map_axis():
    """(zeta, eps): no inv_beta or delta on the plane, every cell its own call."""
    r = attractor_plane("zeta", [0.05, 0.1], "eps", [0.5, 0.7],
                        {"inv_beta": 1.1, "delta": 0.25}, **KW)
    one = attractor_map([1.1], [0.25], 0.1, 0.7, **KW)
    _same({n: r[n][..., 1, 1] for n in _ARRAYS}, {n: one[n][..., 0, 0] for n in _ARRAYS},
          "(zeta, eps) cell")


def test_amplitude_scales_out():
    """x = A y: the cell at amplitude A and play delta, its starts' box in x units, is the
    unit-force cell at delta / A with the box divided by A (exponents, rates and basins)."""
    r = attractor_plane("amplitude", [1.0, 2.0], "delta", [0.5, 2.0],
                        {"zeta": ZETA, "eps": EPS, "inv_beta": 1.1}, **KW)
    unit = attractor_map([1.1], [0.25, 1.0], ZETA, EPS, gap=(0.0, 2.0), velocity=(-2.0, 2.0),
                         **KW)
    _same({n: r[n][..., 1, :] for n in _ARRAYS}, {n: unit[n][..., 0, :] for n in _ARRAYS},
          "A = 2")


def test_refusals():
    with pytest.raises(ValueError, match="rms.*harmonic force alone"):
        attractor_plane("rms", [0.1, 0.2], "delta", DELTA, {"zeta": ZETA, "eps": EPS,
                                                           "inv_beta": 1.1}, **KW)
    with pytest.raises(ValueError, match="amplitude"):
        attractor_plane("amplitude", [0.0, 1.0], "delta", DELTA,
                        {"zeta": ZETA, "eps": EPS, "inv_beta": 1.1}, **KW)
    with pytest.raises(ValueError, match="fixed must give"):
        attractor_plane("eps", [0.5], "delta", DELTA, {"zeta": ZETA}, **KW)
