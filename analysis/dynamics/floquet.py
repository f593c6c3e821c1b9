"""Floquet multipliers of a monodromy matrix, the one home of the eigenvalue problem of
``J = D P^k`` (periodic orbits, branch points, the basins' unrefined cycles, the eigenvector
of a period doubling).

With frozen memory (the rule is described in :mod:`analysis.dynamics.periodic_orbits`): which
coordinates are frozen, the multipliers of the reduced block plus exactly 1 per frozen
direction with their labels; without (the defaults), the eigenvalues and eigenvectors of ``J``
by decreasing modulus. Beside them what is read off the multipliers: the exponents
``log|μ|/(k·T)``, the multipliers that are not frozen (those the stability and the bifurcation
tests judge), ``max |μ|`` over them and stability.

Stability is "stable" (every judged ``|μ| < 1``), "unstable" (one ``|μ| > 1``) or "neutral":
a multiplier on the unit circle within the round-off of its computation
(:func:`multiplier_roundoff`) can be told neither inside nor outside — e.g. an undamped
resonance where ``P^k`` is the identity and the computed multipliers are ``1 − 4e-16``."""

from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = [
    "RESET_ROUNDOFF",
    "active_multipliers",
    "floquet_exponents",
    "floquet_multipliers",
    "frozen_coordinates",
    "is_stable",
    "max_abs_multiplier",
    "multiplier_roundoff",
    "stability",
]

#: largest ``|μ|/max(1, max|μ|)`` of a structural zero multiplier that is set to exactly 0:
#: a zero eigenvalue of multiplicity m computed in double precision moves by up to
#: ``(eps·|J|)^(1/m)`` (a double zero splits like a Jordan block: ~1.5e-8); measured on the
#: toolkit's reset orbits 1e-18 .. 3.5e-10. 1e-6 leaves a margin of 70 over a split pair and
#: is far below any multiplier that matters for stability.
RESET_ROUNDOFF = 1e-6


def frozen_coordinates(jacobian: np.ndarray, head: int = 2) -> np.ndarray:
    """Mask of the frozen memory coordinates of ``jacobian = D P^k``: the coordinates after the
    first ``head`` (``q, v``) whose row is exactly the identity's (module docstring)."""
    jac = np.asarray(jacobian, dtype=np.float64)
    d = jac.shape[0]
    eye = np.eye(d)
    mask = np.zeros(d, dtype=bool)
    for j in range(head, d):
        mask[j] = bool(np.array_equal(jac[j], eye[j]))
    return mask


def floquet_multipliers(
    jacobian: np.ndarray,
    frozen: np.ndarray | None = None,
    n_zero: int = 0,
    labels: tuple[str, ...] = (),
) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Multipliers, eigenvectors and multiplier labels of ``jacobian`` with the ``frozen`` mask
    (default: nothing frozen, no structural zero: ``numpy.linalg.eig`` of ``jacobian`` by
    decreasing modulus, complex, every label ``""``; ``labels`` name the coordinates and are
    needed only for frozen ones).

    The eigenvalues of the reduced block ``J_rr`` (its ``n_zero`` smallest set to exactly 0,
    the structurally reset directions, where they are round-off: ``|μ| <=``
    :data:`RESET_ROUNDOFF` ``·max(1, max|μ|)``; a larger one is a genuine multiplier, kept
    unlabelled — the structural claim does not hold for this Jacobian) and exactly 1 per
    frozen coordinate, by decreasing
    modulus; eigenvectors: ``(w_r, 0)`` for ``J_rr w_r = μ w_r`` and the family's tangent
    ``(−(J_rr − I)^{-1} J_rf e_f, e_f)`` for a frozen ``f`` (least squares if ``J_rr − I`` is
    singular)."""
    jac = np.asarray(jacobian, dtype=np.float64)
    d = jac.shape[0]
    if frozen is None:
        frozen = np.zeros(d, dtype=bool)
    elif np.any(frozen) and len(labels) != d:
        raise ValueError(f"labels must name the {d} coordinates when some are frozen")
    free = np.nonzero(~frozen)[0]
    fixed = np.nonzero(frozen)[0]
    mu_r, vec_r = np.linalg.eig(jac[np.ix_(free, free)])
    order = np.argsort(-np.abs(mu_r), kind="stable")
    mu_r, vec_r = mu_r[order].astype(complex), vec_r[:, order].astype(complex)
    tags = [""] * mu_r.size
    n_zero = min(max(0, int(n_zero)), mu_r.size)
    scale = max(1.0, float(np.abs(mu_r[0]))) if mu_r.size else 1.0
    for i in range(mu_r.size - n_zero, mu_r.size):
        if abs(mu_r[i]) <= RESET_ROUNDOFF * scale:
            mu_r[i] = 0.0
            tags[i] = "reset"
    vec = np.zeros((d, d), dtype=complex)
    vec[free, : free.size] = vec_r
    mu = np.concatenate([mu_r, np.ones(fixed.size, dtype=complex)])
    if fixed.size:
        a = jac[np.ix_(free, free)] - np.eye(free.size)
        b = -jac[np.ix_(free, fixed)]
        family = np.linalg.lstsq(a, b, rcond=None)[0]
        vec[np.ix_(free, free.size + np.arange(fixed.size))] = family
        vec[fixed, free.size + np.arange(fixed.size)] = 1.0
        tags += [f"frozen: {labels[j]}" for j in fixed]
    order = np.argsort(-np.abs(mu), kind="stable")
    return mu[order], vec[:, order], tuple(tags[i] for i in order)


def active_multipliers(multipliers: np.ndarray, labels: tuple[str, ...] = ()) -> np.ndarray:
    """The multipliers not labelled frozen (all without labels): a frozen direction is a
    parameter of a family of orbits, exactly 1, and judges neither stability nor bifurcations.
    """
    mu = np.asarray(multipliers)
    if not labels:
        return mu
    return mu[np.array([not t.startswith("frozen") for t in labels], dtype=bool)]


def max_abs_multiplier(multipliers: np.ndarray, labels: tuple[str, ...] = ()) -> float:
    """``max |μ|`` over the multipliers not labelled frozen (1 if all are)."""
    mu = active_multipliers(multipliers, labels)
    return float(np.max(np.abs(mu))) if mu.size else 1.0


def multiplier_roundoff(
    jacobian: np.ndarray,
    multipliers: np.ndarray,
    frozen: np.ndarray | None,
    n_products: int,
) -> np.ndarray:
    """Round-off bound of each ``|μ|`` (in the order of ``multipliers``, those of
    :func:`floquet_multipliers` for ``jacobian`` and ``frozen``; 0 for a frozen one).

    ``jacobian`` is a product of ``n_products`` matrices computed in floating point: its
    error is at most ``n·ε·|J|₂`` (the forward bound of a matrix product, ``γ_n``, with the
    factors' norms taken as ``|J|``), and a simple eigenvalue moves by at most ``κ_i`` times
    a perturbation of ``J``, ``κ_i = |x_i||y_i| / |y_i^H x_i|`` (right/left eigenvectors of the
    reduced block; 1 for a normal matrix). The band is ``κ_i·n·ε·|J_rr|₂``: a multiplier
    closer to the unit circle than this is neutral."""
    jac = np.asarray(jacobian, dtype=np.float64)
    mu = np.asarray(multipliers)
    if frozen is None:
        frozen = np.zeros(jac.shape[0], dtype=bool)
    free = np.nonzero(~frozen)[0]
    band = np.zeros(mu.size)
    if free.size == 0:
        return band
    block = jac[np.ix_(free, free)]
    w, left, right = scipy.linalg.eig(block, left=True, right=True)
    overlap = np.abs(np.sum(left.conj() * right, axis=0))
    norms = np.linalg.norm(left, axis=0) * np.linalg.norm(right, axis=0)
    with np.errstate(divide="ignore"):
        kappa = np.where(overlap > 0.0, norms / overlap, np.inf)
    scale = int(n_products) * np.finfo(np.float64).eps * float(np.linalg.norm(block, 2))
    for i, m in enumerate(mu):
        # the eigenvalue of the block nearest to m: the same matrix, so m itself up to the
        # order of a conjugate pair (whose κ agree); a zeroed reset direction keeps 0 (a
        # frozen 1 gets a band too, unused: frozen directions judge nothing)
        if m != 0.0:
            band[i] = kappa[int(np.argmin(np.abs(w - m)))] * scale
    return band


def stability(
    multipliers: np.ndarray, labels: tuple[str, ...] = (), roundoff: np.ndarray | None = None
) -> str:
    """``"unstable"`` if a judged multiplier (not frozen) has ``|μ| > 1 + band``,
    ``"neutral"`` if none does but one has ``|μ| >= 1 − band``, else ``"stable"`` (also when
    all are frozen); ``band`` is ``roundoff`` (per multiplier, :func:`multiplier_roundoff`;
    default 0: ``|μ| = 1`` exactly is neutral)."""
    mu = np.asarray(multipliers)
    band = np.zeros(mu.size) if roundoff is None else np.asarray(roundoff, dtype=np.float64)
    keep = np.ones(mu.size, dtype=bool)
    if labels:
        keep = np.array([not t.startswith("frozen") for t in labels], dtype=bool)
    size, band = np.abs(mu[keep]), band[keep]
    if np.any(size > 1.0 + band):
        return "unstable"
    if np.all(size < 1.0 - band):
        return "stable"
    return "neutral"


def is_stable(
    multipliers: np.ndarray, labels: tuple[str, ...] = (), roundoff: np.ndarray | None = None
) -> bool:
    """Every multiplier not labelled frozen inside the unit circle by more than its
    ``roundoff`` band, ``|μ| < 1 − band`` (default band 0: ``|μ| < 1``; True if all are frozen:
    nothing grows)."""
    return stability(multipliers, labels, roundoff) == "stable"


def floquet_exponents(multipliers: np.ndarray, duration: float) -> np.ndarray:
    """``log|μ| / duration`` (``duration = k·T``, the orbit's period in time units), in the
    order of ``multipliers``; ``-inf`` for ``μ = 0`` (a reset direction)."""
    with np.errstate(divide="ignore"):
        return np.log(np.abs(np.asarray(multipliers))) / duration
