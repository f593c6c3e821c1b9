"""The figure of the width-disorder study (:mod:`analysis.experiments.width_disorder`)."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = ["plot_study"]

_COLORS = {2.9: "tab:blue", 4.0: "tab:red"}


def _value(x: Any) -> float:
    return float(x) if x is not None else float("nan")


def _pair(point: dict, key: str) -> tuple[float, float]:
    mean, sem = point.get(key, (np.nan, np.nan))
    return _value(mean), _value(sem)


def plot_study(record: dict, path: str | os.PathLike) -> None:
    """Four panels: the exponents (full spectrum and memory-frozen), the dimensions (D_KY of
    both, D_BC of the section), the neutral exponents and live memory directions against σ_r
    for the continuum (σ_r = 0, the erf play, drawn at the left edge), and the finite-N means
    of D_KY and D_BC against σ_r per N."""
    import matplotlib.pyplot as plt  # drawing only; the backend stays the caller's

    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
    (ax_l, ax_d), (ax_n, ax_f) = axes
    cont = record["continuum"]
    spreads = sorted(
        {p["width_spread"] for p in cont} | {r["width_spread"] for r in record["finite"]}
    )
    positive = [s for s in spreads if s > 0]
    play_x = min(positive) / 2 if positive else 0.01
    proj = record["size"]["projection_periods"]
    p0 = proj[0] if proj else None

    def xs(points: list[dict]) -> np.ndarray:
        return np.array([p["width_spread"] if p["width_spread"] > 0 else play_x for p in points])

    for c in sorted({p["coupling"] for p in cont}):
        pts = sorted((p for p in cont if p["coupling"] == c), key=lambda p: p["width_spread"])
        x, col = xs(pts), _COLORS.get(c, None)
        for key, fmt, lab in (
            ("lambda_max", "o-", r"$\lambda_1$"),
            ("lambda_2", "s--", r"$\lambda_2$ (with memory)"),
        ):
            m = np.array([_pair(p, key) for p in pts])
            ax_l.errorbar(
                x, m[:, 0], yerr=m[:, 1], fmt=fmt, color=col, capsize=3, label=f"{lab}, C = {c:g}"
            )
        if p0 is not None:
            m = np.array([_pair(p, f"frozen_P{p0}_lambda_2") for p in pts])
            ax_l.errorbar(
                x,
                m[:, 0],
                yerr=m[:, 1],
                fmt="^:",
                color=col,
                capsize=3,
                label=rf"$\lambda_2$ without memory older than {p0} T, C = {c:g}",
            )
        for key, fmt, lab in (
            ("kaplan_yorke", "s--", r"$D_\mathrm{KY}$ (with memory)"),
            ("box_counting", "o-", r"$D_\mathrm{BC}$ of $(q, v)$"),
            ("box_counting_qvm", "d-.", r"$D_\mathrm{BC}$ of $(q, v, M)$"),
        ):
            m = np.array([_pair(p, key) for p in pts])
            ax_d.errorbar(
                x, m[:, 0], yerr=m[:, 1], fmt=fmt, color=col, capsize=3, label=f"{lab}, C = {c:g}"
            )
        if p0 is not None:
            m = np.array([_pair(p, f"frozen_P{p0}_kaplan_yorke") for p in pts])
            ax_d.errorbar(
                x,
                m[:, 0],
                yerr=m[:, 1],
                fmt="^:",
                color=col,
                capsize=3,
                label=rf"$D_\mathrm{{KY}}$ without old memory, C = {c:g}",
            )
        neutral = np.array([np.mean(p["neutral"]) for p in pts])
        live = np.array([p["live_memory_mean"] for p in pts])
        ax_n.plot(x, neutral, "o-", color=col, label=f"neutral exponents, C = {c:g}")
        ax_n.plot(x, live, "s--", color=col, label=f"live memory directions, C = {c:g}")
        low = np.array([np.mean([r["live_memory_min"] for r in p["runs"]]) for p in pts])
        ax_n.plot(x, low, "v:", color=col, label=f"fewest live memory directions, C = {c:g}")
    fin = record["finite"]
    markers = dict(zip(sorted({r["spins"] for r in fin}), "o^sDv<>", strict=False))
    for c in sorted({r["coupling"] for r in fin}):
        for n, mk in markers.items():
            rows = sorted(
                (r for r in fin if r["coupling"] == c and r["spins"] == n),
                key=lambda r: r["width_spread"],
            )
            if not rows:
                continue
            x = xs(rows)
            ky = [_value(r["mean_kaplan_yorke"]) for r in rows]
            bc = [_value(r["mean_box_counting"]) for r in rows]
            k = rows[0]["realizations"]
            ax_f.plot(
                x,
                ky,
                mk + "--",
                color=_COLORS.get(c),
                mfc="none",
                label=rf"$\langle D_\mathrm{{KY}}\rangle$ N = {n} ({k}), C = {c:g}",
            )
            ax_f.plot(
                x,
                bc,
                mk + "-",
                color=_COLORS.get(c),
                label=rf"$\langle D_\mathrm{{BC}}\rangle$ N = {n}, C = {c:g}",
            )
    titles = (
        "continuum: Lyapunov exponents",
        "continuum: dimensions",
        "continuum: memory directions (means over initial conditions)",
        "finite N (registry model 'preisach'): ensemble means",
    )
    for ax, title in zip(axes.flat, titles, strict=True):
        ax.set_xscale("log")
        ax.minorticks_off()
        ticks = [play_x, *positive]
        ax.set_xticks(ticks)
        ax.set_xticklabels(["play"] + [f"{s:g}" for s in positive])
        ax.set_xlabel(r"width spread $\sigma_r$ (play: $\sigma_r = 0$)")
        ax.set_title(title, fontsize=10)
        if ax.get_legend_handles_labels()[0]:  # a part not run leaves its panels empty
            ax.legend(fontsize=6.5)
    size = record["size"]
    fig.suptitle(
        rf"Preisach $N(s;0,1)\,N(r;1,\sigma_r^2)$, $\zeta$ = 0.05, $\Omega$ = 1: continuum "
        f"t = {size['t_end']:g} ({size['initial_conditions']} initial conditions), finite N "
        f"t = {size['finite_t_end']:g}",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
