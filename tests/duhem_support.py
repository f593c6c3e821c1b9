"""A Duhem operator of module-level functions (picklable), shared by the contract and pickling
tests: ``dz/du = 1 − d·z``, so ``z`` relaxes toward +1 while the input rises and toward −1
while it falls."""

from __future__ import annotations

from hysteresis import Duhem


def _rise(u, z):
    return 1.0 - z


def _fall(u, z):
    return 1.0 + z


def _rise_partials(u, z):
    return 0.0, -1.0


def _fall_partials(u, z):
    return 0.0, 1.0


def relaxing_duhem() -> Duhem:
    """The operator described in the module docstring."""
    return Duhem(_rise, _fall, rising_partials=_rise_partials, falling_partials=_fall_partials)
