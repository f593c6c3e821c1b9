"""The operator contract (hysteresis.base): required methods are abstract, and every library
operator satisfies the contract of its family (what the oscillator's engines use)."""

from __future__ import annotations

import inspect

import numpy as np
import pytest
from duhem_support import relaxing_duhem

import hysteresis
from hysteresis import (
    BoucWen,
    Cascade,
    ContinuousHysteron,
    GeneralizedPlay,
    Hysteron,
    InverseOperator,
    JilesAtherton,
    PiecewiseConstantHysteron,
    PlayOperator,
    PrandtlIshlinskii,
    PreisachModel,
    Relay,
    RelayTable,
    SpinDimerEnsemble,
    StaticMap,
    Switching,
    WeightedSum,
)
from hysteresis.algebra import SwitchingSum
from hysteresis.base import Branch, Linearization, SwitchingHysteron
from hysteresis.flow import BranchFlow
from hysteresis.rfim import RandomFieldIsing
from oscillators import ForcedOscillator
from oscillators.engines.relay import RelayReferenceEngine

#: what a new operator of each family must write (everything else is derived or optional)
PC_REQUIRED = ("relay_table", "relay_outputs", "state_from_relay_outputs")
CONTINUOUS_REQUIRED = ("initial_state", "apply", "branch_flow")
SWITCHING_REQUIRED = ("initial_state", "apply", "output", "switching", "n_units")
#: the sentence part naming what each returns
RETURNS = {
    "relay_table": "relay_table() returning a hysteresis.relay_table.RelayTable",
    "relay_outputs": "relay_outputs(state) returning an array of the relays' outputs",
    "state_from_relay_outputs": "state_from_relay_outputs(outputs, input) returning the state",
    "initial_state": "initial_state(u0) returning the state reached by rising",
    "apply": "apply(inputs, state) returning the pair (outputs, final state)",
    "branch_flow": "branch_flow(state, direction) returning a hysteresis.flow.BranchFlow",
    "output": "output(state) returning the output in that state",
    "switching": "switching(state) returning a hysteresis.base.Switching",
    "n_units": "the property n_units returning the number of switching units",
}


def _method(name):
    if name == "n_units":
        return property(lambda self: 1)
    params = {
        "relay_table": "self",
        "relay_outputs": "self, state",
        "state_from_relay_outputs": "self, outputs, input",
        "initial_state": "self, u0",
        "apply": "self, inputs, state=None",
        "branch_flow": "self, state, direction",
        "output": "self, state",
        "switching": "self, state",
    }[name]
    namespace: dict = {}
    exec(f"def {name}({params}):\n    return None", namespace)
    return namespace[name]


def _subclass(family, required, missing):
    """A subclass of ``family`` implementing every required method but ``missing``."""
    body = {name: _method(name) for name in required if name != missing}
    return type(f"Without_{missing}", (family,), body)


@pytest.mark.parametrize(
    ("family", "required", "missing"),
    [(PiecewiseConstantHysteron, PC_REQUIRED, m) for m in PC_REQUIRED]
    + [(ContinuousHysteron, CONTINUOUS_REQUIRED, m) for m in CONTINUOUS_REQUIRED]
    + [(SwitchingHysteron, SWITCHING_REQUIRED, m) for m in SWITCHING_REQUIRED],
)
def test_operator_missing_a_method_gets_one_sentence_naming_it(family, required, missing):
    """The error names the class, the method with its arguments and what it must return."""
    cls = _subclass(family, required, missing)
    with pytest.raises(TypeError) as info:
        cls()
    message = str(info.value)
    assert message == (
        f"Can't instantiate abstract class Without_{missing}: it must implement "
        f"{RETURNS[missing]}{message.split(RETURNS[missing])[1]}"
    )
    assert message.endswith("(the operator contract, hysteresis.base)")
    assert message.count(". ") == 0 and "\n" not in message  # one sentence


def test_the_required_methods_are_exactly_the_abstract_ones():
    assert PiecewiseConstantHysteron.__abstractmethods__ == frozenset(PC_REQUIRED)
    assert ContinuousHysteron.__abstractmethods__ == frozenset(CONTINUOUS_REQUIRED)
    assert SwitchingHysteron.__abstractmethods__ == frozenset(SWITCHING_REQUIRED)


def test_complete_operators_construct_and_optional_methods_default():
    _subclass(PiecewiseConstantHysteron, PC_REQUIRED, None)()
    op = _subclass(ContinuousHysteron, CONTINUOUS_REQUIRED, None)()
    assert op.compiled_play() is None
    assert op.compiled_flow() is None
    assert op.max_slope is None


def _piecewise_constant_operators():
    return [
        Relay(1.0, -0.5),
        PreisachModel.from_relays([1.0, 0.5, 0.2, 0.0], [-1.0, 0.0, -0.3, 0.0]),
        SpinDimerEnsemble.random(40, width=2.0, spread=1.0, spin_coupling=2.0, seed=0),
        0.5 * Relay(1.0, -0.5) + 0.5 * Relay(0.2, -0.1),  # a RelaySum
    ]


def _switching_operators():
    """Piecewise-constant operators without a relay table (interacting units)."""
    rfim = RandomFieldIsing.lattice((4, 4, 4), 4.0, seed=0)
    return [rfim, 0.5 * rfim + 0.5 * Relay(0.2, -0.1)]  # a SwitchingSum


def _continuous_operators():
    return [
        PlayOperator(1.0),
        GeneralizedPlay.erf(2.0, 1.0),
        PrandtlIshlinskii([0.0, 0.5, 1.5], [0.2, 0.5, 0.3]),
        PreisachModel.from_everett(lambda a, b: ((a - b) / 2.0) ** 2, -1.0, 1.0),
        0.7 * PlayOperator(1.0) + 0.3 * Relay(0.5, -0.5),  # a BranchSum
        StaticMap(np.tanh, _tanh_slope),
        Cascade(PrandtlIshlinskii([0.0, 1.0], [0.5, 0.5]), StaticMap(np.tanh, _tanh_slope)),
        InverseOperator(PrandtlIshlinskii([0.0, 1.0], [1.0, 0.5])),
        BoucWen(1.0, 0.5, 0.5, 1.5),  # a Duhem operator
        JilesAtherton(ms=1.0, a=0.5, k=0.4, c=0.2, alpha=0.3),
        relaxing_duhem(),
    ]


def _tanh_slope(u):
    return 1.0 / np.cosh(u) ** 2


def test_every_library_operator_belongs_to_one_family_and_is_complete():
    """Every concrete operator class the package exports is in exactly one family, and none is
    abstract (it implements every required method)."""
    exported = [getattr(hysteresis, name) for name in hysteresis.__all__]
    classes = [c for c in exported if inspect.isclass(c) and issubclass(c, Hysteron)]
    families = (
        Hysteron,
        SwitchingHysteron,
        PiecewiseConstantHysteron,
        ContinuousHysteron,
        PreisachModel,
        WeightedSum,
    )
    concrete = [c for c in classes if c not in families]
    for cls in concrete:
        pc = issubclass(cls, SwitchingHysteron)
        assert pc != issubclass(cls, ContinuousHysteron), cls
        assert cls.piecewise_constant is pc
        assert cls.has_relay_table is issubclass(cls, PiecewiseConstantHysteron)
        assert not inspect.isabstract(cls), (cls, cls.__abstractmethods__)
    # and the contract tests below build one of each (the lattice and its sums may not be
    # exported yet)
    built = {
        type(op)
        for op in _piecewise_constant_operators() + _switching_operators() + _continuous_operators()
    }
    assert set(concrete) <= built and built - set(concrete) <= {RandomFieldIsing, SwitchingSum}


@pytest.mark.parametrize("op", _piecewise_constant_operators(), ids=lambda op: type(op).__name__)
def test_piecewise_constant_contract(op):
    state = op.apply([0.3, 2.0, -0.2])[1]
    table = op.relay_table()
    assert isinstance(table, RelayTable)
    y = op.relay_outputs(state)
    assert y.shape == (table.n_relays,)
    assert table.output(y) == pytest.approx(op.output(state), abs=1e-12)
    back = op.state_from_relay_outputs(y, -0.2)
    assert np.array_equal(op.relay_outputs(back), y)
    assert op.output(back) == pytest.approx(op.output(state), abs=1e-12)
    assert isinstance(op.switching(state), Switching)
    ForcedOscillator(op, coupling=0.5)  # the engine probes the contract at construction


@pytest.mark.parametrize("op", _switching_operators(), ids=lambda op: type(op).__name__)
def test_switching_contract(op):
    """No relay table: next switching inputs around the state's input, the jumps the state
    makes there, and the oscillator's Python reference path (the kernels refused by name)."""
    assert op.piecewise_constant and not op.has_relay_table
    state = op.apply([0.3, 2.0, -0.2])[1]
    sw = op.switching(state)
    assert isinstance(sw, Switching) and sw.lower <= -0.2 < sw.upper
    m = op.output(state)
    assert op.apply([sw.upper], state)[0][0] - m == pytest.approx(sw.jump_up, abs=1e-15)
    below = float(np.nextafter(sw.lower, -np.inf))
    assert op.apply([below], state)[0][0] - m == pytest.approx(sw.jump_down, abs=1e-15)
    assert isinstance(op.n_units, int) and op.n_units >= 64
    system = ForcedOscillator(op, coupling=0.5)
    assert isinstance(system.engine(), RelayReferenceEngine)
    with pytest.raises(ValueError, match="has none"):
        system.engine(method="heap")


@pytest.mark.parametrize("op", _continuous_operators(), ids=lambda op: type(op).__name__)
def test_continuous_contract(op):
    state = op.apply([0.3, 0.8, 0.1])[1]
    for direction in (1, -1):
        flow = op.branch_flow(state, direction)
        assert isinstance(flow, BranchFlow)
        assert float(flow.output(flow.input)) == pytest.approx(op.output(state), abs=1e-12)
        branch = op.branch(state, direction)
        assert isinstance(branch, Branch)
        assert branch.slope == float(flow.slope(flow.input))
        assert branch.breakpoint == flow.breakpoint
        lin = op.linearize(state, direction)
        assert isinstance(lin, Linearization)
        assert lin.d_output_d_memory.shape == (flow.n_memory,)
        assert np.array_equal(lin.slaved, flow.slaved)
    spec = op.compiled_play()
    if spec is not None:
        # a compiled play also offers state(position, input): the engine builds states with it
        rebuilt = op.state(float(state.position), float(state.input))
        assert op.output(rebuilt) == op.output(state)
    ForcedOscillator(op, coupling=0.5)
