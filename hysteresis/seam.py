"""The seam between an operator and the oscillator's engines: what an operator hands over,
checked where it is handed over.

The engines (:mod:`oscillators.engines`) know an operator only through its contract
(:mod:`hysteresis.base`). A user-written operator that answers a contract method with the wrong
thing would otherwise fail deep inside an integration with an ``AttributeError`` about some
internal name; these helpers call the method, check the answer once per call (never inside a
compiled loop) and raise one sentence naming the method, what it returned and what it must
return. The library's operators pass them at the cost of a few attribute reads per call.
"""

from __future__ import annotations

import math
from numbers import Real
from typing import Any

import numpy as np

from hysteresis.flow import BranchFlow
from hysteresis.relay_table import RelayTable

__all__ = [
    "check_state",
    "checked_apply",
    "checked_branch_flow",
    "checked_relay_outputs",
    "checked_relay_table",
]


def _describe(value: Any) -> str:
    text = f"{type(value).__name__} {value!r}"
    return text if len(text) <= 80 else text[:77] + "..."


def check_state(state: Any, source: str) -> float:
    """The input of ``state``, or a ``TypeError`` in one sentence if it has no finite real
    ``.input``; ``source`` says where the state came from (``"returned by MyPlay.apply"``)."""
    u = getattr(state, "input", None)
    if isinstance(u, np.generic) and np.ndim(u) == 0:
        u = u.item()
    if isinstance(u, bool) or not isinstance(u, Real) or not math.isfinite(u):
        missing = not hasattr(state, "input")
        has = "has no attribute .input" if missing else f"has .input = {_describe(u)}"
        raise TypeError(
            f"the state {source} (a {type(state).__name__}) {has}; an operator state must "
            "expose the input it last saw as a finite real attribute .input "
            "(hysteresis.base.HysteronState)"
        )
    return float(u)


def checked_apply(operator: Any, inputs: np.ndarray, state: Any) -> tuple[np.ndarray, Any]:
    """``operator.apply(inputs, state)`` with its answer checked: ``(outputs, state)`` with one
    finite output per input and a state with an ``.input`` equal to the last input."""
    name = f"{type(operator).__name__}.apply"
    result = operator.apply(inputs, state)
    if not (isinstance(result, tuple) and len(result) == 2):
        raise TypeError(
            f"{name}(inputs, state) returned {_describe(result)}; it must return the pair "
            "(outputs, final state)"
        )
    outputs, final = result
    y = np.asarray(outputs, dtype=np.float64) if _is_numeric(outputs) else None
    if y is None or y.shape != np.shape(inputs) or not np.all(np.isfinite(y)):
        raise TypeError(
            f"{name}(inputs, state) returned outputs {_describe(outputs)}; they must be one "
            f"finite number per input (shape {np.shape(inputs)})"
        )
    u = check_state(final, f"returned by {name}")
    last = float(inputs[-1])
    if u != last:
        raise ValueError(
            f"{name}(inputs, state) returned a state at input {u!r}; its .input must be the last "
            f"input {last!r}"
        )
    return y, final


def _is_numeric(x: Any) -> bool:
    try:
        return np.asarray(x).dtype.kind in "biuf"
    except (TypeError, ValueError):
        return False


def checked_branch_flow(operator: Any, state: Any, direction: int) -> BranchFlow:
    """``operator.branch_flow(state, direction)`` with its answer checked once (type, direction,
    input, the value and partials at the input): the generic continuous engine calls this once
    per branch, so a wrong answer stops with one sentence instead of an error deep inside the
    integration."""
    name = f"{type(operator).__name__}.branch_flow(state, {direction:+d})"
    flow = operator.branch_flow(state, direction)
    if not isinstance(flow, BranchFlow):
        raise TypeError(
            f"{name} returned {_describe(flow)}; it must return a hysteresis.flow.BranchFlow"
        )
    u = check_state(state, f"given to {type(operator).__name__}.branch_flow")
    if flow.direction != direction or flow.input != u:
        raise ValueError(
            f"{name} returned a BranchFlow with direction {flow.direction:+d} and input "
            f"{flow.input!r}; they must be the requested direction and the state's input {u!r}"
        )
    y = flow.output(u)
    if not _is_numeric(y) or np.ndim(y) != 0 or not math.isfinite(float(y)):
        raise TypeError(
            f"{name}.output(u) returned {_describe(y)} at the state's input; it must return the "
            "output y(u) as one finite number for a scalar u"
        )
    d = flow.partials(u)
    n = flow.n_memory
    ok = isinstance(d, tuple) and len(d) == 2 and _is_numeric(d[0]) and _is_numeric(d[1])
    if not (ok and np.ndim(d[0]) == 0 and np.shape(d[1]) == (n,)):
        raise TypeError(
            f"{name}.partials(u) returned {_describe(d)} at the state's input; it must return "
            f"the pair (dy/du, dy/dm) of a number and an array of length {n} (one per label)"
        )
    return flow


def checked_relay_table(operator: Any) -> RelayTable:
    """``operator.relay_table()``, checked to be a :class:`RelayTable`."""
    table = operator.relay_table()
    if not isinstance(table, RelayTable):
        raise TypeError(
            f"{type(operator).__name__}.relay_table() returned {_describe(table)}; it must "
            "return a hysteresis.relay_table.RelayTable"
        )
    return table


def checked_relay_outputs(operator: Any, table: RelayTable, state: Any) -> np.ndarray:
    """``operator.relay_outputs(state)`` checked once (the relay engines' view of a
    piecewise-constant operator): one output ``±1`` per relay of ``table``, reachable at the
    state's input."""
    cls = type(operator).__name__
    u = check_state(state, f"given to {cls}.relay_outputs")
    y = operator.relay_outputs(state)
    try:
        return table.check_outputs(y, u)
    except ValueError as exc:
        raise ValueError(
            f"{cls}.relay_outputs(state) returned {_describe(y)}; it must return one output +1 "
            f"or -1 per relay of relay_table() ({table.n_relays}), reachable at the state's "
            f"input ({exc})"
        ) from None
