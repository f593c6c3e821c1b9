"""The Jiles–Atherton model of ferromagnetic hysteresis, a Duhem operator (:mod:`hysteresis.duhem`).

Input the field ``H``, output the magnetisation ``M`` (both in A/m, or any consistent units).
Jiles & Atherton (J. Magn. Magn. Mater. 61 (1986) 48; Jiles, Thoelke & Devine, IEEE Trans.
Magn. 28 (1992) 27), exactly these equations::

    He       = H + α·M                                   (effective field)
    M_an(He) = ms·(coth(He/a) − a/He)                    (anhysteretic, ms·L(He/a))
    M        = (1 − c)·M_irr + c·M_an(He)                (solved for M at every H)
    dM_irr/dHe = δ_M·(M_an − M_irr)/(k·δ),   δ = sign(dH),
                 δ_M = 1 if δ·(M_an − M_irr) > 0 else 0

hence ``dM/dH = χ/(1 − α·χ)`` with ``χ = (1 − c)·χ_irr + c·M_an'(He)``, ``χ_irr = dM_irr/dHe``.

As a Duhem operator the memory variable is ``z = M_irr``: ``dHe/dH = 1/(1 − αχ)`` gives the
slope ``g = dM_irr/dH = χ_irr/(1 − αχ)``, and the output is the output map ``M(H, M_irr)``, the
root of ``F(M) = M − (1 − c)M_irr − c·M_an(H + αM)``. ``F' = 1 − αc·M_an' >= 1 − αc·ms/(3a)``
(``max L' = 1/3`` at 0) and ``F(±ms)`` has the sign of ``±1`` when ``|M_irr| < ms``: the root is
unique, in ``[−ms, ms]``, iff ``αc·ms/(3a) < 1`` — the condition validated (``c = 0``: ``M =
M_irr`` for any ``α``). Its partials: ``∂M/∂H = c·M_an'/F'``, ``∂M/∂M_irr = (1 − c)/F'``.
``dM/dH = ∂M/∂H + ∂M/∂M_irr·g = χ/(1 − αχ)`` (the identity above). The formulas live once, as
compiled functions, in :mod:`hysteresis._duhem_kernels`.

Ill-posedness (the known Jiles–Atherton instability): where ``1 − α·χ <= 0`` the slope would be
infinite or negative. Where ``δ_M = 0``, ``1 − αχ = F' > 0``; where ``δ_M = 1`` it can reach 0
when ``α(1 − c)|M_an − M_irr|/k`` approaches 1 — ``α`` too large for ``k``, or a steep
anhysteretic curve (``α·ms/(3a) > 1``). Near such a point ``g ~ (H* − H)^{-1/2}``; :meth:`apply`
and the branch flow integrate up to it and raise :class:`JilesAthertonInstability` (a one-line
``ValueError`` naming the parameters and the field ``H*``), never a clipped slope.

State and initial state: :meth:`state` ``(M_irr, H)`` with ``|M_irr| < ms``; the demagnetised
state is ``state(0.0, 0.0)``. :meth:`initial_state` (rising from negative saturation) starts on
the anhysteretic curve at ``H = −H_far``, ``H_far = 40·(a + k + α·ms)``, where ``M = M_irr =
M_an`` (``|He/a| >= 40``: ``M_an`` is within ``ms/40`` of ``−ms`` and the curve is unique there
whatever ``α``), and follows the rising branch to ``u0``. ``c = 1`` gives the anhysteretic curve
itself (``M = M_an(H)``, M_irr invisible).

``apply`` runs the compiled adaptive Dormand–Prince 5(4) kernel (:mod:`hysteresis._duhem_kernels`,
``1e-12`` per step); the branch flow of the oscillator's generic engine keeps the ``solve_ivp``
path of :class:`~hysteresis.duhem.Duhem` (``Duhem.apply`` is that path too, the tests' reference).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hysteresis import _duhem_kernels as kern
from hysteresis._validation import MAX_MAGNITUDE, finite_scalar, positive_scalar
from hysteresis.duhem import Duhem, DuhemDomainError, DuhemState

__all__ = ["JilesAtherton", "JilesAthertonInstability"]


class JilesAthertonInstability(DuhemDomainError):
    """``1 − α·χ <= 0`` at the field reached: the Jiles–Atherton equations are ill-posed there
    (module docstring)."""

    def __init__(self, model: JilesAtherton, field: float, m_irr: float, direction: int) -> None:
        self.field = float(field)
        self.m_irr = float(m_irr)
        motion = "rising" if direction > 0 else "falling"
        super().__init__(
            f"Jiles-Atherton is ill-posed at H = {self.field!r} ({motion}, "
            f"M_irr = {self.m_irr!r}): 1 - alpha*chi <= 0 for ms={model.ms!r}, a={model.a!r}, "
            f"k={model.k!r}, c={model.c!r}, alpha={model.alpha!r} (the slope dM/dH would be "
            "infinite or negative: alpha too large for k)"
        )


class JilesAtherton(Duhem):
    """Jiles–Atherton magnetisation ``M[H]`` (module docstring).

    Parameters
    ----------
    ms:
        Saturation magnetisation (> 0).
    a:
        Anhysteretic shape parameter, a field (> 0).
    k:
        Pinning, a field (> 0; about the coercivity).
    c:
        Reversible fraction, ``0 <= c <= 1``.
    alpha:
        Mean-field coupling (>= 0, with ``alpha·c·ms/(3a) < 1``).
    """

    def __init__(self, ms: float, a: float, k: float, c: float, alpha: float) -> None:
        self.ms = positive_scalar(ms, "ms", MAX_MAGNITUDE)
        self.a = positive_scalar(a, "a", MAX_MAGNITUDE)
        self.k = positive_scalar(k, "k", MAX_MAGNITUDE)
        self.c = finite_scalar(c, "c")
        self.alpha = finite_scalar(alpha, "alpha", MAX_MAGNITUDE)
        if not 0.0 <= self.c <= 1.0:
            raise ValueError(f"c must lie in [0, 1], got {self.c!r}")
        if self.alpha < 0.0:
            raise ValueError(f"alpha must be >= 0, got {self.alpha!r}")
        if not self.alpha * self.c * self.ms / (3.0 * self.a) < 1.0:
            raise ValueError(
                "alpha·c·ms/(3a) must be < 1 (a unique magnetisation M at every H), got "
                f"{self.alpha * self.c * self.ms / (3.0 * self.a)!r}"
            )
        self._h = None
        self._dh = None
        self._set_common((0.0, 0.0), ())

    # -- the model -----------------------------------------------------------------------------
    def _slope(self, u: float, z: float, direction: int) -> tuple[float, float, float]:
        g, g_h, g_i, ok = kern.jiles_atherton_slope(
            float(u), float(z), float(direction), self.ms, self.a, self.k, self.c, self.alpha
        )
        if not ok:
            raise JilesAthertonInstability(self, u, z, direction)
        return g, g_h, g_i

    def slope(self, u: float, z: float, direction: int) -> float:
        """``dM_irr/dH = χ_irr/(1 − αχ)`` at ``(H, M_irr) = (u, z)`` (module docstring); raises
        :class:`JilesAthertonInstability` where ``1 − αχ <= 0``."""
        return self._slope(u, z, direction)[0]

    def slope_partials(self, u: float, z: float, direction: int) -> tuple[float, float]:
        """``(∂g/∂H, ∂g/∂M_irr)``, analytic (:mod:`hysteresis._duhem_kernels`)."""
        _, g_h, g_i = self._slope(u, z, direction)
        return g_h, g_i

    def map_output(self, u: float, z: float) -> float:
        """``M(H, M_irr)``, the root of ``M = (1 − c)M_irr + c·M_an(H + αM)``."""
        return kern.jiles_atherton_magnetization(
            float(u), float(z), self.ms, self.a, self.c, self.alpha
        )[0]

    def map_output_partials(self, u: float, z: float) -> tuple[float, float]:
        """``(∂M/∂H, ∂M/∂M_irr) = (c·M_an', 1 − c)/(1 − αc·M_an')``."""
        _, m_h, m_i = kern.jiles_atherton_magnetization(
            float(u), float(z), self.ms, self.a, self.c, self.alpha
        )
        return m_h, m_i

    def _outputs(self, inputs: np.ndarray, z: np.ndarray) -> np.ndarray:
        out = np.empty(inputs.size)
        kern.jiles_atherton_outputs(
            np.ascontiguousarray(inputs, dtype=np.float64),
            np.ascontiguousarray(z, dtype=np.float64),
            self.ms,
            self.a,
            self.c,
            self.alpha,
            out,
        )
        return out

    def anhysteretic(self, h: float) -> float:
        """``M_an`` at field ``h``: the root of ``M = ms·L((h + αM)/a)`` (the output map with
        ``c = 1``), unique when ``α·ms/(3a) < 1`` (else a one-line ``ValueError``)."""
        h = finite_scalar(h, "h", MAX_MAGNITUDE)
        if not self.alpha * self.ms / (3.0 * self.a) < 1.0:
            raise ValueError(
                "anhysteretic(h) needs alpha·ms/(3a) < 1 (else M = M_an(H + αM) has several "
                f"roots), got {self.alpha * self.ms / (3.0 * self.a)!r}"
            )
        return kern.jiles_atherton_magnetization(h, 0.0, self.ms, self.a, 1.0, self.alpha)[0]

    @property
    def output_range(self) -> tuple[float, float]:
        """``(−ms, ms)``."""
        return (-self.ms, self.ms)

    def state(self, irreversible: float, input: float, direction: int = 0) -> DuhemState:
        """The state with irreversible magnetisation ``irreversible`` (``|M_irr| < ms``) at
        field ``input``; ``state(0.0, 0.0)`` is the demagnetised state."""
        irreversible = finite_scalar(irreversible, "irreversible")
        if not abs(irreversible) < self.ms:
            raise ValueError(
                f"irreversible (M_irr) must lie in (-ms, ms) = ±{self.ms!r}, got {irreversible!r}"
            )
        return super().state(irreversible, input, direction)

    def _check_state(self, state: Any) -> DuhemState:
        state = super()._check_state(state)
        if not abs(state.z) < self.ms:
            raise ValueError(
                f"the state's M_irr must lie in (-ms, ms) = ±{self.ms!r}, got {state.z!r}"
            )
        return state

    def initial_state(self, u0: float) -> DuhemState:
        """Rising from negative saturation: from the anhysteretic curve at ``H = −H_far``
        (module docstring) along the rising branch to ``u0``."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        far = min(-40.0 * (self.a + self.k + self.alpha * self.ms), u0)
        # c = 1 output map from M_irr = −ms: Newton from next to the root, unique at |He| >= 40a
        m_far = kern.jiles_atherton_magnetization(far, -self.ms, self.ms, self.a, 1.0, self.alpha)
        _, state = self.apply([u0], DuhemState(m_far[0], far, 1))
        return state

    def apply(self, inputs: Any, state: DuhemState | None = None) -> tuple[np.ndarray, DuhemState]:
        """``M`` along ``inputs`` by the compiled kernel (adaptive Dormand–Prince 5(4) at
        ``1e-12``); a returned state continues the record. Raises
        :class:`JilesAthertonInstability` where the model becomes ill-posed."""
        params = np.array([self.ms, self.a, self.k, self.c, self.alpha])
        return self._compiled_apply(
            inputs, state, kern.MODEL_JILES_ATHERTON, params, self.ms, self.a
        )

    def domain_error(
        self, u: float, z: float, direction: int, reason: str = ""
    ) -> JilesAthertonInstability:
        """:class:`JilesAthertonInstability` at ``(H, M_irr) = (u, z)``."""
        return JilesAthertonInstability(self, u, z, direction)

    def compiled_model(self) -> tuple[str, dict[str, float]]:
        """``("jiles_atherton", {ms, a, k, c, alpha})``: the oscillator's compiled Duhem engine
        evaluates the right-hand side from :mod:`hysteresis._duhem_kernels`."""
        return "jiles_atherton", {
            "ms": self.ms, "a": self.a, "k": self.k, "c": self.c, "alpha": self.alpha,
        }  # fmt: skip

    def __repr__(self) -> str:
        return (
            f"JilesAtherton(ms={self.ms!r}, a={self.a!r}, k={self.k!r}, c={self.c!r}, "
            f"alpha={self.alpha!r})"
        )
