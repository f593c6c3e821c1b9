"""``hyst paper``: regenerate every computational figure and quantitative claim of the paper.

Each figure builder takes a :class:`~analysis.paper.context.PaperContext`, writes its PNG, PDF
and ``.npz`` data, and returns the :class:`~analysis.paper.context.Claim` objects it checked.
:func:`run_paper` runs them in order and writes ``report.md`` and ``report.json``.
"""

from analysis.paper.context import SIZES, Claim, FigureSpec, PaperContext, RunSize
from analysis.paper.runner import FIGURES, run_paper

__all__ = ["FIGURES", "SIZES", "Claim", "FigureSpec", "PaperContext", "RunSize", "run_paper"]
