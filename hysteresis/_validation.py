"""Argument checks shared by every operator.

Every helper returns the converted value or raises :class:`ValueError` (or
:class:`ParameterTypeError`, a ``TypeError`` that is also a ``ValueError``) whose message names
the parameter and states the allowed range, so that bad input never gets clipped or cast
silently: strings (even numeric ones), complex numbers, booleans and ``None`` are refused, not
converted.

Magnitudes: parameters and inputs are bounded by :data:`MAX_MAGNITUDE` (1e300) where the
operators do arithmetic with them (centres ``(α+β)/2``, widths ``α−β``, ``u ± p/2``): beyond it
that arithmetic can overflow to ``inf``, which the compiled kernels must never see.
"""

from __future__ import annotations

import dataclasses
import math
from numbers import Integral, Real
from typing import Any

import numpy as np

__all__ = [
    "MAX_MAGNITUDE",
    "ParameterTypeError",
    "lattice_shape",
    "as_input_sequence",
    "real_array",
    "finite_scalar",
    "positive_scalar",
    "nonnegative_scalar",
    "scalar_in_open_interval",
    "finite_array",
    "positive_integer",
    "nonnegative_integer",
    "direction_sign",
    "as_generator",
    "check_state_type",
    "bounded_work",
    "MAX_GRID_NODES",
    "check_grid_nodes",
]

#: largest magnitude accepted for parameters and inputs whose sums/differences are formed
MAX_MAGNITUDE = 1e300
#: largest number of nodes of an identification grid (the Everett table holds nodes² values)
MAX_GRID_NODES = 2001


class ParameterTypeError(TypeError, ValueError):
    """A parameter of the wrong type (a string, complex number, ``None``, ...).

    Both a ``TypeError`` (what it is) and a ``ValueError`` (what the operators documented for
    every bad argument before the type checks were tightened), so either ``except`` catches it.
    """


def _describe(x: Any) -> str:
    text = repr(x)
    return text if len(text) <= 60 else text[:57] + "..."


def real_array(x: Any, name: str) -> np.ndarray:
    """``x`` as a float64 array (a new copy) of real numbers, without any silent coercion.

    Refused with :class:`ParameterTypeError`: strings and bytes (also numeric ones such as
    ``'1'``), complex values (even with zero imaginary part), booleans, ``None``, masked arrays
    (``numpy.asarray`` would drop the mask) and other non-numbers. Ragged nested sequences
    raise ``ValueError``. Finiteness is not checked here.
    """
    if isinstance(x, str | bytes):
        raise ParameterTypeError(
            f"{name} must be real numbers, got a string {_describe(x)} (strings are not converted)"
        )
    if x is None:
        raise ParameterTypeError(f"{name} must be real numbers, got None")
    if isinstance(x, np.ma.MaskedArray):
        raise ParameterTypeError(
            f"{name} must not be a masked array (its mask would be ignored); pass "
            f"{name}.filled(...) or {name}.compressed()"
        )
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of real numbers (got {_describe(x)})") from exc
    kind = arr.dtype.kind
    if kind == "O":
        for item in arr.flat:
            if isinstance(item, bool | np.bool_) or not isinstance(item, Real | np.number):
                raise ParameterTypeError(
                    f"{name} must contain real numbers only, got {type(item).__name__} "
                    f"{_describe(item)}"
                )
            if isinstance(item, complex | np.complexfloating):
                raise ParameterTypeError(f"{name} must be real, got complex {item!r}")
    elif kind == "c":
        raise ParameterTypeError(
            f"{name} must be real, got complex values (dtype {arr.dtype}); pass the real part "
            "explicitly if that is what you mean"
        )
    elif kind in "USV":
        raise ParameterTypeError(
            f"{name} must be real numbers, got strings or raw data (dtype {arr.dtype})"
        )
    elif kind == "b":
        raise ParameterTypeError(f"{name} must be real numbers, got booleans")
    elif kind not in "iuf":
        raise ParameterTypeError(f"{name} must be real numbers, got dtype {arr.dtype}")
    try:
        return np.array(arr, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name} must be an array of real numbers") from exc


def _check_finite_bounded(arr: np.ndarray, name: str, max_abs: float | None) -> None:
    """Finite entries of magnitude <= ``max_abs`` (if given), in one reduction: NaN and inf
    propagate through ``max(|x|)``, so the slow diagnosis runs only on bad data. A single
    value (the integrators drive operators one input at a time) takes a pure-Python path."""
    if arr.size == 0:
        return
    peak = abs(float(arr.flat[0])) if arr.size == 1 else float(np.max(np.abs(arr)))
    if math.isfinite(peak) and (max_abs is None or peak <= max_abs):
        return
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    _check_magnitude(arr, name, max_abs)


def _check_magnitude(arr: np.ndarray, name: str, max_abs: float | None) -> None:
    if max_abs is not None and arr.size and float(np.max(np.abs(arr))) > max_abs:
        raise ValueError(
            f"{name} must have magnitude <= {max_abs:g} (larger values overflow the operator's "
            f"arithmetic), got {float(arr.flat[int(np.argmax(np.abs(arr)))])!r}"
        )


def as_input_sequence(
    x: Any, name: str = "inputs", max_abs: float | None = MAX_MAGNITUDE
) -> np.ndarray:
    """``x`` as a non-empty 1-D float64 array of finite numbers (a new, writable copy), each of
    magnitude <= ``max_abs`` (default :data:`MAX_MAGNITUDE`; ``None``: no bound)."""
    try:
        arr = real_array(x, name)
    except ParameterTypeError:
        raise
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a 1-D sequence of finite real numbers") from exc
    if arr.ndim != 1:
        raise ValueError(
            f"{name} must be a 1-D sequence of finite real numbers, got shape {arr.shape}"
        )
    if arr.size == 0:
        raise ValueError(f"{name} must contain at least one value (got an empty sequence)")
    _check_finite_bounded(arr, name, max_abs)
    return arr


def finite_scalar(x: Any, name: str, max_abs: float | None = None) -> float:
    """``x`` as a finite Python float (with ``|x| <= max_abs`` if given).

    Strings (even ``'1'``), complex numbers, booleans and ``None`` raise
    :class:`ParameterTypeError`."""
    if isinstance(x, bool | np.bool_):
        raise ParameterTypeError(f"{name} must be a finite real number, got a bool")
    arr = real_array(x, name)
    if arr.ndim != 0:
        raise ValueError(f"{name} must be a finite real scalar, got shape {arr.shape}")
    value = float(arr)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite real number, got {value}")
    _check_magnitude(arr, name, max_abs)
    return value


def positive_scalar(x: Any, name: str, max_abs: float | None = None) -> float:
    """``x`` as a finite float > 0."""
    value = finite_scalar(x, name, max_abs)
    if not value > 0.0:
        raise ValueError(f"{name} must be > 0 (finite), got {value}")
    return value


def nonnegative_scalar(x: Any, name: str, max_abs: float | None = None) -> float:
    """``x`` as a finite float >= 0."""
    value = finite_scalar(x, name, max_abs)
    if not value >= 0.0:
        raise ValueError(f"{name} must be >= 0 (finite), got {value}")
    return value


def scalar_in_open_interval(x: Any, name: str, low: float, high: float) -> float:
    """``x`` as a finite float with ``low < x < high``."""
    value = finite_scalar(x, name)
    if not (low < value < high):
        raise ValueError(f"{name} must lie in the open interval ({low}, {high}), got {value}")
    return value


def finite_array(
    x: Any,
    name: str,
    ndim: int | None = None,
    nonempty: bool = True,
    max_abs: float | None = None,
) -> np.ndarray:
    """``x`` as a float64 array of finite numbers (a new copy), optionally of given ``ndim``
    and with every ``|x_i| <= max_abs``."""
    arr = real_array(x, name)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be a {ndim}-D array, got shape {arr.shape}")
    if nonempty and arr.size == 0:
        raise ValueError(f"{name} must not be empty")
    _check_finite_bounded(arr, name, max_abs)
    return arr


def time_window(t_end: Any, transient: Any) -> tuple[float, float]:
    """``(t_end, transient)`` as floats with ``0 <= transient < t_end`` (``ValueError`` naming
    the parameter otherwise): the averaging window of a run."""
    t_end = finite_scalar(t_end, "t_end")
    transient = finite_scalar(transient, "transient")
    if transient < 0.0:
        raise ValueError(f"transient must be >= 0, got {transient}")
    if not t_end > transient:
        raise ValueError(f"t_end must be > transient = {transient}, got {t_end}")
    return t_end, transient


def positive_integer(x: Any, name: str, minimum: int = 1) -> int:
    """``x`` as a Python int >= ``minimum`` (floats with integral value are not accepted)."""
    if isinstance(x, bool | np.bool_) or not isinstance(x, Integral):
        raise ParameterTypeError(
            f"{name} must be an integer >= {minimum}, got {type(x).__name__} {_describe(x)}"
        )
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


def check_state_type(state: Any, expected: type | tuple[type, ...], operator: Any) -> None:
    """Refuse a state object of the wrong type with a :class:`ParameterTypeError` (a
    ``TypeError``, also a ``ValueError``) naming ``state``."""
    if not isinstance(state, expected):
        names = (
            expected.__name__
            if isinstance(expected, type)
            else " or ".join(t.__name__ for t in expected)
        )
        raise ParameterTypeError(
            f"state must be a {names} of this {type(operator).__name__} (from its "
            f"initial_state/state/apply), got {type(state).__name__}"
        )


def bounded_work(count: Any, name: str, limit: int, what: str) -> int:
    """Refuse up front a request whose size ``count`` exceeds ``limit`` (memory/time bound).

    ``what`` says what is counted (e.g. "grid nodes"); the message names ``name`` and the limit.
    """
    value = float(count)
    if not math.isfinite(value) or value > limit:
        raise ValueError(
            f"{name} asks for {value:.3g} {what}, more than the limit {limit}: refused up front "
            "(it would take unbounded memory or time); choose a coarser value"
        )
    return int(value)


def check_grid_nodes(step: Any, saturation: Any, max_nodes: int = MAX_GRID_NODES) -> int:
    """Number of nodes ``2 ceil(saturation/step) + 1`` of an identification grid, refusing
    more than ``max_nodes`` (default :data:`MAX_GRID_NODES`) with a ``ValueError`` naming
    ``step``: the reversal curves cost ``nodes²/2`` operator steps and the Everett table
    ``nodes²`` floats."""
    step = positive_scalar(step, "step")
    saturation = positive_scalar(saturation, "saturation")
    ratio = saturation / step
    nodes = 2.0 * math.ceil(ratio - 1e-9) + 1.0 if math.isfinite(ratio) else math.inf
    if nodes > max_nodes:
        raise ValueError(
            f"step={step!r} with saturation={saturation!r} asks for {nodes:.3g} grid nodes, "
            f"more than the limit {max_nodes} (memory ~ nodes²): choose step >= "
            f"{2.0 * saturation / (max_nodes - 1):.3g}"
        )
    return int(nodes)


def readonly_array(a: Any, dtype: Any = np.float64) -> np.ndarray:
    """A read-only copy of ``a`` as an array of ``dtype`` (``None``: the dtype numpy infers);
    the one helper every immutable parameter and state object of the package uses."""
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


def frozen_state_reduce(state: Any) -> tuple:
    """``__reduce__`` of an immutable state dataclass holding read-only arrays: rebuilt from
    its fields with the arrays read-only again (pickle protocols < 5 drop that flag)."""
    values = tuple(getattr(state, f.name) for f in dataclasses.fields(state))
    return (_frozen_state, (type(state), values))


def _frozen_state(cls: type, values: tuple) -> Any:
    for value in values:
        if isinstance(value, np.ndarray):
            value.setflags(write=False)
    return cls(*values)


def lattice_shape(shape: Any) -> tuple[int, ...]:
    """The side lengths of a periodic lattice: 1 to 3 integers ``>= 3`` (an int is one side)."""
    dims = (shape,) if isinstance(shape, Integral) else shape
    try:
        dims = tuple(dims)
    except TypeError:
        raise ParameterTypeError(
            f"shape must be 1 to 3 integers >= 3 (the side lengths), got {shape!r}"
        ) from None
    ok = all(isinstance(d, Integral) and not isinstance(d, bool) and d >= 3 for d in dims)
    if not (1 <= len(dims) <= 3 and ok):
        raise ValueError(
            f"shape must be 1 to 3 integers >= 3 (the side lengths; >= 3 so that the 2d "
            f"neighbours of a site are distinct), got {shape!r}"
        )
    return tuple(int(d) for d in dims)
