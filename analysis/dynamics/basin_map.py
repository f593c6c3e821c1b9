"""The grid of starts and the result of a basin map (:func:`analysis.dynamics.basins.basins`):
per-start labels and transient lengths, the attractors with their fractions, JSON, ``.npz`` and
the figure."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hysteresis._validation import MAX_MAGNITUDE, bounded_work, finite_scalar, positive_integer
from oscillators import DEFAULT_V0

__all__ = ["BasinGrid", "BasinMap", "MAX_STARTS"]

#: most starts of one basin map
MAX_STARTS = 10_000_000


@dataclass(frozen=True)
class BasinGrid:
    """An ``size × size`` grid of starts: q0 along x, and v0 (``axis="v0"``) or the play's
    wagon position w0 (``axis="w0"``, with the fixed velocity ``v0``) along y.

    :meth:`starts` lists them row by row (y outer, q0 inner): ``labels.reshape(size, size)``
    is the map with y along the rows.
    """

    q0_range: tuple[float, float]
    y_range: tuple[float, float]
    size: int
    axis: str = "v0"
    v0: float = DEFAULT_V0

    def __post_init__(self) -> None:
        positive_integer(self.size, "size", minimum=2)
        bounded_work(self.size * self.size, "size", MAX_STARTS, "starts")
        if self.axis not in ("v0", "w0"):
            raise ValueError(f"axis must be 'v0' or 'w0', got {self.axis!r}")
        for name, rng in (("q0_range", self.q0_range), (f"{self.axis}_range", self.y_range)):
            lo, hi = (finite_scalar(x, name, MAX_MAGNITUDE) for x in rng)
            if not lo < hi:
                raise ValueError(f"{name} must be (low, high) with low < high, got {rng}")
        finite_scalar(self.v0, "v0", MAX_MAGNITUDE)

    @property
    def q0_values(self) -> np.ndarray:
        return np.linspace(*self.q0_range, self.size)

    @property
    def y_values(self) -> np.ndarray:
        return np.linspace(*self.y_range, self.size)

    def starts(self) -> np.ndarray:
        """Rows ``(q0, v0, w0)``; ``w0`` is nan (default memory) on a (q0, v0) grid."""
        q, y = np.meshgrid(self.q0_values, self.y_values)
        if self.axis == "v0":
            return np.column_stack([q.ravel(), y.ravel(), np.full(q.size, np.nan)])
        return np.column_stack([q.ravel(), np.full(q.size, float(self.v0)), y.ravel()])

    def to_dict(self) -> dict:
        return {
            "q0_range": list(self.q0_range),
            f"{self.axis}_range": list(self.y_range),
            "size": self.size,
            "axis": self.axis,
            **({"v0": self.v0} if self.axis == "w0" else {}),
        }


@dataclass(frozen=True)
class BasinMap:
    """Per-start labels and the attractors they reach.

    ``labels[i]`` is the index into :attr:`attractors` (−1: no state); ``transients[i]`` the
    forcing periods before start i stayed within the tolerance of its cycle (−1 unless
    periodic). Each attractor is a dict with ``label``, ``kind`` (``periodic``, ``chaotic``,
    ``aperiodic``, ``divergent``, ``undecided``), ``count``, ``fraction``, ``interval`` (95 %
    Wilson score interval) and what it is (period, points, multipliers; or λ_max with its
    error and D_KY); ``transient_median``/``transient_max`` for periodic ones.
    """

    starts: np.ndarray
    labels: np.ndarray
    transients: np.ndarray
    periods: np.ndarray
    attractors: list[dict]
    grid: BasinGrid | None = None
    settings: dict = field(default_factory=dict)
    #: wall times: ``sections_s`` (the tasks: every start's section run, or the recurrence
    #: mapper) and ``attractors_s`` (labelling: the refinements and Lyapunov runs once per
    #: attractor)
    timings: dict = field(default_factory=dict)
    #: ``recurrences`` only: the forcing periods each start was integrated before its label
    #: was known (after the transient)
    steps: np.ndarray | None = None

    def label_grid(self) -> np.ndarray:
        """``labels`` as the ``size × size`` map (y along rows); grids only."""
        if self.grid is None:
            raise ValueError("label_grid needs a BasinGrid (the starts were a list)")
        return self.labels.reshape(self.grid.size, self.grid.size)

    def to_dict(self) -> dict:
        """JSON-ready summary (attractors with complex multipliers as [re, im] pairs)."""
        out = []
        for a in self.attractors:
            rec = {}
            for k, v in a.items():
                if k == "multipliers":
                    rec[k] = [[float(m.real), float(m.imag)] for m in np.asarray(v)]
                elif isinstance(v, np.ndarray):
                    rec[k] = v.tolist()
                else:
                    rec[k] = v
            out.append(rec)
        return {
            "starts": int(self.labels.size),
            "valid_starts": int(np.count_nonzero(self.labels >= 0)),
            **({"grid": self.grid.to_dict()} if self.grid is not None else {}),
            **self.settings,
            "attractors": out,
        }

    def save(self, path: str | Path) -> Path:
        """Per-start arrays to an ``.npz``: starts, labels, transients, periods (+ the grid, and
        ``steps`` of the recurrence mapper)."""
        path = Path(path)
        extra = {} if self.steps is None else {"steps": self.steps}
        if self.grid is not None:
            extra.update(q0_values=self.grid.q0_values, y_values=self.grid.y_values)
            extra["label_grid"] = self.label_grid()
        np.savez_compressed(
            path,
            starts=self.starts,
            labels=self.labels,
            transients=self.transients,
            periods=self.periods,
            **extra,
        )
        return path

    def plot(self, path: str | Path, title: str | None = None) -> Path:
        """The basin map coloured by attractor (grids; a list: its starts as points) and, for a
        grid, a second panel with each start's transient length (``sections``) or the periods
        the recurrence mapper integrated it (``recurrences``). Drawn on a
        :class:`matplotlib.figure.Figure` (no pyplot, no backend change)."""
        from matplotlib import colormaps
        from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm
        from matplotlib.figure import Figure
        from matplotlib.patches import Patch

        n = len(self.attractors)
        base = colormaps["tab10" if n <= 10 else "tab20"]
        colours = ["white"] + [base(i % base.N) for i in range(n)]
        cmap = ListedColormap(colours)
        norm = BoundaryNorm(np.arange(-1.5, n + 0.5), cmap.N)
        second, second_label = None, ""
        if self.grid is not None and np.any(self.transients >= 0):
            second = np.ma.masked_less(self.transients.astype(float), 0)
            second_label = "periods until the section repeats within the tolerance"
        elif self.grid is not None and self.steps is not None:
            second = np.ma.masked_where(self.labels < 0, self.steps.astype(float))
            second_label = "periods integrated until the label was known (recurrences)"
        fig = Figure(figsize=(12 if second is not None else 6.5, 5))
        axes = fig.subplots(1, 2 if second is not None else 1)
        axes = np.atleast_1d(axes)
        ax = axes[0]
        if self.grid is not None:
            g = self.grid
            extent = (*g.q0_range, *g.y_range)
            ax.imshow(
                self.label_grid(),
                origin="lower",
                extent=extent,
                aspect="auto",
                cmap=cmap,
                norm=norm,
                interpolation="nearest",
            )
            for a in axes:
                a.set_ylabel("$w_0$" if g.axis == "w0" else "$v_0$")
                a.set_xlabel("$q_0$")
        else:
            ax.scatter(self.starts[:, 0], self.starts[:, 1], c=self.labels, cmap=cmap, norm=norm)
            ax.set_ylabel("$v_0$")
            ax.set_xlabel("$q_0$")
        if self.grid is None or self.grid.axis == "v0":  # the map's plane is the section's
            limits = ax.get_xlim(), ax.get_ylim()
            for a in self.attractors:
                pts = _section_points(a)
                if pts is not None:
                    colour = colours[a["label"] + 1]
                    ax.plot(pts[:, 0], pts[:, 1], "o", ms=5, mfc=colour, mec="black", mew=0.8)
            if self.grid is not None:  # a point outside the grid does not move its frame
                ax.set_xlim(*limits[0])
                ax.set_ylim(*limits[1])
        handles = [
            Patch(color=colours[a["label"] + 1], label=text)
            for a, text in zip(self.attractors, legend_texts(self.attractors), strict=True)
        ]
        ax.legend(handles=handles, fontsize=7, loc="upper right", framealpha=0.8)
        if second is not None:
            t = second.reshape(g.size, g.size)
            im = axes[1].imshow(
                t + 1.0,
                origin="lower",
                extent=extent,
                aspect="auto",
                cmap="viridis",
                norm=LogNorm(vmin=1.0, vmax=max(2.0, float(t.max()) + 1.0)),
                interpolation="nearest",
            )
            fig.colorbar(im, ax=axes[1], label="periods + 1")
            axes[1].set_title(second_label, fontsize=8)
        if title:
            ax.set_title(title, fontsize=8)
        fig.tight_layout()
        fig.savefig(path, dpi=150)
        return Path(path)


def _section_points(a: dict) -> np.ndarray | None:
    """An attractor's section points ``(q, v)`` (periodic ones), else None."""
    pts = a.get("points")
    if pts is None:
        return None
    pts = np.asarray(pts, dtype=float)
    return pts[:, :2] if pts.ndim == 2 and pts.shape[1] >= 2 and len(pts) else None


def legend_texts(attractors: list[dict]) -> list[str]:
    """One legend line per attractor. Lines that would read alike (symmetric partner orbits
    ``−x(t + T/2)`` of an odd operator share period and, often, fraction) name a point of
    each orbit's section, the one of least q, so the legend tells them apart (the map marks
    the points)."""
    plain = [_legend(a) for a in attractors]
    texts = list(plain)
    for i, a in enumerate(attractors):
        pts = _section_points(a)
        if pts is not None and plain.count(plain[i]) > 1:
            q, v = pts[int(np.argmin(pts[:, 0]))]
            texts[i] = texts[i].replace(" (", f" through (q, v) = ({q:.2f}, {v:.2f}) (", 1)
    return texts


def _legend(a: dict) -> str:
    frac = f"{100 * a['fraction']:.1f} %"
    if a["kind"] == "periodic":
        return f"period {a['period']} ({frac})"
    if a["kind"] in ("chaotic", "aperiodic"):
        return f"{a['kind']}, λ = {a['max_exponent']:.3f} ({frac})"
    return f"{a['kind']} ({frac})"
