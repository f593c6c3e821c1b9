"""FORC unmixing of a sample series: a common lattice, FORC-PCA, end-members and proportions.

:func:`unmix_forc` takes FORC files (any format
:func:`~analysis.identification.forc_io.read_forc_file` reads), reversal curves or
identifications, and returns a
:class:`~analysis.identification.unmixing_result.ForcUnmixing`.

1. **Diagrams.** Every file is read and identified with the same smoothing (VARIFORC by
   default) and ``uncertainty=True``: its FORC density ``ρ = μ_αβ`` and the standard error
   ``se`` at every node of its own lattice (:mod:`analysis.identification.variforc`). A file
   that cannot be read or identified is named in ``excluded`` with its one-line reason, and
   the others go on.
2. **Common lattice.** One regular ``(B_c, B_u)`` lattice for all, of the coarsest field step
   of the series, anchored at multiples of that step (so that it does not depend on the order
   of the inputs). Each diagram is resampled onto it by bilinear interpolation in ``(α, β)``
   (``α = B_u + B_c``, ``β = B_u − B_c``; ``se`` likewise, since neighbouring smoothed values are
   nearly fully correlated); a node is kept if every diagram has a value there. While fewer
   than :data:`MIN_COMMON_NODES` nodes are common, the diagram whose removal leaves the most
   common nodes is left out (named in ``excluded``: it does not overlap the others).
3. **Normalisation** (``normalize``): ``"moment"`` (default) divides a diagram by its
   saturation moment ``M_s ≈ max E`` (half the largest measured moment swing, the Everett
   function of the outermost curve): the proportions are then fractions of ``M_s`` carried by
   each end-member, and they add to 1 for a mixture ``M = Σ M_k`` because ``M_s`` adds.
   ``"irreversible"``: by the diagram's mass on the common region (``Σ ρ · 2h²``; the
   proportions are fractions of the irreversible moment there). ``"mass"``/``"volume"``: by
   the file header's sample mass or volume (:mod:`analysis.identification.normalization`);
   the proportions are then those of a linear mixture of specific (per-kg) end-members, which
   a non-magnetic diluent breaks. ``"none"``: the moments as read.
4. **FORC-PCA, end-members, proportions** (:mod:`analysis.identification.endmembers`): the
   number of end-members chosen from the noise when ``n_components=None``, the end-members as
   the N-FINDR simplex of the samples (or given as sample indices or PC coordinates), the
   proportions by fully constrained least squares, their intervals by a seeded parametric
   bootstrap over the per-node standard errors.

Independent per-node noise is what the bootstrap draws; the smoothed density's real noise is
correlated over a smoothing window with a kernel of zero mean (a second derivative), which
averages out of smooth directions, so the intervals are on the wide side: over 20 noise draws
of a synthetic series the bootstrap's standard deviation was 1.6 times (median) the actual
spread of the proportions and the 95 % intervals covered the truth in 98 % of the cases
(tests/test_analysis/identification/test_unmixing.py, marked slow). The intervals hold the
end-members' samples fixed (their own noise is in them, the choice of the samples is not).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification.curves import ReversalCurves
from analysis.identification.density import identify_from_curves
from analysis.identification.endmembers import (
    bootstrap_proportions,
    component_test,
    nfindr,
    principal_components,
    simplex_proportions,
)
from analysis.identification.forc_files.common import MicroMagData
from analysis.identification.forc_io import read_forc_file
from analysis.identification.normalization import sample_amount
from analysis.identification.result import PreisachIdentification
from analysis.identification.unmixing_result import ForcUnmixing
from analysis.identification.variforc import VariforcParameters

__all__ = ["unmix_forc", "NORMALIZE", "MIN_COMMON_NODES", "DEFAULT_MAX_END_MEMBERS"]

NORMALIZE = ("moment", "irreversible", "mass", "volume", "none")
#: fewer common nodes than this and the diagrams are taken not to overlap (step 2)
MIN_COMMON_NODES = 25
#: the largest number of end-members the automatic choice considers
DEFAULT_MAX_END_MEMBERS = 8
#: nodes closer than this fraction of a step to a lattice node are read at that node
_SNAP = 1e-9

Progress = Callable[[int, int, str, str], None]


@dataclass(frozen=True, eq=False)
class _Diagram:
    """One input on its own lattice: ``rho``/``se`` at ``α_i = β_i = origin + i·step``."""

    label: str
    index: int
    origin: float
    step: float
    rho: np.ndarray
    se: np.ndarray | None
    moment: float
    amount: dict[str, float | str]
    window_area: float


def unmix_forc(
    inputs: Sequence[Any],
    n_components: int | None = None,
    end_members: Any = None,
    *,
    normalize: str = "moment",
    smoothing: Any = "variforc",
    labels: Sequence[str] | None = None,
    file_format: str = "auto",
    n_boot: int = 200,
    seed: int | np.random.Generator = 0,
    level: float = 0.95,
    max_end_members: int = DEFAULT_MAX_END_MEMBERS,
    progress: Progress | None = None,
) -> ForcUnmixing:
    """Unmix a series of FORC diagrams into end-members and proportions (module docstring).

    Parameters
    ----------
    inputs:
        FORC file paths, :class:`~analysis.identification.forc_io.MicroMagData`,
        :class:`~analysis.identification.ReversalCurves` or
        :class:`~analysis.identification.PreisachIdentification` (made with smoothing on a
        regular lattice; with ``uncertainty=True`` for the automatic choice and intervals).
    n_components:
        The number of end-members ``m`` (>= 1; ``m − 1`` principal components), or ``None``:
        the smallest ``m`` whose residuals are consistent with the diagrams' standard errors
        (:func:`~analysis.identification.endmembers.component_test`), up to
        ``max_end_members``.
    end_members:
        ``None`` or ``"nfindr"``: the N-FINDR simplex of the samples. A sequence of ``m``
        input indices (0-based, in the order of ``inputs``): those samples. An array of
        shape ``(m, m − 1)``: the end-members' PC coordinates (scores).
    normalize:
        One of :data:`NORMALIZE` (module docstring, step 3).
    smoothing:
        The smoothing of the files' identification (``identify_from_curves``'s
        ``smoothing``; default VARIFORC).
    labels:
        One name per input (default: the file name, else ``sample k``).
    file_format:
        The reader's format (default: detected per file).
    n_boot, seed, level:
        Replicates (>= 20), seed and coverage of the proportions' bootstrap intervals.
    progress:
        Called as ``progress(k, n, label, status)`` after every input is read and identified
        (``status``: ``"ok"`` or the reason it was left out).
    """
    inputs = list(inputs)
    if len(inputs) < 2:
        raise ValueError(f"inputs must hold at least two diagrams, got {len(inputs)}")
    if normalize not in NORMALIZE:
        raise ValueError(f"normalize must be one of {NORMALIZE}, got {normalize!r}")
    if labels is not None and len(labels) != len(inputs):
        raise ValueError(f"labels must give one name per input ({len(inputs)}), got {len(labels)}")
    if isinstance(n_boot, bool) or not isinstance(n_boot, int) or n_boot < 20:
        raise ValueError(f"n_boot must be an integer >= 20, got {n_boot!r}")
    if not (isinstance(level, float | int) and 0.0 < level < 1.0):
        raise ValueError(f"level must lie in (0, 1), got {level!r}")
    if isinstance(max_end_members, bool) or not isinstance(max_end_members, int):
        raise ValueError(f"max_end_members must be an integer >= 1, got {max_end_members!r}")
    if max_end_members < 1:
        raise ValueError(f"max_end_members must be an integer >= 1, got {max_end_members!r}")
    read: list[tuple[int, str, Any, ReversalCurves | None, dict[str, str]]] = []
    excluded: list[tuple[str, str]] = []
    for k, item in enumerate(inputs):
        label = str(labels[k]) if labels is not None else _default_label(item, k)
        try:
            ident, curves, header = _identify(item, k, smoothing, file_format)
            read.append((k, label, ident, curves, header))
        except (ValueError, OSError) as exc:
            if not isinstance(item, str | os.PathLike):
                raise ValueError(f"inputs[{k}] ({label}): {exc}") from exc
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            excluded.append((label, reason))
            if progress is not None:
                progress(k + 1, len(inputs), label, reason)
            continue
        if progress is not None:
            progress(k + 1, len(inputs), label, "ok")
    # one smoothing in field units for all: a diagram on a finer lattice than the coarsest is
    # identified again with its half-widths scaled by the ratio of the steps (VARIFORC's law
    # in steps, s·Δ = (1 − λ)·s_1·Δ + λ·|B|, is then the same in field units)
    coarsest = max((r[2].step for r in read if r[2].step is not None), default=None)
    diagrams: list[_Diagram] = []
    for k, label, ident, curves, header in read:
        try:
            if curves is not None and coarsest is not None and ident.step < coarsest * (1 - 1e-9):
                scaled = _scaled_smoothing(smoothing, coarsest / ident.step)
                if scaled is not None:
                    ident = identify_from_curves(
                        curves,
                        smoothing=scaled,
                        output_range=(-math.inf, math.inf),
                        uncertainty=True,
                    )
            diagrams.append(_diagram(ident, k, label, normalize, header))
        except ValueError as exc:
            if not isinstance(inputs[k], str | os.PathLike):
                raise ValueError(f"inputs[{k}] ({label}): {exc}") from exc
            excluded.append((label, str(exc).splitlines()[0]))
    if len(diagrams) < 2:
        why = f" ({excluded[0][0]}: {excluded[0][1]})" if excluded else ""
        raise ValueError(f"inputs: fewer than two usable diagrams{why}")
    lattice = _common_lattice(diagrams, excluded)
    return _unmix(
        lattice,
        excluded,
        normalize,
        n_components,
        end_members,
        n_boot,
        seed,
        level,
        max_end_members,
    )


# -- step 1: the diagrams ---------------------------------------------------------------------


def _default_label(item: Any, k: int) -> str:
    if isinstance(item, str | os.PathLike):
        return Path(item).name
    return f"sample {k + 1}"


def _identify(
    item: Any, k: int, smoothing: Any, file_format: str
) -> tuple[PreisachIdentification, ReversalCurves | None, dict[str, str]]:
    """An input read and identified: ``(identification, its curves or None, header)``."""
    header: dict[str, str] = {}
    curves = None
    if isinstance(item, str | os.PathLike):
        item = read_forc_file(item, file_format)
    if isinstance(item, MicroMagData):
        header = dict(item.header)
        item = item.curves
    if isinstance(item, ReversalCurves):
        curves = item
        item = identify_from_curves(
            item, smoothing=smoothing, output_range=(-math.inf, math.inf), uncertainty=True
        )
    if not isinstance(item, PreisachIdentification):
        raise TypeError(
            f"inputs[{k}] must be a FORC file path, MicroMagData, ReversalCurves or "
            f"PreisachIdentification, got {type(item).__name__}"
        )
    if item.density_alpha_beta is None:
        raise ValueError("the identification has no smoothed density (identify with smoothing)")
    if item.step is None:
        raise ValueError("the identification is not on a regular lattice (equal α, β nodes)")
    return item, curves, header


def _scaled_smoothing(smoothing: Any, ratio: float) -> Any:
    """``smoothing`` with its half-widths (in steps) multiplied by ``ratio``; ``None`` for
    ``"auto"`` (chosen per diagram: left as it is)."""
    if isinstance(smoothing, str) and smoothing == "auto":
        return None
    if smoothing is None or (isinstance(smoothing, str) and smoothing == "variforc"):
        smoothing = VariforcParameters()
    if isinstance(smoothing, VariforcParameters):
        widths = {n: getattr(smoothing, n) * ratio for n in ("sc0", "sc1", "sb0", "sb1")}
        return replace(smoothing, **widths)
    pair = np.broadcast_to(np.asarray(smoothing, dtype=float), (2,))
    return (float(pair[0] * ratio), float(pair[1] * ratio))


def _diagram(
    ident: PreisachIdentification, k: int, label: str, normalize: str, header: dict[str, str]
) -> _Diagram:
    amount: dict[str, float | str] = {}
    if normalize in ("mass", "volume"):
        amount[normalize] = sample_amount(header, normalize)
    aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    rho = np.where(bb <= aa, ident.density_alpha_beta, np.nan)
    se = None
    if ident.density_se is not None:
        se = np.where(bb <= aa, ident.density_se, np.nan)
        rho = np.where(np.isfinite(se) & (se > 0), rho, np.nan)
    if not np.any(np.isfinite(rho)):
        raise ValueError("the smoothed density is NaN everywhere (too few data points)")
    moment = float(np.max(ident.everett))
    if normalize == "moment" and not moment > 0:
        raise ValueError("normalize='moment': the Everett function is nowhere positive")
    return _Diagram(
        label=label,
        index=k,
        origin=float(ident.alpha[0]),
        step=float(ident.step),
        rho=rho,
        se=se,
        moment=moment,
        amount=amount,
        window_area=_window_area(ident),
    )


def _window_area(ident: PreisachIdentification) -> float:
    """Median area ``4 s_c s_b Δ²`` of the smoothing window in the ``(B_c, B_u)`` plane (the
    correlation area of the smoothed density;
    :func:`~analysis.identification.endmembers.component_test`)."""
    step = float(ident.step)
    if ident.smoothing_widths is not None:
        sc, sb = (np.asarray(w, dtype=float) for w in ident.smoothing_widths)
        ok = np.isfinite(sc) & np.isfinite(sb)
        if ok.any():
            return float(np.median(4.0 * sc[ok] * sb[ok])) * step**2
    if ident.smoothing is not None:
        return 4.0 * float(ident.smoothing[0]) * float(ident.smoothing[1]) * step**2
    return step**2


# -- step 2: the common lattice ---------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class _Lattice:
    diagrams: list[_Diagram]
    bc: np.ndarray
    bu: np.ndarray
    mask: np.ndarray
    rho: np.ndarray  # (n, n_bc, n_bu), NaN outside the mask
    se: np.ndarray | None
    step: float


def _box(d: _Diagram) -> tuple[float, float, float, float]:
    i, j = np.nonzero(np.isfinite(d.rho))
    a, b = d.origin + d.step * i, d.origin + d.step * j
    bc, bu = 0.5 * (a - b), 0.5 * (a + b)
    return float(bc.min()), float(bc.max()), float(bu.min()), float(bu.max())


def _resample(d: _Diagram, values: np.ndarray, bc: np.ndarray, bu: np.ndarray) -> np.ndarray:
    """Bilinear interpolation of ``values`` (on ``d``'s lattice) at the nodes ``bc × bu``;
    NaN where a neighbour with a positive weight is NaN or outside the lattice."""
    n = values.shape[0]
    a = (bu[None, :] + bc[:, None] - d.origin) / d.step
    b = (bu[None, :] - bc[:, None] - d.origin) / d.step
    out = np.zeros(a.shape)
    ok = np.ones(a.shape, dtype=bool)
    ia, ta = _split(a)
    ib, tb = _split(b)
    for da, wa in ((0, 1.0 - ta), (1, ta)):
        for db, wb in ((0, 1.0 - tb), (1, tb)):
            w = wa * wb
            i, j = ia + da, ib + db
            inside = (i >= 0) & (i < n) & (j >= 0) & (j < n)
            v = np.full(a.shape, np.nan)
            v[inside] = values[i[inside], j[inside]]
            used = w > 0
            ok &= ~used | np.isfinite(v)
            out += np.where(used, w * np.nan_to_num(v), 0.0)
    return np.where(ok, out, np.nan)


def _split(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Integer part and fraction, the fraction snapped to 0 within :data:`_SNAP` of a node."""
    r = np.round(x)
    near = np.abs(x - r) < _SNAP
    base = np.where(near, r, np.floor(x)).astype(np.int64)
    return base, np.where(near, 0.0, x - np.floor(x))


def _common_lattice(diagrams: list[_Diagram], excluded: list[tuple[str, str]]) -> _Lattice:
    h = max(d.step for d in diagrams)
    boxes = np.array([_box(d) for d in diagrams])
    bc = h * np.arange(math.floor(boxes[:, 0].min() / h), math.ceil(boxes[:, 1].max() / h) + 1)
    bu = h * np.arange(math.floor(boxes[:, 2].min() / h), math.ceil(boxes[:, 3].max() / h) + 1)
    bc = bc[bc > 0.0]
    rho = np.stack([_resample(d, d.rho, bc, bu) for d in diagrams])
    has_se = all(d.se is not None for d in diagrams)
    se = np.stack([_resample(d, d.se, bc, bu) for d in diagrams]) if has_se else None
    valid = np.isfinite(rho) if se is None else np.isfinite(rho) & np.isfinite(se) & (se > 0)
    keep = list(range(len(diagrams)))
    while np.all(valid[keep], axis=0).sum() < MIN_COMMON_NODES:
        if len(keep) <= 2:
            raise ValueError(
                f"inputs: the diagrams do not overlap (fewer than {MIN_COMMON_NODES} common "
                f"nodes of the (Bc, Bu) lattice of step {h:.4g})"
            )
        counts = [np.all(valid[[j for j in keep if j != k]], axis=0).sum() for k in keep]
        # the removal that leaves the most common nodes; ties: the later label (deterministic)
        drop = max(zip(counts, [diagrams[k].label for k in keep], keep, strict=True))[2]
        excluded.append(
            (diagrams[drop].label, "its diagram does not overlap the others' common region")
        )
        keep.remove(drop)
    mask = np.all(valid[keep], axis=0)
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    crop = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    mask = mask[crop]
    rho = np.where(mask, rho[keep][:, crop[0], crop[1]], np.nan)
    if se is not None:
        se = np.where(mask, se[keep][:, crop[0], crop[1]], np.nan)
    return _Lattice(
        diagrams=[diagrams[k] for k in keep],
        bc=bc[crop[0]],
        bu=bu[crop[1]],
        mask=mask,
        rho=rho,
        se=se,
        step=h,
    )


# -- steps 3 and 4 ----------------------------------------------------------------------------


def _divisors(lat: _Lattice, normalize: str) -> np.ndarray:
    if normalize == "moment":
        return np.array([d.moment for d in lat.diagrams])
    if normalize == "irreversible":
        # ρ = μ_αβ per unit α-β area; dα dβ = 2 dB_c dB_u: a node carries ρ·2h²
        mass = np.nansum(lat.rho, axis=(1, 2)) * 2.0 * lat.step**2
        if np.any(mass <= 0):
            k = int(np.argmin(mass))
            raise ValueError(
                f"normalize='irreversible': {lat.diagrams[k].label} has no positive mass on "
                "the common region"
            )
        return mass
    if normalize in ("mass", "volume"):
        return np.array([float(d.amount[normalize]) for d in lat.diagrams])
    return np.ones(len(lat.diagrams))


def _unmix(
    lat: _Lattice,
    excluded: list[tuple[str, str]],
    normalize: str,
    n_components: int | None,
    end_members: Any,
    n_boot: int,
    seed: int | np.random.Generator,
    level: float,
    max_end_members: int,
) -> ForcUnmixing:
    n = len(lat.diagrams)
    divisors = _divisors(lat, normalize)
    rho = lat.rho / divisors[:, None, None]
    se = None if lat.se is None else lat.se / divisors[:, None, None]
    x = rho[:, lat.mask]
    pcs = principal_components(x)
    test: list[dict[str, float]] = []
    m_max = min(n, max_end_members)
    if se is not None:
        p_eff = float(np.mean([lat.mask.sum() * lat.step**2 / d.window_area for d in lat.diagrams]))
        test = component_test(x, se[:, lat.mask], pcs, max(p_eff, 1.0), m_max)
    vertex_samples, vertices_given, m, chosen_by = _end_member_request(
        end_members, n_components, lat.diagrams, n, test, m_max
    )
    q = m - 1
    if q > pcs.loadings.shape[0]:
        raise ValueError(
            f"n_components: {m} end-members need {q} principal components, the series has "
            f"{pcs.loadings.shape[0]} (its samples span no more)"
        )
    scores = pcs.scores[:, :q]
    if vertices_given is not None:
        vertices = vertices_given
    else:
        if vertex_samples is None:
            vertex_samples = nfindr(scores, m)
        vertices = scores[vertex_samples]
    em_rho = pcs.mean + vertices @ pcs.loadings[:q]
    if end_members is None or (isinstance(end_members, str) and end_members == "nfindr"):
        # automatic end-members in a canonical order: by their median coercivity B_c
        order = np.argsort([_median_bc(lat, row) for row in em_rho], kind="stable")
        vertices, em_rho = vertices[order], em_rho[order]
        vertex_samples = vertex_samples[order]
    proportions, distance = simplex_proportions(scores, vertices)
    intervals = prop_se = None
    if se is not None:
        boot = bootstrap_proportions(
            scores, pcs.loadings[:q], se[:, lat.mask], vertices, vertex_samples, n_boot, seed
        )
        lo, hi = np.percentile(boot, [50.0 * (1.0 - level), 50.0 * (1.0 + level)], axis=0)
        intervals = np.stack([lo, hi], axis=-1)
        prop_se = boot.std(axis=0, ddof=1)
    return ForcUnmixing(
        labels=tuple(d.label for d in lat.diagrams),
        input_indices=tuple(d.index for d in lat.diagrams),
        bc=lat.bc,
        bu=lat.bu,
        mask=lat.mask,
        step=lat.step,
        diagrams=rho,
        standard_errors=se,
        normalize=normalize,
        divisors=divisors,
        mean=_grid(lat.mask, pcs.mean),
        components=np.stack([_grid(lat.mask, v) for v in pcs.loadings]),
        scores=pcs.scores,
        explained_variance=pcs.explained_variance,
        explained_variance_ratio=pcs.explained_variance_ratio,
        component_test=tuple(test),
        n_components=m,
        chosen_by=chosen_by,
        end_member_scores=vertices,
        end_member_samples=None
        if vertex_samples is None
        else tuple(int(i) for i in vertex_samples),
        end_members=np.stack([_grid(lat.mask, row) for row in em_rho]),
        proportions=proportions,
        proportion_intervals=intervals,
        proportion_se=prop_se,
        simplex_distance=distance,
        level=float(level),
        n_boot=n_boot,
        excluded=tuple(excluded),
    )


def _grid(mask: np.ndarray, values: np.ndarray) -> np.ndarray:
    out = np.full(mask.shape, np.nan)
    out[mask] = values
    return out


def _median_bc(lat: _Lattice, values: np.ndarray) -> float:
    """The median ``B_c`` of the positive part of a diagram on the common mask."""
    bc = np.broadcast_to(lat.bc[:, None], lat.mask.shape)[lat.mask]
    w = np.clip(values, 0.0, None)
    if not w.sum() > 0:
        return math.inf
    order = np.argsort(bc, kind="stable")
    cum = np.cumsum(w[order])
    return float(bc[order][np.searchsorted(cum, 0.5 * cum[-1])])


def _end_member_request(
    end_members: Any,
    n_components: int | None,
    diagrams: list[_Diagram],
    n: int,
    test: list[dict[str, float]],
    m_max: int,
) -> tuple[np.ndarray | None, np.ndarray | None, int, str]:
    """``(sample rows, PC coordinates, m, chosen_by)`` of the request."""
    if n_components is not None:
        if isinstance(n_components, bool) or not isinstance(n_components, int | np.integer):
            raise ValueError(f"n_components must be an integer in [1, {n}], got {n_components!r}")
        if not 1 <= n_components <= n:
            raise ValueError(
                f"n_components must lie in [1, {n}] (the usable samples), got {n_components}"
            )
    if end_members is None or (isinstance(end_members, str) and end_members == "nfindr"):
        if n_components is not None:
            return None, None, int(n_components), "given"
        if not test:
            raise ValueError(
                "n_components: give the number of end-members (the inputs have no standard "
                "errors to choose it from: identify with uncertainty=True)"
            )
        accepted = [row["end_members"] for row in test if row["accepted"]]
        m = int(accepted[0]) if accepted else m_max
        return None, None, m, "noise" if accepted else "largest"
    if isinstance(end_members, str):
        raise ValueError(
            f"end_members must be 'nfindr', sample indices or PC coordinates, got {end_members!r}"
        )
    arr = np.asarray(end_members)
    if arr.ndim == 1 and arr.size and np.issubdtype(arr.dtype, np.integer):
        rows = {d.index: r for r, d in enumerate(diagrams)}
        bad = [int(i) for i in arr if int(i) not in rows]
        if bad:
            raise ValueError(
                f"end_members: input {bad[0]} is not a usable sample (indices 0-based in the "
                f"order of inputs; usable: {sorted(rows)})"
            )
        if len(set(arr.tolist())) != arr.size:
            raise ValueError("end_members: the sample indices must be distinct")
        m = arr.size
        sample_rows = np.array([rows[int(i)] for i in arr])
        coords = None
    elif arr.ndim == 2 and arr.shape[1] == arr.shape[0] - 1 and np.issubdtype(arr.dtype, np.number):
        m = arr.shape[0]
        sample_rows, coords = None, arr.astype(float)
        if not np.all(np.isfinite(coords)):
            raise ValueError("end_members: the PC coordinates must be finite")
    else:
        raise ValueError(
            "end_members must be 'nfindr', a sequence of m sample indices or an array of "
            f"m PC coordinates, shape (m, m - 1); got shape {arr.shape}"
        )
    if n_components is not None and n_components != m:
        raise ValueError(f"n_components ({n_components}) and end_members ({m}) disagree")
    return sample_rows, coords, m, "end_members"
