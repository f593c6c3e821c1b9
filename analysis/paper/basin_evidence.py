"""Basin and realization evidence for the report's Discussion: which
attractors coexist at the paper's disputed points and how much of the initial conditions each
one attracts, computed by the report run itself.

* the erf-play limit at C = 1.70, 1.74, 1.75, 1.78, 1.80: basins on an (q0, v0) grid around the
  paper's initial condition (−1, 0.1) — every attractor with its basin fraction, the 95 % Wilson
  interval and what it is (period, Floquet multipliers; or λ_max ± error and D_KY);
* the erf-play limit at C = 2.92: basins on an (q0, w0) grid (w0 the play's wagon position) with
  the transient lengths (median, max) until the section repeats;
* N = 20 000 dimers at C = 2.9: per disorder realization (those of ``hyst ensemble --seed``) the
  attractor the paper's initial condition reaches; the regular ones' periods and multipliers.

Plain reading of :func:`basin_evidence`::

    for C in couplings:   basins(erf play at C, (q0, v0) grid)   -> record per attractor
    basins(erf play at 2.92, (q0, w0) grid)                      -> records + transients
    realization_attractors([N], [2.9], realizations, seed)       -> one record per realization

Every part runs its tasks through the report's results store (:meth:`PaperContext.run`'s store,
workers and scheduler: chunks of starts, one realization per task), so results are written as
they complete and a killed run resumes where it stopped. The labelling (one orbit refinement,
one Lyapunov run per attractor) is recomputed on a rerun; it is seconds.

:data:`BASIN_SIZES` holds the sizes: ``full`` the committed ones of ``docs/basins/`` (20 × 20
grids, up to 2000 periods; 40 × 40, up to 10 000; 50 realizations), ``quick`` a reduced version
whose every record says what was reduced. :func:`basin_lines` formats the JSON record as the
Markdown lines that :func:`analysis.paper.runner.write_report` appends to the Discussion.
"""

from __future__ import annotations

import functools
import time
from collections import Counter
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from analysis.dynamics.basins import EXPERIMENT, BasinGrid, basins
from analysis.experiments.execution import run_tasks
from analysis.experiments.models import build_operator
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    DEFAULT_Q0,
    FREQUENCY,
    SPREAD,
    V0,
    WIDTH,
)
from analysis.experiments.realizations import realization_attractors
from analysis.paper.context import PaperContext
from oscillators import ForcedOscillator

__all__ = ["BASIN_SIZES", "BasinEvidenceSize", "basin_evidence", "basin_lines"]


@dataclass(frozen=True)
class BasinEvidenceSize:
    """Every knob of :func:`basin_evidence` (defaults: the committed ``docs/basins/`` runs).

    ``neighbourhood_*``: the (q0, v0) grids at each of ``couplings``; ``band_*``: the (q0, w0)
    grid at ``band_coupling`` (fixed ``band_v0``); ``realization_*``: the disorder realizations.
    ``periods`` is the measured window of every start (its last ``periods`` section points give
    the period, ``max_period <= periods // 2``); ``*_max_periods`` the most forcing periods a
    start runs before it counts as aperiodic; ``lyapunov_periods`` the Lyapunov run per
    aperiodic attractor candidate; ``chunk`` the starts per stored task.
    """

    name: str = "full"
    couplings: tuple[float, ...] = (1.70, 1.74, 1.75, 1.78, 1.80)
    neighbourhood_grid: int = 20
    neighbourhood_q0_range: tuple[float, float] = (-2.0, 0.0)
    neighbourhood_v0_range: tuple[float, float] = (-0.9, 1.1)
    neighbourhood_max_periods: int = 2000
    band_coupling: float = 2.92
    band_grid: int = 40
    band_q0_range: tuple[float, float] = (-3.0, 3.0)
    band_w0_range: tuple[float, float] = (-3.0, 3.0)
    band_v0: float = V0
    band_max_periods: int = 10_000
    periods: int = 100
    lyapunov_periods: int = 2000
    chunk: int = 50
    realization_spins: int = 20_000
    realization_coupling: float = 2.9
    realizations: int = 50
    realization_transient: int = 160
    realization_periods: int = 1200
    realization_max_periods: int = 6000
    realization_max_period: int = 600
    realization_lyapunov_periods: int = 1000


#: ``full``: the committed sizes; ``quick``: adds about half a minute to ``hyst paper --quick``
BASIN_SIZES: dict[str, BasinEvidenceSize] = {
    "full": BasinEvidenceSize(),
    "quick": BasinEvidenceSize(
        name="quick",
        neighbourhood_grid=6,
        neighbourhood_max_periods=500,
        band_grid=10,
        band_max_periods=2000,
        lyapunov_periods=1000,
        chunk=18,
        realizations=6,
        realization_max_periods=4000,
    ),
}

#: what each part's text names when a size differs from the committed one: (knob, name, value)
_KNOBS = {
    "neighbourhood": (
        ("neighbourhood_grid", "grid", "{0} × {0}"),
        ("neighbourhood_max_periods", "periods per start at most", "{}"),
        ("lyapunov_periods", "Lyapunov run", "{} periods"),
    ),
    "band": (
        ("band_grid", "grid", "{0} × {0}"),
        ("band_max_periods", "periods per start at most", "{}"),
        ("lyapunov_periods", "Lyapunov run", "{} periods"),
    ),
    "realizations": (
        ("realization_spins", "N", "{}"),
        ("realizations", "realizations", "{}"),
        ("realization_max_periods", "periods at most", "{}"),
        ("realization_max_period", "longest period detected", "{}"),
    ),
}


def _reduced(size: BasinEvidenceSize, part: str) -> str:
    """``""`` at the committed sizes, else what this size changed, e.g. ``"quick mode: grid
    6 × 6 (full: 20 × 20), ..."``."""
    full = BASIN_SIZES["full"]
    changes = [
        f"{name} {value.format(getattr(size, knob))} (full: {value.format(getattr(full, knob))})"
        for knob, name, value in _KNOBS[part]
        if getattr(size, knob) != getattr(full, knob)
    ]
    return f"{size.name} mode: " + ", ".join(changes) if changes else ""


def _erf(coupling: float) -> ForcedOscillator:
    operator = build_operator("erf-play", width=WIDTH, spread=SPREAD)
    return ForcedOscillator(operator, coupling, DAMPING_RATIO, FREQUENCY)


def _attractor_record(a: dict[str, Any]) -> dict[str, Any]:
    """One attractor of a basin map without its orbit points (JSON-ready)."""
    rec: dict[str, Any] = {
        "kind": a["kind"],
        "count": int(a["count"]),
        "fraction": float(a["fraction"]),
        "interval": [float(x) for x in a["interval"]],
    }
    if a["kind"] == "periodic":
        mult = np.asarray(a["multipliers"], dtype=complex)
        rec.update(
            period=int(a["period"]),
            multipliers=[[float(m.real), float(m.imag)] for m in mult],
            multipliers_abs=[float(abs(m)) for m in mult],
            tangent_space=list(a["tangent_space"]),
            stable=bool(a["stable"]),
            residual=float(a["residual"]),
            transient_median=float(a["transient_median"]),
            transient_max=int(a["transient_max"]),
        )
    elif a["kind"] == "chaotic":
        rec.update(
            max_exponent=float(a["max_exponent"]),
            max_exponent_error=float(a["max_exponent_error"]),
            kaplan_yorke=float(a["kaplan_yorke"]),
        )
    return rec


def _basin_record(ctx: PaperContext, coupling: float, grid: BasinGrid, max_periods: int,
                  size: BasinEvidenceSize, part: str) -> dict[str, Any]:  # fmt: skip
    system = _erf(coupling)
    key = f"erf-play p={WIDTH} R={SPREAD} C={coupling} zeta={DAMPING_RATIO} Omega={FREQUENCY}"
    result = basins(
        system,
        grid,
        transient=0,
        periods=size.periods,
        max_periods=max_periods,
        lyapunov_periods=size.lyapunov_periods,
        chunk=size.chunk,
        executor=functools.partial(
            run_tasks,
            EXPERIMENT,
            store=ctx.store_path,
            workers=ctx.task_workers,
            scheduler=ctx.scheduler,
            progress=ctx.progress,
            allow_version_mismatch=ctx.allow_version_mismatch,
        ),
        system_key=key,
    )
    valid = result.labels >= 0
    periodic = valid & (result.transients >= 0)
    t = result.transients[periodic]
    return {
        "coupling": float(coupling),
        "grid": grid.to_dict(),
        "periods": size.periods,
        "max_periods": int(max_periods),
        "lyapunov_periods": size.lyapunov_periods,
        "starts": int(result.labels.size),
        "valid_starts": int(np.count_nonzero(valid)),
        "attractors": [_attractor_record(a) for a in result.attractors],
        "transient_median": float(np.median(t)) if t.size else None,
        "transient_max": int(t.max()) if t.size else None,
        "reduced": _reduced(size, part),
    }


def _realization_record(r: dict[str, Any], index: int) -> dict[str, Any]:
    rec: dict[str, Any] = {"index": index, "seed": int(r["seed"]), "kind": r["kind"]}
    if r["kind"] == "periodic":
        mult = np.asarray(r["multipliers"], dtype=float).reshape(-1, 2)
        rec.update(
            period=int(r["period"]),
            transient=int(r["transient"]),
            multipliers=mult.tolist(),
            max_abs_multiplier=float(np.max(np.hypot(mult[:, 0], mult[:, 1]))),
            stable=bool(r["stable"]),
            residual=float(r["residual"]),
        )
    elif r["kind"] in ("chaotic", "undecided"):
        rec.update(
            max_exponent=float(r["max_exponent"]),
            max_exponent_error=float(r["max_exponent_error"]),
            kaplan_yorke=float(r["kaplan_yorke"]),
        )
    return rec


def _realizations(ctx: PaperContext, size: BasinEvidenceSize) -> dict[str, Any]:
    records = realization_attractors(
        [size.realization_spins],
        [size.realization_coupling],
        size.realizations,
        ctx.seed,
        transient=size.realization_transient,
        periods=size.realization_periods,
        max_periods=size.realization_max_periods,
        lyapunov_periods=size.realization_lyapunov_periods,
        max_period=size.realization_max_period,
        store=ctx.store_path,
        workers=ctx.task_workers,
        scheduler=ctx.scheduler,
        progress=ctx.progress,
        allow_version_mismatch=ctx.allow_version_mismatch,
    )
    out = [_realization_record(r, i) for i, r in enumerate(records)]
    return {
        "spins": size.realization_spins,
        "coupling": size.realization_coupling,
        "realizations": size.realizations,
        "base_seed": ctx.seed,
        "q0": DEFAULT_Q0,
        "v0": V0,
        "transient": size.realization_transient,
        "periods": size.realization_periods,
        "max_periods": size.realization_max_periods,
        "max_period": size.realization_max_period,
        "lyapunov_periods": size.realization_lyapunov_periods,
        "counts": dict(Counter(r["kind"] for r in out)),
        "records": out,
        "reduced": _reduced(size, "realizations"),
    }


def basin_evidence(ctx: PaperContext, size: BasinEvidenceSize | None = None) -> dict[str, Any]:
    """The numbers of the module docstring, JSON-ready: ``neighbourhood`` (one basin record per
    C), ``band`` (the (q0, w0) basin record) and ``realizations``, plus ``size`` (the knobs)
    and ``seconds`` (wall time, stored tasks included).
    ``size`` defaults to :data:`BASIN_SIZES` of the run's size name (``ValueError`` for a size
    without basin sizes, e.g. ``smoke``). Tasks go through ``ctx``'s store, workers and
    scheduler."""
    if size is None:
        if ctx.size.name not in BASIN_SIZES:
            raise ValueError(
                f"size: no basin sizes for run size {ctx.size.name!r}; choose from "
                f"{sorted(BASIN_SIZES)} or pass a BasinEvidenceSize"
            )
        size = BASIN_SIZES[ctx.size.name]
    if not isinstance(size, BasinEvidenceSize):
        raise TypeError(f"size must be a BasinEvidenceSize, got {type(size).__name__}")
    near = BasinGrid(
        size.neighbourhood_q0_range, size.neighbourhood_v0_range, size.neighbourhood_grid
    )
    band = BasinGrid(
        size.band_q0_range, size.band_w0_range, size.band_grid, axis="w0", v0=size.band_v0
    )
    start = time.perf_counter()
    out = {
        "size": {f.name: getattr(size, f.name) for f in fields(size)},
        "neighbourhood": [
            _basin_record(ctx, c, near, size.neighbourhood_max_periods, size, "neighbourhood")
            for c in size.couplings
        ],
        "band": _basin_record(ctx, size.band_coupling, band, size.band_max_periods, size, "band"),
        "realizations": _realizations(ctx, size),
    }
    out["seconds"] = round(time.perf_counter() - start, 2)
    return out


# -- Markdown -------------------------------------------------------------------------------------


def _pct(a: dict[str, Any]) -> str:
    lo, hi = a["interval"]
    return f"{100 * a['fraction']:.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]"


def _mu(values: list[float]) -> str:
    return ", ".join(f"{m:.3g}" for m in values)


def _attractor_text(a: dict[str, Any]) -> str:
    if a["kind"] == "periodic":
        return (
            f"period {a['period']} (|μ| = {_mu(a['multipliers_abs'])}; transient median "
            f"{a['transient_median']:g}, max {a['transient_max']}) {_pct(a)}"
        )
    if a["kind"] == "chaotic":
        return (
            f"chaotic λ_max = {a['max_exponent']:.4f} ± {a['max_exponent_error']:.4f} "
            f"(D_KY {a['kaplan_yorke']:.2f}) {_pct(a)}"
        )
    return f"{a['kind']} {_pct(a)}"


def _grid_text(rec: dict[str, Any]) -> str:
    g = rec["grid"]
    y = "w0" if g["axis"] == "w0" else "v0"
    yr = g[f"{y}_range"]
    text = (
        f"{g['size']} × {g['size']} grid over q0 ∈ [{g['q0_range'][0]:g}, {g['q0_range'][1]:g}], "
        f"{y} ∈ [{yr[0]:g}, {yr[1]:g}]"
    )
    if g["axis"] == "w0":
        text += f" (v0 = {g['v0']:g}; {rec['valid_starts']} of {rec['starts']} starts in the band)"
    return text + f", up to {rec['max_periods']} periods per start"


def _reduced_text(rec: dict[str, Any]) -> str:
    return f" *Reduced — {rec['reduced']}.*" if rec.get("reduced") else ""


def _realization_text(r: dict[str, Any]) -> str:
    counts = r["counts"]
    kinds = ", ".join(f"{counts[k]} {k}" for k in ("periodic", "chaotic", "undecided",
                                                    "divergent") if counts.get(k))  # fmt: skip
    regular = [x for x in r["records"] if x["kind"] == "periodic"]
    chaotic = [x["max_exponent"] for x in r["records"] if x["kind"] == "chaotic"]
    text = (
        f"the first {r['realizations']} realizations of seed {r['base_seed']} (those of `hyst "
        f"ensemble`), from (q0, v0) = ({r['q0']:g}, {r['v0']:g}), transient {r['transient']} + up "
        f"to {r['max_periods']} periods, periods <= {r['max_period']}, λ_max over "
        f"{r['lyapunov_periods']} periods:** {kinds}."
    )
    if chaotic:
        text += f" Chaotic: λ_max {min(chaotic):.4f} … {max(chaotic):.4f} (> 2 × its error)."
    if regular:
        text += (
            " Regular: "
            + "; ".join(
                f"realization {x['index']}: period {x['period']} after {x['transient']} periods, "
                f"max |μ| = {x['max_abs_multiplier']:.2g} (residual {x['residual']:.1g})"
                for x in regular
            )
            + "."
        )
    else:
        text += " No regular realization among them."
    undecided = [x["max_exponent"] for x in r["records"] if x["kind"] == "undecided"]
    if undecided:
        text += (
            f" Undecided (no period <= {r['max_period']} within the run, λ_max not above twice "
            f"its error: long periods, slow approach or weak chaos): λ_max {min(undecided):.4f} "
            f"… {max(undecided):.4f}."
        )
    return text


def basin_lines(evidence: dict[str, Any]) -> list[str]:
    """Markdown lines of the Discussion's basin subsection (from :func:`basin_evidence`)."""
    near = evidence["neighbourhood"]
    band = evidence["band"]
    real = evidence["realizations"]
    lines = [
        "### Basins of the coexisting attractors and the disorder realizations (computed by "
        "this run)",
        "",
        "Every start runs from φ = 0 until its last 100 section points repeat within 1e-6 "
        "(periodic: the orbit refined by Newton, multipliers on (q, v, w), the wagon's exactly "
        "0), or to its period limit (aperiodic: chaotic when it lies in the section cloud of a "
        "continuation whose λ_max exceeds twice its error; else undecided). Fractions with the "
        "95 % Wilson score interval; erf play p = 2, R = 1, ζ = 0.05, Ω = 1.",
        "",
        f"- **erf play, C = 1.70–1.80, around the paper's start (q0, v0) = ({DEFAULT_Q0:g}, "
        f"{V0:g}): {_grid_text(near[0])}, Lyapunov runs of {near[0]['lyapunov_periods']} "
        "periods:** "
        + " ".join(
            f"C = {rec['coupling']:.2f}: "
            + "; ".join(_attractor_text(a) for a in rec["attractors"])
            + "."
            for rec in near
        )
        + _reduced_text(near[0]),
        f"- **erf play, C = {band['coupling']:g} in (q0, w0): {_grid_text(band)}:** "
        + "; ".join(_attractor_text(a) for a in band["attractors"])
        + (
            f". Transient until the section repeats: median {band['transient_median']:g}, "
            f"max {band['transient_max']} forcing periods."
            if band["transient_median"] is not None
            else ". No start settled on a periodic orbit."
        )
        + _reduced_text(band),
        f"- **N = {real['spins']} dimers, C = {real['coupling']:g}, "
        + _realization_text(real)
        + _reduced_text(real),
    ]
    return [*lines, ""]
