"""Files that are not (valid) FORC exports, built from the shipped samples (issue 21): binary or
compressed content, text that is no FORC format, absurd values, rows out of measurement order.
Each is refused in one line, by the library reader and by ``hyst identify`` (exit status 2,
one line on stderr); UTF-16 text with a byte-order mark reads like the original."""

from __future__ import annotations

import bz2
import gzip
import io
import os
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from support_paths import DATA, ROOT

from analysis.identification.forc_io import detect_format, read_forc_file

MICROMAG = DATA / "forc_micromag_0015_cgs.frc"
LAKESHORE = DATA / "forc_lakeshore_8600.csv"
CSV = DATA / "forc_erf_play_mayergoyz.csv"
KNOWN = (
    "not a FORC file this toolkit recognises; it reads MicroMag 2900/3900 FORC text export "
    "(line 1 starts with 'MicroMag'), Lake Shore 8600 FORC CSV (a column-title row naming a "
    "field and a moment column with units, then data rows), three-column CSV "
    "'reversal_field,field,moment' or a data-only file (two columns field,moment, a blank line "
    "after every curve)"
)


def _zip(raw: bytes) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("forc.frc", raw)
    return buf.getvalue()


def _data_index(lines: list[str], start: str) -> int:
    return next(i for i, line in enumerate(lines) if line.startswith(start))


def _cli_error(capsys, path: Path, tmp_path: Path) -> str:
    from analysis.cli import main

    code = main(["identify", "--input", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert not (tmp_path / "out").exists()
    return err.strip()


def _refused(path: Path, message: str, capsys, tmp_path: Path) -> None:
    """The library and the CLI give the same one line ``message`` (which names the line or
    starts with the path)."""
    with pytest.raises(ValueError) as info:
        read_forc_file(path)
    assert str(info.value) == message
    err = _cli_error(capsys, path, tmp_path)
    body = message if message.startswith(f"{path}: ") else f"{path}: {message}"
    assert err == f"hyst identify: error: argument --input: {body}"


# -- 1: binary, compressed, UTF-16 ----------------------------------------------------------------
BINARY = [
    ("gzip", lambda raw: gzip.compress(raw), "gzip-compressed data; decompress it first"),
    ("bzip2", lambda raw: bz2.compress(raw), "bzip2-compressed data; decompress it first"),
    (
        "zip",
        _zip,
        "a zip archive or Office document; extract or export the FORC text file",
    ),
    ("png", lambda raw: b"\x89PNG\r\n\x1a\n" + raw, "a PNG image"),
    ("pdf", lambda raw: b"%PDF-1.7\n" + raw, "a PDF document"),
    (
        "utf16-no-bom",
        lambda raw: raw.decode("ascii").encode("utf-16-le"),
        "UTF-16 text without a byte-order mark; save it as UTF-8",
    ),
    (
        "nul-bytes",
        lambda raw: raw[:500] + b"\x00" * 64 + raw[500:],
        "binary data: NUL byte at offset 500",
    ),
    (
        "random-bytes",
        lambda raw: np.random.default_rng(0).integers(1, 256, 4096, dtype=np.uint8).tobytes(),
        None,
    ),
]


@pytest.mark.parametrize("name, mutate, what", BINARY, ids=[b[0] for b in BINARY])
def test_binary_input_is_not_a_text_forc_file(name, mutate, what, tmp_path, capsys):
    path = tmp_path / f"{name}.frc"
    raw = mutate(MICROMAG.read_bytes())
    path.write_bytes(raw)
    if what is None:  # random bytes: NUL-free, not UTF-8, half the bytes non-ASCII
        share = 100 * sum(b >= 0x80 for b in raw) / len(raw)
        what = f"binary data: not UTF-8 and {share:.0f} % non-ASCII bytes"
    _refused(path, f"{path}: not a text FORC file ({what})", capsys, tmp_path)


@pytest.mark.parametrize("sample", [MICROMAG, LAKESHORE, CSV], ids=lambda p: p.suffix)
@pytest.mark.parametrize("codec", ["utf-16", "utf-16-be", "utf-32"])
def test_utf16_and_utf32_with_a_bom_read_like_the_original(sample, codec, tmp_path):
    # decoded, not refused: the byte-order mark makes the encoding certain
    path = tmp_path / ("bom" + sample.suffix)
    text = sample.read_bytes().decode("utf-8")
    path.write_bytes((("\ufeff" if codec.endswith("-be") else "") + text).encode(codec))
    assert path.read_bytes()[:2] in (b"\xff\xfe", b"\xfe\xff")
    assert detect_format(path) == detect_format(sample)
    got, want = read_forc_file(path).curves, read_forc_file(sample).curves
    np.testing.assert_array_equal(got.reversal_field, want.reversal_field)
    for a, b in zip(got.moments + got.fields, want.moments + want.fields, strict=True):
        np.testing.assert_array_equal(a, b)


# -- 2: text that is no FORC export ---------------------------------------------------------------
@pytest.mark.parametrize(
    "source", [ROOT / "README.md", DATA / "make_forc_data.py"], ids=["md", "py"]
)
def test_text_that_is_no_forc_file_names_the_known_formats(source, tmp_path, capsys):
    path = tmp_path / source.name
    path.write_bytes(source.read_bytes())
    _refused(path, f"{path}: {KNOWN}", capsys, tmp_path)


def test_a_lakeshore_title_in_prose_is_not_a_title_row(tmp_path, capsys):
    # one cell naming both a field and a moment (README prose) is not a column-title row
    path = tmp_path / "notes.txt"
    path.write_text("Notes\nthe moment (emu) against the field (Oe) was measured\nthat is all\n")
    _refused(path, f"{path}: {KNOWN}", capsys, tmp_path)


# -- 3: absurd values ------------------------------------------------------------------------------
def test_absurd_moment_is_refused_with_its_line(tmp_path, capsys):
    lines = MICROMAG.read_text().splitlines()
    k = _data_index(lines, "+2.197935E+02")
    lines[k] = "+2.197935E+02,+1.0E+300"
    path = tmp_path / "huge.frc"
    path.write_text("\n".join(lines) + "\n")
    _refused(
        path, f"line {k + 1}: moment 1e+300 is absurd: beyond 1e+30 in magnitude", capsys, tmp_path
    )


def test_exponent_typo_is_refused_against_the_spread_of_the_file(tmp_path, capsys):
    # Lake Shore, moment E-06 typed E+06: 10¹² times the file's spread, below 1e30
    lines = LAKESHORE.read_text().splitlines()
    k = _data_index(lines, "0.200,")
    lines[k] = "0.200,2.19793468E-02,4.50751979E+06"
    path = tmp_path / "typo.csv"
    path.write_text("\n".join(lines) + "\n")
    msg = (
        f"line {k + 1}: moment 4.50752e+06 is absurd: more than 1e+06 times the spread "
        "(7.05e-06) of the file's moments from their median (4.52e-06)"
    )
    _refused(path, msg, capsys, tmp_path)
    # a field of the three-column CSV
    lines = CSV.read_text().splitlines()
    lines[5] = "-5.0,-5.5e9,-0.9999999980268247"
    path = tmp_path / "field.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"^line 6: field -5\.5e\+09 is absurd: more than 1e\+06 "):
        read_forc_file(path)


# -- 4: rows out of measurement order (Lake Shore) -------------------------------------------------
def test_lakeshore_rows_out_of_time_order(tmp_path, capsys):
    lines = LAKESHORE.read_text().splitlines()
    k = _data_index(lines, "0.500,")
    lines[k], lines[k + 1] = lines[k + 1], lines[k]  # two rows swapped
    path = tmp_path / "swapped.csv"
    path.write_text("\n".join(lines) + "\n")
    msg = (
        f"line {k + 2}: time stamp 0.500 is earlier than 0.600 on line {k + 1}: rows out of "
        "measurement order (sort them by the time stamp)"
    )
    _refused(path, msg, capsys, tmp_path)
    # the whole file reversed: the first data row already steps back in time
    path.write_text("\n".join(lines[:4] + lines[4:][::-1]) + "\n")
    with pytest.raises(ValueError, match=r"^line 6: time stamp .* rows out of measurement order"):
        read_forc_file(path)


def test_lakeshore_rows_out_of_order_without_time_stamps(tmp_path, capsys):
    rows = [line.split(",", 1)[1] for line in LAKESHORE.read_text().splitlines()[3:]]
    head = LAKESHORE.read_text().splitlines()[:3]
    k = rows.index("2.19793468E-02,4.50751979E-06")
    swapped = list(rows)
    swapped[k], swapped[k + 1] = swapped[k + 1], swapped[k]  # one curve: 20, 24, 22, 26 mT ...
    path = tmp_path / "notime.csv"
    path.write_text("\n".join(head + swapped) + "\n")
    # the curve splits at the fall 24 -> 22 mT; its second piece steps back against the trend
    msg = (
        f"line {k + 5}: a curve starts at 21.9793 mT after the curve at 19.9739 mT (line 6), "
        "but the reversal fields fall from curve to curve: rows out of measurement order"
    )
    _refused(path, msg, capsys, tmp_path)
    # valid without time stamps: same curves as with them
    path.write_text("\n".join(head + rows) + "\n")
    assert read_forc_file(path).curves.n_curves == read_forc_file(LAKESHORE).curves.n_curves
    # reversed: every row its own "curve" before; now the first step back is named
    path.write_text("\n".join(head + [rows[0]] + rows[1:][::-1]) + "\n")
    with pytest.raises(
        ValueError, match=r"^line \d+: a curve starts at .* rows out of measurement"
    ):
        read_forc_file(path)


def test_one_line_exit_2_from_the_real_process(tmp_path):
    """``python -m analysis.cli identify --input FILE``: one file per finding of issue 21."""
    lines = LAKESHORE.read_text().splitlines()
    k = _data_index(lines, "0.500,")
    lines[k], lines[k + 1] = lines[k + 1], lines[k]
    huge = MICROMAG.read_text().splitlines()
    j = _data_index(huge, "+2.197935E+02")
    huge[j] = "+2.197935E+02,+1.0E+300"
    files = {
        "gz.frc": (gzip.compress(MICROMAG.read_bytes()), "not a text FORC file (gzip"),
        "README.md": ((ROOT / "README.md").read_bytes(), "not a FORC file this toolkit"),
        "huge.frc": ("\n".join(huge).encode(), f"line {j + 1}: moment 1e+300 is absurd"),
        "order.csv": ("\n".join(lines).encode("utf-8"), f"line {k + 2}: time stamp 0.500"),
    }
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    )
    for name, (raw, needle) in files.items():
        (tmp_path / name).write_bytes(raw)
        proc = subprocess.run(
            [sys.executable, "-m", "analysis.cli", "identify", "--input", name, "--out", "o"],
            capture_output=True,
            text=True,
            timeout=120,
            cwd=tmp_path,
            env=env,
        )
        err = proc.stderr.strip().splitlines()
        assert proc.returncode == 2 and len(err) == 1, proc.stderr
        assert re.match(rf"hyst identify: error: argument --input: {re.escape(name)}: ", err[0])
        assert needle in err[0], err[0]
        assert not (tmp_path / "o").exists()
