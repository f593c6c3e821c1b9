"""The Jiles–Atherton model of ferromagnetic hysteresis, a Duhem operator (:mod:`hysteresis.duhem`).

Input the field ``H``, output the magnetisation ``M`` (both in A/m, or any consistent units).
Jiles & Atherton (J. Magn. Magn. Mater. 61 (1986) 48; Jiles, Thoelke & Devine, IEEE Trans.
Magn. 28 (1992) 27), in the rate-independent differential form most codes use::

    H_e  = H + α·M                                  (effective field)
    M_an = M_s·L(H_e/a),   L(x) = coth(x) − 1/x      (anhysteretic magnetisation, Langevin)
    χ_irr = δ_M·(M_an − M) / (δ·k − α·(M_an − M))
    dM/dH = [(1 − c)·χ_irr + c·M_an'(H_e)] / [1 − α·c·M_an'(H_e)]

with ``δ = sign(dH)`` the direction of the field's motion, ``M_an' = dM_an/dH_e =
(M_s/a)·L'(H_e/a)``, and ``δ_M = 1`` when the irreversible change moves ``M`` toward ``M_an``
(``δ·(M_an − M) > 0``), else 0 — the usual correction (Deane, Venkataraman) that keeps the
differential susceptibility from turning negative after a reversal. Parameters: ``Ms`` the
saturation magnetisation, ``a`` the anhysteretic shape (a field), ``alpha`` the mean-field
coupling, ``k`` the pinning (a field: about the coercivity), ``c`` the reversible fraction.

Validity (checked): ``Ms, a, k > 0``, ``0 <= c < 1``, ``alpha >= 0`` and ``α·M_s/(3a) < 1``:
``max L' = 1/3`` at 0, so this keeps the anhysteretic curve single-valued (``H_e`` increasing in
``H``) and the denominator ``1 − α·c·M_an'`` positive. The irreversible denominator
``δk − α(M_an − M)`` is positive wherever ``δ_M = 1`` and ``α|M_an − M| < k``; where it is not
(far from the anhysteretic curve, a known defect of the formulation: the susceptibility would
pass through a pole and turn negative) the irreversible term is taken as 0, like ``δ_M``.

Numerics: ``∂g/∂M`` (the variational equation of the branch) by the complex-step derivative of
the right-hand side, exact to rounding where ``δ_M`` does not switch; ``L`` by its series
``x/3 − x³/45 + 2x⁵/945`` for ``|x| < 1e-3`` (error below ``1e-16·|x|``). The initial state
("rising from negative saturation") starts on the anhysteretic curve at ``H = −H_far`` with
``H_far = 40·(a + k + α·M_s)`` and follows the rising branch to ``u0``.
"""

from __future__ import annotations

import cmath

from hysteresis._validation import MAX_MAGNITUDE, finite_scalar, positive_scalar
from hysteresis.duhem import Duhem, DuhemState

__all__ = ["JilesAtherton"]

#: the complex step of ∂g/∂M (relative to M_s): far below any scale of the model, and the
#: complex-step derivative has no subtraction error, so its size does not matter beyond that
_COMPLEX_STEP = 1e-30


def _langevin(x: complex) -> complex:
    """``L(x) = coth(x) − 1/x`` (series near 0, complex arguments for the complex step)."""
    if abs(x) < 1e-3:
        x2 = x * x
        return x * (1.0 / 3.0 - x2 / 45.0 + 2.0 * x2 * x2 / 945.0)
    return 1.0 / cmath.tanh(x) - 1.0 / x


def _langevin_slope(x: complex) -> complex:
    """``L'(x) = 1/x² − 1/sinh²(x)`` (series ``1/3 − x²/15 + 2x⁴/189`` near 0)."""
    if abs(x) < 1e-3:
        x2 = x * x
        return 1.0 / 3.0 - x2 / 15.0 + 2.0 * x2 * x2 / 189.0
    if abs(x.real) > 350.0:  # sinh² overflows; 1/sinh² is 0 to double precision there
        return 1.0 / (x * x)
    return 1.0 / (x * x) - 1.0 / cmath.sinh(x) ** 2


class JilesAtherton(Duhem):
    """Jiles–Atherton magnetisation ``M[H]`` (module docstring).

    Parameters
    ----------
    Ms:
        Saturation magnetisation (> 0).
    a:
        Anhysteretic shape parameter, a field (> 0).
    alpha:
        Mean-field coupling (>= 0, with ``alpha·Ms/(3a) < 1``).
    k:
        Pinning, a field (> 0).
    c:
        Reversible fraction, ``0 <= c < 1``.
    """

    def __init__(self, Ms: float, a: float, alpha: float, k: float, c: float) -> None:
        self.Ms = positive_scalar(Ms, "Ms", MAX_MAGNITUDE)
        self.a = positive_scalar(a, "a", MAX_MAGNITUDE)
        self.alpha = finite_scalar(alpha, "alpha", MAX_MAGNITUDE)
        self.k = positive_scalar(k, "k", MAX_MAGNITUDE)
        self.c = finite_scalar(c, "c")
        if self.alpha < 0.0:
            raise ValueError(f"alpha must be >= 0, got {self.alpha}")
        if not 0.0 <= self.c < 1.0:
            raise ValueError(f"c must lie in [0, 1), got {self.c}")
        if not self.alpha * self.Ms / (3.0 * self.a) < 1.0:
            raise ValueError(
                f"alpha·Ms/(3a) must be < 1 (a single-valued anhysteretic curve), got "
                f"{self.alpha * self.Ms / (3.0 * self.a)!r}"
            )
        self._h = None
        self._dh = None
        self._set_common((0.0, 0.0), ())

    # -- the model -----------------------------------------------------------------------------
    def _rhs(self, h: float, m: complex, direction: int) -> complex:
        """``dM/dH`` at ``(H, M)`` moving in ``direction`` (complex ``M`` for the complex step;
        ``δ_M`` decided on the real part)."""
        he = h + self.alpha * m
        x = he / self.a
        m_an = self.Ms * _langevin(x)
        dm_an = self.Ms / self.a * _langevin_slope(x)
        gap = m_an - m
        irreversible = 0.0
        if direction * gap.real > 0.0:
            den = direction * self.k - self.alpha * gap
            # past the formulation's pole (α·|M_an − M| >= k) the irreversible susceptibility
            # would be negative or infinite: it is taken as 0 there (module docstring)
            if direction * den.real > 0.0:
                irreversible = gap / den
        return ((1.0 - self.c) * irreversible + self.c * dm_an) / (
            1.0 - self.alpha * self.c * dm_an
        )

    def slope(self, u: float, z: float, direction: int) -> float:
        """``dM/dH`` (module docstring)."""
        return float(self._rhs(float(u), complex(z), direction).real)

    def slope_partials(self, u: float, z: float, direction: int) -> tuple[float, float]:
        """``(0, ∂g/∂M)``: the complex-step derivative in ``M`` (the engines use ``∂g/∂M``
        only)."""
        step = _COMPLEX_STEP * self.Ms
        value = self._rhs(float(u), complex(z, step), direction)
        return 0.0, float(value.imag / step)

    def anhysteretic(self, h: float) -> float:
        """``M_an`` at field ``h``: the root of ``f(M) = M − M_s·L((h + αM)/a)``, unique since
        ``f' >= 1 − α·M_s/(3a) > 0``, in ``[−M_s, M_s]`` (``f(±M_s)`` has the sign of ``±1``).
        Newton safeguarded by that bracket, stopped when the bracket or the step is below
        ``1e-14·M_s`` (a few ulps of ``M_s``: the rounding of ``L`` sets the floor)."""
        h = finite_scalar(h, "h", MAX_MAGNITUDE)
        lo, hi, m = -self.Ms, self.Ms, 0.0
        tol = 1e-14 * self.Ms
        for _ in range(200):
            x = (h + self.alpha * m) / self.a
            f = m - self.Ms * _langevin(complex(x)).real
            if f > 0.0:
                hi = m
            else:
                lo = m
            df = 1.0 - self.alpha * self.Ms / self.a * _langevin_slope(complex(x)).real
            nxt = m - f / df
            if not lo < nxt < hi:  # outside the bracket: bisect
                nxt = 0.5 * (lo + hi)
            if abs(nxt - m) <= tol or hi - lo <= tol:
                return nxt
            m = nxt
        raise ValueError(f"anhysteretic(h = {h!r}): no convergence in 200 iterations")

    @property
    def output_range(self) -> tuple[float, float]:
        """``(−Ms, Ms)``."""
        return (-self.Ms, self.Ms)

    def state(self, z: float, input: float, direction: int = 0) -> DuhemState:
        """The state with magnetisation ``z`` (``|z| < Ms``) at field ``input``."""
        z = finite_scalar(z, "z")
        if not abs(z) < self.Ms:
            raise ValueError(
                f"z (the magnetisation) must lie in (-Ms, Ms) = ±{self.Ms!r}, got {z!r}"
            )
        return super().state(z, input, direction)

    def initial_state(self, u0: float) -> DuhemState:
        """Rising from negative saturation: from the anhysteretic curve at ``H = −H_far``
        (module docstring) along the rising branch to ``u0``."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        far = min(-40.0 * (self.a + self.k + self.alpha * self.Ms), u0)
        _, state = self.apply([u0], DuhemState(self.anhysteretic(far), far, 1))
        return state

    def __repr__(self) -> str:
        return (
            f"JilesAtherton(Ms={self.Ms!r}, a={self.a!r}, alpha={self.alpha!r}, k={self.k!r}, "
            f"c={self.c!r})"
        )
