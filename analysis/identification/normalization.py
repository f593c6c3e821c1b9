"""Normalisation of FORC moments by the sample's mass or volume (from the file header or given).

A FORC file's moments are in A·m² (after :mod:`analysis.identification.forc_io`'s unit
conversion). Dividing by the mass in kg gives A·m²/kg (the usual mass-normalised unit, ρ then in
A·m²/kg/T²); dividing by the volume in m³ gives A/m (the magnetisation, ρ in A/m/T²). The header
value must state its unit (``Mass  +1.25E+01 mg``): a bare number or ``N/A`` is refused with a
message that names the option to give it explicitly (``--mass``, ``--volume``), never guessed.
"""

from __future__ import annotations

import re

from analysis.identification._checks import positive_number

__all__ = ["NORMALIZATIONS", "sample_amount", "normalized_unit"]

NORMALIZATIONS = ("none", "mass", "volume")
#: unit of an amount in the header -> factor to SI (kg, m³)
UNITS = {
    "mass": {"kg": 1.0, "g": 1e-3, "mg": 1e-6, "µg": 1e-9, "ug": 1e-9},
    "volume": {
        "m³": 1.0,
        "m3": 1.0,
        "cm³": 1e-6,
        "cm3": 1e-6,
        "cc": 1e-6,
        "mm³": 1e-9,
        "mm3": 1e-9,
    },
}
_VALUE = re.compile(r"^\s*=?\s*([+\-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+\-]?\d+)?)\s*(\S*)\s*$")


def sample_amount(header: dict[str, str], kind: str, given: float | None = None) -> float:
    """The sample's mass in kg (``kind="mass"``) or volume in m³ (``"volume"``): ``given``
    (already in kg / m³) if not ``None``, else the header's ``Mass`` / ``Volume`` value with its
    unit. Raises a one-line ``ValueError`` when neither is usable."""
    if kind not in UNITS:
        raise ValueError(f"normalisation must be 'mass' or 'volume', got {kind!r}")
    option = f"--{kind}"
    if given is not None:
        return positive_number(given, kind)
    key = next((k for k in header if k.strip().lower() == kind), None)
    if key is None:
        raise ValueError(f"the file's header gives no {kind}; pass it with {option}")
    text = header[key].strip()
    match = _VALUE.match(text)
    if not match:
        raise ValueError(f"the file's header gives no {kind} ({key}: {text}); pass {option}")
    value, unit = float(match.group(1)), match.group(2)
    units = UNITS[kind]
    if unit not in units:
        raise ValueError(
            f"the header's {kind} {text!r} has no known unit ({', '.join(units)}); pass {option}"
        )
    return positive_number(value * units[unit], kind)


def normalized_unit(moment_unit: str | None, kind: str) -> str:
    """The moment unit after normalisation (``A·m²/kg``, ``A/m``)."""
    mu = moment_unit or "moment"
    if kind == "mass":
        return f"{mu}/kg"
    if kind == "volume":
        return "A/m" if mu == "A·m²" else f"{mu}/m³"
    return mu
