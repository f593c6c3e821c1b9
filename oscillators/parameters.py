"""The oscillator's parameters: their bounds, their defaults (the paper's Table II) and their
validation, defined once here and used by :class:`~oscillators.system.ForcedOscillator`, the
closed forms of :mod:`oscillators.linear` and, through the library's messages, the CLI.
"""

from __future__ import annotations

import math
from typing import Any

from hysteresis._validation import finite_scalar

__all__ = [
    "DEFAULT_DAMPING_RATIO",
    "DEFAULT_FREQUENCY",
    "DEFAULT_Q0",
    "DEFAULT_V0",
    "FREQUENCY_RANGE",
    "MAX_COUPLING",
    "MAX_DAMPING_RATIO",
    "MAX_PERIODS",
    "MAX_SAMPLES",
    "RESONANCE_LIMIT",
    "check_closed_form",
    "check_coupling",
    "check_oscillator",
    "real_parameter",
]

#: Largest number of forcing periods / samples a single call may demand (a guard against
#: parameters such as Ω = 1e-300 that would make a run last forever).
MAX_PERIODS = 10**8
MAX_SAMPLES = 10**8
#: Bounds of the system parameters: ``abs(C) <= MAX_COUPLING``, ``0 <= ζ <= MAX_DAMPING_RATIO``,
#: Ω in ``FREQUENCY_RANGE``.
MAX_COUPLING = 1e6
MAX_DAMPING_RATIO = 1e6
FREQUENCY_RANGE = (1e-6, 1e6)
#: Smallest distance from resonance ``√D = |(1 − Ω²) + 2iζΩ|`` the closed-form engines (relay,
#: play) accept. Their exact flights write the state as ``Φ(h)[x − P(φ₀)] + P(φ₁)`` with the
#: particular solution ``P`` of amplitude ``R·max(1, Ω)``, ``R = 1/√D``: the bounded result is a
#: difference of O(R) terms, so one flight carries a rounding error of about 20·ε·R (cos/sin of
#: phases up to ~2π + abs(φ₀), the products, the subtraction; ‖Φ‖ ≈ 1 near resonance, where ζ ≪ 1
#: and Ω ≈ 1). At √D = 1e-6 that is ≤ 2.2e-9 per flight (< 1e-8 over the few closed-form
#: flights of a typical switch interval); it grows as 1/√D, to O(1) at Ω = 1 ± 1e-14. The
#: generic continuous engine integrates the equation itself and has no such limit.
RESONANCE_LIMIT = 1e-6
#: The paper's initial condition (q(0) = −1, all spins down; q'(0) = 0.1, Table II): the default
#: start of every trajectory, section and analysis.
DEFAULT_Q0 = -1.0
DEFAULT_V0 = 0.1
#: The paper's oscillator (Table II), the defaults of :class:`ForcedOscillator`: ζ and Ω.
DEFAULT_DAMPING_RATIO = 0.05
DEFAULT_FREQUENCY = 1.0


def real_parameter(value: Any, name: str) -> float:
    """``value`` as a finite float; strings, ``None`` and complex numbers are refused."""
    if isinstance(value, (str, bytes)) or value is None or isinstance(value, complex):
        raise TypeError(f"{name} must be a real number, got {value!r}")
    return finite_scalar(value, name)


def check_coupling(coupling: Any) -> float:
    """C as a float in ``[-MAX_COUPLING, MAX_COUPLING]``."""
    c = real_parameter(coupling, "coupling")
    if abs(c) > MAX_COUPLING:
        raise ValueError(f"coupling must lie in [-{MAX_COUPLING:g}, {MAX_COUPLING:g}], got {c}")
    return c


def check_oscillator(damping_ratio: Any, frequency: Any) -> tuple[float, float]:
    """(ζ, Ω) as floats within their bounds; the undamped resonance ζ = 0, Ω = 1 is refused."""
    zeta = real_parameter(damping_ratio, "damping_ratio")
    if not 0.0 <= zeta <= MAX_DAMPING_RATIO:
        raise ValueError(
            f"damping_ratio must lie in [0, {MAX_DAMPING_RATIO:g}], got {damping_ratio}"
        )
    omega = real_parameter(frequency, "frequency")
    f_lo, f_hi = FREQUENCY_RANGE
    if not f_lo <= omega <= f_hi:
        raise ValueError(f"frequency must lie in [{f_lo:g}, {f_hi:g}], got {frequency}")
    if zeta == 0.0 and omega == 1.0:
        raise ValueError(
            "damping_ratio = 0 with frequency = 1 (undamped resonance) is not supported"
        )
    return zeta, omega


def check_closed_form(zeta: float, omega: float) -> None:
    """Refuse (ζ, Ω) closer to the undamped resonance than :data:`RESONANCE_LIMIT`.

    For the engines built on the closed-form particular solution (relay, play): its amplitude
    ``1/√D``, ``√D = hypot(1 − Ω², 2ζΩ)``, bounds their rounding error (see the constant).
    """
    dist = math.hypot((1.0 - omega) * (1.0 + omega), 2.0 * zeta * omega)
    if not dist >= RESONANCE_LIMIT:
        raise ValueError(
            f"damping_ratio = {zeta!r} with frequency = {omega!r} is too close to resonance for "
            f"the closed-form engines: hypot(1 - frequency**2, 2*damping_ratio*frequency) = "
            f"{dist:.3g} < {RESONANCE_LIMIT:g} (RESONANCE_LIMIT), where their rounding error "
            "~20·eps/hypot(...) per exact flight exceeds 1e-8; move the parameters away from "
            "resonance"
        )
