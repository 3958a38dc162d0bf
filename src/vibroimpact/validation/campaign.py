"""The whole stress campaign in one call: every family, at full size or as a quick sample.

``python -m vibroimpact.validation.campaign --quick`` prints one line per family; the test
suite runs the same families at full size (``tests/stress/``), and a workflow rule can run
:func:`run_campaign` with ``quick=True`` for a report.
"""
import argparse
import tempfile

from vibroimpact.validation.families import FAMILIES, FULL_CASES, run_family
from vibroimpact.validation.orbit_families import FAMILIES as ORBIT_FAMILIES, run_orbit_family
from vibroimpact.validation.streaming import run_streamed_record

#: Cases per simulator family in a quick sample (seconds).
QUICK_CASES = {name: max(5, n // 20) for name, n in FULL_CASES.items()}
#: Orbit families: cases at full size and quick.
ORBIT_CASES = {"full": 60, "quick": 8}
#: Samples of the streamed record (full: the 1e8 the campaign promises).
STREAM_SAMPLES = {"full": 100_000_000, "quick": 1_000_000}


def run_campaign(seed, quick=False, workdir=None):
    """Run every family; return the list of :class:`FamilyReport`.

    Parameters
    ----------
    seed : int
        Seed of every family's case draws.
    quick : bool
        A seeded quick sample (about a minute) instead of the full campaign.
    workdir : path-like, optional
        Where the streamed record is written (default: a temporary directory).
    """
    size = "quick" if quick else "full"
    cases = QUICK_CASES if quick else FULL_CASES
    reports = [run_family(name, cases[name], seed) for name in FAMILIES]
    reports += [run_orbit_family(name, ORBIT_CASES[size], seed) for name in ORBIT_FAMILIES]
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        reports.append(run_streamed_record(STREAM_SAMPLES[size], seed, tmp))
    return reports


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a quick sample, not full size")
    parser.add_argument("--seed", type=int, default=20261122)
    args = parser.parse_args(argv)
    reports = run_campaign(args.seed, quick=args.quick)
    for report in reports:
        print(report.summary())
    failed = [r for r in reports if not r.ok]
    for report in failed:
        print(report.details())
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
