"""Regenerate the small synthetic FORC files of tests/data with the toolkit's own operators.

    python tests/data/make_forc_data.py

* ``forc_erf_play_mayergoyz.csv``: the paper's erf play (p = 2, R = 1), Mayergoyz curves on the
  regular grid step 0.5, saturation 6 (25 curves).
* ``forc_erf_play_pike.micromag``: the same operator, Pike curves (from positive saturation 6)
  on an irregular lattice shared by reversal fields and fields, with a calibration point at
  HCal = 6 before every curve (MicroMag text format).

The tests compare identifications from these files with identifications made directly from the
operator (:func:`curves_csv`, :func:`curves_micromag` rebuild the same curves).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from analysis.forc_io import write_csv, write_micromag
from analysis.identification import measure_reversal_curves, regular_grid
from hysteresis.play import GeneralizedPlay

HERE = Path(__file__).resolve().parent
WIDTH, SPREAD, SATURATION = 2.0, 1.0, 6.0
CSV_FILE = HERE / "forc_erf_play_mayergoyz.csv"
MICROMAG_FILE = HERE / "forc_erf_play_pike.micromag"


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


def main() -> None:
    write_csv(CSV_FILE, curves_csv())
    mm = curves_micromag()
    write_micromag(
        MICROMAG_FILE,
        mm,
        calibration_field=SATURATION,
        calibration_moments=calibration_moments(mm.n_curves),
        saturation_field=SATURATION,
    )
    print(f"wrote {CSV_FILE} and {MICROMAG_FILE}")


if __name__ == "__main__":
    main()
