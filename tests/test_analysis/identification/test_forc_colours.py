"""The FORC diagram's colour scale: FORCinel-like by default, white at ρ = 0, any matplotlib
map on request; B_c horizontal, B_u vertical."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from forc_synthetic import noisy_curves  # noqa: E402
from matplotlib.colors import TwoSlopeNorm  # noqa: E402
from matplotlib.contour import ContourSet  # noqa: E402
from scipy.stats import norm as normal  # noqa: E402

from analysis.identification import identify_from_curves  # noqa: E402
from analysis.identification.plots import (  # noqa: E402
    FORCINEL_NEGATIVE,
    colormap_name,
    forcinel_cmap,
    plot_forc_diagram,
)


def test_forcinel_scale_is_white_at_zero_blue_below_and_green_yellow_red_above():
    cmap = forcinel_cmap()
    norm = TwoSlopeNorm(vmin=-FORCINEL_NEGATIVE, vcenter=0.0, vmax=1.0)

    def rgb255(x):
        return np.round(np.array(cmap(norm(x))[:3]) * 255)

    # FORCinel's stops (Harrison & Feinberg 2008 as FORCsensei draws them), in RGB 0-255. The
    # map is a table of 1024 colours: a stop is read within half a table step, which on the
    # steepest segment (128 levels over 0.16 of the peak = 0.08 of the map) is < 1 level
    np.testing.assert_array_equal(rgb255(0.0), [255, 255, 255])
    np.testing.assert_array_equal(rgb255(0.02), [255, 255, 255])
    np.testing.assert_array_equal(rgb255(-0.02), [255, 255, 255])
    np.testing.assert_array_equal(rgb255(-FORCINEL_NEGATIVE), [127, 127, 255])  # light blue
    np.testing.assert_allclose(rgb255(0.19), [102, 178, 102], atol=1.0)  # green
    np.testing.assert_allclose(rgb255(0.48), [204, 204, 76], atol=1.0)  # yellow
    np.testing.assert_allclose(rgb255(0.64), [204, 76, 76], atol=1.0)  # red
    np.testing.assert_allclose(rgb255(1.0), [76, 25, 76], atol=1.0)  # dark purple at the peak


def test_forc_diagram_default_norm_and_orientation():
    ident = identify_from_curves(
        noisy_curves(np.random.default_rng(1), 1e-2, np.arange(-20.0, 21.0, 1.0)),
        smoothing=3.0,
        extend=False,
    )
    fig, ax = plt.subplots()
    try:
        mappable = plot_forc_diagram(ax, ident)
        rho = ident.density_alpha_beta
        norm = mappable.norm
        assert isinstance(norm, TwoSlopeNorm) and norm.vcenter == 0.0
        assert norm.vmax == pytest.approx(np.nanmax(rho), rel=1e-12)
        assert norm.vmin == pytest.approx(
            -max(-np.nanmin(rho), FORCINEL_NEGATIVE * np.nanmax(rho)), rel=1e-12
        )
        assert ax.get_xlabel().startswith("$B_c$") and ax.get_ylabel().startswith("$B_u$")
        other = plot_forc_diagram(ax, ident, cmap="viridis")
        assert other.get_cmap().name == "viridis"
    finally:
        plt.close(fig)


def test_colormap_names():
    assert colormap_name("forcinel") == "forcinel" and colormap_name("magma") == "magma"
    with pytest.raises(ValueError, match="not a matplotlib colour map"):
        colormap_name("no-such-map")


def test_significance_is_one_dashed_contour_line_not_hatching():
    # issue 32: significance as a contour line (FORCinel / FORCsensei), not hatching over the
    # noise. The level is the two-sided 95 % normal quantile |ρ|/se = 1.96
    ident = identify_from_curves(
        noisy_curves(np.random.default_rng(1), 5e-2, np.arange(-20.0, 21.0, 1.0)),
        smoothing=3.0,
        extend=False,
        uncertainty=True,
    )
    assert ident.density_se is not None
    fig, ax = plt.subplots()
    try:
        plot_forc_diagram(ax, ident)
        sets = [c for c in ax.get_children() if isinstance(c, ContourSet)]
        sig = [c for c in sets if len(c.levels) == 1 and c.levels[0] > 1.0]
        assert len(sig) == 1, [list(c.levels) for c in sets]
        assert sig[0].levels[0] == pytest.approx(normal.ppf(0.975), rel=1e-12)
        assert sig[0].get_linestyle()[0][1] is not None  # dashed, not solid
        assert sig[0].get_paths() and any(len(p.vertices) for p in sig[0].get_paths())
        # nothing hatched anywhere on the axes
        assert not any(getattr(c, "get_hatch", lambda: None)() for c in ax.get_children())
        legend = ax.get_legend()
        assert [t.get_text() for t in legend.get_texts()] == ["95 % significance"]
    finally:
        plt.close(fig)
