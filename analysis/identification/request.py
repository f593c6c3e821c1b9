"""What one identification is asked to do, checked as a whole before any work: the source (an
operator of the model registry driven through reversal curves, or measured FORC files), the
grid, the smoothing law and the options of measured data, and the decisions that follow from
them (the grid's half-extent, whether the paper's ridge density is the reference).

:class:`IdentifyRequest` is built from keyword arguments; every inconsistent combination is one
``ValueError`` whose message starts with the parameter it is about (``"grid_step is only for
measured data ..."``), so that a front end (``hyst identify``) can name its option for it. The
request reads no file and builds no operator: what needs the data (the file's format, its
moment unit, its fields) is checked by the methods that take it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification.curves import protocol_lattice
from analysis.identification.density import auto_grid
from analysis.identification.forc_io import FORMATS
from analysis.identification.normalization import NORMALIZATIONS, sample_amount
from analysis.identification.smoothing import WINDOWS
from analysis.identification.variforc import VariforcParameters
from hysteresis._validation import check_grid_nodes

__all__ = [
    "COLUMN_LAYOUTS",
    "DEFAULT_MODEL_STEP",
    "DEFAULT_MEASURED_SMOOTHING",
    "DRIFT_CORRECTIONS",
    "IdentifyRequest",
    "PAPER_MODELS",
    "VARIFORC_PARAMETERS",
]

#: the models whose density the paper states (``N(s; 0, R²) δ(r − p/2)``): only these are
#: compared with it, and only with the paper's disorder (not explicit fields)
PAPER_MODELS = ("dimers", "erf-play")
#: the grid step of a model's identification (the paper's fig:preis_dens)
DEFAULT_MODEL_STEP = 0.1
#: the smoothing factor of measured data when none is given (both directions)
DEFAULT_MEASURED_SMOOTHING = 3.0
#: the readers' drift corrections (from the calibration points) and two-column layouts
DRIFT_CORRECTIONS = ("none", "multiplicative", "additive")
COLUMN_LAYOUTS = ("field,moment", "moment,field")
#: replicates of the peak's parametric bootstrap when none is given
DEFAULT_BOOTSTRAP = 200
VARIFORC_PARAMETERS = ("sc0", "sc1", "sb0", "sb1", "lam")
#: the options of measured data, refused with a model when not at their defaults
_MEASURED_ONLY = (
    "workers",
    "grid_step",
    "uncertainty",
    "bootstrap",
    "cmap",
    "bootstrap_seed",
    "smoothing",  # the laws of measured data: "variforc", "auto"
    "normalize",
    "columns",
    "mass",
    "volume",
    "reversible_ridge",
    "drift_correction",
    "file_format",
)

Smoothing = tuple[float, float] | VariforcParameters | str | None


@dataclass(frozen=True)
class IdentifyRequest:
    """One identification: either ``model`` (a registry name) or ``inputs`` (FORC files or
    directories), with the options of that source; the others keep their defaults.

    Attributes
    ----------
    model, explicit_fields:
        The operator's registry name; ``explicit_fields``: dimers with the caller's fields
        rather than the paper's disorder (then the paper's density is no reference).
    inputs, workers:
        Measured FORC files or directories; several paths or a directory are a batch, which
        alone may use ``workers > 1`` processes.
    step, saturation:
        Models: the grid step (default :data:`DEFAULT_MODEL_STEP`) and half-extent ``H``
        (default :meth:`grid_half_extent`).
    smoothing, variforc:
        ``None``, a factor ``SF`` or ``(SF_r, SF_s)``, ``"variforc"`` (with the parameters
        ``variforc``: any of ``sc0, sc1, sb0, sb1, lam``) or ``"auto"``. After construction
        the law :func:`~analysis.identification.identify_from_curves` takes: measured data
        without one get :data:`DEFAULT_MEASURED_SMOOTHING`; ``"auto"`` and ``"variforc"`` are
        measured data only.
    file_format, columns, drift_correction, normalize, mass, volume, grid_step, window,
    reversible_ridge, uncertainty, bootstrap, bootstrap_seed, cmap:
        Measured data only (the defaults otherwise): the reader's options, the normalisation
        (``mass`` only with ``normalize="mass"``, ``volume`` likewise), the protocol lattice's
        step, the smoothing window (``"rs"`` for VARIFORC and uncertainty), the reversible
        ridge, the uncertainty with its bootstrap, the diagram's colour map.
    max_memory:
        Bound on the identification's estimated peak memory in bytes (``None``: the default).
    """

    model: str | None = None
    explicit_fields: bool = False
    inputs: tuple[Path, ...] = ()
    workers: int = 1
    step: float | None = None
    saturation: float | None = None
    smoothing: Smoothing | float = None
    variforc: Mapping[str, float] = field(default_factory=dict, hash=False)
    file_format: str = "auto"
    columns: str | None = None
    drift_correction: str = "none"
    normalize: str = "none"
    mass: float | None = None
    volume: float | None = None
    grid_step: float | None = None
    window: str = "rs"
    reversible_ridge: bool = False
    uncertainty: bool = False
    bootstrap: int | None = None
    bootstrap_seed: int | None = None
    cmap: str | None = None
    max_memory: float | None = None

    def __post_init__(self) -> None:
        _set = object.__setattr__
        _set(self, "inputs", tuple(Path(p) for p in self.inputs))
        _set(self, "variforc", dict(self.variforc))
        if (self.model is None) == (not self.inputs):
            raise ValueError("model and inputs: give exactly one source (an operator or files)")
        given = tuple(n for n in ("bootstrap", "bootstrap_seed") if getattr(self, n) is not None)
        _set(self, "_bootstrap_given", given)
        if self.bootstrap is None:
            _set(self, "bootstrap", DEFAULT_BOOTSTRAP)
        if self.bootstrap_seed is None:
            _set(self, "bootstrap_seed", 0)
        self._check_choices()
        if self.measured:
            for name in ("step", "saturation"):
                if getattr(self, name) is not None:
                    raise ValueError(
                        f"{name} is only for models; with inputs the lattice comes from the "
                        "measurement (grid_step)"
                    )
        else:
            given = self._measured_options_given()
            if given:
                raise ValueError(f"{given[0]} is only for measured data (inputs, a FORC file)")
            _set(self, "step", _positive(self.step, "step", DEFAULT_MODEL_STEP))
            if self.saturation is not None:
                _set(self, "saturation", _positive(self.saturation, "saturation"))
        if self.workers != 1 and not self.batch:
            raise ValueError("workers is only for a batch (a directory or several inputs)")
        _set(self, "smoothing", self._smoothing_law())
        for kind in ("mass", "volume"):
            if getattr(self, kind) is not None:
                if self.normalize != kind:
                    raise ValueError(f"{kind} is only for normalize={kind!r}")
                _set(self, kind, _positive(getattr(self, kind), kind))
        lattice = isinstance(self.smoothing, (VariforcParameters, str)) or self.uncertainty
        if lattice and self.window != "rs":
            raise ValueError(
                f"window must be 'rs' for VARIFORC and uncertainty (the VARIFORC law is defined "
                f"across Bc and along Bu), got {self.window!r}"
            )
        if self.max_memory is not None:
            _set(self, "max_memory", _positive(self.max_memory, "max_memory"))
        if self._bootstrap_given and not self.uncertainty:  # part of the uncertainty: given
            # alone it would be ignored
            raise ValueError(
                f"{self._bootstrap_given[0]} is only with uncertainty (the peak's bootstrap)"
            )

    # -- checks -------------------------------------------------------------------------------

    def _check_choices(self) -> None:
        for name, allowed in (
            ("file_format", FORMATS),
            ("drift_correction", DRIFT_CORRECTIONS),
            ("normalize", NORMALIZATIONS),
            ("window", WINDOWS),
            ("columns", (None, *COLUMN_LAYOUTS)),
        ):
            if getattr(self, name) not in allowed:
                raise ValueError(f"{name} must be one of {allowed}, got {getattr(self, name)!r}")
        for name, low in (("workers", 1), ("bootstrap", 20), ("bootstrap_seed", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
        unknown = sorted(set(self.variforc) - set(VARIFORC_PARAMETERS))
        if unknown:
            raise ValueError(f"variforc takes {', '.join(VARIFORC_PARAMETERS)}; got {unknown[0]!r}")

    def _measured_options_given(self) -> list[str]:
        """The options of measured data given (not at their defaults) with a model."""
        defaults = {f.name: f.default for f in fields(self)}
        return [
            name
            for name in _MEASURED_ONLY
            if (
                isinstance(self.smoothing, str) and self.smoothing in ("variforc", "auto")
                if name == "smoothing"
                else name in self._bootstrap_given
                if name in ("bootstrap", "bootstrap_seed")
                else getattr(self, name) != defaults[name]
            )
        ]

    def _smoothing_law(self) -> Smoothing:
        sm = self.smoothing
        word = sm if isinstance(sm, str) else None
        given = [n for n in VARIFORC_PARAMETERS if n in self.variforc]
        if word == "variforc":
            return VariforcParameters(**self.variforc)
        if given:
            name = "lambda" if given[0] == "lam" else given[0]  # VariforcParameters' wording
            chooses = " (auto chooses)" if word == "auto" else ""
            raise ValueError(f"{name} is only for smoothing='variforc'{chooses}")
        if word == "auto":
            return "auto"
        if word is not None:
            raise ValueError(
                f"smoothing must be a factor, a pair, 'variforc' or 'auto', got {sm!r}"
            )
        if sm is None:
            return (DEFAULT_MEASURED_SMOOTHING,) * 2 if self.measured else None
        pair = tuple(np.atleast_1d(np.asarray(sm, dtype=object)).tolist())
        if len(pair) == 1:
            pair = pair * 2
        if len(pair) != 2:
            raise ValueError(f"smoothing takes one factor SF or two, SF_R SF_S; got {len(pair)}")
        return (_positive(pair[0], "smoothing"), _positive(pair[1], "smoothing"))

    # -- the decisions ------------------------------------------------------------------------

    @property
    def measured(self) -> bool:
        """Measured FORC data (``inputs``), not an operator."""
        return bool(self.inputs)

    @property
    def batch(self) -> bool:
        """Several inputs or a directory: one diagram per file and a summary."""
        return len(self.inputs) > 1 or any(p.is_dir() for p in self.inputs)

    @property
    def paper_reference(self) -> bool:
        """Whether the paper's density ``N(s; 0, R²) δ(r − p/2)`` is the reference: a paper
        model with the paper's disorder, never measured data, other operators or the caller's
        own dimer fields."""
        return self.model in PAPER_MODELS and not self.explicit_fields

    @property
    def paper_figure(self) -> bool:
        """The paper's fig:preis_dens: the finite dimer ensemble next to its erf-play limit."""
        return self.paper_reference and self.model == "dimers"

    @property
    def operator_half_extent(self) -> float | None:
        """The half-extent the operator takes from the grid: ``preisach-uniform``'s density
        fills the triangle ``-H <= β <= α <= H`` of the grid (``saturation``)."""
        return self.saturation if self.model == "preisach-uniform" else None

    def grid_half_extent(
        self, width: float, spread: float, extreme_threshold: float | None = None
    ) -> float:
        """The grid's half-extent ``H``: ``saturation``, else ``5R + p/2`` and at least the
        largest ``|threshold|`` of the operator (dimers); refused with a ``ValueError`` naming
        ``step`` when ``step`` and ``H`` ask for more nodes than the bound (the reversal curves
        cost nodes²/2 operator steps)."""
        saturation = self.saturation
        if saturation is None:
            saturation = 5.0 * spread + 0.5 * width
            if extreme_threshold is not None:
                saturation = max(saturation, float(extreme_threshold))
        check_grid_nodes(self.step, saturation)
        return float(saturation)

    def reader_options(self, file_format: str) -> dict[str, Any]:
        """The reader's keyword arguments for a file of ``file_format`` (as detected):
        ``columns`` for data-only files (a ``ValueError`` naming it for another format) and
        ``drift_correction`` for every format: the reader warns in one line where a file has
        no calibration points and refuses a format whose calibration points it cannot use."""
        out: dict[str, Any] = {}
        if self.columns is not None:
            if file_format != "blocks":
                raise ValueError(
                    f"columns is for data-only files (two columns, no header), not {file_format!r}"
                )
            out["columns"] = self.columns
        if self.drift_correction != "none":  # the reader warns where there are no calibration
            # points and refuses a format that has them but cannot correct with them
            out["drift_correction"] = self.drift_correction
        return out

    def check_grid_step(self, curves: Any) -> None:
        """``grid_step`` applies to the protocol lattice of fields that differ from curve to
        curve: refused (``ValueError``) on curves that share one grid (it would be ignored) and
        when the lattice is too fine or too coarse for the data."""
        if self.grid_step is None:
            return
        # the rule of identify_from_curves(grid="auto"): measured fields -> protocol lattice
        if auto_grid(curves) == "native":
            raise ValueError(
                "grid_step applies to measured fields that differ curve by curve; these curves "
                "share one grid (identified on that grid)"
            )
        protocol_lattice(curves, self.grid_step)

    def amount(self, moment_unit: str | None, header: Mapping[str, str]) -> float:
        """The divisor of the normalisation (1 for none): ``mass`` / ``volume`` or the file
        header's; refused when the file states no moment unit (the normalised unit would be
        unknown)."""
        if self.normalize == "none":
            return 1.0
        if moment_unit is None:
            raise ValueError(
                "normalize needs the file's moment unit: the file states none, so the "
                "normalised unit would be unknown"
            )
        return sample_amount(dict(header), self.normalize, getattr(self, self.normalize))


def _positive(value: Any, name: str, default: float | None = None) -> float:
    if value is None and default is not None:
        return default
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}") from exc
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return v
