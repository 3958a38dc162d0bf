"""The paper's findings (docs/figures.md, points 1-8), each measured on a run's datasets.

Every function takes the datasets a finding is about (as written by the workflow,
``docs/datasets.md``) and returns a :class:`Finding`: the paper's claim, what this run
measured, and whether the claim holds on it (``"yes"``, ``"partly"``, ``"no"``, or ``"n/a"`` when
the datasets cannot decide it: missing, or, for the findings on collisions (2-4, 6, 7), a record
with no collision at any play, which ``measured`` then says). Every ``"partly"`` (and ``"no"``)
verdict also carries ``summary``: one sentence, from the same numbers, saying what holds and
what does not, which the table puts first. The report notebooks show them as a table
(:func:`findings_table`); the workflow tests assert them on the test config.
Nothing here is typed in from a previous run: change a dataset and the verdict changes with it.

Findings 1-7 read trends along delta, the play of the paper's one wall. On a two-wall study
(attribute ``n_walls`` 2) delta places a clearance between two stops, and the settings at
delta and gap - delta are mirror images: those findings are ``n/a`` there, and the study's
own checks are in :mod:`vibroimpact.reports.two_walls`. Finding 8 (stable domains against
the probability map) names no play and is read on either.

The thresholds are the ones stated with each claim below; "within the resolution" means one
bin of the density or the frequency grid.
"""
from dataclasses import dataclass

import numpy as np

from vibroimpact.stats.centroid import (BAND_CHOICES, CENTROID_BAND, FILL_CHOICES, LINE_BINS,
                                        LINE_BINS_CHOICES, shift)
from vibroimpact.stats.theory import upcrossing_rate

#: Fewest impacts a play needs before its means and densities take part in a finding
#: (the batch-means error of a mean over 1000 impacts is a few percent).
MIN_IMPACTS = 1000

CLAIMS = {
    1: "Random force: the PSD of a(tau) peaks near the resonance; as delta decreases the peak "
       "frequency rises and its level falls; at delta = 0 no marked peak remains",
    2: "Impact velocities become smaller as delta decreases, markedly so for negative delta",
    3: "The intervals between impacts follow the same trend",
    4: "Mean velocity and mean interval grow with delta, until past a critical delta no impact "
       "happens",
    5: "Harmonic + random: the input's power is concentrated at the forcing frequency; the "
       "response's power spreads wider and moves to lower frequency as delta decreases",
    6: "Large play: the density of z_j/z peaks at 1, the (1/1) motion; small play: two curves "
       "symmetric about 1/2, the (2/1) motion",
    7: "The velocity after impact is narrowly spread where (1/1) dominates, widely where the "
       "play is small",
    8: "Where the periodic motion is stable with a high degree of stability (Fig. 16), it shows "
       "up with high probability under noise (Fig. 15): the domains look alike",
}


@dataclass(frozen=True)
class Finding:
    """One of the paper's findings measured on a run.

    Attributes
    ----------
    number : int
        Its number in docs/figures.md (1-8).
    claim : str
        What the paper says.
    measured : str
        The numbers this run gives, with the plays and frequencies they are taken at.
    holds : str
        ``"yes"``, ``"partly"`` (the stated part holds, the rest not), ``"no"``, or ``"n/a"``
        (the datasets given cannot decide it; ``measured`` says what is missing).
    summary : str
        One sentence, computed from the same numbers as ``measured``: what holds and what
        does not ("Holds: ...; does not: ..."). Every ``"partly"`` verdict has one; ``""``
        where ``measured`` says it alone.
    """

    number: int
    claim: str
    measured: str
    holds: str
    summary: str = ""


def _finding(number, measured, holds, summary=""):
    return Finding(number, CLAIMS[number], measured, holds, summary)


def _sentence(holds=None, fails=None):
    """``"Holds: <holds>; does not: <fails>."``, either part left out when None."""
    parts = ([f"Holds: {holds}"] if holds else []) + (
        [("does not: " if holds else "Does not hold: ") + fails] if fails else [])
    return "; ".join(parts) + "."


def not_available(number, why):
    """The finding cannot be measured on this study's datasets; ``why`` says what is missing."""
    return _finding(number, why, "n/a")


def _yes(condition):
    return "yes" if condition else "no"


def _increasing(values):
    return bool(np.all(np.diff(np.asarray(values, dtype=float)) > 0))


def _fmt(values, spec=".3g"):
    return ", ".join(format(float(v), spec) for v in values)


def _two_walls(ds, number):
    """Finding ``number`` ``n/a`` on a two-wall study's dataset ``ds`` (None on one wall)."""
    if ds is None or int(ds.attrs.get("n_walls", 1)) != 2:
        return None
    return not_available(number, f"a two-wall study (the second wall at delta - "
                                 f"{float(ds.attrs['gap']):g}): delta places a clearance, "
                                 f"not the paper's play, and the settings at delta and gap - "
                                 f"delta are mirror images; the two-wall checks replace it")


def _without_collision(events):
    """Why ``events`` (one 1/beta row or all) cannot decide a finding on collisions: the
    record has none at any play (and, with no force at all, that the mass stays at rest);
    None when some play has one."""
    if int(events.n_collisions.sum()) > 0:
        return None
    why = f"no collision in this record at any play (delta = {_fmt(np.unique(events.delta))})"
    zero = (float(events.attrs.get("noise_rms", 1.0)) == 0.0
            and float(events.attrs.get("amplitude", 1.0)) == 0.0)
    return why + ("; the force is zero (rms 0, no harmonic): the mass stays at rest" if zero
                  else "")


def _impacting(events, minimum=MIN_IMPACTS):
    """The plays with at least ``minimum`` collisions (one 1/beta row), in increasing delta."""
    keep = events.delta[events.n_collisions >= minimum]
    return events.sel(delta=keep).sortby("delta")


def _row(ds, inv_beta=None):
    """One 1/beta_f row of a dataset (the nearest to ``inv_beta``, or the only one)."""
    if "inv_beta" not in ds.dims:
        return ds
    if inv_beta is None:
        if ds.sizes["inv_beta"] != 1:
            raise ValueError(f"the dataset has {ds.sizes['inv_beta']} rows of 1/beta_f; "
                             f"give inv_beta")
        return ds.isel(inv_beta=0)
    return ds.sel(inv_beta=inv_beta, method="nearest")


# --- random force (Figs. 6-9) -----------------------------------------------------------------

def finding1(spectra, band=(0.2, 3.0), flat=3.0):
    """PSD of a(tau) against delta (Fig. 6).

    Over ``band`` of beta, for the plays delta > 0 in decreasing order, the peak frequency must
    rise (never fall by a bin of the spectrum, and end higher than it starts: plays too large
    to be hit share the linear peak's bin) and the peak level fall; at delta = 0 the peak must
    be below ``flat`` times the median (no marked peak). A zero random force (the linear
    reference ``S_lin`` zero) or fewer than two frequencies in ``band`` leave nothing to
    judge: ``n/a``.
    """
    if (two := _two_walls(spectra, 1)) is not None:
        return two
    s = _row(spectra).sel(beta=slice(*band))
    if s.sizes["beta"] < 2:
        step = float(spectra.beta[1] - spectra.beta[0])
        return not_available(1, f"the spectrum's resolution (beta step {step:.3g}) leaves "
                                f"{s.sizes['beta']} frequencies in {band[0]:g} <= beta <= "
                                f"{band[1]:g}; a finer one needs a longer spectra.nperseg")
    if "S_lin" in s and not float(s.S_lin.max()) > 0.0:
        return not_available(1, "the random force is zero (rms 0): a(tau) has no spectrum")
    positive = s.sel(delta=s.delta[s.delta > 0]).sortby("delta", ascending=False)
    if positive.sizes["delta"] < 2 or 0.0 not in s.delta.values:
        return not_available(1, f"needs spectra at two plays > 0 and at delta = 0; this study "
                                f"has delta = {_fmt(s.delta.values)}")
    peak_beta = positive.S_a.idxmax("beta").values
    peak_level = positive.S_a.max("beta").values
    at_zero = s.S_a.sel(delta=0.0)
    sharpness = float(at_zero.max() / at_zero.median())
    step = float(s.beta[1] - s.beta[0])
    rises = bool(np.all(np.diff(peak_beta) > -0.5 * step) and peak_beta[-1] > peak_beta[0])
    falls, flat_at_zero = _increasing(-peak_level), sharpness < flat
    measured = (f"delta = {_fmt(positive.delta.values)}: peak at beta = {_fmt(peak_beta)}, "
                f"level {_fmt(peak_level)}; at delta = 0 peak / median = {sharpness:.2f} "
                f"(< {flat:g} counts as no marked peak)")
    return _finding(1, measured, _yes(rises and falls and flat_at_zero))


def finding2(events):
    """Mean velocity after impact against delta (Figs. 7, 9): increasing over the plays with
    impacts, and "markedly so for negative delta": it falls faster, relative to its value,
    over the negative plays than over as wide a range of positive ones (the mean slope of
    ln v against delta on [delta_min, 0] exceeds that on [0, -delta_min])."""
    if (two := _two_walls(events, 2)) is not None:
        return two
    if (why := _without_collision(_row(events))) is not None:
        return not_available(2, why)
    ev = _impacting(_row(events))
    if ev.sizes["delta"] < 3:
        return not_available(2, f"needs three plays with >= {MIN_IMPACTS} impacts")
    d, v = ev.delta.values, ev.v_after_mean.values
    measured = (f"mean velocity after impact {v[-1]:.3g} at delta = {d[-1]:.3g} down to "
                f"{v[0]:.3g} at delta = {d[0]:.3g}"
                f"{', increasing throughout' if _increasing(v) else ', not monotone'}")
    if not np.any(v > 0.0):
        # eps = 0 (plastic impact): the mass leaves the wall at rest after every impact
        return not_available(2, "the mean velocity after impact is 0 at every play (eps = 0: "
                                "plastic impact)")
    marked = True
    at = lambda x: float(ev.v_after_mean.sel(delta=x, method="nearest"))
    if d[0] < 0 and 0.0 in d and d[-1] >= -d[0] and min(at(d[0]), at(0.0), at(-d[0])) > 0.0:
        slope_neg = np.log(at(0.0) / at(d[0])) / -d[0]
        slope_pos = np.log(at(-d[0]) / at(0.0)) / -d[0]
        marked = slope_neg > slope_pos
        measured += (f"; it falls x {at(0.0) / at(d[0]):.1f} from delta = 0 to {d[0]:.3g} "
                     f"against x {at(-d[0]) / at(0.0):.1f} from {-d[0]:.3g} to 0")
    return _finding(2, measured, _yes(_increasing(v) and marked))


def finding3(events):
    """Mean interval between collisions against delta (Figs. 8, 9): increasing over the plays
    with impacts. On a pre-loaded wall the mass rests long on it between collisions, so the
    interval may grow again at the lowest plays: ``yes`` when it increases over every play,
    ``partly`` when it increases from some play <= 0 upwards (the table says where it turns
    and the contact fraction below), ``no`` otherwise."""
    if (two := _two_walls(events, 3)) is not None:
        return two
    if (why := _without_collision(_row(events))) is not None:
        return not_available(3, why)
    ev = _impacting(_row(events))
    if ev.sizes["delta"] < 3:
        return not_available(3, f"needs three plays with >= {MIN_IMPACTS} collisions")
    d, z = ev.delta.values, ev.interval_mean.values
    rising = np.diff(z) > 0
    # the first play from which the mean interval increases all the way up
    turn = int(rising.size - np.argmin(rising[::-1])) if not rising.all() else 0
    measured = (f"mean interval {z[-1]:.3g} at delta = {d[-1]:.3g} down to {z[turn]:.3g} at "
                f"delta = {d[turn]:.3g}, increasing from there up")
    if turn == 0:
        return _finding(3, measured + " over every play", "yes")
    below = ev.isel(delta=slice(0, turn))
    measured += (f"; below it: {_fmt(below.interval_mean.values)} at delta = "
                 f"{_fmt(below.delta.values)}, contact fraction "
                 f"{_fmt(below.contact_fraction.values, '.2f')}")
    holds = "partly" if d[turn] <= 0.0 else "no"
    summary = _sentence(
        f"the mean interval grows with delta from delta = {d[turn]:.3g} up ({z[turn]:.3g} -> "
        f"{z[-1]:.3g})" if holds == "partly" else None,
        f"below delta = {d[turn]:.3g} it grows again as delta falls (to {z[0]:.3g} at "
        f"delta = {d[0]:.3g}), where the mass rests on the wall for a fraction "
        f"{float(below.contact_fraction.max()):.2f} of the time")
    return _finding(3, measured, holds, summary)


def finding4(events, orders=2.0):
    """Collision rate against delta (Fig. 9): for delta > 0 it never rises and falls by at least
    ``orders`` orders of magnitude.

    Whether "past a critical play no impact happens" is read against Rice's up-crossing rate
    of the wall-free response (`vibroimpact.stats.upcrossing_rate`, from the dataset's
    ``linear_sigma_x/_v``): where the record holds no collision and Rice's rate expects fewer
    than 3 in its length, the impacts stop at the record's reach, not at a threshold of the
    system ("partly": the rate falls, it does not vanish). Without those attributes only the
    fall is read ("yes").
    """
    if (two := _two_walls(events, 4)) is not None:
        return two
    ev = _row(events).sortby("delta")
    if (why := _without_collision(ev)) is not None:
        return not_available(4, why)
    d, rate = ev.delta.values, ev.collision_rate.values
    positive = (d > 0) & (rate > 0)
    if positive.sum() < 3:
        return not_available(4, "needs three plays > 0 with impacts")
    low = float(rate[positive].min())
    at_low = float(d[positive][np.argmin(rate[positive])])
    fall = np.log10(rate.max() / low)
    none = d[(d > at_low) & (ev.n_collisions.values == 0)]
    measured = (f"collision rate falls from {rate.max():.3g} to {low:.3g} per unit time at "
                f"delta = {at_low:.3g} ({fall:.1f} orders of magnitude); "
                + (f"no impact from delta = {none.min():.3g} on" if none.size else
                   "every play of the grid still has impacts"))
    falling = bool(np.all(np.diff(rate[d > 0]) <= 0)) and fall >= orders
    sigma = (ev.attrs.get("linear_sigma_x"), ev.attrs.get("linear_sigma_v"))
    record = ev.attrs.get("record_length")
    if not falling:
        rises = bool(np.any(np.diff(rate[d > 0]) > 0))
        return _finding(4, measured, "no", _sentence(fails=(
            "the collision rate rises between some plays delta > 0" if rises else
            f"the collision rate falls only {fall:.1f} orders of magnitude (< {orders:g})")))
    if not (none.size and None not in sigma and record is not None):
        return _finding(4, measured, "yes")
    edge = float(none.min())
    rice_edge = upcrossing_rate(edge, *map(float, sigma))
    expected = float(record) * rice_edge
    rice = upcrossing_rate(at_low, *map(float, sigma))
    measured += (f" in this record of length {float(record):.3g} (units of tau); Rice's "
                 f"up-crossing rate of the wall-free response is {rice_edge:.3g} per unit time "
                 f"at delta = {edge:.3g}, an expected {expected:.2g} up-crossings in the record "
                 f"(at delta = {at_low:.3g} it is {rice:.3g} per unit time, "
                 f"{float(record) * rice:.3g} expected): ")
    if expected < 3.0:
        measured += "the impacts stop at the record's reach; the rate falls, never to zero"
        summary = _sentence(
            f"the collision rate falls as delta grows, by {fall:.1f} orders of magnitude",
            f"a critical delta past which no impact happens, since Rice's rate expects "
            f"{expected:.2g} up-crossings of delta = {edge:.3g} in this record: the impacts "
            f"stop at the record's reach")
        return _finding(4, measured, "partly", summary)
    measured += "fewer impacts than the Gaussian response's excursions: a threshold"
    return _finding(4, measured, "yes")


def random_force(events=None, spectra=None):
    """Findings 1-4 of a random-force study; those whose datasets are missing are ``n/a``."""
    found = [finding1(spectra) if spectra is not None else
             not_available(1, "this study draws no spectrum of a(tau) (Fig. 6)")]
    for number, fn in ((2, finding2), (3, finding3), (4, finding4)):
        found.append(fn(events) if events is not None else
                     not_available(number, "this study has no impact statistics (Figs. 7-9)"))
    return found


# --- harmonic plus random force (Figs. 11-15) --------------------------------------------------

def spectra_shifts(spectra, line_bins=LINE_BINS, band=CENTROID_BAND):
    """``{inv_beta: vibroimpact.stats.centroid.Shift}`` of every 1/beta_f row of a spectra
    dataset."""
    return {float(ib): shift(spectra.sel(inv_beta=ib), 1.0 / float(ib), band, line_bins)
            for ib in np.atleast_1d(spectra.inv_beta.values)}


def _choices_text():
    """The choices a verdict on the broadband shift must hold under, in words."""
    return (f"half-width {', '.join(map(str, LINE_BINS_CHOICES))} bins x beta <= "
            f"{', '.join(format(b, 'g') for b in BAND_CHOICES)} x the lines' bins "
            f"{' or '.join(('bridged' if f == 'bridge' else 'dropped') for f in FILL_CHOICES)}")


def _between(value, low, high, spec=".2f"):
    """``"0.98 [0.96, 1.00]"``, or the value alone when its interval is not known."""
    if not (np.isfinite(low) and np.isfinite(high)):
        return format(float(value), spec)
    value, low, high = (format(float(x), spec) for x in (value, low, high))
    return f"{value} [{low}, {high}]"


def finding5(spectra, amplitude=1.0, halfwidth=0.1, band=CENTROID_BAND, events=None,
             line_bins=LINE_BINS):
    """Input and response spectra under ``amplitude sin(beta_f tau) + r(tau)`` (Figs. 11, 12).

    The input: the line carries ``amplitude^2/2`` against the random part's power (the
    integral of its one-sided PSD); concentrated means > 80 %. The response, per 1/beta_f:
    its share of power within ``halfwidth`` of beta_f must fall as delta decreases (spreads
    wider), and its power must move to lower frequency. The paper's Fig. 12 shows the
    broadband response moving; its lines at k beta_f carry the periodic part of the motion,
    whose strength follows the play (at delta = 2 the line at beta_f holds ~40 times the power
    it holds at -0.5), so a centroid with the lines in mostly follows the line. The move is
    therefore read on the broadband response (`vibroimpact.stats.centroid.shift`: the lines
    taken out over ``line_bins`` bins either side, their powers reported apart), its centroid
    over ``0 < beta <= band`` at the smallest play against the largest, with a 95 % interval
    from the spread of the dataset's batch spectra (``S_a_batch``). It moves to lower
    frequency when that change is below 0 under every choice of the half-width, the band and
    what stands in the lines' bins (`LINE_BINS_CHOICES` x `BAND_CHOICES` x `FILL_CHOICES`),
    to higher frequency (against the paper) when above 0 under every choice; otherwise it is
    not resolved, and no contradiction is printed.
    ``measured`` gives both readings (the centroid with the lines and the broadband one).

    Fewer than two frequencies in the band (a Welch segment too short) leave it ``n/a``, and
    so do ``events`` (the study's impact statistics) without a collision at the spectra's
    plays: a response that never meets the wall cannot show what impacts do to it; and a
    two-wall study (delta is no play there).
    """
    if (two := _two_walls(spectra, 5)) is not None:
        return two
    if events is not None:
        at = events.sel(delta=spectra.delta.values, method="nearest")
        if "inv_beta" in at.dims and "inv_beta" in spectra.dims:
            at = at.sel(inv_beta=np.atleast_1d(spectra.inv_beta.values), method="nearest")
        why = _without_collision(at)
        if why is not None:
            return not_available(5, why.replace("at any play", "at the plays of the spectra"))
    beta = spectra.beta.values
    if np.count_nonzero((beta > 0) & (beta <= band)) < 2:
        return not_available(5, f"the spectrum's resolution (beta step {beta[1] - beta[0]:.3g}) "
                                f"leaves fewer than two frequencies in 0 < beta <= {band:g}; a "
                                f"finer one needs a longer spectra.nperseg")
    if spectra.sizes["delta"] < 2:
        return not_available(5, "needs spectra of a(tau) at two plays")
    lines, shares, centroids = [], [], []
    spread_all = True
    wider, narrower, lower, higher, unresolved = [], [], [], [], []
    shifts = spectra_shifts(spectra, line_bins, band)
    for inv_beta, sh in shifts.items():
        s = spectra.sel(inv_beta=inv_beta).sortby("delta")
        beta = s.beta.values
        step = beta[1] - beta[0]
        random_power = 2 * float(s.S_f.sum()) * step / (2 * np.pi)
        line = 0.5 * amplitude ** 2
        lines.append(line / (line + random_power))
        near = np.abs(beta - 1 / inv_beta) < halfwidth
        share = s.S_a.isel(beta=near).sum("beta") / s.S_a.sum("beta")
        d_hi, d_lo = float(s.delta[-1]), float(s.delta[0])
        at = f"1/beta_f = {inv_beta:.3g}"
        shares.append(f"{at}: {float(share[-1]):.2f} at delta = {d_hi:.3g} -> "
                      f"{float(share[0]):.2f} at delta = {d_lo:.3g}")
        diff, low, high = sh.change[(int(line_bins), float(band), "bridge")]
        centroids.append(
            f"{at}: with the lines {sh.centroid_lines[-1]:.2f} -> {sh.centroid_lines[0]:.2f}; "
            f"broadband {_between(sh.centroid[-1], sh.centroid_low[-1], sh.centroid_high[-1])}"
            f" -> {_between(sh.centroid[0], sh.centroid_low[0], sh.centroid_high[0])} "
            f"(change {_between(diff, low, high, '+.2f')}), broadband peak "
            f"{_between(sh.peak[-1], sh.peak_low[-1], sh.peak_high[-1])} -> "
            f"{_between(sh.peak[0], sh.peak_low[0], sh.peak_high[0])}, power of the line at "
            f"beta_f {sh.lines[-1, 0]:.3g} -> {sh.lines[0, 0]:.3g}")
        spread_all &= float(share[0]) < float(share[-1])
        (wider if float(share[0]) < float(share[-1]) else narrower).append(
            f"{float(share[-1]):.2f} -> {float(share[0]):.2f} at {at}")
        moved = f"{sh.centroid[-1]:.2f} -> {sh.centroid[0]:.2f} at {at}"
        {"falls": lower, "rises": higher, "unresolved": unresolved}[sh.reading()].append(moved)
    lower_all = not higher and not unresolved
    concentrated = min(lines) > 0.8
    n_batches = min(sh.n_batches for sh in shifts.values())
    errors = (f"95 % intervals from {n_batches} batches (delete-one jackknife; the peak's from "
              f"the batches' own peaks)" if n_batches else
              "no batch spectra in this dataset (S_a_batch): no intervals, no verdict on the "
              "shift")
    measured = (f"line share of the input power {_fmt(lines, '.2f')}; response power within "
                f"+-{halfwidth:g} of beta_f, " + "; ".join(shares)
                + f"; centroid (beta <= {band:g}) from the largest play to the smallest, "
                f"broadband = the lines at k beta_f taken out (+-{line_bins} bins): "
                + "; ".join(centroids) + f"; {errors}; the broadband change read under "
                f"{_choices_text()}")
    holds = "yes" if concentrated and spread_all and lower_all else (
        "partly" if concentrated and spread_all else "no")
    deltas = np.sort(spectra.delta.values)
    falling = f"as delta falls from {deltas[-1]:.3g} to {deltas[0]:.3g}"
    near = f"its share within +-{halfwidth:g} of beta_f"
    centre = (f"its broadband centroid (beta <= {band:g}, the lines out), under every choice "
              f"of {_choices_text()}")
    held = [f"the input's power is concentrated at beta_f (line share {_fmt(lines, '.2f')})"
            if concentrated else None,
            f"{falling} the response's power spreads wider ({near} " + ", ".join(wider) + ")"
            if wider else None,
            f"moves to lower frequency ({centre}: " + ", ".join(lower) + ")" if lower else None]
    failed = [None if concentrated else f"the input's line carries only {_fmt(lines, '.2f')} "
                                        f"of its power (<= 0.8)",
              f"{falling} the response's power does not spread wider ({near} "
              + ", ".join(narrower) + ")" if narrower else None,
              f"{'' if narrower else falling + ' '}the broadband response moves to higher "
              f"frequency, opposite to the paper ({centre}: " + ", ".join(higher) + ")"
              if higher else None,
              "the broadband centroid's move is not resolved (its 95 % interval holds 0 or "
              "the choices disagree: " + ", ".join(unresolved) + ")" if unresolved else None]
    summary = "" if holds == "yes" else _sentence(
        " and ".join(h for h in held if h) or None, " and ".join(f for f in failed if f) or None)
    return _finding(5, measured, holds, summary)


def finding5_readings(spectra, line_bins=LINE_BINS, band=CENTROID_BAND):
    """Finding 5's two readings per 1/beta_f and play (a pandas DataFrame): the centroid of
    the whole response (lines included), the broadband centroid and peak with their 95 %
    intervals, and the power of each line at k beta_f taken out (``line k``)."""
    import pandas as pd

    rows = []
    for inv_beta, sh in spectra_shifts(spectra, line_bins, band).items():
        for k, d in enumerate(sh.delta):
            rows.append({"1/beta_f": inv_beta, "delta": float(d),
                         f"centroid with the lines (beta <= {band:g})": sh.centroid_lines[k],
                         "broadband centroid": sh.centroid[k],
                         "centroid 95 %": _between(sh.centroid[k], sh.centroid_low[k],
                                                   sh.centroid_high[k], ".3f").partition(" ")[2],
                         "broadband peak": sh.peak[k],
                         "peak 95 %": _between(sh.peak[k], sh.peak_low[k],
                                               sh.peak_high[k], ".3f").partition(" ")[2],
                         **{f"line {j + 1} beta_f": sh.lines[k, j]
                            for j in range(sh.lines.shape[1])}})
    return pd.DataFrame(rows)


def finding5_choices(spectra):
    """The broadband centroid's change from the largest play to the smallest under each
    choice of the lines' half-width, the band and what stands in the lines' bins (a pandas
    DataFrame: the two centroids, the change, its 95 % interval, and which way it reads),
    per 1/beta_f: finding
    5 calls a move only when every row of a 1/beta_f reads the same."""
    import pandas as pd

    rows = []
    for inv_beta, sh in spectra_shifts(spectra).items():
        for (h, top, fill), (diff, low, high) in sh.change.items():
            large, small = sh.ends[(h, top, fill)]
            rows.append({"1/beta_f": inv_beta, "half-width (bins)": h, "beta <=": top,
                         "lines' bins": "bridged" if fill == "bridge" else "dropped",
                         f"centroid at delta = {sh.delta[-1]:g}": large,
                         f"at delta = {sh.delta[0]:g}": small, "change": diff,
                         "95 %": f"[{low:+.3f}, {high:+.3f}]",
                         "reads": ("falls" if high < 0 else "rises" if low > 0 else
                                   "unresolved")})
    return pd.DataFrame(rows)


def _peaks_below_one(ratio, density):
    """The two largest values of a z_j/z density below 1, one on each side of 1/2."""
    low, high = (ratio < 0.5), (ratio >= 0.5) & (ratio < 1.0)
    if not low.any() or not high.any():
        return np.nan, np.nan
    return ratio[low][np.argmax(density[low])], ratio[high][np.argmax(density[high])]


def _motion(events, name):
    return events.motion_probability.sel(motion=name)


def finding6(events, inv_beta=1.1, symmetric=0.1):
    """Density of z_j/z (Fig. 13) at the row nearest ``inv_beta``.

    Large play: at the play where (1/1) is most probable, the density's mode lies within 0.05
    of 1 and P(1/1) > 0.5. Small play: at the smaller play where (2/1) is most
    probable, the two peaks below 1 add up to 1 within ``symmetric`` and P(2/1) > 0.5.
    """
    if (two := _two_walls(events, 6)) is not None:
        return two
    if (why := _without_collision(_row(events, inv_beta))) is not None:
        return not_available(6, why)
    ev = _impacting(_row(events, inv_beta))
    motions = [str(m) for m in ev.motion.values] if "motion" in ev.dims else []
    if "ratio_density" not in ev or not {"1/1", "2/1"} <= set(motions) or ev.sizes["delta"] < 2:
        return not_available(6, "needs the z_j/z densities and the (1/1), (2/1) probabilities "
                                "of a harmonic study at two plays")
    ratio = ev.ratio.values
    p11, p21 = _motion(ev, "1/1"), _motion(ev, "2/1")
    large = float(ev.delta[int(p11.argmax("delta"))])
    mode = float(ratio[int(ev.ratio_density.sel(delta=large).argmax("ratio"))])
    smaller = ev.sel(delta=ev.delta[ev.delta < large])
    at = f"1/beta_f = {float(ev.inv_beta):.3g}: "
    large_ok = abs(mode - 1.0) < 0.05 and float(p11.sel(delta=large)) > 0.5
    measured = (at + f"delta = {large:.3g}: mode of z_j/z {mode:.2f}, P(1/1) = "
                f"{float(p11.sel(delta=large)):.2f}")
    small_ok = False
    if smaller.sizes["delta"]:
        small = float(smaller.delta[int(_motion(smaller, "2/1").argmax("delta"))])
        lo, hi = _peaks_below_one(ratio, ev.ratio_density.sel(delta=small).values)
        small_ok = (abs(lo + hi - 1.0) < symmetric and float(p21.sel(delta=small)) > 0.5)
        measured += (f"; delta = {small:.3g}: peaks at {lo:.2f} and {hi:.2f} (sum "
                     f"{lo + hi:.2f}), P(2/1) = {float(p21.sel(delta=small)):.2f}")
    if "1/2" in motions:
        p12 = _motion(ev, "1/2")
        sub = float(ev.delta[int(p12.argmax("delta"))])
        measured += f"; (1/2) most probable at delta = {sub:.3g}: P = {float(p12.max()):.2f}"
    return _finding(6, measured, _yes(large_ok and small_ok))


def _cv(events, delta):
    """Coefficient of variation of the velocity after impact from its density at ``delta``."""
    d = events.v_after_density.sel(delta=delta).values
    v = events.v_after.values
    mean = (v * d).sum() / d.sum()
    return float(np.sqrt(((v - mean) ** 2 * d).sum() / d.sum()) / mean)


def finding7(events, inv_beta=1.1, correlation=-0.7, deltas=None):
    """Spread of the velocity after impact (Fig. 14) at the row nearest ``inv_beta``, read
    over every play the figure draws (``deltas``; default every play with impacts).

    The spread is the coefficient of variation (CV) of the density. A play is *narrow* when
    its CV lies nearer the CV at the play where (1/1) is most probable than the smallest CV
    of the small plays where (1/1) is not dominant (P(1/1) < 0.5, below the smallest play
    where it is). "yes": the spread falls as P(1/1) grows along the plays (Spearman rank
    correlation <= ``correlation``) and every play where (1/1) dominates (P >= 0.5) or that is
    larger is narrow; "partly": the spread falls with P(1/1) but such a play is wide; "no":
    it does not fall with P(1/1).
    """
    from vibroimpact.stats.ranks import spearman

    if (two := _two_walls(events, 7)) is not None:
        return two
    if (why := _without_collision(_row(events, inv_beta))) is not None:
        return not_available(7, why)
    ev = _impacting(_row(events, inv_beta))
    if "motion_probability" not in ev or "1/1" not in [str(m) for m in ev.motion.values]:
        return not_available(7, "needs the velocity densities and P(1/1) of a harmonic study")
    if deltas is not None:
        wanted = np.asarray(deltas, dtype=float)
        ev = ev.sel(delta=[d for d in ev.delta.values if np.min(np.abs(wanted - d)) < 1e-9])
    p11 = _motion(ev, "1/1").values
    d = ev.delta.values
    dominant = p11 >= 0.5
    if not d.size:
        return not_available(7, f"no play has >= {MIN_IMPACTS} collisions")
    if not dominant.any():
        return not_available(7, f"(1/1) dominates at no play drawn (delta = {_fmt(d)})")
    small = (d < d[dominant].min()) & ~dominant
    if not small.any():
        return not_available(7, f"no play below delta = {d[dominant].min():.3g} where (1/1) "
                                f"is not dominant")
    cv = np.array([_cv(ev, x) for x in d])
    limit = 0.5 * (cv[np.argmax(p11)] + cv[small].min())
    rho = spearman(p11, cv)
    wide = (dominant | (d > d[dominant].min())) & (cv >= limit)
    parts = [f"{x:.3g}: {c:.2f} (P(1/1) {p:.2f})" for x, c, p in zip(d, cv, p11)]
    measured = (f"1/beta_f = {float(ev.inv_beta):.3g}, coefficient of variation at delta = "
                + "; ".join(parts) + f". Rank correlation with P(1/1) {rho:.2f}; narrow below "
                f"{limit:.2f}")
    if wide.any():
        measured += f"; wide at delta = {_fmt(d[wide])}, where (1/1) is not alone"
    holds = "no" if not rho <= correlation else "partly" if wide.any() else "yes"
    falls = (f"the spread of the velocity after impact falls as P(1/1) grows (rank "
             f"correlation {rho:.2f} <= {correlation:g})")
    wide_text = (f"it is wide (CV {_fmt(cv[wide], '.2f')} >= {limit:.2f}) at delta = "
                 f"{_fmt(d[wide])}, where P(1/1) = {_fmt(p11[wide], '.2f')} and (1/1) is not "
                 f"alone")
    summary = {"yes": "",
               "partly": _sentence(falls, wide_text),
               "no": _sentence(fails=f"the spread does not fall as P(1/1) grows (rank "
                                     f"correlation {rho:.2f} > {correlation:g})")}[holds]
    return _finding(7, measured, holds, summary)


def _predictor(predictors, name, motion):
    """The stable-domain correlation of predictor ``name`` with P of ``motion`` (or None)."""
    return next((c for c in predictors or () if c.predictor == name and c.motion == motion
                 and c.where == "domain"), None)


def _resolved(c):
    """A correlation computed, with its 95 % interval clear of 0."""
    return c is not None and np.isfinite(c.rho) and (c.low > 0 or c.high < 0)


#: A rank correlation whose 95 % interval reaches below this |rho| may be weak: no noise-free
#: predictor is called the best on such evidence (the usual reading: |rho| < 0.3 weak).
WEAK_RHO = 0.3

#: The sign of rho with P each noise-free predictor is expected to have where it predicts P
#: (a more stable orbit, a larger basin, a more negative exponent: a likelier motion).
EXPECTED_SIGN = {"S": 1, "basin": 1, "lyapunov": -1}


def _overlap(a, b):
    """Whether the 95 % intervals of two correlations overlap in |rho|."""
    def span(c):
        return sorted((abs(c.low), abs(c.high))) if c.low * c.high > 0 else (0.0, max(
            abs(c.low), abs(c.high)))
    (a0, a1), (b0, b1) = span(a), span(b)
    return a0 <= b1 and b0 <= a1


def _best_text(free):
    """Which resolved noise-free predictor ranks P best, in words the numbers allow: none
    when the strongest's interval reaches a weak |rho| (`WEAK_RHO`); several when their
    intervals overlap; and the direction, with a note where it is not the expected one
    (`EXPECTED_SIGN`)."""
    best = max(free, key=lambda n: abs(free[n].rho))
    c = free[best]
    direction = f"P {'rises' if c.rho > 0 else 'falls'} as {best} grows"
    if np.sign(c.rho) != EXPECTED_SIGN.get(best, np.sign(c.rho)):
        direction += ", against the expected direction"
    if min(abs(c.low), abs(c.high)) < WEAK_RHO:
        return (f"no noise-free predictor ranks P clearly: the strongest, {best} "
                f"({direction}), has an interval reaching |rho| < {WEAK_RHO:g}")
    alike = [n for n in free if n != best and _overlap(free[n], c)]
    if alike:
        return (f"{best} ranks P most strongly ({direction}), not clearly more than "
                f"{' or '.join(alike)} (their 95 % intervals overlap)")
    return f"{best} ranks P best among the noise-free predictors ({direction})"


def _predictors_text(predictors, motion):
    """The noise-free predictors of ``motion``'s P in its stable domain, and which ranks P
    best, if the numbers say so (:func:`_best_text`; :mod:`vibroimpact.reports.predictors`)."""
    found = {name: _predictor(predictors, name, motion)
             for name in ("S", "basin", "lyapunov", "residence")}
    shown = {n: c for n, c in found.items() if c is not None and np.isfinite(c.rho)}
    if not shown:
        return ""
    cells = next(iter(shown.values())).n_cells
    parts = [f"{n} {c.rho:+.2f} [{c.low:+.2f}, {c.high:+.2f}]"
             + (f" ({c.n_cells} cells)" if c.n_cells != cells else "")
             for n, c in shown.items()]
    text = f"; inside the domain ({cells} cells) rho with " + ", ".join(parts)
    free = {n: c for n, c in shown.items() if n != "residence" and _resolved(c)}
    if free:
        text += "; " + _best_text(free)
    return text


def _complex_text(a):
    """Where the multipliers are complex, S does not depend on delta (over the paper's plane
    it depends on 1/beta_f alone): say in how much of the domain (``complex_share`` of
    :func:`vibroimpact.reports.notebook.map_agreement`, given where delta is an axis)."""
    share = a.get("complex_share", np.nan)
    if not np.isfinite(share) or share == 0:
        return ""
    return (f"; multipliers a complex pair in {100 * share:.0f} % of the domain's cells, where "
            "S = 100 (1 - eps exp(-zeta z/m)), z = 2 pi n/beta_f, does not depend on delta: "
            "rho(P, S) cannot rank P along delta there")


def finding8(agreement, inside=0.75, correlation=0.5, min_cells=5, predictors=None):
    """Fig. 15 against Fig. 16, from :func:`vibroimpact.plotting.maps.map_agreement` and, when
    given, the predictors of P (:func:`vibroimpact.reports.predictors.predictor_correlations`).

    Where: of the cells where a motion has probability >= 50 %, at least ``inside`` lie in
    its stable domain (motions with fewer than ``min_cells`` such cells are not judged). How
    strongly: Spearman's rank correlation of probability and S inside the domain at least
    ``correlation`` and, with ``predictors``, its 95 % bootstrap interval clear of 0. Both:
    ``yes``; where only: ``partly``; not where: ``no``. ``measured`` also gives the other
    predictors' correlations inside the domain (basin fraction, Lyapunov exponent, residence
    time) and the noise-free one that ranks P best, where the intervals allow naming one
    (:func:`_best_text`): the claim names S, the data may favour another. With
    ``complex_share`` in a motion's agreement (the share of its stable cells whose
    multipliers are a complex pair), it says that S does not depend on delta there.
    """
    judged = {m: a for m, a in agreement.items() if a["n_dominant"] >= min_cells}
    if not judged:
        return not_available(8, f"no motion has {min_cells} cells with probability >= 50 %")
    parts = [f"({m}) {a['n_dominant']} cells >= 50 %: {100 * a['dominant_inside']:.0f} % inside, "
             f"domain covered {100 * a['domain_covered']:.0f} %, rank correlation with S "
             f"{a['rank_correlation']:.2f}" + _complex_text(a) + _predictors_text(predictors, m)
             for m, a in judged.items()]
    where = all(a["dominant_inside"] >= inside for a in judged.values())

    def strong(m, a):
        if not (np.isfinite(a["rank_correlation"]) and a["rank_correlation"] >= correlation):
            return False
        return predictors is None or _resolved(_predictor(predictors, "S", m))

    strongly = all(strong(m, a) for m, a in judged.items())
    holds = "yes" if where and strongly else ("partly" if where else "no")
    share = [100 * a["dominant_inside"] for a in judged.values()]
    span = (f"{min(share):.0f}" if round(min(share)) == round(max(share)) else
            f"{min(share):.0f}-{max(share):.0f}")
    domains = (f"the domains agree: {span} % of the cells where a motion has P >= 50 % lie "
               f"inside its stable domain (>= {100 * inside:.0f} % asked)")
    outside = [f"({m}) {100 * a['dominant_inside']:.0f} %" for m, a in judged.items()
               if a["dominant_inside"] < inside]
    weak = [f"{_rho_text(m, a, predictors)} for ({m})" for m, a in judged.items()
            if not strong(m, a)]
    ranks = ("S does not rank P inside them (rho = " + ", ".join(weak)
             + f"; >= {correlation:g}"
             + (" with a 95 % interval clear of 0" if predictors is not None else "")
             + " asked)") if weak else None
    summary = {"yes": "",
               "partly": _sentence(domains, ranks),
               "no": _sentence(
                   f"S ranks P inside the domains ({', '.join(f'({m})' for m in judged)})"
                   if not weak else None,
                   "the domains do not agree: of the cells where a motion has P >= 50 %, "
                   + ", ".join(outside) + f" lie inside its stable domain (< {100 * inside:.0f} "
                   "%)" + (f"; and {ranks}" if ranks else ""))}[holds]
    return _finding(8, "; ".join(parts), holds, summary)


def _rho_text(motion, agreement, predictors):
    """The rank correlation of P and S of ``motion`` inside its domain, with its 95 % interval
    when the predictors give one."""
    c = _predictor(predictors, "S", motion)
    if c is not None and np.isfinite(c.rho):
        return f"{c.rho:.2f} [{c.low:.2f}, {c.high:.2f}]"
    return f"{agreement['rank_correlation']:.2f}"


def harmonic_random(events=None, spectra=None, agreement=None, amplitude=1.0, inv_beta=1.1,
                    density_delta=None, predictors=None):
    """Findings 5-8 of a harmonic-plus-random study; those whose datasets are missing are
    ``n/a``. ``agreement`` is :func:`vibroimpact.plotting.maps.map_agreement` of its map with
    an orbits map; ``density_delta``, the plays Fig. 14 draws, are those finding 7 reads
    (default: every play with impacts); ``predictors`` the correlations finding 8 also reads
    (:func:`vibroimpact.reports.predictors.predictor_correlations`)."""
    found = [finding5(spectra, amplitude, events=events) if spectra is not None else
             not_available(5, "this study draws no spectrum of a(tau) (Fig. 12)")]
    missing = "this study has no impact densities (Figs. 13, 14)"
    found.append(finding6(events, inv_beta) if events is not None else not_available(6, missing))
    found.append(finding7(events, inv_beta, deltas=density_delta) if events is not None else
                 not_available(7, missing))
    found.append(finding8(agreement, predictors=predictors) if agreement is not None else
                 not_available(8, "this study has no probability map compared with an orbits "
                                  "map (fig15_vs_fig16)"))
    return found


def findings_table(found):
    """The findings as a table (pandas DataFrame): number, claim, measured, holds; a
    verdict's ``summary`` (what holds, what does not) opens its ``measured`` cell."""
    import pandas as pd

    return pd.DataFrame([dict(finding=f.number, claim=f.claim,
                              measured=f"{f.summary} {f.measured}" if f.summary else f.measured,
                              holds=f.holds) for f in found]).set_index("finding")
