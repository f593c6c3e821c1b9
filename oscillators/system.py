"""The forced oscillator coupled to a hysteresis operator, as a system object.

Paper eq. (eom_2): ``q'' + 2ζ q' + q = cos φ + C·M[q]``, ``φ' = Ω``, state
``x = (q, v = q', φ)`` plus the operator's memory. The object holds the parameters and the
operator; integrators are chosen by operator type:

* piecewise-constant operators (relay, discrete Preisach, spin dimers): exact event-driven
  integration (:mod:`oscillators.piecewise_constant`);
* play-type operators (``PlayOperator``, ``GeneralizedPlay``): the play-limit flow
  (:mod:`oscillators.play_flow`).
"""

from __future__ import annotations

import math
from typing import Any

from hysteresis._validation import finite_scalar
from hysteresis.base import Hysteron
from oscillators import piecewise_constant as pc
from oscillators.results import OscillatorState, PoincareSection, TangentResult, Trajectory

__all__ = ["ForcedOscillator"]


class ForcedOscillator:
    """Driven damped oscillator with hysteretic feedback ``C·M[q]``.

    Parameters
    ----------
    operator:
        Any :class:`~hysteresis.base.Hysteron` (the paper's ``M[q]``).
    coupling:
        C, strength of the hysteresis force (finite, any sign).
    damping_ratio:
        ζ >= 0 (Table II: 0.05); play-type operators need ζ < 1 (the play-limit integrator
        uses the underdamped closed form).
    frequency:
        Ω > 0, excitation frequency (Table II: 1.0). ζ = 0 with Ω = 1 (undamped resonance) is
        rejected.
    """

    def __init__(
        self,
        operator: Hysteron,
        coupling: float,
        damping_ratio: float = 0.05,
        frequency: float = 1.0,
    ) -> None:
        if not isinstance(operator, Hysteron):
            raise ValueError(f"operator must be a Hysteron, got {type(operator).__name__}")
        self._operator = operator
        self._coupling = finite_scalar(coupling, "coupling")
        zeta = finite_scalar(damping_ratio, "damping_ratio")
        if zeta < 0.0:
            raise ValueError(f"damping_ratio must be >= 0, got {damping_ratio}")
        omega = finite_scalar(frequency, "frequency")
        if omega <= 0.0:
            raise ValueError(f"frequency must be > 0, got {frequency}")
        if zeta == 0.0 and omega == 1.0:
            raise ValueError(
                "damping_ratio = 0 with frequency = 1 (undamped resonance) is not supported"
            )
        if zeta >= 1.0 and self.is_play_type:
            # checked here, not first at integration time: the play-limit flow
            # (oscillators.play_flow) uses the underdamped propagator only
            raise ValueError(
                f"damping_ratio must lie in [0, 1) for play-type operators (the play-limit "
                f"integrator supports underdamped motion only), got {zeta}"
            )
        self._zeta = zeta
        self._omega = omega

    # -- parameters --------------------------------------------------------------------------
    @property
    def operator(self) -> Hysteron:
        """The hysteresis operator M."""
        return self._operator

    @property
    def coupling(self) -> float:
        """C."""
        return self._coupling

    @property
    def damping_ratio(self) -> float:
        """ζ."""
        return self._zeta

    @property
    def frequency(self) -> float:
        """Ω."""
        return self._omega

    @property
    def period(self) -> float:
        """Forcing period T = 2π/Ω."""
        return 2.0 * math.pi / self._omega

    def __repr__(self) -> str:
        return (
            f"ForcedOscillator({self._operator!r}, coupling={self._coupling!r}, "
            f"damping_ratio={self._zeta!r}, frequency={self._omega!r})"
        )

    # -- dispatch ----------------------------------------------------------------------------
    @property
    def is_play_type(self) -> bool:
        """True for ``PlayOperator`` / ``GeneralizedPlay`` (memory: the wagon position w)."""
        from hysteresis.play import GeneralizedPlay, PlayOperator

        return isinstance(self._operator, (PlayOperator, GeneralizedPlay))

    def _kind(self) -> str:
        if getattr(self._operator, "piecewise_constant", False):
            return "pc"
        if self.is_play_type:
            return "play"
        return "continuous"

    def _unsupported(self) -> NotImplementedError:
        return NotImplementedError(
            f"{type(self._operator).__name__} is a continuous operator that is not play-type; "
            "the oscillator integrates piecewise-constant operators and PlayOperator/"
            "GeneralizedPlay only"
        )

    def _play_w0(self, q0: float, operator_state: Any, w0: float | None) -> float:
        if operator_state is not None and w0 is not None:
            raise ValueError("give either operator_state or w0, not both")
        if w0 is not None:
            return finite_scalar(w0, "w0")
        if operator_state is not None:
            return float(operator_state.position)
        return float(self._operator.initial_state(q0).position)

    def initial_operator_state(self, q0: float = -1.0, w0: float | None = None) -> Any:
        """Operator state at t = 0: ``initial_state(q0)``, or the play at wagon position w0."""
        if w0 is not None:
            if not self.is_play_type:
                raise ValueError("w0 is only meaningful for play-type operators")
            return self._operator.state(finite_scalar(w0, "w0"), finite_scalar(q0, "q0"))
        return self._operator.initial_state(finite_scalar(q0, "q0"))

    # -- integration ------------------------------------------------------------------------
    def trajectory(
        self,
        t_end: float,
        q0: float = -1.0,
        v0: float = 0.1,
        operator_state: Any = None,
        sample_dt: float = 0.01,
        phi0: float = 0.0,
        *,
        w0: float | None = None,
    ) -> Trajectory:
        """Samples every ``sample_dt`` on [0, t_end] and the exact switches / wall events.

        ``operator_state=None`` means ``operator.initial_state(q0)`` (play: ``w0 = q0 − p/2``
        unless ``w0`` is given).
        """
        phi0 = finite_scalar(phi0, "phi0")
        kind = self._kind()
        if kind == "pc":
            if w0 is not None:
                raise ValueError("w0 is only meaningful for play-type operators")
            return pc.pc_trajectory(self, t_end, q0, v0, operator_state, sample_dt, phi0)
        if kind == "play":
            from oscillators.play_flow import play_trajectory

            w = self._play_w0(q0, operator_state, w0)
            return play_trajectory(self, t_end, q0, v0, w, sample_dt, phi0)
        raise self._unsupported()

    def poincare_section(
        self,
        n_periods: int,
        transient_periods: int = 0,
        q0: float = -1.0,
        v0: float = 0.1,
        operator_state: Any = None,
        *,
        w0: float | None = None,
    ) -> PoincareSection:
        """Stroboscopic section at φ = 0 mod 2π: points at t = (transient_periods + i)·T.

        Without transient the first point is the initial state.
        """
        kind = self._kind()
        if kind == "pc":
            if w0 is not None:
                raise ValueError("w0 is only meaningful for play-type operators")
            return pc.pc_poincare(self, n_periods, transient_periods, q0, v0, operator_state)
        if kind == "play":
            from oscillators.play_flow import play_poincare

            w = self._play_w0(q0, operator_state, w0)
            return play_poincare(self, n_periods, transient_periods, q0, v0, w)
        raise self._unsupported()

    def stroboscopic_map(self, state: OscillatorState) -> OscillatorState:
        """The state one forcing period T after ``state`` (any phase)."""
        kind = self._kind()
        if kind == "pc":
            return pc.pc_stroboscopic_map(self, state)
        if kind == "play":
            from oscillators.play_flow import play_trajectory

            w = float(state.operator_state.position)
            traj = play_trajectory(self, self.period, state.q, state.v, w, self.period, state.phi)
            f = traj.final
            return OscillatorState(f.q, f.v, f.phi, f.operator_state, state.t + self.period)
        raise NotImplementedError(
            f"stroboscopic_map is not available for {type(self._operator).__name__}"
        )

    def tangent(
        self,
        t_end: float,
        transient: float = 0.0,
        q0: float = -1.0,
        v0: float = 0.1,
        operator_state: Any = None,
        *,
        w0: float | None = None,
        include_phase: bool = False,
        progress: bool = True,
    ) -> TangentResult:
        """Lyapunov spectrum by the tangent flow with QR, averaged over [transient, t_end].

        ``exponents`` are descending; ``labels`` names the tangent-space basis in a fixed order
        (``("q", "v"[, "phi"])`` piecewise-constant, ``("q", "v"[, "phi"], "w")`` play-type),
        not the direction of each exponent.
        """
        kind = self._kind()
        if kind == "pc":
            if w0 is not None:
                raise ValueError("w0 is only meaningful for play-type operators")
            return pc.pc_tangent(
                self, t_end, transient, q0, v0, operator_state, include_phase, progress
            )
        if kind == "play":
            from oscillators.play_flow import play_tangent

            w = self._play_w0(q0, operator_state, w0)
            return play_tangent(
                self, t_end, transient, q0, v0, w, include_phase=include_phase, progress=progress
            )
        raise self._unsupported()
