"""What a sum of operators hands the oscillator beyond its outputs: the parts' driven variables,
pushed gradients and moving breakpoint composed into the sum's branch flow, and the compiled
description of a sum of plays and relays (:class:`hysteresis.algebra.BranchSum` delegates to
these functions).

A sum of plays (identity or erf shape), Prandtl–Ishlinskii operators and relay-type operators is
one set of plays ``y = Σ a_i f_i(w_i)`` plus relays ``Σ c_j y_j`` with the parts' weights folded
into ``a_i`` and ``c_j``: one :class:`~hysteresis.flow.CompiledFlow` of kind
``"prandtl_ishlinskii"`` for the compiled continuous engine, whose states are read and built
through the parts' own constructors.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hysteresis.flow import BranchFlow, CompiledFlow
from hysteresis.seam import checked_relay_outputs, checked_relay_table
from hysteresis.sum_state import SumState

__all__ = ["compiled_sum_flow", "composed_fields", "play_parts"]


def play_parts(total: Any) -> list[tuple[int, Any]] | None:
    """Per part, its plays as the compiled engine takes them (a relay-type part: ``None``),
    or ``None`` if a part is neither relays, a play (identity or erf shape) nor a
    Prandtl–Ishlinskii operator."""
    found: list[tuple[int, Any]] = []
    for k, p in enumerate(total.parts):
        if p.piecewise_constant:
            if not p.has_relay_table:  # interacting units: no relays for the kernel
                return None
            found.append((k, None))
            continue
        cp = p.compiled_play()
        if cp is not None and cp.shape in ("identity", "erf"):
            found.append((k, cp))
            continue
        cf = p.compiled_flow()
        if cf is not None and cf.kind == "prandtl_ishlinskii" and cf.positions is None:
            found.append((k, cf))
            continue
        return None
    return found


def compiled_sum_flow(total: Any) -> CompiledFlow | None:
    """A sum of plays (identity or erf shape), Prandtl–Ishlinskii operators and relay-type
    operators is one set of plays ``y = Σ a_i f_i(w_i)`` plus relays ``Σ c_j y_j``, with the
    part's weight folded into each ``a_i`` and ``c_j``: the oscillator's compiled
    continuous engine integrates it (relays switch at their thresholds with the saltation
    of the jump). Its states are read and built through the parts' own constructors
    (``state(position, input)``, ``state(positions, input)``,
    ``state_from_relay_outputs``); memory labels ``"k:w"``, ``"k:w{j}"`` as in
    :meth:`BranchSum.branch_flow <hysteresis.algebra.BranchSum.branch_flow>`. ``None`` for
    any other sum."""
    found = play_parts(total)
    if found is None:
        return None
    relays = [(k, checked_relay_table(total.parts[k])) for k, spec in found if spec is None]
    found = [(k, spec) for k, spec in found if spec is not None]
    half, weights, spreads, labels, sizes = [], [], [], [], []
    for k, spec in found:
        w = float(total.weights[k])
        if isinstance(spec, CompiledFlow):
            n = spec.half_widths.size
            half.extend(spec.half_widths)
            weights.extend(w * spec.weights)
            spreads.extend(spec.spreads)
            labels.extend(f"{k}:{spec.label(j)}" for j in range(n))
        else:
            n = 1
            half.append(0.5 * spec.width)
            weights.append(w)
            spreads.append(spec.spread if spec.shape == "erf" else 0.0)
            labels.append(f"{k}:w")
        sizes.append(n)
    bounds = np.cumsum([0, *sizes])
    kinds = [isinstance(spec, CompiledFlow) for _, spec in found]
    parts = total.parts

    def positions(state: SumState) -> np.ndarray:
        state = total._check_state(state)
        return np.concatenate(
            [
                np.asarray(state[k].positions if pi else [state[k].position], dtype=float)
                for (k, _), pi in zip(found, kinds, strict=True)
            ]
            or [np.zeros(0)]  # relays only (a negative weight kept them out of a RelaySum)
        )

    r_sizes = [t.n_relays for _, t in relays]
    r_bounds = np.cumsum([0, *r_sizes])

    def relay_outputs(state: SumState) -> np.ndarray:
        state = total._check_state(state)
        return np.concatenate(
            [checked_relay_outputs(parts[k], t, state[k]) for k, t in relays] or [[]]
        )

    def make_state(pos: np.ndarray, input: float, y: np.ndarray | None = None) -> SumState:
        out: list[Any] = [None] * len(parts)
        for i, ((k, _), pi) in enumerate(zip(found, kinds, strict=True)):
            chunk = pos[bounds[i] : bounds[i + 1]]
            out[k] = parts[k].state(chunk if pi else float(chunk[0]), input)
        for i, (k, _) in enumerate(relays):
            out[k] = parts[k].state_from_relay_outputs(y[r_bounds[i] : r_bounds[i + 1]], input)
        return SumState(out)

    relay_fields: dict[str, Any] = {}
    if relays:
        relay_fields = {
            "relay_alpha": np.concatenate([t.alpha for _, t in relays]),
            "relay_beta": np.concatenate([t.beta for _, t in relays]),
            "relay_weights": np.concatenate(
                [float(total.weights[k]) * t.weights for k, t in relays]
            ),
            "relay_outputs": relay_outputs,
        }
    return CompiledFlow(
        kind="prandtl_ishlinskii",
        label=labels.__getitem__,
        half_widths=np.array(half),
        weights=np.array(weights),
        spreads=np.array(spreads),
        positions=positions,
        make_state=make_state,
        **relay_fields,
    )


def composed_fields(
    flows: list[BranchFlow], indices: list[int], bounds: np.ndarray, gradient_of: int
) -> dict[str, Any]:
    """The parts' driven variables, pushed gradients and moving breakpoint of a sum's branch
    (:mod:`hysteresis.flow`), each part's columns in its block ``bounds[k]:bounds[k+1]`` of the
    sum's memory, labels prefixed ``"i:"`` with the part's index ``i`` in the sum."""
    n = int(bounds[-1])
    out: dict[str, Any] = {}
    if gradient_of >= 0:
        grad = np.zeros(n)
        k = gradient_of
        grad[bounds[k] : bounds[k + 1]] = flows[k].breakpoint_gradient
        out["breakpoint_gradient"] = grad
    driving = [k for k, f in enumerate(flows) if f.driven_labels]
    if driving:
        out["driven_labels"] = tuple(
            f"{indices[k]}:{lab}" for k in driving for lab in flows[k].driven_labels
        )

        def driven(u):
            values, d_u, d_m = [], [], []
            for k in driving:
                v, du, dm = flows[k].driven(u)
                block = np.zeros((len(flows[k].driven_labels), n))
                block[:, bounds[k] : bounds[k + 1]] = dm
                values.append(np.atleast_1d(v))
                d_u.append(np.atleast_1d(du))
                d_m.append(block)
            return np.concatenate(values), np.concatenate(d_u), np.vstack(d_m)

        out["driven"] = driven
    if any(f.pushed_gradient is not None for f in flows):

        def pushed_gradient(u0):
            d_u, d_m = [], []
            for k, f in enumerate(flows):
                n_p = int(np.count_nonzero(f.pushed))
                if n_p == 0:
                    continue
                block = np.zeros((n_p, n))
                if f.pushed_gradient is None:  # δm_p := δu
                    du = np.ones(n_p)
                else:
                    du, dm = f.pushed_gradient(u0)
                    block[:, bounds[k] : bounds[k + 1]] = dm
                d_u.append(np.atleast_1d(du))
                d_m.append(block)
            if not d_u:
                return np.zeros(0), np.zeros((0, n))
            return np.concatenate(d_u), np.vstack(d_m)

        out["pushed_gradient"] = pushed_gradient
    return out
