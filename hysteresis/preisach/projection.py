"""Projection of an identified (noisy, partly negative) Preisach density onto a valid model.

An identification from measured reversal curves gives the Everett function ``E(α_k, β_l)`` on
a lattice of nodes and the cell masses ``m_ij`` as its mixed second differences. Noise makes
some masses negative, so they are not the weights of a Preisach model. The projection used
here is the non-negative least-squares problem on the cell masses

    minimise  Σ_{(k, l) measured} ( Σ_{cells (i, j) ⊂ {β_l < β' <= α' <= α_k}} m_ij − E_kl )²
    subject to m_ij >= 0,

i.e. the non-negative masses whose Everett function (hence whose reversal curves, since
``E = ½ (output change after the reversal)``) is closest to the measured one. The residual is a
sum over measured nodes only: where the lattice has no data, nothing is imposed. Each cell's
mass becomes one relay at the cell's upper corner ``(α_hi, min(β_hi, α_hi))``: for inputs on the
lattice nodes a relay anywhere in the half-open cell ``(α_lo, α_hi] × (β_lo, β_hi]`` switches
exactly like that corner relay, so the model reproduces every node-input history of the cell
masses exactly; between nodes it is the lattice's staircase. Cells touching the diagonal give
zero-width relays (the reversible part of a measured sample).

Solvers: up to 2500 cells Lawson–Hanson on the explicit matrix (``scipy.optimize.nnls``).
Above, when the fitted nodes are exactly the nodes of the physical cells (FORCs measured on a
common grid: the native grid), the Everett map is square and invertible — its inverse is
Mayergoyz's mixed second difference, a sparse matrix ``D`` — and the NNLS is the dual problem
``min_{g >= 0} ½ gᵀ D Dᵀ g + (D E)ᵀ g`` with a sparse Hessian, solved by an active-set method
with sparse LU solves (a few hundred nodes: tens of thousands of cells, seconds); otherwise
matrix-free block principal pivoting. All stop on the KKT conditions
(:data:`KKT_TOLERANCE`). For a Preisach operator's own FORCs the second differences are its
weights and are non-negative: the projection returns them unchanged (exact identification).

The model is normalised: weights ``w = m / K`` with the scale ``K = Σ m`` (half the output
swing between the saturations), so that ``output ≈ offset + K · M[u]`` with ``M`` the model's
output in ``[−1, 1]``.

This module must not import :mod:`analysis`: the identification result is duck-typed (it needs
``alpha``, ``beta``, ``everett`` and optionally ``measured``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from hysteresis.preisach.base import PreisachModel

__all__ = ["PreisachProjection", "project_identification"]

_DENSE_LIMIT = 2500  # cells; above, the sparse second-difference solve or block pivoting
#: Convergence criterion of the large-problem solver: the KKT conditions of the NNLS problem
#: (x >= 0, g = Aᵀ(Ax − b) >= 0, x·g = 0) hold to this fraction of ‖Aᵀb‖∞ (the gradient's scale
#: at x = 0). Lawson–Hanson (the dense path) meets them exactly.
KKT_TOLERANCE = 1e-9


@dataclass(frozen=True, eq=False)
class PreisachProjection:
    """Result of :func:`project_identification`.

    Attributes
    ----------
    alpha, beta:
        Thresholds of the relays with positive mass (``alpha >= beta``).
    weights:
        Their normalised weights (``>= 0``, sum 1).
    scale:
        ``K = Σ m``: outputs are ``offset + K · M[u]``.
    masses:
        The fitted non-negative cell masses, shape of the identification's ``cell_mass`` (0 for
        unphysical cells).
    residual_rms:
        Root-mean-square misfit of the Everett function over the fitted nodes.
    n_nodes:
        Number of nodes fitted.
    """

    alpha: np.ndarray
    beta: np.ndarray
    weights: np.ndarray
    scale: float
    masses: np.ndarray
    residual_rms: float
    n_nodes: int

    def model(self) -> PreisachModel:
        """The :class:`~hysteresis.preisach.DiscretePreisachModel` of the relays."""
        return PreisachModel.from_relays(self.alpha, self.beta, self.weights)


def _everett_apply(masses: np.ndarray) -> np.ndarray:
    """``E[k, l] = Σ_{i < k, j >= l} M[i, j]`` on the (n_a + 1) × (n_b + 1) nodes."""
    n_a, n_b = masses.shape
    out = np.zeros((n_a + 1, n_b + 1))
    suffix = np.cumsum(masses[:, ::-1], axis=1)[:, ::-1]  # Σ_{j >= l}
    out[1:, :n_b] = np.cumsum(suffix, axis=0)
    return out


def _everett_adjoint(resid: np.ndarray) -> np.ndarray:
    """Adjoint of :func:`_everett_apply`: ``G[i, j] = Σ_{k > i, l <= j} R[k, l]``."""
    r = resid[1:, :-1]
    rev = np.cumsum(r[::-1, :], axis=0)[::-1, :]  # Σ_{k > i}
    return np.cumsum(rev, axis=1)  # Σ_{l <= j}


def project_identification(
    result: Any,
    *,
    use_measured_only: bool = True,
    max_iter: int | None = None,
) -> PreisachProjection:
    """Non-negative least-squares projection of an identification onto a discrete model.

    Parameters
    ----------
    result:
        Any object with ``alpha`` (n_a + 1 ascending nodes), ``beta`` (n_b + 1), ``everett``
        (shape (n_a + 1, n_b + 1)) and optionally ``measured`` (boolean mask of the nodes backed
        by data) — e.g. :class:`analysis.identification.PreisachIdentification`.
    use_measured_only:
        Fit only the nodes of ``measured`` (when present); otherwise every node with
        ``β < α``.
    max_iter:
        Limit of the exchange steps of the solvers used above 2500 cells (block principal
        pivoting, default 200); they stop when the KKT conditions hold to
        :data:`KKT_TOLERANCE` relative and raise if that is not reached within the limit.
        When every node with ``β < α`` is fitted and the nodes match the cells one to one (the
        native grid of FORCs on a common grid: a square system), the problem is solved as the
        sparse linear complementarity problem of the cells' second differences
        (``_second_difference_nnls``, grids of a few hundred nodes in seconds); otherwise
        matrix-free (``_block_pivoting_nnls``).

    Returns
    -------
    PreisachProjection

    Raises
    ------
    ValueError
        If the arrays are inconsistent, non-finite on fitted nodes, or the fit has no mass.
    RuntimeError
        If the large-problem solver does not meet its convergence criterion within ``max_iter``.
    """

    alpha = np.asarray(getattr(result, "alpha", None), dtype=float)
    beta = np.asarray(getattr(result, "beta", None), dtype=float)
    E = np.asarray(getattr(result, "everett", None), dtype=float)
    if alpha.ndim != 1 or beta.ndim != 1 or alpha.size < 2 or beta.size < 2:
        raise ValueError("result.alpha and result.beta must be 1-D with at least two nodes")
    if E.shape != (alpha.size, beta.size):
        raise ValueError(f"result.everett must have shape {(alpha.size, beta.size)}, got {E.shape}")
    if np.any(np.diff(alpha) <= 0) or np.any(np.diff(beta) <= 0):
        raise ValueError("result.alpha and result.beta must be strictly increasing")
    aa, bb = np.meshgrid(alpha, beta, indexing="ij")
    rows = bb < aa
    measured = getattr(result, "measured", None)
    if use_measured_only and measured is not None:
        measured = np.asarray(measured, dtype=bool)
        if measured.shape != E.shape:
            raise ValueError("result.measured must have the shape of result.everett")
        rows &= measured
    if not np.all(np.isfinite(E[rows])):
        raise ValueError("result.everett must be finite on the fitted nodes")
    n_rows = int(rows.sum())
    if n_rows == 0:
        raise ValueError("no node with β < α to fit")
    a_hi = alpha[1:, None] + 0.0 * beta[None, :-1]
    b_lo = beta[None, :-1] + 0.0 * alpha[1:, None]
    cells = a_hi > b_lo  # cells with a physical part β <= α
    n_cells = int(cells.sum())
    target = E[rows]

    def forward(x: np.ndarray) -> np.ndarray:
        m = np.zeros(cells.shape)
        m[cells] = np.ravel(x)
        return _everett_apply(m)[rows]

    def adjoint(r: np.ndarray) -> np.ndarray:
        full = np.zeros(E.shape)
        full[rows] = np.ravel(r)
        return _everett_adjoint(full)[cells]

    if n_cells <= _DENSE_LIMIT:
        # scipy.optimize costs ~0.2 s at import: loaded where used (fast `hyst` start)
        from scipy.optimize import nnls

        mat = np.empty((n_rows, n_cells))
        unit = np.zeros(n_cells)
        for c in range(n_cells):
            unit[c] = 1.0
            mat[:, c] = forward(unit)
            unit[c] = 0.0
        x, _ = nnls(mat, target, maxiter=50 * n_cells)
    else:
        diff = _second_difference(rows, cells, forward)
        if diff is not None:
            x = _second_difference_nnls(diff, forward, adjoint, target, max_iter)
        else:
            x = _block_pivoting_nnls(forward, adjoint, target, n_cells, max_iter)
    masses = np.zeros(cells.shape)
    masses[cells] = x
    resid = forward(x) - target
    total = float(x.sum())
    if not total > 0:
        raise ValueError("the projection has no positive mass (is the Everett function flat?)")
    keep = masses > 0
    a_rel = (alpha[1:, None] + 0.0 * beta[None, 1:])[keep]
    b_rel = np.minimum((beta[None, 1:] + 0.0 * alpha[1:, None])[keep], a_rel)
    w = masses[keep] / total
    w = w / w.sum()  # exact normalisation against round-off
    masses.setflags(write=False)
    return PreisachProjection(
        alpha=a_rel,
        beta=b_rel,
        weights=w,
        scale=total,
        masses=masses,
        residual_rms=float(np.sqrt(np.mean(resid**2))),
        n_nodes=n_rows,
    )


def _block_pivoting_nnls(
    forward: Any, adjoint: Any, target: np.ndarray, n: int, max_iter: int | None
) -> np.ndarray:
    """``argmin ‖A x − b‖ subject to x >= 0`` for a matrix-free ``A`` (Kim & Park 2011).

    Block principal pivoting: split the variables into a free set ``F`` and a set ``G`` held
    at zero; solve the unconstrained least squares on ``F`` (LSMR to round-off), form the
    gradient ``y = Aᵀ(A x − b)`` on ``G``; the infeasible variables (``x_F < 0`` or
    ``y_G < 0``) change sides — all of them while their number falls, after three steps
    without progress only the one of largest index (this rule makes the method terminate).
    Stops when the KKT conditions hold to :data:`KKT_TOLERANCE` relative to ``‖Aᵀb‖∞``.
    """
    # scipy.sparse.linalg is heavy at import: loaded where used (fast `hyst` start)
    from scipy.sparse.linalg import LinearOperator, lsmr

    limit = 200 if max_iter is None else int(max_iter)
    if limit < 1:
        raise ValueError(f"max_iter must be a positive integer, got {max_iter!r}")
    scale = float(np.max(np.abs(adjoint(target))))
    if scale == 0.0:
        return np.zeros(n)
    tol = KKT_TOLERANCE * scale
    x = np.zeros(n)
    free = adjoint(-target) < 0.0  # the variables the gradient at x = 0 wants to raise
    n_infeasible, backup = n + 1, 3
    for _ in range(limit):
        idx = np.flatnonzero(free)
        x = np.zeros(n)
        if idx.size:

            def sub_forward(z: np.ndarray, idx: np.ndarray = idx) -> np.ndarray:
                full = np.zeros(n)
                full[idx] = z
                return forward(full)

            def sub_adjoint(r: np.ndarray, idx: np.ndarray = idx) -> np.ndarray:
                return adjoint(r)[idx]

            sub = LinearOperator(
                (target.size, idx.size), matvec=sub_forward, rmatvec=sub_adjoint, dtype=float
            )
            x[idx] = lsmr(sub, target, atol=1e-15, btol=1e-15, maxiter=50 * n)[0]
        grad = adjoint(forward(x) - target)
        bad = (free & (x < 0.0)) | (~free & (grad < -tol))
        if not bad.any():
            # KKT: on F the gradient vanishes (to the LSMR solve), on G it is >= −tol
            violation = float(np.max(np.abs(grad[free]), initial=0.0))
            if violation <= tol:
                return np.maximum(x, 0.0)
            raise RuntimeError(
                "the NNLS projection's least-squares solve did not reach the KKT tolerance "
                f"(gradient {violation / scale:.2e} of its scale on the free set, criterion "
                f"{KKT_TOLERANCE:g})"
            )
        k = int(bad.sum())
        if k < n_infeasible:
            n_infeasible, backup = k, 3
            free ^= bad
        elif backup > 0:
            backup -= 1
            free ^= bad
        else:
            last = int(np.flatnonzero(bad)[-1])
            free[last] = not free[last]
    raise RuntimeError(
        f"the NNLS projection did not converge within max_iter = {limit} exchange steps "
        f"(KKT tolerance {KKT_TOLERANCE:g}); pass a larger max_iter"
    )


def _second_difference(rows: np.ndarray, cells: np.ndarray, forward: Any) -> Any:
    """The inverse ``D`` of the Everett map as a sparse matrix, or ``None`` if it has none.

    When the fitted nodes are exactly the nodes ``(i + 1, j)`` of the physical cells ``(i, j)``
    (and every other node's Everett value is identically zero: the nodes with ``β >= α`` and
    the first row), the map ``x → E[rows]`` is square and its inverse is Mayergoyz's mixed
    second difference ``m_ij = E[i+1, j] − E[i, j] − E[i+1, j+1] + E[i, j+1]`` (entries ±1,
    four per row). The inverse is checked on a random vector (``None`` if it fails).
    """
    # scipy.sparse is heavy at import: loaded where used (fast `hyst` start)
    from scipy.sparse import csr_matrix

    n_cells, n_rows = int(cells.sum()), int(rows.sum())
    if n_cells != n_rows:
        return None
    index = np.full((rows.shape[0] + 1, rows.shape[1] + 1), -1, dtype=np.int64)
    index[:-1, :-1][rows] = np.arange(n_rows)
    ci, cj = np.nonzero(cells)  # the row-major order of masses[cells]
    cols = np.stack([index[ci + 1, cj], index[ci, cj], index[ci + 1, cj + 1], index[ci, cj + 1]])
    vals = np.array([1.0, -1.0, -1.0, 1.0])[:, None] * np.ones(n_cells)
    keep = cols >= 0  # a node outside the fit has E = 0 identically (checked below)
    who = np.broadcast_to(np.arange(n_cells), cols.shape)
    diff = csr_matrix((vals[keep], (who[keep], cols[keep])), shape=(n_cells, n_rows))
    z = np.random.default_rng(0).random(n_cells)  # a fixed probe, not a random quantity
    if not np.allclose(diff @ forward(z), z, rtol=0.0, atol=1e-9 * n_cells):
        return None
    return diff


def _second_difference_nnls(
    diff: Any, forward: Any, adjoint: Any, target: np.ndarray, max_iter: int | None
) -> np.ndarray:
    """``argmin ‖A x − b‖ subject to x >= 0`` for an invertible ``A`` with sparse ``D = A⁻¹``.

    With the gradient ``g = Aᵀ(Ax − b)``: ``Ax − b = Dᵀg``, so ``x = q + M g`` with the exact
    cell masses ``q = D b`` and the sparse positive definite ``M = D Dᵀ`` (small integers): the
    KKT conditions ``x >= 0, g >= 0, x·g = 0`` are those of the dual problem
    ``min_{g >= 0} ½ gᵀMg + qᵀg`` (gradient ``x``). It is solved by the Lawson–Hanson active
    set method on ``g`` (every cell with ``x < 0`` enters the set of clamped cells at once,
    one at a time — the most negative — when that made no progress, which keeps the method
    finite), each subspace solve ``M_SS g_S = −q_S`` a sparse LU with iterative refinement
    (exact residuals: ``M`` is integer). A Preisach operator's data (``q >= 0``) need no step
    and give ``x = q``, Mayergoyz's identification. The KKT conditions are checked with the
    original operators to :data:`KKT_TOLERANCE` relative to ``‖Aᵀb‖∞``.
    """
    # scipy.sparse.linalg is heavy at import: loaded where used (fast `hyst` start)
    from scipy.sparse.linalg import splu

    limit = 200 if max_iter is None else int(max_iter)
    if limit < 1:
        raise ValueError(f"max_iter must be a positive integer, got {max_iter!r}")
    n = diff.shape[0]
    q = diff @ target
    scale = float(np.max(np.abs(adjoint(target))))
    if scale == 0.0:
        return np.zeros(n)
    tol = KKT_TOLERANCE * scale
    tol_x = KKT_TOLERANCE * max(float(np.max(np.abs(q))), np.finfo(float).tiny)
    mat = (diff @ diff.T).tocsr()

    def subspace(idx: np.ndarray) -> np.ndarray:
        sub = mat[idx][:, idx].tocsc()
        lu = splu(
            sub, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True}
        )
        z = lu.solve(-q[idx])
        for _refine in range(3):  # M is ill-conditioned (~n⁴); its residual is exact
            z += lu.solve(-q[idx] - sub @ z)
        return z

    g = np.zeros(n)
    clamped = np.zeros(n, dtype=bool)
    x = q.copy()
    objective, single = 0.0, False
    for _ in range(limit):
        viol = ~clamped & (x < -tol_x)
        if not viol.any():
            x[clamped | (x <= tol_x)] = 0.0  # round-off of exactly empty cells, too
            grad = adjoint(forward(x) - target)
            worst = max(-float(np.min(grad)), float(np.max(np.abs(grad[x > tol_x]), initial=0.0)))
            if worst <= tol:
                return x
            raise RuntimeError(
                "the NNLS projection's sparse active-set solve did not reach the KKT tolerance "
                f"({worst / scale:.2e} of the gradient's scale, criterion {KKT_TOLERANCE:g})"
            )
        if single:
            viol = np.zeros(n, dtype=bool)
            viol[int(np.argmin(np.where(clamped, np.inf, x)))] = True
        clamped |= viol
        for _inner in range(n):
            idx = np.flatnonzero(clamped)
            z = np.zeros(n)
            z[idx] = subspace(idx)
            low = clamped & (z <= 0.0)
            if not low.any():
                g = z
                break
            # move from the feasible g towards z until the first clamped g reaches zero; that
            # one (and any other reaching zero) leaves the clamped set
            where = np.flatnonzero(low)
            gap = g[where] - z[where]  # >= 0; 0 only where g = z = 0 (blocks at once)
            ratio = np.divide(g[where], gap, out=np.zeros(where.size), where=gap > 0)
            t = float(np.min(ratio))
            g = np.maximum(g + t * (z - g), 0.0)
            drop = low & (g <= 0.0)
            drop[where[np.argmin(ratio)]] = True
            g[drop] = 0.0
            clamped &= ~drop
        x = q + mat @ g
        new = float(0.5 * g @ (mat @ g) + q @ g)
        single = not new < objective  # no progress: the next step adds one cell only
        objective = min(objective, new)
    raise RuntimeError(
        f"the NNLS projection did not converge within max_iter = {limit} active-set steps "
        f"(KKT tolerance {KKT_TOLERANCE:g}); pass a larger max_iter"
    )
