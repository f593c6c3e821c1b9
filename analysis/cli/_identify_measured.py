"""What ``hyst identify --input`` makes of its smoothing and unit options: the smoothing law
(a factor, VARIFORC with its parameters, or ``auto``), the normalisation's divisor, the unit
of ρ, and the uncertainty and colour options; and what it says about the data: the kind of
curves (in-field or remanence FORC) and the warnings about them. Errors are one line naming
the option (:class:`~analysis.cli._parsing.CliError`).
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from analysis.cli._parsing import CliError, int_at_least, positive_float
from analysis.identification.curves import KIND_NAMES
from analysis.identification.normalization import normalized_unit, sample_amount
from analysis.identification.plots import colormap_name
from analysis.identification.variforc import VariforcParameters

__all__ = [
    "VARIFORC_OPTIONS",
    "smoothing_option",
    "amount_option",
    "rho_unit",
    "curve_kind",
    "diagram_name",
    "data_warnings",
    "add_uncertainty_options",
]

VARIFORC_OPTIONS = ("sc0", "sc1", "sb0", "sb1", "lam")


def smoothing_option(
    args: argparse.Namespace, default: float | None
) -> tuple[float, float] | VariforcParameters | None:
    """``--smoothing`` (and the VARIFORC options) as the library takes it."""
    sm = args.smoothing
    given = [n for n in VARIFORC_OPTIONS if getattr(args, n, None) is not None]
    if sm == ["auto"]:
        if given:
            option = "--lambda" if given[0] == "lam" else f"--{given[0]}"
            raise CliError(f"argument {option}: only with --smoothing variforc (auto chooses)")
        return "auto"  # type: ignore[return-value]
    if sm is not None and len(sm) == 1 and sm[0] == "variforc":
        kw = {n: getattr(args, n) for n in given}
        try:
            return VariforcParameters(**kw)
        except ValueError as exc:
            name = str(exc).split()[0]
            option = "--lambda" if name == "lambda" else f"--{name}"
            raise CliError(f"argument {option}: {exc}") from exc
    if given:
        option = "--lambda" if given[0] == "lam" else f"--{given[0]}"
        raise CliError(f"argument {option}: only with --smoothing variforc")
    if sm is None:
        return None if default is None else (default, default)
    if len(sm) not in (1, 2):
        raise CliError(
            f"argument --smoothing: takes one factor SF or two, SF_R SF_S, or 'variforc'; got "
            f"{len(sm)} values"
        )
    try:
        values = [positive_float(x) for x in sm]
    except (argparse.ArgumentTypeError, ValueError) as exc:
        raise CliError(f"argument --smoothing: {exc} (or 'variforc', 'auto')") from exc
    return (values[0], values[0]) if len(values) == 1 else (values[0], values[1])


def amount_option(args: argparse.Namespace, data: Any) -> float:
    """The divisor of ``--normalize`` (1 for none), checked before any output is written."""
    for option, kind in (("--mass", "mass"), ("--volume", "volume")):
        if getattr(args, kind) is not None and args.normalize != kind:
            raise CliError(f"argument {option}: only with --normalize {kind}")
    if args.normalize == "none":
        return 1.0
    if data.moment_unit is None:
        raise CliError(
            f"argument --normalize: {args.input}: the file states no moment unit, so the "
            "normalised unit would be unknown"
        )
    try:
        return sample_amount(data.header, args.normalize, getattr(args, args.normalize))
    except ValueError as exc:
        raise CliError(f"argument --normalize: {args.input}: {exc}") from exc


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
    region its masses and diagram cover) and a negative irreversible mass."""
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
        default=200,
        metavar="N",
        help="--uncertainty: replicates of the peak's parametric bootstrap (>= 20; default 200)",
    )
    g.add_argument(
        "--bootstrap-seed",
        type=int_at_least(0),
        default=0,
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
