"""The fit record every record fitter returns, and the checks of an input/output record (shared
by :mod:`analysis.identification.fitting` and
:mod:`analysis.identification.differential_fits`, which it re-exports)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from hysteresis._validation import real_array

__all__ = ["RecordFit", "check_record", "fit_result"]


@dataclass(frozen=True, eq=False)
class RecordFit:
    """A model fitted to an input/output record.

    Attributes
    ----------
    model:
        The fitted operator (:class:`~hysteresis.DiscretePreisachModel`, normalised;
        :class:`~hysteresis.PrandtlIshlinskii`; :class:`~hysteresis.BoucWen`;
        :class:`~hysteresis.JilesAtherton`).
    offset, scale:
        Output model ``y ≈ offset + scale · model(u)`` (``scale = 1`` where the model's own
        parameters carry the amplitude: Prandtl–Ishlinskii, Bouc–Wen, Jiles–Atherton).
    train_rms, validation_rms:
        Root-mean-square error on the training and validation samples (NaN without
        validation samples).
    n_train, n_validation:
        Sample counts.
    parameters:
        The fitted parameters by name (``None`` where the model is its weights only: Preisach).
    standard_errors:
        Their standard errors, ``s·sqrt(diag((JᵀJ)⁻¹))`` at the optimum (``J`` the Jacobian of
        the residuals, ``s²`` the residual variance) carried to the named parameters by the
        delta method; ``None`` where not computed.
    initial_state:
        The operator's state at the record's first input (fixed by the first sample), from
        which :meth:`predict` starts; ``None``: the model's default ``initial_state``.
    info:
        How the fit went (starts tried, evaluations, seconds, the initial guess), JSON-ready.
    """

    model: Any
    offset: float
    scale: float
    train_rms: float
    validation_rms: float
    n_train: int
    n_validation: int
    parameters: Mapping[str, float] | None = None
    standard_errors: Mapping[str, float] | None = None
    initial_state: Any = None
    info: Mapping[str, Any] | None = None

    def predict(self, inputs: Any) -> np.ndarray:
        """``offset + scale · model(inputs)``, from :attr:`initial_state` (the record's first
        memory; the inputs continue from the record's first input) or, without one, from the
        model's default initial state."""
        y, _ = self.model.apply(np.asarray(inputs, dtype=float), self.initial_state)
        return self.offset + self.scale * y


def check_record(
    u: Any, y: Any, train_fraction: float, min_samples: int = 2
) -> tuple[np.ndarray, np.ndarray, int]:
    """``(u, y, n_train)``: two finite 1-D float arrays of one length (>= ``min_samples``) and
    the number of training samples, ``floor(train_fraction · len(u))`` (>= ``min_samples``)."""
    u = real_array(u, "u")
    y = real_array(y, "y")
    if u.ndim != 1 or y.shape != u.shape or u.size < min_samples:
        raise ValueError(f"u and y must be 1-D arrays of the same length (>= {min_samples})")
    if not (np.all(np.isfinite(u)) and np.all(np.isfinite(y))):
        raise ValueError("u and y must be finite (no NaN/inf)")
    if not (isinstance(train_fraction, (int, float)) and 0.0 < train_fraction <= 1.0):
        raise ValueError(f"train_fraction must be in (0, 1], got {train_fraction!r}")
    n_train = int(math.floor(train_fraction * u.size))
    if n_train < min_samples:
        raise ValueError(f"train_fraction leaves fewer than {min_samples} training samples")
    return u, y, n_train


def fit_result(
    model: Any,
    offset: float,
    scale: float,
    pred: np.ndarray,
    y: np.ndarray,
    n_train: int,
    **extra: Any,
) -> RecordFit:
    """The :class:`RecordFit` of the predictions ``pred`` of the whole record (train and
    validation RMS from the split at ``n_train``); ``extra``: the optional fields."""
    err = pred - y
    train = float(np.sqrt(np.mean(err[:n_train] ** 2)))
    n_val = y.size - n_train
    val = float(np.sqrt(np.mean(err[n_train:] ** 2))) if n_val else float("nan")
    return RecordFit(model, offset, scale, train, val, n_train, n_val, **extra)
