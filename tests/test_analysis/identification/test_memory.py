"""Issue 21: the peak memory of an identification is estimated before it starts and bounded."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from analysis.cli import main
from analysis.experiments.models import build_operator
from analysis.identification import identify_from_curves, identify_preisach
from analysis.identification.curves import (
    ReversalCurves,
    measure_reversal_curves,
    regular_grid,
)
from analysis.identification.density import estimate_memory
from analysis.identification.memory import (
    MemoryBoundError,
    check_memory,
    default_max_memory,
    estimate_identification_bytes,
)
from hysteresis._validation import MAX_GRID_NODES

#: stated margin of the estimate: between the measured peak and 1.75 times it
MARGIN = 1.75


def _measured_curves(n_curves: int, seed: int = 0) -> ReversalCurves:
    """Pike curves with jittered fields (protocol lattice of about n_curves nodes)."""
    rng = np.random.default_rng(seed)
    rev, fields, moments = [], [], []
    top = float(n_curves)
    for i in range(n_curves):
        hr = i + rng.uniform(-0.01, 0.01)
        h = hr + np.arange(0.0, top - hr + 0.5)
        h[1:] += rng.uniform(-0.05, 0.05, h.size - 1)
        rev.append(hr)
        fields.append(h)
        moments.append(np.tanh((h - hr) / (top / 4)) + np.tanh(h / top))
    return ReversalCurves(np.array(rev), tuple(fields), tuple(moments), convention="pike")


def _peak(fn):
    fn()  # warm-up: imports and caches are not the identification's
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize(("n_curves", "smoothing"), [(120, None), (120, 3.0), (200, 3.0)])
def test_estimate_within_margin_of_tracemalloc_peak_protocol(n_curves, smoothing):
    curves = _measured_curves(n_curves)
    estimate = estimate_memory(curves, smoothing=smoothing, grid="protocol")
    peak = _peak(lambda: identify_from_curves(curves, smoothing=smoothing, grid="protocol"))
    assert peak <= estimate <= MARGIN * peak, (estimate, peak)


@pytest.mark.parametrize(("step", "smoothing"), [(0.05, None), (0.2, 2.0)])
def test_estimate_within_margin_of_tracemalloc_peak_operator(step, smoothing):
    op = build_operator("erf-play", width=1.0, spread=1.0)
    n = 2 * int(np.ceil(5.5 / step - 1e-9)) + 1
    sm = None if smoothing is None else (smoothing, smoothing)
    estimate = estimate_identification_bytes(n * (n + 1) // 2, n, smoothing=sm, grid="native")
    peak = _peak(lambda: identify_preisach(op, step, 5.5, smoothing=smoothing))
    assert peak <= estimate <= MARGIN * peak, (estimate, peak)


def test_tiny_bound_refused_before_allocating():
    curves = _measured_curves(60)
    tracemalloc.start()
    try:
        with pytest.raises(MemoryBoundError) as err:
            identify_from_curves(curves, smoothing=3.0, grid="protocol", max_memory=1e5)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    msg = str(err.value)
    assert "\n" not in msg and "GB" in msg and "--max-memory" in msg and "coarser" in msg
    assert peak < 200_000  # nothing of the lattice's size (60² nodes × 560 B ≈ 2 MB)
    op = build_operator("erf-play", width=1.0, spread=1.0)
    with pytest.raises(MemoryBoundError, match="bound 1e-06 GB"):
        identify_preisach(op, 0.1, 5.5, max_memory=1000)


def test_default_bound_and_huge_estimate():
    assert default_max_memory() > 0
    # 3000² protocol lattice, smoothed: ~5 GB (the finding), refused under a 1 GB bound
    big = estimate_identification_bytes(10**6, 3000, smoothing=(3.0, 3.0))
    assert 4e9 < big < 6e9
    with pytest.raises(MemoryBoundError, match=r"estimated 5\.\d+ GB"):
        check_memory(big, 1e9)


def test_cli_refuses_one_line_exit_2(tmp_path, capsys):
    code = main(
        ["identify", "--model", "erf-play", "--step", "0.05", "--max-memory", "0.0001"]
        + ["--out", str(tmp_path / "o")]
    )
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(lines) == 1 and "estimated" in lines[0] and "bound 0.0001 GB" in lines[0]


def test_file_reading_estimate_and_refusal(tmp_path, capsys):
    from support_paths import DATA

    from analysis.identification.forc_io import read_forc_file
    from analysis.identification.memory import estimate_read_bytes

    path = DATA / "forc_lakeshore_8600.csv"
    size = path.stat().st_size
    peak = _peak(lambda: read_forc_file(path))
    assert peak <= estimate_read_bytes(size) <= 1.85 * peak, (estimate_read_bytes(size), peak)
    with pytest.raises(MemoryBoundError, match="reading of the file"):
        read_forc_file(path, max_memory=1000)
    code = main(["identify", "--input", str(path), "--max-memory", "1e-6"])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "bound 1e-06 GB" in lines[0], lines


@pytest.mark.parametrize("step", [0.12, 0.06])
@pytest.mark.parametrize(
    ("smoothing", "uncertainty"), [("variforc", False), ("auto", False), (3.0, True)]
)
def test_estimate_of_the_lattice_regression_on_the_native_table(step, smoothing, uncertainty):
    # VARIFORC, "auto" and uncertainty fit on the regular native table by the lattice
    # regression (FFT normal equations), not the scattered k-d tree windows: the estimate
    # was the windows' (8-60 times the tracemalloc peak, issue 32: 27.5 GB for a run of 1.86)
    curves = measure_reversal_curves(
        build_operator("erf-play", width=2.0, spread=1.0), regular_grid(step, 6.0)
    )
    estimate = estimate_memory(curves, smoothing=smoothing, uncertainty=uncertainty)
    peak = _peak(
        lambda: identify_from_curves(
            curves, smoothing=smoothing, uncertainty=uncertainty, output_range=(-1.0, 1.0)
        )
    )
    assert peak <= estimate <= MARGIN * peak, (estimate, peak)


def test_a_fine_model_step_is_refused_up_front_naming_step():
    # a grid beyond MAX_GRID_NODES is refused before the operator is driven (not a bare
    # MemoryError from the nodes² Everett table)
    class Untouchable:
        output_range = (-1.0, 1.0)

        def __getattr__(self, name):
            raise AssertionError(f"the operator was used ({name})")

    with pytest.raises(ValueError) as exc:
        identify_preisach(Untouchable(), 1e-7, 6.0)
    text = str(exc.value)
    assert text.startswith("step=") and str(MAX_GRID_NODES) in text and "\n" not in text
