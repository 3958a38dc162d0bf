"""What a two-wall (clearance) study measures, in place of the paper's findings.

The paper's findings 1-7 read trends along delta, the play of one wall. With a second wall
at delta - gap, delta places a clearance: moving it shifts the two stops together, and the
settings at delta and gap - delta are mirror images of each other (x -> -x swaps the walls;
the force's harmonic part changes sign, which a shift of half a period undoes, and the
random part's law is even). So a two-wall study's report shows, per wall, the collision rate
and the mean velocity after impact (:func:`per_wall`), checks that mirror settings agree
within their intervals (:func:`mirror_pairs`, :func:`mirror_check`), and reads where the
motions sit against the two-wall stable domains through finding 8 (its claim does not name
the play). :func:`vibroimpact.reports.findings.harmonic_random` and ``random_force`` give
findings 1-7 ``n/a`` for a two-wall study and say why.

Mirror images: the upper wall at delta is the lower wall at gap - delta, and the two walls
need one restitution (``eps == eps_lower``). Two mirror cells run on the same record r(tau)
(common random numbers), whereas the mirror of a cell's motion is driven by -r(tau): they
are two realisations of one law, compared as independent estimates.
"""
import numpy as np

from vibroimpact._plane import DEFAULT_PLANE, dataset_axes
from vibroimpact.reports.findings import MIN_IMPACTS, Finding, _sentence

__all__ = ["MIRROR_CLAIM", "is_two_wall", "mirror_check", "mirror_pairs", "per_wall"]

#: The symmetry check's claim (the table's "claim" column).
MIRROR_CLAIM = ("Mirror images: the settings at delta and gap - delta (walls swapped, one "
                "restitution) agree within their 95 % intervals, each wall's statistics "
                "against the other wall's at the mirror play")

#: Statistics compared between mirror cells: (name, variable, its 95 % interval's bounds).
_STATISTICS = (("collision rate", "wall_collision_rate", "wall_collision_rate_lo",
                "wall_collision_rate_hi"),
               ("mean velocity after impact", "wall_v_after_mean", "wall_v_after_mean_lo",
                "wall_v_after_mean_hi"))
_MIRROR_WALL = {"upper": "lower", "lower": "upper"}


def is_two_wall(ds):
    """Whether ``ds`` is a two-wall study's dataset (attribute ``n_walls`` 2)."""
    return ds is not None and int(ds.attrs.get("n_walls", 1)) == 2


def mirror_pairs(ds):
    """The plays of ``ds`` whose mirror image is also in it: ``[(d, gap - d), ...]`` with
    ``d <= gap - d`` (a play at gap / 2 is its own mirror image: its two walls are compared).
    Empty when the walls' restitutions differ (then no setting is a mirror image), and for a
    map over another plane than (1/beta_f, delta) (its gap or restitutions may be axes)."""
    if set(dataset_axes(ds)) != set(DEFAULT_PLANE):     # either order of its axes
        return []
    gap = float(ds.attrs["gap"])
    if not np.isclose(float(ds.attrs["eps"]), float(ds.attrs["eps_lower"]), rtol=0, atol=1e-12):
        return []
    d = np.asarray(ds.delta, dtype=float)
    scale = max(1.0, float(np.abs(d).max()), gap)
    pairs = []
    for x in d:
        y = d[np.abs(d - (gap - x)) < 1e-9 * scale]
        if y.size and x <= y[0] + 1e-9 * scale:
            pairs.append((float(x), float(y[0])))
    return pairs


def per_wall(events):
    """Per wall and play (and 1/beta_f): the collisions, their rate and the mean velocity
    after impact with their 95 % intervals, the mean interval between collisions at the same
    wall, and the fraction that end sticking (a pandas DataFrame; the events dataset's
    ``wall_*`` variables, docs/datasets.md "Per wall")."""
    import pandas as pd

    rows = []
    rows_ib = np.atleast_1d(events.inv_beta.values) if "inv_beta" in events.dims else [None]
    for ib in rows_ib:
        ev = events.sel(inv_beta=ib) if ib is not None else events
        for d in ev.delta.values:
            for w in ev.wall.values:
                c = ev.sel(delta=d, wall=w)
                rows.append({
                    **({"1/beta_f": float(ib)} if ib is not None else {}),
                    "delta": float(d), "wall": str(w),
                    "collisions": int(c.wall_n_collisions),
                    "rate": float(c.wall_collision_rate),
                    "rate 95 %": f"[{float(c.wall_collision_rate_lo):.3g}, "
                                 f"{float(c.wall_collision_rate_hi):.3g}]",
                    "mean v after": float(c.wall_v_after_mean),
                    "v after 95 %": f"[{float(c.wall_v_after_mean_lo):.3g}, "
                                    f"{float(c.wall_v_after_mean_hi):.3g}]",
                    "mean interval (same wall)": float(c.wall_interval_mean),
                    "stuck fraction": float(c.wall_stuck_fraction)})
    return pd.DataFrame(rows)


def _interval(cell, low, high):
    return float(cell[low]), float(cell[high])


def mirror_table(events, spectra_shift=None):
    """Every comparison the symmetry check makes (a pandas DataFrame): per 1/beta_f, mirror
    pair and statistic, the wall at delta against the other wall at gap - delta, each with its
    95 % interval, and whether the intervals overlap (``agree``). A wall with fewer than
    `MIN_IMPACTS` collisions at either play is left out (its mean has no batch error to
    trust). ``spectra_shift``: ``{inv_beta: vibroimpact.stats.centroid.Shift}``, whose
    broadband centroids at mirror plays are compared too (a(tau) is measured from the wall at
    delta, so its fluctuation at gap - delta is the mirror's with its sign changed: the same
    spectrum)."""
    import pandas as pd

    rows = []
    pairs = mirror_pairs(events)
    rows_ib = np.atleast_1d(events.inv_beta.values) if "inv_beta" in events.dims else [None]
    for ib in rows_ib:
        ev = events.sel(inv_beta=ib) if ib is not None else events
        where = {"1/beta_f": float(ib)} if ib is not None else {}
        for d, m in pairs:
            walls = ["upper"] if d == m else ["upper", "lower"]
            for w in walls:
                a, b = ev.sel(delta=d, wall=w), ev.sel(delta=m, wall=_MIRROR_WALL[w])
                if min(int(a.wall_n_collisions), int(b.wall_n_collisions)) < MIN_IMPACTS:
                    continue
                for name, var, low, high in _STATISTICS:
                    rows.append(_compare(where, f"{name}", (d, w), float(a[var]),
                                         _interval(a, low, high), (m, _MIRROR_WALL[w]),
                                         float(b[var]), _interval(b, low, high)))
        if spectra_shift is not None and ib is not None:
            s = spectra_shift.get(float(ib))
            if s is not None and s.n_batches:
                at = {float(x): k for k, x in enumerate(s.delta)}
                for d, m in pairs:
                    if d != m and d in at and m in at:
                        i, j = at[d], at[m]
                        rows.append(_compare(
                            where, f"broadband centroid of a(tau) (beta <= {s.band:g})",
                            (d, "-"), s.centroid[i], (s.centroid_low[i], s.centroid_high[i]),
                            (m, "-"), s.centroid[j], (s.centroid_low[j], s.centroid_high[j])))
    return pd.DataFrame(rows)


def _mirror_motion(name):
    """The mirror image of a two-wall motion ``"(m_upper,m_lower)/n"``: its walls swapped."""
    head, _, n = str(name).partition(")/")
    upper, _, lower = head.lstrip("(").partition(",")
    return f"({lower},{upper})/{n}"


def map_mirror_table(motion_map, z=1.959963984540054):
    """The symmetry check on a two-wall probability map: per 1/beta_f and mirror pair, the
    probability of each motion at delta against that of its mirror motion (walls swapped) at
    gap - delta, each with the interval +-``z`` standard errors the cell reached
    (``probability_stderr``), and whether they overlap. Left out: cells where both are 0
    (nothing to compare) and a probability with standard error 0 (never seen, or always:
    its interval of width 0 is no measure of what a finite record leaves open)."""
    import pandas as pd

    rows = []
    pairs = mirror_pairs(motion_map)
    if not pairs:
        return pd.DataFrame(rows)
    motions = [str(m) for m in motion_map.motion.values]
    for ib in np.atleast_1d(motion_map.inv_beta.values):
        where = {"1/beta_f": float(ib)}
        for d, m in pairs:
            for name in motions:
                mirror = _mirror_motion(name)
                if mirror not in motions or (
                        d == m and motions.index(mirror) < motions.index(name)):
                    continue
                a = motion_map.sel(inv_beta=ib, delta=d, motion=name)
                b = motion_map.sel(inv_beta=ib, delta=m, motion=mirror)
                pa, pb = float(a.probability), float(b.probability)
                sa, sb = z * float(a.probability_stderr), z * float(b.probability_stderr)
                if (d == m and name == mirror) or not (sa > 0.0 and sb > 0.0):
                    continue
                rows.append(_compare(where, f"P({name})", (d, "-"), pa, (pa - sa, pa + sa),
                                     (m, "-"), pb, (pb - sb, pb + sb)))
                if mirror != name:
                    rows[-1]["statistic"] = f"P({name}) against P({mirror})"
    return pd.DataFrame(rows)


def _compare(where, name, at_a, a, ia, at_b, b, ib):
    agree = bool(ia[0] <= ib[1] and ib[0] <= ia[1])
    return {**where, "statistic": name, "delta": at_a[0], "wall": at_a[1], "value": a,
            "95 %": f"[{ia[0]:.3g}, {ia[1]:.3g}]", "mirror delta": at_b[0],
            "mirror wall": at_b[1], "mirror value": b,
            "mirror 95 %": f"[{ib[0]:.3g}, {ib[1]:.3g}]", "agree": agree}


def mirror_check(events=None, spectra_shift=None, motion_map=None):
    """The symmetry check as a finding (:class:`vibroimpact.reports.findings.Finding`,
    number ``"mirror"``) over :func:`mirror_table` (an events study) and
    :func:`map_mirror_table` (a map study): ``yes`` when every comparison agrees, ``partly``
    when at least 3 in 4 do, ``no`` otherwise; ``n/a`` when no setting is another's mirror
    image (the restitutions differ, or no play's mirror is in the grid) or nothing is left to
    compare. Overlapping 95 % intervals is a loose test for one pair; over many pairs a few
    may still miss by chance, which ``measured`` names with their numbers."""
    ds = events if events is not None else motion_map
    if not is_two_wall(ds):
        return Finding("mirror", MIRROR_CLAIM, "a one-wall study: no mirror image", "n/a")
    axes = dataset_axes(ds)
    if set(axes) != set(DEFAULT_PLANE):
        return Finding("mirror", MIRROR_CLAIM, f"the map runs over ({axes[0]}, {axes[1]}): "
                       f"the check pairs the plays delta and gap - delta at each 1/beta_f, "
                       f"one gap and one restitution (a map over (1/beta_f, delta))", "n/a")
    gap = float(ds.attrs["gap"])
    if not mirror_pairs(ds):
        eps, eps_l = float(ds.attrs["eps"]), float(ds.attrs["eps_lower"])
        why = (f"the walls' restitutions differ (eps = {eps:g}, eps_lower = {eps_l:g}): no "
               f"setting is the mirror image of another" if eps != eps_l else
               f"no play of the grid has its mirror image gap - delta (gap = {gap:g}) in it")
        return Finding("mirror", MIRROR_CLAIM, why, "n/a")
    import pandas as pd

    table = pd.concat([mirror_table(events, spectra_shift) if events is not None else None,
                       map_mirror_table(motion_map) if motion_map is not None else None])
    pairs = ", ".join(f"delta = {d:g} and {m:g}" if d != m else f"delta = {d:g} (its two walls)"
                      for d, m in mirror_pairs(ds))
    if table.empty:
        return Finding("mirror", MIRROR_CLAIM, f"mirror pairs {pairs}: nothing to compare "
                       f"(too few collisions, or probabilities without an error)", "n/a")
    n, n_agree = len(table), int(table.agree.sum())
    missed = table[~table.agree]
    measured = (f"gap = {gap:g}, one restitution; mirror pairs {pairs}; {n_agree} of {n} "
                f"comparisons agree")
    if len(missed):
        measured += "; apart: " + "; ".join(
            (f"1/beta_f = {r['1/beta_f']:.3g}, " if "1/beta_f" in r else "")
            + f"{r.statistic} at delta = {r.delta:g}"
            + (f" ({r.wall})" if r.wall != "-" else "") + f": {r.value:.3g} {r['95 %']} "
            f"against {r['mirror value']:.3g} {r['mirror 95 %']} at delta = "
            f"{r['mirror delta']:g}" + (f" ({r['mirror wall']})" if r.wall != "-" else "")
            for _, r in missed.iterrows())
    holds = "yes" if n_agree == n else ("partly" if n_agree >= 0.75 * n else "no")
    summary = "" if holds == "yes" else _sentence(
        f"{n_agree} of {n} mirror comparisons agree within their 95 % intervals"
        if holds == "partly" else None,
        f"{n - n_agree} {'is' if n - n_agree == 1 else 'are'} apart (the intervals do not "
        f"overlap)")
    return Finding("mirror", MIRROR_CLAIM, measured, holds, summary)
