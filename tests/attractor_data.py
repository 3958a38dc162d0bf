"""Synthetic boundaries, basins and Lyapunov datasets laid out as the writers will lay them out.

Stand-ins until the numerics that produce them land: each is derived from an orbit map
(``results/orbits/{name}.nc``) so that its features sit where that map's stable domains are,
and is physically plausible rather than computed: the boundary curves are the smoothed edges of
the stable cells, their kind read from why the neighbouring cells have no stable motion; the
basin fractions are multinomial draws of `N_STARTS` starts shared among the stable types.
"""
import contourpy
import numpy as np
import xarray as xr
from scipy import ndimage, stats

#: Kind of a boundary by the reason of the cells beyond it (``reason`` of the orbit map):
#: solutions vanish in a fold, touch the wall in a grazing, lose stability by period doubling.
KIND_OF_REASON = {1: "fold", 2: "grazing", 3: "period_doubling"}
#: A run of vertices of one kind shorter than this joins its neighbour (a kind does not flip
#: back and forth along a boundary).
SHORTEST_RUN = 4
N_STARTS = 64
MOTIONS = ["1/1", "2/1", "1/2", "1/3", "3/1", "other"]
CLASSES = ["listed", "periodic_other", "sticking", "chaotic", "undecided", "wall_free"]
#: Above this play the synthetic "other" starts take the wall-free response (no impact).
WALL_FREE_DELTA = 2.2
BOX = "phase in [0, 2pi), x0 = delta - g, g in [0, 4], v0 in [-4, 4]"
CONFIDENCE = 0.95


def _kind_runs(kinds):
    """``[(start, stop, kind)]``: runs of one kind, short ones merged into their predecessor."""
    edges = np.flatnonzero(np.r_[True, kinds[1:] != kinds[:-1], True])
    runs = [[a, b, kinds[a]] for a, b in zip(edges[:-1], edges[1:])]
    merged = []
    for run in runs:
        if merged and (run[1] - run[0] < SHORTEST_RUN or run[2] == merged[-1][2]):
            merged[-1][1] = run[1]
        else:
            merged.append(run)
    if len(merged) > 1 and merged[0][1] - merged[0][0] < SHORTEST_RUN:
        merged[1][0] = 0
        merged.pop(0)
    return [tuple(r) for r in merged]


def boundaries(orbits, smooth=1.0):
    """Boundaries dataset from an orbit map: smooth curves along each type's stable cells.

    The 0.5 contour of the stable mask blurred by `smooth` cells, cut where the kind (from
    the nearest cell without a stable motion, `KIND_OF_REASON`; ``existence`` for what a
    subharmonic type (n > 1) calls a fold) changes; the cuts are the codimension-two points.
    """
    x, y = orbits["inv_beta"].values, orbits["delta"].values
    xs, ys, curve, kinds, types = [], [], [], [], []
    c2 = {"inv_beta": [], "delta": [], "type": [], "kinds": []}
    for name in orbits["type"].values:
        sel = orbits.sel(type=name)
        stable = sel["n_stable"].values > 0
        if not stable.any():
            continue
        _, (ii, jj) = ndimage.distance_transform_edt(stable, return_indices=True)
        beyond = sel["reason"].values[ii, jj]
        field = ndimage.gaussian_filter(stable.astype(float), smooth, mode="nearest")
        gen = contourpy.contour_generator(x, y, field.T,
                                          line_type=contourpy.LineType.Separate)
        fold = "fold" if str(name).endswith("/1") else "existence"
        for line in gen.lines(0.5):
            if len(line) < 2 * SHORTEST_RUN:
                continue
            i = np.abs(x[:, None] - line[:, 0]).argmin(axis=0)
            j = np.abs(y[:, None] - line[:, 1]).argmin(axis=0)
            kind = np.array([KIND_OF_REASON.get(int(r), "fold") for r in beyond[i, j]],
                            dtype=object)
            kind[kind == "fold"] = fold
            runs = _kind_runs(kind)
            closed = np.allclose(line[0], line[-1])
            if closed and len(runs) > 1:          # start the loop at a change of kind
                shift = runs[1][0]
                line = np.concatenate([line[shift:-1], line[:shift + 1]])
                kind = np.concatenate([kind[shift:-1], kind[:shift + 1]])
                runs = _kind_runs(kind)
            for k, (a, b, what) in enumerate(runs):
                piece = line[a:min(b + 1, len(line))]
                xs += list(piece[:, 0])
                ys += list(piece[:, 1])
                curve += [len(kinds)] * len(piece)
                kinds.append(str(what))
                types.append(str(name))
                if k:
                    c2["inv_beta"].append(line[a, 0])
                    c2["delta"].append(line[a, 1])
                    c2["type"].append(str(name))
                    c2["kinds"].append(f"{runs[k - 1][2]}+{what}")
    return xr.Dataset(
        {"inv_beta": ("point", np.array(xs)), "delta": ("point", np.array(ys)),
         "curve": ("point", np.array(curve, dtype=int)),
         "kind": ("curve", np.array(kinds, dtype=str)),
         "type": ("curve", np.array(types, dtype=str)),
         **{f"codim2_{k}": ("codim2", np.array(v, dtype=float if k in ("inv_beta", "delta")
                                                else str))
            for k, v in c2.items()}},
        attrs=dict(zeta=orbits.attrs["zeta"], eps=orbits.attrs["eps"]))


def grid(step=0.05):
    """The Fig. 15 grid: inv_beta 0.2 .. 3.0, delta -1.5 .. 3.0."""
    return (np.round(np.arange(0.2, 3.0 + step / 2, step), 10),
            np.round(np.arange(-1.5, 3.0 + step / 2, step), 10))


def _on_grid(orbits, inv_beta, delta):
    return orbits.sel(inv_beta=xr.DataArray(inv_beta, dims="inv_beta"),
                      delta=xr.DataArray(delta, dims="delta"), method="nearest")


def _clopper_pearson(count, n):
    alpha = 1.0 - CONFIDENCE
    with np.errstate(invalid="ignore"):
        lo = np.where(count > 0, stats.beta.ppf(alpha / 2, count, n - count + 1), 0.0)
        hi = np.where(count < n, stats.beta.ppf(1 - alpha / 2, count + 1, n - count), 1.0)
    return lo, hi


def basins(orbits, inv_beta=None, delta=None, seed=0):
    """Basins dataset on a grid (default the Fig. 15 grid) from an orbit map.

    Each stable type draws starts in proportion to 0.2 + S/100 against a coexisting motion
    of another type (0.25 .. 0.75, all of them where no type is stable); a share sticks (all
    below delta = -1.3: pressed to a pre-loaded wall), some is chaotic (where no type is
    stable, at small 1/beta), a little undecided.
    """
    rng = np.random.default_rng(seed)
    if inv_beta is None:
        inv_beta, delta = grid()
    on = _on_grid(orbits, inv_beta, delta)
    shape = (len(inv_beta), len(delta))
    listed = MOTIONS[:-1]
    n_stable = np.zeros((len(MOTIONS), *shape), int)
    weight = np.zeros((len(MOTIONS), *shape))
    for k, name in enumerate(listed):
        if name in on["type"].values:
            sel = on.sel(type=name)
            n_stable[k] = sel["n_stable"].values
            weight[k] = np.where(n_stable[k] > 0, 0.2 + np.nan_to_num(sel["S"].values) / 100,
                                 0.0)
    ib, d = np.meshgrid(inv_beta, delta, indexing="ij")
    stick = 0.03 + 0.97 / (1.0 + np.exp(10.0 * (d + 1.0)))    # pressed to a pre-loaded wall
    total = weight.sum(axis=0)
    chaotic = 3.0 * np.exp(-((ib - 0.6) ** 2 / 0.05 + (d - 0.3) ** 2 / 0.3)) * (total == 0)
    free = 1.0 - stick
    # a coexisting motion of another type draws starts everywhere: an impact motion, or
    # above delta = WALL_FREE_DELTA the wall-free linear response
    other = 0.25 + 0.5 * np.exp(-(d - 1.0) ** 2) + (total == 0)
    wall_free = np.where(d > WALL_FREE_DELTA, other, 0.0)
    other = other - wall_free
    p = np.concatenate([free * weight[:-1],
                        np.stack([other * free, stick, chaotic * free, 0.01 * free,
                                  wall_free * free])])
    p /= p.sum(axis=0, keepdims=True)
    counts = np.empty((p.shape[0], *shape), int)
    for i in range(shape[0]):
        for j in range(shape[1]):
            counts[:, i, j] = rng.multinomial(N_STARTS, p[:, i, j])
    k_listed = len(listed)
    count = np.concatenate([counts[:k_listed], counts[k_listed:].sum(axis=0)[None]])
    fraction = count / N_STARTS
    lo, hi = _clopper_pearson(count, N_STARTS)
    # near a pre-loaded wall a share of the starts sticks once per cycle
    stick_fraction = np.where(n_stable > 0, 0.4 * fraction * (d < 0.0)[None], 0.0)
    stick_fraction[-1] = np.nan
    class_count = np.concatenate([count[:k_listed].sum(axis=0)[None], counts[k_listed:]])
    dims = ("motion", "inv_beta", "delta")
    ds = xr.Dataset(
        {"fraction": (dims, fraction), "fraction_lo": (dims, lo), "fraction_hi": (dims, hi),
         "count": (dims, count), "n_stable": (dims, n_stable),
         "stick_fraction": (dims, stick_fraction),
         "class_fraction": (("class", "inv_beta", "delta"), class_count / N_STARTS)},
        coords={"motion": MOTIONS, "inv_beta": inv_beta, "delta": delta, "class": CLASSES},
        attrs=dict(zeta=orbits.attrs["zeta"], eps=orbits.attrs["eps"], n_starts=N_STARTS,
                   box=BOX))
    ds["fraction"].attrs.update(long_name="basin fraction", units="1")
    return ds


def lyapunov(basins_ds, seed=0):
    """Lyapunov dataset from a basins dataset: class of the cell the largest share, exponent
    negative where periodic (more so where the listed share is high), positive where chaotic,
    -inf where every start sticks, -zeta where no start impacts (large play)."""
    rng = np.random.default_rng(seed)
    cf = basins_ds["class_fraction"].values
    cell_class = np.argmax(cf, axis=0).astype("int8")
    zeta = float(basins_ds.attrs["zeta"])
    d = basins_ds["delta"].values[None, :] + 0.0 * basins_ds["inv_beta"].values[:, None]
    lam = np.select([cell_class == 3, cell_class == 4],
                    [0.05 + 0.1 * cf[3], 0.002 * rng.standard_normal(cell_class.shape)],
                    -zeta - 0.3 * cf[0])
    lam = np.where(cf[2] == 1.0, -np.inf, lam)
    impact_rate = np.where(d > WALL_FREE_DELTA, 0.0, 0.15 * (WALL_FREE_DELTA - d) / 3.7)
    lam = np.where(impact_rate == 0.0, -zeta, lam)
    # where some starts are chaotic, their positive exponent is the cell's largest
    lyapunov_class = np.where((cf[3] > 0) & (cell_class != 3), 3, cell_class).astype("int8")
    lam = np.where((cf[3] > 0) & (cell_class != 3), 0.05 + 0.1 * cf[3], lam)
    stderr = np.where(np.isin(cell_class, (3, 4)), 0.004, np.nan)
    dims = ("inv_beta", "delta")
    ds = xr.Dataset(
        {"lyapunov": (dims, lam), "lyapunov_stderr": (dims, stderr),
         "cell_class": (dims, cell_class), "impact_rate": (dims, impact_rate),
         "lyapunov_class": (dims, lyapunov_class),
         "class_fraction": basins_ds["class_fraction"]},
        coords={k: basins_ds[k] for k in ("inv_beta", "delta", "class")},
        attrs=dict(zeta=basins_ds.attrs["zeta"], eps=basins_ds.attrs["eps"]))
    for name in ("cell_class", "lyapunov_class"):
        ds[name].attrs.update(flag_values=np.arange(len(CLASSES), dtype="int8"),
                              flag_meanings=" ".join(CLASSES))
    ds["lyapunov"].attrs.update(long_name="largest Lyapunov exponent", units="1")
    return ds
