"""Issue 32: a basin map's legend tells symmetric partner orbits apart (same period, same
fraction) by a point of each orbit's section, which the map marks."""

from __future__ import annotations

import numpy as np

from analysis.dynamics.basin_map import BasinGrid, BasinMap, legend_texts


def _partners() -> list[dict]:
    # an orbit and its partner -x(t + T/2): the same period and share of the starts
    a = np.array([[1.2, 0.4, 1.0], [-0.3, 2.0, 1.0]])
    b = np.array([[-1.5, -0.2, -1.0], [0.7, -1.1, -1.0]])
    common = {"kind": "periodic", "period": 2, "fraction": 0.5, "count": 8}
    return [{"label": 0, "points": a, **common}, {"label": 1, "points": b, **common}]


def test_partner_orbits_read_apart_by_their_least_q_point():
    texts = legend_texts(_partners())
    assert texts[0] != texts[1]
    assert texts[0] == "period 2 through (q, v) = (-0.30, 2.00) (50.0 %)"
    assert texts[1] == "period 2 through (q, v) = (-1.50, -0.20) (50.0 %)"


def test_distinct_legends_stay_as_they_were():
    a, b = _partners()
    b = {**b, "period": 4}
    assert legend_texts([a, b]) == ["period 2 (50.0 %)", "period 4 (50.0 %)"]
    chaotic = {"label": 2, "kind": "chaotic", "max_exponent": 0.11, "fraction": 0.25}
    assert legend_texts([chaotic])[0] == "chaotic, λ = 0.110 (25.0 %)"


def test_the_map_marks_the_section_points(tmp_path):
    grid = BasinGrid((-2.0, 2.0), (-2.0, 2.0), 4)
    labels = np.repeat([0, 1], 8).astype(np.int32)
    out = BasinMap(
        starts=grid.starts(),
        labels=labels,
        transients=np.full(16, -1),
        periods=np.full(16, 2),
        attractors=_partners(),
        grid=grid,
    ).plot(tmp_path / "map.png")
    assert out.stat().st_size > 0
