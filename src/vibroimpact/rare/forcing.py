"""The random force as a filter with a state: what a clone of a sample path must carry.

:func:`vibroimpact.noise.generate` streams a whole record from one seed; a path of a splitting
algorithm must instead stop at a sample, be copied, and go on with *fresh* innovations. Every
kind of :class:`~vibroimpact.noise.NoiseSpec` is a causal filter of white Gaussian
innovations ``e_k`` (unit variance) with the same taps or coefficients as the generator's:

- ``white`` (and a ``band_limited`` cut-off at the Nyquist frequency, as the generator
  treats it): ``r_k = rms e_k``; no memory.
- ``band_limited``: an FIR ``r_k = sum_{j=0}^{m-1} h_j e_{k-j}``: its memory is the last
  ``m - 1`` innovations. By default (``phase="minimum"``) the taps are the minimum-phase
  version of the generator's Kaiser taps: the same ``|H|`` (to ~1e-8 in the pass band), so the
  same Gaussian process in law, but causal in the way that matters for splitting. The
  generator's taps (``phase="linear"``) are symmetric: a new innovation reaches the force at
  full weight only ``(m - 1) / 2`` samples later (197 time units for the paper's force), so
  two clones share their force for that long and splitting cannot tell them apart (measured:
  every clone of a path at a level repeats its score, the run dies out). The minimum-phase
  taps put 90 % of their energy in the first 100 (10 time units).
- ``lowpass2``: the ARMA(2, 1) recursion in direct form II transposed
  (``scipy.signal.lfilter``): its memory is the 2-slot filter state ``zi``, started in an
  exact draw of its stationary state as the generator does.

A :class:`ForceState` (the current sample ``r_k`` and the memory) is the noise's share of the
state a clone copies. The arithmetic of one output sample depends on its inputs only, never on
where a call splits the record (a fixed-order sum for the FIR, a sequential recursion for
lowpass2), so advancing a state by ``n1`` then ``n2`` innovations gives bit for bit what
advancing it by the ``n1 + n2`` at once gives.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal
from numba import njit

from vibroimpact import noise as _noise

#: FFT length of the cepstrum in the minimum-phase construction (its aliasing error falls
#: with it: 2^19 points give |H| within ~1e-8 of the linear-phase taps' in the pass band).
MIN_PHASE_FFT = 2**19


@dataclass(frozen=True)
class ForceState:
    """The random force's state at a sample.

    Attributes
    ----------
    r : float
        The force sample ``r_k`` there (dimensionless force).
    memory : ndarray of float64
        The filter's memory: the last ``m - 1`` innovations (FIR, oldest first), the
        lfilter state ``zi`` (lowpass2, shape (2,)) or empty (white). Never written to.
    """

    r: float
    memory: np.ndarray


class ForceFilter:
    """The filter of one :class:`~vibroimpact.noise.NoiseSpec`, stepped from a ForceState.

    Parameters
    ----------
    spec : NoiseSpec
        The random force's target statistics; the taps (coefficients) are the generator's.
    phase : {"minimum", "linear"}, optional
        ``band_limited`` only: the minimum-phase taps of the same magnitude response (the
        default; module docstring) or the generator's own linear-phase taps.
    """

    def __init__(self, spec, phase="minimum"):
        if not isinstance(spec, _noise.NoiseSpec):
            raise ValueError(f"spec must be a NoiseSpec, got {type(spec).__name__}")
        if phase not in ("minimum", "linear"):
            raise ValueError(f"phase must be 'minimum' or 'linear', got {phase!r}")
        self.spec = spec
        self.phase = phase
        if spec.kind == "white" or (spec.kind == "band_limited" and spec._full_band):
            self.kind = "white"
        else:
            self.kind = spec.kind
        self.taps = None
        if self.kind == "band_limited":
            self.taps = _noise.band_limited_taps(spec)
            if phase == "minimum":
                taps = scipy.signal.minimum_phase(self.taps, "homomorphic", n_fft=MIN_PHASE_FFT,
                                                  half=False)
                self.taps = taps * (spec.rms / math.sqrt(np.dot(taps, taps)))
        self.arma = _noise.lowpass2_arma(spec) if self.kind == "lowpass2" else None

    @property
    def n_memory(self):
        """Length of the memory array (0 for white)."""
        return {"white": 0, "band_limited": 0 if self.taps is None else self.taps.size - 1,
                "lowpass2": 2}[self.kind]

    def stationary(self, rng):
        """A draw of the stationary state (the force at a sample and its memory).

        Parameters
        ----------
        rng : numpy.random.Generator
            Source of the innovations.

        Returns
        -------
        ForceState
        """
        if self.kind == "white":
            return ForceState(self.spec.rms * float(rng.standard_normal()), np.empty(0))
        if self.kind == "band_limited":
            m = self.taps.size
            e = rng.standard_normal(m)
            out = np.empty(1)
            _fir(self.taps, e, out)
            return ForceState(float(out[0]), e[1:].copy())
        spec = self.spec
        b, a = self.arma
        unit = _noise.NoiseSpec("lowpass2", 1.0, spec.dt, spec.beta_c, spec.zeta_f)
        b_u, _ = _noise.lowpass2_arma(unit)
        rho_1 = _noise.lowpass2_correlation(spec.dt, spec.beta_c, spec.zeta_f)
        y_prev, e, xi = rng.standard_normal(3)
        y = rho_1 * y_prev + b_u[0] * e + math.sqrt(max(1.0 - rho_1**2 - b_u[0] ** 2, 0.0)) * xi
        zi = spec.rms * np.array([b_u[1] * e - a[1] * y - a[2] * y_prev, -a[2] * y])
        return ForceState(float(spec.rms * y), zi)

    def advance(self, state, e):
        """The next samples from ``state`` and the innovations ``e``.

        Parameters
        ----------
        state : ForceState
            The state at sample ``k``.
        e : ndarray of float64, shape (n,)
            Unit innovations ``e_{k+1} ... e_{k+n}``.

        Returns
        -------
        r : ndarray of float64, shape (n + 1,)
            ``r_k ... r_{k+n}`` (``r[0]`` is ``state.r``): the samples the simulator steps
            through.
        end : ForceState
            The state at sample ``k + n``.
        """
        e = np.ascontiguousarray(e, dtype=np.float64)
        r = np.empty(e.size + 1)
        r[0] = state.r
        if e.size == 0:
            return r, state
        if self.kind == "white":
            r[1:] = self.spec.rms * e
            return r, ForceState(float(r[-1]), state.memory)
        if self.kind == "band_limited":
            buf = np.concatenate([state.memory, e])
            _fir(self.taps, buf, r[1:])
            return r, ForceState(float(r[-1]), buf[buf.size - self.n_memory:].copy())
        b, a = self.arma
        r[1:], zi = scipy.signal.lfilter(b, a, e, zi=state.memory)
        return r, ForceState(float(r[-1]), zi)


@njit(cache=True)
def _fir(taps, buf, out):
    """``out[i] = sum_j taps[j] buf[i + m - 1 - j]``, in a fixed order for every ``i``.

    Four partial sums over the reversed taps (index mod 4) then their fixed combination:
    several times the speed of one dependency chain, and the same bits for an output
    whatever the array around it.
    """
    m = taps.size
    rev = taps[::-1].copy()
    for i in range(out.size):
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        j = 0
        while j + 3 < m:
            s0 += rev[j] * buf[i + j]
            s1 += rev[j + 1] * buf[i + j + 1]
            s2 += rev[j + 2] * buf[i + j + 2]
            s3 += rev[j + 3] * buf[i + j + 3]
            j += 4
        while j < m:
            s0 += rev[j] * buf[i + j]
            j += 1
        out[i] = (s0 + s1) + (s2 + s3)
