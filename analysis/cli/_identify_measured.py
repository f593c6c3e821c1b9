"""``hyst identify --input``: the words of ``--smoothing`` (a factor or two, ``variforc``,
``auto``), the unit of ρ, the uncertainty and colour options; and what the command says about
the data: the kind of curves (in-field or remanence FORC), the warnings about them and the major
loop's hysteresis parameters. Errors
are one line naming the option (:class:`~analysis.cli._parsing.CliError`); what the options
mean together is decided by :class:`~analysis.identification.request.IdentifyRequest`.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from analysis.cli._parsing import CliError, int_at_least, positive_float
from analysis.identification.curves import KIND_NAMES
from analysis.identification.major_loop import hysteresis_parameters
from analysis.identification.normalization import normalized_unit
from analysis.identification.plots import colormap_name
from analysis.identification.result import RIDGE_EXCLUSION_STEPS

__all__ = [
    "smoothing_words",
    "rho_unit",
    "curve_kind",
    "diagram_name",
    "data_warnings",
    "add_uncertainty_options",
    "hysteresis_report",
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
