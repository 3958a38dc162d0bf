"""Switching between the motions of a probability map (Fig. 15): is it Markov?

The map stores per cell the residence times in each state (the motions, "none") and the rates
of switching between them (docs/datasets.md). Two questions, two functions:

- :func:`stationary_check`: the stationary distribution of the rate matrix against the
  fractions of time the map stores (each motion's probability plus its impact-stick variant,
  "none" the rest). They agree for any record, Markov or not, up to the record's ends (flux
  balance: the switches into a state and out of it differ by at most one;
  `stats.residence_statistics`): a check of the bookkeeping, which a test holds within the
  probabilities' errors.
- :func:`markov_cells`: the real diagnostic, whether the residence times are memoryless
  (`stats.markov_residence_check`: the coefficient of variation of the complete stretches
  against a Markov chain's). The map does not store the sequence of stretches, so the second
  consequence, a first-order jump chain (`stats.jump_chain_independence`), is not checked
  here.
"""
import numpy as np

__all__ = ["stationary_check", "markov_cells", "markov_summary"]

_PLANE = ("inv_beta", "delta")


def _plane(motion_map):
    """The map's two grid dims, x first: its ``axes`` attribute (a map over any two
    parameters, docs/datasets.md), the default (inv_beta, delta) without one."""
    axes = motion_map.attrs.get("axes")
    if axes is None:
        return _PLANE
    return tuple(str(a) for a in ([axes] if isinstance(axes, str) else axes))


def stationary_check(motion_map):
    """The rate matrix's stationary distribution against the stored fractions of time.

    Returns
    -------
    dict of ndarray, shape (n_inv_beta, n_delta, n_states)
        ``pi`` (`stats.stationary_distribution` of ``switch_rate``), ``fraction``
        (``probability + stick_probability`` per motion, "none" = 1 - their sum), ``stderr``
        (of the fraction: the two standard errors in quadrature; for "none", all of them in
        quadrature) and ``within`` (``|pi - fraction| <= stderr``; a NaN ``pi``, not unique,
        counts as not within); and ``n_switches``, shape (n_inv_beta, n_delta): the cell's
        switches. The identity holds up to one unbalanced switch at the record's ends, a
        large share of the flux in a cell with few switches: there ``pi`` may put its weight
        on the state the record ends in (measured on the default map: every cell with 10
        switches or more within one standard error, the 79 cells outside it have at most 7).
    """
    from vibroimpact import stats

    plane = _plane(motion_map)
    rate = motion_map["switch_rate"].transpose(*plane, "from_motion", "to_motion").values
    p = (motion_map["probability"] + motion_map["stick_probability"]).transpose(
        *_plane(motion_map), "motion").values
    err = np.hypot(motion_map["probability_stderr"], motion_map["stick_probability_stderr"])
    err = err.transpose(*_plane(motion_map), "motion").values
    fraction = np.concatenate([p, 1.0 - p.sum(axis=-1, keepdims=True)], axis=-1)
    stderr = np.concatenate([err, np.sqrt((err ** 2).sum(axis=-1, keepdims=True))], axis=-1)
    pi = np.stack([[stats.stationary_distribution(r) for r in row] for row in rate])
    switches = motion_map["switch_count"].sum(("from_motion", "to_motion"))
    return dict(pi=pi, fraction=fraction, stderr=stderr,
                within=np.abs(pi - fraction) <= stderr,
                n_switches=switches.transpose(*_plane(motion_map)).values)


def _unit(state):
    """Forcing periods of one group of motion ``state`` ("m/n": n). NaN for "none": its
    stretches are whole unclassified intervals of any length, so a Markov chain gives a CV
    anywhere between that of a geometric number of steps and 1; it is shown, not judged."""
    return float(state.split("/")[1]) if "/" in state else np.nan


def markov_cells(motion_map):
    """`stats.markov_residence_check` of every state and cell of the map.

    Returns
    -------
    dict
        ``{state: stats.MarkovCheck}`` with arrays over (inv_beta, delta); a motion (m/n) is
        judged in units of its n forcing periods, "none" not at all (its ``markov`` NaN).
    """
    from vibroimpact import stats

    stay = stats.by_state(motion_map)
    out = {}
    for state in (str(s) for s in stay["state"].values):
        r = stay.sel(state=state).transpose(*_plane(motion_map), ...)
        out[state] = stats.markov_residence_check(
            r["residence_time"].values, r["residence_time_stderr"].values,
            r["n_stretches"].values, unit=_unit(state))
    return out


def _where(motion_map, mask, limit=6):
    """The cells of ``mask`` as text, ``(1/beta_f, delta)`` pairs, at most ``limit`` of them."""
    i, j = np.nonzero(mask)
    xn, yn = _plane(motion_map)
    x, y = motion_map[xn].values[i], motion_map[yn].values[j]
    cells = [f"({a:.3g}, {b:.3g})" for a, b in zip(x, y)]
    more = f" and {len(cells) - limit} more" if len(cells) > limit else ""
    return ", ".join(cells[:limit]) + more


def markov_summary(motion_map):
    """Per state, over the map's cells with at least `stats.residence.MARKOV_MIN_STRETCHES`
    complete stretches: how many look Markov, too regular (CV below a Markov chain's) or too
    irregular (above), the median CV against the Markov one, and where the cells that are
    not Markov lie (1/beta_f, delta). "none" is shown, not judged (:func:`markov_cells`).

    Returns
    -------
    pandas.DataFrame
        One row per state; ``attrs["note"]``: the bookkeeping check (:func:`stationary_check`)
        in words.
    """
    import pandas as pd

    from vibroimpact.stats.residence import MARKOV_MIN_STRETCHES, by_state

    stretches = by_state(motion_map)["n_stretches"]
    rows = {}
    for state, check in markov_cells(motion_map).items():
        n = stretches.sel(state=state).transpose(*_plane(motion_map)).values
        enough = (n >= MARKOV_MIN_STRETCHES) & np.isfinite(check.cv)
        judged = np.isfinite(check.markov)
        regular = judged & (check.markov == 0.0) & (check.z < 0)
        irregular = judged & (check.markov == 0.0) & (check.z > 0)
        verdict = judged.any() or state != "none"
        rows["none" if state == "none" else f"({state})"] = {
            f"cells with >= {MARKOV_MIN_STRETCHES} stretches": int(enough.sum()),
            "close to Markov": int((check.markov == 1.0).sum()) if verdict else "",
            "too regular": int(regular.sum()) if verdict else "",
            "too irregular": int(irregular.sum()) if verdict else "",
            "median CV": f"{np.median(check.cv[enough]):.2f}" if enough.any() else "",
            "median Markov CV": (f"{np.median(check.cv_markov[judged]):.2f}"
                                 if judged.any() else "not judged" if not verdict else ""),
            f"not Markov at ({', '.join(_plane(motion_map))})".replace(
                "inv_beta", "1/beta_f"): _where(motion_map, regular | irregular),
        }
    table = pd.DataFrame.from_dict(rows, orient="index")
    table.attrs["note"] = _bookkeeping_text(motion_map)
    return table


def _bookkeeping_text(motion_map):
    """:func:`stationary_check` in words: in the cells with at least ``min_switches``
    switches (the map's attribute, 10 if absent), and how many of the others miss."""
    s = stationary_check(motion_map)
    many = s["n_switches"] >= int(motion_map.attrs.get("min_switches", 10))
    within = s["within"].all(axis=-1)
    deviation = np.abs(s["pi"] - s["fraction"]).max(axis=-1)
    text = (f"Stationary distribution of the switching rates against the fractions of time "
            f"(the bookkeeping, Markov or not): in the {int(many.sum())} cells with "
            f"{int(motion_map.attrs.get('min_switches', 10))} switches or more, within one "
            f"standard error in {int(within[many].sum())} (largest |pi - fraction| "
            f"{np.nanmax(deviation[many], initial=0.0):.3g})")
    few = ~many & ~within
    if few.any():
        text += (f"; {int(few.sum())} of the {int((~many).sum())} cells with fewer switches "
                 f"are not (the switch left unbalanced at the record's end weighs there)")
    return text + "."
