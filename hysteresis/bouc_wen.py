"""The Bouc–Wen hysteresis operator, a Duhem operator (:mod:`hysteresis.duhem`).

Bouc–Wen (Bouc 1967, Wen 1976) in its rate-independent form::

    ż = A·u̇ − β·|u̇|·|z|ⁿ⁻¹·z − γ·u̇·|z|ⁿ   ⇔   dz/du = A − |z|ⁿ·(β·d·sign(z) + γ),

``d = sign(u̇)`` the direction of input motion. Output ``z``. The restoring force of the
Bouc–Wen oscillator, ``α·k·u + (1 − α)·k·z``, is a sum of operators,
``alpha*k*StaticMap(identity) + (1 - alpha)*k*BoucWen(...)`` (:mod:`hysteresis.algebra`).

Parameters and boundedness
--------------------------
``A > 0``, ``n >= 1``, ``β + γ > 0`` and ``β >= 0``. With ``s = sign(z)``:

* *loading* (``d·s = +1``, ``|z|`` grows with the input travel):
  ``d|z|/d(travel) = A − |z|ⁿ(β + γ)``, which vanishes at ``z_max = (A/(β + γ))^(1/n)``
  (needs ``β + γ > 0``) and pulls ``|z|`` back to it from either side;
* *unloading* (``d·s = −1``): ``d|z|/d(travel) = −A + |z|ⁿ(γ − β)``; at ``|z| = z_max`` this is
  ``−2Aβ/(β + γ)``, so ``|z|`` shrinks iff ``β >= 0`` (for ``β < 0`` it grows past ``z_max``
  and, since then ``γ − β > 0``, without bound).

Hence for ``β >= 0`` the interval ``[−z_max, z_max]`` is invariant: every state stays in it and
the output range is ``(−z_max, z_max)``; ``β >= 0`` is the bounded-z condition validated here,
and :meth:`BoucWen.state` accepts ``|z| <= z_max`` only. (For ``|z| > z_max`` boundedness would
need ``β >= γ`` as well, the condition ``β >= |γ|`` often quoted.)

Negative saturation and the initial state: falling, ``z`` tends to ``−z_max`` (loading with
``s = −1``); rising from there the travel to any finite ``u0`` is infinite, and the rising
branch converges to its stable fixed point ``z_max`` (``dz/du = A − zⁿ(β + γ)`` for ``z > 0``).
So :meth:`BoucWen.initial_state` is ``z = z_max`` at every ``u0``; the virgin (demagnetised)
state is ``state(0.0, u0)``.

Closed form for ``n = 1`` (the tests' truth): while ``sign(z) = s`` and ``d`` are fixed,
``dz/du = A − λz`` with ``λ = β·d + γ·s``, so
``z = A/λ + (z0 − A/λ)·exp(−λ(u − u0))`` (``z = z0 + A(u − u0)`` at ``λ = 0``).

Numerics: the slope is :func:`hysteresis._duhem_kernels.bouc_wen_slope` (compiled, the one
home of the formula); :meth:`BoucWen.apply` runs the compiled adaptive Dormand–Prince 5(4)
kernel of that module (``1e-12`` per step, restarted exactly at ``z = 0``); the branch flow of
the generic engine and ``Duhem.apply(bw, ...)`` keep the ``solve_ivp`` path.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hysteresis import _duhem_kernels as kern
from hysteresis._validation import MAX_MAGNITUDE, finite_scalar, positive_scalar
from hysteresis.duhem import Duhem, DuhemState

__all__ = ["BoucWen"]


class BoucWen(Duhem):
    """Bouc–Wen operator ``dz/du = A − |z|ⁿ·(β·d·sign(z) + γ)``, output ``z`` (module docstring).

    Parameters
    ----------
    A:
        Initial slope (> 0).
    beta, gamma:
        Shape parameters, ``beta >= 0`` and ``beta + gamma > 0`` (bounded ``z``).
    n:
        Sharpness of the transition to saturation (>= 1).
    """

    def __init__(self, A: float, beta: float, gamma: float, n: float = 1.0) -> None:
        self.A = positive_scalar(A, "A", MAX_MAGNITUDE)
        self.beta = finite_scalar(beta, "beta", MAX_MAGNITUDE)
        self.gamma = finite_scalar(gamma, "gamma", MAX_MAGNITUDE)
        self.n = finite_scalar(n, "n", 1e3)
        if not self.n >= 1.0:
            raise ValueError(f"n must be >= 1, got {self.n}")
        if not self.beta + self.gamma > 0.0:
            raise ValueError(f"beta + gamma must be > 0, got {self.beta + self.gamma}")
        if not self.beta >= 0.0:
            raise ValueError(
                f"beta must be >= 0 (else z grows without bound on unloading), got {self.beta}"
            )
        self._h = None
        self._dh = None
        self._set_common((0.0, 0.0), (0.0,))
        self.z_max = (self.A / (self.beta + self.gamma)) ** (1.0 / self.n)

    def slope(self, u: float, z: float, direction: int) -> float:
        """``A − |z|ⁿ·(β·d·sign(z) + γ)`` (:func:`hysteresis._duhem_kernels.bouc_wen_slope`)."""
        return self._slope(z, direction)[0]

    def slope_partials(self, u: float, z: float, direction: int) -> tuple[float, float]:
        """``(0, −n|z|ⁿ⁻¹(β·d + γ·sign z))`` (one-sided at ``z = 0``, a kink)."""
        return 0.0, self._slope(z, direction)[1]

    def _slope(self, z: float, direction: int) -> tuple[float, float]:
        return kern.bouc_wen_slope(
            float(z), float(direction), self.A, self.beta, self.gamma, self.n
        )

    def apply(self, inputs: Any, state: DuhemState | None = None) -> tuple[np.ndarray, DuhemState]:
        """``z`` along ``inputs`` by the compiled kernel (adaptive Dormand–Prince 5(4) at
        ``1e-12`` per step, restarted at the kink ``z = 0``); a returned state continues."""
        params = np.array([self.A, self.beta, self.gamma, self.n])
        return self._compiled_apply(
            inputs, state, kern.MODEL_BOUC_WEN, params, self.z_max, self.z_max / self.A
        )

    @property
    def output_range(self) -> tuple[float, float]:
        """``(−z_max, z_max)``, the invariant interval."""
        return (-self.z_max, self.z_max)

    @property
    def max_slope(self) -> float:
        """Largest ``dz/du`` on ``|z| <= z_max``: ``A·max(1, 2β/(β + γ))`` (at ``z = 0`` or on
        unloading at ``|z| = z_max``)."""
        return self.A * max(1.0, 2.0 * self.beta / (self.beta + self.gamma))

    def state(self, z: float, input: float, direction: int = 0) -> DuhemState:
        """The state with ``z`` (``|z| <= z_max``) at ``input``."""
        z = finite_scalar(z, "z")
        if abs(z) > self.z_max * (1.0 + 1e-12):
            raise ValueError(f"z must lie in [-z_max, z_max] = ±{self.z_max!r}, got {z!r}")
        return super().state(z, input, direction)

    def initial_state(self, u0: float) -> DuhemState:
        """``z = z_max``: rising from negative saturation (module docstring)."""
        return DuhemState(self.z_max, finite_scalar(u0, "u0", MAX_MAGNITUDE), 1)

    def __repr__(self) -> str:
        return f"BoucWen(A={self.A!r}, beta={self.beta!r}, gamma={self.gamma!r}, n={self.n!r})"
