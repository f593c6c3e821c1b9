"""Which engine integrates an operator, read from its contract (:mod:`hysteresis.base`)."""

from __future__ import annotations

import warnings
from typing import Any

from hysteresis.base import ContinuousHysteron
from oscillators.engines.base import Engine
from oscillators.engines.compiled_continuous import CompiledContinuousEngine
from oscillators.engines.compiled_duhem import CompiledDuhemEngine
from oscillators.engines.continuous import ContinuousEngine
from oscillators.engines.play import PlayEngine
from oscillators.engines.relay import RelayEngine
from oscillators.engines.switching import SwitchingKernelEngine

__all__ = ["select_engine", "GenericEngineWarning", "python_path_reason", "describe_engine"]


class GenericEngineWarning(UserWarning):
    """A composite operator runs on the generic (Python, ``solve_ivp``) continuous engine
    because a part has no compiled description; the message names the parts."""


def python_path_reason(operator: Any) -> str | None:
    """Why the generic engine integrates ``operator`` although it is built from parts
    (the optional contract member ``uncompiled_reason``), or ``None``."""
    reason = getattr(operator, "uncompiled_reason", None)
    return str(reason) if reason else None


def describe_engine(name: str, operator: Any) -> str:
    """An engine's ``name``, and why a composite ``operator`` runs on the Python path where it
    does (``"continuous engine (Python path: ...)"``)."""
    reason = python_path_reason(operator)
    return name if reason is None else f"{name} (Python path: {reason})"


def select_engine(operator: Any) -> type[Engine]:
    """The engine class for ``operator``, chosen from what its contract hands over.

    ``operator.piecewise_constant`` -> :class:`RelayEngine` (the compiled kernels, or the Python
    reference path for ``method="generic"``), or for interacting spins without a relay table
    (``compiled_switching()`` not ``None``) :class:`SwitchingKernelEngine` (the same hops, the
    spins' sorted lists; ``method="generic"``: the reference path);
    ``operator.compiled_play()`` not ``None`` -> :class:`PlayEngine`; else
    ``operator.compiled_flow()`` not ``None`` -> :class:`CompiledContinuousEngine`, of kind
    ``"duhem"`` (Bouc–Wen, Jiles–Atherton: the state constructor ``make_state`` comes with the
    description) -> :class:`CompiledDuhemEngine` (``method="generic"``: the generic engine);
    any other (continuous) operator -> :class:`ContinuousEngine` over its ``branch_flow`` — with a
    one-line :class:`GenericEngineWarning` when the operator says why it has no compiled
    description (``uncompiled_reason``: a composite whose parts the compiled engines cannot
    take together). A fast path
    comes with the state constructor its engine needs (``state(position, input)`` for a compiled
    play, ``state(positions, input)`` for Prandtl–Ishlinskii plays, ``state_from_extrema``
    for a Preisach model's Everett function): checked here, so that a missing one is refused
    when the system is built.
    """
    if operator.piecewise_constant:
        if not operator.has_relay_table and operator.compiled_switching() is not None:
            return SwitchingKernelEngine
        return RelayEngine
    if not isinstance(operator, ContinuousHysteron):
        raise TypeError(
            f"operator {type(operator).__name__} cannot be coupled to the oscillator: it is "
            "neither a PiecewiseConstantHysteron nor a ContinuousHysteron (see hysteresis.base)"
        )
    if operator.compiled_play() is not None:
        _require(operator, "state", "compiled_play()", "state(position, input)", "the wagon")
        return PlayEngine
    spec = operator.compiled_flow()
    if spec is not None and spec.kind == "duhem":
        return CompiledDuhemEngine
    if spec is not None:
        if spec.kind == "preisach":
            _require(
                operator, "state_from_extrema", "compiled_flow()", "state_from_extrema(extrema)",
                "the staircase of remembered extrema",
            )  # fmt: skip
        elif spec.make_state is None:  # a composite hands over its own state constructor
            _require(operator, "state", "compiled_flow()", "state(positions, input)", "the wagons")
        return CompiledContinuousEngine
    reason = python_path_reason(operator)
    if reason is not None:
        # never a silent fallback: a composite of compiled parts would be expected to run at
        # kernel speed
        warnings.warn(
            f"{reason}: the generic continuous engine integrates it in Python (solve_ivp)",
            GenericEngineWarning,
            stacklevel=3,
        )
    return ContinuousEngine


def _require(operator: Any, method: str, fast_path: str, call: str, memory: str) -> None:
    """The state constructor a compiled engine builds its states with (the contract requires it
    of an operator whose fast path is not ``None``), or one sentence saying what is missing."""
    if not callable(getattr(operator, method, None)):
        raise TypeError(
            f"operator {type(operator).__name__} has a {fast_path} description but no {call}: "
            f"an operator offering that fast path must also offer {call} returning the state "
            f"with {memory} at the given values (the compiled engine builds its states with it)"
        )
