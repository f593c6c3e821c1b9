"""Issue 21: every operator pickles and round-trips, masked arrays are refused, and the
continuous Preisach model's ``apply`` runs in chunks with bounded memory."""

from __future__ import annotations

import inspect
import pickle
import tracemalloc

import numpy as np
import pytest
from duhem_support import relaxing_duhem

import hysteresis
from analysis.experiments.models import build_operator, model_names
from hysteresis import (
    BoucWen,
    Cascade,
    ContinuousPreisachModel,
    GeneralizedPlay,
    InverseOperator,
    JilesAtherton,
    PlayOperator,
    PrandtlIshlinskii,
    PreisachModel,
    RandomFieldIsing,
    Relay,
    SpinDimerEnsemble,
    StaticMap,
    WeightedSum,
)
from hysteresis._validation import finite_array, finite_scalar, real_array
from hysteresis.base import Hysteron
from hysteresis.preisach import continuous
from hysteresis.relay_table import RelayTable

U = np.sin(np.linspace(0.0, 40.0, 1500)) * np.linspace(0.3, 7.0, 1500)
PROTOCOLS = sorted({4, pickle.DEFAULT_PROTOCOL, pickle.HIGHEST_PROTOCOL})


# module-level callables: picklable, unlike lambdas (a custom shape or density must be)
def _tanh_derivative(w):
    return 1.0 / np.cosh(w) ** 2


def _triangle_density(a, b):
    return np.where(b <= a, 0.125, 0.0)  # mass 1 on -2 <= b <= a <= 2


def _quadratic_everett(a, b):
    return ((a - b) / 2.0) ** 2


def _operators() -> dict[str, Hysteron]:
    return {
        "relay": Relay(1.0, -0.5),
        "play": PlayOperator(1.5),
        "gp-erf": GeneralizedPlay.erf(2.0, 1.0),
        "gp-custom": GeneralizedPlay(1.0, np.tanh, _tanh_derivative, name="tanh"),
        "pi": PrandtlIshlinskii([0.0, 1.0, 2.0], [1.0, 0.5, 0.25]),
        "discrete": PreisachModel.from_relays([1.0, 2.0, 0.5], [0.0, -1.0, 0.5]),
        "density": PreisachModel.from_density(_triangle_density, -2.0, 2.0, 32),
        "everett": PreisachModel.from_everett(_quadratic_everett, -1.0, 1.0),
        "gaussian": ContinuousPreisachModel.gaussian(2.0, 1.0, 0.2),
        "dimers": SpinDimerEnsemble.random(20, 2.0, 1.0, 2.0, seed=0),
        "relay-sum": 0.5 * Relay(1.0, -0.5) + 0.5 * PreisachModel.from_relays([1.0], [0.0]),
        "mixed-sum": 0.6 * GeneralizedPlay.erf(2.0, 1.0) - 0.4 * Relay(1.0, -0.5),
        "static-map": StaticMap(np.tanh, _tanh_derivative),
        "cascade": Cascade(
            PrandtlIshlinskii([0.0, 1.0], [0.5, 0.5]), StaticMap(np.tanh, _tanh_derivative)
        ),
        "inverse": InverseOperator(PrandtlIshlinskii([0.0, 1.0], [0.5, 0.5])),
        "bouc-wen": BoucWen(1.0, 0.5, 0.5, 1.5),
        "jiles-atherton": JilesAtherton(ms=1.0, a=0.5, k=0.4, c=0.2, alpha=0.3),
        "duhem": relaxing_duhem(),
        "rfim": RandomFieldIsing.lattice((4, 4), disorder=1.5, seed=0),
        "switching-sum": RandomFieldIsing.lattice((6,), disorder=1.0, seed=1) + Relay(1.0, 0.0),
    }


def _same_state(a, b) -> bool:
    if isinstance(a, tuple):  # a sum's state: its parts' states
        return type(a) is type(b) and len(a) == len(b) and all(map(_same_state, a, b))
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b, equal_nan=True)
    if hasattr(a, "__dataclass_fields__"):  # a cascade's or an inverse's state holds states
        return type(a) is type(b) and all(
            _same_state(getattr(a, f), getattr(b, f)) for f in a.__dataclass_fields__
        )
    return a == b


def _check_round_trip(op: Hysteron) -> None:
    y, final = op.apply(U)
    for protocol in PROTOCOLS:
        copy = pickle.loads(pickle.dumps(op, protocol=protocol))
        assert type(copy) is type(op)
        assert repr(copy) == repr(op)
        y2, final2 = copy.apply(U)
        assert np.array_equal(y, y2)  # bit for bit
        assert _same_state(final, final2)
        # the original's state is accepted by the copy (same ownership fingerprint)
        assert getattr(copy, "_fingerprint", None) == getattr(op, "_fingerprint", None)
        more = U[::-1][:200]
        assert np.array_equal(op.apply(more, final)[0], copy.apply(more, final)[0])
        # a pickled state too (its arrays read-only again)
        state = pickle.loads(pickle.dumps(final, protocol=protocol))
        assert _same_state(final, state)
        assert np.array_equal(op.apply(more, final)[0], copy.apply(more, state)[0])
        for part in state if isinstance(state, tuple) else (state,):  # a sum: its parts
            for value in vars(part).values():
                assert not (isinstance(value, np.ndarray) and value.flags.writeable)
        # read-only parameter arrays stay read-only (protocol 4 drops the flag)
        for name, value in vars(op).items():
            if isinstance(value, np.ndarray) and not value.flags.writeable:
                assert not getattr(copy, name).flags.writeable, name


@pytest.mark.parametrize("name", model_names())
def test_every_registry_model_pickles_and_round_trips(name):
    _check_round_trip(build_operator(name, spins=20, resolution=32))


@pytest.mark.parametrize("key", list(_operators()))
def test_every_operator_class_pickles_and_round_trips(key):
    _check_round_trip(_operators()[key])


def test_the_cases_cover_every_exported_operator_class():
    exported = {
        c
        for c in (getattr(hysteresis, n) for n in hysteresis.__all__)
        if inspect.isclass(c) and issubclass(c, Hysteron) and not inspect.isabstract(c)
    }
    covered = {type(op) for op in _operators().values()}
    assert exported <= covered | {PreisachModel, WeightedSum}, exported - covered


def test_relay_table_and_erf_shape_pickle():
    table = RelayTable([1.0, 2.0], [0.0, -1.0], [0.5, 0.5])
    table.nested_plan()
    copy = pickle.loads(pickle.dumps(table, protocol=4))
    for attr in ("alpha", "beta", "weights"):
        assert np.array_equal(getattr(copy, attr), getattr(table, attr))
        assert not getattr(copy, attr).flags.writeable
    gp = GeneralizedPlay.erf(2.0, 0.7)
    w = np.linspace(-3.0, 3.0, 13)
    for fn in (gp.shape, gp.shape_derivative):
        assert np.array_equal(pickle.loads(pickle.dumps(fn))(w), fn(w))


# -- masked arrays ------------------------------------------------------------------------------
MASKED = np.ma.masked_array([0.0, 5.0, 1.0], mask=[False, True, False])


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: Relay(1.0, 0.0).apply(MASKED), "inputs"),
        (lambda: PlayOperator(1.0).apply(MASKED), "inputs"),
        (lambda: build_operator("preisach-gauss").apply(MASKED), "inputs"),
        (lambda: PreisachModel.from_relays(MASKED, [0.0, 0.0, 0.0]), "alpha"),
        (lambda: PrandtlIshlinskii([0.0, 1.0, 2.0], MASKED), "weights"),
        (lambda: Relay(np.ma.masked_array(1.0, mask=False), 0.0), "alpha"),
        (lambda: finite_array(MASKED, "x"), "x"),
        (lambda: finite_scalar(np.ma.masked, "x"), "x"),
        (lambda: real_array(np.ma.masked_array([1.0]), "x"), "x"),
    ],
)
def test_masked_arrays_are_refused_naming_the_parameter(call, name):
    with pytest.raises(TypeError, match=rf"^{name} must not be a masked array") as info:
        call()
    assert "\n" not in str(info.value)


# -- chunked apply ------------------------------------------------------------------------------
@pytest.mark.parametrize("key", ["gaussian", "density", "everett"])
def test_chunked_apply_equals_one_pass_bit_for_bit(key, monkeypatch):
    op = _operators()[key]
    u = np.concatenate([U, 0.5 * U[::-1], U[:333]])
    start = op.apply(U[:50])[1]
    whole = [op.apply(u), op.apply(u, start)]
    monkeypatch.setattr(continuous, "_APPLY_CHUNK", 64)
    assert u.size > 10 * continuous._APPLY_CHUNK
    for (y, final), (yc, finalc) in zip(whole, [op.apply(u), op.apply(u, start)], strict=True):
        assert np.array_equal(y, yc)
        assert _same_state(final, finalc)
        assert np.array_equal(final.prefix, finalc.prefix)


def test_continuous_apply_memory_is_bounded_by_the_chunk(monkeypatch):
    chunk = 1024
    monkeypatch.setattr(continuous, "_APPLY_CHUNK", chunk)
    op = build_operator("preisach-gauss")
    nodes = op._gaussian_arguments[-1]
    n = 200_000
    u = 5.0 * np.sin(np.linspace(0.0, 300.0, n))
    op.apply(u[:10])  # compile the kernels outside the measurement
    tracemalloc.start()
    try:
        op.apply(u)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # the input copy and the outputs are O(n) floats; everything else is per chunk (the
    # unchunked quadrature needed n x nodes floats per temporary: ~400 MB here)
    bound = 3 * 8 * n + 16 * 8 * chunk * nodes
    assert peak < bound, (peak, bound)
