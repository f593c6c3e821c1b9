"""Which engine integrates an operator, read from its contract (:mod:`hysteresis.base`)."""

from __future__ import annotations

from typing import Any

from hysteresis.base import ContinuousHysteron
from oscillators.engines.base import Engine
from oscillators.engines.compiled_continuous import CompiledContinuousEngine
from oscillators.engines.continuous import ContinuousEngine
from oscillators.engines.play import PlayEngine
from oscillators.engines.relay import RelayEngine

__all__ = ["select_engine"]


def select_engine(operator: Any) -> type[Engine]:
    """The engine class for ``operator``, chosen from what its contract hands over.

    ``operator.piecewise_constant`` -> :class:`RelayEngine` (the compiled kernels, or the Python
    reference path for ``method="generic"``); ``operator.compiled_play()`` not ``None`` ->
    :class:`PlayEngine`; else ``operator.compiled_flow()`` not ``None`` ->
    :class:`CompiledContinuousEngine` (``method="generic"``: the generic engine); any other
    (continuous) operator -> :class:`ContinuousEngine` over its ``branch_flow``.
    """
    if operator.piecewise_constant:
        return RelayEngine
    if not isinstance(operator, ContinuousHysteron):
        raise TypeError(
            f"operator {type(operator).__name__} cannot be coupled to the oscillator: it is "
            "neither a PiecewiseConstantHysteron nor a ContinuousHysteron (see hysteresis.base)"
        )
    if operator.compiled_play() is not None:
        return PlayEngine
    if operator.compiled_flow() is not None:
        return CompiledContinuousEngine
    return ContinuousEngine
