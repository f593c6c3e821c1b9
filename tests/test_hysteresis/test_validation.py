"""Argument checks: converted values pass, bad values raise ValueError naming the parameter."""

import numpy as np
import pytest

from hysteresis._validation import (
    as_generator,
    as_input_sequence,
    direction_sign,
    finite_array,
    finite_scalar,
    nonnegative_integer,
    nonnegative_scalar,
    positive_integer,
    positive_scalar,
    scalar_in_open_interval,
)


def test_input_sequence_converts_to_float_1d():
    arr = as_input_sequence([1, 2, 3])
    assert arr.dtype == np.float64 and arr.shape == (3,)


@pytest.mark.parametrize(
    "bad", [[], [1.0, np.nan], [np.inf], [[1.0, 2.0]], 3.0, "abc", [1.0, -np.inf]]
)
def test_input_sequence_rejects(bad):
    with pytest.raises(ValueError, match="drive"):
        as_input_sequence(bad, name="drive")


def test_input_sequence_default_name():
    with pytest.raises(ValueError, match="inputs"):
        as_input_sequence([])


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, "x", [1.0], None, True])
def test_finite_scalar_rejects(bad):
    with pytest.raises(ValueError, match="alpha"):
        finite_scalar(bad, "alpha")


def test_scalar_ranges():
    assert finite_scalar(np.float32(2.5), "x") == 2.5
    assert positive_scalar(1e-300, "x") == 1e-300
    assert nonnegative_scalar(0, "width") == 0.0
    with pytest.raises(ValueError, match=r"width must be >= 0"):
        nonnegative_scalar(-1e-12, "width")
    with pytest.raises(ValueError, match=r"spread must be > 0"):
        positive_scalar(0.0, "spread")
    with pytest.raises(ValueError, match=r"width must lie in the open interval \(0.0, 4.0\)"):
        scalar_in_open_interval(4.0, "width", 0.0, 4.0)
    assert scalar_in_open_interval(3.999, "width", 0.0, 4.0) == 3.999


def test_finite_array_and_integers():
    assert finite_array([[1, 2]], "fields", ndim=2).shape == (1, 2)
    with pytest.raises(ValueError, match="fields"):
        finite_array([1, 2], "fields", ndim=2)
    with pytest.raises(ValueError, match="fields"):
        finite_array([[np.nan, 1.0]], "fields")
    assert positive_integer(4, "n_spins", minimum=2) == 4
    for bad in (1, 2.0, True, "4"):
        with pytest.raises(ValueError, match="n_spins"):
            positive_integer(bad, "n_spins", minimum=2)


def test_direction_and_generator():
    assert direction_sign(1) == 1 and direction_sign(-1) == -1
    for bad in (0, 2, True, 0.5):
        with pytest.raises(ValueError, match="direction"):
            direction_sign(bad)
    g = np.random.default_rng(3)
    assert as_generator(g) is g
    assert as_generator(5).normal() == np.random.default_rng(5).normal()
    for bad in (-1, 1.5, "a", None):
        with pytest.raises(ValueError, match="seed"):
            as_generator(bad)


def test_nonnegative_integer():
    assert nonnegative_integer(0, "transient_periods") == 0
    assert nonnegative_integer(np.int64(7), "transient_periods") == 7
    for bad in (-1, 2.5, 2.0, True, "3", None):
        with pytest.raises(ValueError, match="transient_periods"):
            nonnegative_integer(bad, "transient_periods")
