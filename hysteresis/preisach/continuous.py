"""The continuous Preisach model: a density on the triangle (see :mod:`hysteresis.preisach.base`).

Amortised O(1) Everett evaluations per input step through cached prefix sums along the
staircase (:func:`hysteresis.preisach._kernels.continuous_staircase`). The Gaussian
width-disorder density of :meth:`ContinuousPreisachModel.gaussian` is built in
:mod:`hysteresis.preisach.gaussian`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hysteresis._validation import (
    MAX_MAGNITUDE,
    ParameterTypeError,
    as_input_sequence,
    bounded_work,
    direction_sign,
    finite_scalar,
    positive_integer,
    positive_scalar,
    readonly_array,
)
from hysteresis.base import ContinuousHysteron
from hysteresis.flow import BranchFlow, CompiledFlow
from hysteresis.preisach import _kernels as _k
from hysteresis.preisach import _scalar
from hysteresis.preisach._everett_kernels import KIND_TABLE, everett_eval, everett_many
from hysteresis.preisach.base import (
    PreisachModel,
    PreisachState,
    _fingerprint,
    _stack,
)
from hysteresis.preisach.everett_table import (
    CompiledEverett,
    density_table,
    everett_function_table,
)
from hysteresis.preisach.gaussian import (
    BUILD_NODES,
    GaussianTable,
    gaussian_support,
    gaussian_table,
)

__all__ = ["ContinuousPreisachModel"]

#: largest ``resolution`` of :meth:`PreisachModel.from_density` and of a compiled table: the
#: quadrature holds ~16·resolution²/2 density values while it runs, the Hermite table keeps
#: 4·(resolution + 1)² floats (537 MB at the limit)
_MAX_RESOLUTION = 4096
#: grid cells per side of the table :meth:`ContinuousPreisachModel.compiled_everett` builds for
#: a :meth:`PreisachModel.from_everett` model
COMPILED_RESOLUTION = 512
#: smallest ``width_spread`` σ_r of a Gaussian model that the oscillator's compiled continuous
#: engine integrates (its fixed RK8 step must resolve the band of ~24 σ_r where the Everett
#: function turns; below it the generic adaptive engine does, see ``uncompiled_reason``)
MIN_COMPILED_WIDTH_SPREAD = 0.005
#: inputs per chunk of :meth:`ContinuousPreisachModel.apply`: its working memory (a user's
#: vectorised Everett function may hold chunk × nodes floats) is bounded by this, not by the
#: length of the input
_APPLY_CHUNK = 8192


class _FloatEverett:
    """``everett`` with its values as a float64 array (a picklable wrapper)."""

    def __init__(self, everett: Callable) -> None:
        self.everett = everett

    def __call__(self, a, b) -> np.ndarray:
        return np.asarray(self.everett(a, b), dtype=np.float64)


def _gaussian_model(width: float, spread: float, width_spread: float, nodes: int):
    """:meth:`ContinuousPreisachModel.gaussian` (unpickling rebuilds the model from these)."""
    return ContinuousPreisachModel.gaussian(width, spread, width_spread, nodes)


class ContinuousPreisachModel(PreisachModel, ContinuousHysteron[PreisachState], kind="continuous"):
    """Preisach model with a density on the triangle ``lower <= β <= α <= upper``.

    Memory variables for :meth:`linearize`: the staircase extrema (see there). Branch slopes are
    ``2 ∂E/∂α(u, m_last)`` on a rising input and ``−2 ∂E/∂β(M_last, u)`` on a falling one.
    """

    def __init__(self, lower: float, upper: float) -> None:
        self._lower = finite_scalar(lower, "lower", MAX_MAGNITUDE)
        self._upper = finite_scalar(upper, "upper", MAX_MAGNITUDE)
        if not self._upper > self._lower:
            raise ValueError(f"upper must be > lower, got lower={lower}, upper={upper}")
        self._everett_fn: Callable = None  # type: ignore[assignment]
        self._gradient_fn: Callable | None = None
        self._density_fn: Callable | None = None

    @property
    def lower(self) -> float:
        return self._lower

    @property
    def upper(self) -> float:
        return self._upper

    def _saturation_input(self) -> float:
        return self._upper

    @property
    def min_slope(self) -> float | None:
        """0 for a :meth:`gaussian` model whose width law is cut above ``r = 0``
        (``r_lo = p/2 − 8σ_r > 0``: no relay narrower than ``2 r_lo``, so after every reversal
        the output stays flat while the input moves by ``2 r_lo``); ``None`` otherwise.

        Why not a number: a branch leaving a reversal at ``m`` has the slope
        ``2 ∂E/∂α(u, m) = 2 ∫_m^u μ(u, β) dβ``, which vanishes at ``u = m`` for every bounded
        density, so the least slope is always 0; yet the branches strictly increase (on
        ``[lower, upper]``) exactly when every triangle at the diagonal has mass,
        ``E(u, m) > 0`` for ``lower <= m < u <= upper``, a property of the density near the
        diagonal that the model does not know in general (the inverse checks each branch)."""
        gaussian = self.__dict__.get("_gaussian")
        if gaussian is not None and gaussian_support(*gaussian)[3] > 0.0:
            return 0.0
        return None

    def __repr__(self) -> str:
        return f"ContinuousPreisachModel(lower={self._lower}, upper={self._upper})"

    #: the table of a from_everett model's compiled_everett() (rebuilt on demand) is not pickled
    _transient_attributes = ("_compiled_tables",)

    def __reduce__(self) -> tuple:
        """A :meth:`gaussian` model is pickled as its parameters and rebuilt (deterministic:
        same Everett function, same fingerprint, so the original's states are accepted);
        any other model as its attributes (its callables must be picklable)."""
        gaussian = self.__dict__.get("_gaussian_arguments")
        if gaussian is not None:
            return (_gaussian_model, gaussian)
        return super().__reduce__()

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def _from_density(cls, density, lower, upper, resolution, mass_tolerance):
        if not callable(density):
            raise ParameterTypeError("density must be a vectorised callable density(alpha, beta)")
        model = cls(lower, upper)
        n = positive_integer(resolution, "resolution", minimum=2)
        # the quadrature holds 16 resolution²/2 density values and the table 4 (n+1)² floats:
        # bound the memory up front
        bounded_work(n, "resolution", _MAX_RESOLUTION, "grid cells per side")
        mass_tolerance = positive_scalar(mass_tolerance, "mass_tolerance")
        table, model._mass_scale = density_table(
            density, model._lower, model._upper, n, mass_tolerance
        )
        model._compiled_everett = CompiledEverett(
            KIND_TABLE, np.array([model._lower, model._upper]), table
        )
        model._density_fn = density
        model._everett_fn = model._everett_from_table
        model._gradient_fn = model._gradient_from_table
        model._set_fingerprint()
        return model

    @classmethod
    def _from_everett(cls, everett, lower, upper, everett_gradient):
        if not callable(everett):
            raise ParameterTypeError("everett must be a vectorised callable everett(alpha, beta)")
        if everett_gradient is not None and not callable(everett_gradient):
            raise ParameterTypeError("everett_gradient must be callable or None")
        model = cls(lower, upper)
        lo, up = model._lower, model._upper
        try:
            total_arr = np.asarray(everett(np.array([up]), np.array([lo])))
        except Exception as exc:
            raise ValueError(
                f"everett must accept numpy arrays (a, b); it raised {type(exc).__name__}: {exc}"
            ) from exc
        if total_arr.dtype.kind not in "iuf" or total_arr.shape != (1,):
            raise ValueError(
                "everett must return one real value per (a, b) pair, got "
                f"dtype {total_arr.dtype} shape {total_arr.shape}"
            )
        total = float(total_arr[0])
        if abs(total - 1.0) > 1e-6:
            raise ValueError(
                f"everett must satisfy E(upper, lower) = 1 (total mass), got {total!r}"
            )
        x = np.linspace(lo, up, 11)
        if np.max(np.abs(np.asarray(everett(x, x), dtype=np.float64))) > 1e-9:
            raise ValueError("everett must vanish on the diagonal, E(a, a) = 0")
        model._everett_fn = _FloatEverett(everett)
        model._gradient_fn = everett_gradient
        model._check_everett_probe()
        model._set_fingerprint()
        return model

    def _check_everett_probe(self, nodes: int = 65) -> None:
        """Everett function on a probe grid: finite, one value per pair, and every cell mass
        ``E(a', b) − E(a, b) − E(a', b') + E(a, b') >= 0`` (non-negative density)."""
        x = np.linspace(self._lower, self._upper, nodes)
        a, b = np.meshgrid(x, x, indexing="ij")
        lower = a > b
        values = self._everett_fn(a[lower], b[lower])
        if values.shape != (int(lower.sum()),):
            raise ValueError(
                f"everett must return one value per (a, b) pair, got shape {values.shape}"
            )
        if not np.all(np.isfinite(values)):
            i = int(np.argmax(~np.isfinite(values)))
            raise ValueError(
                f"everett must be finite on lower <= b <= a <= upper, got {values[i]} at "
                f"(a, b) = ({a[lower][i]!r}, {b[lower][i]!r})"
            )
        table = np.zeros((nodes, nodes))
        table[lower] = values
        # cell (a_i, a_{i+1}] x (b_j, b_{j+1}] for j <= i; E = 0 for b >= a
        mass = table[1:, :-1] - table[:-1, :-1] - table[1:, 1:] + table[:-1, 1:]
        cells = np.tril(np.ones_like(mass, dtype=bool))
        tol = 1e-9 * max(1.0, float(np.max(np.abs(values))))
        if np.any(mass[cells] < -tol):
            i, j = np.argwhere(cells & (mass < -tol))[0]
            raise ValueError(
                "everett must be the Everett function of a non-negative density, but the cell "
                f"alpha in ({x[i]:.6g}, {x[i + 1]:.6g}], beta in ({x[j]:.6g}, {x[j + 1]:.6g}] "
                f"has negative mass {mass[i, j]:.3g}"
            )

    def _set_fingerprint(self) -> None:
        x = np.linspace(self._lower, self._upper, 9)
        a, b = np.meshgrid(x, x, indexing="ij")
        self._fingerprint = _fingerprint(
            b"continuous", np.array([self._lower, self._upper]), self.everett(a, b)
        )

    # -- Everett function ----------------------------------------------------------------------
    def _clip(self, a, b):
        a = np.clip(np.asarray(a, dtype=np.float64), self._lower, self._upper)
        b = np.clip(np.asarray(b, dtype=np.float64), self._lower, self._upper)
        return np.broadcast_arrays(a, b)

    def everett(self, a, b) -> np.ndarray:
        """``E(a, b)``: mass of ``{b < β <= α <= a}``; 0 for ``b >= a``. Arguments outside
        ``[lower, upper]`` act as the nearest bound (the density vanishes outside)."""
        a, b = self._clip(a, b)
        out = np.zeros(a.shape)
        mask = a > b
        if np.any(mask):
            out[mask] = self._everett_fn(a[mask], b[mask])
        return out

    def _everett_from_table(self, a, b):
        c = self._compiled_everett
        return everett_many(c.kind, c.params, c.table, a, b)[0]

    def _gradient_from_table(self, a, b):
        c = self._compiled_everett
        return everett_many(c.kind, c.params, c.table, a, b)[1:]

    def everett_gradient(self, a, b) -> tuple[np.ndarray, np.ndarray]:
        """``(∂E/∂α, ∂E/∂β)`` at ``(a, b)``; zero outside the triangle's interior."""
        a0 = np.asarray(a, dtype=np.float64)
        b0 = np.asarray(b, dtype=np.float64)
        a, b = self._clip(a0, b0)
        da = np.zeros(a.shape)
        db = np.zeros(a.shape)
        inside = a > b
        if np.any(inside):
            if self._gradient_fn is not None:
                ga, gb = self._gradient_fn(a[inside], b[inside])
            else:
                step = 1e-6 * (self._upper - self._lower)
                ai, bi = a[inside], b[inside]
                ga = (self._everett_fn(ai + step, bi) - self._everett_fn(ai - step, bi)) / (
                    2 * step
                )
                gb = (self._everett_fn(ai, bi + step) - self._everett_fn(ai, bi - step)) / (
                    2 * step
                )
            da[inside] = ga
            db[inside] = gb
        a_b, b_b = np.broadcast_arrays(a0, b0)
        # beyond the support the Everett function no longer depends on that argument
        da = np.where((a_b < self._lower) | (a_b > self._upper), 0.0, da)
        db = np.where((b_b < self._lower) | (b_b > self._upper), 0.0, db)
        return da, db

    def density(self, alpha, beta) -> np.ndarray:
        """Preisach density ``μ(α, β) = −∂²E/∂α∂β`` (the given callable for
        :meth:`from_density`, central differences of ``E`` for :meth:`from_everett`)."""
        alpha, beta = np.broadcast_arrays(
            np.asarray(alpha, dtype=np.float64), np.asarray(beta, dtype=np.float64)
        )
        if self._density_fn is not None:
            return self._mass_scale * np.asarray(self._density_fn(alpha, beta), dtype=np.float64)
        h = 1e-4 * (self._upper - self._lower)
        e = self._everett_fn
        return -(
            e(alpha + h, beta + h)
            - e(alpha + h, beta - h)
            - e(alpha - h, beta + h)
            + e(alpha - h, beta - h)
        ) / (4 * h * h)

    def density_rs(self, r, s) -> np.ndarray:
        """Density in rotated coordinates ``s = (α+β)/2``, ``r = (α−β)/2``:
        ``μ_rs(r, s) = 2 μ(s + r, s − r)`` (Jacobian of the map (r, s) -> (α, β) is 2)."""
        r = np.asarray(r, dtype=np.float64)
        s = np.asarray(s, dtype=np.float64)
        return 2.0 * self.density(s + r, s - r)

    # -- states ------------------------------------------------------------------------------
    def _terms(self, stack: np.ndarray) -> np.ndarray:
        """Everett term of every stack entry (0 for the sentinels)."""
        terms = np.zeros(stack.size)
        if stack.size > 2:
            idx = np.arange(2, stack.size)
            is_max = idx % 2 == 0
            a = np.where(is_max, stack[idx], stack[idx - 1])
            b = np.where(is_max, stack[idx - 1], stack[idx])
            terms[2:] = np.where(is_max, 1.0, -1.0) * self.everett(a, b)
        return terms

    def initial_state(self, u0: float) -> PreisachState:
        """Rise from negative saturation to ``u0``: ``M = −1 + 2 E(u0, lower)``."""
        u0 = finite_scalar(u0, "u0", MAX_MAGNITUDE)
        stack = np.array([np.inf, -np.inf, u0])
        prefix = np.cumsum(self._terms(stack))
        return PreisachState(
            extrema=readonly_array([u0]),
            output=float(-1.0 + 2.0 * prefix[-1]),
            prefix=readonly_array(prefix),
            model_fingerprint=self._fingerprint,
        )

    def _unpack(self, state: PreisachState):
        self._check_state(state)
        if state.prefix is None:
            raise ValueError("state must be a state of a continuous PreisachModel")
        prefix = np.asarray(state.prefix, dtype=np.float64)
        if prefix.shape != (state.extrema.size + 2,):
            raise ValueError("state is inconsistent: prefix and extrema differ in length")
        if state.model_fingerprint is None:
            # a state built by hand: its prefix sums must be this model's (O(depth), once)
            e = np.asarray(state.extrema, dtype=np.float64)
            if not np.all(np.isfinite(e)) or float(np.max(np.abs(e))) > MAX_MAGNITUDE:
                raise ValueError("state.extrema must be finite with magnitude <= 1e300")
            expected = np.cumsum(self._terms(_stack(state)))
            if not np.allclose(prefix, expected, rtol=0.0, atol=1e-9):
                raise ValueError("state does not belong to this PreisachModel (prefix sums)")
        return _stack(state), prefix

    def apply(self, inputs, state: PreisachState | None = None) -> tuple[np.ndarray, PreisachState]:
        """Outputs for ``inputs`` from ``state`` (default ``initial_state(inputs[0])``) and the
        final state. Long inputs run in chunks of :data:`_APPLY_CHUNK`, each continuing the
        state of the previous one (exact: the same arithmetic as one pass), so the working
        memory does not grow with the length of the input."""
        u = as_input_sequence(inputs)
        if state is None:
            state = self.initial_state(float(u[0]))
        chunk = _APPLY_CHUNK
        if u.size <= chunk:
            return self._apply_chunk(u, state)
        outputs = np.empty(u.size)
        for start in range(0, u.size, chunk):
            outputs[start : start + chunk], state = self._apply_chunk(
                u[start : start + chunk], state
            )
        return outputs, state

    def _apply_chunk(self, u: np.ndarray, state: PreisachState) -> tuple[np.ndarray, PreisachState]:
        stack, prefix = self._unpack(state)
        top = stack.size - 1
        vals = np.empty(stack.size + u.size + 2)  # at most one new entry per input
        vals[: stack.size] = stack
        refs = np.empty(vals.size, dtype=np.int64)
        refs[: stack.size] = -1 - np.arange(stack.size)
        a, b, sign, base, vals, refs, top = _k.continuous_staircase(u, vals, refs, top)
        terms = sign * self.everett(a, b)
        sums = _k.continuous_accumulate(terms, base, prefix)
        refs = refs[: top + 1]
        final_prefix = np.where(
            refs >= 0, sums[np.maximum(refs, 0)], prefix[np.maximum(-1 - refs, 0)]
        )
        final_prefix[:2] = 0.0
        outputs = -1.0 + 2.0 * sums
        new_state = PreisachState(
            extrema=readonly_array(vals[2 : top + 1]),
            output=float(outputs[-1]),
            prefix=readonly_array(final_prefix),
            model_fingerprint=self._fingerprint,
        )
        return outputs, new_state

    # -- branch flow for the oscillator's continuous engine ------------------------------------
    @staticmethod
    def extremum_label(index: int) -> str:
        """Memory label of ``extrema[index]``: ``"M1", "m1", "M2", "m2", ...``."""
        return f"M{index // 2 + 1}" if index % 2 == 0 else f"m{index // 2 + 1}"

    def branch_flow(self, state: PreisachState, direction: int) -> BranchFlow:
        """The branch in ``direction`` as a :class:`~hysteresis.flow.BranchFlow`.

        Memory: the remembered extrema (labels :meth:`extremum_label`), all frozen. Continuing
        the last monotone segment they are ``extrema[:-1]``; reversing, the current input
        becomes a new extremum (flagged ``pushed``, ``δm := δu``) and the memory is all of
        ``extrema``. With ``m`` the last memory variable (partner of the moving input) and
        ``c`` the Everett prefix sum up to it, the output is
        ``y(u) = −1 + 2c + 2E(u, m)`` rising and ``y(u) = −1 + 2c − 2E(m, u)`` falling, so
        ``∂y/∂u = 2∂E/∂α(u, m)`` / ``−2∂E/∂β(m, u)``; ``∂y/∂m_j`` is constant for every
        extremum but ``m``, which adds ``2∂E/∂β(u, m)`` / ``−2∂E/∂α(m, u)``
        (:meth:`everett_gradient`). Breakpoint: the previous extremum of the moving input's
        kind; reaching it wipes it out together with ``m`` (``breakpoint_removes``). A reversal
        pushes the reversal input (``reversal_pushes``).
        """
        direction = direction_sign(direction)
        stack, prefix = self._unpack(state)
        top = stack.size - 1
        rising_state = top % 2 == 0
        reversing = (direction > 0) != rising_state
        partner = top if reversing else top - 1  # stack index of the memory variable m
        n_mem = partner - 1  # stack indices 2 .. partner
        memory = stack[2 : partner + 1].copy()
        labels = tuple(self.extremum_label(k) for k in range(n_mem))
        pushed = np.zeros(n_mem, dtype=bool)
        if reversing:
            pushed[-1] = True
        # constant gradient of the Everett terms that do not involve the moving input
        grad0 = np.zeros(stack.size)
        if partner >= 2:
            idx = np.arange(2, partner + 1)
            even = idx % 2 == 0
            a = np.where(even, stack[idx], stack[idx - 1])
            b = np.where(even, stack[idx - 1], stack[idx])
            da, db = self.everett_gradient(a, b)
            sign = np.where(even, 2.0, -2.0)
            np.add.at(grad0, np.where(even, idx, idx - 1), sign * da)
            np.add.at(grad0, np.where(even, idx - 1, idx), sign * db)
        grad0 = grad0[2 : partner + 1]
        m = float(stack[partner])
        base = -1.0 + 2.0 * float(prefix[partner])
        k_last = n_mem - 1
        everett, gradient = self._scalar_everett(), self._scalar_gradient()
        if direction > 0:

            def output(u):
                return base + 2.0 * everett(u, m)

            def partials(u):
                ea, eb = gradient(u, m)
                u = np.asarray(u, dtype=np.float64)
                d_m = np.broadcast_to(grad0, u.shape + grad0.shape).copy()
                if k_last >= 0:
                    d_m[..., k_last] += 2.0 * eb
                return 2.0 * ea, d_m

        else:

            def output(u):
                return base - 2.0 * everett(m, u)

            def partials(u):
                ea, eb = gradient(m, u)
                u = np.asarray(u, dtype=np.float64)
                d_m = np.broadcast_to(grad0, u.shape + grad0.shape).copy()
                if k_last >= 0:
                    d_m[..., k_last] -= 2.0 * ea
                return -2.0 * eb, d_m

        bp_index = partner - 1
        breakpoint = float(stack[bp_index])
        removes = tuple(labels[i - 2] for i in (bp_index, partner) if i >= 2)
        return BranchFlow(
            direction=direction,
            input=float(stack[top]),
            labels=labels,
            memory=memory,
            slaved=np.zeros(n_mem, dtype=bool),
            output=output,
            partials=partials,
            breakpoint=breakpoint,
            breakpoint_removes=removes if np.isfinite(breakpoint) else (),
            reversal_pushes=True,
            pushed=pushed,
        )

    def compiled_flow(self) -> CompiledFlow | None:
        """The staircase for the oscillator's compiled continuous engine: this model's
        :meth:`compiled_everett` (``None`` if it has none, or for a Gaussian width law narrower
        than the engine's fixed step resolves, :attr:`uncompiled_reason`: the generic engine
        integrates it) and the memory labels of :meth:`extremum_label`."""
        if self.uncompiled_reason is not None:
            return None
        everett = self.compiled_everett()
        if everett is None:
            return None
        return CompiledFlow(kind="preisach", label=self.extremum_label, everett=everett)

    @property
    def uncompiled_reason(self) -> str | None:
        """Why the oscillator integrates this model with the generic (adaptive) engine, or
        ``None``. A Gaussian width law with ``width_spread`` below
        :data:`MIN_COMPILED_WIDTH_SPREAD`: its Everett function turns within a band of the
        input about ``24 σ_r`` wide, which one fixed RK8 step of the compiled engine crosses
        (measured at p = 2, R = 1, C = 1 and 2 over t = 30 against a tight adaptive
        reference: ≤ 5e-10 at σ_r ≥ 0.005, 2e-8–2e-7 at σ_r = 0.002)."""
        gaussian = self.__dict__.get("_gaussian")
        if gaussian is not None and gaussian[2] < MIN_COMPILED_WIDTH_SPREAD:
            return (
                f"width_spread {gaussian[2]:g} is below {MIN_COMPILED_WIDTH_SPREAD:g}, narrower "
                "than the compiled engine's fixed RK8 step resolves"
            )
        return None

    def _scalar_everett(self) -> Callable:
        """``everett`` with a fast path for scalar arguments (:mod:`._scalar`)."""
        return _scalar.scalar_everett(self)

    def _scalar_gradient(self) -> Callable:
        """``everett_gradient`` with a fast path for scalar arguments (:mod:`._scalar`)."""
        return _scalar.scalar_gradient(self)

    @classmethod
    def gaussian(
        cls,
        width: float = 2.0,
        spread: float = 1.0,
        width_spread: float = 0.1,
        nodes: int = BUILD_NODES,
    ) -> ContinuousPreisachModel:
        """Density ``N(s; 0, R²)·N(r; p/2, σ_r²)`` in rotated coordinates (paper eq. pdens_sr
        with the ridge ``δ(r − p/2)`` widened to a normal law of the half-width ``r``).

        ``width`` = p > 0, ``spread`` = R > 0, ``width_spread`` = σ_r > 0. The width law is
        cut to ``|r − p/2| <= 8σ_r``, ``r >= 0``, and the model renormalised to mass 1 (a
        change only if σ_r is not small against p/2). The Everett function

            E(a, b) = ∫_0^{(a−b)/2} N(r; p/2, σ_r²) [Φ((a − r)/R) − Φ((b + r)/R)] dr

        (``Φ`` the standard normal CDF) is evaluated through its separable form
        ``F(a, t) + F(−b, t) − W(t)``, ``t = (a − b)/2``, with ``F`` a bi-quintic Hermite table
        (:mod:`hysteresis.preisach.gaussian`): ``|E − E_exact| <= 1e-12`` and a gradient
        within ~1e-9 (1.2e-8 at σ_r = 0.0125; the bounds derived there,
        :attr:`gaussian_table`), the gradient the exact derivative of that E (continuous
        but for a jump within the gradient bound across ``(a − b)/2 = r_hi``); the model
        (:meth:`everett`, :meth:`everett_gradient`, :meth:`apply`, the generic engine) and the
        compiled engine evaluate the same kernel.
        ``nodes`` (>= 4): Gauss–Legendre nodes per cell of the quadratures that build the
        table (cached per parameter set, 0.13–0.22 s, ~13 MB). As σ_r → 0 the model tends to the
        generalized play ``GeneralizedPlay.erf(p, R)`` (paper: the thermodynamic limit).
        Support ``[−L, L]`` with ``L = p/2 + 8σ_r + 9R``.
        """
        table = gaussian_table(width, spread, width_spread, nodes)
        compiled = table.compiled
        model = cls(compiled.lower, compiled.upper)
        model._compiled_everett = compiled
        model._everett_fn = model._everett_from_table
        model._gradient_fn = model._gradient_from_table
        model._gaussian = table.parameters
        model._gaussian_table = table
        model._gaussian_arguments = (*table.parameters, positive_integer(nodes, "nodes", 4))
        kind, params, grid = compiled.kind, compiled.params, compiled.table

        def everett_scalar(a, b):
            return everett_eval(kind, params, grid, a, b)[0]

        def gradient_scalar(a, b):
            return everett_eval(kind, params, grid, a, b)[1:]

        model._fast_scalar = (everett_scalar, gradient_scalar)
        model._set_fingerprint()
        return model

    @property
    def gaussian_table(self) -> GaussianTable | None:
        """The table of a :meth:`gaussian` model (its error bounds, grid, memory), else
        ``None``."""
        return self.__dict__.get("_gaussian_table")

    def compiled_everett(self, resolution: int | None = None) -> CompiledEverett:
        """The Everett function as arrays for the compiled kernel
        :func:`~hysteresis.preisach._everett_kernels.everett_eval`.

        :meth:`gaussian`: kind 2, the separable bi-quintic table that :meth:`everett` /
        :meth:`everett_gradient` evaluate (the same function). :meth:`from_density`: kind 1, the
        model's own C¹ bicubic Hermite table (the very function :meth:`everett` evaluates).
        :meth:`from_everett`: kind 1, a table of the user's function on a ``resolution``-cell
        grid (default :data:`COMPILED_RESOLUTION`; built on first call and kept) — the model
        itself keeps evaluating the user's callable, the compiled engine integrates the table,
        which differs from it by the interpolation error bound of
        :mod:`hysteresis.preisach.everett_table` (plus the small error of the nodal
        differences, see :func:`.everett_table.everett_function_table`).
        ``resolution`` applies to :meth:`from_everett` models only.
        """
        built = self.__dict__.get("_compiled_everett")
        if built is not None:
            if resolution is not None:
                raise ValueError(
                    "resolution applies to from_everett models only (this model's Everett "
                    "function is compiled as built)"
                )
            return built
        n = COMPILED_RESOLUTION if resolution is None else resolution
        n = positive_integer(n, "resolution", minimum=2)
        bounded_work(n, "resolution", _MAX_RESOLUTION, "grid cells per side")
        cache = self.__dict__.setdefault("_compiled_tables", {})
        if n not in cache:
            table = everett_function_table(
                self._everett_fn, self._gradient_fn, self._lower, self._upper, n
            )
            cache.clear()  # keep one table (memory)
            cache[n] = CompiledEverett(KIND_TABLE, np.array([self._lower, self._upper]), table)
        return cache[n]
