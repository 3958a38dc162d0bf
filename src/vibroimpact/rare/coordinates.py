"""Reaction coordinates and start sets, read at the force samples: callables of ``(x, v)``.

Each takes arrays of the displacement ``x`` and velocity ``x'`` at samples and returns an
array; they hold their scales so that a run's inputs are plain recorded numbers.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vibroimpact import _checks


@dataclass(frozen=True)
class Displacement:
    """``xi = x / sigma_x``: the level-crossing coordinate (B is ``xi >= level / sigma_x``).

    Parameters
    ----------
    sigma_x : float
        Scale, ``> 0`` (the stationary std of ``x``).
    """

    sigma_x: float

    def __post_init__(self):
        _checks.real("sigma_x", self.sigma_x, low=0.0, low_open=True)

    def __call__(self, x, v):
        return np.asarray(x, dtype=float) / self.sigma_x


@dataclass(frozen=True)
class Energy:
    """``xi = sqrt((x / sigma_x)^2 + (x' / sigma_v)^2)``: the normalised energy norm, which
    for the lightly damped oscillator follows its envelope; ``x >= level`` needs ``xi >=
    level / sigma_x``.

    Parameters
    ----------
    sigma_x, sigma_v : float
        Scales, ``> 0`` (the stationary std's of ``x`` and ``x'``).
    """

    sigma_x: float
    sigma_v: float

    def __post_init__(self):
        _checks.real("sigma_x", self.sigma_x, low=0.0, low_open=True)
        _checks.real("sigma_v", self.sigma_v, low=0.0, low_open=True)

    def __call__(self, x, v):
        return np.hypot(np.asarray(x, dtype=float) / self.sigma_x,
                        np.asarray(v, dtype=float) / self.sigma_v)


@dataclass(frozen=True)
class EnergyBelow:
    """The start set ``A = {Energy(x, v) < radius}``.

    Parameters
    ----------
    radius : float
        In units of the stds, ``> 0``.
    sigma_x, sigma_v : float
        Scales, ``> 0``.
    """

    radius: float
    sigma_x: float
    sigma_v: float

    def __post_init__(self):
        _checks.real("radius", self.radius, low=0.0, low_open=True)
        object.__setattr__(self, "_energy", Energy(self.sigma_x, self.sigma_v))

    def __call__(self, x, v):
        return self._energy(x, v) < self.radius
