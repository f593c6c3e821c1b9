"""The derived half of the operator contract (hysteresis.base) and the checks at the seam.

A relay-type operator writes three methods (relay_table, relay_outputs,
state_from_relay_outputs); ``initial_state``, ``output``, ``apply`` and ``switching`` are derived
from them in ``PiecewiseConstantHysteron``. A continuous operator writes ``initial_state``,
``apply`` and ``branch_flow``; ``output`` is derived from the branch flow. Each derived method is
checked here against every library operator's own (faster, independently written) version on
random states. Then: what a user-written operator that answers wrongly gets (hysteresis.seam),
one sentence each.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pytest

from hysteresis import (
    ContinuousHysteron,
    GeneralizedPlay,
    PiecewiseConstantHysteron,
    PlayOperator,
    PrandtlIshlinskii,
    PreisachModel,
    Relay,
    RelayTable,
    SpinDimerEnsemble,
)
from hysteresis.base import HysteronState
from hysteresis.flow import BranchFlow, CompiledFlow
from hysteresis.play import CompiledPlay
from oscillators import ForcedOscillator
from oscillators.engines import ContinuousEngine


def _relay_operators():
    rng = np.random.default_rng(3)
    # ties in alpha and beta, zero widths, zero weights: every corner of the switching rule
    alpha = np.round(rng.normal(0.0, 1.0, 40), 1)
    beta = alpha - np.round(rng.uniform(0.0, 1.5, 40), 1)
    weights = rng.uniform(0.0, 1.0, 40)
    weights[::7] = 0.0
    weights /= weights.sum()
    return [
        Relay(1.0, -0.5),
        Relay(0.3, 0.3),
        PreisachModel.from_relays(alpha, beta, weights),
        SpinDimerEnsemble.random(60, width=1.0, spread=1.0, spin_coupling=0.6, seed=2),
    ]


def _continuous_operators():
    return [
        PlayOperator(1.0),
        GeneralizedPlay.erf(2.0, 1.0),
        GeneralizedPlay(1.5, np.tanh, lambda w: 1.0 / np.cosh(w) ** 2),
        PrandtlIshlinskii([0.0, 0.5, 1.5], [0.2, 0.5, 0.3]),
        PreisachModel.from_everett(lambda a, b: ((a - b) / 2.0) ** 2, -1.0, 1.0),
    ]


def _random_histories(n: int = 25, seed: int = 0):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield rng.normal(0.0, 1.5, rng.integers(1, 9))


ids = lambda op: type(op).__name__  # noqa: E731


@pytest.mark.parametrize("op", _relay_operators(), ids=ids)
def test_derived_relay_methods_agree_with_the_operators_own(op):
    """switching, output, apply and initial_state derived from the relay table equal the
    operator's own implementations on random states (thresholds exactly; sums of weights to
    the rounding of a sum of N terms)."""
    base = PiecewiseConstantHysteron
    for history in _random_histories():
        state = op.apply(history)[1]
        own, derived = op.switching(state), base.switching(op, state)
        assert (derived.lower, derived.upper) == (own.lower, own.upper)
        assert derived.jump_up == pytest.approx(own.jump_up, abs=1e-13)
        assert derived.jump_down == pytest.approx(own.jump_down, abs=1e-13)
        assert base.output(op, state) == pytest.approx(op.output(state), abs=1e-13)
        # the derived apply drives every relay from the state: same outputs, same relays
        more = np.random.default_rng(len(history)).normal(0.0, 1.5, 30)
        y_own, s_own = op.apply(more, state)
        y_der, s_der = base.apply(op, more, state)
        np.testing.assert_allclose(y_der, y_own, rtol=0, atol=1e-13)
        # (relays of zero weight never change the output: a Preisach state does not keep them)
        live = op.relay_table().weights > 0
        assert np.array_equal(op.relay_outputs(s_der)[live], op.relay_outputs(s_own)[live])
        u0 = float(history[0])
        assert np.array_equal(
            op.relay_outputs(base.initial_state(op, u0))[live],
            op.relay_outputs(op.initial_state(u0))[live],
        )


@pytest.mark.parametrize("op", _continuous_operators(), ids=ids)
def test_derived_output_agrees_with_the_operators_own(op):
    for history in _random_histories():
        state = op.apply(history)[1]
        assert ContinuousHysteron.output(op, state) == pytest.approx(
            op.output(state), rel=1e-14, abs=1e-15
        )


@pytest.mark.parametrize("op", _relay_operators() + _continuous_operators(), ids=ids)
def test_every_library_state_is_a_hysteron_state(op):
    state = op.apply([0.3, -0.4])[1]
    assert isinstance(state, HysteronState)
    assert state.input == -0.4


# -- a relay-type operator written on the three required methods only ---------------------------
@dataclass(frozen=True)
class BankState:
    outputs: tuple[float, ...]
    input: float


class RelayBank(PiecewiseConstantHysteron[BankState]):
    """Weighted relays, written from scratch on the contract: three methods."""

    def __init__(self, alpha, beta, weights) -> None:
        self._table = RelayTable(alpha, beta, weights)

    def relay_table(self) -> RelayTable:
        return self._table

    def relay_outputs(self, state: BankState) -> np.ndarray:
        return np.array(state.outputs)

    def state_from_relay_outputs(self, outputs, input: float) -> BankState:
        y = self._table.check_outputs(outputs, input)
        return BankState(tuple(float(v) for v in y), float(input))


def test_relay_type_operator_from_three_methods_integrates_like_the_preisach_model():
    """The same relays as a three-method operator and as a discrete Preisach model: the relay
    kernel gives bit-identical trajectories (it runs on the table alone), and the Python
    reference path — which drives the new operator through the derived switching/apply/output
    — agrees with the kernel to the accuracy of the kernel's crossing search."""
    alpha = np.array([1.2, 0.4, 0.4, -0.1, 0.3])
    beta = np.array([-0.6, -1.0, 0.1, -0.9, 0.3])
    weights = np.array([0.3, 0.2, 0.1, 0.25, 0.15])
    bank = RelayBank(alpha, beta, weights)
    model = PreisachModel.from_relays(alpha, beta, weights)
    runs = {}
    for name, op, options in (
        ("bank", bank, None),
        ("model", model, None),
        ("bank generic", bank, {"method": "generic"}),
    ):
        system = ForcedOscillator(op, coupling=1.5, damping_ratio=0.1)
        runs[name] = system.trajectory(40.0, sample_dt=0.5, engine_options=options)
    assert np.array_equal(runs["bank"].q, runs["model"].q)
    assert np.array_equal(runs["bank"].switches, runs["model"].switches)
    assert runs["bank"].switches.size > 20
    np.testing.assert_allclose(runs["bank generic"].q, runs["bank"].q, rtol=0, atol=1e-9)
    assert isinstance(runs["bank"].final.operator_state, BankState)


# -- the seam: one sentence for each wrong answer -----------------------------------------------
class PlainPlay(ContinuousHysteron):
    """A play delegating to PlayOperator, with one answer broken by each test below."""

    def __init__(self, width: float = 1.0) -> None:
        self._play = PlayOperator(width)

    def initial_state(self, u0):
        return self._play.initial_state(u0)

    def apply(self, inputs, state=None):
        return self._play.apply(inputs, state)

    def branch_flow(self, state, direction):
        return self._play.branch_flow(state, direction)


@dataclass(frozen=True)
class NoInput:
    position: float


class _StateWithoutInput(PlainPlay):
    def initial_state(self, u0):
        return NoInput(u0 - 0.5)


class _FlowAsDict(PlainPlay):
    def branch_flow(self, state, direction):
        return {"direction": direction}


class _OutputNone(PlainPlay):
    def branch_flow(self, state, direction):
        flow = self._play.branch_flow(state, direction)
        return BranchFlow(
            direction=flow.direction, input=flow.input, labels=flow.labels, memory=flow.memory,
            slaved=flow.slaved, output=lambda u: None, partials=flow.partials,
            breakpoint=flow.breakpoint, breakpoint_resets=flow.breakpoint_resets,
        )  # fmt: skip


class _PartialsTooShort(PlainPlay):
    def branch_flow(self, state, direction):
        flow = self._play.branch_flow(state, direction)
        return BranchFlow(
            direction=flow.direction, input=flow.input, labels=flow.labels, memory=flow.memory,
            slaved=flow.slaved, output=flow.output, partials=lambda u: (0.0, np.zeros(0)),
            breakpoint=flow.breakpoint, breakpoint_resets=flow.breakpoint_resets,
        )  # fmt: skip


class _ApplyReturnsOutputs(PlainPlay):
    def apply(self, inputs, state=None):
        return self._play.apply(inputs, state)[0]


SEAM_ERRORS = [
    (
        _StateWithoutInput,
        TypeError,
        "the state given as state.operator_state (a NoInput) has no attribute .input; an "
        "operator state must expose the input it last saw as a finite real attribute .input "
        "(hysteresis.base.HysteronState)",
    ),
    (
        _FlowAsDict,
        TypeError,
        "_FlowAsDict.branch_flow(state, +1) returned dict {'direction': 1}; it must return a "
        "hysteresis.flow.BranchFlow",
    ),
    (
        _OutputNone,
        TypeError,
        "_OutputNone.branch_flow(state, +1).output(u) returned NoneType None at the state's "
        "input; it must return the output y(u) as one finite number for a scalar u",
    ),
    (
        _PartialsTooShort,
        TypeError,
        "_PartialsTooShort.branch_flow(state, +1).partials(u) returned tuple (0.0, array([], "
        "dtype=float64)) at the state's input; it must return the pair (dy/du, dy/dm) of a "
        "number and an array of length 1 (one per label)",
    ),
    (
        _ApplyReturnsOutputs,
        TypeError,
        r"_ApplyReturnsOutputs.apply\(inputs, state\) returned ndarray array\(\[[-0-9.e]+\]\); "
        r"it must return the pair \(outputs, final state\)",
    ),
]


@pytest.mark.parametrize("v0", [0.3, 0.0])  # at rest the engine first asks for the output
@pytest.mark.parametrize(("cls", "error", "message"), SEAM_ERRORS, ids=lambda x: str(x)[:30])
def test_a_wrong_answer_at_the_seam_is_one_sentence(cls, error, message, v0):
    system = ForcedOscillator(cls(), coupling=0.5)
    with pytest.raises(error) as info:
        system.trajectory(5.0, q0=0.0, v0=v0)
    if cls is _ApplyReturnsOutputs:  # the input of the first event is in the message
        assert re.fullmatch(message, str(info.value)), str(info.value)
    else:
        assert str(info.value) == message


def test_the_reference_play_passes_the_seam_checks_and_matches_the_library_play():
    """Without a broken answer the delegating play integrates exactly like PlayOperator in the
    generic engine (the checks change nothing)."""
    times = np.linspace(0.0, 8.0, 81)
    out = {}
    for name, op in (("mine", PlainPlay()), ("theirs", PlayOperator(1.0))):
        system = ForcedOscillator(op, coupling=0.5)
        engine = ContinuousEngine(system, system.initial_state(0.0, 0.3))
        out[name] = np.empty((times.size, 4))
        engine.advance(times, out[name])
        assert engine.n_events >= 4
    assert np.array_equal(out["mine"], out["theirs"])


class _RelayTableAsList(RelayBank):
    def relay_table(self):
        return [self._table]


class _OutputsTooLong(RelayBank):
    def relay_outputs(self, state):
        return np.append(state.outputs, 1.0)


def test_relay_type_wrong_answers_are_one_sentence():
    args = ([1.0], [-1.0], [1.0])
    with pytest.raises(TypeError) as info:
        ForcedOscillator(_RelayTableAsList(*args), coupling=0.5)
    assert str(info.value) == (
        "_RelayTableAsList.relay_table() returned list [RelayTable(n_relays=1)]; it must return "
        "a hysteresis.relay_table.RelayTable"
    )
    with pytest.raises(ValueError) as info:
        ForcedOscillator(_OutputsTooLong(*args), coupling=0.5).trajectory(1.0)
    assert str(info.value).startswith(
        "_OutputsTooLong.relay_outputs(state) returned ndarray array([-1.,  1.]); it must return "
        "one output +1 or -1 per relay of relay_table() (1), reachable at the state's input"
    )


class _CompiledPlayWithoutState(PlainPlay):
    def compiled_play(self):
        return CompiledPlay(width=1.0, shape="identity")


class _PlaysWithoutState(PlainPlay):
    def compiled_flow(self):
        return CompiledFlow("prandtl_ishlinskii", str, half_widths=[0.5], weights=[1.0])


class _EverettWithoutStaircase(PlainPlay):
    def compiled_flow(self):
        return CompiledFlow("preisach", str, everett=object())


@pytest.mark.parametrize(
    ("cls", "fast_path", "call", "memory"),
    [
        (_CompiledPlayWithoutState, "compiled_play()", "state(position, input)", "the wagon"),
        (_PlaysWithoutState, "compiled_flow()", "state(positions, input)", "the wagons"),
        (
            _EverettWithoutStaircase,
            "compiled_flow()",
            "state_from_extrema(extrema)",
            "the staircase of remembered extrema",
        ),
    ],
)
def test_a_fast_path_without_its_state_constructor_is_refused_when_the_system_is_built(
    cls, fast_path, call, memory
):
    with pytest.raises(TypeError) as info:
        ForcedOscillator(cls(), coupling=0.5)
    assert str(info.value) == (
        f"operator {cls.__name__} has a {fast_path} description but no {call}: an operator "
        f"offering that fast path must also offer {call} returning the state with {memory} at "
        "the given values (the compiled engine builds its states with it)"
    )
