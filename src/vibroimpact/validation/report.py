"""What one stress family reports: :class:`FamilyReport`."""
from dataclasses import dataclass, field

#: How many failing cases a report keeps in full (the counts cover all of them).
KEEP_FAILURES = 5


@dataclass
class FamilyReport:
    """Counts and worst errors of one family of constructed cases.

    Attributes
    ----------
    family : str
        The family's name.
    cases : int
        Cases tried.
    compared : int
        Events compared one by one with the independent reference (impacts, releases,
        sticking onsets; for orbit families, orbits).
    missed, spurious : int
        Reference events the checked code did not produce, and events it produced that the
        reference does not have.
    approximated : int
        Events that a documented approximation takes as resting contact (eps = 1
        micro-bounces, the many-events rule): counted apart, not misses.
    exceptions : int
        Cases in which the checked code raised.
    worst_error : float
        Largest error over all compared events, in the family's own measure (see ``measure``).
    tolerance : float
        The error above which a compared event counts as a failure.
    measure : str
        What ``worst_error`` measures, e.g. ``"max(|dtau|, |du/u|)"``.
    worst_case : dict or None
        The inputs of the case with the largest error.
    failures : list of str
        The first :data:`KEEP_FAILURES` failing cases, each with its inputs and what failed.
    n_failed : int
        Cases with an exception, a miss, a spurious event or an error above tolerance.
    seconds : float
        Wall time spent on the family.
    extra : dict
        Family-specific figures (e.g. peak resident memory of a streamed record).
    """

    family: str
    tolerance: float
    measure: str
    cases: int = 0
    compared: int = 0
    missed: int = 0
    spurious: int = 0
    approximated: int = 0
    exceptions: int = 0
    worst_error: float = 0.0
    worst_case: dict | None = None
    failures: list = field(default_factory=list)
    n_failed: int = 0
    seconds: float = 0.0
    extra: dict = field(default_factory=dict)

    @property
    def ok(self):
        """True when no case failed."""
        return self.n_failed == 0

    def add_error(self, error, case, count=1):
        """Record ``count`` compared events whose largest error is ``error``; keep the case
        if it is the worst so far."""
        self.compared += count
        if error > self.worst_error or self.worst_case is None:
            self.worst_error = max(error, self.worst_error)
            self.worst_case = case

    def fail(self, case, what):
        """Count a failing case and keep its description while there is room."""
        self.n_failed += 1
        if len(self.failures) < KEEP_FAILURES:
            self.failures.append(f"{what}; case: {case!r}")

    def summary(self):
        """One line: the family's counts and worst error."""
        line = (f"{self.family:<22s} cases {self.cases:5d}  compared {self.compared:6d}  "
                f"missed {self.missed}  spurious {self.spurious}  exceptions {self.exceptions}  "
                f"approximated {self.approximated}  worst {self.worst_error:.2e} "
                f"(tol {self.tolerance:.0e}, {self.measure})  {self.seconds:.1f} s")
        if self.extra:
            line += "  " + "  ".join(f"{k} {v}" for k, v in self.extra.items())
        return line

    def details(self):
        """The summary line followed by the kept failures, for an assertion message."""
        return "\n".join([self.summary(), *self.failures])

    def as_row(self):
        """A flat dict of the counts (for a table or a dataset)."""
        return dict(family=self.family, cases=self.cases, compared=self.compared,
                    missed=self.missed, spurious=self.spurious, approximated=self.approximated,
                    exceptions=self.exceptions, failed=self.n_failed,
                    worst_error=self.worst_error, tolerance=self.tolerance,
                    measure=self.measure, seconds=self.seconds, **self.extra)
