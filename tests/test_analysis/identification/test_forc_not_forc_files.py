"""Measurement files that are not FORCs (MicroMag remanence-curve and hysteresis-loop exports,
Lake Shore loop and remanence-curve exports, a binary file, an empty file) are refused in one
line that says what the file is not, by the reader and by ``hyst identify`` (exit status 2)."""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np
import pytest
from support_paths import DATA

from analysis.cli import main
from analysis.identification.forc_io import read_forc_file

H = np.linspace(0.5, -0.5, 21)
LOOP_H = np.concatenate([H, -H[1:]])  # T: from +0.5 down to −0.5 and back
LOOP_M = 1e-6 * np.tanh(LOOP_H / 0.1)
DCD_H = np.linspace(0.0, -0.5, 26)  # backfield remanence: each field applied, then removed
DCD_M = 1e-6 * np.tanh((DCD_H + 0.05) / 0.1)


def _micromag(title: str) -> str:
    head = [
        "MicroMag 2900/3900 Data File (Series 0016.002)",
        title,
        "11/23/2015  09:41",
        "",
        "INSTRUMENT",
        "Units of measure                Hybrid SI",
        "",
        "      Field         Moment",
        "       (T)          (Am²)",
        "",
    ]
    rows = [f"{h:+.6E},{m:+.6E}" for h, m in zip(LOOP_H, LOOP_M, strict=True)]
    return "\r\n".join([*head, *rows, "MicroMag 2900/3900 Data File ends"]) + "\r\n"


def _lakeshore(title: str, h: np.ndarray, m: np.ndarray) -> str:
    rows = [f"Lake Shore 8600 Series VSM,{title}", "Sample,synthetic"]
    rows.append("Time Stamp [s],Field (µ0H) [T],Moment (m) [A·m²]")
    rows += [f"{0.1 * k:.3f},{a:.8E},{b:.8E}" for k, (a, b) in enumerate(zip(h, m, strict=True))]
    return "\n".join(rows) + "\n"


LAKESHORE_NOT = (
    "not a FORC measurement: the field rises over two or more points on {n} stretch{es} only (a "
    "hysteresis loop, a remanence curve or a single sweep; FORCs rise once from every reversal "
    "field)"
)
CASES = [
    (
        "micromag-loop.frc",
        _micromag("Direct moment vs. field; Hysteresis loop").encode("utf-8"),
        "line 2: MicroMag hysteresis-loop export is not supported; export the measurement as "
        "'First-order reversal curves'",
    ),
    (
        "micromag-irm-dcd.frc",
        _micromag("Remanence curves; IRM/DCD").encode("utf-8"),
        "line 2: MicroMag remanence-curve export is not supported; export the measurement as "
        "'First-order reversal curves'",
    ),
    (
        "lakeshore-loop.csv",
        _lakeshore("Hysteresis loop", LOOP_H, LOOP_M).encode("utf-8"),
        "{path}: " + LAKESHORE_NOT.format(n=1, es=""),
    ),
    (
        "lakeshore-dcd.csv",
        _lakeshore("DCD remanence", DCD_H, DCD_M).encode("utf-8"),
        "{path}: " + LAKESHORE_NOT.format(n=0, es="es"),
    ),
    (
        "remanence-forc.frc.gz",
        gzip.compress((DATA / "forc_micromag_remanence.frc").read_bytes()),
        "{path}: not a text FORC file (gzip-compressed data; decompress it first)",
    ),
    ("empty.frc", b"", "{path}: an empty file (no text), not a FORC file"),
    ("blank.frc", b"\r\n  \r\n\t\n", "{path}: an empty file (no text), not a FORC file"),
]


@pytest.mark.parametrize("name, raw, message", CASES, ids=[c[0] for c in CASES])
def test_not_a_forc_file_is_refused_in_one_line(name, raw, message, tmp_path, capsys):
    path: Path = tmp_path / name
    path.write_bytes(raw)
    message = message.format(path=path)
    with pytest.raises(ValueError) as info:
        read_forc_file(path)
    assert str(info.value) == message
    code = main(["identify", "--input", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    body = message if message.startswith(f"{path}: ") else f"{path}: {message}"
    assert code == 2 and err == f"hyst identify: error: argument --input: {body}\n"
    assert not (tmp_path / "out").exists()
