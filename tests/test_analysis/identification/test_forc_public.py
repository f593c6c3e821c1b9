"""Real instrument FORC exports (tests/data/forc_public/, provenance in its README.md) read as
written: each one was refused before (a Lake Shore header line taken for the column titles, a
remanence script whose ramps measure their ends, a data-only file with a units header and an
end marker). The curves are checked against the file's own text, parsed here independently:
the segment numbers, the script, the header's protocol, and, for the data-only layout, the same
measurement read with its script."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from support_paths import DATA

from analysis.cli import main
from analysis.identification.forc_io import detect_format, read_forc_file

PUBLIC = DATA / "forc_public"
LAKESHORE = PUBLIC / "B-9-3-85-87-FORC-1.5T_excerpt.csv"
REMANENCE = PUBLIC / "MSM33-60-1-d416_2.remforc"
IRREGULAR = PUBLIC / "MSM33-60-1-d416_2.irforc"
DATA_ONLY = PUBLIC / "ps97-085-3-d472_9.irforc"


def _lakeshore_rows() -> tuple[dict[str, str], list[tuple[int, float, float]]]:
    """Header ``key: value`` pairs and the rows ``(segment, field T, moment A·m²)``."""
    text = LAKESHORE.read_bytes().decode("latin-1").splitlines()
    title = next(i for i, line in enumerate(text) if line.startswith("Step,Iteration,Segment"))
    header = dict(
        line.split(": ", 1) for line in text[:title] if ": " in line and not line.startswith("#")
    )
    rows = [r for r in csv.reader(text[title + 1 :]) if r]
    return header, [(int(r[2]), float(r[3]), float(r[4])) for r in rows]


def test_lakeshore_8600_export_reads_by_its_segments():
    # before: "line 12: cannot tell the unit of the field column 'Moment X calibration field:
    # 0.5 T'" (a header line naming a moment and a field was taken for the column titles)
    assert detect_format(LAKESHORE) == "lakeshore"
    data = read_forc_file(LAKESHORE)
    header, rows = _lakeshore_rows()
    segments: dict[int, list[tuple[float, float]]] = {}
    for seg, h, m in rows:
        segments.setdefault(seg, []).append((h, m))
    # the export alternates a calibration point (even segment) and a curve (odd segment)
    curves = [segments[s] for s in sorted(segments) if s % 2 == 1]
    cals = [segments[s] for s in sorted(segments) if s % 2 == 0]
    c = data.curves
    assert data.field_unit == "mT" and data.moment_unit == "A·m²"
    assert c.convention == "pike" and c.n_curves == len(curves) == 28
    for k, seg in enumerate(curves):
        np.testing.assert_array_equal(c.fields[k], [1e3 * h for h, _ in seg])  # T -> mT
        np.testing.assert_array_equal(c.moments[k], [m for _, m in seg])
    assert all(len(s) == 1 for s in cals)
    np.testing.assert_array_equal(data.calibration_moments, [s[0][1] for s in cals])
    assert data.calibration_field == pytest.approx(1e3 * cals[0][0][0])
    # the header's protocol: 251 FORCs (this excerpt holds 28), reversal fields 1.6 mT apart
    # from Max Hu = 100 mT down, every point inside Hc <= 200 mT, Hu <= 100 mT (one step of
    # slack for the measured fields)
    assert header["Number of FORCs"] == "251" and header["Field step size"] == "1.6 mT"
    assert not data.complete and "28 of the 251 FORCs" in data.notes[0]
    np.testing.assert_allclose(c.reversal_field[:20], 100.0 - 1.6 * np.arange(20), atol=0.1)
    step = 1.6
    for h in c.fields:
        hc, hu = (h - h[0]) / 2, (h + h[0]) / 2
        assert hc.max() <= 200.0 + step and hu.max() <= 100.0 + step
    assert c.reversal_field.min() == pytest.approx(-100.0 - 200.0, abs=step)
    # the curves reaching the top of the protocol (Hu = 100, Hc = 200: 300 mT) stop below the
    # calibration point measured after them (it is no point of theirs)
    assert max(h.max() for h in c.fields) < data.calibration_field


def _script_and_data(path):
    """The SCRIPT rows ``(initial, increment, final, final index)`` in T and the data rows
    ``(field T, moment A·m²)`` of a "Multiple segments" export."""
    text = path.read_bytes().decode("latin-1").splitlines()
    script, data = [], []
    for line in text:
        cells = line.strip().split(",")
        if len(cells) == 7 and cells[0].isdigit():
            script.append((float(cells[2]), float(cells[3]), float(cells[4]), int(cells[6])))
        elif len(cells) == 2:
            data.append((float(cells[0]), float(cells[1])))
    return script, data


def test_remanence_script_with_measuring_ramps():
    # before: "line 75: a remanence FORC script measures one point per segment ...; this
    # segment measures 2" (the instrument's ramps 0 -> B -> 0 measure both their ends)
    assert detect_format(REMANENCE) == "segments"
    data = read_forc_file(REMANENCE)
    script, points = _script_and_data(REMANENCE)
    assert len(script) == 1982 and len(points) == script[-1][3] == 3921  # the header's counts
    c = data.curves
    assert c.kind == "remanence" and data.in_field_curves.kind == "in-field"
    assert data.field_unit == "mT" and data.moment_unit == "A·m²"  # Hybrid SI: T, A·m²
    # one curve after every single-point segment at zero field (the calibration point after
    # each saturating excursion) that more measurements follow; its reversal field is the
    # target of the first ramp after it
    singles = [k for k, s in enumerate(script) if s[1] == 0.0 and s[0] == s[2] == 0.0]
    starts = [script[k + 1][2] for k in singles if k + 1 < len(script)]
    assert c.n_curves == len(starts) == 40 and data.calibration_moments.size == len(singles)
    # the measured fields sit 1.4 % above the commanded ones (the magnet's calibration)
    np.testing.assert_allclose(c.reversal_field, 1e3 * np.array(starts), rtol=0.02, atol=0.5)
    assert c.reversal_field[-1] < -155.0  # the last curve starts at negative saturation
    # every curve rises to the saturating field of the script (157.766 mT commanded)
    top = max(s[2] for s in script)
    np.testing.assert_allclose([h[-1] for h in c.fields], 1e3 * top, rtol=0.02)
    # the first point of the first curve, by hand: segment 7 (0 -> B_a) ends and segment 8
    # (B_a -> 0) starts at B_a (data points 11 and 12, 1-based), segment 8 ends and segment 9
    # starts back at zero field (points 13 and 14): averaged, as for in-field scripts
    assert script[6][2] == script[7][0] == pytest.approx(0.131906)
    assert c.fields[0][0] == pytest.approx(1e3 * (points[10][0] + points[11][0]) / 2)
    assert data.in_field_curves.moments[0][0] == pytest.approx((points[10][1] + points[11][1]) / 2)
    assert c.moments[0][0] == pytest.approx((points[12][1] + points[13][1]) / 2)
    assert abs(points[12][0]) < 1e-3 and abs(points[13][0]) < 1e-3  # at zero field
    assert data.calibration_field == 0.0 and np.all(np.abs(data.calibration_fields) < 1.0)


def _blocks(path):
    """Blank-line separated blocks of ``field, moment`` rows (T, A·m²) of a data section."""
    blocks, current = [], None
    for line in path.read_bytes().decode("latin-1").splitlines():
        cells = line.strip().split(",")
        if len(cells) != 2:
            current = None
            continue
        if current is None:
            current = []
            blocks.append(current)
        current.append((float(cells[0]), float(cells[1])))
    return blocks


def test_data_only_irregular_file_with_units_header_and_end_marker():
    # before: "not a FORC file this toolkit recognises" (two title lines, an end marker)
    assert detect_format(DATA_ONLY) == "blocks"
    data = read_forc_file(DATA_ONLY)
    assert data.field_unit == "mT" and data.moment_unit == "A·m²"  # from "(T)  (Am²)"
    blocks = _blocks(DATA_ONLY)
    top = max(b[0][0] for b in blocks if len(b) == 1)
    cal = [b for b in blocks if len(b) == 1 and abs(b[0][0] - top) < 1e-3]
    reversal = [k for k, b in enumerate(blocks) if len(b) == 1 and b not in cal]
    c = data.curves
    assert c.n_curves == len(reversal) == 40 and data.calibration_moments.size == len(cal) == 40
    # a reversal point is measured again as the first point of the segment after it, and once
    # more by any segment that starts within 0.1 % of the largest field (a commanded step
    # shorter than that): the points of one field are averaged
    tol = 1e-3 * max(abs(h) for b in blocks for h, _ in b)
    for k, b in enumerate(reversal):
        group = [blocks[b][0], blocks[b + 1][0]]
        rest = [p for block in blocks[b + 1 :] for p in block][1:]
        while abs(rest[0][0] - group[-1][0]) <= tol:
            group.append(rest.pop(0))
        assert c.reversal_field[k] == pytest.approx(1e3 * np.mean([h for h, _ in group]))
        assert c.moments[k][0] == pytest.approx(np.mean([m for _, m in group]))
        assert c.fields[k][1] == pytest.approx(1e3 * rest[0][0], abs=1e3 * tol)
    # the curves end where the segments end, at the top field of the protocol
    assert max(h.max() for h in c.fields) == pytest.approx(1e3 * blocks[-1][-1][0])
    assert c.reversal_field.min() == c.reversal_field[-1] < -330.0  # the last: -330.7, -330.0


def test_data_section_alone_gives_the_curves_of_its_script(tmp_path):
    """The same irregular measurement read twice: the full export through its script (commanded
    fields) and its data section alone (blocks joined by their shared end points)."""
    raw = IRREGULAR.read_bytes().split(b"\n")
    title = max(i for i, line in enumerate(raw) if line.strip() == b"Field         Moment")
    section = tmp_path / "data_section.txt"
    section.write_bytes(b"\n".join(raw[title:]))
    assert detect_format(IRREGULAR) == "segments" and detect_format(section) == "blocks"
    a, b = read_forc_file(IRREGULAR), read_forc_file(section)
    assert a.curves.n_curves == b.curves.n_curves == 40
    for name in ("fields", "moments"):
        for x, y in zip(getattr(a.curves, name), getattr(b.curves, name), strict=True):
            np.testing.assert_allclose(x, y, rtol=1e-12)  # T -> mT before or after averaging
    np.testing.assert_allclose(a.calibration_moments, b.calibration_moments, rtol=1e-12)


def test_data_only_units_and_column_titles_are_checked(tmp_path):
    lines = DATA_ONLY.read_bytes().split(b"\r\n")
    bad = tmp_path / "furlongs.txt"
    bad.write_bytes(b"\r\n".join([lines[0], b"     (furlong)          (Am\xb2)", *lines[2:]]))
    with pytest.raises(ValueError, match=r"^line 2: cannot tell the units \(furlong\)"):
        read_forc_file(bad)
    with pytest.raises(ValueError, match="columns='moment,field', but the column titles name"):
        read_forc_file(DATA_ONLY, columns="moment,field")


@pytest.mark.parametrize(
    "path, fmt, n_curves, kind",
    [
        (LAKESHORE, "lakeshore", 28, "FORC"),
        (REMANENCE, "segments", 40, "remanence FORC"),
        (DATA_ONLY, "blocks", 40, "FORC"),
    ],
    ids=["lakeshore", "remanence", "data-only"],
)
def test_cli_identifies_each_real_export(tmp_path, path, fmt, n_curves, kind, capsys):
    out = tmp_path / "out"
    argv = ["identify", "--input", str(path), "--smoothing", "3", "--json", "--out", str(out)]
    assert main(argv) == 0
    report = json.loads(capsys.readouterr().out)
    assert (report["format"], report["n_curves"], report["curve_kind"]) == (fmt, n_curves, kind)
    assert report["field_unit"] == "mT" and report["moment_unit"] == "A·m²"
    assert (out / "identify.json").exists()
