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

Each wall has its own impact law, :class:`Restitution`: the velocity after impact is
``-eps(u) u`` for the approach velocity ``u``, with

    eps(u) = eps / (1 + |u| / speed_scale),

Newton's law (the paper's eq. 7, ``eps`` constant) when ``speed_scale`` is infinite, the
default, and a restitution that falls with the impact speed otherwise, as measured
restitution does (W. Goldsmith, *Impact*, 1960, ch. 6). This module is the one place the law
and its consequences are written: the rebound :func:`rebound_velocity`, its derivative
:func:`rebound_derivative` (the saltation matrix, the Jacobians), its ratio
:func:`rebound_ratio`, and the range of the restitution over a band of speeds
:func:`restitution_range` (the simulator's proof that chatter has ended). The kernels read
the law from the compiled model: ``eps`` and ``a = 1 / speed_scale`` (0 for Newton's law) per
wall. The functions are plain Python (:mod:`vibroimpact._law` compiles them once for the
kernels, docs/architecture.md "Adding physics"); with ``a = 0`` each rounds exactly as
Newton's law written in place.
"""
from dataclasses import dataclass, field
import math

import numpy as np

from vibroimpact import _checks

#: Sides of a wall: ``ABOVE`` stands above the mass (the mass lives in ``x <= position`` and
#: hits it moving up, the paper's wall); ``BELOW`` stands below it (``x >= position``).
ABOVE = 1
BELOW = -1


def rebound_velocity(eps, u, a=0.0):
    """Velocity just after an impact met at velocity ``u``: ``-eps(u) u``, with
    ``eps(u) = eps / (1 + a |u|)`` (``a = 1 / speed_scale``; ``a = 0``: Newton's law, paper
    eq. 7, to the bit: the quotient by ``1.0`` is exact).

    In any frame: ``u`` and the result share the frame's sign convention. Plain arithmetic,
    so numba compiles it into the kernels as it is (``vibroimpact.impact.stepping``).
    """
    return -eps * u / (1.0 + a * abs(u))


def rebound_derivative(eps, u, a=0.0):
    """``d rebound_velocity / du`` at the approach velocity ``u``: the impact's tangent
    (the orbit solver's and the attractors' Jacobians, the saltation matrix):
    ``-eps / (1 + a |u|)^2``; Newton's law: ``-eps``.

    tests/test_impact_law.py holds it to a finite difference of :func:`rebound_velocity`.
    """
    d = 1.0 + a * abs(u)
    return -eps / (d * d)


def rebound_ratio(eps, u, a=0.0):
    """``rebound_velocity(eps, u, a) / u = -eps(u)``: the saltation matrix's position entry,
    and the orbit solver's ``-v_+ = -rebound_ratio * u`` in its Jacobians' ``d/dtau``
    entries.

    Written out so that Newton's law gives ``-eps`` to the last bit (the quotient
    ``(-eps * u) / u`` does not); tests/test_impact_law.py holds the three to one another.
    """
    return -eps / (1.0 + a * abs(u))


def restitution_range(eps, a, w):
    """``(lowest, highest)`` restitution ``eps(u)`` over the speeds ``0 <= |u| <= w``: the
    law falls with the speed, so ``(eps / (1 + a w), eps)``; Newton's law: ``(eps, eps)``.

    The simulator's chatter proof (:func:`vibroimpact.impact.events.chatter_tail`) bounds the
    rebounds of a sequence whose speeds stay below ``w`` with it.
    """
    return eps / (1.0 + a * w), eps


def law_rates(speed_scale=math.inf, speed_scale_lower=None):
    """``(a, a_lower)``: the kernels' ``1 / speed_scale`` of the wall at ``delta`` and of the
    second wall (``speed_scale_lower`` None: the first's), 0 for Newton's law, checked."""
    upper = Restitution(0.0, speed_scale).a
    lower = upper if speed_scale_lower is None else Restitution(
        0.0, _speed_scale(speed_scale_lower, "speed_scale_lower")).a
    return upper, lower


def _speed_scale(value, name="speed_scale"):
    """The law's speed scale checked: a real number > 0, ``inf`` for Newton's law."""
    if isinstance(value, (int, float)) and not isinstance(value, bool) and value == math.inf:
        return math.inf
    try:
        return _checks.real(name, value, low=0.0, low_open=True)
    except ValueError:
        raise ValueError(f"{name} must be a real number > 0, or inf for Newton's law (a "
                         f"constant restitution), got {value!r}") from None


@dataclass(frozen=True)
class Restitution:
    """The impact law of a wall: restitution ``eps(u) = eps / (1 + |u| / speed_scale)`` at
    the approach speed ``|u|``, ``0 <= eps <= 1`` its value at vanishing speed and
    ``speed_scale > 0`` the speed at which it has halved; ``speed_scale = inf`` (the default)
    is Newton's law with the constant coefficient ``eps``."""

    eps: float
    speed_scale: float = math.inf

    def __post_init__(self):
        object.__setattr__(self, "eps", _checks.eps(self.eps))
        object.__setattr__(self, "speed_scale", _speed_scale(self.speed_scale))

    @property
    def a(self):
        """``1 / speed_scale``: the kernels' form of the law's speed dependence (0: Newton)."""
        return 0.0 if math.isinf(self.speed_scale) else 1.0 / self.speed_scale

    @property
    def newton(self):
        """Whether the restitution is constant (Newton's law)."""
        return math.isinf(self.speed_scale)

    def rebound(self, u):
        """Velocity after impact for the approach velocity ``u`` (either sign convention)."""
        return rebound_velocity(self.eps, u, self.a)


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
    def paper(cls, zeta, eps, delta, amplitude=0.0, beta=1.0, *, gap=None, eps_lower=None,
              speed_scale=math.inf, speed_scale_lower=None):
        """The paper's oscillator from its loose parameters (the public functions' arguments),
        with an optional second wall ``gap`` below the first (restitution ``eps_lower``,
        default ``eps``). ``speed_scale`` (and ``speed_scale_lower``, default
        ``speed_scale``) make a wall's restitution fall with the impact speed
        (:class:`Restitution`); ``inf``, the default, is Newton's law."""
        delta = _checks.real("delta", delta)
        walls = [Wall(delta, ABOVE, Restitution(eps, speed_scale))]
        if gap is not None:
            gap = _checks.real("gap", gap, low=0.0, low_open=True)
            lower = delta - gap
            if not math.isfinite(lower) or not lower < delta:
                raise ValueError(f"gap must be a finite real number > 0 that leaves "
                                 f"delta - gap below delta, got {gap!r}")
            eps_lower = eps if eps_lower is None else eps_lower
            speed_scale_lower = (speed_scale if speed_scale_lower is None
                                 else speed_scale_lower)
            walls.append(Wall(lower, BELOW, Restitution(
                _checks.eps(eps_lower, "eps_lower"),
                _speed_scale(speed_scale_lower, "speed_scale_lower"))))
        elif eps_lower is not None or speed_scale_lower is not None:
            name = "eps_lower" if eps_lower is not None else "speed_scale_lower"
            raise ValueError(f"{name} needs a second wall: give gap as well")
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

    @property
    def newton(self):
        """Whether every wall follows Newton's law (a constant restitution): what the
        closed-form orbit solvers and the paper's theories assume."""
        return all(w.law.newton for w in self.walls)

    def restitution(self, u, wall=None):
        """The restitution ``eps_w(u)`` of each impact met at approach speed ``u`` at wall
        ``wall`` (0 per impact, the default: the wall at ``delta``; 1: the one below), by each
        wall's law: the rebound speed is ``restitution * u`` (float64 array)."""
        u = np.abs(np.asarray(u, dtype=float))
        upper = self.walls[0].law
        out = -rebound_ratio(upper.eps, u, upper.a)
        if self.n_walls == 2 and wall is not None:
            lower = self.walls[1].law
            out = np.where(np.asarray(wall) == 1, -rebound_ratio(lower.eps, u, lower.a), out)
        return out

    def params(self):
        """The loose parameters, as the results' ``params`` record them (a wall's
        ``speed_scale`` only where its law is not Newton's)."""
        out = dict(zeta=self.zeta, eps=self.eps, delta=self.delta,
                   amplitude=self.amplitude, beta=self.beta)
        if self.n_walls == 2:
            out.update(gap=self.gap, eps_lower=self.eps_lower)
        if not self.newton:
            out["speed_scale"] = self.walls[0].law.speed_scale
            if self.n_walls == 2:
                out["speed_scale_lower"] = self.walls[1].law.speed_scale
        return out
