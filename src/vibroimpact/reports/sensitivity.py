"""The weight of the collision rule: each statistic a figure draws under every grouping rule.

Every impact statistic counts collisions (docs/figures.md, "Collisions"), grouped by the
physical rule: a chatter sequence is joined by hops that the push ``f - delta`` presses
throughout. The events and map datasets also carry the same statistics under the earlier,
impacts-only rule and per rebound above the study's ``rebound_floor`` (``rule_*`` variables,
dimension ``rule``, docs/datasets.md). :func:`rule_sensitivity` tabulates them with the
largest difference from the physical rule; :func:`finding_sensitivity` re-reads findings 2
and 3 (mean velocity after impact and mean interval against delta) under each rule and names
the largest difference at negative play, where they depend on the grouping.

Nothing here is typed in: the tables are read from the datasets as written.
"""
import math

import numpy as np
import pandas as pd

#: The rules as the datasets name them, and as the tables head them.
RULE_NAMES = {"physical": "physical (used)", "impacts": "impacts only (earlier)",
              "rebounds": "per rebound above floor"}
#: The events datasets' statistics under each rule, and their names in the table.
_EVENT_STATISTICS = (("rule_collision_rate", "collision rate"),
                     ("rule_v_after_mean", "mean velocity after impact"),
                     ("rule_interval_mean", "mean interval"))
#: Plays tabulated when none are given: negative play (findings 2 and 3), zero, positive.
DEFAULT_DELTAS = (-1.0, -0.5, 0.0, 0.5, 1.0)


def _has_rules(ds):
    return ds is not None and "rule" in ds.dims


def _plays(ds, deltas):
    """The plays of ``ds`` nearest to ``deltas`` (each once, in order)."""
    grid = np.asarray(ds.delta.values, dtype=float)
    wanted = DEFAULT_DELTAS if deltas is None else deltas
    picked = [float(grid[np.argmin(abs(grid - d))]) for d in wanted]
    return sorted(set(picked))


def _row(values, name, **where):
    """One table row: the statistic under each rule and the largest relative difference from
    the physical rule (in % of it; NaN when it is 0 or missing)."""
    ref = values.get("physical", math.nan)
    others = [abs(v - ref) for r, v in values.items() if r != "physical" and np.isfinite(v)]
    largest = max(others) if others and np.isfinite(ref) else math.nan
    rel = 100.0 * largest / abs(ref) if np.isfinite(largest) and ref != 0 else math.nan
    return dict(where, statistic=name, **{RULE_NAMES[r]: v for r, v in values.items()},
                **{"largest difference": largest, "largest difference (%)": rel})


def rule_sensitivity(events=None, motion_map=None, deltas=None, map_cells=((2.0, -0.5),)):
    """Each collision statistic a figure draws under the three grouping rules.

    Parameters
    ----------
    events : xarray.Dataset, optional
        An events dataset (random or harmonic study) with ``rule_*`` variables.
    motion_map : xarray.Dataset, optional
        A map dataset with ``rule_probability``, ``rule_stick_probability``.
    deltas : sequence of float, optional
        Plays of the events dataset (nearest on its grid; default `DEFAULT_DELTAS`).
    map_cells : sequence of (1/beta_f, delta)
        Cells of the map (nearest on its grid).

    Returns
    -------
    pandas.DataFrame
        One row per (dataset, 1/beta_f, delta, statistic): the rate, mean velocity after
        impact and mean interval, and for a harmonic study or the map P of each motion and of
        its impact-stick variant ("P(2/1)", "P(2/1) stick"); columns the rules, the largest
        absolute difference from the physical rule and that difference in % of it. Empty when
        no dataset carries the rules (made before they were stored).
    """
    rows = []
    if _has_rules(events):
        rules = [str(r) for r in events.rule.values]
        harmonic = "rule_motion_probability" in events
        for inv_beta in events.inv_beta.values:
            for delta in _plays(events, deltas):
                cell = events.sel(inv_beta=inv_beta, delta=delta)
                where = dict(dataset="events", inv_beta=float(inv_beta) if harmonic else math.nan,
                             delta=delta)
                for var, name in _EVENT_STATISTICS:
                    rows.append(_row({r: float(cell[var].sel(rule=r)) for r in rules}, name,
                                     **where))
                if harmonic:
                    for motion in cell.motion.values:
                        for var, suffix in (("rule_motion_probability", ""),
                                            ("rule_motion_stick_probability", " stick")):
                            vals = {r: float(cell[var].sel(rule=r, motion=motion))
                                    for r in rules}
                            rows.append(_row(vals, f"P({motion}){suffix}", **where))
    if _has_rules(motion_map):
        rules = [str(r) for r in motion_map.rule.values]
        axes = motion_map.attrs.get("axes")
        if axes is not None:    # a map over another plane: its middle cell, named by its axes
            x, y = (str(a) for a in axes)
            middle = {x: motion_map.sizes[x] // 2, y: motion_map.sizes[y] // 2}
            picked = [motion_map.isel(middle)]
        else:
            picked = [motion_map.sel(inv_beta=inv_beta, delta=delta, method="nearest")
                      for inv_beta, delta in map_cells]
        for cell in picked:
            where = dict(dataset="map", inv_beta=float(cell.inv_beta),
                         delta=float(cell.delta))
            if axes is not None:        # the plane's values (a fixed one is an attribute)
                where.update(inv_beta=math.nan, delta=math.nan)
                where.update({str(a): float(cell[str(a)]) for a in axes})
            for motion in cell.motion.values:
                for var, suffix in (("rule_probability", ""), ("rule_stick_probability",
                                                               " stick")):
                    vals = {r: float(cell[var].sel(rule=r, motion=motion)) for r in rules}
                    rows.append(_row(vals, f"P({motion}){suffix}", **where))
    return pd.DataFrame(rows)


def finding_sensitivity(events, findings=(2, 3)):
    """Findings 2 and 3 re-read under each grouping rule, with the largest difference at
    negative play named.

    Each finding's function (:mod:`vibroimpact.reports.findings`) is run on the dataset with
    its statistics (``v_after_mean``, ``interval_mean``, ``n_collisions``) replaced by those
    of the rule, so the verdict is the one that rule would give.

    Returns
    -------
    pandas.DataFrame
        One row per finding (and per 1/beta_f of a harmonic study): its verdict under each
        rule, and the largest difference between
        the rules over the negative plays with collisions (the statistic, the play, its value
        under each rule). Empty when ``events`` carries no rules, and for a two-wall study
        (findings 2 and 3 read the paper's play, which delta is not there).
    """
    if not _has_rules(events) or int(events.attrs.get("n_walls", 1)) == 2:
        return pd.DataFrame()
    rules = [str(r) for r in events.rule.values]
    rows = []
    for i in range(events.sizes.get("inv_beta", 1)):
        ds = events.isel(inv_beta=slice(i, i + 1)) if "inv_beta" in events.dims else events
        where = ({"inv_beta": float(ds.inv_beta[0])} if events.sizes.get("inv_beta", 1) > 1
                 else {})
        rows += [dict(finding=number, **where, **row)
                 for number in findings for row in [_one_finding(ds, number, rules)]]
    return pd.DataFrame(rows)


def _one_finding(events, number, rules):
    """One finding's verdict under each rule and its largest difference at negative play,
    on a dataset of one row of 1/beta_f."""
    from vibroimpact.reports import findings as fnd

    plain, by_rule, name = {2: ("v_after_mean", "rule_v_after_mean",
                                "mean velocity after impact"),
                            3: ("interval_mean", "rule_interval_mean", "mean interval")}[number]
    verdict = {}
    for r in rules:
        ds = events.assign({plain: events[by_rule].sel(rule=r, drop=True),
                            "n_collisions": events["rule_n_events"].sel(rule=r, drop=True)})
        verdict[RULE_NAMES[r]] = getattr(fnd, f"finding{number}")(ds).holds
    # the largest relative spread between the rules at negative play
    neg = events[by_rule].where((events.delta < 0) & (events.rule_n_events >= fnd.MIN_IMPACTS))
    ref = neg.sel(rule="physical", drop=True)
    spread = (abs(neg - ref).max("rule") / abs(ref)).fillna(-1.0)
    text = "no negative play with collisions"
    if float(spread.max()) >= 0:
        at = spread.argmax(...)
        cell = neg.isel(at)
        values = ", ".join(f"{RULE_NAMES[r]} {float(cell.sel(rule=r)):.3g}" for r in rules)
        text = (f"{name} at delta = {float(cell.delta):.3g}: {values} "
                f"({100 * float(spread.isel(at)):.0f} % of the physical value)")
    return {**verdict, "largest difference at negative play": text}


def styled(table):
    """A table of this module for a report: numbers to three significant digits, text left
    aligned and wrapped, no index."""
    numbers = table.select_dtypes("number").columns
    return (table.style.format("{:.3g}", subset=numbers, na_rep="")
            .set_properties(**{"text-align": "left", "white-space": "normal"})
            .hide(axis="index"))
