"""The first use of a compiled engine warns while numba compiles its kernels (once)."""

from __future__ import annotations

import warnings

import pytest

from hysteresis import PrandtlIshlinskii, Relay
from oscillators import ForcedOscillator, OscillatorState
from oscillators.engines import _compilation


def test_first_engine_without_a_cache_warns_once(monkeypatch):
    monkeypatch.setattr(_compilation, "_checked", set())
    monkeypatch.setattr(_compilation, "has_cache", lambda name: False)
    system = ForcedOscillator(Relay(1.0, -1.0), coupling=1.0)
    start = OscillatorState(q=0.0, v=0.0, phi=0.0, operator_state=None)
    with pytest.warns(_compilation.CompilationNotice, match="relay kernel.*compiles"):
        system.engine(start)
    with warnings.catch_warnings():
        warnings.simplefilter("error", _compilation.CompilationNotice)
        system.engine(start)  # the same kernels: said once per process
        # a Python engine compiles nothing
        pi = PrandtlIshlinskii([0.0, 1.0], [0.2, 0.2])
        ForcedOscillator(pi, coupling=0.5).engine(start, method="generic")


def test_a_cached_kernel_module_is_found(monkeypatch):
    # the kernels of this test session were compiled (and cached) by the engines above
    from oscillators.engines import _relay_kernels  # noqa: F401

    ForcedOscillator(Relay(1.0, -1.0), coupling=1.0).trajectory(1.0)
    assert _compilation.has_cache("oscillators.engines._relay_kernels")
    assert _compilation.has_cache("not.a.loaded.module")  # nothing to say about it
