"""Argument checks shared by the identification modules (the message names the argument)."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["finite_number", "positive_number"]


def finite_number(x: Any, name: str) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a finite real number, got {x!r}") from exc
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite real number, got {v}")
    return v


def positive_number(x: Any, name: str) -> float:
    v = finite_number(x, name)
    if v <= 0:
        raise ValueError(f"{name} must be > 0, got {v}")
    return v
