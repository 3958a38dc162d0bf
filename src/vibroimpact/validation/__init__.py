"""The validation room: an independent high-precision reference and stress families.

Nothing here is used to compute results. It exists so that the simulator and the orbit solver
can be checked against something that shares none of their code, by the test suite at full
size (``tests/stress/``) and by the workflow as a seeded sample.

- :mod:`~vibroimpact.validation.reference`: an mpmath simulator of the same closed form
  (34 digits by default), written without importing the rest of the package.
- :mod:`~vibroimpact.validation.report`: :class:`FamilyReport`, the counts one family reports.
- :mod:`~vibroimpact.validation.compare`: event-by-event comparison with the reference, each
  error against an allowance from its conditioning.
- :mod:`~vibroimpact.validation.families`: constructed families of singular configurations
  (releases, sticking onsets, grazing, extreme parameters) and :func:`run_family`.
- :mod:`~vibroimpact.validation.orbit_families`: periodic orbits near a fold, a period
  doubling and grazing, against an independent solver.
- :mod:`~vibroimpact.validation.streaming`: a long record streamed from disk, checked by
  invariants and by chunk-size equality.
- :mod:`~vibroimpact.validation.campaign`: every family in one call, full size or a seeded
  sample (``python -m vibroimpact.validation.campaign --size quick`` or ``--size sample``).
"""
