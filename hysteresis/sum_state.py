"""The state of a sum of operators (:mod:`hysteresis.algebra`): the tuple of its parts' states."""

from __future__ import annotations

from typing import Any

__all__ = ["SumState"]


class SumState(tuple):
    """The state of a sum: the tuple of its parts' states (immutable, like the parts' states).

    ``input`` is the input the sum last saw (every part saw the same one).
    """

    __slots__ = ()

    def __new__(cls, parts: Any) -> SumState:
        return super().__new__(cls, tuple(parts))

    def __reduce__(self) -> tuple:
        return (SumState, (tuple(self),))

    @property
    def input(self) -> float:
        """The input the sum last saw (its first part's)."""
        return self[0].input

    def __repr__(self) -> str:
        return f"SumState({', '.join(repr(s) for s in self)})"
