"""The one set of argument validators: every message names the argument and its allowed range.

Used at the edge of every public function (simulator, orbit solver, noise, statistics) so that
a bad value fails before it reaches a numba kernel, with the same wording everywhere:
``zeta must be a finite real number in (0, 1), got 1.5``.
"""
import math
import numbers
import operator

import numpy as np

__all__ = ["real", "integer", "zeta", "eps"]


def _range_text(low, high, low_open, high_open):
    if low is not None and high is not None:
        return f" in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    if low is not None:
        return f" {'>' if low_open else '>='} {low:g}"
    if high is not None:
        return f" {'<' if high_open else '<='} {high:g}"
    return ""


def real(name, value, *, low=None, high=None, low_open=False, high_open=False):
    """``value`` as a float, checked finite and within the given bounds.

    Parameters
    ----------
    name : str
        The argument's name, as the caller wrote it (it starts the error message).
    value : object
        A real number (Python or numpy; not bool).
    low, high : float or None
        Bounds; ``None`` for none.
    low_open, high_open : bool
        Whether the bound itself is excluded.

    Raises
    ------
    ValueError
        ``"<name> must be a finite real number in (0, 1), got <value>"``.
    """
    bounds = _range_text(low, high, low_open, high_open)
    message = f"{name} must be a finite real number{bounds}, got {value!r}"
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Real, np.number)):
        raise ValueError(message)
    x = float(value)
    inside = (math.isfinite(x)
              and (low is None or (x > low if low_open else x >= low))
              and (high is None or (x < high if high_open else x <= high)))
    if not inside:
        raise ValueError(message)
    return x


def integer(name, value, *, low=None, high=None):
    """``value`` as an int within ``[low, high]``; integral floats (YAML's ``1.0e8``) are
    accepted."""
    message = f"{name} must be an integer{_range_text(low, high, False, False)}, got {value!r}"
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(message)
    if isinstance(value, (float, np.floating)) and float(value).is_integer():
        value = int(value)
    try:
        n = operator.index(value)
    except TypeError:
        raise ValueError(message) from None
    if (low is not None and n < low) or (high is not None and n > high):
        raise ValueError(message)
    return n


def zeta(value, name="zeta"):
    """Damping ratio: underdamped, ``0 < zeta < 1`` (the closed-form flights assume it)."""
    return real(name, value, low=0.0, high=1.0, low_open=True, high_open=True)


def eps(value, name="eps"):
    """Restitution coefficient, ``0 <= eps <= 1``."""
    return real(name, value, low=0.0, high=1.0)
