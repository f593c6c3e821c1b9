"""FORC unmixing of a sample series: ``hyst unmix`` on 12 and on 100 files of ~5000 points.

The series is synthetic and written as files first (not timed): three Gaussian Preisach
populations (``ContinuousPreisachModel.gaussian``) driven through reversal curves on a regular
grid whose step gives ``--points`` points per file, mixed in Dirichlet proportions, moment
noise ``--noise``, and every field jittered by 1 % of a step (as measured fields differ curve
by curve: the files take the protocol-lattice path of measured data). The figure of merit is
the wall time of ``hyst unmix --input DIR`` (reading, identification with VARIFORC and standard
errors, the common lattice, PCA, N-FINDR, 200 bootstrap replicates, figures, summaries), the
issue's targets: 12 files in <= 30 s, 100 files in <= 3 min. The library's share without the
figures is timed separately, and the recovered proportions' largest error is printed as a
check.

    python benchmarks/bench_unmix.py [--sizes 12 100] [--points 5000] [--noise 3e-3]

The last line is one JSON object with the times.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from analysis.cli import main
from analysis.identification import ReversalCurves, measure_reversal_curves, regular_grid
from analysis.identification.forc_io import write_csv
from analysis.identification.unmixing import unmix_forc
from hysteresis.preisach import ContinuousPreisachModel

POPULATIONS = ((2.0, 0.25, 0.15), (1.0, 0.45, 0.2), (0.4, 0.8, 0.12))
SATURATION = 3.0


def write_series(folder: Path, n: int, points: int, noise: float, seed: int) -> np.ndarray:
    """``n`` files in ``folder`` (the three pure populations first); the true proportions."""
    nodes = math.sqrt(2.0 * points)  # a triangle of nodes²/2 points
    step = 2.0 * SATURATION / (nodes - 1.0)
    grid = regular_grid(step, SATURATION)
    parts = [
        measure_reversal_curves(ContinuousPreisachModel.gaussian(*p), grid) for p in POPULATIONS
    ]
    rng = np.random.default_rng(seed)
    truth = np.vstack([np.eye(3), rng.dirichlet(np.ones(3), size=max(n - 3, 0))])[:n]
    first = parts[0]
    for k, p in enumerate(truth):
        fields, moments = [], []
        for c in range(first.n_curves):
            h = first.fields[c] + rng.normal(0.0, 0.01 * step, first.fields[c].size)
            h = np.minimum.accumulate(h)  # stays falling (Mayergoyz curves)
            m = sum(pk * part.moments[c] for pk, part in zip(p, parts, strict=True))
            fields.append(h)
            moments.append(m + rng.normal(0.0, noise, m.size))
        curves = ReversalCurves(np.array([h[0] for h in fields]), tuple(fields), tuple(moments))
        write_csv(folder / f"sample_{k:03d}.csv", curves)
    return truth


def main_bench() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[12, 100])
    ap.add_argument("--points", type=int, default=5000)
    ap.add_argument("--noise", type=float, default=3e-3)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    record: dict = {"points": args.points, "noise": args.noise, "runs": []}
    for n in args.sizes:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp) / "series"
            folder.mkdir()
            truth = write_series(folder, n, args.points, args.noise, args.seed)
            files = sorted(folder.iterdir())
            t0 = time.perf_counter()
            result = unmix_forc(files)
            t_lib = time.perf_counter() - t0
            t0 = time.perf_counter()
            code = main(
                ["unmix", "--input", str(folder), "--out", str(Path(tmp) / "out"), "--quiet"]
            )
            t_cli = time.perf_counter() - t0
            cols = [int(np.argmax(truth[i])) for i in result.end_member_samples or ()]
            err = math.nan
            if result.n_components == 3 and sorted(cols) == [0, 1, 2]:
                est = np.zeros_like(truth)
                est[:, cols] = result.proportions
                err = float(np.max(np.abs(est - truth)))
            run = {
                "files": n,
                "points_per_file": int(np.mean([sum(1 for _ in open(f)) - 1 for f in files])),
                "end_members": result.n_components,
                "max_proportion_error": err,
                "library_s": t_lib,
                "cli_s": t_cli,
                "exit": code,
            }
            record["runs"].append(run)
            print(
                f"{n} files: hyst unmix {t_cli:.1f} s (library {t_lib:.1f} s), "
                f"{result.n_components} end-members, largest proportion error {err:.3g}"
            )
    print(json.dumps(record))


if __name__ == "__main__":
    main_bench()
