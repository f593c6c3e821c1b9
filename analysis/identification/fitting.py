"""Identification from arbitrary input/output records (not only reversal curves).

Control engineers measure an actuator with whatever excitation is convenient: a record of
inputs ``u_t`` and outputs ``y_t``. Both models here are linear in their weights once the
input record is fixed, so the identification is a constrained linear least-squares problem:

* :func:`fit_preisach_record` — a discrete Preisach model on a lattice: one relay per lattice
  cell (the corner relays of :mod:`hysteresis.preisach.projection`),
  ``y_t ≈ c + Σ_k m_k r_k(t)`` with the relay outputs ``r_k(t) ∈ {−1, +1}`` computed from the
  input record and ``m_k >= 0``.
* :func:`fit_bouc_wen`, :func:`fit_jiles_atherton` — the differential models, nonlinear in their
  parameters (:mod:`analysis.identification.differential_fits`, re-exported here).
* :func:`fit_prandtl_ishlinskii` — a Prandtl–Ishlinskii operator,
  ``y_t ≈ c + Σ_i a_i F_{p_i}[u]_t`` with plays of given widths (width 0 = the linear term).
  The weights may be negative (a saturating actuator needs them: its loading curve is
  concave) but every partial sum ``A_i = a_0 + … + a_i`` is kept ``>= a_min > 0``, the exact
  condition for the inverse :meth:`hysteresis.PrandtlIshlinskii.inverse` to exist: the fit is
  a bound-constrained least-squares problem in the partial sums,
  ``y ≈ c + Σ_i A_i (F_{p_i} − F_{p_{i+1}})`` (``F_{p_{n+1}} = 0``). See
  ``examples/compensate_actuator.py``.

Train/validation split: the record is split in time; the operators are driven through the
whole record (their memory at the start of the validation part is the one the training inputs
left), the weights are fitted on the first ``train_fraction`` of the samples and the root-mean-
square error is reported on both parts. Initial memory: every relay down (the record is taken
to start after negative saturation), every play in ``initial_state(u_0)`` (rising from −∞);
start a record with a saturating excursion, or discard its beginning, if that is not so.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from analysis.identification._record_fit import RecordFit, check_record, fit_result
from analysis.identification.differential_fits import fit_bouc_wen, fit_jiles_atherton
from hysteresis._validation import real_array
from hysteresis.prandtl_ishlinskii import PrandtlIshlinskii
from hysteresis.preisach import DiscretePreisachModel

__all__ = [
    "RecordFit",
    "fit_bouc_wen",
    "fit_jiles_atherton",
    "relay_outputs",
    "fit_preisach_record",
    "fit_prandtl_ishlinskii",
]


def relay_outputs(u: Any, alpha: Any, beta: Any, initial: int = -1) -> np.ndarray:
    """Outputs of relays ``(α_k, β_k)`` along the input record ``u``, shape (len(u), K).

    Relay convention of the toolkit: +1 once ``u >= α``, −1 once ``u < β``, otherwise the last
    value; ``initial`` (−1 or +1) before the first switching. Vectorised: the last up-event
    and the last down-event of every relay are running maxima over time.
    """
    u = real_array(u, "u")
    a = real_array(alpha, "alpha")
    b = real_array(beta, "beta")
    if initial not in (-1, 1):
        raise ValueError(f"initial must be -1 or +1, got {initial!r}")
    t = np.arange(1, u.size + 1)[:, None]
    up = np.maximum.accumulate(np.where(u[:, None] >= a[None, :], t, 0), axis=0)
    down = np.maximum.accumulate(np.where(u[:, None] < b[None, :], t, 0), axis=0)
    out = np.where(up > down, 1.0, -1.0)
    out[(up == 0) & (down == 0)] = float(initial)
    return out


def fit_preisach_record(
    u: Any,
    y: Any,
    nodes: Any,
    *,
    train_fraction: float = 0.7,
) -> RecordFit:
    """Fit a discrete Preisach model on the lattice ``nodes`` to a record ``(u, y)``.

    Parameters
    ----------
    u, y:
        Input and output samples (1-D, same length, finite).
    nodes:
        Strictly increasing lattice (both thresholds); one relay per cell
        ``(α_{i−1}, α_i] × (β_{j−1}, β_j]`` with ``j <= i``, at its corner ``(α_i, β_j)``. Inputs
        beyond the lattice saturate it.
    train_fraction:
        Fraction (0, 1] of the record, from its start, used for the fit.

    Returns
    -------
    RecordFit
        ``model`` normalised (weights sum 1), ``y ≈ offset + scale · model(u)``.
    """
    u, y, n_train = check_record(u, y, train_fraction)
    x = np.asarray(nodes, dtype=float)
    if x.ndim != 1 or x.size < 2 or np.any(np.diff(x) <= 0) or not np.all(np.isfinite(x)):
        raise ValueError("nodes must be a strictly increasing 1-D array of >= 2 finite values")
    i, j = np.tril_indices(x.size - 1)
    alpha, beta = x[1:][i], x[1:][j]
    if alpha.size > 20000:
        raise ValueError(f"nodes give {alpha.size} cells (> 20000); use a coarser lattice")
    # relays switch at the input crossing; node-valued relays on a lattice of the data suffice
    relays = relay_outputs(u, alpha, beta)
    design = np.column_stack([np.ones(u.size), relays])
    coef = _bounded_lstsq(design[:n_train], y[:n_train], np.zeros(alpha.size))
    masses = np.maximum(coef[1:], 0.0)
    total = float(masses.sum())
    if not total > 0:
        raise ValueError("the fit has no positive relay mass (is y independent of u?)")
    keep = masses > 0
    w = masses[keep] / total
    model = DiscretePreisachModel(alpha[keep], beta[keep], w / w.sum())
    pred = design @ np.concatenate([[coef[0]], masses])
    return fit_result(model, float(coef[0]), total, pred, y, n_train)


def fit_prandtl_ishlinskii(
    u: Any,
    y: Any,
    widths: Any,
    *,
    train_fraction: float = 0.7,
    min_partial_sum: float | None = None,
) -> RecordFit:
    """Fit Prandtl–Ishlinskii weights to a record ``(u, y)`` by constrained least squares.

    Parameters
    ----------
    u, y:
        Input and output samples (1-D, same length, finite).
    widths:
        Distinct play widths ``p_i >= 0``; a width 0 (the linear term) is added if missing.
    train_fraction:
        Fraction (0, 1] of the record, from its start, used for the fit.
    min_partial_sum:
        Lower bound ``a_min > 0`` of every partial sum ``a_0 + … + a_i`` (default
        ``10⁻³ · ptp(y)/ptp(u)``): the fitted operator is invertible, with the slope of its
        inverse bounded by ``1/a_min``.

    Returns
    -------
    RecordFit
        ``model`` a :class:`~hysteresis.PrandtlIshlinskii`, ``y ≈ offset + model(u)``;
        ``parameters`` the offset and the weights ``a_i`` of the widths ``model.widths``, with
        their ``standard_errors`` (``s²(XᵀX)⁻¹`` of the linear regression, conditional on the
        partial sums held at their bound).
    """
    u, y, n_train = check_record(u, y, train_fraction)
    p = np.asarray(widths, dtype=float).ravel()
    if p.size == 0 or not np.all(np.isfinite(p)) or np.any(p < 0):
        raise ValueError("widths must be a non-empty sequence of finite values >= 0")
    p = np.unique(np.concatenate([[0.0], p]))
    span_u = float(np.ptp(u))
    if span_u == 0.0:
        raise ValueError("u must vary (a constant input identifies nothing)")
    if min_partial_sum is None:
        min_partial_sum = 1e-3 * max(float(np.ptp(y)), 1e-300) / span_u
    if not (math.isfinite(min_partial_sum) and min_partial_sum > 0):
        raise ValueError(f"min_partial_sum must be > 0, got {min_partial_sum!r}")
    plays = np.column_stack(
        [PrandtlIshlinskii([w], [1.0]).apply(u)[0] for w in p]  # F_p[u] from initial_state(u0)
    )
    # y = c + Σ a_i F_i = c + Σ A_i (F_i − F_{i+1}) with A_i the partial sums
    diffs = plays - np.column_stack([plays[:, 1:], np.zeros(u.size)])
    design = np.column_stack([np.ones(u.size), diffs])
    coef = _bounded_lstsq(design[:n_train], y[:n_train], np.full(p.size, min_partial_sum))
    partial = np.maximum(coef[1:], min_partial_sum)
    weights = np.diff(np.concatenate([[0.0], partial]))
    model = PrandtlIshlinskii(p, weights)
    pred = design @ np.concatenate([[coef[0]], partial])
    errors = _linear_errors(
        design[:n_train], y[:n_train] - pred[:n_train], partial, min_partial_sum
    )
    names = ["offset", *(f"a_{i}" for i in range(p.size))]
    return fit_result(
        model,
        float(coef[0]),
        1.0,
        pred,
        y,
        n_train,
        parameters=dict(zip(names, [float(coef[0]), *weights.tolist()], strict=True)),
        standard_errors=dict(zip(names, errors.tolist(), strict=True)),
    )


def _linear_errors(
    design: np.ndarray, residuals: np.ndarray, partial: np.ndarray, lower: float
) -> np.ndarray:
    """Standard errors of ``(offset, a_0, …, a_K)`` of the partial-sum regression
    ``y ≈ c + Σ A_i D_i``: ``s²(XᵀX)⁻¹`` over the offset and the partial sums off their bound
    (those at the bound held fixed: the errors are conditional on the active set), carried to
    the weights ``a_i = A_i − A_{i−1}`` linearly."""
    free = np.concatenate([[True], partial > lower * (1.0 + 1e-9)])
    x = design[:, free]
    dof = max(design.shape[0] - x.shape[1], 1)
    s2 = float(residuals @ residuals) / dof
    cov_free = s2 * np.linalg.pinv(x.T @ x)
    cov = np.zeros((free.size, free.size))
    cov[np.ix_(free, free)] = cov_free
    # (c, A_0..A_K) -> (c, a_0..a_K): a_i = A_i − A_{i−1}
    t = np.eye(free.size)
    t[np.arange(2, free.size), np.arange(1, free.size - 1)] = -1.0
    return np.sqrt(np.maximum(np.diag(t @ cov @ t.T), 0.0))


def _bounded_lstsq(design: np.ndarray, y: np.ndarray, lower: np.ndarray) -> np.ndarray:
    """``min |design·x − y|`` with ``x[0]`` free (the offset) and ``x[1:] >= lower``.

    Active-set NNLS (Lawson–Hanson, exact) after the substitutions ``x[1:] = lower + z`` and
    ``x[0] = c⁺ − c⁻``.
    """
    shifted = y - design[:, 1:] @ lower
    aug = np.column_stack([design[:, :1], -design[:, :1], design[:, 1:]])
    from scipy.optimize import nnls  # heavy at import: loaded where used (fast `hyst` start)

    z, _ = nnls(aug, shifted, maxiter=50 * aug.shape[1])
    return np.concatenate([[z[0] - z[1]], lower + z[2:]])
