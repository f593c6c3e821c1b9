"""Regenerate the small synthetic FORC files of tests/data with the toolkit's own operators.

    python tests/data/make_forc_data.py

* ``forc_erf_play_mayergoyz.csv``: the paper's erf play (p = 2, R = 1), Mayergoyz curves on the
  regular grid step 0.5, saturation 6 (25 curves).
* ``forc_erf_play_pike.micromag``: the same operator, Pike curves (from positive saturation 6)
  on an irregular lattice shared by reversal fields and fields, with a calibration point at
  HCal = 6 before every curve (MicroMag text format).

Instrument-style exports of a synthetic *sample* (:func:`sample`: 20 000 relays with coercivity
``B_c ~ N(30, 6²)`` mT and interaction field ``B_u ~ N(0, 5²)`` mT, plus a reversible part
``0.15 tanh(B/60 mT)``, moment scale 5·10⁻⁶ A·m²), measured like an instrument does
(:func:`measure`): regular protocol of step 2 mT, measured fields jittered by 0.05 mT,
calibration point at HCal (its field drifting by up to 2 mT) before every curve, moment noise
0.1 % of the saturation moment, and a slow multiplicative drift of the instrument gain. Layouts
follow the MicroMag and Lake Shore file descriptions (see :mod:`analysis.identification.forc_io`):

* ``forc_micromag_0015_cgs.frc``: Series 0015 header (short keys ``NForc``, ``NData``,
  ``HCal``, ``HSat`` with ``=``), ``Units of measure = cgs`` (Oe, emu), LF line ends.
* ``forc_micromag_0016_hybrid_si.frc``: Series 0016 header (date/time line after the title,
  sections, long keys ``Number of FORCs`` …), ``Hybrid SI`` (T, A·m²), cp1252 text with
  ``Am²``, ``µ``, ``°`` in unit lines, CRLF line ends, column-title lines, end marker.
* ``forc_micromag_0016_si_aborted.frc``: Series 0016, ``SI``, measurement aborted in the middle
  of a curve (fewer curves and points than announced, no end marker).
* ``forc_micromag_irregular.frc``: a "Direct moment vs. field; Multiple segments" export
  (refused by the reader).
* ``forc_micromag_segments.frc`` and ``forc_micromag_segments_regular.frc``: one irregular
  FORC protocol (reversal fields and fields on the irregular lattice of
  :func:`irregular_nodes`, 30 curves) of a known discrete Preisach model (:func:`segments_model`:
  3000 relays, seeded), written as a "Direct moment vs. field; Multiple segments" export (the
  segment script, every inner field measured twice) and as a regular MicroMag FORC file.
* ``forc_micromag_remanence.frc``: a remanence FORC protocol (every field point followed by a
  point measured back at zero field) of a known discrete Preisach model
  (:func:`remanence_model`: 400 relays, seeded) on the regular lattice ``0.75·k``,
  ``k = −8 … 8`` (16 curves), written as a "Multiple segments" export
  (:func:`remanence_protocol` drives the model through the script's field sequence).
* ``forc_lakeshore_8600.csv``: Lake Shore 8600-style CSV (time, field in T, moment in A·m²),
  one row per point, calibration points in the stream.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from analysis.identification import ReversalCurves, measure_reversal_curves, regular_grid
from analysis.identification.forc_io import write_csv, write_micromag, write_segments
from hysteresis.play import GeneralizedPlay
from hysteresis.preisach import PreisachModel

HERE = Path(__file__).resolve().parent
WIDTH, SPREAD, SATURATION = 2.0, 1.0, 6.0
CSV_FILE = HERE / "forc_erf_play_mayergoyz.csv"
MICROMAG_FILE = HERE / "forc_erf_play_pike.micromag"

# the synthetic sample (fields in mT)
BC_MEAN, BC_SD, BU_SD = 30.0, 6.0, 5.0
REV_FRACTION, REV_FIELD = 0.15, 60.0
MOMENT = 5e-6  # A·m²
STEP, H_SAT, H_CAL = 2.0, 150.0, 150.0
HR_MIN, HR_MAX, H_MAX = -70.0, 20.0, 90.0
NOISE, JITTER, CAL_DRIFT, GAIN_DRIFT = 1e-3, 0.05, 2.0, 1e-5
SAMPLE_FILES = {
    "0015": HERE / "forc_micromag_0015_cgs.frc",
    "0016": HERE / "forc_micromag_0016_hybrid_si.frc",
    "aborted": HERE / "forc_micromag_0016_si_aborted.frc",
    "irregular": HERE / "forc_micromag_irregular.frc",
    "lakeshore": HERE / "forc_lakeshore_8600.csv",
}
SEGMENTS_FILES = {
    "segments": HERE / "forc_micromag_segments.frc",
    "regular": HERE / "forc_micromag_segments_regular.frc",
}
REMANENCE_FILE = HERE / "forc_micromag_remanence.frc"
REMANENCE_STEP = 0.75  # the lattice 0.75·k, k = −8 … 8, holds 0


def operator() -> GeneralizedPlay:
    return GeneralizedPlay.erf(WIDTH, SPREAD)


def irregular_nodes() -> np.ndarray:
    """An irregular lattice on [-6, 6]: dense near 0, coarse in the tails (31 nodes)."""
    x = np.linspace(-1.0, 1.0, 31)
    return SATURATION * (0.55 * x + 0.45 * x**3)


def curves_csv():
    grid = regular_grid(0.5, SATURATION)
    return measure_reversal_curves(operator(), grid, convention="mayergoyz")


def curves_micromag():
    nodes = irregular_nodes()
    return measure_reversal_curves(
        operator(), nodes, nodes, convention="pike", saturation=SATURATION
    )


def calibration_moments(n_curves: int) -> np.ndarray:
    op = operator()
    y, _ = op.apply(np.array([SATURATION]), op.initial_state(SATURATION))
    return np.full(n_curves, float(y[0]))


# ----------------------------------------------------------------------------------------------
# the synthetic sample and its measurement
# ----------------------------------------------------------------------------------------------
def sample(n_relays: int = 20000, seed: int = 1):
    """Irreversible part: a discrete Preisach model in mT (weights 1/n)."""
    rng = np.random.default_rng(seed)
    bc = np.abs(rng.normal(BC_MEAN, BC_SD, n_relays))
    bu = rng.normal(0.0, BU_SD, n_relays)
    return PreisachModel.from_relays(bu + bc, bu - bc)


def reversible(h: np.ndarray) -> np.ndarray:
    return REV_FRACTION * np.tanh(np.asarray(h) / REV_FIELD)


def true_moment(model, fields: np.ndarray, reversal: float) -> np.ndarray:
    """Noise-free moment (A·m²) along a Pike curve at the given (actual) fields."""
    y, _ = model.apply(np.concatenate([[reversal], fields]), model.initial_state(H_SAT))
    return MOMENT * ((1.0 - REV_FRACTION) * y[1:] + reversible(fields))


def measure(
    model=None,
    step: float = STEP,
    hr_min: float = HR_MIN,
    hr_max: float = HR_MAX,
    h_max: float = H_MAX,
    seed: int = 2,
    noise: float = NOISE,
    jitter: float = JITTER,
    gain_drift: float = GAIN_DRIFT,
):
    """Measured FORC sequence in mT and A·m²: list of (kind, fields, moments) in time order.

    ``kind`` is ``"cal"`` (one point near HCal) or ``"curve"``; curves from the highest reversal
    field down (the MicroMag order). The gain drifts as ``1 + gain_drift·t`` with ``t`` the
    number of points measured so far.
    """
    model = sample() if model is None else model
    rng = np.random.default_rng(seed)
    reversals = np.arange(hr_max, hr_min - 1e-9, -step)
    seq = []
    t = 0
    for hr in reversals:
        h_cal = H_CAL + rng.uniform(-CAL_DRIFT, CAL_DRIFT)
        m_cal = MOMENT * ((1.0 - REV_FRACTION) + reversible(h_cal))
        seq.append(("cal", np.array([h_cal]), np.array([m_cal * (1 + gain_drift * t)])))
        t += 1
        nominal = np.arange(hr, h_max + 1e-9, step)
        fields = nominal + rng.normal(0.0, jitter, nominal.size)
        m = true_moment(model, fields, fields[0])
        gain = 1.0 + gain_drift * (t + np.arange(m.size))
        m = m * gain + rng.normal(0.0, noise * MOMENT, m.size)
        t += m.size
        seq.append(("curve", fields, m))
    return seq


def _fmt(x: float) -> str:
    return f"{x:+.6E}"


def _blocks(seq, f_fac: float, m_fac: float, eol: str) -> list[str]:
    out = []
    for _, h, m in seq:
        for hh, mm in zip(h, m, strict=True):
            out.append(_fmt(hh * f_fac) + "," + _fmt(mm * m_fac))
        out.append("")
    return out


def micromag_0015(seq) -> str:
    n_curves = sum(k == "curve" for k, _, _ in seq)
    n_data = sum(h.size for k, h, _ in seq if k == "curve")
    lines = [
        "MicroMag 2900/3900 Data File (Series 0015)",
        "First-order reversal curves",
        "07/15/2011  14:32",
        "Configuration  = AGM",
        "Units of measure = cgs",
        "Averaging time = +1.000000E-01",
        f"HCal           = {_fmt(H_CAL * 10)}",
        f"HSat           = {_fmt(H_SAT * 10)}",
        f"NForc          = {n_curves}",
        f"NData          = {n_data}",
        "",
        "  Field     Moment",
        "",
    ]
    lines += _blocks(seq, 10.0, 1e3, "\n")  # Oe, emu
    lines.append("MicroMag 2900/3900 Data File ends")
    return "\n".join(lines) + "\n"


def micromag_0016(seq, units: str = "Hybrid SI", end: bool = True, announce=None) -> str:
    n_curves = sum(k == "curve" for k, _, _ in seq)
    n_data = sum(h.size for k, h, _ in seq if k == "curve")
    if announce is not None:
        n_curves, n_data = announce
    lines = [
        "MicroMag 2900/3900 Data File (Series 0016.002)",
        "First-order reversal curves",
        "11/23/2015  09:41",
        "",
        "INSTRUMENT",
        "Configuration                   VSM",
        "Temperature control             None",
        "Hardware version                0004",
        f"Units of measure                {units}",
        "Temperature in                  °C",
        "",
        "SAMPLE",
        "Mass                            N/A",
        "",
        "SETTINGS",
        "Field range                    +1.000000E+00",
        "Moment range                   +10.00000E-06 Am²",
        "Averaging time                 +100.0000E-03 s",
        "Lock-in sensitivity            1 µV",
        "",
        "SCRIPT",
        f"Calibration field              {_fmt(H_CAL * 1e-3)}",
        f"Saturation field               {_fmt(H_SAT * 1e-3)}",
        f"Number of FORCs                {n_curves:+d}",
        f"Number of data                 {n_data:+d}",
        "",
        "      Field         Moment",
        "       (T)          (Am²)",
        "",
    ]
    lines += _blocks(seq, 1e-3, 1.0, "\r\n")  # T, A·m²
    if end:
        lines.append("MicroMag 2900/3900 Data File ends")
    return "\r\n".join(lines) + "\r\n"


def micromag_irregular() -> str:
    return (
        "MicroMag 2900/3900 Data File (Series 0016.002)\r\n"
        "Direct moment vs. field; Multiple segments\r\n"
        "11/23/2015  09:41\r\n\r\nNumber of segments             +3\r\n\r\n"
        "+1.000000E-01,+4.000000E-06\r\n+5.000000E-02,+3.000000E-06\r\n"
    )


def lakeshore(seq) -> str:
    lines = [
        "Lake Shore 8600 Series VSM,FORC export",
        "Sample,synthetic (hysteresis-toolkit)",
        f"Calibration field [T],{H_CAL * 1e-3:.6E}",
        "Time Stamp [s],Field (µ0H) [T],Moment (m) [A·m²]",
    ]
    t = 0.0
    for _, h, m in seq:
        for hh, mm in zip(h, m, strict=True):
            lines.append(f"{t:.3f},{hh * 1e-3:.8E},{mm:.8E}")
            t += 0.1
    return "\n".join(lines) + "\n"


def segments_model() -> PreisachModel:
    """A discrete Preisach model: 3000 relays, centres N(1.5, 0.5²), widths |N(2.5, 0.6²)|."""
    rng = np.random.default_rng(0)
    a = rng.normal(1.5, 0.5, 3000)
    b = a - np.abs(rng.normal(2.5, 0.6, 3000))
    return PreisachModel.from_relays(a, b)


def curves_segments():
    """Pike curves of :func:`segments_model` on the irregular lattice (reversal fields below
    saturation: every curve has two points or more)."""
    nodes = irregular_nodes()
    return measure_reversal_curves(
        segments_model(), nodes[:-1], fields=nodes, convention="pike", saturation=SATURATION
    )


def write_segments_files() -> None:
    curves = curves_segments()
    cal = np.ones(curves.n_curves)
    write_segments(SEGMENTS_FILES["segments"], curves, SATURATION, cal)
    write_micromag(
        SEGMENTS_FILES["regular"], curves, calibration_field=SATURATION, calibration_moments=cal
    )


def remanence_model() -> PreisachModel:
    """A discrete Preisach model inside (−6, 6): 400 relays, centres N(0.3, 1²), half-widths
    |N(1.5, 0.6²)|, clipped to ±5.9 (every relay inside the lattice)."""
    rng = np.random.default_rng(3)
    s = rng.normal(0.3, 1.0, 400)
    r = np.abs(rng.normal(1.5, 0.6, 400))
    return PreisachModel.from_relays(np.clip(s + r, -5.9, 5.9), np.clip(s - r, -5.9, 5.9))


def remanence_protocol(model) -> tuple[ReversalCurves, ReversalCurves]:
    """In-field and zero-field (remanence) Pike curves of ``model`` on the lattice
    ``REMANENCE_STEP·k``: per curve, from positive saturation down to ``B_a``, then for every
    field ``B_b >= B_a`` in turn: to ``B_b`` (in-field moment), back to 0 (remanent moment)."""
    nodes = REMANENCE_STEP * np.arange(-8, 9)
    rev, fields, in_field, remanent = [], [], [], []
    for b_a in nodes[:-1]:
        h = nodes[nodes >= b_a]
        inputs = np.ravel(np.column_stack([h, np.zeros_like(h)]))  # B_a, 0, B_1, 0, ...
        y, _ = model.apply(inputs, model.initial_state(SATURATION))
        rev.append(b_a)
        fields.append(h)
        in_field.append(np.asarray(y[0::2], dtype=float))
        remanent.append(np.asarray(y[1::2], dtype=float))
    rev = np.array(rev)
    return (
        ReversalCurves(rev, tuple(fields), tuple(in_field), "pike"),
        ReversalCurves(rev, tuple(fields), tuple(remanent), "pike", "remanence"),
    )


def write_remanence_file() -> None:
    in_field, remanent = remanence_protocol(remanence_model())
    cal = np.ones(in_field.n_curves)
    write_segments(REMANENCE_FILE, in_field, SATURATION, cal, remanence=remanent)


def main() -> None:
    write_segments_files()
    write_remanence_file()
    write_csv(CSV_FILE, curves_csv())
    mm = curves_micromag()
    write_micromag(
        MICROMAG_FILE,
        mm,
        calibration_field=SATURATION,
        calibration_moments=calibration_moments(mm.n_curves),
        saturation_field=SATURATION,
    )
    seq = measure()
    SAMPLE_FILES["0015"].write_text(micromag_0015(seq))
    SAMPLE_FILES["0016"].write_bytes(micromag_0016(seq).encode("cp1252"))
    # aborted: stop in the middle of the 30th curve (calibration + curve blocks)
    cut = seq[:59] + [("curve", seq[59][1][:7], seq[59][2][:7])]
    n_curves = sum(k == "curve" for k, _, _ in seq)
    n_data = sum(h.size for k, h, _ in seq if k == "curve")
    text = micromag_0016(cut, units="SI", end=False, announce=(n_curves, n_data))
    SAMPLE_FILES["aborted"].write_bytes(text.encode("cp1252"))
    SAMPLE_FILES["irregular"].write_bytes(micromag_irregular().encode("cp1252"))
    SAMPLE_FILES["lakeshore"].write_text(lakeshore(seq), encoding="utf-8")
    print(
        "wrote",
        ", ".join(
            str(p.name)
            for p in [
                CSV_FILE,
                MICROMAG_FILE,
                *SAMPLE_FILES.values(),
                *SEGMENTS_FILES.values(),
                REMANENCE_FILE,
            ]
        ),
    )


if __name__ == "__main__":
    main()
