"""Small dense linear algebra on preallocated scratch (no allocation in the scans): an
in-place solve, the cofactor null vector of an ``(n-1) x n`` block, a norm.
"""
from math import sqrt

import numpy as np

from vibroimpact.orbits._jit import kernel


@kernel
def _solve_inplace(a, b, n):
    """Solve ``a[:n,:n] x = b[:n]`` in place (x in b); returns False if singular."""
    for k in range(n):
        p = k
        big = abs(a[k, k])
        for i in range(k + 1, n):
            if abs(a[i, k]) > big:
                big = abs(a[i, k])
                p = i
        if big == 0.0 or not np.isfinite(big):
            return False
        if p != k:
            for c in range(k, n):
                tmp = a[k, c]
                a[k, c] = a[p, c]
                a[p, c] = tmp
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
        piv = a[k, k]
        for i in range(k + 1, n):
            f = a[i, k] / piv
            if f != 0.0:
                for c in range(k + 1, n):
                    a[i, c] -= f * a[k, c]
                b[i] -= f * b[k]
    for k in range(n - 1, -1, -1):
        s = b[k]
        for c in range(k + 1, n):
            s -= a[k, c] * b[c]
        b[k] = s / a[k, k]
    return True


@kernel
def cofactors(kmat, row0, ncol, sub, out):
    """Signed cofactors of the ``(ncol-1) x ncol`` block ``kmat[row0:row0+ncol-1]``.

    ``out[k] = (-1)^k det(block without column k)``: the generalized cross product, a null
    vector of the block and a polynomial (smooth) function of its entries. One elimination with
    partial pivoting; ``out`` is all zero when the first ``ncol-1`` columns are singular.
    """
    r = ncol - 1
    for i in range(r):
        for c in range(ncol):
            sub[i, c] = kmat[row0 + i, c]
    sgn = 1.0
    prod = 1.0
    for k in range(r):
        p = k
        big = abs(sub[k, k])
        for i in range(k + 1, r):
            if abs(sub[i, k]) > big:
                big = abs(sub[i, k])
                p = i
        if big == 0.0:
            for c in range(ncol):
                out[c] = 0.0
            return
        if p != k:
            sgn = -sgn
            for c in range(k, ncol):
                tmp = sub[k, c]
                sub[k, c] = sub[p, c]
                sub[p, c] = tmp
        piv = sub[k, k]
        prod *= piv
        for i in range(k + 1, r):
            f = sub[i, k] / piv
            if f != 0.0:
                for c in range(k + 1, ncol):
                    sub[i, c] -= f * sub[k, c]
    # null vector with last component 1, then scaled to the cofactor normalization
    out[r] = 1.0
    for k in range(r - 1, -1, -1):
        acc = sub[k, r]
        for c in range(k + 1, r):
            acc += sub[k, c] * out[c]
        out[k] = -acc / sub[k, k]
    c_last = sgn * prod * (1.0 if r % 2 == 0 else -1.0)
    for c in range(ncol):
        out[c] *= c_last


@kernel
def _norm(v, n):
    acc = 0.0
    for i in range(n):
        acc += v[i] * v[i]
    return sqrt(acc)
