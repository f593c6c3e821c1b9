"""``hyst identify``: Preisach-plane identification from first-order reversal curves."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

MODELS = ("dimers", "erf-play", "play", "preisach-uniform")


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "identify",
        help="identify the Preisach density of an operator or of measured FORC data",
        description="Drive an operator through first-order reversal curves on a regular grid "
        "(Mayergoyz convention: rise from negative saturation to alpha, fall to beta), compute "
        "the exact cell masses of the Preisach density and compare with the paper's "
        "N(s; 0, R^2) delta(r - p/2). With --input, identify from a measured FORC file (MicroMag "
        "Series 0015/0016, Lake Shore 8600 CSV or the toolkit's CSV): grid from the measurement "
        "protocol, local-regression smoothing, FORC diagram in Bc/Bu (mT) and data-driven "
        "metrics only (no paper overlay). Writes DIR/identify.json and the figure (PNG, PDF, "
        "NPZ); dimers also give the paper's fig:preis_dens (erf play N -> infinity next to the "
        "finite ensemble).",
    )
    p.add_argument("--model", choices=MODELS, default="dimers", help="operator (default dimers)")
    p.add_argument("--spins", type=int, default=20000, help="number of spins N (dimers)")
    p.add_argument("--seed", type=int, default=0, help="disorder seed (dimers)")
    p.add_argument("--width", type=float, default=2.0, help="loop width p (default 2)")
    p.add_argument("--spread", type=float, default=1.0, help="spread R of the centres (default 1)")
    p.add_argument("--spin-coupling", type=float, default=2.0, help="dimer coupling J (default 2)")
    p.add_argument("--step", type=float, default=0.1, help="grid step Delta (default 0.1)")
    p.add_argument(
        "--saturation",
        type=float,
        default=None,
        help="grid half-extent H (default 5R + p/2; for dimers at least the largest |threshold|)",
    )
    p.add_argument(
        "--smoothing",
        type=float,
        nargs="+",
        default=None,
        metavar="SF",
        help="smoothing factor SF, or SF_R SF_S (window half-widths across r and along s, in "
        "grid steps); models: none by default; --input: 3 by default",
    )
    p.add_argument("--input", default=None, help="FORC data file instead of a model")
    p.add_argument(
        "--format",
        choices=("auto", "csv", "micromag", "lakeshore"),
        default="auto",
        help="--input format (default: detected from the file)",
    )
    p.add_argument(
        "--reversible-ridge",
        action="store_true",
        help="--input: include the reversible ridge at Bc = 0 in the smoothed density (constant "
        "extension below the diagonal, exact for relay systems); default: irreversible only",
    )
    p.add_argument(
        "--drift-correction",
        choices=("none", "multiplicative", "additive"),
        default="none",
        help="--input: linear drift correction from the calibration points (default none)",
    )
    p.add_argument(
        "--window",
        choices=("rs", "pike"),
        default="rs",
        help="--input: smoothing window, |dr|,|ds| <= SF steps (rs, default) or Pike et al. "
        "(1999)'s square |dB|,|dB_r| <= SF steps (pike)",
    )
    p.add_argument(
        "--grid-step",
        type=float,
        default=None,
        help="--input: lattice step in the file's field unit after conversion (default: the "
        "median field step of the measurement)",
    )
    p.add_argument("--out", required=True, help="output directory")
    p.add_argument("--json", action="store_true", help="print the metrics as JSON on stdout")
    p.add_argument("--progress", action="store_true", help="progress bar over the curves")
    p.set_defaults(func=run)


def _build_operator(args: argparse.Namespace) -> tuple[Any, dict[str, Any]]:
    from hysteresis import play as play_mod

    if args.model == "dimers":
        from hysteresis.spin_dimers import SpinDimerEnsemble

        ens = SpinDimerEnsemble.random(
            args.spins, args.width, args.spread, args.spin_coupling, seed=args.seed
        )
        return ens, {"centres": ens.thresholds().centre, "thresholds": ens.thresholds()}
    if args.model == "erf-play":
        return play_mod.GeneralizedPlay.erf(args.width, args.spread), {}
    if args.model == "play":
        return play_mod.PlayOperator(args.width), {}
    # preisach-uniform: uniform density on the triangle beta <= alpha in [-H, H]^2
    from hysteresis.preisach import PreisachModel

    h = float(args.saturation or (5 * args.spread + 0.5 * args.width))
    return _uniform_preisach(PreisachModel, h), {}


def _uniform_preisach(model_cls: Any, half_extent: float) -> Any:
    area = 2.0 * half_extent**2  # triangle beta <= alpha inside [-H, H]^2

    def density(alpha, beta):
        import numpy as np

        a = np.asarray(alpha, dtype=float)
        b = np.asarray(beta, dtype=float)
        inside = (b <= a) & (a <= half_extent) & (b >= -half_extent)
        return np.where(inside, 1.0 / area, 0.0)

    return model_cls.from_density(density, -half_extent, half_extent)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from analysis.identification import compare_with_ridge, identify_preisach
    from analysis.preisach_plots import figure_preisach_density, figure_single_density
    from hysteresis.play import GeneralizedPlay

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    if args.smoothing is not None and len(args.smoothing) not in (1, 2):
        raise ValueError("--smoothing takes one factor SF or two, SF_R SF_S")
    if args.input:
        try:
            return _run_measured(args, out, t0)
        except (ValueError, OSError) as exc:
            # a user's file: one line naming the problem (and its line), not a traceback
            print(f"hyst identify: error: {args.input}: {exc}", file=sys.stderr)
            return 2
    smoothing = tuple(args.smoothing) if args.smoothing else None
    if smoothing is not None and len(smoothing) == 1:
        smoothing = (smoothing[0], smoothing[0])
    report: dict[str, Any] = {
        "width": args.width,
        "spread": args.spread,
    }
    if args.step <= 0 or not math.isfinite(args.step):
        raise ValueError(f"--step must be > 0, got {args.step}")
    operator, extra = _build_operator(args)
    saturation = args.saturation or (5 * args.spread + 0.5 * args.width)
    if args.model == "dimers" and args.saturation is None:
        th = extra["thresholds"]
        saturation = max(saturation, float(np.max(np.abs([th.alpha, th.beta]))))
    ident = identify_preisach(
        operator, args.step, saturation, smoothing=smoothing, progress=args.progress
    )
    report.update(
        model=args.model,
        step=args.step,
        saturation=saturation,
        grid_nodes=int(ident.alpha.size),
    )
    if args.model == "dimers":
        report.update(spins=args.spins, seed=args.seed, spin_coupling=args.spin_coupling)
    label = args.model
    # the paper's ridge metrics: only for the paper's models (dimers, erf play), never over
    # user data or other operators
    cmp = None
    if args.model in ("dimers", "erf-play"):
        cmp = compare_with_ridge(ident, args.width, args.spread, centres=extra.get("centres"))
        report.update(cmp.as_dict())
    else:
        report.pop("spread")
        report.update(
            total_mass=ident.total_mass,
            irreversible_mass=ident.irreversible_mass,
            reversible_mass=ident.reversible_mass,
        )
    report["mass_outside_grid"] = ident.mass_outside_grid
    report["smoothing"] = list(smoothing) if smoothing else None
    if args.model == "dimers":
        limit = identify_preisach(
            GeneralizedPlay.erf(args.width, args.spread),
            args.step,
            report["saturation"],
        )
        lim = compare_with_ridge(limit, args.width, args.spread)
        report["erf_play"] = lim.as_dict()
        paths = figure_preisach_density(
            limit,
            ident,
            args.width,
            args.spread,
            out,
            finite_label=f"N = {args.spins}",
            extra_data={"centres": extra["centres"]},
        )
    else:
        paths = figure_single_density(
            ident,
            out,
            f"identify_{label}".replace(".", "_"),
            title=f"Preisach density: {label}",
            smoothed=smoothing is not None,
            spread=args.spread if args.model in ("dimers", "erf-play") else None,
        )
    report["figures"] = [str(p) for p in paths]
    report["seconds"] = time.perf_counter() - t0
    text = json.dumps(_jsonable(report), indent=2, allow_nan=True)
    (out / "identify.json").write_text(text + "\n")
    if args.json:
        sys.stdout.write(text + "\n")
    elif cmp is None:
        print(
            f"total mass {ident.total_mass:.12g} (irreversible {ident.irreversible_mass:.6g}, "
            f"on the diagonal {ident.reversible_mass:.6g})"
        )
        print(f"wrote {out / 'identify.json'} and {', '.join(str(p) for p in paths)}")
    else:
        print(
            f"total mass {cmp.total_mass:.12g}, r centre {cmp.r_centre:.12g}, "
            f"mass within 2 cells of the ridge {cmp.r_mass_within_2_cells:.6g}, "
            f"s-CDF distance to the Gaussian {cmp.s_cdf_distance_gaussian:.3g}"
            + (
                f", to the empirical CDF {cmp.s_cdf_distance_empirical:.3g}"
                if cmp.s_cdf_distance_empirical is not None
                else ""
            )
        )
        print(f"wrote {out / 'identify.json'} and {', '.join(str(p) for p in paths)}")
    return 0


def _run_measured(args: argparse.Namespace, out: Path, t0: float) -> int:
    """Measured FORC data: data-driven summaries only (no paper overlay)."""
    import numpy as np

    from analysis.forc_io import detect_format, read_forc_file
    from analysis.identification import identify_from_curves
    from analysis.preisach_plots import figure_forc

    fmt = detect_format(args.input) if args.format == "auto" else args.format
    kwargs: dict[str, Any] = {}
    if fmt in ("micromag", "lakeshore") and args.drift_correction != "none":
        kwargs["drift_correction"] = args.drift_correction
    elif args.drift_correction != "none":
        raise ValueError(
            f"--drift-correction needs calibration points (MicroMag or Lake "
            f"Shore files), not {fmt!r}"
        )
    data = read_forc_file(args.input, fmt, **kwargs)
    sm = args.smoothing or [3.0]
    smoothing = (sm[0], sm[0]) if len(sm) == 1 else (sm[0], sm[1])
    ident = identify_from_curves(
        data.curves,
        smoothing=smoothing,
        output_range=(-math.inf, math.inf),
        extend=args.reversible_ridge,
        step=args.grid_step,
        window=args.window,
    )
    bc, bu, rho = ident.density_peak()
    step = ident.step if ident.step is not None else float(np.median(np.diff(ident.alpha)))
    report: dict[str, Any] = {
        "input": str(args.input),
        "format": fmt,
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
        "smoothing_factor": list(smoothing),
        "window": args.window,
        "reversible_ridge": args.reversible_ridge,
        "peak_bc_mT": bc,
        "peak_bu_mT": bu,
        "peak_rho": rho,
        "irreversible_mass": ident.irreversible_mass,
        "reversible_mass": ident.reversible_mass,
        "drift_correction": args.drift_correction,
    }
    stem = "identify_" + Path(args.input).stem.replace(".", "_")
    paths = figure_forc(
        ident,
        out,
        stem,
        title=f"{Path(args.input).name}: SF = {smoothing[0]:g}/{smoothing[1]:g}, Δ = {step:.3g} mT",
        field_unit="mT",
        moment_unit=data.moment_unit,
    )
    report["figures"] = [str(p) for p in paths]
    report["seconds"] = time.perf_counter() - t0
    text = json.dumps(_jsonable(report), indent=2, allow_nan=True)
    (out / "identify.json").write_text(text + "\n")
    if args.json:
        sys.stdout.write(text + "\n")
    else:
        print(
            f"{report['n_curves']} curves, {report['n_points']} points, grid step {step:.4g} mT; "
            f"FORC peak at Bc = {bc:.4g} mT, Bu = {bu:.4g} mT; irreversible mass "
            f"{ident.irreversible_mass:.4g}"
        )
        print(f"wrote {out / 'identify.json'} and {', '.join(str(p) for p in paths)}")
    return 0


def _jsonable(x: Any) -> Any:
    import numpy as np

    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
