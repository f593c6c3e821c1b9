"""Figures of identified Preisach densities (paper figure fig:preis_dens).

FORC-diagram conventions: ``r = (α−β)/2`` on the x axis from 0, ``s = (α+β)/2`` on the y axis,
equal aspect. A density without negative cells is drawn on a sequential colour map from 0
(``viridis``: the low tails of a ridge stay visible against the blank plane); one with negative
masses (noisy data) on a diverging map centred at 0, negative cells in blue.
Cells are drawn as the rotated squares they are in the ``r``-``s`` plane (``pcolormesh`` on the
quadrilateral mesh of the nodes), coloured by the unsmoothed density ``μ_rs = 2·mass/(ΔαΔβ)`` or,
if requested and available, the smoothed one.

Measured data (:func:`plot_forc_diagram`, :func:`figure_forc`) use the FORC conventions of the
field: ``B_c = (B − B_r)/2`` and ``B_u = (B + B_r)/2`` in mT (``r`` and ``s``), the FORC
distribution ``ρ = −½ ∂²M/∂B_r∂B`` (equal to the Preisach ``μ_αβ``; the toolkit's r-s density is
``μ_rs = 2ρ``), by default on the FORCinel-like colour scale (:func:`forcinel_cmap`: white at
``ρ = 0``, blue below, green–yellow–red–purple above), contour lines at fixed fractions of the peak,
and the colour mesh rasterised inside vector axes, so that a PDF of a 10⁵-node diagram stays
small and fast to write.

matplotlib is imported inside the drawing functions, on purpose: importing this module neither
loads matplotlib nor fixes its backend (the caller may still choose one, e.g. ``Agg``).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from analysis.identification.result import PreisachIdentification

__all__ = [
    "plot_density_rs",
    "plot_s_marginal",
    "figure_preisach_density",
    "figure_single_density",
    "plot_forc_diagram",
    "figure_forc",
    "forc_profiles",
    "forc_limits",
    "forcinel_cmap",
    "colormap_name",
    "FORCINEL",
]

#: the name of the FORCinel-like colour scale (:func:`forcinel_cmap`), the FORC default
FORCINEL = "forcinel"
#: FORCinel's scale: colour stops at fractions of the peak ρ (positive side) and the colours
#: (RGB 0–255): white within ±2.5 % of the peak, green, yellow, red, purple, dark purple
_FORCINEL_STOPS = (
    (0.025, (255, 255, 255)),
    (0.19, (102, 178, 102)),
    (0.48, (204, 204, 76)),
    (0.64, (204, 76, 76)),
    (0.80, (153, 102, 153)),
    (0.97, (76, 25, 76)),
    (1.0, (76, 25, 76)),
)
#: the negative end (light blue) and the smallest negative range drawn, in units of the peak
_FORCINEL_BLUE = (127, 127, 255)
FORCINEL_NEGATIVE = 0.19

#: a negative minimum beyond this fraction of the maximum counts as meaningful (diverging map)
NEGATIVE_FRACTION = 0.05
CONTOUR_FRACTIONS = (0.1, 0.3, 0.5, 0.7, 0.9)
#: ``abs(ρ)/se`` below this is not significant at 95 % (the contour line on the FORC diagram)
SIGNIFICANT = 1.959963984540054
#: the FORC diagram's default crop: the nodes with ``|ρ|`` at least this fraction of the peak
#: (FORCinel's white band: below it the colour scale is white anyway) ...
CROP_FRACTION = 0.025
#: ... widened by this fraction of their span on every cropped side (at least half a grid step)
CROP_MARGIN = 0.1


def plot_density_rs(
    ax: Any,
    ident: PreisachIdentification,
    smoothed: bool = False,
    r_max: float | None = None,
    s_limits: tuple[float, float] | None = None,
    vmax: float | None = None,
    cmap: str | None = None,
) -> Any:
    """Density in the r-s plane on ``ax``; returns the mappable (for a colour bar).

    ``cmap=None`` picks ``viridis`` from 0 for a non-negative density and the diverging
    ``RdBu_r`` centred at 0 when some cell is negative.
    """
    from matplotlib.colors import Normalize, TwoSlopeNorm

    aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    rr, ss = 0.5 * (aa - bb), 0.5 * (aa + bb)
    if smoothed:
        if ident.density_rs is None:
            raise ValueError("smoothed=True needs an identification made with smoothing")
        values = np.where(bb <= aa, ident.density_rs, np.nan)
        mesh_r, mesh_s, c = rr, ss, values
        shading = "gouraud"
    else:
        values = ident.cell_density_rs().copy()
        # cells on the unphysical side carry no mass, and mixed differences of a smooth E leave
        # round-off of ~1e-16 elsewhere: leave both blank (display only; the data keep them)
        tiny = 1e-12 * max(float(np.abs(ident.cell_mass).max()), 1e-300)
        values[np.abs(ident.cell_mass) <= tiny] = np.nan
        mesh_r, mesh_s, c = rr, ss, values
        shading = "flat"
    finite = np.isfinite(c)
    top = vmax if vmax is not None else (float(np.nanmax(np.abs(c))) if finite.any() else 1.0)
    top = top if top > 0 else 1.0
    positive = not finite.any() or float(np.nanmin(c)) >= 0.0
    if positive:
        norm = Normalize(vmin=0.0, vmax=top)
        cmap = cmap or "viridis"
    else:
        norm = TwoSlopeNorm(vmin=-top, vcenter=0.0, vmax=top)
        cmap = cmap or "RdBu_r"
    mappable = ax.pcolormesh(
        mesh_r,
        mesh_s,
        np.ma.masked_invalid(c),
        cmap=cmap,
        norm=norm,
        shading=shading,
        rasterized=True,  # vector axes, raster mesh: small, fast PDFs
    )
    ax.set_xlim(0.0, r_max if r_max is not None else float(rr.max()))
    if s_limits is not None:
        ax.set_ylim(*s_limits)
    ax.set_aspect("equal")
    ax.set_xlabel("r = (α − β)/2")
    ax.set_ylabel("s = (α + β)/2")
    return mappable


def plot_s_marginal(
    ax: Any,
    idents: dict[str, PreisachIdentification],
    spread: float,
    centre: float = 0.0,
) -> None:
    """Numerical ``μ(s)`` (see :meth:`PreisachIdentification.s_density`) vs ``N(s; centre, R²)``."""
    markers = ["o", "s", "^", "v"]
    lo, hi = np.inf, -np.inf
    for (label, ident), mk in zip(idents.items(), markers, strict=False):
        s, dens = ident.s_density()
        ax.plot(s, dens, mk, ms=3, mfc="none", label=label)
        lo, hi = min(lo, s.min()), max(hi, s.max())
    grid = np.linspace(lo, hi, 600)
    from scipy.stats import norm  # heavy at import: loaded where used (fast `hyst` start)

    ax.plot(grid, norm.pdf(grid, loc=centre, scale=spread), "k-", lw=1, label="N(s; 0, R²)")
    ax.set_xlabel("s")
    ax.set_ylabel("μ(s)")
    ax.legend(fontsize=8)


def figure_preisach_density(
    limit: PreisachIdentification,
    finite: PreisachIdentification,
    width: float,
    spread: float,
    out_dir: str | Path,
    stem: str = "fig_preis_dens",
    finite_label: str = "N = 20 000",
    extra_data: dict[str, Any] | None = None,
    title: str | None = None,
) -> list[Path]:
    """Paper figure fig:preis_dens: (a) μ(s) numerical vs theory, (b) N → ∞, (c) finite N.

    Writes ``stem.png``, ``stem.pdf`` and ``stem.npz`` (grids, Everett functions, cell masses,
    marginals) into ``out_dir``; returns the paths. ``title`` replaces the default
    ``"Preisach density, p = .., R = .."``.
    """
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(12, 4.2), gridspec_kw={"width_ratios": [1.3, 1, 1]})
    plot_s_marginal(axes[0], {"N → ∞ (erf play)": limit, finite_label: finite}, spread)
    axes[0].set_title("(a)")
    r_max = width
    s_lim = (-4.0 * spread, 4.0 * spread)
    vmax = max(
        float(np.nanmax(np.abs(limit.cell_density_rs()))),
        float(np.nanmax(np.abs(finite.cell_density_rs()))),
    )
    for ax, ident, title in (
        (axes[1], limit, "(b) N → ∞"),
        (axes[2], finite, f"(c) {finite_label}"),
    ):
        mappable = plot_density_rs(ax, ident, r_max=r_max, s_limits=s_lim, vmax=vmax)
        ax.axvline(0.5 * width, color="0.5", lw=0.5, ls=":")
        ax.set_title(title)
    fig.colorbar(mappable, ax=axes[1:], label="μ_rs (cell mass / r-s area)", shrink=0.85)
    if title is None:
        title = f"Preisach density, p = {width:g}, R = {spread:g}"
    fig.suptitle(title, fontsize=10)
    paths = [out_dir / f"{stem}.png", out_dir / f"{stem}.pdf", out_dir / f"{stem}.npz"]
    fig.savefig(paths[0], dpi=150, bbox_inches="tight")
    fig.savefig(paths[1], bbox_inches="tight")
    plt.close(fig)
    data: dict[str, Any] = {"width": width, "spread": spread}
    for key, ident in (("limit", limit), ("finite", finite)):
        data[f"{key}_alpha"] = ident.alpha
        data[f"{key}_beta"] = ident.beta
        data[f"{key}_everett"] = ident.everett
        data[f"{key}_cell_mass"] = ident.cell_mass
        if ident.is_regular:
            s, ms = ident.s_marginal()
            r, mr = ident.r_marginal()
            data[f"{key}_s"], data[f"{key}_s_mass"] = s, ms
            data[f"{key}_r"], data[f"{key}_r_mass"] = r, mr
    data.update(extra_data or {})
    np.savez_compressed(paths[2], **data)
    return paths


def figure_single_density(
    ident: PreisachIdentification,
    out_dir: str | Path,
    stem: str,
    title: str = "",
    smoothed: bool = False,
    spread: float | None = None,
    labels: Sequence[str] = (),
) -> list[Path]:
    """One identification: r-s density (and μ(s) if the grid is regular); PNG, PDF, NPZ."""
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    ncols = 2 if ident.is_regular else 1
    fig, axes = plt.subplots(1, ncols, figsize=(5 * ncols + 1, 4.2), squeeze=False)
    axes = axes[0]
    if ident.is_regular:
        s, dens = ident.s_density()
        axes[0].plot(s, dens, "o", ms=3, mfc="none", label="identified")
        if spread is not None:
            from scipy.stats import norm  # heavy at import: loaded where used

            axes[0].plot(s, norm.pdf(s, scale=spread), "k-", lw=1, label="N(s; 0, R²)")
        axes[0].set_xlabel("s")
        axes[0].set_ylabel("μ(s)")
        axes[0].legend(fontsize=8)
    mappable = plot_density_rs(axes[-1], ident, smoothed=smoothed)
    fig.colorbar(mappable, ax=axes[-1], label="μ_rs")
    fig.suptitle(title, fontsize=10)
    paths = [out_dir / f"{stem}.png", out_dir / f"{stem}.pdf", out_dir / f"{stem}.npz"]
    fig.savefig(paths[0], dpi=150, bbox_inches="tight")
    fig.savefig(paths[1], bbox_inches="tight")
    plt.close(fig)
    np.savez_compressed(
        paths[2],
        alpha=ident.alpha,
        beta=ident.beta,
        everett=ident.everett,
        cell_mass=ident.cell_mass,
    )
    return paths


def forc_limits(
    ident: PreisachIdentification, fraction: float = CROP_FRACTION
) -> tuple[float, float, float]:
    """``(B_c max, B_u min, B_u max)`` of the cropped diagram: the nodes where
    ``|ρ| >= fraction ×`` the peak (:data:`CROP_FRACTION`: FORCinel's white band, drawn white
    anyway) and, with standard errors, significant at 95 %, widened by :data:`CROP_MARGIN` of
    their span, but at least by half a grid step ``Δ/2`` (the reach of a node's drawn cell in
    ``B_c`` and ``B_u``: a region one node thin keeps whole cells, not a zero-size window), and
    kept within the evaluated nodes. ``fraction=0`` gives the evaluated region's extent."""
    if ident.density_alpha_beta is None:
        raise ValueError("a FORC diagram needs an identification made with smoothing")
    aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    rr, ss = 0.5 * (aa - bb), 0.5 * (aa + bb)
    rho = np.where(bb <= aa, ident.density_alpha_beta, np.nan)
    finite = np.isfinite(rho)
    if not finite.any():
        raise ValueError("the smoothed density is NaN everywhere (too few data points)")
    full = (float(rr[finite].max()), float(ss[finite].min()), float(ss[finite].max()))
    top = float(np.nanmax(np.abs(rho)))
    shown = finite & (np.abs(np.nan_to_num(rho)) >= fraction * top)
    if ident.density_se is not None:  # and significant at 95 %, where standard errors exist
        with np.errstate(divide="ignore", invalid="ignore"):
            shown &= np.nan_to_num(np.abs(rho) / ident.density_se) > SIGNIFICANT
    if fraction <= 0.0 or top == 0.0 or shown.sum() < 2:
        return full
    r_hi = float(rr[shown].max())
    s_lo, s_hi = float(ss[shown].min()), float(ss[shown].max())
    half_cell = 0.5 * ident.grid_step
    pad_r = max(CROP_MARGIN * r_hi, half_cell)
    pad_s = max(CROP_MARGIN * (s_hi - s_lo), half_cell)
    return min(r_hi + pad_r, full[0]), max(s_lo - pad_s, full[1]), min(s_hi + pad_s, full[2])


def plot_forc_diagram(
    ax: Any,
    ident: PreisachIdentification,
    field_unit: str | None = "mT",
    moment_unit: str | None = "A·m²",
    cmap: str = FORCINEL,
    contours: Sequence[float] = CONTOUR_FRACTIONS,
    scale: float = 1.0,
    significance: bool = True,
    limits: tuple[float, float, float] | None = None,
) -> Any:
    """FORC diagram of the smoothed density: ``ρ`` over ``(B_c, B_u)``; returns the mappable.

    The colours show ``scale · ρ``. With ``significance`` and an identification made with
    ``uncertainty=True``, the 95 % significance level ``|ρ| = 1.96 se`` is drawn as one
    contour line (dark grey, dashed; labelled in the legend): the density inside it is
    significant, outside it is noise (FORCinel and FORCsensei draw it the same way).

    ``cmap="forcinel"`` (default): :func:`forcinel_cmap`, white at ``ρ = 0``
    (``TwoSlopeNorm``), the negative range down to the lowest value or 19 % of the peak,
    whichever is lower. Any other matplotlib map name: centred at 0 (``TwoSlopeNorm``, ±the
    larger extreme) when at least 1 % of the nodes lie below −5 % of the peak (a negative
    region, e.g. of interacting single-domain particles), else from 0 (noise-level negatives
    drawn as 0). NaN nodes (outside the measured region) stay blank. Contours at
    ``contours`` × the peak. ``B_c`` is horizontal, ``B_u`` vertical; the axes show
    ``limits = (B_c max, B_u min, B_u max)``, by default :func:`forc_limits` (cropped to the
    density above 2.5 % of the peak).
    """
    from matplotlib.colors import Normalize, TwoSlopeNorm
    from matplotlib.lines import Line2D

    if ident.density_alpha_beta is None:
        raise ValueError("a FORC diagram needs an identification made with smoothing")
    aa, bb = np.meshgrid(ident.alpha, ident.beta, indexing="ij")
    rr, ss = 0.5 * (aa - bb), 0.5 * (aa + bb)
    rho = scale * np.where(bb <= aa, ident.density_alpha_beta, np.nan)
    finite = np.isfinite(rho)
    if not finite.any():
        raise ValueError("the smoothed density is NaN everywhere (too few data points)")
    top = float(np.nanmax(rho))
    low = float(np.nanmin(rho))
    top = top if top > 0 else 1.0
    # meaningful negative region: at least 1 % of the nodes below −5 % of the peak (isolated
    # noise or edge values do not switch the map)
    diverging = float(np.nanpercentile(rho, 1.0)) < -NEGATIVE_FRACTION * top
    if cmap == FORCINEL:
        cmap = forcinel_cmap()
        norm = TwoSlopeNorm(vmin=-max(-low, FORCINEL_NEGATIVE * top), vcenter=0.0, vmax=top)
    elif diverging:
        bound = max(top, -low)
        norm = TwoSlopeNorm(vmin=-bound, vcenter=0.0, vmax=bound)
    else:
        norm = Normalize(vmin=0.0, vmax=top)
    masked = np.ma.masked_invalid(rho)
    mappable = ax.pcolormesh(
        rr, ss, masked, cmap=cmap, norm=norm, shading="nearest", rasterized=True
    )
    levels = sorted(f * top for f in contours if 0 < f < 1)
    if levels:
        ax.contour(rr, ss, masked, levels=levels, colors="k", linewidths=0.5)
    if significance and ident.density_se is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            sig = np.abs(ident.density_alpha_beta) / ident.density_se
        sig = np.ma.masked_invalid(np.where(finite, sig, np.nan))
        if sig.count() and sig.min() < SIGNIFICANT < sig.max():
            style = {"colors": "0.25", "linewidths": 0.9, "linestyles": "--"}
            ax.contour(rr, ss, sig, levels=[SIGNIFICANT], **style)
            line = Line2D([], [], color="0.25", lw=0.9, ls="--")
            ax.legend([line], ["95 % significance"], loc="upper right", fontsize=7)
    bc_max, bu_lo, bu_hi = limits if limits is not None else forc_limits(ident)
    ax.set_xlim(0.0, bc_max)
    ax.set_ylim(bu_lo, bu_hi)
    ax.set_aspect("equal")
    unit = f" ({field_unit})" if field_unit else ""
    ax.set_xlabel(f"$B_c$ = ($B$ − $B_r$)/2{unit}")
    ax.set_ylabel(f"$B_u$ = ($B$ + $B_r$)/2{unit}")
    return mappable


def forcinel_cmap() -> Any:
    """The FORCinel-like colour scale for ``TwoSlopeNorm(vmin, 0, vmax)``: the lower half of
    the map is ``[vmin, 0]`` (light blue at ``vmin`` to white), the upper half ``[0, vmax]``
    (white up to 2.5 % of the peak, then green at 19 %, yellow at 48 %, red at 64 %, purple
    at 80 % and dark purple from 97 %).

    The scale of FORCinel (Harrison & Feinberg 2008, G-cubed 9, Q05016), as FORCsensei
    (Heslop et al. 2020) reproduces it for matplotlib (``FORCinel_colormap``: the same colour
    stops at the same fractions of the peak, a white band of ±2.5 % around zero and a
    negative range of at least 19 % of the peak). Written here from that description; the
    negative side's stops are scaled to the negative range drawn
    (:data:`FORCINEL_NEGATIVE` × the peak unless the data go lower)."""
    from matplotlib.colors import LinearSegmentedColormap

    def rgb(c: tuple[int, int, int]) -> tuple[float, float, float]:
        return (c[0] / 255.0, c[1] / 255.0, c[2] / 255.0)

    white = 0.5 - 0.5 * 0.025 / FORCINEL_NEGATIVE
    stops = [(0.0, rgb(_FORCINEL_BLUE)), (white, rgb((255, 255, 255)))]
    stops += [(0.5 + 0.5 * f, rgb(c)) for f, c in _FORCINEL_STOPS]
    return LinearSegmentedColormap.from_list(FORCINEL, stops, N=1024)


def colormap_name(text: str) -> str:
    """``text`` if it names a matplotlib colour map or :data:`FORCINEL`, else ``ValueError``
    naming the allowed values (for the CLI's ``--cmap``)."""
    import matplotlib

    if text == FORCINEL or text in matplotlib.colormaps:
        return text
    raise ValueError(
        f"{text!r} is not a matplotlib colour map nor {FORCINEL!r} (e.g. viridis, RdBu_r)"
    )


def forc_profiles(ident: PreisachIdentification) -> tuple[np.ndarray, ...]:
    """Marginal profiles of the smoothed ``ρ``: ``(B_c, ∫ρ dB_u, B_u, ∫ρ dB_c)`` on the
    lattice (regular grids: the nodes with ``i − j = d`` lie at ``B_c = dΔ/2``, ``Δ`` apart
    in ``B_u``; NaN nodes count as 0).

    Both skip the ``B_c ≈ 0`` ridge as the peak search does
    (:data:`~analysis.identification.result.RIDGE_EXCLUSION_STEPS` grid steps,
    :meth:`~analysis.identification.result.PreisachIdentification.ridge_excluded`): the
    ``B_c`` profile starts there, the ``B_u`` profile integrates ``B_c`` from there."""
    step = ident._require_regular()
    rho = np.nan_to_num(ident.density_alpha_beta, nan=0.0)
    i, j = np.indices(rho.shape)
    d = (i - j).ravel()
    keep = (d >= 0) & ~ident.ridge_excluded().ravel()
    bc_prof = np.bincount(d[keep], weights=rho.ravel()[keep], minlength=rho.shape[0]) * step
    k = (i + j).ravel()
    bu_prof = np.bincount(k[keep], weights=rho.ravel()[keep], minlength=2 * rho.shape[0] - 1)
    # nodes with one i + j lie Δ apart in B_c (i − j steps by 2): the weight is Δ, as along a
    # diagonal i − j (Δ apart in B_u)
    bu_prof = bu_prof * step
    bc = np.arange(bc_prof.size) * 0.5 * step
    first = int(np.min(d[keep])) if keep.any() else 0
    bu = ident.alpha[0] + np.arange(bu_prof.size) * 0.5 * step
    return bc[first:], bc_prof[first:], bu, bu_prof


def figure_forc(
    ident: PreisachIdentification,
    out_dir: str | Path,
    stem: str,
    title: str = "",
    field_unit: str | None = "mT",
    moment_unit: str | None = "A·m²",
    cmap: str = FORCINEL,
    rho_factor: float = 1.0,
    rho_unit: str | None = None,
    limits: tuple[float, float, float] | None = None,
) -> list[Path]:
    """FORC diagram of measured data: ``stem.png`` (150 dpi), ``stem.pdf`` (vector axes,
    raster mesh) and ``stem.npz`` (nodes, Everett table, cell masses, smoothed ρ, its standard
    error and significance when computed).

    ``ρ`` is drawn times ``rho_factor`` in ``rho_unit`` (default: moment per field unit²),
    with the power of ten in the colour-bar label (no offset text to collide with the title).
    On a regular lattice the profiles are drawn on the diagram's own axes: ``∫ρ dB_u`` below
    it over the same ``B_c`` range, ``∫ρ dB_c`` to its right over the same ``B_u`` range
    (both without the ``B_c ≈ 0`` ridge, :func:`forc_profiles`). ``limits``: ``(B_c max,
    B_u min, B_u max)`` of the axes, default :func:`forc_limits` (the cropped diagram)."""
    import matplotlib.pyplot as plt
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fu = field_unit or "field unit"
    mu = moment_unit or "moment unit"
    unit = rho_unit or f"{mu}/{fu}²"
    top = float(np.nanmax(np.abs(ident.density_alpha_beta))) * abs(rho_factor)
    power = int(np.floor(np.log10(top))) if top > 0 and np.isfinite(top) else 0
    scale = rho_factor / 10.0**power
    limits = limits if limits is not None else forc_limits(ident)
    profiles = ident.is_regular
    fig, ax = plt.subplots(figsize=(7.6, 6.4) if profiles else (6.4, 4.8))
    mappable = plot_forc_diagram(
        ax, ident, field_unit, moment_unit, cmap, scale=scale, limits=limits
    )
    divider = make_axes_locatable(ax)
    exp = f"$10^{{{power}}}$ " if power else ""
    if profiles:
        ax_u = divider.append_axes("right", size="28%", pad=0.12, sharey=ax)
        ax_c = divider.append_axes("bottom", size="28%", pad=0.12, sharex=ax)
    cax = divider.append_axes("right", size="4%", pad=0.35 if profiles else 0.15)
    bar = fig.colorbar(mappable, cax=cax, label=f"$\\rho$ ({exp}{unit})")
    bar.ax.set_yscale("linear")  # a TwoSlopeNorm bar in proportion to ρ, not half and half
    if profiles:
        # rho_factor converts field unit⁻²; a profile has one field power less
        bc, pc, bu, pu = forc_profiles(ident)
        pfac = np.sqrt(abs(rho_factor))
        punit = f"{mu}/T" if rho_unit and rho_unit.endswith("/T²") else f"{mu}/{fu}"
        pc, pu = pc * pfac, pu * pfac
        ptop = max(float(np.max(np.abs(pc), initial=0.0)), float(np.max(np.abs(pu), initial=0.0)))
        ppow = int(np.floor(np.log10(ptop))) if ptop > 0 and np.isfinite(ptop) else 0
        pexp = f"$10^{{{ppow}}}$ " if ppow else ""  # the power in the label, as the bar's
        ax_c.plot(bc, pc / 10.0**ppow, "k-", lw=1)
        ax_c.set_xlabel(ax.get_xlabel())
        ax_c.set_ylabel(f"$\\int\\rho\\,\\mathrm{{d}}B_u$\n({pexp}{punit})", fontsize=8)
        ax_u.plot(pu / 10.0**ppow, bu, "k-", lw=1)
        ax_u.set_xlabel(f"$\\int\\rho\\,\\mathrm{{d}}B_c$\n({pexp}{punit})", fontsize=8)
        ax.tick_params(labelbottom=False)
        ax.set_xlabel("")
        ax_u.tick_params(labelleft=False)
        ax_c.set_xlim(0.0, limits[0])  # the diagram's axes (shared), restated after plotting
        ax_u.set_ylim(limits[1], limits[2])
        ax_c.axhline(0.0, color="0.6", lw=0.5)
        ax_u.axvline(0.0, color="0.6", lw=0.5)
        for a in (ax_c, ax_u):
            a.tick_params(labelsize=7)
    if title:
        fig.suptitle(title, fontsize=9)
    paths = [out_dir / f"{stem}.png", out_dir / f"{stem}.pdf", out_dir / f"{stem}.npz"]
    fig.savefig(paths[0], dpi=150, bbox_inches="tight")
    fig.savefig(paths[1], dpi=150, bbox_inches="tight")
    plt.close(fig)
    extra = {}
    if ident.density_se is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            extra = {
                "rho_se": ident.density_se,
                "significance": ident.density_alpha_beta / ident.density_se,
            }
    np.savez_compressed(
        paths[2],
        alpha=ident.alpha,
        beta=ident.beta,
        everett=ident.everett,
        cell_mass=ident.cell_mass,
        rho=ident.density_alpha_beta,
        rho_factor=rho_factor,
        **extra,
    )
    return paths
