"""What the compiled fixed-step RK8 engines share: the ``method`` switch to the generic
reference path, the step and damping bounds, and the validation of a start state.

:class:`~oscillators.engines.compiled_continuous.CompiledContinuousEngine` (plays, PI,
Preisach, sums) and :class:`~oscillators.engines.compiled_duhem.CompiledDuhemEngine`
(Bouc–Wen, Jiles–Atherton) integrate with the one RK8 step of
:mod:`oscillators.engines._dop853_kernel` at ``h = step/ρ``; both build the generic
:class:`~oscillators.engines.continuous.ContinuousEngine` instead for ``method="generic"``.
"""

from __future__ import annotations

from typing import Any

from hysteresis._validation import finite_scalar, positive_scalar
from oscillators.engines.base import Engine, TangentFlow, wrap_phase
from oscillators.engines.continuous import ContinuousEngine
from oscillators.results import OscillatorState

__all__ = ["CompiledRK8Engine", "METHODS", "DEFAULT_STEP", "MAX_STEP", "STIFF_DAMPING_LIMIT"]

#: ``method`` values: ``"auto"``/``"compiled"`` the compiled engine, ``"generic"`` the reference
#: path (:class:`~oscillators.engines.continuous.ContinuousEngine`).
METHODS = ("auto", "compiled", "generic")
#: RK8 step (time units) for ρ = 1; the step is ``step/ρ`` with ρ the largest rate of the
#: linearised motion (each engine's module docstring).
DEFAULT_STEP = 0.05
#: the largest ``step`` accepted
MAX_STEP = 0.2
#: largest ζ the compiled RK8 engines integrate: the explicit step is 0.05/(2ζ), so a forcing
#: period costs ~250·ζ steps (measured, a PI operator: 0.05 s at ζ = 100, 0.55 s at 1e3, 4.5 s
#: at 1e4); at the oscillator's limit ζ = 1e6 a period would take minutes, so such a system is
#: refused when it is built (the relay kernels solve any ζ in closed form)
STIFF_DAMPING_LIMIT = 1e4


class CompiledRK8Engine(TangentFlow, Engine):
    """Base of the compiled RK8 engines: :meth:`check_system` (ζ bound), construction
    (``method="generic"`` builds the reference engine) and :meth:`_start` (the checked start
    values). A subclass sets ``name`` and ``kernel_module``."""

    @classmethod
    def check_system(cls, system: Any) -> None:
        """Refuse a damping ratio above :data:`STIFF_DAMPING_LIMIT` (the explicit step would
        make every period cost ~250·ζ RK8 steps)."""
        zeta = float(system.damping_ratio)
        if zeta > STIFF_DAMPING_LIMIT:
            raise ValueError(
                f"damping_ratio must be <= {STIFF_DAMPING_LIMIT:g} for the {cls.name}, got "
                f"{zeta:g}: its explicit RK8 step 0.05/(2ζ) would cost about {250 * zeta:.0e} "
                "steps per forcing period"
            )

    def __new__(cls, system: Any, state: OscillatorState, method: str = "auto", **options: Any):
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}, got {method!r}")
        if method == "generic":
            return ContinuousEngine(system, state, **options)
        return super().__new__(cls)

    def _start(
        self, system: Any, state: OscillatorState, step: float
    ) -> tuple[float, float, float, float, float]:
        """``(step, coupling, q, v, t0)`` checked; sets ``_zeta`` and ``_phi0``."""
        step = positive_scalar(step, "step")
        if step > MAX_STEP:
            raise ValueError(f"step must lie in (0, {MAX_STEP}], got {step}")
        self._zeta = finite_scalar(system.damping_ratio, "damping_ratio")
        coupling = finite_scalar(system.coupling, "coupling")
        q = finite_scalar(state.q, "state.q")
        v = finite_scalar(state.v, "state.v")
        t0 = finite_scalar(state.t, "state.t")
        self._phi0 = wrap_phase(finite_scalar(state.phi, "state.phi"))
        return step, coupling, q, v, t0
