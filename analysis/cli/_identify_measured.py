"""``hyst identify --input``: the words of ``--smoothing`` (a factor or two, ``variforc``,
``auto``), the unit of ρ, the uncertainty and colour options; and what the command says about
the data: the kind of curves (in-field or remanence FORC), the warnings about them and the major
loop's hysteresis parameters; reading one measured file (:func:`read_measured`) and
identifying it into ``identify.json`` and its FORC diagram (:func:`identify_measured`). Errors
are one line naming the option (:class:`~analysis.cli._parsing.CliError`); what the options
mean together is decided by :class:`~analysis.identification.request.IdentifyRequest`.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli._output import to_json
from analysis.cli._parsing import CliError, int_at_least, library_errors, positive_float
from analysis.identification import identify_from_curves
from analysis.identification.curves import KIND_NAMES
from analysis.identification.forc_io import detect_format, read_forc_file
from analysis.identification.major_loop import hysteresis_parameters
from analysis.identification.memory import MemoryBoundError
from analysis.identification.normalization import normalized_unit
from analysis.identification.plots import FORCINEL, colormap_name, figure_forc
from analysis.identification.request import IdentifyRequest
from analysis.identification.result import RIDGE_EXCLUSION_STEPS
from analysis.identification.uncertainty import summarize_uncertainty
from analysis.identification.variforc import VariforcParameters

__all__ = [
    "smoothing_words",
    "rho_unit",
    "curve_kind",
    "diagram_name",
    "data_warnings",
    "add_uncertainty_options",
    "hysteresis_report",
    "read_measured",
    "identify_measured",
]


def smoothing_words(
    words: list[str] | None,
) -> float | tuple[float, float] | str | None:
    """``--smoothing`` parsed: ``None``, ``"variforc"``, ``"auto"`` or one or two positive
    factors (the library's :class:`~analysis.identification.request.IdentifyRequest` decides
    what the source and the VARIFORC options make of them)."""
    if words is None:
        return None
    if words in (["variforc"], ["auto"]):
        return words[0]
    if len(words) not in (1, 2):
        raise CliError(
            f"argument --smoothing: takes one factor SF or two, SF_R SF_S, or 'variforc'; got "
            f"{len(words)} values"
        )
    try:
        factors = tuple(positive_float(x) for x in words)
    except (argparse.ArgumentTypeError, ValueError) as exc:
        raise CliError(f"argument --smoothing: {exc} (or 'variforc', 'auto')") from exc
    return factors[0] if len(factors) == 1 else factors


def rho_unit(data: Any, normalize: str = "none") -> tuple[float, str]:
    """Factor from the identification's ρ (moment per mT²) to the field's unit, and its name:
    ``A·m²/T²`` (×10⁶; ``A·m²/kg/T²``, ``A/m/T²`` normalised) when the file states its units,
    else the file's own units."""
    if data.field_unit == "mT" and data.moment_unit:
        return 1e6, f"{normalized_unit(data.moment_unit, normalize)}/T²"
    return 1.0, "moment/field² (as written)"


def curve_kind(data: Any) -> str:
    """``"FORC"`` or ``"remanence FORC"``: what the file's curves are (reports)."""
    return KIND_NAMES[data.curves.kind]


def diagram_name(data: Any) -> str:
    """``"FORC diagram"`` or ``"Remanence FORC diagram"`` (titles)."""
    name = curve_kind(data)
    return f"{name[:1].upper()}{name[1:]} diagram"


def data_warnings(data: Any, ident: Any) -> list[str]:
    """What the result cannot say because of the data, one sentence each: an aborted run (the
    region its masses and diagram cover), a peak at the ridge exclusion's edge (unresolved on
    a coarse grid) and a negative irreversible mass."""
    out = []
    curves = data.curves
    if not data.complete and curves.convention == "pike":
        last = int(np.argmin(curves.reversal_field))
        others = [h[-1] for c, h in enumerate(curves.fields) if c != last]
        end = float(curves.fields[last][-1])
        stop = ""
        if others and end < float(np.median(others)):
            rev = curves.reversal_field[last]
            stop = f"; its last curve (B_r = {rev:.4g} mT) stops at {end:.4g} mT"
        out.append(
            f"aborted measurement ({'; '.join(data.notes)}){stop}: the diagram and the masses "
            f"cover reversal fields >= {curves.reversal_field[last]:.4g} mT only, the "
            "irreversible mass misses the relays switching below"
        )
    if ident.density_alpha_beta is not None and ident.peak_at_exclusion_edge():
        edge = RIDGE_EXCLUSION_STEPS * ident.grid_step
        out.append(
            f"the FORC density rises toward the B_c = 0 ridge up to the peak search's exclusion "
            f"edge (B_c = {edge:.4g} mT, {RIDGE_EXCLUSION_STEPS} grid steps of "
            f"{ident.grid_step:.4g} mT): no coercivity peak is resolved above it; the reported "
            "peak is the edge's largest value and its B_c interval starts at 0"
        )
    if ident.irreversible_mass < 0:
        out.append(
            f"the irreversible mass is negative ({ident.irreversible_mass:.4g}): the measured "
            "curves cross (noise, drift or an incomplete protocol), check them"
        )
    return out


def _cmap(text: str) -> str:
    """``--cmap``: a matplotlib colour map name or ``forcinel``."""
    try:
        return colormap_name(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_uncertainty_options(g: Any) -> None:
    """``--uncertainty``, ``--bootstrap``, ``--bootstrap-seed`` and ``--cmap`` (on the group
    ``g`` of ``hyst identify``)."""
    g.add_argument(
        "--uncertainty",
        action="store_true",
        help="--input: standard error of rho at every node, significance contours on the "
        "diagram, the peak with a bootstrap interval and the irreversible mass with its error",
    )
    g.add_argument(
        "--bootstrap",
        type=int_at_least(20, 100000),
        default=None,
        metavar="N",
        help="--uncertainty: replicates of the peak's parametric bootstrap (>= 20; default 200)",
    )
    g.add_argument(
        "--bootstrap-seed",
        type=int_at_least(0),
        default=None,
        metavar="S",
        help="--uncertainty: seed of the bootstrap's noise (>= 0; default 0)",
    )
    g.add_argument(
        "--cmap",
        type=_cmap,
        default=None,
        metavar="NAME",
        help="colour map of the FORC diagram: any matplotlib map name (default: FORCinel-like, "
        "white at rho = 0, blue below, green-yellow-red above)",
    )


def hysteresis_report(curves: Any, amount: float) -> dict[str, Any]:
    """The major loop's parameters (moments divided by the normalisation ``amount``; fields
    in mT; ``None`` where the data do not allow them)."""
    hp = hysteresis_parameters(curves)
    out = hp.as_dict()
    for key in ("ms", "mrs"):
        if out[key] is not None:
            out[key] /= amount
    return {
        "ms": out["ms"],
        "mrs": out["mrs"],
        "bc_mT": out["bc"],
        "bcr_mT": out["bcr"],
        "mrs_ms": out["mrs_ms"],
        "bcr_bc": out["bcr_bc"],
    }


# -- measured data ---------------------------------------------------------------------------


def read_measured(
    request: IdentifyRequest, path: Path, options: Mapping[str, str]
) -> tuple[str, Any, float]:
    """Read one FORC file (before any output is written): its format, its data and the
    normalisation's divisor; errors name the option (and the file and line; ``options``: the
    command's library-parameter -> option names)."""
    if not path.exists():
        raise CliError(f"argument --input: {path}: no such file")
    if not path.is_file():
        raise CliError(f"argument --input: {path}: not a regular file")
    if not os.access(path, os.R_OK):
        raise CliError(f"argument --input: {path}: not readable")
    try:
        fmt = detect_format(path) if request.file_format == "auto" else request.file_format
    except (ValueError, OSError) as exc:
        raise CliError(f"argument --input: {_about(path, exc)}") from exc
    with library_errors(options):
        reader_options = request.reader_options(fmt)
    try:
        with warnings.catch_warnings(record=True) as notes:  # a note, not a failure
            warnings.simplefilter("always")
            data = read_forc_file(path, fmt, max_memory=request.max_memory, **reader_options)
        for note in notes:
            print(f"hyst identify: note: {note.message}", file=sys.stderr)
    except MemoryBoundError as exc:
        raise CliError(f"argument --input: {path}: {exc}") from exc
    except (ValueError, OSError) as exc:
        # a user's file: one line naming the problem (and its line), not a traceback
        raise CliError(f"argument --input: {_about(path, exc)}") from exc
    try:
        request.check_grid_step(data.curves)
    except ValueError as exc:
        raise CliError(f"argument --grid-step: {_about(path, exc)}") from exc
    try:
        amount = request.amount(data.moment_unit, data.header)
    except ValueError as exc:
        raise CliError(f"argument --normalize: {_about(path, exc)}") from exc
    return fmt, data, amount


def _about(path: Path, exc: Exception) -> str:
    """``PATH: message``, the path once (the readers' messages may start with it)."""
    msg = str(exc)
    return msg if msg.startswith(f"{path}: ") else f"{path}: {msg}"


def identify_measured(
    request: IdentifyRequest,
    path: Path,
    out: Path,
    t0: float,
    fmt: str,
    data: Any,
    amount: float,
) -> tuple[dict[str, Any], list[str]]:
    """Measured FORC data: data-driven summaries only (no paper overlay); writes
    identify.json and the FORC diagram into ``out``; the report and its lines."""
    smoothing = request.smoothing
    variforc = isinstance(smoothing, (VariforcParameters, str))
    try:
        ident = identify_from_curves(
            data.curves,
            smoothing=smoothing,
            output_range=(-math.inf, math.inf),
            extend=request.reversible_ridge,
            step=request.grid_step,
            window=request.window,
            max_memory=request.max_memory,
            uncertainty=request.uncertainty,
        )
    except MemoryBoundError as exc:
        raise CliError(f"argument --input: {path}: {exc}") from exc
    except ValueError as exc:
        option = "--grid-step" if str(exc).startswith("step") else "--input"
        raise CliError(f"argument {option}: {path}: {exc}") from exc
    bc, bu, rho = ident.density_peak()
    edge = ident.peak_at_exclusion_edge()
    step = ident.step if ident.step is not None else float(np.median(np.diff(ident.alpha)))
    # ρ in the field's unit: moment per T² (the readers give fields in mT: 1/mT² = 10⁶/T²)
    rho_factor, rho_name = rho_unit(data, request.normalize)
    rho_factor /= amount
    report: dict[str, Any] = {
        "input": str(path),
        "format": fmt,
        "curve_kind": curve_kind(data),
        "warnings": data_warnings(data, ident),
        "convention": data.curves.convention,
        "units_of_measure": data.units_of_measure,
        "field_unit": data.field_unit or "as written (taken as mT)",
        "moment_unit": data.moment_unit or "as written",
        "complete": data.complete,
        "notes": list(data.notes),
        "n_curves": data.curves.n_curves,
        "n_points": data.curves.n_points,
        "grid_step_mT": step,
        "grid_regular": ident.is_regular,
        "smoothing_method": ident.smoothing_method,
        "smoothing_factor": None if variforc else list(smoothing),
        "variforc": ident.variforc,
        "smoothing_choice": ident.smoothing_choice,
        "window": request.window,
        "reversible_ridge": request.reversible_ridge,
        # no peak (a density exactly 0): null, a value that is missing, not a measured NaN
        "peak_bc_mT": _present(bc),
        "peak_bu_mT": _present(bu),
        "peak_rho": _present(rho * rho_factor),
        "rho_unit": rho_name,
        "irreversible_mass": ident.irreversible_mass / amount,
        "irreversible_mass_definition": "sum of cell masses off the B_c = 0 ridge = "
        "∬ρ dB dB_r (Preisach α-β plane)",
        "irreversible_mass_bcbu": ident.irreversible_mass_bcbu / amount,
        "irreversible_mass_bcbu_definition": "∬ρ dB_c dB_u over the FORC diagram = half of "
        "irreversible_mass (Jacobian 1/2; PmagPy's convention)",
        "peak_excludes_bc_below_mT": RIDGE_EXCLUSION_STEPS * step,
        # the density rises across the exclusion's edge: the peak is not resolved above it
        "peak_at_exclusion_edge": edge,
        "hysteresis": hysteresis_report(data.curves, amount),
        "reversible_mass": ident.reversible_mass / amount,
        "mass_unit": normalized_unit(data.moment_unit, request.normalize),
        "normalize": request.normalize,
        "normalized_by": None if request.normalize == "none" else amount,
        "drift_correction": request.drift_correction,
    }
    interval = ""
    if request.uncertainty:
        u = summarize_uncertainty(ident, n_boot=request.bootstrap, seed=request.bootstrap_seed)
        report.update(
            peak_rho_se=_present(u.peak_rho_se * rho_factor),
            # at the exclusion's edge the replicates' peaks pile up on it: the peak lies at
            # or below the edge, the honest interval starts at B_c = 0
            peak_bc_interval_mT=[
                0.0 if edge and k == 0 else _present(x) for k, x in enumerate(u.peak_bc_interval)
            ],
            peak_bu_interval_mT=[_present(x) for x in u.peak_bu_interval],
            peak_interval_method=f"parametric bootstrap, {request.bootstrap} replicates, 95 %",
            irreversible_mass_se=u.irreversible_mass_se / amount,
            significant_fraction=u.significant_fraction,
            noise_sigma=u.noise_sigma,
        )
        lo_bc, hi_bc = report["peak_bc_interval_mT"]
        interval = (
            ""
            if math.isnan(bc)
            else (
                f" (Bc in [{lo_bc:.4g}, {hi_bc:.4g}], Bu in "
                f"[{u.peak_bu_interval[0]:.4g}, {u.peak_bu_interval[1]:.4g}])"
            )
        )
    stem = "identify_" + path.stem.replace(".", "_")
    # measured data: the title names the file and the identification's parameters (there is
    # no model)
    if variforc:
        law = "VARIFORC sc={sc0:g}/{sc1:g} sb={sb0:g}/{sb1:g} λ={lam:g}".format(**ident.variforc)
        if ident.smoothing_choice is not None:
            law += " (chosen automatically)"
    else:
        law = f"SF={smoothing[0]:g}/{smoothing[1]:g}"
    title = f"{diagram_name(data)}: {path.name}\n"
    title += f"{law}, Δ={step:.3g} mT, window={request.window}"
    paths = figure_forc(
        ident,
        out,
        stem,
        title=title,
        field_unit="mT",
        moment_unit=normalized_unit(data.moment_unit, request.normalize),
        rho_factor=rho_factor,
        rho_unit=rho_name,
        cmap=request.cmap or FORCINEL,
    )
    report["figure_title"] = title
    report["figures"] = [str(p) for p in paths]
    report["seconds"] = time.perf_counter() - t0
    (out / "identify.json").write_text(to_json(report, indent=2) + "\n")
    mass = f"{report['irreversible_mass']:.4g}"
    if request.uncertainty:
        mass += f" ± {report['irreversible_mass_se']:.2g}"
    peak = (
        "no FORC peak (the density is zero)"
        if math.isnan(bc)
        else f"FORC peak{' at the exclusion edge' if edge else ''} at Bc = {bc:.4g} mT, "
        f"Bu = {bu:.4g} mT{interval}"
    )
    lines = [
        f"{report['n_curves']} curves, {report['n_points']} points, grid step {step:.4g} mT; "
        f"{peak}; irreversible mass {mass}",
        f"wrote {out / 'identify.json'} and {', '.join(str(p) for p in paths)}",
    ]
    return report, lines


def _present(x: float) -> float | None:
    """``x``, or ``None`` (JSON ``null``) where it is missing: the peak's values and interval
    when there is no peak (NaN from :meth:`density_peak`). Measured non-finite values elsewhere
    keep the strict-JSON strings of :mod:`analysis._json`."""
    return None if math.isnan(x) else x
