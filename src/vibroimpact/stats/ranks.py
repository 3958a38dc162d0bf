"""Average ranks and Spearman's rank correlation, without importing ``scipy.stats``.

``scipy.stats`` takes ~0.56 s to import beside numpy, pandas, xarray and matplotlib
(``python -X importtime``), more than a third of a report job's cells; the reports and the
predictors job need from it only ``rankdata``, ``spearmanr`` and ``chi2.sf``. These are the
same computations bit for bit (tests/test_ranks.py holds them to scipy.stats): average ranks
are integers or halves, exact in floating point, from the dense codes of ``np.unique``; the
correlation is ``np.corrcoef`` of the two rank columns, as ``scipy.stats.spearmanr`` computes
it. ``chi2.sf`` is ``scipy.special.chdtrc``, which scipy.stats calls.
"""
import numpy as np

__all__ = ["average_ranks", "spearman", "chi2_sf"]


def average_ranks(a, axis=-1):
    """``scipy.stats.rankdata(a, method="average", axis=axis)``: ranks from 1, ties sharing
    the mean of the ranks they span (``(below + 1 + below + equal) / 2``, exact)."""
    a = np.moveaxis(np.asarray(a), axis, -1)
    shape = a.shape
    rows = a.reshape(-1, shape[-1]) if a.ndim else a.reshape(1, 1)
    out = np.empty(rows.shape, dtype=np.float64)
    for i, row in enumerate(rows):
        _, codes, counts = np.unique(row, return_inverse=True, return_counts=True)
        upto = np.cumsum(counts)
        out[i] = ((upto - counts + upto + 1) / 2.0)[codes.ravel()]
    return np.moveaxis(out.reshape(shape), -1, axis)


def spearman(x, y):
    """Spearman's rank correlation of ``x`` and ``y`` (1-d, finite, one length): what
    ``scipy.stats.spearmanr(x, y).statistic`` gives, NaN for fewer than 2 values or a
    constant input."""
    a = np.column_stack((np.asarray(x, dtype=float), np.asarray(y, dtype=float)))
    if a.shape[0] <= 1 or (a[:, 0][0] == a[:, 0]).all() or (a[:, 1][0] == a[:, 1]).all():
        return np.nan
    return float(np.corrcoef(average_ranks(a, axis=0), rowvar=0)[1, 0])


def chi2_sf(x, dof):
    """Upper tail of the chi-square law with ``dof`` degrees of freedom at ``x``
    (``scipy.stats.chi2.sf(x, dof)``)."""
    from scipy.special import chdtrc

    return chdtrc(dof, x)
