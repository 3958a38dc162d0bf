"""Reaction coordinates and start sets, read at the force samples: callables of ``(x, v)``.

Each takes arrays of the displacement ``x`` and velocity ``x'`` at samples and returns an
array; they hold their scales so that a run's inputs are plain recorded numbers.
:class:`Predicted` reads the random force's memory too (its ``along_path``, which
:class:`~vibroimpact.rare.paths.Dynamics` calls): the coordinate for a smooth force, whose
next samples the memory nearly fixes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

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


class Predicted:
    """The oscillator's envelope with the random force's predictable part included: a
    reaction coordinate with no inertia, for a smooth (band-limited) force.

    ``xi = exp(zeta H) Energy(x_hat(H), x'_hat(H))``, where ``x_hat, x'_hat`` is the
    wall-free linear oscillator's state ``H`` after the sample predicted with every later
    innovation zero: the free response of ``(x, x')`` plus the response to the force samples
    the memory already fixes (``r_{k+i} = sum_{j >= i} h_j e_{k+i-j}`` for ``1 <= i <= H /
    dt``, joined by straight lines as the simulator joins them, and ``r_k`` itself). The
    factor ``exp(zeta H)`` undoes the damping over ``H``, so that without the predictable
    force ``xi`` is the energy coordinate's envelope now.

    Why: :class:`Energy` is read from ``(x, x')`` alone, but a band-limited force is smooth
    (correlation time ~ ``1 / beta_c``) and its next samples are nearly fixed by its memory:
    the energy over the next few samples is then nearly a function of the state at the
    sample, and the clones of a path branched where it first exceeded a level repeat its
    coming peak, tie with it and die with it (the heavy-tailed underestimate of ``p`` at
    high levels). In the linear theory the complex amplitude ``exp(zeta t) (x + i x')``
    conditioned on the past is a martingale once the predictable force is counted: each new
    innovation moves ``xi`` by its whole future effect, independent of the past, and clones
    part at once. ``H`` should cover the taps' energy (the minimum-phase taps of the paper's
    force hold 90 % of it in their first 10 time units).

    The coordinate is a function of the state at the sample (``x, x'``, the force sample and
    the filter's memory) and so keeps adaptive multilevel splitting unbiased; it ignores a
    harmonic force and the wall (it is a coordinate, not a prediction the estimate relies
    on).

    Parameters
    ----------
    zeta : float
        Damping ratio of the oscillator, ``0 < zeta < 1``.
    force : ForceFilter
        The filter the paths run (``band_limited`` or ``white``; its taps and ``dt``).
    sigma_x, sigma_v : float
        Scales, ``> 0`` (as :class:`Energy`).
    horizon : float, optional
        ``H`` (dimensionless time, ``> 0``), rounded to whole samples.
    """

    def __init__(self, zeta, force, sigma_x, sigma_v, horizon=20.0):
        import scipy.linalg

        from vibroimpact.rare.forcing import ForceFilter

        if not isinstance(force, ForceFilter):
            raise ValueError(f"force must be a ForceFilter, got {type(force).__name__}")
        if force.kind not in ("band_limited", "white"):
            raise ValueError(f"Predicted needs a band_limited or white force, got {force.kind}")
        self.zeta = _checks.zeta(zeta)
        self.force = force
        self.sigma_x = _checks.real("sigma_x", sigma_x, low=0.0, low_open=True)
        self.sigma_v = _checks.real("sigma_v", sigma_v, low=0.0, low_open=True)
        dt = force.spec.dt
        n_h = max(1, round(_checks.real("horizon", horizon, low=0.0, low_open=True) / dt))
        self.horizon = n_h * dt
        # one step of x'' + 2 zeta x' + x = f with f linear between samples, exactly:
        # s_{k+1} = Phi s_k + G0 f_k + G1 f_{k+1}
        aug = np.zeros((4, 4))
        aug[0, 1], aug[1, 0], aug[1, 1], aug[1, 2], aug[2, 3] = 1.0, -1.0, -2.0 * zeta, 1.0, 1.0
        step = scipy.linalg.expm(aug * dt)
        phi, g1 = step[:2, :2], step[:2, 3] / dt
        g0 = step[:2, 2] - g1
        powers = [np.eye(2)]
        for _ in range(n_h):
            powers.append(phi @ powers[-1])
        #: the free response over H
        self.free = powers[n_h]
        # weight of the force sample k + i in the state at k + H, i = 0 .. n_h
        w = np.zeros((n_h + 1, 2))
        for i in range(n_h + 1):
            if i < n_h:
                w[i] += powers[n_h - 1 - i] @ g0
            if i > 0:
                w[i] += powers[n_h - i] @ g1
        self.w0 = w[0]
        taps = force.taps if force.kind == "band_limited" else np.array([force.spec.rms])
        m1 = taps.size - 1
        # c_l = sum_{i >= 1} w_i h_{i+l}: the weight of e_{k-l}, l = 0 .. m - 2, the memory
        c = np.zeros((2, m1))
        for i in range(1, min(n_h, m1) + 1):
            c[:, :m1 - i + 1] += np.outer(w[i], taps[i:])
        #: ``c_l``, the weights of ``e_{k-l}`` (``l = 0 .. m - 2``) in ``x_hat, x'_hat``
        self.kernel = c
        self._scale = math.exp(self.zeta * self.horizon)

    def predict(self, x, v, r, memory, e):
        """``x_hat(H), x'_hat(H)`` at every sample of a path.

        Parameters
        ----------
        x, v, r : ndarray of float64, shape (N + 1,)
            Displacement, velocity and force at the path's samples.
        memory : ndarray of float64
            The force filter's memory at the path's start (the last innovations, oldest
            first).
        e : ndarray of float64, shape (N,)
            The path's innovations after its start.

        Returns
        -------
        ndarray of float64, shape (2, N + 1)
        """
        x = np.asarray(x, dtype=float)
        v = np.asarray(v, dtype=float)
        out = self.free @ np.vstack([x, v]) + np.outer(self.w0, np.asarray(r, dtype=float))
        m1 = self.kernel.shape[1]
        if m1:
            buf = np.concatenate([memory, e])
            # sum_l c_l e_{k-l}: e_k is buf[m1 - 1 + i] at the path's sample i
            out += scipy.signal.fftconvolve(buf[None, :], self.kernel, mode="valid", axes=1)
        return out

    def along_path(self, x, v, r, memory, e):
        """The coordinate at every sample of a path (arguments as :meth:`predict`)."""
        xh, vh = self.predict(x, v, r, memory, e)
        return self._scale * np.hypot(xh / self.sigma_x, vh / self.sigma_v)

    def __call__(self, x, v):
        raise TypeError("Predicted reads the force's memory: use along_path (Dynamics does)")
