"""vibroimpact: exact simulation and statistics of a vibro-impact oscillator.

Reproduces Irie, Yamada & Matsuzaki (1974), "On the dynamic response of a vibro-impact
system to random force", Bull. Fac. Eng. Hokkaido Univ. 72, 13-24.

The public API is re-exported lazily: ``import vibroimpact`` loads neither numba nor the
simulator; ``vibroimpact.simulate`` does, on first use. Subpackages (docs/api.md):
``impact`` (the simulator), ``orbits`` (periodic motions), ``stats``, ``noise``,
``plotting``, ``pipeline`` (the workflow-facing layer), ``validation``. ``__version__`` is
lazy too: reading it asks git (a checkout) or ``importlib.metadata`` (an installed package),
which a figure job does not otherwise need. ``snakefile()`` is the workflow's Snakefile, for a
host workflow that pulls it in as a module.
"""
import importlib

PAPER_REFERENCE = (
    "T. Irie, G. Yamada, H. Matsuzaki (1974), On the Dynamic Response of a Vibro-Impact "
    "System to Random Force, Bull. Fac. Eng. Hokkaido Univ. 72, 13-24, hdl:2115/41224"
)

# public name -> module that defines it (imported on first access)
_LAZY = {
    "simulate": "vibroimpact.impact.simulate",
    "simulate_chunks": "vibroimpact.impact.simulate",
    "SimulationResult": "vibroimpact.impact.simulate",
    "periodic_orbits": "vibroimpact.orbits.api",
    "PeriodicOrbit": "vibroimpact.orbits.api",
    "orbit_map": "vibroimpact.orbits.api",
    "periodic_motions": "vibroimpact.attractors.shooting",
    "domain_boundaries": "vibroimpact.orbits.boundaries",
    "attractor_map": "vibroimpact.attractors.api",
    "snakefile": "vibroimpact.pipeline.layout",
    # the oscillator, its walls and their impact laws (`periodic_motions`, `simulate_model`)
    "Model": "vibroimpact.model",
    "Restitution": "vibroimpact.model",
}

# PLE0604: ruff cannot see that the keys of _LAZY are strings
__all__ = [*_LAZY, "PAPER_REFERENCE", "__version__"]  # noqa: PLE0604


def _version():
    """The version of this copy: from git tags in a checkout, else the installed one's
    (`vibroimpact._release`)."""
    from vibroimpact._release import version

    return version()


def __getattr__(name):
    if name == "__version__":
        globals()[name] = _version()
        return globals()[name]
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *_LAZY, "__version__"})
