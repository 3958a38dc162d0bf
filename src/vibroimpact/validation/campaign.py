"""The whole stress campaign in one call: every family, at full size or as a sample.

``python -m vibroimpact.validation.campaign --size quick`` prints one line per family; the test
suite runs the same families, the first third of each (``tests/stress/``), and the workflow runs
:func:`run_campaign` at the size its config names (``validation.stress.size``: ``sample`` by
default, or ``quick``) and stores :func:`campaign_dataset` of its reports
(``results/validation/stress_sample.nc``).

Three sizes (:data:`SIZES`), each drawing the first cases of the same seeded sequence, so a
smaller size's cases are the first ones of a larger size's:

``full``
    3,650 simulator cases, 1,700 orbit cases (:data:`FULL_ORBIT_CASES`), a record of 1e8
    samples, drawn from the slow test suite's seeds (:data:`SLOW_SEED` and
    :data:`SLOW_ORBIT_SEED`). ``python -m vibroimpact.validation.campaign --size full --table
    workflow/notebooks/stress_campaign.csv`` runs it and writes the table that the stability
    report and the README show. The slow suite (``tests/stress``) runs the first third of every
    family's cases (:data:`SLOW_CASES`, :data:`SLOW_ORBIT_CASES`) and the whole record.
``quick``
    About 5 % of it (209 cases, a record of 1e6 samples, 64 replayed flights): ~20 CPU-s.
``sample``
    The default build's: every family, at a few cases each, each family at most ~0.3 CPU-s
    (the dearer a family's case, the fewer: 2 chatter cases of ``stick_onset``, 25 touches of
    ``release_touch``), a record of 2.5e5 samples streamed in chunks of 2^16, 65,521 (prime)
    and 2^18 samples, 8 replayed flights: ~3 CPU-s.
"""
import argparse
import logging
import tempfile

import numpy as np
import xarray as xr

from vibroimpact.validation.families import FAMILIES, FULL_CASES, run_family
from vibroimpact.validation.orbit_families import FAMILIES as ORBIT_FAMILIES, run_orbit_family
from vibroimpact.validation.streaming import DEFAULT_CHUNK_SIZES, run_streamed_record

log = logging.getLogger(__name__)

#: Cases per simulator family in a quick sample (5 % of the full campaign, at least 5).
QUICK_CASES = {name: max(5, n // 20) for name, n in FULL_CASES.items()}
#: Cases per simulator family in the default build's sample: CPU-s per case of the quick sample
#: (shared 2-core machine, warm numba cache) release 0.05, release_touch 0.004, start_pulled
#: 0.03, force_equals_delta 0.04, stick_onset 0.28, grazing 0.08, extreme 0.015.
SAMPLE_CASES = {"release": 6, "release_touch": 25, "start_pulled": 6, "force_equals_delta": 6,
                "stick_onset": 2, "grazing": 4, "extreme": 15}
#: Orbit families: cases per family in a quick sample and in the default build's.
ORBIT_CASES = {"quick": 8, "sample": 4}
#: The slow suite's seeds: the simulator families' and the streamed record's, the orbit
#: families'.
SLOW_SEED = 20261122
SLOW_ORBIT_SEED = 20240601
#: Cases per orbit family of the full campaign.
FULL_ORBIT_CASES = {"orbit_fold": 600, "orbit_period_doubling": 300, "orbit_grazing": 800}
#: The slow suite's cases: the first third of every family's full campaign (the same seeds, so
#: the same cases), which at full size took a quarter of the slow suites' time, the 34-digit
#: reference most of it (README, "Tests"); the full campaign's table (``--size full
#: --table``) is the one the stability report shows.
SLOW_CASES = {name: n // 3 for name, n in FULL_CASES.items()}
SLOW_ORBIT_CASES = {name: n // 3 for name, n in FULL_ORBIT_CASES.items()}
#: Samples of the streamed record (full: the 1e8 the campaign promises).
STREAM_SAMPLES = {"full": 100_000_000, "quick": 1_000_000, "sample": 250_000}
#: Chunk sizes of the streamed record's runs (at least three, one not a power of two, all
#: shorter than the record but the last).
CHUNK_SIZES = {"full": DEFAULT_CHUNK_SIZES, "quick": DEFAULT_CHUNK_SIZES,
               "sample": (2**16, 65_521, 2**18)}
#: Flights after an impact replayed by the mpmath reference (~0.14 CPU-s each at delta 1.5).
REPLAYS = {"full": 64, "quick": 64, "sample": 8}
#: Cases per simulator family at each size.
CASES = {"full": FULL_CASES, "quick": QUICK_CASES, "sample": SAMPLE_CASES}
#: The sizes of a campaign.
SIZES = ("full", "quick", "sample")


def run_campaign(seed, quick=False, workdir=None, size=None, orbit_seed=None):
    """Run every family; return the list of :class:`FamilyReport`.

    Parameters
    ----------
    seed : int
        Seed of every family's case draws.
    quick : bool
        A seeded quick sample (~20 CPU-s) instead of the full campaign (when ``size`` is
        None).
    workdir : path-like, optional
        Where the streamed record is written (default: a temporary directory).
    size : {"full", "quick", "sample"}, optional
        The campaign's size (:data:`SIZES`); overrides ``quick``.
    orbit_seed : int, optional
        Seed of the orbit families' draws (default ``seed``).
    """
    size = ("quick" if quick else "full") if size is None else size
    if size not in SIZES:
        raise ValueError(f"size must be one of {SIZES}, got {size!r}")
    cases = CASES[size]
    reports = [run_family(name, cases[name], seed) for name in FAMILIES]
    orbit_seed = seed if orbit_seed is None else orbit_seed
    reports += [run_orbit_family(name, FULL_ORBIT_CASES[name] if size == "full"
                                 else ORBIT_CASES[size], orbit_seed)
                for name in ORBIT_FAMILIES]
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        reports.append(run_streamed_record(STREAM_SAMPLES[size], seed, tmp,
                                           chunk_sizes=CHUNK_SIZES[size],
                                           n_replay=REPLAYS[size]))
    return reports


#: Counts of a report stored per family (int), with their long_name.
COUNTS = {
    "cases": "cases tried",
    "compared": "events compared one by one with the independent reference",
    "missed": "reference events the checked code did not produce",
    "spurious": "events the checked code produced that the reference does not have",
    "approximated": "events a documented approximation takes as resting contact",
    "exceptions": "cases in which the checked code raised",
    "failed": "cases with an exception, a miss, a spurious event or an error above tolerance",
}
#: Scalars of the case descriptions kept in ``worst_case`` (shortened to 4 digits).
CASE_DIGITS = 4


def describe_case(case):
    """One line of a case's inputs: scalars to `CASE_DIGITS` digits, sequences by their length."""
    if case is None:
        return ""
    if not isinstance(case, dict):
        return str(case)
    parts = []
    for key, value in case.items():
        if isinstance(value, (list, tuple, np.ndarray)):
            parts.append(f"{key}=[{len(value)} values]")
        elif isinstance(value, (float, np.floating)):
            parts.append(f"{key}={float(value):.{CASE_DIGITS}g}")
        else:
            parts.append(f"{key}={value}")
    return ", ".join(parts)


def campaign_dataset(reports, attrs=None):
    """The reports of :func:`run_campaign` as an :class:`xarray.Dataset` along ``family``.

    Parameters
    ----------
    reports : sequence of :class:`~vibroimpact.validation.report.FamilyReport`
    attrs : dict, optional
        Global attributes (provenance, the seed).

    Returns
    -------
    xarray.Dataset
        Per family: the counts of :data:`COUNTS` (int), ``worst_error`` and ``tolerance`` (in the
        family's own measure, ``measure``; a family passes when every compared event's error is
        below its tolerance), ``worst_case`` (the inputs of the worst case, one line),
        ``first_failure`` (empty when none failed), ``details`` (the family-specific figures,
        e.g. memory and timings of the streamed record) and ``seconds``. ``seconds`` and
        ``details`` are flagged ``run_measurement = 1``: they change from run to run, the rest
        is fixed by the seed.
    """
    rows = [r.as_row() for r in reports]
    data = {name: ("family", np.array([row[name] for row in rows], dtype=np.int64),
                   dict(long_name=long_name, units="1")) for name, long_name in COUNTS.items()}
    data.update(
        worst_error=("family", np.array([float(r.worst_error) for r in reports]),
                     dict(long_name="largest error over the compared events (in `measure`)",
                          units="1")),
        tolerance=("family", np.array([float(r.tolerance) for r in reports]),
                   dict(long_name="error above which a compared event fails", units="1")),
        measure=("family", [r.measure for r in reports],
                 dict(long_name="what worst_error measures", units="1")),
        worst_case=("family", [describe_case(r.worst_case) for r in reports],
                    dict(long_name="inputs of the case with the largest error", units="1")),
        first_failure=("family", [r.failures[0] if r.failures else "" for r in reports],
                       dict(long_name="the first failing case and what failed", units="1")),
        details=("family", ["  ".join(f"{k} {v}" for k, v in r.extra.items()) for r in reports],
                 dict(long_name="family-specific figures", units="1", run_measurement=1)),
        seconds=("family", np.array([float(r.seconds) for r in reports]),
                 dict(long_name="wall time spent on the family", units="s", run_measurement=1)),
    )
    return xr.Dataset(data, coords=dict(family=("family", [r.family for r in reports],
                                                dict(long_name="stress family", units="1"))),
                      attrs=dict(attrs or {}))


#: The campaign table's columns (``workflow/notebooks/stress_campaign.csv``).
TABLE_COLUMNS = ("family", "cases", "events compared", "missed", "spurious", "exceptions",
                 "worst error / allowance", "undecidable")


def campaign_table(reports):
    """The reports as the campaign table (a DataFrame of strings, :data:`TABLE_COLUMNS`): per
    family its counts, the worst error as a fraction of its allowance (two digits; <= 1
    passes) and what could not be decided: for a simulator family the events within
    round-off of the wall (not compared), for an orbit family the cases the independent
    solver could not decide (skipped), nothing for the streamed record."""
    import pandas as pd

    rows = []
    for r in reports:
        undecided = r.extra.get("ambiguous", r.extra.get("skipped", ""))
        rows.append((r.family, r.cases, r.compared, r.missed, r.spurious, r.exceptions,
                     f"{r.worst_error / r.tolerance:.2g}", undecided))
    return pd.DataFrame(rows, columns=TABLE_COLUMNS).astype(str)


def stress_sample(seed, workdir=None, size="quick"):
    """A seeded sample of every family (:func:`run_campaign` at ``size``, ``"quick"`` or
    ``"sample"``) as a dataset (:func:`campaign_dataset`); the attributes give the seed and the
    sample's size."""
    if size not in ("quick", "sample"):
        raise ValueError(f"size must be 'quick' or 'sample' (the full campaign is `python -m "
                         f"vibroimpact.validation.campaign --size full`), got {size!r}")
    reports = run_campaign(seed, workdir=workdir, size=size)
    for report in reports:
        log.info("%s", report.summary())
    attrs = dict(seed=int(seed), size=size, cases=str(CASES[size]),
                 orbit_cases=ORBIT_CASES[size], stream_samples=STREAM_SAMPLES[size],
                 chunk_sizes=str(list(CHUNK_SIZES[size])), replays=REPLAYS[size])
    return campaign_dataset(reports, attrs)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a quick sample, not full size")
    parser.add_argument("--size", choices=SIZES, default=None,
                        help="the campaign's size (overrides --quick)")
    parser.add_argument("--seed", type=int, default=SLOW_SEED)
    parser.add_argument("--orbit-seed", type=int, default=SLOW_ORBIT_SEED)
    parser.add_argument("--table", default=None,
                        help="write the campaign table (CSV) there, whole or not at all")
    args = parser.parse_args(argv)
    reports = run_campaign(args.seed, quick=args.quick, size=args.size,
                           orbit_seed=args.orbit_seed)
    for report in reports:
        print(report.summary())
    if args.table:
        from vibroimpact._files import atomic_path

        with atomic_path(args.table) as tmp:
            campaign_table(reports).to_csv(tmp, index=False)
    failed = [r for r in reports if not r.ok]
    for report in failed:
        print(report.details())
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
