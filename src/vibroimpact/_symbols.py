"""The parameters a map's plane may run over, in the paper's symbols.

One table for every layer that names a parameter to a reader: the figures' axis labels
(`vibroimpact.plotting`), the captions that say what a map holds fixed, and the messages of
the plane solver (`vibroimpact.orbits.plane`). Plain data, no import: a config check, a report
or a figure job may read it without loading matplotlib or a kernel.

Each name is the one a study's config and a map dataset use (``ds.attrs["axes"]``, the grid's
dimension names, the keys of ``ds.attrs["fixed"]``).
"""
from __future__ import annotations

__all__ = ["PARAMETERS", "PLANE_PARAMETERS", "HARMONIC_PARAMETERS", "TWO_WALL_PARAMETERS",
           "NOISE_PARAMETERS", "parameter_symbol", "parameter_label", "fixed_caption",
           "format_value"]

#: ``name: (symbol in mathtext, symbol in plain text, axis label in mathtext)``. The paper
#: writes zeta (eq. 1), eps (eq. 2), delta (Fig. 1), the harmonic force ``sin(beta_f tau)``
#: (section 4) and the random force's rms (Fig. 4); ``eps_lower``, ``gap`` and ``amplitude``
#: are this package's (a second wall at ``delta - gap`` with restitution ``eps_lower``, the
#: harmonic force ``A sin(beta_f tau)``). The labels of ``delta`` and ``inv_beta`` are those
#: the paper's maps have always carried (`vibroimpact.plotting.LABELS`).
PARAMETERS = {
    "zeta": (r"\zeta", "ζ", r"damping ratio $\zeta$"),
    "eps": (r"\varepsilon", "ε", r"restitution $\varepsilon$"),
    "eps_lower": (r"\varepsilon_l", "ε_l", r"restitution of the lower wall $\varepsilon_l$"),
    "delta": (r"\delta", "δ", r"play $\delta$"),
    "gap": ("g", "g", r"gap $g$ between the walls"),
    "amplitude": ("A", "A", r"amplitude $A$ of the harmonic force"),
    "inv_beta": (r"1/\beta_f", "1/β_f", r"inverse forcing frequency $1/\beta_f$"),
    "rms": (r"\sigma_r", "σ_r", r"rms $\sigma_r$ of the random force"),
}
#: The names a plane's axes may take, in the order a caption lists them.
PLANE_PARAMETERS = tuple(PARAMETERS)
#: The parameters of the periodic motions under the harmonic force alone (Fig. 16,
#: `vibroimpact.orbits.plane.orbit_plane`): one wall, and with a second wall.
HARMONIC_PARAMETERS = ("zeta", "eps", "delta", "inv_beta", "amplitude")
TWO_WALL_PARAMETERS = HARMONIC_PARAMETERS + ("gap", "eps_lower")
#: Parameters of the random force: a plane over one has no Fig. 16 (a config check can say
#: so from this table, before any job, without loading a kernel).
NOISE_PARAMETERS = ("rms",)


def _known(name):
    if name not in PARAMETERS:
        raise ValueError(f"parameter {name!r} is not one a map's plane may run over; the "
                         f"parameters: {list(PARAMETERS)}")
    return PARAMETERS[name]


def parameter_symbol(name, math=True):
    """The paper's symbol of parameter `name`: ``"$\\zeta$"`` (mathtext) or ``"ζ"``."""
    symbol, text, _ = _known(name)
    return f"${symbol}$" if math else text


def parameter_label(name):
    """The axis label of parameter `name` in mathtext (``"restitution $\\varepsilon$"``)."""
    return _known(name)[2]


def format_value(value):
    """A parameter value with 4 significant digits (never 0.30000000000000004); a value that
    is not a number (a noise kind) as it is."""
    try:
        return f"{float(value):.4g}"
    except (TypeError, ValueError):
        return str(value)


def fixed_caption(fixed, math=True):
    """The caption line saying what a map holds fixed: ``"ζ = 0.05, A = 1, 1/β_f = 1.1, σ_r =
    0.29"``.

    Parameters
    ----------
    fixed : dict
        ``{name: value}`` of the parameters the plane does not run over (a map dataset's
        ``attrs["fixed"]``, decoded). Known parameters come first, in the order of
        `PARAMETERS`, written with their symbols; any other key after them, by its name.
    math : bool
        Symbols in mathtext (a figure) or in plain Unicode (a report, a test).

    Returns
    -------
    str
        ``""`` when nothing is fixed.
    """
    if not isinstance(fixed, dict):
        raise ValueError(f"fixed must be a dict of parameter values, got {type(fixed).__name__}")
    known = [k for k in PARAMETERS if k in fixed]
    other = sorted(k for k in fixed if k not in PARAMETERS)
    parts = [f"{parameter_symbol(k, math)} = {format_value(fixed[k])}" for k in known]
    parts += [f"{k} = {format_value(fixed[k])}" for k in other]
    return ", ".join(parts)
