"""The Gaussian width-disorder density of :meth:`ContinuousPreisachModel.gaussian
<hysteresis.preisach.continuous.ContinuousPreisachModel.gaussian>`: its Everett function and
gradient by one Gauss–Legendre quadrature (see that method for the formulas)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from hysteresis._validation import positive_integer, positive_scalar, readonly_array
from hysteresis.preisach.base import _gauss

__all__ = ["GaussianEverett", "gaussian_everett"]


@dataclass(frozen=True)
class GaussianEverett:
    """The Everett function of the density ``N(s; 0, R²)·N(r; p/2, σ_r²)`` on ``[−L, L]``.

    ``everett``/``gradient`` are vectorised (arguments in the support), ``everett_scalar``/
    ``gradient_scalar`` their scalar fast paths with the semantics of the model's
    ``everett()``/``everett_gradient()`` (arguments clipped to the support, zero off the
    triangle); ``parameters`` is ``(width, spread, width_spread)`` after validation;
    ``kernel_params`` the same quadrature as the ``params`` of the compiled kernel
    (:func:`hysteresis.preisach._everett_kernels.everett_eval`, kind 0).
    """

    everett: Callable
    gradient: Callable
    everett_scalar: Callable
    gradient_scalar: Callable
    bound: float
    parameters: tuple[float, float, float]
    kernel_params: np.ndarray


def gaussian_everett(
    width: float, spread: float, width_spread: float, nodes: int
) -> GaussianEverett:
    """Validated parameters (``width``, ``spread``, ``width_spread`` > 0, ``nodes`` >= 4) and
    the Everett function of the Gaussian width-disorder density (support ``L = p/2 + 8σ_r +
    9R``)."""
    from scipy.special import ndtr

    width = positive_scalar(width, "width")
    spread = positive_scalar(spread, "spread")
    width_spread = positive_scalar(width_spread, "width_spread")
    n = positive_integer(nodes, "nodes", minimum=4)
    half = 0.5 * width
    r_lo = max(0.0, half - 8.0 * width_spread)
    r_hi = half + 8.0 * width_spread
    bound = r_hi + 9.0 * spread
    g, gw = _gauss(n)
    norm_r = 1.0 / (width_spread * math.sqrt(2.0 * math.pi))
    norm_s = 1.0 / (spread * math.sqrt(2.0 * math.pi))

    def _nodes(a, b):
        a, b = np.broadcast_arrays(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64))
        top = np.clip(0.5 * (a - b), r_lo, r_hi)
        span = (top - r_lo)[..., None]
        r = r_lo + span * g
        wr = span * gw * norm_r * np.exp(-0.5 * ((r - half) / width_spread) ** 2)
        return a[..., None], b[..., None], r, wr

    def raw(a, b):
        a, b, r, wr = _nodes(a, b)
        return np.sum(wr * (ndtr((a - r) / spread) - ndtr((b + r) / spread)), axis=-1)

    total = float(raw(bound, -bound))

    def everett(a, b):
        return raw(a, b) / total

    def gradient(a, b):
        a, b, r, wr = _nodes(a, b)
        da = np.sum(wr * np.exp(-0.5 * ((a - r) / spread) ** 2), axis=-1) * norm_s
        db = -np.sum(wr * np.exp(-0.5 * ((b + r) / spread) ** 2), axis=-1) * norm_s
        return da / total, db / total

    def weights_at(a, b):
        top = min(max(0.5 * (a - b), r_lo), r_hi)
        span = top - r_lo
        r = r_lo + span * g
        return r, span * gw * norm_r * np.exp(-0.5 * ((r - half) / width_spread) ** 2)

    # scalar fast paths with the semantics of everett()/everett_gradient() (arguments
    # clipped to the support, zero off the triangle): the oscillator engine evaluates them
    # once per integrator stage
    def everett_scalar(a, b):
        a = min(max(a, -bound), bound)
        b = min(max(b, -bound), bound)
        if not a > b:
            return 0.0
        r, wr = weights_at(a, b)
        return float(np.dot(wr, ndtr((a - r) / spread) - ndtr((b + r) / spread))) / total

    def gradient_scalar(a0, b0):
        a = min(max(a0, -bound), bound)
        b = min(max(b0, -bound), bound)
        if not a > b:
            return 0.0, 0.0
        r, wr = weights_at(a, b)
        da = db = 0.0
        if -bound <= a0 <= bound:
            da = float(np.dot(wr, np.exp(-0.5 * ((a - r) / spread) ** 2))) * norm_s / total
        if -bound <= b0 <= bound:
            db = -float(np.dot(wr, np.exp(-0.5 * ((b + r) / spread) ** 2))) * norm_s / total
        return da, db

    return GaussianEverett(
        everett=everett,
        gradient=gradient,
        everett_scalar=everett_scalar,
        gradient_scalar=gradient_scalar,
        bound=bound,
        parameters=(width, spread, width_spread),
        kernel_params=readonly_array(
            [-bound, bound, half, width_spread, spread, r_lo, r_hi, norm_r, norm_s, total]
            + list(g)
            + list(gw)
        ),
    )
