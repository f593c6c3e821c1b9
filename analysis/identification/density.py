"""Identification of the Preisach density from reversal curves.

The Everett function is tabulated on the *native* grid (reversal fields × union of field
values: exact cell masses of simulated or shared-lattice data) or on the *protocol* lattice
(measured data, regridded onto the measurement's field step), the exact cell masses are its
mixed second differences, and the smoothed density is a local quadratic regression
(:mod:`analysis.identification.smoothing`). Conventions: :mod:`analysis.identification.curves`;
cells and masses: :mod:`analysis.identification.result`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from analysis.identification._checks import positive_number
from analysis.identification.curves import (
    ReversalCurves,
    measure_reversal_curves,
    protocol_lattice,
    regular_grid,
    rising_form,
)
from analysis.identification.memory import check_memory, estimate_identification_bytes
from analysis.identification.result import PreisachIdentification
from analysis.identification.smoothing import (
    WINDOWS,
    grid_quadratic_density,
    local_quadratic_density,
)
from analysis.identification.smoothing_choice import auto_candidates, choose_smoothing
from analysis.identification.variforc import VariforcParameters, weighted_quadratic_density
from hysteresis._validation import check_grid_nodes

__all__ = ["identify_preisach", "identify_from_curves", "auto_grid", "estimate_memory"]

GRIDS = ("auto", "native", "protocol")


def identify_preisach(
    operator: Any,
    step: float,
    saturation: float,
    *,
    centre: float = 0.0,
    smoothing: float | tuple[float, float] | None = None,
    progress: bool = False,
    max_memory: float | None = None,
) -> PreisachIdentification:
    """Identify the Preisach density of ``operator`` from reversal curves on a regular grid.

    The grid is :func:`regular_grid` ``(step, saturation, centre)``. For every node ``α_i`` the
    operator is put in ``initial_state(α_i)`` (rise from negative saturation) and driven by one
    ``apply`` through the descending nodes ``α_i, α_{i−1}, …, α_0`` (Mayergoyz convention). The
    result holds the Everett function on the grid and the exact cell masses (see
    :mod:`analysis.identification.result`). ``saturation`` should make the operator saturate
    at ``±saturation`` (for the paper's density, ``saturation >= 5R + p/2`` leaves < 6·10⁻⁷ of
    the mass outside).

    Parameters
    ----------
    smoothing:
        ``None`` (no smoothed density), a smoothing factor ``SF`` (isotropic) or
        ``(SF_r, SF_s)``: local quadratic regression of ``E`` over the nodes with
        ``|Δr| <= SF_r·Δ`` and ``|Δs| <= SF_s·Δ`` (keep ``SF_r`` small across a ridge and
        ``SF_s`` larger along it); see :func:`local_quadratic_density`.
    max_memory:
        Bound in bytes on the estimated peak memory
        (:func:`~analysis.identification.memory.estimate_identification_bytes`; default
        :func:`~analysis.identification.memory.default_max_memory`): a larger grid is refused
        with :class:`~analysis.identification.memory.MemoryBoundError` before the operator is
        driven.
    """
    n = check_grid_nodes(step, saturation)  # refuse an unbounded grid (MAX_GRID_NODES) up front
    sm = None if smoothing is None else _smoothing_factors(smoothing)
    estimate = estimate_identification_bytes(n * (n + 1) // 2, n, smoothing=sm, grid="native")
    check_memory(estimate, max_memory)
    grid = regular_grid(step, saturation, centre)
    curves = measure_reversal_curves(operator, grid, convention="mayergoyz", progress=progress)
    output_range = tuple(float(x) for x in getattr(operator, "output_range", (-1.0, 1.0)))
    return identify_from_curves(curves, smoothing=smoothing, output_range=output_range, extend=True)


def _everett_table(curves: ReversalCurves) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """E on (curve nodes × union of fields); returns (alpha_nodes, beta_nodes, E[alpha, beta]).

    Along each curve E is taken at its native points, linearly interpolated between them (exact
    at the native points; exact everywhere when the curves share their field values), zero on the
    reversal side (the exact extension) and constant beyond the curve's last point (the curve is
    assumed to end in saturation).
    """
    order = np.argsort(curves.reversal_field)
    rev = curves.reversal_field[order]
    pts = np.unique(np.concatenate(curves.fields))
    table = np.zeros((rev.size, pts.size))
    for row, c in enumerate(order):
        h = curves.fields[c]
        m = curves.moments[c]
        if curves.convention == "mayergoyz":
            e = 0.5 * (m[0] - m)  # E(α = H_r, β = h)
            # h falls; np.interp needs ascending abscissae
            vals = np.interp(pts, h[::-1], e[::-1])  # constant beyond both ends
            vals[pts >= h[0]] = 0.0
        else:
            e = 0.5 * (m - m[0])  # E(α = h, β = H_r)
            vals = np.interp(pts, h, e)
            vals[pts <= h[0]] = 0.0
        table[row] = vals
    if curves.convention == "mayergoyz":
        return rev, pts, table
    return pts, rev, table.T.copy()


def _is_regular(alpha: np.ndarray, beta: np.ndarray) -> float | None:
    if alpha.size < 2 or alpha.size != beta.size or not np.array_equal(alpha, beta):
        return None
    d = np.diff(alpha)
    step = (alpha[-1] - alpha[0]) / (alpha.size - 1)
    if np.allclose(d, step, rtol=1e-9, atol=0.0):
        return float(step)
    return None


def identify_from_curves(
    curves: ReversalCurves,
    *,
    smoothing: float | tuple[float, float] | None = None,
    output_range: tuple[float, float] = (-1.0, 1.0),
    extend: bool | None = None,
    grid: str = "auto",
    step: float | None = None,
    window: str = "rs",
    max_memory: float | None = None,
    uncertainty: bool = False,
) -> PreisachIdentification:
    """Identify from reversal-curve data (measured or simulated, regular or irregular).

    Parameters
    ----------
    curves:
        The reversal curves (either convention).
    smoothing:
        ``None`` (cell masses only), a smoothing factor ``SF`` or ``(SF_r, SF_s)``: local
        quadratic regression of ``E`` in the window ``|Δr| <= SF_r·Δ``, ``|Δs| <= SF_s·Δ``
        (see :func:`identify_preisach`). On the native grid of irregular data the unit ``Δ`` is
        the larger of the median reversal-field spacing and the median field step.
        May also be ``"variforc"`` or a
        :class:`~analysis.identification.variforc.VariforcParameters`: VARIFORC smoothing (Egli
        2013) on the lattice (protocol grid, or a regular native grid), regressed on ``M/2``; or
        ``"auto"``: VARIFORC with the far-field half-width ``s_1`` chosen per data set among
        :data:`~analysis.identification.smoothing_choice.AUTO_CANDIDATES` by a Lepski/ICI
        rule on ``ρ`` (the largest smoothing whose ``ρ`` stays within noise of every finer
        one; :mod:`analysis.identification.smoothing_choice`), the criterion, scores and
        choice in :attr:`PreisachIdentification.smoothing_choice`.
    output_range:
        Saturation outputs (for :attr:`PreisachIdentification.mass_outside_grid`); pass
        ``(-inf, inf)`` for measured data of unknown saturation.
    extend:
        Use the extension ``E = 0`` for ``β >= α`` in the regression. This is exact for relay
        (Preisach) systems and puts the reversible part of a measured sample into a ridge at
        ``r = 0``; ``False`` regresses measured points only (the usual irreversible FORC
        density, NaN where a window has no data on one side of a node). Default (``None``):
        ``True`` on the native grid (simulated data), ``False`` on the protocol grid
        (measured data: the reversible ridge is excluded unless asked for).
    grid:
        ``"native"``: nodes are the reversal fields along one axis and the union of all field
        values along the other (exact cell masses of simulated or shared-lattice data; no
        regridding). ``"protocol"``: a regular lattice with the measurement's field step ``Δ``
        (``step``, default the median field increment along the curves), anchored at the
        reversal fields; each curve is interpolated linearly onto it along the field and
        neighbouring curves linearly across reversal fields. Use it for measured data, whose
        field values all differ slightly (the native grid of such data has near-zero-area
        cells). ``"auto"`` (default): :func:`auto_grid`; with VARIFORC or uncertainty, an
        irregular native grid is replaced by the protocol lattice (the weighted regression
        needs a regular lattice).
    step:
        Lattice step of the protocol grid (> 0); ignored on the native grid.
    window:
        Shape of the regression window on the protocol grid: ``"rs"`` (default),
        ``|Δr| <= SF_r·Δ`` and ``|Δs| <= SF_s·Δ``; ``"pike"``, Pike et al. (1999)'s square
        ``|Δα| <= SF·Δ`` and ``|ΔB_r| = |Δβ| <= SF·Δ`` (``(2 SF + 1)²`` points, ``SF = SF_r``).
        The native grid always uses ``"rs"``.
    max_memory:
        Bound in bytes on the estimated peak memory (default
        :func:`~analysis.identification.memory.default_max_memory`); above it the identification
        is refused with :class:`~analysis.identification.memory.MemoryBoundError` before the
        lattice is allocated (:func:`estimate_memory` gives the estimate).
    uncertainty:
        Also compute the standard error of the smoothed density at every node
        (:attr:`PreisachIdentification.density_se`; :mod:`analysis.identification.variforc`).
        With a fixed factor the density is then the same estimator regressed on the half
        moments ``M/2`` (independent noise per point) instead of the Everett differences; it
        differs from the default by the reversal points' noise only.

    Returns
    -------
    PreisachIdentification
        With ``measured`` set on the protocol grid (nodes backed by data; outside it ``E`` is
        extended: 0 for ``β >= α``, constant beyond a curve's last point) and the smoothed
        density NaN wherever the node is not measured or its window lacks data on either side
        across or along the diagonal.
    """
    if grid not in GRIDS:
        raise ValueError(f"grid must be one of {GRIDS}, got {grid!r}")
    if window not in WINDOWS:
        raise ValueError(f"window must be one of {WINDOWS}, got {window!r}")
    check_memory(
        estimate_memory(curves, smoothing=smoothing, grid=grid, step=step, uncertainty=uncertainty),
        max_memory,
    )
    smoothing = _variforc_or(smoothing)
    grid, lattice = _grid_and_fit(curves, smoothing, grid, uncertainty)
    if uncertainty and smoothing is None:
        raise ValueError("uncertainty needs smoothing (a factor or VARIFORC)")
    if lattice and window != "rs":
        raise ValueError("VARIFORC and uncertainty use the rs window; window must be 'rs'")
    if grid == "protocol":
        ext = False if extend is None else bool(extend)
        return _identify_protocol(
            curves, smoothing, output_range, ext, step, window, lattice, uncertainty
        )
    extend = True if extend is None else bool(extend)
    alpha, beta, E = _everett_table(curves)
    if alpha.size < 2 or beta.size < 2:
        raise ValueError("need at least two reversal curves and two distinct fields")
    mass = E[1:, :-1] - E[:-1, :-1] - E[1:, 1:] + E[:-1, 1:]
    reg_step = _is_regular(alpha, beta)
    density = None
    sm = None
    extra: dict[str, Any] = {}
    if lattice:
        if reg_step is None:
            raise ValueError(
                "VARIFORC and uncertainty need a regular lattice: fields on one regular grid "
                "shared by the curves, or grid='protocol'"
            )
        aa, bb = np.meshgrid(alpha, beta, indexing="ij")
        valid = _native_valid(curves, alpha, beta) | ((bb > aa) if extend else False)
        values = E + _native_offsets(curves, alpha, beta)
        extra = _lattice_fit(
            values, valid, valid & (bb <= aa), reg_step, smoothing, alpha[0], uncertainty
        )
        if uncertainty:
            extra["noise_sigma"] = measurement_noise(curves, extra["noise_sigma"])
        density = extra.pop("density")
        sm = extra.pop("sm")
    elif smoothing is not None:
        sm = _smoothing_factors(smoothing)
        unit = reg_step if reg_step is not None else _typical_step(curves)
        pa, pb, pe = _native_points(
            curves, beta if curves.convention == "mayergoyz" else alpha, extend
        )
        aa, bb = np.meshgrid(alpha, beta, indexing="ij")
        where = bb <= aa
        density = np.full(aa.shape, np.nan)
        density[where] = local_quadratic_density(
            pa, pb, pe, aa[where], bb[where], sm[0] * unit, sm[1] * unit
        )
    for arr in (alpha, beta, E, mass):
        arr.setflags(write=False)
    if density is not None:
        density.setflags(write=False)
    return PreisachIdentification(
        alpha=alpha,
        beta=beta,
        everett=E,
        cell_mass=mass,
        step=reg_step,
        output_range=(float(output_range[0]), float(output_range[1])),
        density_alpha_beta=density,
        smoothing=sm,
        convention=curves.convention,
        reversible_ridge=extend,
        n_curves=curves.n_curves,
        n_points=curves.n_points,
        curve_kind=curves.kind,
        **extra,
    )


def _variforc_or(smoothing: Any) -> Any:
    """``"variforc"`` -> the default :class:`VariforcParameters`; ``"auto"`` kept; anything
    else unchanged."""
    if isinstance(smoothing, str):
        if smoothing == "auto":
            return smoothing
        if smoothing != "variforc":
            raise ValueError(
                f"smoothing must be a factor, a pair (SF_r, SF_s), 'variforc', 'auto' or "
                f"VariforcParameters, got {smoothing!r}"
            )
        return VariforcParameters()
    return smoothing


def _lattice_fit(
    values: np.ndarray,
    valid: np.ndarray,
    evaluate: np.ndarray,
    step: float,
    smoothing: Any,
    origin: float,
    errors: bool,
) -> dict[str, Any]:
    """The weighted lattice regression (VARIFORC or a fixed factor with standard errors) as
    the fields of :class:`PreisachIdentification`."""
    choice = None
    if isinstance(smoothing, str):  # "auto"
        smoothing, choice = choose_smoothing(values, valid, evaluate, step, origin)
    if isinstance(smoothing, VariforcParameters):
        fit = weighted_quadratic_density(values, valid, evaluate, step, smoothing, origin, errors)
        sm, method, params = None, "variforc", smoothing.as_dict()
    else:
        sm = _smoothing_factors(smoothing)
        fit = weighted_quadratic_density(values, valid, evaluate, step, sm, origin, errors)
        method, params = "fixed", None
    sigma = float(np.nanmedian(fit.sigma)) if np.any(np.isfinite(fit.sigma)) else None
    return {
        "density": fit.rho,
        "sm": sm,
        "density_se": fit.se if errors else None,
        "smoothing_method": method,
        "variforc": params,
        "noise_sigma": sigma,
        "smoothing_widths": (fit.sc, fit.sb),
        "smoothing_choice": choice,
    }


def measurement_noise(curves: ReversalCurves, fallback: float | None = None) -> float | None:
    """Noise of the half moments ``M/2``, from the fourth differences along the curves.

    For white noise of standard deviation ``σ`` the fourth difference has the variance
    ``70 σ²``; a smooth curve adds only ``h⁴`` times its fourth derivative. The median absolute
    fourth difference over all curves (``/0.6745``: a robust standard deviation, insensitive to
    the few steps where a curve switches sharply) gives ``σ``, halved for ``M/2``; independent
    of the smoothing. ``fallback`` when no curve has five points.
    """
    diffs = [np.diff(m, 4) for m in curves.moments if m.size >= 5]
    if not diffs:
        return fallback
    d = np.concatenate(diffs)
    return float(0.5 * np.median(np.abs(d)) / 0.6744897501960817 / math.sqrt(70.0))


def _native_valid(curves: ReversalCurves, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Nodes of the native table that are measured points (curve x its own fields)."""
    valid = np.zeros((alpha.size, beta.size), dtype=bool)
    for r, h in zip(curves.reversal_field, curves.fields, strict=True):
        if curves.convention == "mayergoyz":
            valid[np.searchsorted(alpha, r), :] = np.isin(beta, h)
        else:
            valid[:, np.searchsorted(beta, r)] = np.isin(alpha, h)
    return valid


def _native_offsets(curves: ReversalCurves, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """``M/2 − E`` on the native table: the reversal point's half moment of each curve
    (a function of the curve alone, so the mixed derivative of ``E`` is unchanged)."""
    if curves.convention == "mayergoyz":  # E = (m0 − m)/2, M/2 ↔ −m/2 = E − m0/2, by α row
        off = np.zeros(alpha.size)
        for r, m in zip(curves.reversal_field, curves.moments, strict=True):
            off[np.searchsorted(alpha, r)] = -0.5 * m[0]
        return off[:, None]
    off = np.zeros(beta.size)  # Pike: E = (m − m0)/2, M/2 = E + m0/2, by β column
    for r, m in zip(curves.reversal_field, curves.moments, strict=True):
        off[np.searchsorted(beta, r)] = 0.5 * m[0]
    return off[None, :]


def _grid_and_fit(
    curves: ReversalCurves, smoothing: Any, grid: str, uncertainty: bool
) -> tuple[str, bool]:
    """The grid an identification runs on and whether it fits by the lattice regression
    (VARIFORC, ``"auto"``, uncertainty; ``smoothing`` after :func:`_variforc_or`): ``"auto"``
    is :func:`auto_grid`, except that a lattice fit on a native table that is not regular
    goes to the protocol lattice (the lattice regression needs a regular lattice)."""
    chosen = grid
    if grid == "auto":
        grid = auto_grid(curves)
    lattice = isinstance(smoothing, (VariforcParameters, str)) or (
        bool(uncertainty) and smoothing is not None
    )
    if lattice and chosen == "auto" and grid == "native":
        union = np.unique(np.concatenate(curves.fields))
        if not _is_regular(*_native_axes(curves, union, np.sort(curves.reversal_field))):
            grid = "protocol"
    return grid, lattice


def estimate_memory(
    curves: ReversalCurves,
    *,
    smoothing: Any = None,
    grid: str = "auto",
    step: float | None = None,
    uncertainty: bool = False,
) -> int:
    """Estimated peak bytes of ``identify_from_curves(curves, smoothing=…, grid=…, step=…,
    uncertainty=…)`` from the sizes alone
    (:func:`~analysis.identification.memory.estimate_identification_bytes`; the lattice's node
    count, nothing of its size is allocated), on the path that call takes: the protocol
    lattice, the lattice regression on the native table, or its scattered windows."""
    smoothing = _variforc_or(smoothing)
    grid, lattice = _grid_and_fit(curves, smoothing, grid, uncertainty)
    if isinstance(smoothing, str):  # "auto": the largest candidate
        smoothing = auto_candidates()[-1]
    if isinstance(smoothing, VariforcParameters):  # the lattice path: its far-field window
        smoothing = (smoothing.sc1, smoothing.sb1)
    sm = None if smoothing is None else _smoothing_factors(smoothing)
    if grid == "protocol":
        n = protocol_lattice(curves, step).size
        return estimate_identification_bytes(curves.n_points, n, smoothing=sm, grid=grid)
    n_union = np.unique(np.concatenate(curves.fields)).size
    return estimate_identification_bytes(
        curves.n_points,
        curves.n_curves,
        n_union,
        smoothing=sm,
        grid="lattice" if lattice and sm is not None else "native",
    )


def auto_grid(curves: ReversalCurves) -> str:
    """The grid ``identify_from_curves(grid="auto")`` uses: ``"protocol"`` when the union of
    field values has more than twice as many values as the longest curve plus the number of
    curves (measured fields, different on every curve) or when the fields lie on one uniform
    grid but the native table would not be square (its nodes then are not one regular
    lattice), else ``"native"``."""
    union = np.unique(np.concatenate(curves.fields))
    longest = max(h.size for h in curves.fields)
    if union.size > 2 * (longest + curves.n_curves):
        return "protocol"
    rev = np.sort(curves.reversal_field)
    if _is_regular(union, union) and not _is_regular(*_native_axes(curves, union, rev)):
        # an exact uniform grid whose native table is not square (e.g. Pike curves running
        # past the last reversal field): the protocol lattice of that grid is regular and
        # reproduces the data at its nodes
        return "protocol"
    return "native"


def _native_axes(
    curves: ReversalCurves, union: np.ndarray, rev: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(α nodes, β nodes)`` of the native table."""
    return (rev, union) if curves.convention == "mayergoyz" else (union, rev)


def _protocol_table(
    curves: ReversalCurves, step: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Everett table on the protocol lattice: ``(nodes, E[α, β], measured[α, β], step)``."""
    return _protocol_tables(curves, step)[:4]


def _protocol_tables(
    curves: ReversalCurves, step: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, np.ndarray]:
    """:func:`_protocol_table` plus ``M/2 − E`` (the curves' reversal half moments,
    interpolated like the curves; broadcastable to the table)."""
    nodes = protocol_lattice(curves, step)
    step = float(nodes[1] - nodes[0])
    rev, fields, ev = rising_form(curves)
    order = np.argsort(rev)
    rev = rev[order]
    n = nodes.size
    half = 0.5 * step
    g = np.empty((rev.size, n))
    meas = np.empty((rev.size, n), dtype=bool)
    # half moment at the reversal point, rising form: Pike +m0/2, Mayergoyz (mirrored) −m0/2
    sign = 0.5 if curves.convention == "pike" else -0.5
    first = np.array([sign * curves.moments[c][0] for c in order])
    for row, c in enumerate(order):
        h, e = fields[c], ev[c]
        g[row] = np.interp(nodes, h, e)  # 0 below the reversal field, constant beyond the end
        g[row, nodes < h[0]] = 0.0
        meas[row] = (nodes >= h[0] - half) & (nodes <= h[-1] + half)
    # beyond its last point a curve continues parallel to the curve above it (zero density in
    # the cells it did not measure); held constant, it would put minus the rise of the curve
    # above into those cells (an aborted run's partial last curve: a negative mass)
    for row in range(rev.size - 2, -1, -1):
        end = fields[order[row]][-1]
        beyond = nodes > end
        g[row, beyond] += g[row + 1, beyond] - np.interp(end, nodes, g[row + 1])
    # across reversal fields: linear interpolation between the bracketing curves
    k = np.clip(np.searchsorted(rev, nodes), 1, max(rev.size - 1, 1))
    if rev.size == 1:
        t = np.zeros(n)
        c0 = c1 = np.zeros(n, dtype=int)
    else:
        c0, c1 = k - 1, k
        t = np.clip((nodes - rev[c0]) / (rev[c1] - rev[c0]), 0.0, 1.0)
    table = (1.0 - t)[:, None] * g[c0] + t[:, None] * g[c1]
    offset = (1.0 - t) * first[c0] + t * first[c1]
    used0 = t < 1.0 - 1e-9
    used1 = t > 1e-9
    m_tab = (meas[c0] | ~used0[:, None]) & (meas[c1] | ~used1[:, None])
    # nodes farther than half a step outside the reversal-field range are not measured
    outside = (nodes < rev[0] - half) | (nodes > rev[-1] + half)
    m_tab[outside] = False
    # above the highest reversal field nothing reverses: E(x, h) = E_last(h) − E_last(x) (the
    # upper branch of the last curve; a constant in x would pile its cumulative rise into
    # every diagonal cell)
    above = np.flatnonzero(nodes > rev[-1] + half)
    if above.size:
        last = g[np.argmax(rev)] if rev.size else g[0]
        table[above] = last[None, :] - last[above][:, None]
        offset[above] = last[above] + first[np.argmax(rev)]
    # table[R, h]; physical region h >= R; on and below the diagonal E = 0 exactly
    below = nodes[None, :] <= nodes[:, None]
    table[below] = 0.0
    diag = np.eye(n, dtype=bool) & ~outside[:, None]
    m_tab = (m_tab & ~below) | diag
    if curves.convention == "pike":  # alpha = h, beta = R
        E, measured = table.T.copy(), m_tab.T.copy()
        out_nodes = nodes
        offset = offset[None, :]
    else:  # alpha = -R', beta = -h'
        E, measured = table[::-1, ::-1].copy(), m_tab[::-1, ::-1].copy()
        out_nodes = -nodes[::-1]
        offset = offset[::-1][:, None]
    return out_nodes, E, measured, step, offset


def _identify_protocol(
    curves: ReversalCurves,
    smoothing: float | tuple[float, float] | None,
    output_range: tuple[float, float],
    extend: bool,
    step: float | None,
    window: str = "rs",
    lattice: bool = False,
    uncertainty: bool = False,
) -> PreisachIdentification:
    nodes, E, measured, step, offset = _protocol_tables(curves, step)
    mass = E[1:, :-1] - E[:-1, :-1] - E[1:, 1:] + E[:-1, 1:]
    density = None
    sm = None
    extra: dict[str, Any] = {}
    if lattice:
        aa, bb = np.meshgrid(nodes, nodes, indexing="ij")
        valid = measured | ((bb > aa) if extend else False)
        evaluate = measured & (bb <= aa)
        extra = _lattice_fit(
            E + offset, valid, evaluate, step, smoothing, float(nodes[0]), uncertainty
        )
        if uncertainty:
            extra["noise_sigma"] = measurement_noise(curves, extra["noise_sigma"])
        density = extra.pop("density")
        sm = extra.pop("sm")
    elif smoothing is not None:
        sm = _smoothing_factors(smoothing)
        aa, bb = np.meshgrid(nodes, nodes, indexing="ij")
        valid = measured | ((bb > aa) if extend else False)
        evaluate = measured & (bb <= aa)
        density = grid_quadratic_density(E, valid, evaluate, step, sm[0], sm[1], window)
        density.setflags(write=False)
    alpha = nodes.copy()
    beta = nodes.copy()
    for arr in (alpha, beta, E, mass, measured):
        arr.setflags(write=False)
    return PreisachIdentification(
        alpha=alpha,
        beta=beta,
        everett=E,
        cell_mass=mass,
        step=step,
        output_range=(float(output_range[0]), float(output_range[1])),
        density_alpha_beta=density,
        smoothing=sm,
        convention=curves.convention,
        measured=measured,
        reversible_ridge=extend,
        n_curves=curves.n_curves,
        n_points=curves.n_points,
        curve_kind=curves.kind,
        **extra,
    )


def _native_points(
    curves: ReversalCurves, other_nodes: np.ndarray, extend: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scattered (α, β, E) at the native curve points, plus extension points E = 0."""
    a_list, b_list, e_list = [], [], []
    for r, h, m in zip(curves.reversal_field, curves.fields, curves.moments, strict=True):
        if curves.convention == "mayergoyz":
            a_list.append(np.full(h.size, r))
            b_list.append(h)
            e_list.append(0.5 * (m[0] - m))
            if extend:
                ext = other_nodes[other_nodes > r]
                a_list.append(np.full(ext.size, r))
                b_list.append(ext)
                e_list.append(np.zeros(ext.size))
        else:
            a_list.append(h)
            b_list.append(np.full(h.size, r))
            e_list.append(0.5 * (m - m[0]))
            if extend:
                ext = other_nodes[other_nodes < r]
                a_list.append(ext)
                b_list.append(np.full(ext.size, r))
                e_list.append(np.zeros(ext.size))
    return np.concatenate(a_list), np.concatenate(b_list), np.concatenate(e_list)


def _typical_step(curves: ReversalCurves) -> float:
    """Smoothing unit for irregular data: the larger of the median spacing of the reversal
    fields and the median field step along the curves."""
    rev = np.diff(np.sort(curves.reversal_field))
    along = np.concatenate([np.abs(np.diff(h)) for h in curves.fields])
    candidates = [float(np.median(x)) for x in (rev, along) if x.size]
    if not candidates:
        raise ValueError("smoothing needs at least two reversal curves or two points per curve")
    return max(candidates)


def _smoothing_factors(smoothing: float | tuple[float, float]) -> tuple[float, float]:
    if np.ndim(smoothing) == 0:
        sf = positive_number(smoothing, "smoothing")
        return (sf, sf)
    if len(smoothing) != 2:
        raise ValueError("smoothing must be a positive number or a pair (SF_r, SF_s)")
    return (
        positive_number(smoothing[0], "smoothing[0] (SF_r)"),
        positive_number(smoothing[1], "smoothing[1] (SF_s)"),
    )
