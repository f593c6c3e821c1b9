"""The engines integrating the forced oscillator (the seam: :mod:`oscillators.engines.base`).

* :mod:`~oscillators.engines.base` — :class:`Engine` (the motion: clock, time checks,
  divergence test), :class:`TangentFlow` (the tangent bookkeeping an engine adds),
  :class:`DivergenceError`, :class:`GrazingError`,
  :class:`SlidingError`, :class:`SwitchBudgetError` (the switch budget),
  :class:`StepBudgetError` (the step budget);
* :mod:`~oscillators.engines.relay` — :class:`RelayEngine`: :class:`RelayKernelEngine`
  (compiled, nested or heap plan) and :class:`RelayReferenceEngine` (Python reference path);
* :mod:`~oscillators.engines.switching` — :class:`SwitchingKernelEngine` (interacting spins:
  a random-field Ising lattice, ``compiled_switching()``; the relay kernel's hops);
* :mod:`~oscillators.engines.play` — :class:`PlayEngine` (compiled play limit);
* :mod:`~oscillators.engines.continuous` — :class:`ContinuousEngine` (solve_ivp over
  ``branch_flow``);
* :mod:`~oscillators.engines.compiled_continuous` — :class:`CompiledContinuousEngine`
  (compiled RK8 for Prandtl–Ishlinskii and continuous Preisach, ``compiled_flow()``);
* :mod:`~oscillators.engines.compiled_duhem` — :class:`CompiledDuhemEngine` (compiled RK8
  of ``(q, v, z)`` for Bouc–Wen and Jiles–Atherton, a ``"duhem"`` ``compiled_flow()``);
* :mod:`~oscillators.engines.select` — :func:`select_engine` (from the operator's contract).

Compiled kernels: ``_relay_kernels.py``, ``_switching_kernels.py``, ``_play_kernels.py``,
``_continuous_kernels.py`` (with ``_continuous_layout.py``, ``_relay_landings.py``,
``_frozen_hops.py``), ``_duhem_engine_kernels.py``, ``_dop853_kernel.py``.
"""

from oscillators.engines.base import (
    TIME_TOLERANCE,
    DivergenceError,
    Engine,
    GrazingError,
    SlidingError,
    StepBudgetError,
    SwitchBudgetError,
    TangentFlow,
    require_tangent_flow,
    split_times,
    wrap_phase,
)
from oscillators.engines.compiled_continuous import CompiledContinuousEngine
from oscillators.engines.compiled_duhem import CompiledDuhemEngine
from oscillators.engines.continuous import ContinuousEngine
from oscillators.engines.play import PlayEngine
from oscillators.engines.relay import RelayEngine, RelayKernelEngine, RelayReferenceEngine
from oscillators.engines.select import (
    GenericEngineWarning,
    describe_engine,
    python_path_reason,
    select_engine,
)
from oscillators.engines.switching import SwitchingKernelEngine

__all__ = [
    "TIME_TOLERANCE",
    "CompiledContinuousEngine",
    "CompiledDuhemEngine",
    "ContinuousEngine",
    "DivergenceError",
    "Engine",
    "GrazingError",
    "PlayEngine",
    "RelayEngine",
    "RelayKernelEngine",
    "RelayReferenceEngine",
    "SlidingError",
    "StepBudgetError",
    "SwitchBudgetError",
    "SwitchingKernelEngine",
    "TangentFlow",
    "require_tangent_flow",
    "select_engine",
    "GenericEngineWarning",
    "python_path_reason",
    "describe_engine",
    "split_times",
    "wrap_phase",
]
