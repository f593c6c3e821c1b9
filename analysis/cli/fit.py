"""``hyst fit``: fit a hysteresis model to an input/output record (a CSV file).

The record is read by :func:`~analysis.identification.record_io.read_record` (columns named
``input`` and ``output`` in the header, or ``--columns``) and fitted by
:mod:`analysis.identification.fitting`: ``bouc-wen`` and ``jiles-atherton`` by nonlinear least
squares from several starts (parameters with standard errors), ``pi`` (Prandtl–Ishlinskii,
``--plays`` widths evenly on ``(0, ptp(u)]`` and the linear term) and ``preisach`` (a discrete
Preisach model on ``--nodes`` thresholds evenly on ``[min u, max u]``) by constrained linear
least squares. The first ``--train-fraction`` of the record trains, the rest validates.
Writes ``OUT/fit.json`` (the record ``--json`` prints) and ``OUT/fit.png``/``fit.pdf`` (the
loop, data and model; the output against the sample index; the residuals).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np

from analysis.cli._options import add_output_options
from analysis.cli._output import emit, prepare_out, write_record
from analysis.cli._parsing import (
    CliError,
    Given,
    add_subcommand,
    given_options,
    int_at_least,
    library_errors,
)
from analysis.identification.differential_fits import MIN_SAMPLES
from analysis.identification.fitting import (
    fit_bouc_wen,
    fit_jiles_atherton,
    fit_prandtl_ishlinskii,
    fit_preisach_record,
)
from analysis.identification.record_io import read_record

__all__ = ["FIT_MODELS", "register", "run"]

#: the models ``hyst fit`` fits
FIT_MODELS = ("bouc-wen", "jiles-atherton", "pi", "preisach")

#: library parameter -> the option of this command that carries it
OPTIONS = {
    "u": "--input",
    "y": "--input",
    "H": "--input",
    "M": "--input",
    "columns": "--columns",
    "train_fraction": "--train-fraction",
    "n_starts": "--starts",
    "widths": "--plays",
    "nodes": "--nodes",
}


def _fraction(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number in (0, 1], got {text!r}") from None
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 1], got {text!r}")
    return value


def register(subparsers: Any) -> None:
    p = add_subcommand(
        subparsers,
        "fit",
        help="fit a hysteresis model (Bouc-Wen, Jiles-Atherton, PI, Preisach) to a CSV record",
        description="Read the input and output columns of --input and fit --model to them: "
        "bouc-wen (y = offset + z, z of BoucWen(A, beta, gamma, n), z = y[0] - offset at the "
        "first sample) and jiles-atherton (M of JilesAtherton(ms, a, k, c, alpha) for the field "
        "H, M_irr from the first sample) by nonlinear least squares from several starts; pi "
        "and preisach by constrained linear least squares. The first --train-fraction of the "
        "samples trains, the rest validates. Writes OUT/fit.json (parameters with standard "
        "errors, train and validation RMS) and OUT/fit.png, OUT/fit.pdf (data vs model, "
        "residuals).",
    )
    g = p.add_argument_group("fit")
    g.add_argument("--model", required=True, choices=FIT_MODELS, help="the model to fit")
    g.add_argument(
        "--input", type=Path, required=True, metavar="CSV", help="the record (a CSV file)"
    )
    g.add_argument(
        "--columns",
        nargs=2,
        metavar=("INPUT", "OUTPUT"),
        default=None,
        help="header names of the input and output columns (default: 'input' and 'output'); "
        "in a file without a header, their 1-based positions (default: 1 2)",
    )
    g.add_argument(
        "--train-fraction",
        type=_fraction,
        default=0.7,
        help="fraction (0, 1] of the record, from its start, that trains the fit",
    )
    g.add_argument(
        "--starts",
        type=int_at_least(1, 50),
        default=None,
        action=Given,
        help="bouc-wen, jiles-atherton: starts of the least-squares fit (default 3 and 4)",
    )
    g.add_argument(
        "--plays",
        type=int_at_least(1, 500),
        default=16,
        action=Given,
        help="pi: number of play widths, evenly on (0, ptp(u)] (plus the linear term)",
    )
    g.add_argument(
        "--nodes",
        type=int_at_least(2, 200),
        default=16,
        action=Given,
        help="preisach: thresholds evenly on [min u, max u] (a relay per lattice cell)",
    )
    add_output_options(p, writes="fit.json, fit.png and fit.pdf")
    p.set_defaults(func=run)


#: option (its dest) -> the models that read it
_READERS = {
    "starts": ("bouc-wen", "jiles-atherton"),
    "plays": ("pi",),
    "nodes": ("preisach",),
}


def run(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    given = given_options(args)
    for dest, models in _READERS.items():
        if dest in given and args.model not in models:
            raise CliError(
                f"argument --{dest}: only for --model {' or '.join(models)}, not {args.model}"
            )
    with library_errors(OPTIONS, "--input"):
        columns = None if args.columns is None else tuple(args.columns)
        record = read_record(args.input, columns, min_samples=MIN_SAMPLES)
    out = prepare_out(args)
    u, y = record.u, record.y
    with library_errors(OPTIONS, "--input"):
        fit = _fit(args, u, y)
    report: dict[str, Any] = {
        "model": args.model,
        "input": str(record.path),
        "columns": list(record.columns),
        "samples": int(u.size),
        "train_fraction": args.train_fraction,
        "n_train": fit.n_train,
        "n_validation": fit.n_validation,
        "train_rms": fit.train_rms,
        "validation_rms": fit.validation_rms,
        **_parameters(args.model, fit),
        "fit": dict(fit.info or {}),
    }
    paths = _figure(out, args, record, fit)
    report["figures"] = [str(p) for p in paths]
    report["seconds"] = time.perf_counter() - t0
    write_record(out, "fit.json", report)
    lines = [f"{args.model} fitted to {u.size} samples of {record.path}"]
    errors = report.get("standard_errors") or {}
    for name, value in (report.get("parameters") or {}).items():
        if isinstance(value, list):
            continue
        err = errors.get(name)
        lines.append(f"  {name} = {value:.6g}" + (f" +- {err:.2g}" if err is not None else ""))
    lines.append(
        f"  RMS train {fit.train_rms:.4g} ({fit.n_train} samples), validation "
        f"{fit.validation_rms:.4g} ({fit.n_validation} samples)"
    )
    lines.append(f"wrote {report['json']}, {', '.join(report['figures'])}")
    emit(args, report, lines)
    return 0


def _fit(args: argparse.Namespace, u: np.ndarray, y: np.ndarray) -> Any:
    tf = args.train_fraction
    if args.model == "bouc-wen":
        return fit_bouc_wen(u, y, train_fraction=tf, n_starts=args.starts or 3)
    if args.model == "jiles-atherton":
        return fit_jiles_atherton(u, y, train_fraction=tf, n_starts=args.starts or 4)
    span = float(np.ptp(u))
    if span == 0.0:
        raise ValueError("u must vary (a constant input identifies nothing)")
    if args.model == "pi":
        widths = span * np.arange(1, args.plays + 1) / args.plays
        return fit_prandtl_ishlinskii(u, y, widths, train_fraction=tf)
    nodes = np.linspace(float(u.min()), float(u.max()), args.nodes)
    return fit_preisach_record(u, y, nodes, train_fraction=tf)


def _parameters(model: str, fit: Any) -> dict[str, Any]:
    """``parameters`` and ``standard_errors`` of the report (a Preisach fit: its relays)."""
    if model == "preisach":
        m = fit.model
        return {
            "parameters": {"offset": fit.offset, "scale": fit.scale},
            "standard_errors": None,
            "relays": {
                "alpha": list(m.alpha),
                "beta": list(m.beta),
                "weights": list(m.weights),
            },
        }
    out: dict[str, Any] = {
        "parameters": dict(fit.parameters or {}),
        "standard_errors": None if fit.standard_errors is None else dict(fit.standard_errors),
    }
    if model == "pi":
        out["widths"] = list(fit.model.widths)
    return out


def _figure(out: Path, args: argparse.Namespace, record: Any, fit: Any) -> list[Path]:
    import matplotlib.pyplot as plt  # drawing only; the backend stays the caller's

    u, y = record.u, record.y
    pred = fit.predict(u)
    k = np.arange(u.size)
    n = fit.n_train
    fig, ax = plt.subplots(1, 3, figsize=(14, 4))
    ax[0].plot(u, y, ".", ms=2, color="0.6", label="data")
    ax[0].plot(u, pred, lw=0.8, color="tab:red", label="model")
    ax[0].set(xlabel=record.columns[0], ylabel=record.columns[1], title="loop")
    ax[0].legend(fontsize=8)
    ax[1].plot(k, y, ".", ms=2, color="0.6", label="data")
    ax[1].plot(k, pred, lw=0.8, color="tab:red", label="model")
    ax[1].set(xlabel="sample", ylabel=record.columns[1], title="record")
    ax[2].plot(k, y - pred, lw=0.6, color="tab:blue")
    ax[2].set(
        xlabel="sample",
        ylabel="data - model",
        title=f"residuals: RMS train {fit.train_rms:.3g}, validation {fit.validation_rms:.3g}",
    )
    for a in ax[1:]:
        if fit.n_validation:
            a.axvline(n - 0.5, color="k", lw=0.6, ls=":")
    fig.suptitle(f"hyst fit --model {args.model}: {record.path}", fontsize=10)
    fig.tight_layout()
    paths = [out / "fit.png", out / "fit.pdf"]
    fig.savefig(paths[0], dpi=130)
    fig.savefig(paths[1])
    plt.close(fig)
    return paths
