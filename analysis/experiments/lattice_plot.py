"""The figure of the lattice study (:mod:`analysis.experiments.lattice`)."""

from __future__ import annotations

import os

import numpy as np

__all__ = ["plot_study"]

_COLORS = {2.9: "tab:blue", 4.0: "tab:red"}
_MARKERS = "osD^v<>"


def _pair(point: dict, side: str | None, key: str) -> tuple[float, float]:
    src = point if side is None else point[side]
    mean, sem = src[key]
    return (float("nan") if mean is None else float(mean), float("nan") if sem is None else sem)


def plot_study(record: dict, path: str | os.PathLike) -> None:
    """Six panels against the disorder R (one line per L and C; R_c ≈ 2.16 marked): λ_max of
    the coupled lattice (filled) and of its identified Preisach model (open), the fraction of
    regular realizations, ``D_KY`` and ``D_BC``, the operator-level error of the Preisach
    model (raw input and on the grid nodes), the largest avalanche of the major loop, and the
    avalanche-size histograms of the coupled motion, the periodic sweep and the major loop at
    the largest L."""
    import matplotlib.pyplot as plt  # drawing only; the backend stays the caller's

    pts = record["points"]
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    ax_l, ax_r, ax_d = axes[0]
    ax_e, ax_m, ax_h = axes[1]
    sides = sorted({p["side"] for p in pts})
    for c in sorted({p["coupling"] for p in pts}):
        col = _COLORS.get(c)
        for side, mk in zip(sides, _MARKERS, strict=False):
            sel = sorted(
                (p for p in pts if p["coupling"] == c and p["side"] == side),
                key=lambda p: p["disorder"],
            )
            if not sel:
                continue
            x = np.array([p["disorder"] for p in sel])
            lab = f"L = {side}, C = {c:g}"
            for part, fill, ls in (("lattice", col, "-"), ("preisach", "none", ":")):
                m = np.array([_pair(p, part, "lambda_max") for p in sel])
                ax_l.errorbar(x, m[:, 0], yerr=m[:, 1], fmt=mk + ls, color=col, mfc=fill,
                              capsize=2, label=f"{part}, {lab}")  # fmt: skip
                fr = [p[part]["fraction_regular"] for p in sel]
                ax_r.plot(x, fr, mk + ls, color=col, mfc=fill, label=f"{part}, {lab}")
            for key, ls in (("kaplan_yorke", "-"), ("box_counting", "--")):
                m = np.array([_pair(p, "lattice", key) for p in sel])
                ax_d.errorbar(x, m[:, 0], yerr=m[:, 1], fmt=mk + ls, color=col, capsize=2,
                              label=f"{key}, {lab}")  # fmt: skip
            for key, ls, fill in (
                ("operator_error_rms", "-", col),
                ("operator_error_on_nodes_rms", ":", "none"),
            ):
                m = np.array([_pair(p, None, key) for p in sel])
                short = key.replace("operator_error_", "")
                ax_e.errorbar(x, m[:, 0], yerr=m[:, 1], fmt=mk + ls, color=col, mfc=fill,
                              capsize=2, label=f"{short}, {lab}")  # fmt: skip
            if c == min(p["coupling"] for p in pts):
                m = np.array([_pair(p, None, "major_largest_fraction") for p in sel])
                ax_m.errorbar(x, m[:, 0], yerr=m[:, 1], fmt=mk + "-", color="k", capsize=2,
                              label=f"L = {side}")  # fmt: skip
    big = max(sides)
    top = [p for p in pts if p["side"] == big]
    for p in top:
        if p["coupling"] != max(q["coupling"] for q in top):
            continue
        edges = np.asarray(p["bin_edges"], dtype=float)
        centre, width = np.sqrt(edges[:-1] * edges[1:]), np.diff(edges)
        for key, ls in (("coupled_histogram", "-"), ("sweep_histogram", "--"),
                        ("major_histogram", ":")):  # fmt: skip
            h = np.asarray(p[key], dtype=float) / width
            h = np.where(h > 0, h / max(h.sum(), 1.0), np.nan)
            ax_h.loglog(
                centre, h, ls, marker=".", label=f"{key.split('_')[0]}, R = {p['disorder']:g}"
            )
    for ax in (ax_l, ax_r, ax_d, ax_e, ax_m):
        ax.axvline(2.16, color="0.6", lw=0.8, ls="--")
        ax.set_xlabel("disorder R (J = 1)")
    ax_l.axhline(0.0, color="0.6", lw=0.8)
    titles = (
        (ax_l, r"$\lambda_\max$: lattice (filled) vs identified Preisach (open)"),
        (ax_r, "fraction of regular realizations"),
        (ax_d, r"coupled lattice: $D_\mathrm{KY}$ (solid), $D_\mathrm{BC}$ (dashed)"),
        (ax_e, "Preisach model's rms error in M along the lattice orbit's input"),
        (ax_m, "largest avalanche of the major loop / N"),
        (ax_h, f"avalanche sizes, L = {big}, C = {max(p['coupling'] for p in top):g}"),
    )
    for ax, title in titles:
        ax.set_title(title, fontsize=9)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=5.5)
    ax_h.set_xlabel("avalanche size S")
    ax_h.set_ylabel("P(S)")
    size = record["size"]
    fig.suptitle(
        rf"RFIM $L^3$, J = 1, coupled to $\ddot q + 2\zeta\dot q + q = \cos\Omega t + C M$; "
        f"{size['realizations']} realizations, {size['periods']} periods "
        f"({size['transient_periods']} transient)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
