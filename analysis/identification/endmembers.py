"""The linear algebra of FORC unmixing: PCA, the number of end-members, the simplex, proportions.

A sample series is a matrix ``X`` (``n`` samples × ``p`` nodes of a common FORC lattice). The
linear mixing model is ``X_i = Σ_k p_ik · D_k + noise`` with ``p_ik >= 0``, ``Σ_k p_ik = 1`` and
``m`` end-member diagrams ``D_k``: the samples lie in the ``(m − 1)``-dimensional affine hull of
the end-members, i.e. in the span of the mean and the first ``m − 1`` principal components
(FORC-PCA, Harrison et al. 2018), inside the simplex whose vertices are the end-members.

* :func:`principal_components`: PCA of the centred series through the eigenvectors of the
  ``n × n`` Gram matrix ``X_c X_cᵀ = U S² Uᵀ`` (loadings ``V = X_cᵀ U S⁻¹``, scores ``U S``): the
  SVD of ``X_c`` at ``O(n² p)`` for ``p ≫ n``; signs fixed by the loadings (the largest
  ``|entry|`` positive), so that the result does not depend on the order of the samples.
* :func:`component_test`: the number of end-members from the noise. After the mean and ``q``
  components the residual of pure noise lies in the ``(n − 1 − q)``-dimensional complement in
  sample space, so ``E Σ (R/se)² ≈ (n − 1 − q)·p``: the statistic
  ``χ²_q = Σ (R/se)² / ((n − 1 − q) p)`` is ≈ 1 once every component above the noise is in the
  model and larger before. Its standard deviation is ``sqrt(2/ν)`` with ``ν = (n − 1 − q)·p_eff``
  independent values, ``p_eff`` the lattice nodes per smoothing window (the smoothed density is
  correlated over a window); the smallest ``m = q + 1`` with ``χ²_q <= 1 + 3·sqrt(2/ν)`` is
  chosen.
* :func:`nfindr`: the simplex of largest volume spanned by ``m`` samples in the space of the
  first ``m − 1`` scores (N-FINDR, Winter 1999), grown vertex by vertex from the sample
  farthest from the centroid and then improved by single-vertex exchanges until no exchange
  enlarges it: a deterministic function of the point set, whatever the order of the samples.
* :func:`simplex_proportions`: fully constrained least squares, ``min ‖t − pᵀV‖²`` over
  ``p >= 0``, ``Σ p = 1`` (NNLS with the sum as a heavily weighted extra row, Heinz & Chang
  2001): the barycentric coordinates inside the simplex, the nearest point of the simplex
  outside it.
* :func:`bootstrap_proportions`: a parametric bootstrap of the proportions over the per-node
  standard errors (independent Gaussian noise of standard deviation ``se`` at every node). The
  noise enters the proportions only through the scores, so the replicates draw the score noise
  exactly, ``N(0, Vᵀ diag(se_i²) V)`` per sample, instead of ``p`` node values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "PrincipalComponents",
    "principal_components",
    "component_test",
    "nfindr",
    "simplex_volume",
    "simplex_proportions",
    "bootstrap_proportions",
    "ACCEPT_Z",
]

#: the k-choice accepts ``χ²_q <= 1 + ACCEPT_Z·sqrt(2/ν)`` (module docstring)
ACCEPT_Z = 3.0
#: weight of the sum-to-one row of the constrained least squares, relative to the scale of the
#: vertices: the sum is then met to ~1e-12 before the final renormalisation
_SUM_WEIGHT = 1e6


@dataclass(frozen=True, eq=False)
class PrincipalComponents:
    """PCA of a series (rows: samples).

    ``mean`` (p,); ``loadings`` (r, p), orthonormal rows; ``scores`` (n, r) with
    ``X = mean + scores @ loadings`` exactly (to round-off); ``singular_values`` (r,),
    descending, of the centred series; ``explained_variance = s²/(n − 1)`` and its ratio to the
    total variance. ``r`` is the numerical rank of the centred series (<= n − 1)."""

    mean: np.ndarray
    loadings: np.ndarray
    scores: np.ndarray
    singular_values: np.ndarray
    explained_variance: np.ndarray
    explained_variance_ratio: np.ndarray

    def reconstruct(self, q: int) -> np.ndarray:
        """The series from the mean and the first ``q`` components, shape (n, p)."""
        return self.mean + self.scores[:, :q] @ self.loadings[:q]


def principal_components(x: np.ndarray) -> PrincipalComponents:
    """PCA of the rows of ``x`` (n >= 2 samples × p values) through the Gram matrix."""
    x = np.asarray(x, dtype=float)
    if x.ndim != 2 or x.shape[0] < 2 or x.shape[1] < 1:
        raise ValueError(f"x must be a 2-D array of >= 2 samples, got shape {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError("x must be finite")
    n = x.shape[0]
    mean = x.mean(axis=0)
    xc = x - mean
    w, u = np.linalg.eigh(xc @ xc.T)
    order = np.argsort(w)[::-1]
    w, u = w[order], u[:, order]
    # eigenvalues below the Gram matrix's round-off are no components (the centred series has
    # rank <= n − 1; the last eigenvalue is 0 up to round-off)
    keep = w > max(n, 1) * 64 * np.finfo(float).eps * max(float(w[0]), 0.0)
    keep[n - 1 :] = False
    w, u = w[keep], u[:, keep]
    s = np.sqrt(w)
    loadings = (u.T @ xc) / s[:, None]
    # one step of re-orthonormalisation: the Gram route loses accuracy in the small components
    q_mat, _ = np.linalg.qr(loadings.T)
    signs = np.sign(np.sum(q_mat * loadings.T, axis=0))
    loadings = (q_mat * signs).T
    flip = np.sign(loadings[np.arange(loadings.shape[0]), np.argmax(np.abs(loadings), axis=1)])
    loadings *= flip[:, None]
    scores = xc @ loadings.T
    total = float(np.sum(xc * xc)) / max(n - 1, 1)
    var = w / max(n - 1, 1)
    for arr in (mean, loadings, scores, s, var):
        arr.setflags(write=False)
    return PrincipalComponents(
        mean=mean,
        loadings=loadings,
        scores=scores,
        singular_values=s,
        explained_variance=var,
        explained_variance_ratio=var / total if total > 0 else np.zeros_like(var),
    )


def component_test(
    x: np.ndarray,
    se: np.ndarray,
    pcs: PrincipalComponents,
    p_eff: float,
    max_end_members: int,
) -> list[dict[str, float]]:
    """``χ²`` of the residuals for ``m = 1 … max_end_members`` end-members (``m − 1``
    components), with its acceptance bound (module docstring). One dict per ``m``:
    ``end_members``, ``components``, ``chi2``, ``bound``, ``nu``, ``accepted``; ``m = n``
    (no residual left) has ``chi2 = NaN`` and is accepted only by default."""
    n, p = x.shape
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(se > 0, 1.0 / se, 0.0)
    out = []
    for m in range(1, max_end_members + 1):
        q = m - 1
        dof = n - 1 - q
        if dof <= 0 or q > pcs.loadings.shape[0]:
            out.append(
                dict(
                    end_members=m,
                    components=q,
                    chi2=math.nan,
                    bound=math.nan,
                    nu=0.0,
                    accepted=False,
                )
            )
            continue
        resid = (x - pcs.reconstruct(q)) * inv
        chi2 = float(np.sum(resid * resid)) / (dof * p)
        nu = dof * p_eff
        bound = 1.0 + ACCEPT_Z * math.sqrt(2.0 / nu)
        out.append(
            dict(
                end_members=m,
                components=q,
                chi2=chi2,
                bound=bound,
                nu=nu,
                accepted=bool(chi2 <= bound),
            )
        )
    return out


def simplex_volume(vertices: np.ndarray) -> float:
    """``(m − 1)!`` × the ``(m − 1)``-volume of the simplex of ``m`` vertices (rows) in any
    dimension: ``sqrt(det(D Dᵀ))``, ``D`` the edges from the first vertex."""
    v = np.asarray(vertices, dtype=float)
    if v.shape[0] <= 1:
        return 1.0
    d = v[1:] - v[0]
    g = d @ d.T
    return float(math.sqrt(max(np.linalg.det(g), 0.0)))


def nfindr(points: np.ndarray, m: int, max_sweeps: int = 100) -> np.ndarray:
    """Indices (ascending) of the ``m`` points spanning the simplex of largest volume (module
    docstring). ``points`` (n, >= m − 1): the first ``m − 1`` coordinates are used."""
    t = np.asarray(points, dtype=float)
    n = t.shape[0]
    if not 1 <= m <= n:
        raise ValueError(f"the number of end-members must lie in [1, {n}] (the samples), got {m}")
    t = t[:, : m - 1]
    centre = t.mean(axis=0)
    if m == 1:
        return np.array([int(np.argmin(np.sum((t - centre) ** 2, axis=1)))])
    chosen = [int(np.argmax(np.sum((t - centre) ** 2, axis=1)))]
    while len(chosen) < m:  # grow: the point that enlarges the partial simplex most
        vols = [simplex_volume(t[[*chosen, i]]) if i not in chosen else -1.0 for i in range(n)]
        chosen.append(int(np.argmax(vols)))
    best = simplex_volume(t[chosen])
    for _ in range(max_sweeps):  # exchange single vertices while the volume grows
        improved = False
        for k in range(m):
            for i in range(n):
                if i in chosen:
                    continue
                trial = chosen.copy()
                trial[k] = i
                vol = simplex_volume(t[trial])
                if vol > best * (1.0 + 1e-12):
                    chosen, best, improved = trial, vol, True
        if not improved:
            break
    return np.array(sorted(chosen))


def simplex_proportions(points: np.ndarray, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fully constrained least squares of every point on the vertices: ``(proportions (n, m),
    distance (n,))``, proportions ``>= 0`` summing to 1, ``distance`` from the point to the
    simplex (0 inside it, to round-off)."""
    # scipy.optimize costs ~0.2 s at import: loaded where used (fast `hyst` start)
    from scipy.optimize import nnls

    t = np.atleast_2d(np.asarray(points, dtype=float))
    v = np.atleast_2d(np.asarray(vertices, dtype=float))
    m = v.shape[0]
    if m == 1:
        return np.ones((t.shape[0], 1)), np.sqrt(np.sum((t - v[0]) ** 2, axis=1))
    scale = max(float(np.max(np.abs(v))), float(np.max(np.abs(t))), 1e-300)
    big = _SUM_WEIGHT * scale
    a = np.vstack([v.T, np.full((1, m), big)])
    out = np.empty((t.shape[0], m))
    for i, row in enumerate(t):
        p, _ = nnls(a, np.append(row, big), maxiter=50 * m)
        out[i] = _polish(p, row, v)
    dist = np.sqrt(np.sum((t - out @ v) ** 2, axis=1))
    return out, dist


def _polish(p: np.ndarray, point: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The weighted-row NNLS solution made exact: the equality-constrained least squares on
    its support (the KKT system ``[V_S V_Sᵀ 1; 1ᵀ 0]``), kept if it stays >= 0 (to 1e-9, then
    clipped); else the NNLS solution renormalised."""
    support = np.flatnonzero(p > 0)
    total = p.sum()
    fallback = p / total if total > 0 else np.full(p.size, 1.0 / p.size)
    if support.size == 0:
        return fallback
    vs = v[support]
    k = support.size
    kkt = np.zeros((k + 1, k + 1))
    kkt[:k, :k] = vs @ vs.T
    kkt[:k, k] = kkt[k, :k] = 1.0
    rhs = np.append(vs @ point, 1.0)
    sol = np.linalg.lstsq(kkt, rhs, rcond=None)[0][:k]
    if np.all(sol >= -1e-9):  # round-off below 0 of a coordinate that is 0 (a vertex, an edge)
        sol = np.clip(sol, 0.0, None)
        out = np.zeros(p.size)
        out[support] = sol / sol.sum()
        return out
    return fallback


def bootstrap_proportions(
    scores: np.ndarray,
    loadings: np.ndarray,
    se: np.ndarray,
    vertices: np.ndarray,
    vertex_samples: np.ndarray | None,
    n_boot: int,
    seed: int | np.random.Generator,
) -> np.ndarray:
    """Replicates of the proportions, shape (n_boot, n, m) (module docstring).

    ``scores`` (n, q): the samples' scores on the ``q = m − 1`` components ``loadings``
    (q, p); ``se`` (n, p) the per-node standard errors. ``vertex_samples``: the samples that
    are the end-members (their replicates move with their noise), or ``None`` for end-members
    given as fixed points ``vertices`` (m, q)."""
    rng = np.random.default_rng(seed)
    n, q = scores.shape
    m = vertices.shape[0]
    if q == 0:
        return np.ones((n_boot, n, m))
    # score noise of sample i: N(0, L diag(se_i²) Lᵀ), drawn through its Cholesky factor
    chol = np.empty((n, q, q))
    for i in range(n):
        cov = (loadings * se[i] ** 2) @ loadings.T
        cov += np.eye(q) * 1e-14 * max(float(np.trace(cov)), 1e-300)
        chol[i] = np.linalg.cholesky(cov)
    out = np.empty((n_boot, n, m))
    for b in range(n_boot):
        z = rng.standard_normal((n, q))
        t = scores + np.einsum("nij,nj->ni", chol, z)
        v = t[vertex_samples] if vertex_samples is not None else vertices
        out[b], _ = simplex_proportions(t, v)
    return out
