"""The layout fixes of issue 32's figure polish, on the smoke-size builds: fig:preis_dens's
r-s panels take the width and share one colour bar (one scale), fig:erf_10000 draws v and C·M
on separate axes, fig:N=2_schema shows its section points (every point drawn, markers)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from analysis.experiments.parameters import SIZES  # noqa: E402
from analysis.paper.context import PaperContext  # noqa: E402
from analysis.paper.figures_dynamics import fig_erf_10000, fig_n2_schema  # noqa: E402
from analysis.paper.figures_identification import fig_preis_dens  # noqa: E402


@pytest.fixture
def captured(tmp_path, monkeypatch):
    ctx = PaperContext(tmp_path, SIZES["smoke"])
    got = {}

    def keep(fig, label, data):
        got[label] = (fig, data)
        return []

    monkeypatch.setattr(ctx, "save_figure", keep)
    yield ctx, got
    for fig, _ in got.values():
        plt.close(fig)


def test_n2_schema_shows_every_section_point(captured):
    ctx, got = captured
    fig_n2_schema(ctx)
    fig, data = got["fig:N=2_schema"]
    (ax,) = fig.axes
    lines = [ln for ln in ax.get_lines() if ln.get_linestyle() == "None"]
    assert len(lines) == 2  # one marker set per sheet, no connecting line
    assert sum(len(ln.get_xdata()) for ln in lines) == len(data["q"])
    assert all(ln.get_markersize() >= 5 for ln in lines)
    lo, hi = ax.get_xlim()
    assert lo <= float(np.min(data["q"])) and float(np.max(data["q"])) <= hi


def test_erf_10000_puts_v_and_cm_on_separate_axes(captured):
    ctx, got = captured
    fig_erf_10000(ctx)
    fig, data = got["fig:erf_10000"]
    assert len(fig.axes) == 4
    top, bottom = fig.axes[0], fig.axes[2]  # subplots(2, 2): row-major
    assert top.get_ylabel() == "v" and bottom.get_ylabel().startswith("C·M")
    # the upper axes hold v only, the lower C·M = 4·M only
    traj_v = [ln for ln in top.get_lines() if len(ln.get_ydata()) == len(data["limit_traj_v"])]
    np.testing.assert_array_equal(traj_v[0].get_ydata(), data["limit_traj_v"])
    (cm,) = bottom.get_lines()
    np.testing.assert_allclose(cm.get_ydata(), 4.0 * data["limit_traj_M"])


def test_preis_dens_panels_share_one_colour_bar_and_the_width(captured):
    ctx, got = captured
    fig_preis_dens(ctx)
    fig, _ = got["fig:preis_dens"]
    panels = fig.axes[:3]
    bars = [ax for ax in fig.axes[3:] if ax.get_label() == "<colorbar>"]
    assert len(fig.axes) == 4 and len(bars) == 1  # one bar for (b) and (c)
    meshes = [ax.collections[0] for ax in panels[1:]]
    assert meshes[0].norm.vmin == meshes[1].norm.vmin
    assert meshes[0].norm.vmax == meshes[1].norm.vmax
    for ax in panels[1:]:
        assert ax.get_aspect() == "auto"  # fills its slot, not an equal-aspect strip
    assert panels[2].get_shared_y_axes().joined(panels[1], panels[2])
    assert "_" not in bars[0].get_ylabel().replace("_{", "")  # mathtext, no literal underscore
