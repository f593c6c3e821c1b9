"""Identification of the differential hysteresis models — Bouc–Wen and Jiles–Atherton — from an
input/output record, by nonlinear least squares.

Both models are Duhem operators (:mod:`hysteresis.duhem`): the output is the solution of an ODE
in the input, nonlinear in the parameters, so the fit is ``scipy.optimize.least_squares``
(trust-region reflective, bounds on every parameter, Jacobian by forward differences) on the
residuals ``model(u_t) − y_t`` of the training part of the record (the first
``train_fraction`` of the samples; the validation RMS is that of the rest, the operator driven
through the whole record).

Scaling. The record is first made dimensionless, ``ũ = u/s_u``, ``ỹ = (y − c_y)/s_y``
(``s`` half the peak-to-peak range, ``c_y`` the output's mid-range; Jiles–Atherton keeps
``c_y = 0``, its loop is odd), and every positive parameter is fitted as its logarithm, a
fraction in ``(0, 1)`` as its logit: the fitted coordinates are all of order one, so one
relative difference step and one trust region suit them all. The parameters are reported in
the record's units.

Standard errors. With ``J`` the Jacobian of the residuals at the optimum (in the fitted
coordinates θ), ``s² = Σ r²/(m − p)`` (``m`` training samples, ``p`` parameters) and
``cov(θ) = s²·(JᵀJ)⁻¹``, the usual asymptotic covariance of least squares under white noise;
the first sample's noise, which moves the initial state and with it the optimum by
``−(JᵀJ)⁻¹Jᵀ·∂(model)/∂y₀·δy₀``, adds its variance (``s²`` times that vector's outer
product); the named parameters' errors follow by the delta method,
``cov = G·cov(θ)·Gᵀ`` with ``G`` the
Jacobian of the map θ -> parameters (central differences). A correlated noise makes them too
small; a parameter at a bound (listed in ``info["at_bounds"]``) has no meaningful error.

Bouc–Wen (:func:`fit_bouc_wen`). Output model ``y = offset + linear·u + σ·z``, ``z`` the output
of ``BoucWen(A, beta, gamma, n)`` — the Bouc–Wen restoring force ``α·k·u + (1 − α)·k·z`` up to
an offset. ``σ = ±1`` is the loop's orientation, read from the record (the sign of
``∮ y du``): ``z`` is a smooth *stop* (its loop runs clockwise in ``(u, z)``: the rising branch
on top), so a play-like actuator (counter-clockwise, e.g. a piezo stack ``y = d·u − z``) has
``σ = −1``; it is not fitted. Identifiability: scaling ``z -> λz`` (``λ > 0``) maps
``(A, β, γ) -> (λA, λ^{1−n}β, λ^{1−n}γ)`` and gives the same loop ``λ`` times taller, so a
separate output scale (the restoring force's ``(1 − α)k``) would be degenerate with these three;
it is not fitted — ``z`` carries the record's output units, ``A`` is the slope of ``σz`` where
``z = 0``, the saturation is ``z_max = (A/(β + γ))^{1/n}``. ``linear`` (the force's ``α·k``)
is the slope where ``z`` saturates, ``linear + 2wσA`` the slope just after a reversal there,
``linear + σA`` the slope at ``z = 0``: all identifiable once the record approaches saturation
(a record that stays in the loop's middle correlates ``linear``, ``A`` and ``z_max``: their
standard errors say so). Fitted coordinates: ``log A``, ``log z_max``,
``w = β/(β + γ) >= 0``, ``log n``, the offset and ``linear``; ``(A, β, γ, n, offset,
linear)`` and ``z_max`` are reported. The first sample fixes the initial state:
``z = σ(y[0] − offset − linear·u[0])`` at ``u[0]`` (clipped into ``[−z_max, z_max]``; with
``linear=False`` and ``σ = +1``, ``z = y[0] − offset``).

Jiles–Atherton (:func:`fit_jiles_atherton`). Output ``M`` of
``JilesAtherton(ms, a, k, c, alpha)`` for the field ``H``; fitted coordinates ``log ms``,
``log a``, ``log k``, ``logit c`` and ``logit ρ`` with ``ρ = α·ms/(3a) ∈ (0, 1)`` (the
condition of a single-valued anhysteretic curve, stricter than the model's
``α·c·ms/(3a) < 1``). Where the model is ill-posed along the record (``1 − αχ <= 0``,
:class:`~hysteresis.jiles_atherton.JilesAthertonInstability`) the residuals are a large
constant, so the fit steers away from such parameters. The first ``(H, M)`` fixes the initial
memory ``M_irr``: the root of ``M(H_0, M_irr) = M_0`` (the output map is increasing in
``M_irr``; bisection on ``(−ms, ms)``).

Initial guesses and several starts: the guess comes from features of the loop (below, per
model), and the fit runs from several starts (the guess combined with a few values of the
parameter the features do not fix), each for a few iterations; the best is then iterated to
convergence. A user's ``initial`` guess is the first start.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from analysis.identification._record_fit import RecordFit, check_record, fit_result
from hysteresis import BoucWen, JilesAtherton, StaticMap, weighted_sum

__all__ = ["fit_bouc_wen", "fit_jiles_atherton", "loop_features"]

#: least number of samples of a record (and of its training part) for a nonlinear fit
MIN_SAMPLES = 20
#: residual evaluations of each start (the best start is then iterated to convergence)
_START_NFEV = 40
#: residual evaluations of the final iteration
_POLISH_NFEV = 400
#: relative difference step of the Jacobian (the model's integration error is ~1e-12, so the
#: difference quotient's rounding error is ~1e-6 relative and its truncation error ~1e-6 too)
_DIFF_STEP = 1e-6
#: residual of a parameter point where the model cannot be evaluated (far worse than any fit)
_PENALTY = 1e3


@dataclass(frozen=True)
class _Problem:
    """A fit in the dimensionless record: ``simulate(θ, ũ, ỹ0) -> ỹ``, ``natural(θ)`` the
    reported parameters (record units), bounds of θ."""

    names: tuple[str, ...]
    coordinates: tuple[str, ...]
    simulate: Callable[[np.ndarray, np.ndarray, float], np.ndarray]
    natural: Callable[[np.ndarray], np.ndarray]
    lower: np.ndarray
    upper: np.ndarray


def _least_squares(
    problem: _Problem, starts: Sequence[np.ndarray], u: np.ndarray, y: np.ndarray
) -> tuple[Any, list[float]]:
    """The best of the starts (each ``_START_NFEV`` evaluations), iterated to convergence."""
    # scipy.optimize costs ~0.3 s at import: loaded where used (fast `hyst` start)
    from scipy.optimize import least_squares

    def residuals(theta: np.ndarray) -> np.ndarray:
        try:
            pred = problem.simulate(theta, u, float(y[0]))
        except (ValueError, ArithmeticError):  # outside the model's domain, or no integration
            return np.full(y.size, _PENALTY)
        r = pred - y
        return r if np.all(np.isfinite(r)) else np.full(y.size, _PENALTY)

    def run(x0: np.ndarray, nfev: int) -> Any:
        x0 = np.clip(x0, problem.lower, problem.upper)
        return least_squares(
            residuals,
            x0,
            bounds=(problem.lower, problem.upper),
            method="trf",
            diff_step=_DIFF_STEP,
            max_nfev=nfev,
            x_scale=1.0,
            ftol=1e-12,
            xtol=1e-12,
        )

    tried = [run(np.asarray(x, dtype=float), _START_NFEV) for x in starts]
    costs = [float(r.cost) for r in tried]
    best = tried[int(np.argmin(costs))]
    if best.status == 0:  # stopped by the evaluation budget: iterate on
        best = run(best.x, _POLISH_NFEV)
    return best, costs


def _errors(problem: _Problem, res: Any, u: np.ndarray, y0: float) -> tuple[np.ndarray, np.ndarray]:
    """``(parameters, standard errors)``: ``s²(JᵀJ)⁻¹`` in θ, plus the noise of the first
    sample (which fixes the initial state), carried by the delta method."""
    jac = np.asarray(res.jac, dtype=float)
    m, p = jac.shape
    dof = max(m - p, 1)
    s2 = 2.0 * float(res.cost) / dof
    us, sv, vt = np.linalg.svd(jac, full_matrices=False)
    # a direction the data do not constrain gets a huge (not an infinite) variance
    sv = np.maximum(sv, 1e-300 + 1e-13 * (sv[0] if sv.size else 1.0))
    cov = (vt.T / sv**2) @ vt * s2
    theta = res.x
    # the first sample's noise moves the initial state, hence the optimum by
    # δθ = −(JᵀJ)⁻¹Jᵀ·(∂pred/∂y0)·δy0 with var(δy0) = s²
    h = 1e-6
    dpred = (problem.simulate(theta, u, y0 + h) - problem.simulate(theta, u, y0 - h)) / (2 * h)
    shift = -(vt.T / sv) @ (us.T @ dpred)
    cov = cov + s2 * np.outer(shift, shift)
    g = np.empty((len(problem.names), p))
    for j in range(p):
        h = 1e-6 * max(1.0, abs(theta[j]))
        up, down = theta.copy(), theta.copy()
        up[j] += h
        down[j] -= h
        g[:, j] = (problem.natural(up) - problem.natural(down)) / (2.0 * h)
    var = np.einsum("ij,jk,ik->i", g, cov, g)
    return problem.natural(theta), np.sqrt(np.maximum(var, 0.0))


def _monotone_runs(u: np.ndarray) -> list[np.ndarray]:
    """Index arrays of the maximal monotone runs of ``u`` (a run starts at a reversal)."""
    d = np.sign(np.diff(u))
    runs, start, direction = [], 0, 0
    for i, s in enumerate(d):
        if s == 0 or s == direction or direction == 0:
            direction = direction or int(s)
            continue
        runs.append(np.arange(start, i + 1))
        start, direction = i, int(s)
    runs.append(np.arange(start, u.size))
    return [r for r in runs if r.size >= 2]


def _slope(u: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of ``y`` on ``u`` (NaN for fewer than 3 points or no spread)."""
    if u.size < 3 or np.ptp(u) == 0:
        return float("nan")
    return float(np.polyfit(u, y, 1)[0])


def loop_features(u: Any, y: Any) -> dict[str, float]:
    """Features of a hysteresis record, in its own units.

    ``center`` (mid-range of ``y``), ``saturation`` (half the range of ``y``), ``coercivity``
    (median ``|u − u_c|`` where ``y`` crosses ``center``, ``u_c`` the input's mid-range),
    ``remanence`` (median ``|y − center|`` where ``u`` crosses ``u_c``),
    ``initial_susceptibility`` (median slope ``dy/du`` of the monotone runs through
    ``|y − center| < 0.35·saturation``: Bouc–Wen's ``A``) and ``reversal_susceptibility``
    (median slope over the first tenth of the input range after a reversal at
    ``|y − center| > 0.6·saturation``). NaN where the record has none of them.
    """
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    cy = 0.5 * (y.max() + y.min())
    sy = 0.5 * float(np.ptp(y))
    cu = 0.5 * (u.max() + u.min())
    su = 0.5 * float(np.ptp(u))
    yc, uc = y - cy, u - cu
    cross_y = np.nonzero(np.signbit(yc[1:]) != np.signbit(yc[:-1]))[0]
    cross_u = np.nonzero(np.signbit(uc[1:]) != np.signbit(uc[:-1]))[0]
    centre, after = [], []
    for run in _monotone_runs(u):
        mid = run[np.abs(yc[run]) < 0.35 * sy]
        centre.append(_slope(u[mid], y[mid]))
        if abs(yc[run[0]]) > 0.6 * sy:
            near = run[np.abs(u[run] - u[run[0]]) <= 0.1 * su]
            after.append(_slope(u[near], y[near]))

    def median(values: Any) -> float:
        v = np.asarray(values, dtype=float)
        v = v[np.isfinite(v)]
        return float(np.median(v)) if v.size else float("nan")

    return {
        "center": float(cy),
        "saturation": sy,
        "coercivity": median(np.abs(uc[cross_y])),
        "remanence": median(np.abs(yc[cross_u])),
        "initial_susceptibility": median([s for s in centre if s > 0]),
        "reversal_susceptibility": median([s for s in after if s > 0]),
    }


def _scales(u: np.ndarray, y: np.ndarray, centred: bool) -> tuple[float, float, float]:
    """``(s_u, s_y, c_y)`` of the dimensionless record (module docstring)."""
    su = 0.5 * float(np.ptp(u))
    sy = 0.5 * float(np.ptp(y)) if centred else float(np.max(np.abs(y)))
    if not su > 0:
        raise ValueError("u must vary (a constant input identifies nothing)")
    if not sy > 0:
        raise ValueError("y must vary (a constant output identifies no hysteresis)")
    return su, sy, (0.5 * float(y.max() + y.min()) if centred else 0.0)


def _check_starts(n_starts: Any) -> int:
    if isinstance(n_starts, bool) or not isinstance(n_starts, (int, np.integer)):
        raise TypeError(f"n_starts must be an int, got {type(n_starts).__name__}")
    if not 1 <= n_starts <= 50:
        raise ValueError(f"n_starts must be in [1, 50], got {n_starts}")
    return int(n_starts)


def _finish(
    problem: _Problem,
    res: Any,
    costs: list[float],
    guess: Mapping[str, float],
    t0: float,
    build: Callable[[dict[str, float]], tuple[Any, Any, float]],
    u: np.ndarray,
    y: np.ndarray,
    n_train: int,
    train: tuple[np.ndarray, np.ndarray],
) -> RecordFit:
    """The :class:`RecordFit`: parameters and errors (``train`` the dimensionless training
    record), the model and its initial state (``build``), predictions of the whole record."""
    values, errors = _errors(problem, res, train[0], float(train[1][0]))
    params = {n: float(v) for n, v in zip(problem.names, values, strict=True)}
    model, state, offset = build(params)
    pred, _ = model.apply(u, state)
    # fitted coordinates at a bound: their errors are not meaningful
    at_bounds = [c for c, m in zip(problem.coordinates, res.active_mask, strict=True) if m]
    info = {
        "starts": len(costs),
        "start_costs": costs,
        "evaluations": int(res.nfev),
        "status": res.message,
        "seconds": time.perf_counter() - t0,
        "initial_guess": dict(guess),
        "at_bounds": at_bounds,
    }
    return fit_result(
        model,
        offset,
        1.0,
        offset + pred,
        y,
        n_train,
        parameters=params,
        standard_errors={n: float(e) for n, e in zip(problem.names, errors, strict=True)},
        initial_state=state,
        info=info,
    )


# -- Bouc–Wen -----------------------------------------------------------------------------------

_BW_NAMES = ("A", "beta", "gamma", "n", "offset", "z_max")


def _identity(u: np.ndarray) -> np.ndarray:
    return u


def _unit_slope(u: np.ndarray) -> np.ndarray:
    return np.ones_like(u)


def _bw_dimensionless(theta: np.ndarray) -> tuple[float, float, float, float, float, float]:
    """``(A, β, γ, n, offset, z_max)`` of the dimensionless record from θ."""
    a = math.exp(theta[0])
    z_max = math.exp(theta[1])
    w = float(theta[2])
    n = math.exp(theta[3])
    s = a / z_max**n  # β + γ
    return a, w * s, (1.0 - w) * s, n, float(theta[4]), z_max


def _orientation(u: np.ndarray, y: np.ndarray) -> int:
    """+1 when the loop runs clockwise in ``(u, y)`` (``∮ y du > 0``: the rising branch above
    the falling one, as Bouc–Wen's ``z``, a smooth stop), −1 counter-clockwise (a play-like
    actuator, ``y = d·u − z``)."""
    area = float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(u)))
    return 1 if area >= 0.0 else -1


def _tip_slope(u: np.ndarray, y: np.ndarray) -> float:
    """Median slope over the last 15 % of the input range before each reversal (where ``z``
    saturates, the slope is the linear term's)."""
    su = 0.5 * float(np.ptp(u))
    slopes = []
    for run in _monotone_runs(u)[:-1]:
        near = run[np.abs(u[run] - u[run[-1]]) <= 0.15 * su]
        slopes.append(_slope(u[near], y[near]))
    v = np.asarray(slopes, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.median(v)) if v.size else 0.0


def fit_bouc_wen(
    u: Any,
    y: Any,
    *,
    train_fraction: float = 0.7,
    n_starts: int = 3,
    linear: bool = True,
    initial: Mapping[str, float] | None = None,
) -> RecordFit:
    """Fit ``y ≈ offset + linear·u + σ·BoucWen(A, beta, gamma, n)[u]`` to a record (module
    docstring; ``σ = ±1`` the loop's orientation, from the sign of ``∮ y du``).

    Parameters
    ----------
    u, y:
        Input and output samples (1-D, same length >= 20, finite).
    train_fraction:
        Fraction (0, 1] of the record, from its start, used for the fit.
    n_starts:
        Starts from the loop features (:func:`loop_features` of ``σ(y − linear·u)``): the
        linear term the slope before the reversals, ``A`` the initial susceptibility,
        ``z_max`` the saturation, ``offset`` the centre, ``w`` from the reversal
        susceptibility; ``n`` takes the values 1, 2, 4, 1.5, 3, ... in turn.
    linear:
        Fit the linear term (else ``linear = 0``).
    initial:
        A guess ``{"A", "beta", "gamma", "n"[, "offset", "linear"]}`` in the record's units,
        the first of the ``n_starts`` (``n_starts=1``: the only one).

    Returns
    -------
    RecordFit
        ``model`` the operator ``linear·u + σ·z`` (a :class:`~hysteresis.algebra.WeightedSum`
        of an identity :class:`~hysteresis.StaticMap` and a :class:`~hysteresis.BoucWen`; the
        :class:`~hysteresis.BoucWen` itself when ``linear=False`` and ``σ = +1``),
        ``y ≈ offset + model(u)`` from ``initial_state`` (``z = σ(y[0] − offset −
        linear·u[0])`` at ``u[0]``); ``parameters`` and ``standard_errors`` for ``A, beta,
        gamma, n, offset, z_max`` (and ``linear``); ``info["orientation"]`` is ``σ``.
    """
    t0 = time.perf_counter()
    u, y, n_train = check_record(u, y, train_fraction, MIN_SAMPLES)
    n_starts = _check_starts(n_starts)
    if not isinstance(linear, bool):
        raise TypeError(f"linear must be a bool, got {type(linear).__name__}")
    su, sy, cy = _scales(u, y, centred=True)
    un, yn = u / su, (y - cy) / sy
    sign = _orientation(un[:n_train], yn[:n_train])

    def parts(theta: np.ndarray, u0: float, y0: float) -> tuple[Any, Any, float, float]:
        a, beta, gamma, n, offset, _ = _bw_dimensionless(theta)
        d = float(theta[5]) if linear else 0.0
        op = BoucWen(a, beta, gamma, n)
        lim = op.z_max * (1.0 - 1e-9)
        z0 = min(max(sign * (y0 - offset - d * u0), -lim), lim)
        return op, op.state(z0, u0), offset, d

    def simulate(theta: np.ndarray, uu: np.ndarray, y0: float) -> np.ndarray:
        op, state, offset, d = parts(theta, float(uu[0]), y0)
        z, _ = op.apply(uu, state)
        return offset + d * uu + sign * z

    def natural(theta: np.ndarray) -> np.ndarray:
        a, beta, gamma, n, offset, z_max = _bw_dimensionless(theta)
        k = sy ** (1.0 - n) / su  # z = s_y·z̃, u = s_u·ũ (module docstring)
        out = [a * sy / su, beta * k, gamma * k, n, cy + sy * offset, sy * z_max]
        return np.array(out + ([float(theta[5]) * sy / su] if linear else []))

    lower = [math.log(1e-3), math.log(0.05), 0.0, 0.0, -2.0] + ([-50.0] if linear else [])
    upper = [math.log(1e4), math.log(50.0), 20.0, math.log(30.0), 2.0] + ([50.0] if linear else [])
    problem = _Problem(
        _BW_NAMES + (("linear",) if linear else ()),
        ("log A", "log z_max", "w", "log n", "offset") + (("linear",) if linear else ()),
        simulate,
        natural,
        np.array(lower),
        np.array(upper),
    )
    d0 = _tip_slope(un[:n_train], yn[:n_train]) if linear else 0.0
    feats = loop_features(un[:n_train], sign * (yn[:n_train] - d0 * un[:n_train]))
    a0 = feats["initial_susceptibility"]
    a0 = a0 if math.isfinite(a0) and a0 > 0 else 2.0
    w0 = feats["reversal_susceptibility"] / (2.0 * a0)
    w0 = min(max(w0, 0.05), 5.0) if math.isfinite(w0) else 0.75
    zm0 = min(max(1.02 * feats["saturation"], 0.1), 10.0)
    o0 = sign * feats["center"]
    exponents = (1.0, 2.0, 4.0, 1.5, 3.0, 6.0, 1.2, 2.5, 5.0, 8.0)
    starts = [
        np.array([math.log(a0), math.log(zm0), w0, math.log(n), o0] + ([d0] if linear else []))
        for n in (exponents * 5)[:n_starts]
    ]
    if initial is not None:  # the user's guess first, within the n_starts
        starts = [_bw_theta(initial, su, sy, cy, linear), *starts][:n_starts]
    guess = {
        "A": a0 * sy / su,
        "z_max": zm0 * sy,
        "w": w0,
        "offset": cy + sy * o0,
        "linear": d0 * sy / su,
        "orientation": sign,
    }
    res, costs = _least_squares(problem, starts, un[:n_train], yn[:n_train])

    def build(p: dict[str, float]) -> tuple[Any, Any, float]:
        bw = BoucWen(p["A"], p["beta"], p["gamma"], p["n"])
        u0 = float(u[0])
        d = p.get("linear", 0.0)
        lim = bw.z_max * (1.0 - 1e-9)
        state = bw.state(min(max(sign * (float(y[0]) - p["offset"] - d * u0), -lim), lim), u0)
        if not linear and sign == 1:
            return bw, state, p["offset"]
        ident = StaticMap(_identity, _unit_slope, name="u")
        model = (
            weighted_sum([ident, bw], [d, float(sign)]) if linear else weighted_sum([bw], [-1.0])
        )
        states = (ident.initial_state(u0), state) if linear else (state,)
        return model, model.state(*states), p["offset"]

    train = (un[:n_train], yn[:n_train])
    fit = _finish(problem, res, costs, guess, t0, build, u, y, n_train, train)
    return replace(fit, info={**dict(fit.info or {}), "orientation": sign})


def _bw_theta(
    initial: Mapping[str, float], su: float, sy: float, cy: float, linear: bool
) -> np.ndarray:
    """θ of a guess in the record's units (checked by building the operator)."""
    if not isinstance(initial, Mapping):
        raise TypeError(f"initial must be a mapping of parameters, got {type(initial).__name__}")
    known = {"A", "beta", "gamma", "n", "offset", "linear"}
    unknown = sorted(set(initial) - known)
    if unknown:
        raise ValueError(f"initial has unknown keys {unknown}; known: {sorted(known)}")
    try:
        op = BoucWen(initial["A"], initial["beta"], initial["gamma"], initial.get("n", 1.0))
    except KeyError as exc:
        raise ValueError(f"initial must give A, beta and gamma (missing {exc})") from None
    a = op.A * su / sy
    z_max = op.z_max / sy
    w = op.beta / (op.beta + op.gamma)
    offset = (float(initial.get("offset", cy)) - cy) / sy
    theta = [math.log(a), math.log(z_max), w, math.log(op.n), offset]
    return np.array(theta + ([float(initial.get("linear", 0.0)) * su / sy] if linear else []))


# -- Jiles–Atherton -----------------------------------------------------------------------------

_JA_NAMES = ("ms", "a", "k", "c", "alpha")


def _logit(p: float) -> float:
    return math.log(p / (1.0 - p))


def _expit(x: float) -> float:
    return 1.0 / (1.0 + math.exp(-x)) if x >= 0 else math.exp(x) / (1.0 + math.exp(x))


def _ja_dimensionless(theta: np.ndarray) -> tuple[float, float, float, float, float]:
    """``(ms, a, k, c, alpha)`` of the dimensionless record from θ."""
    ms, a, k = math.exp(theta[0]), math.exp(theta[1]), math.exp(theta[2])
    c, rho = _expit(float(theta[3])), _expit(float(theta[4]))
    return ms, a, k, c, 3.0 * rho * a / ms


def _initial_memory(model: Any, h0: float, m0: float) -> Any:
    """The state at ``h0`` whose output is ``m0``: ``M(h0, M_irr)`` is increasing in
    ``M_irr``, so bisection on ``(−ms, ms)`` (to a few ulps of ``ms``); an ``m0`` beyond the
    outputs there (noise at saturation) takes the nearest end."""
    lo, hi = -model.ms * (1.0 - 1e-9), model.ms * (1.0 - 1e-9)
    if model.map_output(h0, lo) >= m0:
        return model.state(lo, h0)
    if model.map_output(h0, hi) <= m0:
        return model.state(hi, h0)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if model.map_output(h0, mid) < m0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 4e-16 * model.ms:
            break
    return model.state(0.5 * (lo + hi), h0)


def _ja_simulate(theta: np.ndarray, h: np.ndarray, m0: float) -> np.ndarray:
    model = JilesAtherton(*_ja_dimensionless(theta))
    m, _ = model.apply(h, _initial_memory(model, float(h[0]), m0))
    return m


def fit_jiles_atherton(
    H: Any,
    M: Any,
    *,
    train_fraction: float = 0.7,
    n_starts: int = 4,
    initial: Mapping[str, float] | None = None,
) -> RecordFit:
    """Fit ``M ≈ JilesAtherton(ms, a, k, c, alpha)[H]`` to a record (module docstring).

    Parameters
    ----------
    H, M:
        Field and magnetisation samples (1-D, same length >= 20, finite; any consistent units).
    train_fraction:
        Fraction (0, 1] of the record, from its start, used for the fit.
    n_starts:
        Starts from the loop features (:func:`loop_features`): ``k`` the coercivity, ``ms``
        1.15 times the largest ``|M|`` (a measured loop rarely saturates fully) and ``a`` such
        that the anhysteretic curve reaches the loop's tip; ``(c, ρ)`` taking the values
        (0.2, 0.3), (0.5, 0.1), (0.1, 0.6), (0.5, 0.5), ... in turn.
    initial:
        A guess ``{"ms", "a", "k", "c", "alpha"}`` in the record's units, the first of the
        ``n_starts`` (``n_starts=1``: the only one).

    Returns
    -------
    RecordFit
        ``model`` a :class:`~hysteresis.JilesAtherton`, ``M ≈ model(H)`` from ``initial_state``
        (``M_irr`` from the first sample); ``parameters`` and ``standard_errors`` for
        ``ms, a, k, c, alpha``.
    """
    t0 = time.perf_counter()
    h, m, n_train = check_record(H, M, train_fraction, MIN_SAMPLES)
    n_starts = _check_starts(n_starts)
    sh, sm, _ = _scales(h, m, centred=False)
    hn, mn = h / sh, m / sm

    def natural(theta: np.ndarray) -> np.ndarray:
        ms, a, k, c, alpha = _ja_dimensionless(theta)
        return np.array([ms * sm, a * sh, k * sh, c, alpha * sh / sm])

    problem = _Problem(
        _JA_NAMES,
        ("log ms", "log a", "log k", "logit c", "logit rho"),
        _ja_simulate,
        natural,
        np.array([math.log(0.5), math.log(1e-3), math.log(1e-3), _logit(1e-4), _logit(1e-4)]),
        np.array([math.log(20.0), math.log(1e2), math.log(1e2), _logit(0.99), _logit(0.99)]),
    )
    feats = loop_features(hn, mn)
    k0 = feats["coercivity"]
    k0 = k0 if math.isfinite(k0) and k0 > 0 else 0.2
    ms0 = 1.15
    # L(x) = 1/ms0 at the tip (H, M) ≈ (1, 1): x ≈ 1/(1 − 1/ms0), the large-x form of L
    x_tip = 1.0 / (1.0 - 1.0 / ms0)
    pairs = ((0.2, 0.3), (0.5, 0.1), (0.1, 0.6), (0.5, 0.5), (0.3, 0.05), (0.05, 0.2))
    starts = []
    for c0, rho0 in (pairs * 9)[:n_starts]:
        a0 = 1.0 / max(x_tip - 3.0 * rho0 / ms0, 1.0)  # H + αM = a·x at the tip
        starts.append(
            np.array([math.log(ms0), math.log(a0), math.log(k0), _logit(c0), _logit(rho0)])
        )
    if initial is not None:  # the user's guess first, within the n_starts
        starts = [_ja_theta(initial, sh, sm), *starts][:n_starts]
    guess = {"ms": ms0 * sm, "k": k0 * sh, "coercivity": feats["coercivity"] * sh}
    res, costs = _least_squares(problem, starts, hn[:n_train], mn[:n_train])

    def build(p: dict[str, float]) -> tuple[Any, Any, float]:
        model = JilesAtherton(p["ms"], p["a"], p["k"], p["c"], p["alpha"])
        return model, _initial_memory(model, float(h[0]), float(m[0])), 0.0

    train = (hn[:n_train], mn[:n_train])
    return _finish(problem, res, costs, guess, t0, build, h, m, n_train, train)


def _ja_theta(initial: Mapping[str, float], sh: float, sm: float) -> np.ndarray:
    """θ of a guess in the record's units (checked by building the operator)."""
    if not isinstance(initial, Mapping):
        raise TypeError(f"initial must be a mapping of parameters, got {type(initial).__name__}")
    keys = {"ms", "a", "k", "c", "alpha"}
    if set(initial) != keys:
        raise ValueError(f"initial must give exactly {sorted(keys)}, got {sorted(initial)}")
    op = JilesAtherton(initial["ms"], initial["a"], initial["k"], initial["c"], initial["alpha"])
    c = min(max(op.c, 1e-4), 0.99)
    rho = min(max(op.alpha * op.ms / (3.0 * op.a), 1e-4), 0.99)
    return np.array(
        [math.log(op.ms / sm), math.log(op.a / sh), math.log(op.k / sh), _logit(c), _logit(rho)]
    )
