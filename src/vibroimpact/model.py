"""The oscillator, its walls and its force: the one description every layer takes.

A :class:`Model` is resolved once (from a study's config, or from the public functions'
loose arguments) and carried down to the kernels, which receive it compiled into their
parameter vector (:func:`vibroimpact.impact.simulate.model_parameters`, slots in
:mod:`vibroimpact.impact.layout`). The dimensionless equation of motion is (docs/model.md)

    x'' + 2 zeta x' + x = f(tau) = r(tau) + amplitude sin(beta tau)

between impacts, with the mass confined by its walls:

- the paper's wall at ``x = delta``, hit from below (the mass lives in ``x <= delta``);
- optionally a second wall at ``x = delta - gap``, hit from above (a clearance of width
  ``gap`` between two stops: ``delta - gap <= x <= delta``).

A machine designer's symmetric stops at ``+-g/2`` about an offset ``x_c`` are
``Model.stops(g, x_c)``: ``delta = x_c + g/2``, ``gap = g``.

Each wall has its own impact law. The law is :class:`Restitution` (Newton's law, the
paper's eq. 7: the velocity after impact is ``-eps`` times the velocity before); it is the
one place that law is written: :func:`rebound_velocity`, with its derivative
:func:`rebound_derivative` and its ratio :func:`rebound_ratio` beside it (plain Python;
:mod:`vibroimpact._law` compiles them once for the kernels, docs/architecture.md "Adding
physics").
"""
from dataclasses import dataclass, field
import math


from vibroimpact import _checks

#: Sides of a wall: ``ABOVE`` stands above the mass (the mass lives in ``x <= position`` and
#: hits it moving up, the paper's wall); ``BELOW`` stands below it (``x >= position``).
ABOVE = 1
BELOW = -1


def rebound_velocity(eps, u):
    """Velocity just after an impact met at velocity ``u`` (Newton's law, paper eq. 7).

    In any frame: ``u`` and the result share the frame's sign convention. Plain arithmetic,
    so numba compiles it into the kernels as it is (``vibroimpact.impact.stepping``).
    """
    return -eps * u


def rebound_derivative(eps, u):
    """``d rebound_velocity / du`` at the approach velocity ``u``: the impact's tangent
    (the orbit solver's and the attractors' Jacobians, the saltation matrix).

    Newton's law: ``-eps``. A new law edits this beside :func:`rebound_velocity`
    (tests/test_impact_law.py holds the pair to a finite difference).
    """
    return -eps


def rebound_ratio(eps, u):
    """``rebound_velocity(eps, u) / u``: the saltation matrix's position entry, and the
    orbit solver's ``-v_+ = -rebound_ratio * u`` in its Jacobians' ``d/dtau`` entries.

    Newton's law: ``-eps``, written out so that it is ``-eps`` to the last bit (the quotient
    ``(-eps * u) / u`` is not). A new law edits this beside :func:`rebound_velocity`
    (tests/test_impact_law.py holds the three to one another).
    """
    return -eps


@dataclass(frozen=True)
class Restitution:
    """Newton's impact law with a constant coefficient ``0 <= eps <= 1``."""

    eps: float

    def __post_init__(self):
        object.__setattr__(self, "eps", _checks.eps(self.eps))

    def rebound(self, u):
        """Velocity after impact for the approach velocity ``u`` (either sign convention)."""
        return rebound_velocity(self.eps, u)


@dataclass(frozen=True)
class Wall:
    """A rigid stop at ``x = position`` on ``side`` (:data:`ABOVE` or :data:`BELOW` the
    mass), with its impact law."""

    position: float
    side: int
    law: Restitution

    def __post_init__(self):
        object.__setattr__(self, "position", _checks.real("wall position", self.position))
        if self.side not in (ABOVE, BELOW):
            raise ValueError(f"wall side must be {ABOVE} (above the mass) or {BELOW} (below "
                             f"it), got {self.side!r}")

    @property
    def eps(self):
        return self.law.eps


@dataclass(frozen=True)
class Model:
    """The oscillator (damping ``zeta``), its walls and its harmonic force.

    ``walls[0]`` is the paper's wall at ``x = delta`` (above the mass); ``walls[1]``, when
    present, the second wall at ``x = delta - gap`` (below it). The random part of the force
    is a record, not a parameter: it travels with the call (``noise=``) or the study's
    noise spec.
    """

    zeta: float
    walls: tuple
    amplitude: float = 0.0
    beta: float = 1.0
    name: str = field(default="", compare=False)

    def __post_init__(self):
        object.__setattr__(self, "zeta", _checks.zeta(self.zeta))
        object.__setattr__(self, "amplitude", _checks.real("amplitude", self.amplitude))
        object.__setattr__(self, "beta", _checks.real("beta", self.beta, low=0.0,
                                                        low_open=True))
        walls = tuple(self.walls)
        if not 1 <= len(walls) <= 2 or walls[0].side != ABOVE or (
                len(walls) == 2 and walls[1].side != BELOW):
            raise ValueError("walls must be the wall above the mass (x = delta), optionally "
                             "followed by one below it (x = delta - gap)")
        if len(walls) == 2 and not walls[1].position < walls[0].position:
            raise ValueError(f"gap must be a finite real number > 0, got "
                             f"{walls[0].position - walls[1].position!r}")
        object.__setattr__(self, "walls", walls)

    @classmethod
    def paper(cls, zeta, eps, delta, amplitude=0.0, beta=1.0, *, gap=None, eps_lower=None):
        """The paper's oscillator from its loose parameters (the public functions' arguments),
        with an optional second wall ``gap`` below the first (restitution ``eps_lower``,
        default ``eps``)."""
        delta = _checks.real("delta", delta)
        walls = [Wall(delta, ABOVE, Restitution(eps))]
        if gap is not None:
            gap = _checks.real("gap", gap, low=0.0, low_open=True)
            lower = delta - gap
            if not math.isfinite(lower) or not lower < delta:
                raise ValueError(f"gap must be a finite real number > 0 that leaves "
                                 f"delta - gap below delta, got {gap!r}")
            eps_lower = eps if eps_lower is None else eps_lower
            walls.append(Wall(lower, BELOW, Restitution(_checks.eps(eps_lower, "eps_lower"))))
        elif eps_lower is not None:
            raise ValueError("eps_lower needs a second wall: give gap as well")
        return cls(zeta, tuple(walls), amplitude, beta)

    @classmethod
    def stops(cls, zeta, clearance, offset=0.0, eps=1.0, eps_lower=None, amplitude=0.0,
              beta=1.0):
        """Symmetric stops at ``offset +- clearance / 2`` (a machine designer's backlash)."""
        clearance = _checks.real("clearance", clearance, low=0.0, low_open=True)
        offset = _checks.real("offset", offset)
        return cls.paper(zeta, eps, offset + 0.5 * clearance, amplitude, beta,
                         gap=clearance, eps_lower=eps_lower)

    # the paper's names, read by every layer that knows one wall
    @property
    def delta(self):
        return self.walls[0].position

    @property
    def eps(self):
        return self.walls[0].eps

    @property
    def n_walls(self):
        return len(self.walls)

    @property
    def gap(self):
        """Width of the clearance (``None`` with one wall)."""
        return self.walls[0].position - self.walls[1].position if self.n_walls == 2 else None

    @property
    def lower(self):
        """Position of the wall below the mass (``-inf`` with one wall)."""
        return self.walls[1].position if self.n_walls == 2 else -math.inf

    @property
    def eps_lower(self):
        return self.walls[1].eps if self.n_walls == 2 else None

    def params(self):
        """The loose parameters, as the results' ``params`` record them."""
        out = dict(zeta=self.zeta, eps=self.eps, delta=self.delta,
                   amplitude=self.amplitude, beta=self.beta)
        if self.n_walls == 2:
            out.update(gap=self.gap, eps_lower=self.eps_lower)
        return out
