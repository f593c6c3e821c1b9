"""Width disorder: λ_max and D_KY of the forced oscillator with a Gaussian-ridge Preisach model.

    python examples/width_disorder.py [--out out/examples] [--smoke] [--t-end 3000]
        [--transient 300] [--spreads 0.4 0.2 0.1 0.05 0.025]

The paper's thermodynamic limit has all elementary loops of one width p (a ridge δ(r − p/2) in
the Preisach plane; the generalized play ``GeneralizedPlay.erf(p, R)``). Real materials have a
width distribution: here the density is ``N(s; 0, R²)·N(r; p/2, σ_r²)``
(:meth:`ContinuousPreisachModel.gaussian`, p = 2, R = 1) and the oscillator (ζ = 0.05, Ω = 1,
q0 = −1, v0 = 0.1, rising from negative saturation) runs through the generic continuous engine
with its tangent flow (memory directions: the remembered extrema of the staircase). For
C = 2.9 and 4.0 and each σ_r the script computes the Lyapunov spectrum, λ_max and D_KY; σ_r = 0
is the erf play itself (compiled play kernel). Nothing is tuned: one initial condition, one run
length for all.

Output (resumable: finished runs are read back, not recomputed): ``width_disorder.json`` (one
entry per (C, σ_r, t_end, transient)) and ``width_disorder.png``.

Note on λ_2 and D_KY: the tangent space of a Preisach model holds every remembered extremum.
A perturbation copied into an extremum at a reversal (δm := δq) stays frozen until that extremum
is wiped out, and an outer extremum that is rarely or never wiped out is a neutral direction
(exponent 0: each value of it carries its own invariant set). In the full tangent space the
second exponent is therefore pulled towards 0 by the long-lived extrema, and D_KY reflects the
memory turnover rather than the chaotic (q, v) dynamics; this holds however small σ_r is, since
the extrema stay in the state even where their influence on the output vanishes. The play
forgets its memory perturbation at every wall hit (λ = −∞). λ_max is not affected.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis.dynamics.dimensions import kaplan_yorke_dimension  # noqa: E402
from analysis.dynamics.lyapunov import lyapunov_spectrum  # noqa: E402
from hysteresis import ContinuousPreisachModel, GeneralizedPlay  # noqa: E402
from oscillators import ForcedOscillator  # noqa: E402

WIDTH, SPREAD, ZETA, OMEGA = 2.0, 1.0, 0.05, 1.0
COUPLINGS = (2.9, 4.0)


def run_one(coupling: float, width_spread: float, t_end: float, transient: float) -> dict:
    """Spectrum of one (C, σ_r); σ_r = 0 is the erf play."""
    if width_spread == 0.0:
        operator = GeneralizedPlay.erf(WIDTH, SPREAD)
    else:
        operator = ContinuousPreisachModel.gaussian(WIDTH, SPREAD, width_spread)
    system = ForcedOscillator(operator, coupling, ZETA, OMEGA)
    start = time.perf_counter()
    res = lyapunov_spectrum(system, t_end, transient, q0=-1.0, v0=0.1, progress=False)
    exps = np.asarray(res.exponents, dtype=float)
    # running estimate at the middle of the averaging window: |λ(T) − λ(T/2)| is a rough
    # finite-time error bar
    half = 0.5 * (transient + t_end)
    i_half = int(np.argmin(np.abs(np.asarray(res.history_t) - half)))
    lam_half = float(np.asarray(res.history)[i_half, 0])
    return {
        "coupling": coupling,
        "width_spread": width_spread,
        "t_end": t_end,
        "transient": transient,
        "exponents": [float(x) if np.isfinite(x) else str(x) for x in exps],
        "lambda_max": float(exps[0]),
        "lambda_max_half": lam_half,
        "lambda_2": float(exps[1]),
        "kaplan_yorke": float(kaplan_yorke_dimension(exps)),
        "tangent_space": list(res.tangent_space),
        "seconds": time.perf_counter() - start,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="tiny sizes (for tests)")
    parser.add_argument("--t-end", type=float, default=3000.0, help="Lyapunov run length")
    parser.add_argument("--transient", type=float, default=300.0)
    parser.add_argument(
        "--spreads", type=float, nargs="+", default=[0.4, 0.2, 0.1, 0.05, 0.025], help="σ_r"
    )
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.smoke:
        args.t_end, args.transient, args.spreads = 30.0, 5.0, [0.2]
    for s in args.spreads:
        if not s > 0.0:
            raise SystemExit(
                f"--spreads must be > 0 (σ_r = 0 is the erf play, always run), got {s}"
            )
    store = out / ("width_disorder_smoke.json" if args.smoke else "width_disorder.json")
    results: dict[str, dict] = json.loads(store.read_text()) if store.exists() else {}
    spreads = [0.0] + sorted(args.spreads, reverse=True)
    for c in COUPLINGS:
        for s in spreads:
            key = f"C={c:g} sigma_r={s:g} t_end={args.t_end:g} transient={args.transient:g}"
            if key not in results:
                results[key] = run_one(c, s, args.t_end, args.transient)
                store.write_text(json.dumps(results, indent=1))  # resumable after each run
            r = results[key]
            print(
                f"C = {c:g}, sigma_r = {s:<6g}: lambda_max = {r['lambda_max']:+.4f}, "
                f"D_KY = {r['kaplan_yorke']:.3f}, exponents = {r['exponents'][:4]} "
                f"({r['seconds']:.0f} s)",
                flush=True,
            )

    fig, axes = plt.subplots(1, 3, figsize=(14, 3.8))
    for c, color in zip(COUPLINGS, ("tab:blue", "tab:red"), strict=True):
        rows = [
            results[f"C={c:g} sigma_r={s:g} t_end={args.t_end:g} transient={args.transient:g}"]
            for s in spreads
        ]
        sig = np.array([r["width_spread"] for r in rows[1:]])
        lam = np.array([r["lambda_max"] for r in rows[1:]])
        err = np.array(
            [abs(r["lambda_max"] - r.get("lambda_max_half", r["lambda_max"])) for r in rows[1:]]
        )
        lam2 = np.array([r.get("lambda_2", np.nan) for r in rows[1:]])
        dky = np.array([r["kaplan_yorke"] for r in rows[1:]])
        axes[0].errorbar(sig, lam, yerr=err, fmt="o-", color=color, capsize=3, label=f"C = {c:g}")
        axes[0].axhline(rows[0]["lambda_max"], color=color, ls="--", lw=1)
        axes[1].plot(sig, lam2, "o-", color=color, label=f"C = {c:g}")
        axes[1].axhline(rows[0].get("lambda_2", np.nan), color=color, ls="--", lw=1)
        axes[2].plot(sig, dky, "o-", color=color, label=f"C = {c:g}")
        axes[2].axhline(rows[0]["kaplan_yorke"], color=color, ls="--", lw=1)
    names = (
        r"$\lambda_\max$ (bars: $|\lambda(T) - \lambda(T/2)|$)",
        r"$\lambda_2$",
        r"$D_\mathrm{KY}$",
    )
    for ax, name in zip(axes, names, strict=True):
        ax.set_xscale("log")
        ax.minorticks_off()
        ax.set_xticks(sorted(args.spreads))
        ax.set_xticklabels([f"{x:g}" for x in sorted(args.spreads)])
        ax.set_xlabel(r"width spread $\sigma_r$")
        ax.set_ylabel(name)
        ax.legend(title="dashed: erf play ($\\sigma_r = 0$)", fontsize=8, title_fontsize=8)
    fig.suptitle(
        f"Preisach N(s;0,1)·N(r;1,σ_r²): p = {WIDTH:g}, R = {SPREAD:g}, "
        f"t = {args.t_end:g} (transient {args.transient:g})",
        fontsize=10,
    )
    fig.tight_layout()
    png = out / ("width_disorder_smoke.png" if args.smoke else "width_disorder.png")
    fig.savefig(png, dpi=120)
    print(f"wrote {png} and {store}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
