"""The model registry: one name -> operator builder table for the CLI, ``hyst paper`` and the
ensembles.

Every model is built from one :class:`ModelParameters` record whose defaults are the paper's
Table I/II values (loop width ``p = 2``, centre spread ``R = 1``, spin coupling ``J = 2``,
``N = 20 000`` spins, seed 0). A model only reads the parameters it lists in
:attr:`ModelSpec.parameters`; :func:`model_record` reports exactly those, so a JSON record or a
figure title names what defines the operator and nothing else.

========================  =====================================================================
name                      operator
========================  =====================================================================
``dimers``                ``SpinDimerEnsemble.random(N, p, R, J, seed)`` (or explicit fields)
``erf-play``              ``GeneralizedPlay.erf(p, R)``: the dimers' N -> infinity limit
``play``                  ``PlayOperator(p)``
``relay``                 ``Relay(alpha, beta)``, default ``(p/2, -p/2)``
``n2``                    one dimer, ``b = (2, 0)``, J (paper fig:N=2_schema)
``n4``                    two dimers, ``b = (2, 0), (-0.5, -2.5)``, J (paper fig:N=4_traj)
``preisach``              N random relays: centres ``s ~ N(0, R²)``, half-widths
                          ``r ~ N(p/2, σ_r²)`` restricted to ``r >= 0`` (discrete sample of
                          ``preisach-gauss``; ``σ_r = 0``: the paper's equal widths)
``preisach-gauss``        continuous Preisach model, density ``N(s; 0, R²)·N(r; p/2, σ_r²)``
                          on ``r >= 0``, renormalised (``σ_r > 0``)
``pi``                    Prandtl–Ishlinskii: K plays, widths evenly spaced on
                          ``[p/2, 3p/2]``, equal weights ``1/K``
``preisach-uniform``      continuous Preisach model, uniform density on the triangle
                          ``-H <= β <= α <= H``, ``H = 5R + p/2`` unless given (a reference
                          density for the identification)
``bouc-wen``              ``BoucWen(A, beta, gamma, n)`` (fields ``bw_a``, ``bw_beta``,
                          ``bw_gamma``, ``bw_n``; default ``(1, 0.75, 0.25, 1)``: saturation
                          ``z_max = 1``)
``jiles-atherton``        ``JilesAtherton(ms, a, k, c, alpha)`` (fields ``ja_ms``, ``ja_a``,
                          ``ja_k``, ``ja_c``, ``ja_alpha``; default ``(1, 0.2, 0.3, 0.2, 0.1)``:
                          a loop of half-width about ``k`` in the oscillator's units)
``rfim``                  ``RandomFieldIsing.lattice(lattice, disorder, 1, seed)``: periodic
                          lattice, fields ``N(0, disorder²)``, spin coupling 1 (R in units of J)
========================  =====================================================================

The Duhem models' fields carry a prefix (``bw_``, ``ja_``): their parameters' usual names
(``alpha``, ``beta``, ``c``) are taken by the relay's thresholds and, on the command line, by
the oscillator's coupling ``C``. A library error about one of them is reported under the
field's name (``bw_beta must be >= 0 ...``).

Here ``s = (α + β)/2`` is a relay's centre and ``r = (α − β)/2`` its half-width, so the paper's
ridge ``δ(r − p/2)`` is the limit ``σ_r -> 0``. The old spelling ``erf_play`` is accepted with a
:class:`DeprecationWarning`.

Where a model is named (:func:`build_operator`, :func:`model_record`), a **weighted sum** of
names is accepted too, e.g. ``"0.7*erf-play + 0.3*preisach"`` (grammar and refusals:
:mod:`analysis.experiments.model_expression`; :func:`parse_model` reads it): the operator
``Σ_k w_k · M_k`` of :func:`hysteresis.weighted_sum`, every part built from the same
:class:`ModelParameters` (one ``seed``, one ``N``, one ``p``, ...), so a name may appear once.
A single name, or ``1*name``, is that model itself, exactly as before.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from analysis.experiments.model_expression import (
    ModelExpression,
    ModelExpressionError,
    parse_model_expression,
)
from analysis.experiments.parameters import (
    PLAYS,
    SEED,
    SPIN_COUPLING,
    SPINS,
    SPREAD,
    WIDTH,
    WIDTH_SPREAD,
)
from hysteresis import (
    BoucWen,
    ContinuousPreisachModel,
    GeneralizedPlay,
    JilesAtherton,
    PlayOperator,
    PrandtlIshlinskii,
    PreisachModel,
    RandomFieldIsing,
    Relay,
    SpinDimerEnsemble,
    weighted_sum,
)
from hysteresis._validation import as_generator, positive_integer

__all__ = [
    "ALIASES",
    "MODELS",
    "ModelExpression",
    "ModelExpressionError",
    "ModelParameters",
    "ModelSpec",
    "build_operator",
    "canonical_model",
    "canonical_model_name",
    "describe_model",
    "model_names",
    "model_record",
    "parameters_read",
    "parse_model",
    "uniform_half_extent",
]


@dataclass(frozen=True)
class ModelParameters:
    """Parameters shared by the models (defaults: the paper's Tables I and II).

    Attributes
    ----------
    spins:
        N, number of spins (``dimers``; even, >= 2) or of relays (``preisach``; >= 1).
    seed:
        Seed of the disorder (``dimers``, ``preisach``), an int >= 0.
    width:
        p, the loop width (``2 × half-width`` of a relay), > 0.
    spread:
        R, standard deviation of the loop centres, > 0.
    spin_coupling:
        J, the spin-spin coupling of the dimers, > 0 (``dimers`` need ``0 < p < 2J``).
    width_spread:
        σ_r, standard deviation of the relay half-widths (``preisach`` >= 0,
        ``preisach-gauss`` > 0).
    fields:
        Explicit local fields ``(n_dimers, 2)`` for ``dimers`` (overrides N, p, R, seed).
    alpha, beta:
        Relay thresholds (``relay``; default ``±p/2``).
    plays:
        K, number of plays of ``pi``, >= 1.
    resolution:
        Everett-table resolution of ``preisach-uniform`` (grid points per axis).
    half_extent:
        H, half-extent of the ``preisach-uniform`` triangle, > 0 (default ``5R + p/2``).
    bw_a, bw_beta, bw_gamma, bw_n:
        ``bouc-wen``: ``A > 0``, ``beta >= 0``, ``gamma`` with ``beta + gamma > 0``, ``n >= 1``
        (:class:`~hysteresis.BoucWen`).
    ja_ms, ja_a, ja_k, ja_c, ja_alpha:
        ``jiles-atherton``: ``ms, a, k > 0``, ``0 <= c < 1``, ``alpha >= 0`` with
        ``alpha·ms/(3a) < 1`` (:class:`~hysteresis.JilesAtherton`).
    lattice, disorder:
        ``rfim``: the side lengths (1 to 3 integers >= 3) and R >= 0 (the fields' standard
        deviation; the spin coupling is 1, the critical disorder in 3-D ``R_c ≈ 2.16``).
    """

    spins: int = SPINS
    seed: int = SEED
    width: float = WIDTH
    spread: float = SPREAD
    spin_coupling: float = SPIN_COUPLING
    width_spread: float = WIDTH_SPREAD
    fields: tuple[tuple[float, float], ...] | None = None
    alpha: float | None = None
    beta: float | None = None
    plays: int = PLAYS
    resolution: int = 512
    half_extent: float | None = None
    bw_a: float = 1.0
    bw_beta: float = 0.75
    bw_gamma: float = 0.25
    bw_n: float = 1.0
    ja_ms: float = 1.0
    ja_a: float = 0.2
    ja_k: float = 0.3
    ja_c: float = 0.2
    ja_alpha: float = 0.1
    lattice: tuple[int, ...] = (20, 20, 20)
    disorder: float = 2.6


@dataclass(frozen=True)
class ModelSpec:
    """One registry entry.

    Attributes
    ----------
    name:
        Canonical name (lower case, words joined by ``-``).
    description:
        One line for ``--help`` and the docs.
    parameters:
        Names of the :class:`ModelParameters` fields the builder reads.
    builder:
        ``builder(params) -> operator``.
    play_type:
        True when the operator's memory is one wagon position (``--w0`` applies).
    """

    name: str
    description: str
    parameters: tuple[str, ...]
    builder: Callable[[ModelParameters], Any]
    play_type: bool = False


# -- builders -------------------------------------------------------------------------------


def _dimers(p: ModelParameters) -> Any:
    if p.fields is not None:
        return SpinDimerEnsemble(np.asarray(p.fields, dtype=float), p.spin_coupling)
    return SpinDimerEnsemble.random(p.spins, p.width, p.spread, p.spin_coupling, p.seed)


def _erf_play(p: ModelParameters) -> Any:
    return GeneralizedPlay.erf(p.width, p.spread)


def _play(p: ModelParameters) -> Any:
    return PlayOperator(p.width)


def _relay(p: ModelParameters) -> Any:
    alpha = 0.5 * p.width if p.alpha is None else p.alpha
    beta = -0.5 * p.width if p.beta is None else p.beta
    return Relay(alpha, beta)


def _n2(p: ModelParameters) -> Any:
    return SpinDimerEnsemble(np.array([[2.0, 0.0]]), p.spin_coupling)


def _n4(p: ModelParameters) -> Any:
    return SpinDimerEnsemble(np.array([[2.0, 0.0], [-0.5, -2.5]]), p.spin_coupling)


def _check_width_spread(p: ModelParameters, strictly_positive: bool) -> float:
    sr = p.width_spread
    ok = isinstance(sr, (int, float)) and math.isfinite(sr) and (sr > 0 or not strictly_positive)
    if not ok or sr < 0:
        bound = "> 0" if strictly_positive else ">= 0"
        raise ValueError(f"width_spread must be a finite number {bound}, got {sr!r}")
    return float(sr)


def _check_positive(value: Any, name: str) -> float:
    if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return float(value)


def _preisach(p: ModelParameters) -> Any:
    n = positive_integer(p.spins, "spins")
    width = _check_positive(p.width, "width")
    spread = _check_positive(p.spread, "spread")
    sr = _check_width_spread(p, strictly_positive=False)
    rng = as_generator(p.seed)
    centres = rng.normal(0.0, spread, size=n)
    half = np.full(n, 0.5 * width)
    if sr > 0:
        # truncated normal on r >= 0 by redrawing the negative draws (exact, and cheap: the
        # fraction redrawn is Φ(-p/(2σ_r)))
        half = rng.normal(0.5 * width, sr, size=n)
        bad = half < 0
        while np.any(bad):
            half[bad] = rng.normal(0.5 * width, sr, size=int(np.count_nonzero(bad)))
            bad = half < 0
    return PreisachModel.from_relays(centres + half, centres - half)


def _preisach_gauss(p: ModelParameters) -> Any:
    width = _check_positive(p.width, "width")
    spread = _check_positive(p.spread, "spread")
    sr = _check_width_spread(p, strictly_positive=True)
    # smooth Everett function by 1-D quadrature (N(r; p/2, σ_r²) cut at r >= 0 and
    # renormalised): no table kinks, so the continuous engine takes large steps (a tabulated
    # from_density model of the same law is ~20x slower to integrate)
    return ContinuousPreisachModel.gaussian(width, spread, sr)


def _pi(p: ModelParameters) -> Any:
    k = positive_integer(p.plays, "plays")
    width = _check_positive(p.width, "width")
    widths = width * np.linspace(0.5, 1.5, k) if k > 1 else np.array([width])
    return PrandtlIshlinskii(widths, np.full(k, 1.0 / k))


def uniform_half_extent(p: ModelParameters) -> float:
    """H of ``preisach-uniform``: ``half_extent`` if given, else ``5R + p/2``."""
    if p.half_extent is not None:
        return _check_positive(p.half_extent, "half_extent")
    spread = _check_positive(p.spread, "spread")
    width = _check_positive(p.width, "width")
    return 5.0 * spread + 0.5 * width


class _UniformTriangleDensity:
    """Uniform density ``1/(2H²)`` on the triangle ``-H <= β <= α <= H`` (a module-level
    class, not a closure, so that the model pickles)."""

    def __init__(self, h: float) -> None:
        self.h = h
        self.area = 2.0 * h**2  # the triangle β <= α inside [-H, H]²

    def __call__(self, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
        a = np.asarray(alpha, dtype=float)
        b = np.asarray(beta, dtype=float)
        inside = (b <= a) & (a <= self.h) & (b >= -self.h)
        return np.where(inside, 1.0 / self.area, 0.0)


def _preisach_uniform(p: ModelParameters) -> Any:
    h = uniform_half_extent(p)
    return PreisachModel.from_density(_UniformTriangleDensity(h), -h, h, int(p.resolution))


def _renamed(build: Callable[[], Any], fields: Mapping[str, str]) -> Any:
    """``build()``, with a library error's parameter names (the words before ``must``) replaced
    by the :class:`ModelParameters` fields that carry them (``beta`` -> ``bw_beta``)."""
    try:
        return build()
    except (ValueError, TypeError) as exc:
        text = str(exc)
        head, sep, tail = text.partition(" must ")
        if not sep:
            raise
        head = re.sub(r"\b\w+\b", lambda m: fields.get(m.group(), m.group()), head)
        raise type(exc)(head + sep + tail) from None


_BW_FIELDS = {"A": "bw_a", "beta": "bw_beta", "gamma": "bw_gamma", "n": "bw_n"}
_JA_FIELDS = {"ms": "ja_ms", "a": "ja_a", "k": "ja_k", "c": "ja_c", "alpha": "ja_alpha"}


def _bouc_wen(p: ModelParameters) -> Any:
    return _renamed(lambda: BoucWen(p.bw_a, p.bw_beta, p.bw_gamma, p.bw_n), _BW_FIELDS)


def _jiles_atherton(p: ModelParameters) -> Any:
    return _renamed(lambda: JilesAtherton(p.ja_ms, p.ja_a, p.ja_k, p.ja_c, p.ja_alpha), _JA_FIELDS)


def _rfim(p: ModelParameters) -> Any:
    build = lambda: RandomFieldIsing.lattice(p.lattice, p.disorder, 1.0, seed=p.seed)  # noqa: E731
    return _renamed(build, {"shape": "lattice"})


_SPECS = (
    ModelSpec(
        "dimers",
        "spin dimers with the paper's disorder (N, p, R, J, seed) or explicit fields",
        ("spins", "seed", "width", "spread", "spin_coupling"),
        _dimers,
    ),
    ModelSpec(
        "erf-play",
        "erf generalized play, the dimers' N -> infinity limit (p, R)",
        ("width", "spread"),
        _erf_play,
        play_type=True,
    ),
    ModelSpec("play", "classical play of width p", ("width",), _play, play_type=True),
    ModelSpec("relay", "one relay, thresholds (alpha, beta) = (p/2, -p/2)", ("width",), _relay),
    ModelSpec("n2", "one dimer b = (2, 0) (paper fig:N=2_schema)", ("spin_coupling",), _n2),
    ModelSpec(
        "n4", "two dimers b = (2, 0), (-0.5, -2.5) (paper fig:N=4_traj)", ("spin_coupling",), _n4
    ),
    ModelSpec(
        "preisach",
        "N random relays: centres N(0, R^2), half-widths N(p/2, sigma_r^2) on r >= 0",
        ("spins", "seed", "width", "spread", "width_spread"),
        _preisach,
    ),
    ModelSpec(
        "preisach-gauss",
        "continuous Preisach density N(s; 0, R^2) N(r; p/2, sigma_r^2), r >= 0",
        ("width", "spread", "width_spread"),
        _preisach_gauss,
    ),
    ModelSpec(
        "pi",
        "Prandtl-Ishlinskii: K plays, widths evenly on [p/2, 3p/2], weights 1/K",
        ("width", "plays"),
        _pi,
    ),
    ModelSpec(
        "preisach-uniform",
        "continuous Preisach model, uniform density on -H <= beta <= alpha <= H "
        "(H = 5R + p/2 unless given)",
        ("width", "spread", "half_extent"),
        _preisach_uniform,
    ),
    ModelSpec(
        "bouc-wen",
        "Bouc-Wen dz/du = A - |z|^n (beta sign(du) sign(z) + gamma), a Duhem operator",
        tuple(_BW_FIELDS.values()),
        _bouc_wen,
    ),
    ModelSpec(
        "jiles-atherton",
        "Jiles-Atherton magnetisation M[H] (ms, a, k, c, alpha), a Duhem operator in M_irr",
        tuple(_JA_FIELDS.values()),
        _jiles_atherton,
    ),
    ModelSpec(
        "rfim",
        "random-field Ising lattice, fields N(0, R^2) (--disorder), J = 1, periodic (--lattice)",
        ("lattice", "disorder", "seed"),
        _rfim,
    ),
)

#: canonical name -> :class:`ModelSpec`, in the order shown by ``--help``
MODELS: Mapping[str, ModelSpec] = {spec.name: spec for spec in _SPECS}
#: deprecated spelling -> canonical name
ALIASES: Mapping[str, str] = {"erf_play": "erf-play"}


def model_names() -> tuple[str, ...]:
    """The canonical model names."""
    return tuple(MODELS)


def canonical_model_name(name: str) -> str:
    """The canonical spelling of ``name``.

    Deprecated spellings (``erf_play``) are mapped with a :class:`DeprecationWarning`; an
    unknown name raises ``ValueError`` listing the choices.
    """
    if not isinstance(name, str):
        raise TypeError(f"model must be a str, got {type(name).__name__}")
    if name in MODELS:
        return name
    if name in ALIASES:
        new = ALIASES[name]
        warnings.warn(
            f"model name {name!r} is deprecated; use {new!r}", DeprecationWarning, stacklevel=2
        )
        return new
    raise ValueError(f"model must be one of {', '.join(MODELS)}; got {name!r}")


def _parameters(params: ModelParameters | None, overrides: Mapping[str, Any]) -> ModelParameters:
    base = ModelParameters() if params is None else params
    known = {f.name for f in fields(ModelParameters)}
    unknown = sorted(set(overrides) - known)
    if unknown:
        raise TypeError(f"unknown model parameter(s) {unknown}; known: {sorted(known)}")
    if overrides.get("fields") is not None:
        overrides = dict(overrides)
        overrides["fields"] = tuple(
            (float(a), float(b)) for a, b in np.asarray(overrides["fields"], dtype=float)
        )
    return replace(base, **overrides)


def parse_model(text: str) -> ModelExpression:
    """``text`` (a registry name or a weighted sum of them, see
    :mod:`analysis.experiments.model_expression`) as a :class:`ModelExpression` of canonical
    names; a deprecated spelling warns as in :func:`canonical_model_name`.

    Raises
    ------
    ModelExpressionError
        (a ``ValueError``) anything else, in one line; an unknown name lists the names.
    """
    spellings = {**{n: n for n in MODELS}, **ALIASES}
    expr = parse_model_expression(text, spellings)
    for term in expr.terms:
        if term.spelling in ALIASES:
            new = ALIASES[term.spelling]
            warnings.warn(
                f"model name {term.spelling!r} is deprecated; use {new!r}",
                DeprecationWarning,
                stacklevel=2,
            )
    return expr


def canonical_model(text: str) -> str:
    """The canonical text of a model name or weighted sum (:func:`parse_model`): a name as
    :func:`canonical_model_name` gives it, a sum as ``0.7*erf-play + 0.3*preisach``."""
    if isinstance(text, str) and text in MODELS:
        return text
    expr = parse_model(text)
    return expr.plain or str(expr)


def _expression(name: str) -> ModelExpression | None:
    """``None`` for a registry name or alias (or a non-string, refused by
    :func:`canonical_model_name` as before), else the parsed text."""
    if not isinstance(name, str) or name in MODELS or name in ALIASES:
        return None
    return parse_model(name)


def _spec(name: str, expr: ModelExpression | None) -> ModelSpec:
    """The registry entry of a plain name (``expr`` ``None``, or one term of weight 1)."""
    return MODELS[canonical_model_name(name) if expr is None else str(expr.plain)]


def build_operator(name: str, params: ModelParameters | None = None, **overrides: Any) -> Any:
    """Build the operator registered as ``name``, or the weighted sum ``name`` spells.

    Parameters
    ----------
    name:
        A name of :data:`MODELS` (or a deprecated alias), or a weighted sum of them such as
        ``"0.7*erf-play + 0.3*preisach"`` (:func:`parse_model`).
    params:
        Base parameters (default: :class:`ModelParameters`, the paper's values); a sum builds
        every part from them.
    **overrides:
        Fields of :class:`ModelParameters` to replace, e.g. ``spins=200, seed=3``.

    Returns
    -------
    The hysteresis operator (a :class:`~hysteresis.base.Hysteron`; a sum's is a
    :class:`~hysteresis.algebra.WeightedSum`).

    Raises
    ------
    ValueError
        Unknown model name or a text that is no weighted sum of names, or a parameter outside
        its range (named in the message).
    """
    expr = _expression(name)
    if expr is None or expr.plain is not None:
        return _spec(name, expr).builder(_parameters(params, overrides))
    p = _parameters(params, overrides)
    return weighted_sum([MODELS[n].builder(p) for n in expr.names], expr.weights)


def _read(spec: ModelSpec, p: ModelParameters) -> dict[str, Any]:
    """The parameters ``spec``'s model reads, JSON-ready."""
    if spec.name == "preisach-uniform":
        return {"half_extent": uniform_half_extent(p)}
    if spec.name == "relay":
        return {
            "alpha": 0.5 * p.width if p.alpha is None else p.alpha,
            "beta": -0.5 * p.width if p.beta is None else p.beta,
        }
    names = spec.parameters
    if spec.name == "dimers" and p.fields is not None:
        names = ("fields", "spin_coupling")
    out: dict[str, Any] = {}
    for n in names:
        v = getattr(p, n)
        out[n] = [list(row) for row in v] if n == "fields" else v
    return out


def _reads(spec: ModelSpec, p: ModelParameters) -> set[str]:
    """The :class:`ModelParameters` fields ``spec``'s builder reads with the values ``p``."""
    if spec.name == "relay":  # p sets a threshold only where alpha or beta is not given
        width = {"width"} if p.alpha is None or p.beta is None else set()
        return {"alpha", "beta"} | width
    if spec.name == "preisach-uniform" and p.half_extent is not None:
        return {"half_extent", "resolution"}  # H given: 5R + p/2 is not computed
    if spec.name == "preisach-uniform":
        return {"width", "spread", "half_extent", "resolution"}
    if spec.name == "dimers" and p.fields is not None:  # the fields replace N, p, R, seed
        return {"fields", "spin_coupling"}
    return set(spec.parameters)


def parameters_read(
    name: str, params: ModelParameters | None = None, **overrides: Any
) -> frozenset[str]:
    """The :class:`ModelParameters` fields that the model ``name`` (a registry name or a
    weighted sum, whose parts' reads are joined) reads with these values: a field outside
    the set does not change the operator (e.g. ``spins`` of ``erf-play``, the ``N -> inf``
    limit; ``width`` of a ``relay`` whose two thresholds are given; ``spins``, ``width``,
    ``spread``, ``seed`` of ``dimers`` with explicit ``fields``)."""
    expr = _expression(name)
    p = _parameters(params, overrides)
    if expr is None or expr.plain is not None:
        return frozenset(_reads(_spec(name, expr), p))
    return frozenset().union(*(_reads(MODELS[n], p) for n in expr.names))


def model_record(
    name: str, params: ModelParameters | None = None, **overrides: Any
) -> dict[str, Any]:
    """``{"model": name, <the parameters the model reads>}``, JSON-ready.

    For a weighted sum, ``"model"`` is its canonical text (``"0.7*erf-play + 0.3*preisach"``),
    ``"weights"`` maps each part's name to its weight, and the parameters are those any part
    reads (each once: every part reads the same values).
    """
    expr = _expression(name)
    if expr is None or expr.plain is not None:
        spec = _spec(name, expr)
        return {"model": spec.name, **_read(spec, _parameters(params, overrides))}
    p = _parameters(params, overrides)
    weights = dict(zip(expr.names, expr.weights, strict=True))
    out: dict[str, Any] = {"model": str(expr), "weights": weights}
    for n in expr.names:
        out.update(_read(MODELS[n], p))
    return out


_SYMBOLS = {
    "spins": "N",
    "seed": "seed",
    "width": "p",
    "spread": "R",
    "spin_coupling": "J",
    "width_spread": "σ_r",
    "plays": "K",
    "alpha": "α",
    "beta": "β",
    "fields": "b",
    "half_extent": "H",
    "bw_a": "A",
    "bw_beta": "β",
    "bw_gamma": "γ",
    "bw_n": "n",
    "ja_ms": "Ms",
    "ja_a": "a",
    "ja_k": "k",
    "ja_c": "c",
    "ja_alpha": "α",
    "lattice": "L",
    "disorder": "R",
}


def describe_model(record: Mapping[str, Any], extra: Sequence[tuple[str, Any]] = ()) -> str:
    """A one-line title, e.g. ``"dimers N=20000 p=2 R=1 J=2 seed=0, C=4"``, from a
    :func:`model_record` (plus ``extra`` ``(symbol, value)`` pairs such as the coupling); a sum
    is written in parentheses, ``"(0.7*erf-play + 0.3*preisach) p=2 R=1 ..."``."""
    parts = []
    for key, value in record.items():
        if key in ("model", "weights"):
            continue
        sym = _SYMBOLS.get(key, key)
        if key == "fields":
            value = ",".join(f"({a:g},{b:g})" for a, b in value)
        elif key == "lattice":
            value = "x".join(str(n) for n in value)
        elif isinstance(value, float):
            value = f"{value:g}"
        parts.append(f"{sym}={value}")
    model = str(record["model"])
    text = (f"({model}) " if " " in model else f"{model} ") + " ".join(parts)
    tail = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in extra)
    return f"{text.strip()}, {tail}" if tail else text.strip()
