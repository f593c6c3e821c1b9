"""Figures of a FORC unmixing (:class:`~analysis.identification.unmixing_result.ForcUnmixing`).

Three figures, as FORC-PCA studies show them (Harrison et al. 2018; Lascu et al. 2015):

* **scores**: every sample in the plane of the first two principal components, labelled, with
  the end-member simplex drawn (its edges projected onto that plane when there are more than
  three end-members; a line segment for two, on the first component's axis);
* **end-members**: the end-members' FORC diagrams over ``(B_c, B_u)`` on the common lattice,
  on the FORCinel colour scale (:func:`~analysis.identification.plots.forcinel_cmap`,
  white at ``ρ = 0``);
* **proportions**: the proportions per sample as stacked bars (in the order of the inputs),
  each end-member's interval as an error bar at its segment.

matplotlib is imported inside the drawing functions (importing this module loads none).
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification.plots import FORCINEL, FORCINEL_NEGATIVE, forcinel_cmap
from analysis.identification.unmixing_result import ForcUnmixing

__all__ = [
    "plot_scores",
    "plot_end_member",
    "plot_proportions",
    "figure_unmixing",
    "END_MEMBER_COLOURS",
]

#: one colour per end-member (bars, simplex vertices), the same in every figure
END_MEMBER_COLOURS = (
    "#1b9e77",
    "#d95f02",
    "#7570b3",
    "#e7298a",
    "#66a61e",
    "#e6ab02",
    "#a6761d",
    "#666666",
)


def _colour(k: int) -> str:
    return END_MEMBER_COLOURS[k % len(END_MEMBER_COLOURS)]


def plot_scores(ax: Any, result: ForcUnmixing, labels: bool = True) -> None:
    """PC1–PC2 scores of the samples with the end-member simplex (module docstring)."""
    s = result.scores
    x = s[:, 0] if s.shape[1] > 0 else np.zeros(result.n_samples)
    y = s[:, 1] if s.shape[1] > 1 else np.zeros(result.n_samples)
    ax.scatter(x, y, s=16, c="k", zorder=3)
    if labels:
        for xi, yi, name in zip(x, y, result.labels, strict=True):
            ax.annotate(name, (xi, yi), fontsize=6, xytext=(3, 3), textcoords="offset points")
    v = result.end_member_scores
    if v.shape[1] >= 1:
        vx = v[:, 0]
        vy = v[:, 1] if v.shape[1] > 1 else np.zeros(v.shape[0])
        for a, b in itertools.combinations(range(v.shape[0]), 2):
            ax.plot([vx[a], vx[b]], [vy[a], vy[b]], "-", color="0.5", lw=0.8, zorder=1)
        for k in range(v.shape[0]):
            ax.scatter(
                vx[k], vy[k], s=60, marker="^", color=_colour(k), zorder=4, label=f"EM{k + 1}"
            )
        ax.legend(fontsize=7, loc="best")
    evr = result.explained_variance_ratio
    ax.set_xlabel(f"PC1 ({100 * evr[0]:.1f} %)" if evr.size > 0 else "PC1")
    ax.set_ylabel(f"PC2 ({100 * evr[1]:.1f} %)" if evr.size > 1 else "PC2")
    ax.set_title(f"PC scores, {result.n_components} end-members ({result.chosen_by})", fontsize=9)


def plot_end_member(
    ax: Any, result: ForcUnmixing, k: int, field_unit: str = "mT", cmap: str = FORCINEL
) -> Any:
    """The FORC diagram of end-member ``k`` on ``ax``; returns the mappable."""
    from matplotlib.colors import TwoSlopeNorm

    rho = np.ma.masked_invalid(result.end_members[k])
    top = float(rho.max()) if rho.count() else 1.0
    top = top if top > 0 else 1.0
    low = float(rho.min()) if rho.count() else 0.0
    norm = TwoSlopeNorm(vmin=-max(-low, FORCINEL_NEGATIVE * top), vcenter=0.0, vmax=top)
    colours = forcinel_cmap() if cmap == FORCINEL else cmap
    mappable = ax.pcolormesh(
        result.bc, result.bu, rho.T, cmap=colours, norm=norm, shading="nearest", rasterized=True
    )
    ax.set_aspect("equal")
    ax.set_xlabel(f"$B_c$ ({field_unit})")
    ax.set_ylabel(f"$B_u$ ({field_unit})")
    ax.set_title(f"EM{k + 1}", fontsize=9, color=_colour(k))
    return mappable


def plot_proportions(ax: Any, result: ForcUnmixing) -> None:
    """Stacked bars of the proportions per sample, with the intervals (module docstring)."""
    n, m = result.proportions.shape
    x = np.arange(n)
    bottom = np.zeros(n)
    for k in range(m):
        p = result.proportions[:, k]
        ax.bar(x, p, bottom=bottom, color=_colour(k), width=0.8, label=f"EM{k + 1}")
        if result.proportion_intervals is not None:
            lo, hi = result.proportion_intervals[:, k, 0], result.proportion_intervals[:, k, 1]
            ax.errorbar(
                x + (k - (m - 1) / 2) * 0.8 / max(m, 1) * 0.6,
                bottom + p,
                yerr=[np.clip(p - lo, 0, None), np.clip(hi - p, 0, None)],
                fmt="none",
                ecolor="k",
                elinewidth=0.7,
                capsize=1.5,
            )
        bottom = bottom + p
    ax.set_xticks(x)
    ax.set_xticklabels(result.labels, rotation=60, ha="right", fontsize=6)
    ax.set_ylim(0.0, 1.05)
    ax.set_ylabel(f"proportion ({_basis(result.normalize)})")
    pct = int(round(100 * result.level))
    bars = f"; bars: {pct} % bootstrap intervals" if result.proportion_intervals is not None else ""
    ax.set_title(f"proportions per sample{bars}", fontsize=9)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))


def _basis(normalize: str) -> str:
    return {
        "moment": "of M_s",
        "irreversible": "of the irreversible moment",
        "mass": "per mass",
        "volume": "per volume",
        "none": "of the moment",
    }[normalize]


def figure_unmixing(
    result: ForcUnmixing,
    out_dir: str | Path,
    stem: str = "unmix",
    field_unit: str = "mT",
    cmap: str = FORCINEL,
    title: str = "",
) -> list[Path]:
    """The three figures as ``stem_scores``, ``stem_end_members``, ``stem_proportions``
    (PNG at 150 dpi and PDF each) and ``stem.npz`` (the lattice, the normalised diagrams and
    standard errors, the mean, the components, the end-members); returns the paths."""
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []

    def save(fig: Any, name: str) -> None:
        if title:
            fig.suptitle(title, fontsize=9)
        fig.tight_layout()
        for ext in ("png", "pdf"):
            path = out_dir / f"{stem}_{name}.{ext}"
            fig.savefig(path, dpi=150, bbox_inches="tight")
            paths.append(path)
        plt.close(fig)

    fig, ax = plt.subplots(figsize=(5.6, 4.6))
    plot_scores(ax, result, labels=result.n_samples <= 60)
    save(fig, "scores")
    m = result.n_components
    cols = min(m, 4)
    rows = -(-m // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.4 * cols + 0.6, 3.2 * rows), squeeze=False)
    for k in range(rows * cols):
        ax = axes.flat[k]
        if k >= m:
            ax.set_visible(False)
            continue
        mappable = plot_end_member(ax, result, k, field_unit, cmap)
        fig.colorbar(mappable, ax=ax, shrink=0.8, label="ρ (normalised)")
    save(fig, "end_members")
    fig, ax = plt.subplots(figsize=(max(5.0, 0.22 * result.n_samples + 2.0), 4.0))
    plot_proportions(ax, result)
    save(fig, "proportions")
    npz = out_dir / f"{stem}.npz"
    arrays = {
        "bc": result.bc,
        "bu": result.bu,
        "mask": result.mask,
        "diagrams": result.diagrams,
        "mean": result.mean,
        "components": result.components,
        "end_members": result.end_members,
        "proportions": result.proportions,
        "scores": result.scores,
        "labels": np.array(result.labels),
    }
    if result.standard_errors is not None:
        arrays["standard_errors"] = result.standard_errors
    if result.proportion_intervals is not None:
        arrays["proportion_intervals"] = result.proportion_intervals
    np.savez_compressed(npz, **arrays)
    paths.append(npz)
    return paths
