"""The papermill arguments of the report notebooks (``notebooks/*.ipynb``).

The workflow's report rules pass every parameter of a notebook's ``parameters`` cell with
``-p``: the paths of the rule's inputs, and for a study its name, forcing amplitude, the
1/beta_f its density findings read and the plays its density figures draw. Plain values in,
a string out: nothing here knows Snakemake.
"""
import shlex

__all__ = ["DENSITY_INV_BETA", "REPORT_PARAMETERS", "nearest", "notebook_parameters",
           "papermill_arguments", "study_report_kind"]

#: The parameters of each notebook, in its `parameters` cell; each is passed with -p.
REPORT_PARAMETERS = {
    "random_force": ("study", "events", "spectra", "noise", "trace", "figures"),
    "harmonic_random": ("study", "events", "spectra", "noise", "trace", "map", "orbits",
                        "map_orbits", "basins", "lyapunov", "predictors", "figures",
                        "amplitude", "inv_beta", "density_delta"),
    "periodic_motions": ("name", "orbits", "boundaries", "basins", "lyapunov", "map",
                         "map_orbits", "predictors", "figures"),
    "performance": ("work_precision", "figures"),
    "stability": ("stress", "campaign", "figures"),
}

#: The 1/beta_f of the paper's densities under harmonic plus random force (Figs. 13, 14:
#: tau/1.1); a study's report reads the value of its grid nearest to it.
DENSITY_INV_BETA = 1.1


def harmonic(entry):
    """Whether a study's force has a harmonic part: an amplitude, or an amplitude axis of a
    plane (a list or ``{start, stop, step}``), with any value but 0."""
    amp = entry.get("amplitude", 0.0)
    if isinstance(amp, dict):                   # a grid {start, stop, step}
        values = [amp.get("start", 0.0), amp.get("stop", 0.0)]
    elif isinstance(amp, (list, tuple)):
        values = amp
    else:
        values = [amp]
    return any(float(v) != 0.0 for v in values)


def study_report_kind(entry):
    """The notebook of a study's report: random force alone, or harmonic plus random."""
    return "harmonic_random" if harmonic(entry) else "random_force"


def nearest(values, target):
    """The value of ``values`` nearest to ``target`` (the first of two as near)."""
    return min(values, key=lambda v: abs(v - target))


def notebook_parameters(notebook, inputs, study=None, entry=None, inv_beta=(), orbits=None):
    """``{name: value}`` of every parameter of ``notebook`` (a key of REPORT_PARAMETERS).

    Parameters
    ----------
    notebook : str
        The notebook's name.
    inputs : mapping
        The rule's named inputs, paths; ``figures`` a list of paths, joined by spaces.
    study, entry : str and mapping, optional
        A study report's study and its config entry.
    inv_beta : sequence of float
        The study's 1/beta_f grid.
    orbits : str, optional
        An orbits report's entry name.

    Returns
    -------
    dict
        Each parameter as a string; ``""`` for a dataset the study does not have.
    """
    given = {name: " ".join(value) if name == "figures" else str(value)
             for name, value in inputs.items()}
    if study is not None:
        amp = entry.get("amplitude", 0.0)
        # an amplitude axis (a plane over it) has no one amplitude: NaN (only finding 5, on
        # the spectra, reads it)
        given.update(study=study,
                     amplitude=float(amp) if isinstance(amp, (int, float)) else float("nan"),
                     inv_beta=nearest([float(v) for v in inv_beta], DENSITY_INV_BETA),
                     density_delta=" ".join(str(float(d))
                                            for d in entry.get("density_delta") or ()))
    if orbits is not None:
        given["name"] = orbits
    return {name: str(given.get(name, "")) for name in REPORT_PARAMETERS[notebook]}


def papermill_arguments(parameters):
    """``-p name value`` for each parameter, quoted for a shell."""
    return " ".join(f"-p {name} {shlex.quote(value)}" for name, value in parameters.items())
