"""Argument checks shared by every operator.

Every helper returns the converted value or raises :class:`ValueError` whose message names the
parameter and states the allowed range, so that bad input never gets clipped silently.
"""

from __future__ import annotations

import math
from numbers import Integral
from typing import Any

import numpy as np

__all__ = [
    "as_input_sequence",
    "finite_scalar",
    "positive_scalar",
    "nonnegative_scalar",
    "scalar_in_open_interval",
    "finite_array",
    "positive_integer",
    "nonnegative_integer",
    "direction_sign",
    "as_generator",
]


def as_input_sequence(x: Any, name: str = "inputs") -> np.ndarray:
    """``x`` as a non-empty 1-D float64 array of finite numbers (a new, writable copy)."""
    try:
        arr = np.array(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a 1-D sequence of finite real numbers") from exc
    if arr.ndim != 1:
        raise ValueError(
            f"{name} must be a 1-D sequence of finite real numbers, got shape {arr.shape}"
        )
    if arr.size == 0:
        raise ValueError(f"{name} must contain at least one value (got an empty sequence)")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return arr


def finite_scalar(x: Any, name: str) -> float:
    """``x`` as a finite Python float."""
    if isinstance(x, bool):
        raise ValueError(f"{name} must be a finite real number, got a bool")
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a finite real number, got {x!r}") from exc
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a finite real scalar, got shape {arr.shape}")
    value = float(arr)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite real number, got {value}")
    return value


def positive_scalar(x: Any, name: str) -> float:
    """``x`` as a finite float > 0."""
    value = finite_scalar(x, name)
    if not value > 0.0:
        raise ValueError(f"{name} must be > 0 (finite), got {value}")
    return value


def nonnegative_scalar(x: Any, name: str) -> float:
    """``x`` as a finite float >= 0."""
    value = finite_scalar(x, name)
    if not value >= 0.0:
        raise ValueError(f"{name} must be >= 0 (finite), got {value}")
    return value


def scalar_in_open_interval(x: Any, name: str, low: float, high: float) -> float:
    """``x`` as a finite float with ``low < x < high``."""
    value = finite_scalar(x, name)
    if not (low < value < high):
        raise ValueError(f"{name} must lie in the open interval ({low}, {high}), got {value}")
    return value


def finite_array(x: Any, name: str, ndim: int | None = None, nonempty: bool = True) -> np.ndarray:
    """``x`` as a float64 array of finite numbers (a new copy), optionally of given ``ndim``."""
    try:
        arr = np.array(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of finite real numbers") from exc
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be a {ndim}-D array, got shape {arr.shape}")
    if nonempty and arr.size == 0:
        raise ValueError(f"{name} must not be empty")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return arr


def positive_integer(x: Any, name: str, minimum: int = 1) -> int:
    """``x`` as a Python int >= ``minimum`` (floats with integral value are not accepted)."""
    if isinstance(x, bool) or not isinstance(x, Integral):
        raise ValueError(f"{name} must be an integer >= {minimum}, got {x!r}")
    value = int(x)
    if value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value}")
    return value


def nonnegative_integer(x: Any, name: str) -> int:
    """``x`` as a Python int >= 0 (floats with integral value are not accepted)."""
    return positive_integer(x, name, minimum=0)


def direction_sign(direction: Any, name: str = "direction") -> int:
    """``direction`` as +1 (rising input) or -1 (falling input)."""
    if isinstance(direction, bool) or direction not in (1, -1):
        raise ValueError(f"{name} must be +1 (rising) or -1 (falling), got {direction!r}")
    return int(direction)


def as_generator(seed: Any, name: str = "seed") -> np.random.Generator:
    """A numpy Generator from a non-negative int seed or a Generator (used as is).

    ``None`` is rejected: every random quantity must be reproducible, so a silent fall-back to
    fresh OS entropy is not offered.
    """
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None:
        raise ValueError(
            f"{name} is required: give a non-negative int or a numpy.random.Generator "
            "(None would draw fresh, irreproducible entropy)"
        )
    if isinstance(seed, Integral) and not isinstance(seed, bool) and seed >= 0:
        return np.random.default_rng(seed)
    raise ValueError(f"{name} must be a non-negative int or a numpy.random.Generator, got {seed!r}")
