"""The compiled QR pieces of the Benettin loop (:mod:`analysis.dynamics.lyapunov`), in a module
of their own so that compiled Benettin loops of engines (:mod:`analysis.dynamics._relay_benettin`)
call the very same functions: the same reflections, the same bits."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["householder_qr"]


@njit(cache=True)
def householder_qr(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """Reduced QR of ``y`` (d × k) by Householder reflections: ``Q`` (d × m), ``|R_jj|`` (m),
    m = min(d, k), and whether ``y`` was finite (else Q and R are not computed).

    The same reflections as LAPACK's ``geqrf`` (``np.linalg.qr``), compiled: for the 2 × 2 to
    3 × 3 deviation matrices of the relay engines the NumPy call costs more than the integration
    of a forcing period of a small ensemble. Plain reading::

        R := Y
        for j < m:  x := R[j:, j];  α := -sign(x_0) |x|;  u := x - α e_0
                    R[j:, j:] -= 2 u (uᵀ R[j:, j:]) / (uᵀ u);  |R_jj| = |α|
        Q := H_0 H_1 ... H_(m-1) I[:, :m]     (H_j = I - 2 u_j u_jᵀ / u_jᵀ u_j)

    A zero column gives the identity reflection and R_jj = 0.
    """
    d, k = y.shape
    m = min(d, k)
    qmat = np.zeros((d, m))
    diag = np.zeros(m)
    for i in range(d):
        for j in range(k):
            if not math.isfinite(y[i, j]):
                return qmat, diag, False
    r = y.copy()
    u = np.zeros((m, d))
    unorm2 = np.zeros(m)
    for j in range(m):
        norm2 = 0.0
        for i in range(j, d):
            norm2 += r[i, j] * r[i, j]
        if norm2 == 0.0:
            continue
        alpha = -math.copysign(math.sqrt(norm2), r[j, j])
        for i in range(j, d):
            u[j, i] = r[i, j]
        u[j, j] -= alpha
        un2 = 0.0
        for i in range(j, d):
            un2 += u[j, i] * u[j, i]
        unorm2[j] = un2
        diag[j] = abs(alpha)
        for c in range(j, k):
            dot = 0.0
            for i in range(j, d):
                dot += u[j, i] * r[i, c]
            f = 2.0 * dot / un2
            for i in range(j, d):
                r[i, c] -= f * u[j, i]
    for i in range(m):
        qmat[i, i] = 1.0
    for j in range(m - 1, -1, -1):
        if unorm2[j] == 0.0:
            continue
        for c in range(m):
            dot = 0.0
            for i in range(j, d):
                dot += u[j, i] * qmat[i, c]
            f = 2.0 * dot / unorm2[j]
            for i in range(j, d):
                qmat[i, c] -= f * u[j, i]
    return qmat, diag, True


@njit(cache=True)
def _accumulate_logs(diag: np.ndarray, k: int, rank: int, lsum: np.ndarray) -> bool:
    """lsum[j] += log|R_jj| for j < rank, -inf beyond (structural collapse); returns whether a
    direction collapsed in this interval."""
    collapsed = False
    for j in range(k):
        if j < rank:
            lsum[j] += math.log(diag[j]) if diag[j] > 0.0 else -math.inf
        elif math.isfinite(lsum[j]):
            lsum[j] = -math.inf
            collapsed = True
    return collapsed
