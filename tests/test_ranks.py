"""`vibroimpact.stats.ranks` is scipy.stats' rankdata, spearmanr and chi2.sf bit for bit (the
reports use it so as not to import scipy.stats), and a report's statistics do not import
scipy.stats."""
import subprocess
import sys

import numpy as np
import pytest
import scipy.stats

from vibroimpact.stats.ranks import average_ranks, chi2_sf, spearman


@pytest.mark.parametrize("n", [2, 3, 7, 64, 1000])
@pytest.mark.parametrize("ties", [False, True])
def test_ranks_and_spearman_are_scipys_bit_for_bit(n, ties):
    rng = np.random.default_rng(n + 1000 * ties)
    for _ in range(20):
        x = rng.integers(0, max(2, n // 4), n).astype(float) if ties else rng.normal(size=n)
        y = rng.normal(size=n) + 0.5 * x
        assert np.array_equal(average_ranks(x), scipy.stats.rankdata(x))
        expected = scipy.stats.spearmanr(x, y).statistic
        got = spearman(x, y)
        assert got == expected or (np.isnan(got) and np.isnan(expected))


def test_ranks_along_an_axis_and_degenerate_inputs():
    a = np.random.default_rng(3).integers(0, 4, (6, 25)).astype(float)
    for axis in (0, 1, -1):
        assert np.array_equal(average_ranks(a, axis=axis), scipy.stats.rankdata(a, axis=axis))
    assert np.isnan(spearman([1.0, 1.0, 1.0], [1.0, 2.0, 3.0]))   # a constant input
    assert np.isnan(spearman([1.0], [2.0]))                        # one value
    assert spearman([1.0, 2.0, 3.0], [3.0, 2.0, 1.0]) == -1.0


def test_chi2_tail_is_scipys():
    for dof in (1, 2, 5, 12):
        for x in (0.0, 0.1, 1.0, 7.5, 40.0):
            assert chi2_sf(x, dof) == scipy.stats.chi2.sf(x, dof)


def test_the_reports_statistics_do_not_import_scipy_stats():
    code = ("import sys, numpy as np\n"
            "from vibroimpact.reports import findings, predictors, sensitivity\n"
            "from vibroimpact.stats import ranks, residence, motions\n"
            "motions.motion_map_agreement(np.arange(9.).reshape(3, 3), np.ones((3, 3), bool),"
            " np.arange(9.).reshape(3, 3))\n"
            "print('scipy.stats' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "False"
