"""``hyst identify``: Preisach-plane identification from first-order reversal curves.

Two sources: an operator of the model registry (``--model``, the shared model options of
:mod:`analysis.cli._options`) driven through the reversal curves of a regular grid, or a
measured FORC file (``--input``). The paper's ridge metrics (``N(s; 0, R²) δ(r − p/2)``) are
computed only for the paper's models (``dimers``, ``erf-play``); other models and measured data
get data-driven summaries (masses, peak of the FORC density).

The command parses the options into the library's
:class:`~analysis.identification.request.IdentifyRequest`, which checks them as a whole and
makes the decisions (the grid, the smoothing law, the paper's reference); the command prints
the library's message after the option it names, reads the file or builds the operator, and
renders the report, the figure and the lines.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli._build import (
    check_model_options,
    check_no_model_options,
    model_parameters,
    model_record,
    option_error,
)
from analysis.cli._identify_batch import forc_input_files, input_files, run_batch
from analysis.cli._identify_measured import (
    add_uncertainty_options,
    identify_measured,
    read_measured,
    smoothing_words,
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
    library_errors,
    nonnegative_float,
    positive_float,
)
from analysis.experiments.models import MODELS, build_operator
from analysis.identification import (
    compare_with_ridge,
    identify_preisach,
)
from analysis.identification.forc_io import FORMATS
from analysis.identification.memory import MemoryBoundError
from analysis.identification.normalization import (
    NORMALIZATIONS,
)
from analysis.identification.plots import (
    figure_preisach_density,
    figure_single_density,
)
from analysis.identification.request import (
    COLUMN_LAYOUTS,
    DEFAULT_MODEL_STEP,
    DRIFT_CORRECTIONS,
    VARIFORC_PARAMETERS,
    IdentifyRequest,
)
from analysis.identification.smoothing import WINDOWS
from analysis.identification.variforc import VariforcParameters

__all__ = ["register", "run"]

#: models this command identifies (the registry's names)
IDENTIFY_MODELS = ("dimers", "erf-play", "play", "preisach-uniform")


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
        help=f"models: grid step Delta (> 0; default {DEFAULT_MODEL_STEP:g})",
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
        choices=COLUMN_LAYOUTS,
        default=None,
        metavar="LAYOUT",  # argparse's {a,b} is ambiguous when the choices hold commas
        help="--input data-only file (two columns, no header): which column is which, "
        + " or ".join(f"'{c}'" for c in COLUMN_LAYOUTS)
        + " (default field,moment)",
    )
    g.add_argument(
        "--reversible-ridge",
        action="store_true",
        help="--input: include the reversible ridge at Bc = 0 in the smoothed density (constant "
        "extension below the diagonal, exact for relay systems); default: irreversible only",
    )
    g.add_argument(
        "--drift-correction",
        choices=DRIFT_CORRECTIONS,
        default="none",
        help="--input: linear drift correction from the calibration points (MicroMag, Lake Shore)",
    )
    g.add_argument(
        "--window",
        choices=WINDOWS,
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


#: library parameter -> the option of this command that carries it
OPTIONS = {
    "model": "--model",
    "inputs": "--input",
    "workers": "--workers",
    "step": "--step",
    "saturation": "--saturation",
    "smoothing": "--smoothing",
    "sc0": "--sc0",
    "sc1": "--sc1",
    "sb0": "--sb0",
    "sb1": "--sb1",
    "lam": "--lambda",
    "lambda": "--lambda",
    "file_format": "--format",
    "columns": "--columns",
    "drift_correction": "--drift-correction",
    "normalize": "--normalize",
    "mass": "--mass",
    "volume": "--volume",
    "grid_step": "--grid-step",
    "window": "--window",
    "reversible_ridge": "--reversible-ridge",
    "uncertainty": "--uncertainty",
    "bootstrap": "--bootstrap",
    "bootstrap_seed": "--bootstrap-seed",
    "cmap": "--cmap",
    "max_memory": "--max-memory",
}


def request_from(args: argparse.Namespace) -> IdentifyRequest:
    """The library's :class:`~analysis.identification.request.IdentifyRequest` of the options
    (it checks them as a whole; its message is printed after the option it names). With
    ``--input`` the model options are not read."""
    variforc = {n: getattr(args, n) for n in VARIFORC_PARAMETERS if getattr(args, n) is not None}
    with library_errors(OPTIONS):
        return IdentifyRequest(
            model=None if args.input is not None else args.model,
            explicit_fields=args.fields is not None,
            inputs=tuple(args.input or ()),
            workers=args.workers,
            step=args.step,
            saturation=args.saturation,
            smoothing=smoothing_words(args.smoothing),
            variforc=variforc,
            file_format=args.format,
            columns=args.columns,
            drift_correction=args.drift_correction,
            normalize=args.normalize,
            mass=args.mass,
            volume=args.volume,
            grid_step=args.grid_step,
            window=args.window,
            reversible_ridge=args.reversible_ridge,
            uncertainty=args.uncertainty,
            bootstrap=args.bootstrap,
            bootstrap_seed=args.bootstrap_seed,
            cmap=args.cmap,
            max_memory=None if args.max_memory is None else args.max_memory * 1e9,
        )


def run(args: argparse.Namespace) -> int:
    """Check the options (the request), read ``--input`` or build the model, identify, write
    and report."""
    t0 = time.perf_counter()
    check_no_model_options(args, "--input", args.input is not None)
    request = request_from(args)
    if request.measured:
        if request.batch:  # folders searched recursively; files no reader recognises skipped
            files, skipped = forc_input_files(list(request.inputs))
            return run_batch(args, files, _one_file, skipped)
        files = input_files(list(request.inputs))
        measured = read_measured(request, files[0], OPTIONS)
        out = prepare_out(args)
        report, lines = identify_measured(request, files[0], out, t0, *measured)
    else:
        model = _prepare_model(args, request)
        out = prepare_out(args)
        announce_compilation(args)
        report, lines = _identify_model(args, request, out, t0, *model)
    emit(args, report, lines)
    return 0


# -- models ----------------------------------------------------------------------------------


def _prepare_model(args: argparse.Namespace, request: IdentifyRequest) -> tuple[Any, Any, float]:
    """The operator, its thresholds (dimers) and the grid's half-extent."""
    # the grid's half-extent 5R + p/2 reads --width and --spread unless --saturation is given
    grid_reads = ("width", "spread") if args.saturation is None else ()
    check_model_options(args, grid_reads, half_extent=request.operator_half_extent)
    params = model_parameters(args, half_extent=request.operator_half_extent)
    try:
        operator = build_operator(args.model, params)
    except (ValueError, TypeError) as exc:
        raise option_error(exc, "--model") from exc
    thresholds = operator.thresholds() if args.model == "dimers" else None
    extreme = None
    if thresholds is not None:
        extreme = float(np.max(np.abs([thresholds.alpha, thresholds.beta])))
    # the reversal curves cost nodes²/2 operator steps: a grid without bound is refused here,
    # naming the option, rather than inside the identification
    with library_errors(OPTIONS, "--step"):
        saturation = request.grid_half_extent(args.width, args.spread, extreme)
    return operator, thresholds, saturation


def _identify_model(
    args: argparse.Namespace,
    request: IdentifyRequest,
    out: Path,
    t0: float,
    operator: Any,
    thresholds: Any,
    saturation: float,
) -> tuple[dict[str, Any], list[str]]:
    """Identify the operator, write identify.json and the figure; the report and its lines."""
    centres = None if thresholds is None else thresholds.centre
    smoothing = request.smoothing
    try:
        ident = identify_preisach(
            operator,
            request.step,
            saturation,
            smoothing=smoothing,
            progress=progress_enabled(args),
            max_memory=request.max_memory,
        )
    except MemoryBoundError as exc:
        raise CliError(f"argument --step: {exc}") from exc
    model = model_record(args, half_extent=request.operator_half_extent)
    report: dict[str, Any] = dict(model)
    report.update(step=request.step, saturation=saturation, grid_nodes=int(ident.alpha.size))
    cmp = None
    if request.paper_reference:
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
    title = figure_title(args, "Preisach density", model=model, **{"Δ": float(request.step)})
    if request.paper_figure:
        limit = identify_preisach(
            build_operator("erf-play", width=args.width, spread=args.spread),
            request.step,
            saturation,
            max_memory=request.max_memory,
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
            # a sum's text is no file name
            "identify_sum" if args.model not in MODELS else f"identify_{args.model}",
            title=title,
            smoothed=smoothing is not None,
            spread=args.spread if request.paper_reference else None,
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
    return report, [summary, written]


# -- batches (the loop and the summary: analysis/cli/_identify_batch.py) ------------------


def _one_file(args: argparse.Namespace, path: Path, out: Path) -> dict[str, Any]:
    """Identify one file of a batch into ``out``; the report, or the error as one line."""
    try:
        request = request_from(args)
        measured = read_measured(request, path, OPTIONS)
        out.mkdir(parents=True, exist_ok=True)
        report, _ = identify_measured(request, path, out, time.perf_counter(), *measured)
    except CliError as exc:
        return {"input": str(path), "status": "failed", "error": str(exc)}
    report["status"] = "ok"
    return report
