"""VARIFORC smoothing (Egli 2013) and the weighted local regression with standard errors.

VARIFORC
--------
Egli, R. (2013), *VARIFORC: An optimized protocol for calculating non-regular first-order
reversal curve (FORC) diagrams*, Global and Planetary Change 110, 302–320. The FORC density is a
weighted local quadratic regression whose window half-widths, in units of the field step ``Δ``,
vary over the diagram: ``s_c`` across (along ``B_c``) and ``s_b`` along ``B_u``::

    s_c(B_c) = min( max((1 − λ) s_c1 + λ |B_c|/Δ,  s_c0),  max(s_c0, |B_c|/Δ) )
    s_b(B_u) = min( max((1 − λ) s_b1 + λ |B_u − B_u0|/Δ,  s_b0),  max(s_b0, |B_u − B_u0|/Δ) )

so that the smoothing is smallest, ``s_c0`` (``s_b0``), on the vertical ridge ``B_c = 0`` (the
central ridge ``B_u = B_u0``), grows linearly with the distance from it (a window never crosses
the ridge: the second argument of ``min``) and tends to ``(1 − λ) s_1 + λ|B|/Δ`` far from it
(``s_c1``, ``s_b1`` plus a linear growth at rate ``λ``). Inside the window the weight is the
product of the one-dimensional weights of Egli (2013, eq. 6), 1 in the interior and falling
to 0 over the last step (:func:`~analysis.identification._regression_kernels.variforc_weight_1d`).
This law and the defaults ``s_c0 = s_b0 = 3``, ``s_c1 = s_b1 = 7``, ``λ = 0.07`` are those of
PmagPy's ``pmagpy.forc`` (``variforc_smoothing_factors``, documented there as FORCinel 3.08's
active implementation; FORCsensei uses the same ``s(H)`` law). ``λ`` is one parameter for both
directions here.

On the toolkit's regular lattice (nodes ``α_i``, ``β_j``, step ``Δ``) ``B_c = r = (α − β)/2``
and ``B_u = s = (α + β)/2``; the window of a node holds the lattice nodes with
``|Δr| <= s_c Δ`` and ``|Δs| <= s_b Δ`` (the ``"rs"`` window of the fixed factor, which is the
special case ``s_c = SF_r``, ``s_b = SF_s`` with unit weights).

Standard errors
---------------
For values ``v = f + ε`` with independent noise of one variance ``σ²`` at the lattice nodes,
the weighted least-squares coefficients ``c = A⁻¹ Xᵀ W v`` (``A = XᵀWX``) have the covariance
``σ² A⁻¹ (XᵀW²X) A⁻¹``; ``σ²`` is estimated per node from the weighted residuals,
``σ̂² = Σ w r² / (Σ w − tr(A⁻¹ XᵀW²X))`` (unbiased when the quadratic is exact). The standard
error of ``ρ`` is that of the mixed coefficient. Noise that is correlated between lattice
nodes (interpolated data, a common per-curve offset) is outside this model: the toolkit
regresses the half moments ``M/2`` (independent per measured point), not the Everett
differences ``(M − M(B_r))/2`` that share the reversal point's noise along a curve.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from analysis.identification._checks import finite_number, positive_number
from analysis.identification._regression_kernels import N_SUMS, line_sums, node_fits, reach

__all__ = [
    "VariforcParameters",
    "variforc_factors",
    "weighted_quadratic_density",
    "LocalRegression",
]

#: a node gets a value only if each half-window holds this fraction of its nodes valid (the
#: rule of :func:`~analysis.identification.smoothing.grid_quadratic_density`)
SIDE_FRACTION = 0.75


@dataclass(frozen=True)
class VariforcParameters:
    """VARIFORC smoothing parameters (Egli 2013), in field steps; defaults of PmagPy/FORCinel.

    Attributes
    ----------
    sc0, sc1:
        Smoothing across (``B_c``) on the vertical ridge ``B_c = 0`` and far from it (>= 1).
    sb0, sb1:
        Smoothing along ``B_u`` on the central ridge ``B_u = bu0`` and far from it (>= 1).
    lam:
        Rate ``λ`` of the linear growth away from the ridges, in ``[0, 1]``.
    bu0:
        Position of the central ridge (field unit of the data; default 0).
    """

    sc0: float = 3.0
    sc1: float = 7.0
    sb0: float = 3.0
    sb1: float = 7.0
    lam: float = 0.07
    bu0: float = 0.0

    def __post_init__(self) -> None:
        for name in ("sc0", "sc1", "sb0", "sb1"):
            value = positive_number(getattr(self, name), name)
            if value < 1.0:
                raise ValueError(f"{name} must be >= 1 (field steps), got {value}")
            object.__setattr__(self, name, value)
        lam = finite_number(self.lam, "lambda")
        if not 0.0 <= lam <= 1.0:
            raise ValueError(f"lambda must lie in [0, 1], got {lam}")
        object.__setattr__(self, "lam", lam)
        object.__setattr__(self, "bu0", finite_number(self.bu0, "bu0"))

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def _law(s0: float, s1: float, lam: float, distance: np.ndarray) -> np.ndarray:
    linear = (1.0 - lam) * s1 + lam * distance
    return np.minimum(np.maximum(linear, s0), np.maximum(s0, distance))


def variforc_factors(
    bc: Any, bu: Any, step: float, params: VariforcParameters
) -> tuple[np.ndarray, np.ndarray]:
    """Local half-widths ``(s_c, s_b)`` in steps at coordinates ``(B_c, B_u)`` (see the
    module docstring for the law)."""
    step = positive_number(step, "step")
    dc = np.abs(np.asarray(bc, dtype=float)) / step
    db = np.abs(np.asarray(bu, dtype=float) - params.bu0) / step
    return _law(params.sc0, params.sc1, params.lam, dc), _law(
        params.sb0, params.sb1, params.lam, db
    )


@dataclass(frozen=True, eq=False)
class LocalRegression:
    """Per-node result of :func:`weighted_quadratic_density` (arrays of the lattice's shape).

    ``rho`` is ``μ_αβ = −∂²v/∂α∂β`` and ``se`` its standard error (field units, NaN where not
    evaluated); ``sigma`` the node's residual noise estimate; ``n_points`` the valid nodes in
    its window; ``sc``, ``sb`` the half-widths used (steps)."""

    rho: np.ndarray
    se: np.ndarray
    sigma: np.ndarray
    n_points: np.ndarray
    sc: np.ndarray
    sb: np.ndarray


def _line_prefix_counts(valid: np.ndarray) -> np.ndarray:
    """``cum[u + n − 1, k]``: valid nodes ``(j + u, j)`` with ``j < k`` on every line
    ``u = i − j`` (prefix sums along the lines, exact integers)."""
    n = valid.shape[0]
    lines = np.zeros((2 * n - 1, n), dtype=np.int64)
    for u in range(-(n - 1), n):
        j = np.arange(max(0, -u), min(n, n - u))
        lines[u + n - 1, j] = valid[j + u, j]
    cum = np.zeros((2 * n - 1, n + 1), dtype=np.int64)
    np.cumsum(lines, axis=1, out=cum[:, 1:])
    return cum


def _fit_by_blocks(values, valid, ti, tj, sc, pr_t, qr_t, ss_of_w, qr_of_w, box, errors):
    """Line sums and node fits, the target lines in blocks (bounded memory of the sums)."""
    n = values.shape[0]
    nt = ti.size
    rho = np.full(nt, np.nan)
    se = np.full(nt, np.nan)
    sigma = np.full(nt, np.nan)
    npts = np.zeros(nt, dtype=np.int64)
    if nt == 0:
        return rho, se, sigma, npts
    cum = _line_prefix_counts(valid)
    u_t = ti - tj
    order = np.argsort(u_t, kind="stable")
    block = max(16, n // 4)  # target lines per block: the sums stay below ~100 B per node
    lines = np.unique(u_t)
    for start in range(0, lines.size, block):
        ul, uh = int(lines[start]), int(lines[min(start + block, lines.size) - 1])
        sel = order[(u_t[order] >= ul) & (u_t[order] <= uh)]
        p_max = int(pr_t[sel].max())
        u_lo, u_hi = max(ul - p_max, -(n - 1)), min(uh + p_max, n - 1)
        half = p_max // 2 + 1
        c_lo, c_hi = int(tj[sel].min()) - half, int(tj[sel].max()) + half + 1
        sums = np.empty((u_hi - u_lo + 1, c_hi - c_lo, 2, N_SUMS))
        line_sums(values, valid, u_lo, u_hi, c_lo, c_hi, ss_of_w, qr_of_w, box, errors, sums)
        r, s, g = (np.full(sel.size, np.nan) for _ in range(3))
        k = np.zeros(sel.size, dtype=np.int64)
        node_fits(
            sums,
            u_lo,
            c_lo,
            cum,
            ti[sel],
            tj[sel],
            sc[sel],
            pr_t[sel],
            qr_t[sel],
            box,
            SIDE_FRACTION,
            errors,
            r,
            s,
            g,
            k,
        )
        rho[sel], se[sel], sigma[sel], npts[sel] = r, s, g, k
    return rho, se, sigma, npts


def _reaches(widths: np.ndarray, box: bool) -> np.ndarray:
    """:func:`reach` of every half-width (computed once per distinct value)."""
    uniq, inverse = np.unique(widths, return_inverse=True)
    return np.array([reach(x, box) for x in uniq], dtype=np.int64)[inverse.reshape(-1)]


def weighted_quadratic_density(
    values: Any,
    valid: Any,
    evaluate: Any,
    step: float,
    smoothing: VariforcParameters | tuple[float, float],
    origin: float = 0.0,
    errors: bool = True,
) -> LocalRegression:
    """Weighted local quadratic regression of ``values`` on a regular lattice, every node
    with its own window (VARIFORC) or one fixed window, with standard errors.

    Parameters
    ----------
    values:
        ``v[α_i, β_j]`` on a square lattice ``α_i = β_i = origin + i·step`` (ignored where not
        valid).
    valid, evaluate:
        Boolean masks: nodes whose value enters the regression; nodes where ``ρ`` is wanted.
        As for :func:`~analysis.identification.smoothing.grid_quadratic_density`, a node gets
        a value only if each of its eight half-windows has at least 3/4 of its nodes valid.
    step:
        Lattice step (> 0).
    smoothing:
        :class:`VariforcParameters` (Egli weights, variable half-widths) or ``(SF_r, SF_s)``
        (unit weights in the fixed window ``|Δr| <= SF_r·step``, ``|Δs| <= SF_s·step``: the
        estimator of ``grid_quadratic_density``, now with standard errors).
    origin:
        Field value of node 0 (for the VARIFORC law, which depends on ``B_c`` and ``B_u``).
    errors:
        Compute ``se`` and ``sigma`` (a second pass over every window); else they are NaN.
    """
    v = np.asarray(values, dtype=float)
    ok = np.asarray(valid, dtype=bool)
    ev = np.asarray(evaluate, dtype=bool)
    if v.ndim != 2 or v.shape[0] != v.shape[1] or ok.shape != v.shape or ev.shape != v.shape:
        raise ValueError("values, valid and evaluate must be square 2-D arrays of one shape")
    step = positive_number(step, "step")
    origin = finite_number(origin, "origin")
    if not np.all(np.isfinite(v[ok])):
        raise ValueError("values must be finite at the valid nodes")
    ti, tj = np.nonzero(ev)
    n = v.shape[0]
    w_all = np.arange(2 * n - 1)
    if isinstance(smoothing, VariforcParameters):
        a = origin + step * ti
        b = origin + step * tj
        sc, sb = variforc_factors(0.5 * (a - b), 0.5 * (a + b), step, smoothing)
        # the half-width along s of every Bu index w = i + j (Bu = origin + w·step/2)
        _, ss_of_w = variforc_factors(0.0 * w_all, origin + 0.5 * step * w_all, step, smoothing)
        box = False
    else:
        if len(smoothing) != 2:
            raise ValueError("smoothing must be VariforcParameters or a pair (SF_r, SF_s)")
        sf_r = positive_number(smoothing[0], "smoothing[0] (SF_r)")
        sf_s = positive_number(smoothing[1], "smoothing[1] (SF_s)")
        sc = np.full(ti.size, sf_r)
        sb = np.full(ti.size, sf_s)
        ss_of_w = np.full(w_all.size, sf_s)
        box = True
    sc = np.asarray(sc, dtype=float)
    sb = np.asarray(sb, dtype=float)
    ss_of_w = np.ascontiguousarray(ss_of_w, dtype=float)
    qr_of_w = _reaches(ss_of_w, box)
    pr_t = _reaches(sc, box)
    qr_t = qr_of_w[ti + tj] if ti.size else np.zeros(0, dtype=np.int64)
    rho_t, se_t, sig_t, n_t = _fit_by_blocks(
        np.where(ok, v, 0.0), ok, ti, tj, sc, pr_t, qr_t, ss_of_w, qr_of_w, box, errors
    )
    shape = v.shape
    out = {name: np.full(shape, np.nan) for name in ("rho", "se", "sigma", "sc", "sb")}
    out["rho"][ti, tj] = rho_t / step**2
    out["se"][ti, tj] = se_t / step**2
    out["sigma"][ti, tj] = sig_t
    out["sc"][ti, tj] = sc
    out["sb"][ti, tj] = sb
    counts = np.zeros(shape, dtype=np.int64)
    counts[ti, tj] = n_t
    for arr in (*out.values(), counts):
        arr.setflags(write=False)
    return LocalRegression(n_points=counts, **out)
