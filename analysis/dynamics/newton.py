"""Newton's method on ``F(z) = 0``: the one loop of the periodic-orbit refinement
(:func:`~analysis.dynamics.periodic_orbits.refine_periodic_orbit`, damped, on ``P^k(x) − x``)
and of the continuation's corrector (:meth:`~analysis.dynamics.branch.BranchProblem.correct`,
undamped, on the bordered system ``[F(x, λ); c·(z − z_pred)]``).

Plain reading::

    evaluate z_0;  residuals = [|F(z_0)|_∞]
    for n = 0, 1, ..., max_iterations:
        converged if  |F(z_n)|_∞ <= tolerance · scale(z_n)                 (residual)
                 and  |c·(z_n − z_pred)| <= border.tolerance · (1 + |z_n|_∞)  (border row, if any)
                 and  |Δ_{n−1}|_∞ <= step_tolerance · scale(z_n)            (the last step)
                 and  converged(z_n)                                      (the caller's own)
        stop (not converged) at n = max_iterations
        solve  [DF; c] Δ = −[F; c·(z_n − z_pred)]   on the free unknowns (the others held)
        undamped:  z_{n+1} = z_n + Δ
        damped:    z_{n+1} = z_n + λΔ,  λ = 1, 1/2, ... (at most max_halvings halvings) until
                   |F(z_{n+1})|_∞ < |F(z_n)|_∞ or the residual criterion holds there

Held unknowns are those the caller leaves out of ``free`` (frozen memory: a parameter of a
family of orbits, whose row and column of ``DF`` are those of a singular direction); the
unknowns beyond ``F``'s components (the parameter λ of a bordered system) are always solved
for. The step tolerance is off by default (``inf``: the residual decides, as both callers
want); a finite one also asks for at least one step.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["Border", "Linearization", "NewtonError", "NewtonResult", "newton"]


@dataclass
class Linearization:
    """``F`` at one iterate, as :func:`newton` needs it.

    Attributes
    ----------
    residual:
        ``F(z)``: m values (without the border row).
    jacobian:
        ``() -> DF(z)`` of shape (m, n), called only when a step is taken from this iterate
        (a derivative by differences is costly).
    free:
        Indices (< m) of the unknowns solved for, which are also the rows kept; ``None``: all.
    data:
        The caller's (e.g. the integration behind ``F``; handed back in the result).
    """

    residual: np.ndarray
    jacobian: Callable[[], np.ndarray]
    free: np.ndarray | None = None
    data: Any = None


@dataclass(frozen=True)
class Border:
    """The extra row ``c·(z − origin) = 0`` of a bordered system (``c = e_λ``: the parameter
    fixed, natural continuation; ``c`` the branch tangent: pseudo-arclength), satisfied when
    ``|c·(z − origin)| <= tolerance · (1 + |z|_∞)``."""

    row: np.ndarray
    origin: np.ndarray
    tolerance: float = 1e-12

    def value(self, z: np.ndarray) -> float:
        return float(self.row @ (z - self.origin))


@dataclass
class NewtonResult:
    """The converged ``z``, its :class:`Linearization`, the residuals ``|F|_∞`` of the accepted
    iterates (last: ``z``'s) and the number of steps taken."""

    z: np.ndarray
    evaluation: Linearization
    residuals: list[float] = field(default_factory=list)
    iterations: int = 0


class NewtonError(RuntimeError):
    """Newton did not converge: ``reason`` is ``"singular"`` (the Newton matrix on the free
    unknowns), ``"stalled"`` (no decrease along a damped step after ``max_halvings``
    halvings) or ``"iterations"`` (``max_iterations`` steps without convergence);
    ``residuals`` as in :class:`NewtonResult`."""

    def __init__(self, reason: str, residuals: list[float]) -> None:
        trace = ", ".join(f"{r:.2e}" for r in residuals)
        super().__init__(f"Newton {reason} (residuals {trace})")
        self.reason = reason
        self.residuals = tuple(residuals)


def _norm(x: np.ndarray) -> float:
    return float(np.max(np.abs(x)))


def _default_scale(z: np.ndarray) -> float:
    """``max(1, |z|_∞)``."""
    return max(1.0, _norm(z))


def _step(ev: Linearization, z: np.ndarray, border: Border | None) -> np.ndarray:
    """The Newton step on the free unknowns (and the border's), the held ones 0."""
    r = ev.residual
    m, n = r.size, z.size
    a = ev.jacobian()
    if border is None:
        mat, rhs = a, r
    else:
        mat = np.zeros((n, n))
        mat[:m] = a
        mat[m] = border.row
        rhs = np.append(r, border.value(z))
    free = np.arange(m) if ev.free is None else ev.free
    keep = np.append(free, np.arange(m, n)) if n > m else free
    dz = np.zeros(n)
    dz[keep] = np.linalg.solve(mat[np.ix_(keep, keep)], -rhs[keep])
    return dz


def newton(
    evaluate: Callable[[np.ndarray, Linearization | None], Linearization],
    z0: np.ndarray,
    *,
    tolerance: float,
    max_iterations: int,
    scale: Callable[[np.ndarray], float] = _default_scale,
    max_halvings: int | None = None,
    step_tolerance: float = math.inf,
    border: Border | None = None,
    converged: Callable[[np.ndarray, Linearization], bool] | None = None,
    trial_failures: tuple[type[BaseException], ...] = (),
) -> NewtonResult:
    """Solve ``F(z) = 0`` from ``z0`` (module docstring).

    Parameters
    ----------
    evaluate:
        ``(z, previous) -> Linearization``: ``F`` at ``z``; ``previous`` is the accepted
        iterate's (``None`` for ``z0``), e.g. to carry a discrete state along. Its exceptions
        propagate, except those in ``trial_failures`` at a damped trial point.
    tolerance:
        Residual tolerance: converged when ``|F(z)|_∞ <= tolerance · scale(z)``.
    max_iterations:
        Most Newton steps (the residual is tested ``max_iterations + 1`` times).
    scale:
        The size a residual (and a step) is measured against; default ``max(1, |z|_∞)``.
    max_halvings:
        ``None``: undamped (every full step is taken); else the step is halved at most this
        many times while the residual does not decrease.
    step_tolerance:
        Also require the last step ``|Δ|_∞ <= step_tolerance · scale(z)`` (default ``inf``:
        not tested).
    border:
        A :class:`Border` row appended to ``F`` (then ``z`` has one more unknown than ``F``
        has components); ``None``: ``F`` is square.
    converged:
        ``(z, linearization) -> bool``, a further condition of convergence (tested last, only
        when the others hold), e.g. that a discrete state closed on itself.
    trial_failures:
        Exceptions of ``evaluate`` at a damped trial point that count as an infinite residual
        (the step is halved).

    Raises
    ------
    NewtonError
        Singular Newton matrix, a stalled damped step, or no convergence in
        ``max_iterations`` steps.
    """
    tolerance = float(tolerance)
    if not (tolerance > 0.0 and math.isfinite(tolerance)):
        raise ValueError(f"tolerance must be finite and > 0, got {tolerance}")
    if not step_tolerance > 0.0:
        raise ValueError(f"step_tolerance must be > 0, got {step_tolerance}")
    if max_iterations < 0:
        raise ValueError(f"max_iterations must be >= 0, got {max_iterations}")
    if max_halvings is not None and max_halvings < 0:
        raise ValueError(f"max_halvings must be None or >= 0, got {max_halvings}")
    z = np.array(z0, dtype=np.float64)
    ev = evaluate(z, None)
    res = _norm(ev.residual)
    extra = z.size - ev.residual.size
    if extra != (0 if border is None else 1):
        raise ValueError(
            f"z has {z.size} unknowns for {ev.residual.size} residuals"
            + (" and one border row" if border is not None else "")
        )
    residuals = [res]
    last_step = math.inf
    for n in range(max_iterations + 1):
        if (
            res <= tolerance * scale(z)
            and (
                border is None
                or abs(border.value(z)) <= border.tolerance * (1.0 + float(np.max(np.abs(z))))
            )
            and last_step <= step_tolerance * scale(z)
            and (converged is None or converged(z, ev))
        ):
            return NewtonResult(z, ev, residuals, n)
        if n == max_iterations:
            break
        try:
            dz = _step(ev, z, border)
        except np.linalg.LinAlgError:
            raise NewtonError("singular", residuals) from None
        if max_halvings is None:
            z = z + dz
            ev = evaluate(z, ev)
            res = _norm(ev.residual)
            last_step = _norm(dz)
        else:
            lam = 1.0
            for _halving in range(max_halvings + 1):
                trial = z + lam * dz
                try:
                    t_ev = evaluate(trial, ev)
                    t_res = _norm(t_ev.residual)
                except trial_failures:
                    t_res = math.inf
                if t_res < res or t_res <= tolerance * scale(trial):
                    break
                lam *= 0.5
            else:
                raise NewtonError("stalled", residuals)
            z, ev, res, last_step = trial, t_ev, t_res, lam * _norm(dz)
        residuals.append(res)
    raise NewtonError("iterations", residuals)
