"""Floquet multipliers of a monodromy matrix, the one home of the eigenvalue problem of
``J = D P^k`` (periodic orbits, branch points, the basins' unrefined cycles, the eigenvector
of a period doubling).

With frozen memory (the rule is described in :mod:`analysis.dynamics.periodic_orbits`): which
coordinates are frozen, the multipliers of the reduced block plus exactly 1 per frozen
direction with their labels; without (the defaults), the eigenvalues and eigenvectors of ``J``
by decreasing modulus. Beside them what is read off the multipliers: the exponents
``log|μ|/(k·T)``, the multipliers that are not frozen (those the stability and the bifurcation
tests judge), ``max |μ|`` over them and stability."""

from __future__ import annotations

import numpy as np

__all__ = [
    "RESET_ROUNDOFF",
    "active_multipliers",
    "floquet_exponents",
    "floquet_multipliers",
    "frozen_coordinates",
    "is_stable",
    "max_abs_multiplier",
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


def is_stable(multipliers: np.ndarray, labels: tuple[str, ...] = ()) -> bool:
    """Every multiplier not labelled frozen inside the unit circle, ``|μ| < 1`` (True if all
    are frozen: nothing grows)."""
    return bool(np.all(np.abs(active_multipliers(multipliers, labels)) < 1.0))


def floquet_exponents(multipliers: np.ndarray, duration: float) -> np.ndarray:
    """``log|μ| / duration`` (``duration = k·T``, the orbit's period in time units), in the
    order of ``multipliers``; ``-inf`` for ``μ = 0`` (a reset direction)."""
    with np.errstate(divide="ignore"):
        return np.log(np.abs(np.asarray(multipliers))) / duration
