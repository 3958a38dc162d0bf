"""Response statistics: spectra, impact events, the (m/n) motion classification, exact theory.

Pure numpy/scipy on arrays: no file I/O, no simulation, no randomness. The simulator produces
the impact events and the sampled record a(tau); these modules turn them into the quantities
the paper plots (Figs. 6-9, 12-15) and hold the exact results used as test oracles.

- `spectra`: Welch PSDs in the paper's convention (eqs. 8, 9) and the one conversion helper;
- `events`: intervals, velocities after impact, densities, batch means, event rates and
  means of few, clustered events, and all of them per wall;
- `collisions`: impacts grouped with the chatter and sticking they start (the unit of every
  impact statistic);
- `motions`: the (m/n) classification of intervals and the probabilities of motions;
- `residence`: residence times in the motions and the rates of switching between them;
- `escape`: the Arrhenius fit of residence times against the noise level;
- `theory`: the wall-free linear response, elastic impacts under white noise (one wall, or
  a clearance between two), and the energy-envelope averaging for eps near 1;
- `identities`: the power balance and the virial of a stationary record (a self-audit);
- `ranks`: average ranks, Spearman's correlation and the chi-square tail without importing
  scipy.stats (imported from its module);
- `centroid`: the centroid of a spectrum over a band (finding 5, Fig. 12's header), imported
  from its module (not re-exported: the simulation jobs do not reach it).

Every public name is re-exported here lazily (``vibroimpact.stats.density``), so a job that
needs one helper does not import the others' scipy modules.
"""
import importlib

_SUBMODULES = ("spectra", "events", "collisions", "motions", "residence", "escape",
               "theory", "identities")
_WHERE = {
    "PSD_DETREND": "spectra", "WelchAccumulator": "spectra", "welch_psd": "spectra",
    "onesided_to_angular": "spectra", "variance_from_psd": "spectra",
    "linear_psd_response": "spectra", "line_power": "spectra",
    "DEFAULT_N_BATCHES": "events", "impact_intervals": "events",
    "velocity_after_impact": "events", "interval_ratio": "events", "Density": "events",
    "density": "events", "BatchMeans": "events", "batch_means": "events", "t_quantile": "events",
    "poisson_interval": "events", "clopper_pearson": "events", "EventRate": "events",
    "event_rate": "events",
    "MarkMean": "events", "mark_mean": "events", "WALLS": "events",
    "wall_statistics": "events",
    "DEFAULT_REBOUND_FLOOR": "collisions", "MIN_REBOUND_FLOOR": "collisions",
    "Collisions": "collisions",
    "group_collisions": "collisions", "close_open_phase": "collisions",
    "pressed_flights": "collisions", "RULES": "collisions",
    "DEFAULT_MOTION_WINDOW": "motions", "DEFAULT_MOTIONS": "motions",
    "classify_impact_intervals": "motions", "impact_motion_probabilities": "motions",
    "count_motion_switches": "motions", "MotionStatistics": "motions",
    "motion_statistics": "motions", "motion_map_agreement": "motions",
    "ResidenceStatistics": "residence", "label_pieces": "residence",
    "residence_statistics": "residence", "by_state": "residence",
    "stationary_distribution": "residence",
    "EscapeFit": "escape", "escape_fit": "escape", "censored_bound": "escape",
    "MarkovCheck": "residence", "markov_residence_check": "residence",
    "jump_chain_independence": "residence",
    "linear_response_std": "theory", "elastic_impact_rate": "theory",
    "upcrossing_rate": "theory", "rayleigh_pdf": "theory",
    "truncated_gaussian_pdf": "theory", "EnvelopeTheory": "theory",
    "energy_envelope": "theory", "envelope_v_after_pdf": "theory",
    "envelope_energy_pdf": "theory", "clearance_mass": "theory",
    "clearance_impact_rates": "theory", "clearance_pdf": "theory",
    "ENVELOPE_EPS_MIN": "theory", "ENVELOPE_DELTA_MIN": "theory",
    "flight_moments": "identities", "identity_residuals": "identities",
    "IdentityResiduals": "identities", "MOMENTS_LOWER": "identities",
    "moment_rows": "identities",
}
__all__ = list(_WHERE)


def __getattr__(name):
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(list(globals()) + __all__ + list(_SUBMODULES))
