"""``hyst identify``: Preisach-plane identification from first-order reversal curves.

Two sources: an operator of the model registry (``--model``, the shared model options of
:mod:`analysis.cli._options`) driven through the reversal curves of a regular grid, or a
measured FORC file (``--input``). The paper's ridge metrics (``N(s; 0, R²) δ(r − p/2)``) are
computed only for the paper's models (``dimers``, ``erf-play``); other models and measured data
get data-driven summaries (masses, peak of the FORC density).
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli._build import (
    check_model_options,
    model_parameters,
    model_record,
    option_error,
)
from analysis.cli._identify_batch import input_files, run_batch
from analysis.cli._identify_measured import (
    add_uncertainty_options,
    amount_option,
    curve_kind,
    data_warnings,
    diagram_name,
    rho_unit,
    smoothing_option,
)
from analysis.cli._options import (
    add_model_options,
    add_output_options,
)
from analysis.cli._output import (
    announce_compilation,
    emit,
    figure_title,
    prepare_out,
    progress_enabled,
    to_json,
)
from analysis.cli._parsing import (
    CliError,
    add_subcommand,
    int_at_least,
    nonnegative_float,
    positive_float,
)
from analysis.experiments.models import build_operator
from analysis.identification import (
    auto_grid,
    compare_with_ridge,
    identify_from_curves,
    identify_preisach,
    protocol_lattice,
)
from analysis.identification.forc_io import detect_format, read_forc_file
from analysis.identification.memory import MemoryBoundError
from analysis.identification.normalization import (
    NORMALIZATIONS,
    normalized_unit,
)
from analysis.identification.plots import (
    FORCINEL,
    figure_forc,
    figure_preisach_density,
    figure_single_density,
)
from analysis.identification.uncertainty import summarize_uncertainty
from analysis.identification.variforc import VariforcParameters
from hysteresis._validation import check_grid_nodes

__all__ = ["register", "run"]

#: models this command identifies (the registry's names)
IDENTIFY_MODELS = ("dimers", "erf-play", "play", "preisach-uniform")
#: models whose density the paper states (N(s; 0, R²) δ(r − p/2)): only these get its metrics
PAPER_MODELS = ("dimers", "erf-play")
FORMATS = ("auto", "csv", "micromag", "lakeshore", "blocks", "segments")
#: the grid step of a model's identification (the paper's fig:preis_dens)
DEFAULT_STEP = 0.1


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "identify",
        help="identify the Preisach density of an operator or of measured FORC data",
        description="Drive an operator through first-order reversal curves on a regular grid "
        "(Mayergoyz convention: rise from negative saturation to alpha, fall to beta), compute "
        "the exact cell masses of the Preisach density and, for the paper's models (dimers, "
        "erf-play), compare with the paper's N(s; 0, R^2) delta(r - p/2). With --input, "
        "identify from a measured FORC file (MicroMag Series 0015/0016, Lake Shore 8600 CSV or "
        "the toolkit's CSV): grid from the measurement protocol, local-regression smoothing, "
        "FORC diagram in Bc/Bu (mT) and data-driven metrics only (no paper overlay). Writes "
        "DIR/identify.json and the figure (PNG, PDF, NPZ); dimers also give the paper's "
        "fig:preis_dens (erf play N -> infinity next to the finite ensemble).",
    )
    add_model_options(p, models=IDENTIFY_MODELS, default="dimers")
    g = p.add_argument_group("identification")
    g.add_argument(
        "--step",
        type=positive_float,
        default=None,
        help=f"models: grid step Delta (> 0; default {DEFAULT_STEP:g})",
    )
    g.add_argument(
        "--saturation",
        type=positive_float,
        default=None,
        help="models: grid half-extent H (> 0; default 5R + p/2, for dimers at least the "
        "largest |threshold|; preisach-uniform: also the triangle's half-extent)",
    )
    g.add_argument(
        "--smoothing",
        nargs="+",
        default=None,
        metavar="SF",
        help="smoothing factor SF, or SF_R SF_S (window half-widths across r and along s, in "
        "grid steps, > 0), or 'variforc' (--input: VARIFORC, Egli 2013, parameters --sc0 "
        "--sc1 --sb0 --sb1 --lambda), or 'auto' (--input: VARIFORC with its half-width chosen "
        "per file by a Lepski rule on the density: the largest half-width whose density stays "
        "within noise of every finer one); default: none for models, 3 for --input",
    )
    defaults = VariforcParameters()
    for name, what in (
        ("sc0", "across Bc on the ridge Bc = 0"),
        ("sc1", "across Bc far from Bc = 0"),
        ("sb0", "along Bu on the ridge Bu = 0"),
        ("sb1", "along Bu far from Bu = 0"),
    ):
        g.add_argument(
            f"--{name}",
            type=positive_float,
            default=None,
            metavar="S",
            help=f"--smoothing variforc: half-width {what}, in field steps (>= 1; default "
            f"{getattr(defaults, name):g}, PmagPy/FORCinel)",
        )
    g.add_argument(
        "--lambda",
        dest="lam",
        type=nonnegative_float,
        default=None,
        metavar="L",
        help=f"--smoothing variforc: rate of the linear growth of the half-widths away from the "
        f"ridges, in [0, 1] (default {defaults.lam:g})",
    )
    g.add_argument(
        "--normalize",
        choices=NORMALIZATIONS,
        default="none",
        help="--input: divide the moments by the sample's mass (A·m²/kg) or volume (A/m), "
        "from the header's Mass/Volume (with its unit) or --mass/--volume",
    )
    g.add_argument(
        "--mass",
        type=positive_float,
        default=None,
        metavar="KG",
        help="--normalize mass: the sample's mass in kg (> 0; default: the file header's)",
    )
    g.add_argument(
        "--volume",
        type=positive_float,
        default=None,
        metavar="M3",
        help="--normalize volume: the sample's volume in m³ (> 0; default: the file header's)",
    )
    add_uncertainty_options(g)
    g.add_argument(
        "--input",
        type=Path,
        nargs="+",
        default=None,
        metavar="PATH",
        help="FORC data file to identify instead of a model (default: none, use --model); a "
        "directory or several files: a batch, one diagram per file in OUT/<file stem>/ and "
        "OUT/summary.csv, OUT/summary.json",
    )
    g.add_argument(
        "--workers",
        type=int_at_least(1, 256),
        default=1,
        help="batch --input: files identified in parallel by this many processes (default 1)",
    )
    g.add_argument(
        "--format",
        choices=FORMATS,
        default="auto",
        help="--input format (auto: detected from the file)",
    )
    g.add_argument(
        "--columns",
        choices=("field,moment", "moment,field"),
        default=None,
        help="--input data-only file (two columns, no header): which column is which "
        "(default field,moment)",
    )
    g.add_argument(
        "--reversible-ridge",
        action="store_true",
        help="--input: include the reversible ridge at Bc = 0 in the smoothed density (constant "
        "extension below the diagonal, exact for relay systems); default: irreversible only",
    )
    g.add_argument(
        "--drift-correction",
        choices=("none", "multiplicative", "additive"),
        default="none",
        help="--input: linear drift correction from the calibration points (MicroMag, Lake Shore)",
    )
    g.add_argument(
        "--window",
        choices=("rs", "pike"),
        default="rs",
        help="--input: smoothing window, |dr|,|ds| <= SF steps (rs) or Pike et al. (1999)'s "
        "square |dB|,|dB_r| <= SF steps (pike)",
    )
    g.add_argument(
        "--grid-step",
        type=positive_float,
        default=None,
        help="--input: lattice step in the file's field unit after conversion (> 0; default: "
        "the median field step of the measurement)",
    )
    g.add_argument(
        "--max-memory",
        type=positive_float,
        default=None,
        metavar="GB",
        help="bound on the estimated peak memory of the identification in GB (> 0; default: "
        "half the physical memory); a larger one is refused before it starts",
    )
    add_output_options(p, writes="identify.json and the figure as PNG, PDF and NPZ")
    p.set_defaults(func=run)


def _max_memory(args: argparse.Namespace) -> float | None:
    """``--max-memory`` in bytes (``None``: the library's default bound)."""
    gb = getattr(args, "max_memory", None)
    return None if gb is None else gb * 1e9


def run(args: argparse.Namespace) -> int:
    """Validate every option (and read ``--input`` or build the model), then identify."""
    t0 = time.perf_counter()
    if args.input is not None:
        for option, given in (("--step", args.step), ("--saturation", args.saturation)):
            if given is not None:
                raise CliError(
                    f"argument {option}: only for models; with --input the lattice comes from "
                    "the measurement (--grid-step)"
                )
        files = input_files(args.input)
        if len(files) > 1 or any(p.is_dir() for p in args.input):
            smoothing_option(args, 3.0)  # option errors before any work
            return run_batch(args, files, _one_file)
        if args.workers != 1:
            raise CliError("argument --workers: only for a batch (a directory or several files)")
        args.input = files[0]
        measured = _prepare_measured(args)
        out = prepare_out(args)
        return _run_measured(args, out, t0, *measured)
    for option, given in (
        ("--workers", args.workers != 1),
        ("--grid-step", args.grid_step is not None),
        ("--uncertainty", args.uncertainty),
        ("--bootstrap", args.bootstrap != 200),
        ("--cmap", args.cmap is not None),
        ("--bootstrap-seed", args.bootstrap_seed != 0),
        ("--smoothing", args.smoothing in (["variforc"], ["auto"])),
        ("--normalize", args.normalize != "none"),
        ("--columns", args.columns is not None),
        ("--mass", args.mass is not None),
        ("--volume", args.volume is not None),
        ("--reversible-ridge", args.reversible_ridge),
        ("--drift-correction", args.drift_correction != "none"),
        ("--format", args.format != "auto"),
    ):
        if given:
            raise CliError(f"argument {option}: only with --input (a measured FORC file)")
    if args.step is None:
        args.step = DEFAULT_STEP
    model = _prepare_model(args)
    out = prepare_out(args)
    announce_compilation(args)
    return _run_model(args, out, t0, *model)


# -- models ----------------------------------------------------------------------------------


def _prepare_model(args: argparse.Namespace) -> tuple[Any, Any, float, Any]:
    """The operator, its thresholds (dimers), the grid's half-extent and the smoothing."""

    check_model_options(args)
    smoothing = smoothing_option(args, None)
    # preisach-uniform: the triangle is the grid (--saturation), so records and titles name it
    args.half_extent = args.saturation if args.model == "preisach-uniform" else None
    params = model_parameters(args)
    try:
        operator = build_operator(args.model, params)
    except (ValueError, TypeError) as exc:
        raise option_error(exc, "--model") from exc
    saturation = args.saturation or (5.0 * args.spread + 0.5 * args.width)
    thresholds = None
    if args.model == "dimers":
        thresholds = operator.thresholds()
        if args.saturation is None:
            extreme = float(np.max(np.abs([thresholds.alpha, thresholds.beta])))
            saturation = max(saturation, extreme)
    try:
        # the reversal curves cost nodes²/2 operator steps: refuse a grid without bound here,
        # naming the option, rather than inside the identification
        check_grid_nodes(args.step, saturation)
    except ValueError as exc:
        raise CliError(f"argument --step: {exc}") from exc
    return operator, thresholds, float(saturation), smoothing


def _run_model(
    args: argparse.Namespace,
    out: Path,
    t0: float,
    operator: Any,
    thresholds: Any,
    saturation: float,
    smoothing: tuple[float, float] | None,
) -> int:

    centres = None if thresholds is None else thresholds.centre
    try:
        ident = identify_preisach(
            operator,
            args.step,
            saturation,
            smoothing=smoothing,
            progress=progress_enabled(args),
            max_memory=_max_memory(args),
        )
    except MemoryBoundError as exc:
        raise CliError(f"argument --step: {exc}") from exc
    report: dict[str, Any] = model_record(args)
    report.update(step=args.step, saturation=saturation, grid_nodes=int(ident.alpha.size))
    # the paper's ridge metrics: only for the paper's models (dimers, erf play), never over
    # user data or other operators
    cmp = None
    # explicit --fields are the user's dimers, not the paper's disorder N(s; 0, R²)
    paper = args.model in PAPER_MODELS and args.fields is None
    if paper:
        cmp = compare_with_ridge(ident, args.width, args.spread, centres=centres)
        report.update(cmp.as_dict())
    else:
        report.update(
            total_mass=ident.total_mass,
            irreversible_mass=ident.irreversible_mass,
            reversible_mass=ident.reversible_mass,
        )
    report["mass_outside_grid"] = ident.mass_outside_grid
    report["smoothing"] = list(smoothing) if smoothing else None
    title = figure_title(args, "Preisach density", **{"Δ": float(args.step)})
    if paper and args.model == "dimers":
        # the paper's figure: the erf play (N -> infinity) next to the finite ensemble
        limit = identify_preisach(
            build_operator("erf-play", width=args.width, spread=args.spread),
            args.step,
            saturation,
            max_memory=_max_memory(args),
        )
        report["erf_play"] = compare_with_ridge(limit, args.width, args.spread).as_dict()
        paths = figure_preisach_density(
            limit,
            ident,
            args.width,
            args.spread,
            out,
            finite_label=f"N = {operator.n_spins}",
            extra_data={"centres": centres},
            title=title,
        )
    else:
        paths = figure_single_density(
            ident,
            out,
            f"identify_{args.model}".replace(".", "_"),
            title=title,
            smoothed=smoothing is not None,
            spread=args.spread if paper else None,
        )
    report["figure_title"] = title
    report["figures"] = [str(p) for p in paths]
    report["seconds"] = time.perf_counter() - t0
    (out / "identify.json").write_text(to_json(report, indent=2) + "\n")
    if cmp is None:
        summary = (
            f"total mass {ident.total_mass:.12g} (irreversible {ident.irreversible_mass:.6g}, "
            f"on the diagonal {ident.reversible_mass:.6g})"
        )
    else:
        summary = (
            f"total mass {cmp.total_mass:.12g}, r centre {cmp.r_centre:.12g}, "
            f"mass within 2 cells of the ridge {cmp.r_mass_within_2_cells:.6g}, "
            f"s-CDF distance to the Gaussian {cmp.s_cdf_distance_gaussian:.3g}"
            + (
                f", to the empirical CDF {cmp.s_cdf_distance_empirical:.3g}"
                if cmp.s_cdf_distance_empirical is not None
                else ""
            )
        )
    written = f"wrote {out / 'identify.json'} and {', '.join(str(p) for p in paths)}"
    emit(args, report, [summary, written])
    return 0


# -- measured data ---------------------------------------------------------------------------


def _prepare_measured(args: argparse.Namespace) -> tuple[str, Any, tuple[float, float]]:
    """Check ``--input`` and the options that go with it and read the file (before any output
    is written); errors name the option (and the file and line)."""

    path = Path(args.input)
    if not path.exists():
        raise CliError(f"argument --input: {path}: no such file")
    if not path.is_file():
        raise CliError(f"argument --input: {path}: not a regular file")
    if not os.access(path, os.R_OK):
        raise CliError(f"argument --input: {path}: not readable")
    smoothing = smoothing_option(args, 3.0)
    try:
        fmt = detect_format(path) if args.format == "auto" else args.format
    except (ValueError, OSError) as exc:
        raise CliError(f"argument --input: {_about(path, exc)}") from exc
    kwargs: dict[str, Any] = {}
    if args.columns is not None:
        if fmt != "blocks":
            raise CliError(
                f"argument --columns: for data-only files (two columns, no header), not {fmt!r}"
            )
        kwargs["columns"] = args.columns
    if args.drift_correction != "none":
        if fmt not in ("micromag", "lakeshore"):
            raise CliError(
                "argument --drift-correction: needs calibration points (MicroMag or Lake Shore "
                f"files), not {fmt!r}"
            )
        kwargs["drift_correction"] = args.drift_correction
    try:
        data = read_forc_file(path, fmt, max_memory=_max_memory(args), **kwargs)
    except MemoryBoundError as exc:
        raise CliError(f"argument --input: {path}: {exc}") from exc
    except (ValueError, OSError) as exc:
        # a user's file: one line naming the problem (and its line), not a traceback
        raise CliError(f"argument --input: {_about(path, exc)}") from exc
    if args.grid_step is not None:
        _check_grid_step(args, data.curves)
    args.amount = amount_option(args, data)
    return fmt, data, smoothing  # type: ignore[return-value]


def _about(path: Path, exc: Exception) -> str:
    """``PATH: message``, the path once (the readers' messages may start with it)."""
    msg = str(exc)
    return msg if msg.startswith(f"{path}: ") else f"{path}: {msg}"


def _check_grid_step(args: argparse.Namespace, curves: Any) -> None:
    """``--grid-step`` applies to the protocol lattice only (fields that differ from curve to
    curve); refuse it on data whose fields share one grid (it would be ignored) and refuse a
    lattice too fine or too coarse for the data, before any output is written."""

    # the rule of identify_from_curves(grid="auto"): measured fields -> protocol lattice
    if auto_grid(curves) == "native":
        raise CliError(
            f"argument --grid-step: {args.input} has its fields on one shared grid (identified "
            "on that grid); --grid-step applies to measured fields that differ curve by curve"
        )
    try:
        protocol_lattice(curves, args.grid_step)
    except ValueError as exc:
        raise CliError(f"argument --grid-step: {args.input}: {exc}") from exc


def _run_measured(
    args: argparse.Namespace,
    out: Path,
    t0: float,
    fmt: str,
    data: Any,
    smoothing: tuple[float, float] | VariforcParameters,
) -> int:
    """Measured FORC data: data-driven summaries only (no paper overlay)."""

    variforc = isinstance(smoothing, (VariforcParameters, str))
    if (variforc or args.uncertainty) and args.window != "rs":
        raise CliError(
            "argument --window: VARIFORC and --uncertainty use the rs window (the VARIFORC "
            "law is defined across Bc and along Bu)"
        )
    try:
        ident = identify_from_curves(
            data.curves,
            smoothing=smoothing,
            output_range=(-math.inf, math.inf),
            extend=args.reversible_ridge,
            step=args.grid_step,
            window=args.window,
            max_memory=_max_memory(args),
            uncertainty=args.uncertainty,
        )
    except MemoryBoundError as exc:
        raise CliError(f"argument --input: {args.input}: {exc}") from exc
    except ValueError as exc:
        option = "--grid-step" if str(exc).startswith("step") else "--input"
        raise CliError(f"argument {option}: {args.input}: {exc}") from exc
    bc, bu, rho = ident.density_peak()
    step = ident.step if ident.step is not None else float(np.median(np.diff(ident.alpha)))
    # ρ in the field's unit: moment per T² (the readers give fields in mT: 1/mT² = 10⁶/T²)
    rho_factor, rho_name = rho_unit(data, args.normalize)
    amount = getattr(args, "amount", 1.0)
    rho_factor /= amount
    report: dict[str, Any] = {
        "input": str(args.input),
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
        "window": args.window,
        "reversible_ridge": args.reversible_ridge,
        "peak_bc_mT": bc,
        "peak_bu_mT": bu,
        "peak_rho": rho * rho_factor,
        "rho_unit": rho_name,
        "irreversible_mass": ident.irreversible_mass / amount,
        "reversible_mass": ident.reversible_mass / amount,
        "mass_unit": normalized_unit(data.moment_unit, args.normalize),
        "normalize": args.normalize,
        "normalized_by": None if args.normalize == "none" else amount,
        "drift_correction": args.drift_correction,
    }
    interval = ""
    if args.uncertainty:
        u = summarize_uncertainty(ident, n_boot=args.bootstrap, seed=args.bootstrap_seed)
        report.update(
            peak_rho_se=u.peak_rho_se * rho_factor,
            peak_bc_interval_mT=list(u.peak_bc_interval),
            peak_bu_interval_mT=list(u.peak_bu_interval),
            peak_interval_method=f"parametric bootstrap, {args.bootstrap} replicates, 95 %",
            irreversible_mass_se=u.irreversible_mass_se / amount,
            significant_fraction=u.significant_fraction,
            noise_sigma=u.noise_sigma,
        )
        interval = (
            f" (Bc in [{u.peak_bc_interval[0]:.4g}, {u.peak_bc_interval[1]:.4g}], Bu in "
            f"[{u.peak_bu_interval[0]:.4g}, {u.peak_bu_interval[1]:.4g}])"
        )
    stem = "identify_" + Path(args.input).stem.replace(".", "_")
    # measured data: the title names the file and the identification's parameters (there is
    # no model)
    if variforc:
        law = "VARIFORC sc={sc0:g}/{sc1:g} sb={sb0:g}/{sb1:g} λ={lam:g}".format(**ident.variforc)
        if ident.smoothing_choice is not None:
            law += " (chosen automatically)"
    else:
        law = f"SF={smoothing[0]:g}/{smoothing[1]:g}"
    title = f"{diagram_name(data)}: {Path(args.input).name}\n"
    title += f"{law}, Δ={step:.3g} mT, window={args.window}"
    paths = figure_forc(
        ident,
        out,
        stem,
        title=title,
        field_unit="mT",
        moment_unit=normalized_unit(data.moment_unit, args.normalize),
        rho_factor=rho_factor,
        rho_unit=rho_name,
        cmap=args.cmap or FORCINEL,
    )
    report["figure_title"] = title
    report["figures"] = [str(p) for p in paths]
    report["seconds"] = time.perf_counter() - t0
    (out / "identify.json").write_text(to_json(report, indent=2) + "\n")
    mass = f"{report['irreversible_mass']:.4g}"
    if args.uncertainty:
        mass += f" ± {report['irreversible_mass_se']:.2g}"
    lines = [
        f"{report['n_curves']} curves, {report['n_points']} points, grid step {step:.4g} mT; "
        f"FORC peak at Bc = {bc:.4g} mT, Bu = {bu:.4g} mT{interval}; irreversible mass {mass}",
        f"wrote {out / 'identify.json'} and {', '.join(str(p) for p in paths)}",
    ]
    if getattr(args, "batch_child", False):
        return report  # type: ignore[return-value]
    emit(args, report, lines)
    return 0


# -- batches (the loop and the summary: analysis/cli/_identify_batch.py) ------------------


def _one_file(args: argparse.Namespace, path: Path, out: Path) -> dict[str, Any]:
    """Identify one file of a batch into ``out``; the report, or the error as one line."""
    child = argparse.Namespace(**vars(args))
    child.input = path
    child.out = out
    child.batch_child = True
    child.json = False
    try:
        measured = _prepare_measured(child)
        out.mkdir(parents=True, exist_ok=True)
        report = _run_measured(child, out, time.perf_counter(), *measured)
        report["status"] = "ok"
        return report  # type: ignore[return-value]
    except CliError as exc:
        return {"input": str(path), "status": "failed", "error": str(exc)}
