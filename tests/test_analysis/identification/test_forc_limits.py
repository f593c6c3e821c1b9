"""The FORC diagram's default crop (:func:`forc_limits`) against densities whose support is known.

A synthetic smoothed density ``ρ = exp(−d²/2)``, ``d² = ((r − r₀)/σ_r)² + ((s − s₀)/σ_s)²``, is
placed on a regular α-β grid. Its region above the documented ``CROP_FRACTION`` of the peak is
the ellipse ``d ≤ c``, ``c = √(2 ln(1/CROP_FRACTION))``, i.e. ``r ≤ r₀ + cσ_r``,
``s₀ − cσ_s ≤ s ≤ s₀ + cσ_s``. The grid's nodes sample the plane at ``Δ/2`` in r and s (the
r-s lattice of a regular α-β grid is a checkerboard of pitch ``Δ/2``), so the extreme node
inside the ellipse lies within one ``Δ`` of the ellipse's extreme: the crop (that extent widened
by ``CROP_MARGIN`` of its span, at least ``Δ/2``) is known to within ``(1 + CROP_MARGIN)·Δ``.
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.identification.plots import CROP_FRACTION, CROP_MARGIN, forc_limits
from analysis.identification.result import PreisachIdentification

STEP = 0.25
NODES = np.arange(-10.0, 10.0 + STEP / 2, STEP)
#: the ellipse d <= C is where exp(-d²/2) >= CROP_FRACTION
C = np.sqrt(2.0 * np.log(1.0 / CROP_FRACTION))


def _rs() -> tuple[np.ndarray, np.ndarray]:
    aa, bb = np.meshgrid(NODES, NODES, indexing="ij")
    return 0.5 * (aa - bb), 0.5 * (aa + bb)


def _blob(r0: float, s0: float, sr: float, ss_: float, height: float = 1.0) -> np.ndarray:
    rr, ss = _rs()
    return height * np.exp(-0.5 * (((rr - r0) / sr) ** 2 + ((ss - s0) / ss_) ** 2))


def _ident(rho: np.ndarray, se: np.ndarray | None = None) -> PreisachIdentification:
    """An identification carrying only what the crop reads: the nodes and the smoothed ρ."""
    n = NODES.size
    rr, _ = _rs()
    rho = np.where(rr >= 0.0, rho, np.nan)  # β > α is not evaluated
    return PreisachIdentification(
        alpha=NODES,
        beta=NODES,
        everett=np.zeros((n, n)),
        cell_mass=np.zeros((n - 1, n - 1)),
        step=STEP,
        density_alpha_beta=rho,
        density_se=se,
    )


def _expected(r_hi: float, s_lo: float, s_hi: float) -> tuple[float, float, float]:
    """The documented crop of a shown region with extent ``[0, r_hi] × [s_lo, s_hi]``: the
    margin, at least half a step (the reach of a node's drawn cell)."""
    pad_r = max(CROP_MARGIN * r_hi, STEP / 2)
    pad_s = max(CROP_MARGIN * (s_hi - s_lo), STEP / 2)
    return r_hi + pad_r, s_lo - pad_s, s_hi + pad_s


def _assert_contains_ellipse(limits, r0, s0, sr, ss_):
    """The crop never cuts the continuous region above the fraction (up to one node pitch)."""
    bc_max, bu_lo, bu_hi = limits
    assert bc_max >= r0 + C * sr - STEP
    assert bu_lo <= s0 - C * ss_ + STEP
    assert bu_hi >= s0 + C * ss_ - STEP


@pytest.mark.parametrize(
    ("r0", "s0", "sr", "ss_"),
    [(3.0, -1.0, 0.5, 0.7), (1.5, 2.0, 0.8, 1.5), (0.0, 0.0, 1.0, 2.0)],
)
def test_crop_is_the_ellipse_widened_by_the_margin(r0, s0, sr, ss_):
    limits = forc_limits(_ident(_blob(r0, s0, sr, ss_)))
    # continuous extent of the region above the fraction (r >= 0: the diagram starts at B_c = 0)
    exact = _expected(r0 + C * sr, s0 - C * ss_, s0 + C * ss_)
    # the node extent is at most one step inside the continuous one (at most (1+margin)·Δ on
    # the widened limits), never outside it
    tol = (1.0 + 2.0 * CROP_MARGIN) * STEP
    assert exact[0] - tol <= limits[0] <= exact[0] + 1e-12
    assert exact[1] - 1e-12 <= limits[1] <= exact[1] + tol
    assert exact[2] - tol <= limits[2] <= exact[2] + 1e-12
    _assert_contains_ellipse(limits, r0, s0, sr, ss_)
    # and it excludes the empty far region: the evaluated plane reaches r = 10, s = ±10
    assert limits[0] < 0.6 * 10.0 and -10.0 + 3.0 < limits[1] and limits[2] < 10.0 - 3.0


def test_every_node_above_the_fraction_is_inside_the_crop_with_the_margin():
    """Brute force over the nodes: none of the shown nodes touches the crop's edge."""
    rho = _blob(2.0, 0.5, 0.6, 1.1) - 0.3 * _blob(1.0, -2.5, 0.4, 0.4)  # a negative lobe too
    limits = forc_limits(_ident(rho))
    rr, ss = _rs()
    shown = (rr >= 0) & (np.abs(rho) >= CROP_FRACTION * np.abs(rho[rr >= 0]).max())
    r_hi, s_lo, s_hi = rr[shown].max(), ss[shown].min(), ss[shown].max()
    assert limits == pytest.approx(_expected(r_hi, s_lo, s_hi), abs=1e-12)
    # the negative lobe (|ρ| up to 0.3 of the peak, above the fraction for d² <= 2 ln(0.3/f))
    # counts as much as a positive one: the crop holds it (up to one node pitch)
    assert limits[1] <= -2.5 - 0.4 * np.sqrt(2.0 * np.log(0.3 / CROP_FRACTION)) + STEP


def test_a_weak_far_lobe_below_the_fraction_is_cropped_away_and_one_above_is_kept():
    main = _blob(2.0, 0.0, 0.5, 0.8)
    below = forc_limits(_ident(main + 0.5 * CROP_FRACTION * _blob(6.0, 3.0, 0.5, 0.5)))
    assert below == forc_limits(_ident(main))
    above = forc_limits(_ident(main + 4.0 * CROP_FRACTION * _blob(6.0, 3.0, 0.5, 0.5)))
    assert above[0] >= 6.0 and above[2] >= 3.0  # the lobe's peak node is inside


def test_nodes_that_are_not_significant_do_not_widen_the_crop():
    """With standard errors, a lobe above the fraction but with |ρ|/se < 1.96 is noise."""
    main = _blob(2.0, 0.0, 0.5, 0.8)
    lobe = 0.5 * _blob(6.0, 3.0, 0.5, 0.5)
    rr, ss = _rs()
    se = np.where(np.hypot(rr - 6.0, ss - 3.0) < 3.0, 1.0, 1e-3)  # the lobe: |ρ|/se <= 0.5
    assert forc_limits(_ident(main + lobe, se)) == forc_limits(_ident(main))
    kept = forc_limits(_ident(main + lobe, np.full_like(se, 1e-3)))
    assert kept[0] >= 6.0 and kept[2] >= 3.0


def test_the_crop_stays_within_the_evaluated_nodes():
    # a blob at the plane's corner: the margin would reach past the nodes, the crop stops there
    limits = forc_limits(_ident(_blob(9.0, 0.0, 1.0, 1.0)))
    rr, ss = _rs()
    evaluated = rr >= 0
    assert limits[0] == pytest.approx(rr[evaluated].max())
    assert limits[1] >= ss[evaluated].min() and limits[2] <= ss[evaluated].max()


def test_fraction_zero_and_too_few_shown_nodes_give_the_evaluated_extent():
    rr, ss = _rs()
    extent = (rr[rr >= 0].max(), ss[rr >= 0].min(), ss[rr >= 0].max())
    assert forc_limits(_ident(_blob(2.0, 0.0, 0.5, 0.8)), fraction=0.0) == pytest.approx(extent)
    single = np.where((np.abs(rr - 2.0) < 1e-9) & (np.abs(ss) < 1e-9), 1.0, 0.0)
    assert forc_limits(_ident(single)) == pytest.approx(extent)  # one node: no region to crop to


def test_a_region_one_node_thin_still_gets_a_crop_of_positive_size():
    """A ridge one node wide in s (sharper than the grid) has zero span in s: the crop must
    still show its nodes' cells (half a node pitch, Δ/2, on each side), not a zero-height
    window that matplotlib would replace by an arbitrary one."""
    rr, ss = _rs()
    ridge = np.where((np.abs(ss - 1.0) < 1e-9) & (rr >= 1.0) & (rr <= 3.0), 1.0, 0.0)
    bc_max, bu_lo, bu_hi = forc_limits(_ident(ridge))
    assert bu_lo <= 1.0 - STEP / 2 and bu_hi >= 1.0 + STEP / 2
    assert bc_max >= 3.0 + STEP / 2
    assert bu_hi - bu_lo < 10.0  # still a crop, not the whole plane


def test_without_smoothed_density_a_one_line_value_error():
    n = NODES.size
    ident = PreisachIdentification(
        alpha=NODES,
        beta=NODES,
        everett=np.zeros((n, n)),
        cell_mass=np.zeros((n - 1, n - 1)),
        step=STEP,
    )
    with pytest.raises(ValueError, match="smoothing"):
        forc_limits(ident)
