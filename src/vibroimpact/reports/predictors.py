"""What predicts the probability of a motion under noise (Fig. 15)? Rank correlations of P
with the candidates, cell by cell over the map's (1/beta_f, delta) plane.

The paper's conclusion 5 (finding 8) names one predictor: the degree of stability S of the
periodic motion under the harmonic force alone (Fig. 16). The datasets offer three more:

- ``S``: Fig. 16's degree of stability (%) at each map cell's own centre: the orbits solved
  there by the orbits entry's own solver (`vibroimpact.orbits.cells.orbits_at_cells`, rule
  ``solve_map_orbits``), never read at a nearby cell of Fig. 16's finer grid (the map's
  cells may sit halfway between two of its cells, where "nearest" is a tie broken by
  rounding); 0 outside the stable domain (S = 100 (1 - |lambda|) is 0 at its edge). Where
  the motion's two multipliers are a complex pair, |lambda| is the square root of the
  Jacobian's determinant, eps exp(-zeta z / m) with z = 2 pi n / beta_f: S does not depend
  on delta there (over the paper's plane it depends on 1/beta_f alone; `orbits_at_cells`
  flags those cells);
- ``basin``: the share of starting states that settle on a stable orbit of the type without
  noise (``results/orbits/{orbits}_basins.nc``, `fraction`);
- ``lyapunov``: the largest Lyapunov exponent of the cell's starts without noise
  (``{orbits}_lyapunov.nc``; -inf where every start sticks, ranked lowest), one per cell;
- ``residence``: the mean residence time of the motion in the noisy record itself (the map's
  ``residence_time``, in forcing periods; 0 where the motion never occurs, left out where it
  has no complete stretch). Not a noise-free predictor: P is the motion's share of the time,
  which is its mean residence time times its number of visits over the record, so the
  residence time predicts P almost by construction. Its row says how much of P is "how long
  the motion holds once reached" against "how often it is reached"; the three others say how
  much the noise-free dynamics foretell.

Each is correlated with P (the map's ``probability``: the motion with free flights, as Figs. 15
and 16 compare) inside the motion's stable domain (``n_stable > 0`` at the cell's centre;
without an orbit map, the basins dataset's ``n_stable``) and over the whole plane. The basins and
exponents are simulated on the orbits entry's ``attractors`` grid, which the config sets to
the map's grid so that they compare cell for cell; a different grid is refused
(:func:`on_map_grid`), never interpolated (a share of starts or an exponent between two
cells is not the value of either).

**Interval.** Spearman's rho with a 95 % percentile bootstrap interval: the cells resampled
with replacement (pairs kept) ``N_RESAMPLES`` times from ``numpy.random.default_rng(SEED)``;
resamples without spread in either variable are dropped. Neighbouring cells are correlated
(P and the predictors vary smoothly over the plane), so the cells are fewer independent
pieces of evidence than their number and the interval is narrower than it should be: read
it as a lower bound on the uncertainty.
"""
from dataclasses import dataclass

import numpy as np

from vibroimpact._plane import dataset_axes

__all__ = ["PREDICTORS", "SEED", "N_RESAMPLES", "MIN_CELLS", "Correlation", "on_map_grid",
           "rank_correlation", "predictor_correlations", "correlations_dataset",
           "read_correlations", "predictors_table"]

#: The candidates, in the table's order, with what each is.
PREDICTORS = {
    "S": "degree of stability S (Fig. 16, no noise)",
    "basin": "basin fraction (no noise)",
    "lyapunov": "largest Lyapunov exponent (no noise)",
    "residence": "mean residence time (the noisy record itself)",
}
#: The bootstrap's seed and number of resamples (module docstring).
SEED = 19741974
N_RESAMPLES = 1000
#: Resamples ranked at a time (memory: a few of (chunk, cells) float arrays).
_CHUNK = 100
#: Fewest cells a rank correlation is computed on.
MIN_CELLS = 5


@dataclass(frozen=True)
class Correlation:
    """Spearman's rho of one predictor with P of one motion over one set of cells.

    ``where`` is ``"domain"`` (the motion's stable domain) or ``"plane"`` (every cell);
    ``rho``, ``low``, ``high`` are NaN when not computed, and ``note`` then says why (the
    dataset is missing, its grid differs, too few cells, no spread).
    """

    predictor: str
    motion: str
    where: str
    rho: float
    low: float
    high: float
    n_cells: int
    note: str = ""


_AXIS_TEXT = {"inv_beta": "1/beta_f"}


def _grid_text(values):
    values = np.asarray(values, dtype=float)
    if values.size < 2:
        return ", ".join(f"{v:.4g}" for v in values)
    return f"{values[0]:.4g} to {values[-1]:.4g} ({values.size} values)"


def on_map_grid(ds, motion_map, name):
    """``ds`` (a basins, Lyapunov or `vibroimpact.orbits.cells.orbits_at_cells` dataset) with
    the map's plane coordinates (``(inv_beta, delta)``, or its ``attrs["axes"]``).

    Raises
    ------
    ValueError
        When its grid is not the map's (both must list the same values, to 1e-9): the
        message gives both grids and how to make them one.
    """
    axes = dataset_axes(motion_map)
    same = all(d in ds.dims and ds.sizes[d] == motion_map.sizes[d]
               and np.allclose(ds[d].values, motion_map[d].values, rtol=0.0, atol=1e-9)
               for d in axes)
    if not same:
        def grid(data):
            return ", ".join(f"{_AXIS_TEXT.get(d, d)} {_grid_text(data[d])}" if d in data.dims
                             else f"no {d} axis" for d in axes)
        hint = ("solve the orbits at the map's cells (orbits_at_cells)" if "orbit" in name
                else "set the attractors grid to the study's")
        raise ValueError(f"the {name} grid ({grid(ds)}) is not the map's ({grid(motion_map)}): "
                         f"{hint} to compare them cell for cell")
    return ds.assign_coords({d: motion_map[d].values for d in axes})


def _ranks(a):
    from vibroimpact.stats.ranks import average_ranks

    return average_ranks(a, axis=-1)


def _codes(a):
    """Dense ranks of ``a``, 0 .. K-1 (equal values share a code), and K."""
    values, codes = np.unique(a, return_inverse=True)
    return codes.ravel(), values.size


def _resample_ranks(coded, idx):
    """``rankdata(a[idx], method="average", axis=-1)``, bit for bit, in O(n) a row: counting
    the dense codes of each resample (``coded`` from :func:`_codes`) instead of sorting it.
    A value's average rank is ``(below + 1 + below + equal) / 2``, integers halved (exact):
    a table of K ranks a row, read at each drawn cell by one flat gather."""
    codes, k = coded
    rows = idx.shape[0]
    flat = codes[idx] + k * np.arange(rows)[:, None]
    counts = np.bincount(flat.ravel(), minlength=rows * k).reshape(rows, k)
    upto = np.cumsum(counts, axis=1)
    below = upto - counts
    return ((below + upto + 1) / 2.0).ravel()[flat]


def _centred(a):
    """``(a - mean, sum of squares)`` a row: the halves of :func:`_pearson_rows`, computed
    once for a variable every correlation of a call shares."""
    a = a - a.mean(axis=-1, keepdims=True)
    return a, (a * a).sum(axis=-1)


class _Bootstrap:
    """What the correlations of one :func:`predictor_correlations` call share, bit for bit:
    the resampled cells (one ``default_rng(seed)`` draw per number of cells: every call of
    :func:`rank_correlation` with the same ``n`` draws the same indices) and the centred
    resampled ranks of the last few variables (P of one motion over one set of cells is
    correlated with each of the four predictors; the Lyapunov exponent, one per cell, with
    every motion's P). At most `_KEEP` + 1 (N_RESAMPLES, n) arrays of ranks and one of cells."""

    _KEEP = 6

    def __init__(self, seed, n_resamples):
        self.seed, self.n_resamples = seed, n_resamples
        self._idx = {}
        self._ranks = {}

    def indices(self, n):
        """The resampled cells, a list of (rows, n) chunks of `_CHUNK` rows."""
        if n not in self._idx:
            rng = np.random.default_rng(self.seed)
            self._idx = {n: [rng.integers(0, n, size=(min(_CHUNK, self.n_resamples - start), n))
                             for start in range(0, self.n_resamples, _CHUNK)]}
        return self._idx[n]

    def centred_ranks(self, values):
        """Per chunk of :meth:`indices`, ``_centred`` of the resampled ranks of ``values``."""
        key = (values.size, values.tobytes())
        if key in self._ranks:                          # the most recently used last
            self._ranks[key] = self._ranks.pop(key)
        else:
            if len(self._ranks) >= self._KEEP:
                self._ranks.pop(next(iter(self._ranks)))
            coded = _codes(values)
            self._ranks[key] = [_centred(_resample_ranks(coded, idx))
                                for idx in self.indices(values.size)]
        return self._ranks[key]


def _pearson_rows(a, b):
    return _pearson_centred(_centred(a), _centred(b))


def _pearson_centred(a, b):
    """Pearson's r a row of two :func:`_centred` variables."""
    (a, aa), (b, bb) = a, b
    with np.errstate(invalid="ignore", divide="ignore"):
        return (a * b).sum(axis=-1) / np.sqrt(aa * bb)


def rank_correlation(x, p, seed=SEED, n_resamples=N_RESAMPLES, level=0.95, *, _shared=None):
    """Spearman's rho of ``x`` and ``p`` with a bootstrap percentile interval.

    Parameters
    ----------
    x, p : array_like, shape (n,)
        Paired values (cells); pairs with a NaN are left out (-inf and inf are ranked).
    seed : int
        Of ``numpy.random.default_rng``: the resampled cells.
    n_resamples : int
    level : float
        Confidence level of the interval.

    Returns
    -------
    rho, low, high : float
        NaN when fewer than `MIN_CELLS` pairs or no spread in either variable.
    n : int
        The pairs used.
    """
    x, p = np.asarray(x, dtype=float).ravel(), np.asarray(p, dtype=float).ravel()
    keep = ~(np.isnan(x) | np.isnan(p))
    x, p = x[keep], p[keep]
    n = int(x.size)
    if n < MIN_CELLS or np.unique(x).size < 2 or np.unique(p).size < 2:
        return np.nan, np.nan, np.nan, n
    rho = float(_pearson_rows(_ranks(x), _ranks(p)))
    shared = _shared if _shared is not None else _Bootstrap(seed, n_resamples)
    if (shared.seed, shared.n_resamples) != (seed, n_resamples):
        raise ValueError(f"a bootstrap of seed {shared.seed} and {shared.n_resamples} "
                         f"resamples shared by a call with seed {seed} and {n_resamples}")
    boot = np.concatenate([_pearson_centred(a, b) for a, b in
                           zip(shared.centred_ranks(x), shared.centred_ranks(p))])
    boot = boot[np.isfinite(boot)]
    tail = 50.0 * (1.0 - level)
    low, high = (np.percentile(boot, [tail, 100.0 - tail]) if boot.size
                 else (np.nan, np.nan))
    return rho, float(min(low, rho)), float(max(high, rho)), n


def _stable_domain(motion_map, orbits, basins, motion):
    """(stable, S) on the map's grid: the orbits at the cells' centres
    (`vibroimpact.orbits.cells.orbits_at_cells`, on the map's grid), or the basins'
    n_stable."""
    if orbits is not None and motion in orbits["type"].values:
        o = orbits.sel(type=motion).transpose(*dataset_axes(motion_map))
        stable = o["n_stable"].values > 0
        S = np.where(stable, o["S"].values, 0.0)
        return stable, S
    # a one-wall basins dataset counts the closed-form orbits' stable solutions per cell; a
    # two-wall one classifies the study's motions and solves none (no n_stable)
    if basins is not None and "n_stable" in basins and motion in basins["motion"].values:
        return basins["n_stable"].sel(motion=motion).values > 0, None
    return None, None


def _fields(motion_map, motion, orbits, basins, lyapunov, errors):
    """``{predictor: array on the map's grid or a reason string}`` for one motion."""
    stable, S = _stable_domain(motion_map, orbits, basins, motion)
    out = {"S": S if S is not None else errors["S"] if "S" in errors else
           "no orbit map (the study draws no fig15_vs_fig16)" if orbits is None else
           f"the orbit map has no type {motion}"}
    for name, ds in (("basin", basins), ("lyapunov", lyapunov)):
        if name in errors:
            out[name] = errors[name]
        elif ds is None:
            out[name] = ("no attractors dataset (neither the study nor the orbits entry "
                         "fig15_vs_fig16 names has an attractors block)")
        elif name == "basin":
            out[name] = (ds["fraction"].sel(motion=motion).values
                         if motion in ds["motion"].values else f"no basin of {motion}")
        else:
            out[name] = ds["lyapunov"].values
    if "residence_time" in motion_map and motion in motion_map["motion"].values:
        r = motion_map.sel(motion=motion)
        seen = (r["n_stretches"].values + r["n_censored"].values) > 0
        out["residence"] = np.where(seen, r["residence_time"].values, 0.0)
    else:
        out["residence"] = "the map stores no residence times"
    return stable, out


def predictor_correlations(motion_map, orbits=None, basins=None, lyapunov=None, seed=SEED,
                           n_resamples=N_RESAMPLES):
    """Spearman's rho of each predictor with each motion's P, in its stable domain and over
    the plane (module docstring).

    Parameters
    ----------
    motion_map : xarray.Dataset
        ``results/datasets/{study}_map.nc``.
    orbits : xarray.Dataset or None
        The periodic orbits at the map's cells (`vibroimpact.orbits.cells.orbits_at_cells` of
        Fig. 16's orbit map, ``results/datasets/{study}_map_orbits.nc``), on the map's grid;
        None: not provided (its rows say so).
    basins, lyapunov : xarray.Dataset or None
        The basins and the Lyapunov datasets of the same system (None: not provided; its rows
        say so). An orbits, basins or Lyapunov dataset on another grid than the map's is not
        used (its rows give :func:`on_map_grid`'s reason): never read at a nearby cell.
    seed, n_resamples : int
        Of the bootstrap (:func:`rank_correlation`).

    Returns
    -------
    list of Correlation
        Per predictor (the order of `PREDICTORS`), per motion of the map, domain then plane.
    """
    motion_map = motion_map.transpose(..., *dataset_axes(motion_map))   # every field (x, y)
    errors = {}
    aligned = {}
    for name, ds in (("S", orbits), ("basin", basins), ("lyapunov", lyapunov)):
        try:
            aligned[name] = None if ds is None else on_map_grid(
                ds, motion_map, "orbits" if name == "S" else name)
        except ValueError as error:
            errors[name], aligned[name] = f"not used: {error}", None
    motions = [str(m) for m in motion_map["motion"].values]
    fields = {m: _fields(motion_map, m, aligned["S"], aligned["basin"], aligned["lyapunov"],
                         errors)
              for m in motions}
    # computed motion by motion (P's resampled ranks shared by the four predictors), listed
    # predictor by predictor
    shared = _Bootstrap(seed, n_resamples)
    found = {}
    for m in motions:
        stable, values = fields[m]
        p = motion_map["probability"].sel(motion=m).values
        for where in ("domain", "plane"):
            for predictor in PREDICTORS:
                x = values[predictor]
                if isinstance(x, str):
                    found[predictor, m, where] = Correlation(predictor, m, where, np.nan,
                                                             np.nan, np.nan, 0, x)
                    continue
                if where == "domain" and stable is None:
                    found[predictor, m, where] = Correlation(
                        predictor, m, where, np.nan, np.nan, np.nan, 0,
                        "no stable domain (no orbit map or basins)")
                    continue
                cells = stable if where == "domain" else np.ones(p.shape, bool)
                rho, low, high, n = rank_correlation(x[cells], p[cells], seed, n_resamples,
                                                     _shared=shared)
                note = ("" if np.isfinite(rho) else
                        f"fewer than {MIN_CELLS} cells" if n < MIN_CELLS else "no spread")
                found[predictor, m, where] = Correlation(predictor, m, where, rho, low, high,
                                                         n, note)
    return [found[predictor, m, where] for predictor in PREDICTORS for m in motions
            for where in ("domain", "plane")]


_FIELDS = ("rho", "low", "high", "n_cells", "note")


def correlations_dataset(correlations):
    """The correlations of :func:`predictor_correlations` as an ``xarray.Dataset`` of dims
    (predictor, motion, where): ``rho``, ``low``, ``high`` (float64, NaN when not computed),
    ``n_cells`` and ``note`` (:class:`Correlation`'s fields). What the map's predictors job
    writes (``results/datasets/{study}_predictors.nc``) and :func:`read_correlations` reads
    back, value for value."""
    import xarray as xr

    correlations = list(correlations)
    motions = list(dict.fromkeys(c.motion for c in correlations))
    wheres = ["domain", "plane"]
    shape = (len(PREDICTORS), len(motions), len(wheres))
    values = {"rho": np.full(shape, np.nan), "low": np.full(shape, np.nan),
              "high": np.full(shape, np.nan), "n_cells": np.zeros(shape, np.int64),
              "note": np.full(shape, "", dtype=object)}
    seen = np.zeros(shape, bool)
    for c in correlations:
        at = (list(PREDICTORS).index(c.predictor), motions.index(c.motion),
              wheres.index(c.where))
        seen[at] = True
        for field in _FIELDS:
            values[field][at] = getattr(c, field)
    if not seen.all():
        raise ValueError(f"correlations: {int((~seen).sum())} of the (predictor, motion, "
                         "where) rows missing; predictor_correlations gives every one")
    dims = ("predictor", "motion", "where")
    ds = xr.Dataset({name: (dims, array) for name, array in values.items()},
                    coords={"predictor": list(PREDICTORS), "motion": motions,
                            "where": wheres})
    for name, long_name in (
            ("rho", "Spearman's rank correlation of the predictor with P"),
            ("low", "95 % bootstrap interval of rho, lower end"),
            ("high", "95 % bootstrap interval of rho, upper end"),
            ("n_cells", "cells correlated"),
            ("note", "why rho is not computed (empty when it is)"),
            ("predictor", "; ".join(f"{k}: {v}" for k, v in PREDICTORS.items())),
            ("motion", "impact motion (m/n) of the map"),
            ("where", "domain: the motion's stable domain; plane: every cell")):
        ds[name].attrs.update(long_name=long_name, units="1")
    ds.attrs.update(seed=SEED, n_resamples=N_RESAMPLES)
    return ds


def read_correlations(ds):
    """The list of :class:`Correlation` a :func:`correlations_dataset` holds, in
    :func:`predictor_correlations`' order (per predictor, per motion, domain then plane)."""
    missing = [name for name in _FIELDS if name not in ds]
    if missing:
        raise ValueError(f"not a predictors dataset: no variable {', '.join(missing)}")
    arrays = {name: ds[name].transpose("predictor", "motion", "where").values
              for name in _FIELDS}
    out = []
    for i, predictor in enumerate(ds["predictor"].values):
        for j, motion in enumerate(ds["motion"].values):
            for k, where in enumerate(ds["where"].values):
                note = arrays["note"][i, j, k]
                out.append(Correlation(str(predictor), str(motion), str(where),
                                       float(arrays["rho"][i, j, k]),
                                       float(arrays["low"][i, j, k]),
                                       float(arrays["high"][i, j, k]),
                                       int(arrays["n_cells"][i, j, k]),
                                       "" if note is None else str(note)))
    return out


def _rho_text(c):
    if not np.isfinite(c.rho):
        return ""
    return f"{c.rho:+.2f} [{c.low:+.2f}, {c.high:+.2f}]"


def predictors_table(correlations):
    """The correlations as a table (pandas DataFrame): a row per predictor and motion, rho
    with its 95 % interval and the number of cells in the stable domain and over the plane,
    and why a value is missing."""
    import pandas as pd

    rows = {}
    for c in correlations:
        row = rows.setdefault((PREDICTORS[c.predictor], f"({c.motion})"), {})
        label = "stable domain" if c.where == "domain" else "whole plane"
        row[f"{label}: rho [95 %]"] = _rho_text(c)
        row[f"{label}: cells"] = c.n_cells
        if c.note and c.note not in row.get("note", ""):
            row["note"] = "; ".join(filter(None, [row.get("note", ""), f"{label}: {c.note}"]))
    table = pd.DataFrame.from_dict(rows, orient="index").fillna("")
    table.index.names = ["predictor", "motion"]
    return table
