"""Benchmark: read + identify + FORC figure of a 300-curve, ~84 000-point measurement.

    python benchmarks/bench_identification.py [--repeats 3] [--keep DIR] [--batch 20]

The measurement is synthetic but instrument-shaped (tests/data/make_forc_data.py: a 20 000-relay
sample plus a reversible part, 0.5 mT protocol step, jittered fields, noise, gain drift,
calibration points), written as a MicroMag Series 0016 file (Hybrid SI, cp1252, CRLF). Timed
(median of ``--repeats`` runs, one core): ``read_micromag`` with drift correction,
``identify_from_curves`` (protocol grid, smoothing factor 3) and ``figure_forc`` (PNG + PDF).

Baseline, in the same run: the plain per-node least-squares smoother
(:func:`analysis.identification.local_quadratic_density`, one ``lstsq`` per node over the same
gridded data and window) in place of the FFT normal-equation smoother; the two densities are
compared (max difference relative to the peak). Target: total <= 10 s.

Smoothing laws on the same file, each timed (median of ``--repeats``) next to the fixed factor
measured in the same run (``identify_from_curves`` alone, the file read once): the fixed factor
3 (FFT normal equations), the fixed factor with standard errors (the lattice regression),
VARIFORC with the published defaults (target: within 2x of the fixed factor), VARIFORC with
standard errors, and ``smoothing="auto"`` (the Lepski rule on ρ: six VARIFORC fits with
standard errors on a sub-lattice of ~12 000 nodes, then the chosen one on all nodes; target:
within 2–3x of VARIFORC). The peak's parametric bootstrap (200 replicates) is timed after the
fits with standard errors.

Batch (``--batch N``, 0 to skip): ``hyst identify --input DIR`` over N copies of the file
(read, identify, figure, summary) on 1 and on 2 worker processes; the ratio is the speed-up of
the second worker (the machine's other load shows in it). Last line: JSON.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core, as the target says
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from analysis.identification import identify_from_curves, local_quadratic_density  # noqa: E402
from analysis.identification.density import _protocol_table  # noqa: E402
from analysis.identification.forc_io import read_micromag  # noqa: E402
from analysis.identification.peak_bootstrap import peak_bootstrap  # noqa: E402
from analysis.identification.plots import figure_forc  # noqa: E402

STEP = 0.5  # mT
N_CURVES = 300
HR_MAX = 20.0
H_MAX = HR_MAX + 130 * STEP  # 300 × 131 + Σc = 84 150 points
SMOOTHING = 3.0


def _maker():
    path = ROOT / "tests" / "data" / "make_forc_data.py"
    spec = importlib.util.spec_from_file_location("make_forc_data", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def write_measurement(path: Path) -> tuple[int, int]:
    mk = _maker()
    seq = mk.measure(
        step=STEP,
        hr_max=HR_MAX,
        hr_min=HR_MAX - (N_CURVES - 1) * STEP,
        h_max=H_MAX,
        jitter=0.0125,
    )
    path.write_bytes(mk.micromag_0016(seq).encode("cp1252"))
    n_curves = sum(k == "curve" for k, _, _ in seq)
    n_points = sum(h.size for k, h, _ in seq if k == "curve")
    return n_curves, n_points


def pipeline(path: Path, out: Path) -> dict[str, float]:
    t0 = time.perf_counter()
    data = read_micromag(path, drift_correction="multiplicative")
    t1 = time.perf_counter()
    ident = identify_from_curves(data.curves, smoothing=SMOOTHING, extend=False)
    t2 = time.perf_counter()
    figure_forc(ident, out, "bench_forc", field_unit="mT", moment_unit="A·m²")
    t3 = time.perf_counter()
    return {"read": t1 - t0, "identify": t2 - t1, "figure": t3 - t2, "total": t3 - t0}


def baseline_smoothing(path: Path) -> tuple[float, float, float]:
    """Per-node lstsq on the same lattice data; returns (seconds, fast seconds, max rel diff)."""
    data = read_micromag(path, drift_correction="multiplicative")
    nodes, E, measured, step = _protocol_table(data.curves, None)
    aa, bb = np.meshgrid(nodes, nodes, indexing="ij")
    where = measured & (bb <= aa)
    t0 = time.perf_counter()
    base = np.full(E.shape, np.nan)
    base[where] = local_quadratic_density(
        aa[measured],
        bb[measured],
        E[measured],
        aa[where],
        bb[where],
        SMOOTHING * step,
        SMOOTHING * step,
    )
    t_base = time.perf_counter() - t0
    t0 = time.perf_counter()
    fast = identify_from_curves(data.curves, smoothing=SMOOTHING, extend=False)
    t_fast = time.perf_counter() - t0
    both = np.isfinite(base) & np.isfinite(fast.density_alpha_beta)
    peak = float(np.nanmax(fast.density_alpha_beta))
    diff = float(np.max(np.abs(base[both] - fast.density_alpha_beta[both]))) / peak
    return t_base, t_fast, diff


def smoothing_laws(path: Path, repeats: int) -> dict[str, float]:
    """Median seconds of ``identify_from_curves`` per smoothing law (the file read once)."""
    data = read_micromag(path, drift_correction="multiplicative")
    laws = {
        "fixed": {"smoothing": SMOOTHING},
        "fixed_with_errors": {"smoothing": SMOOTHING, "uncertainty": True},
        "variforc": {"smoothing": "variforc"},
        "variforc_with_errors": {"smoothing": "variforc", "uncertainty": True},
        "auto": {"smoothing": "auto"},
    }
    identify_from_curves(data.curves, smoothing="variforc", extend=False)  # warm-up (compile)
    out = {}
    for name, kw in laws.items():
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            identify_from_curves(data.curves, extend=False, **kw)
            times.append(time.perf_counter() - t0)
        out[name] = statistics.median(times)
    for name in ("fixed_with_errors", "variforc_with_errors"):
        ident = identify_from_curves(data.curves, extend=False, **laws[name])
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            peak_bootstrap(ident, n_boot=200, seed=0)
            times.append(time.perf_counter() - t0)
        out[f"bootstrap_200_{name.removesuffix('_with_errors')}"] = statistics.median(times)
    return out


def batch(path: Path, n_files: int, workers: int, root: Path) -> float:
    """Seconds of ``hyst identify --input DIR --workers W`` over ``n_files`` copies."""
    import shutil

    from analysis.cli import main as hyst

    folder = root / f"batch_in_{n_files}"
    if not folder.exists():
        folder.mkdir(parents=True)
        for k in range(n_files):
            shutil.copy(path, folder / f"sample_{k:03d}.frc")
    t0 = time.perf_counter()
    code = hyst(
        [
            "identify",
            "--input",
            str(folder),
            "--workers",
            str(workers),
            "--quiet",
            "--out",
            str(root / f"batch_out_{workers}"),
        ]
    )
    if code != 0:
        raise RuntimeError(f"the batch failed (exit status {code})")
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--keep", default=None, help="keep the data file and figure here")
    parser.add_argument("--batch", type=int, default=20, help="files in the batch (0: skip)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.keep) if args.keep else Path(tmp)
        out.mkdir(parents=True, exist_ok=True)
        path = out / "bench_forc.frc"
        n_curves, n_points = write_measurement(path)
        print(f"measurement: {n_curves} curves, {n_points} points, {path.stat().st_size} bytes")
        pipeline(path, out)  # warm-up: imports, caches
        runs = [pipeline(path, out) for _ in range(args.repeats)]
        med = {k: statistics.median(r[k] for r in runs) for k in runs[0]}
        for k, v in med.items():
            print(f"{k:9s} {v:7.3f} s (median of {args.repeats})")
        t_base, t_fast, diff = baseline_smoothing(path)
        print(
            f"smoothing: per-node lstsq baseline {t_base:.2f} s, FFT normal equations "
            f"(identify incl. gridding) {t_fast:.2f} s, ratio {t_base / t_fast:.1f}x, "
            f"max |difference| {diff:.1e} of the peak"
        )
        laws = smoothing_laws(path, args.repeats)
        for name, sec in laws.items():
            print(
                f"smoothing {name:26s} {sec:7.3f} s, {sec / laws['fixed']:5.2f}x the fixed factor"
            )
        print(f"smoothing auto / variforc: {laws['auto'] / laws['variforc']:.2f}x")
        batches = {}
        if args.batch > 0:
            import contextlib
            import io

            with contextlib.redirect_stdout(io.StringIO()):
                batches = {w: batch(path, args.batch, w, out) for w in (1, 2)}
            print(
                f"batch of {args.batch} files: 1 worker {batches[1]:.1f} s, 2 workers "
                f"{batches[2]:.1f} s, speed-up {batches[1] / batches[2]:.2f}x"
            )
        pdf = out / "bench_forc.pdf"
        result = {
            "benchmark": "identification",
            "n_curves": n_curves,
            "n_points": n_points,
            "read_s": med["read"],
            "identify_s": med["identify"],
            "figure_s": med["figure"],
            "total_s": med["total"],
            "target_s": 10.0,
            "meets_target": med["total"] <= 10.0,
            "baseline_per_node_smoothing_s": t_base,
            "identify_s_same_run": t_fast,
            "speedup_vs_baseline": t_base / t_fast,
            "max_rel_difference_to_baseline": diff,
            "pdf_bytes": pdf.stat().st_size,
            "smoothing_s": laws,
            "variforc_over_fixed": laws["variforc"] / laws["fixed"],
            "variforc_meets_2x": laws["variforc"] <= 2.0 * laws["fixed"],
            "auto_over_fixed": laws["auto"] / laws["fixed"],
            "auto_over_variforc": laws["auto"] / laws["variforc"],
            "batch_files": args.batch,
            "batch_s_1_worker": batches.get(1),
            "batch_s_2_workers": batches.get(2),
        }
        print(json.dumps(result))


if __name__ == "__main__":
    main()
