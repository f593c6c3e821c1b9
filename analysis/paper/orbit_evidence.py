"""Periodic-orbit evidence for the report's Discussion: the orbits behind the
disputed windows, their Floquet multipliers, and where continuation finds them born and dying.

* the erf-play limit's periodic window at C = 3.80–3.88: the orbit at C = 3.85 continued up and
  down (pseudo-arclength);
* C = 1.7–1.8: the orbits that fresh starts from the paper's initial condition reach at
  C = 1.70, 1.75, 1.80, each continued across the interval;
* the N = 2 cascade onset (dimer b = (1, −1)): the period-1 orbit without switching continued
  downward from C = 9.5; its end is a grazing located by bisection, against the closed form
  1/(2ζ) + β = 9.

:func:`orbit_evidence` computes the numbers (about 15 s); :func:`orbit_lines` formats them as
Markdown lines that :func:`analysis.paper.runner.write_report` appends to the Discussion.
"""

from __future__ import annotations

from typing import Any

from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.periodic_orbits import OrbitNotFoundError, find_periodic_orbit
from analysis.dynamics.stable_range import stable_range
from analysis.experiments.models import build_operator
from analysis.experiments.parameters import DAMPING_RATIO
from oscillators import ForcedOscillator

__all__ = ["orbit_evidence", "orbit_lines"]

#: the N = 2 dimer's lower threshold and the closed-form onset 1/(2ζ) + β
_BETA = -1.0
CASCADE_CLOSED_FORM = 1.0 / (2.0 * DAMPING_RATIO) + _BETA


def _orbit_record(orbit: Any) -> dict[str, Any]:
    return {
        "period": orbit.period,
        "multipliers_abs": [float(abs(m)) for m in orbit.multipliers],
        "multipliers": [[float(m.real), float(m.imag)] for m in orbit.multipliers],
        "stable": bool(orbit.stable),
        "residual": float(orbit.residual),
    }


def _window(system: ForcedOscillator, c0: float, lo: float, hi: float) -> dict[str, Any]:
    try:
        orbit = find_periodic_orbit(system)
    except OrbitNotFoundError as exc:
        return {"coupling": c0, "orbit": None, "why": str(exc)}
    rec: dict[str, Any] = {"coupling": c0, "orbit": _orbit_record(orbit)}
    for key, stop in (("up", hi), ("down", lo)):
        # the erf play is odd: every orbit has a partner −x(t + T/2), whose branch a fold can
        # lead onto (the window's lower fold at C = 3.7575 does)
        branch = continue_orbit(system, orbit, c0, stop, step=0.005, max_points=150, symmetric=True)
        rec[key] = stable_range(branch, stop - c0).to_record()
    return rec


def orbit_evidence() -> dict[str, Any]:
    """The numbers of the module docstring, JSON-ready."""
    erf = build_operator("erf-play")
    out: dict[str, Any] = {
        "window_3_8": _window(ForcedOscillator(erf, 3.85), 3.85, 3.74, 3.90),
        "window_1_7": [
            _window(ForcedOscillator(erf, c), c, 1.65, 1.85) for c in (1.70, 1.75, 1.80)
        ],
    }
    pair = ForcedOscillator(build_operator("dimers", fields=[[1.0, -1.0]]), 9.5)
    orbit = find_periodic_orbit(pair, max_period=4)
    branch = continue_orbit(pair, orbit, 9.5, 8.99, step=0.05, max_period=4, transient=50)
    graze = next((e for e in branch.events if e.kind == "grazing"), None)
    out["cascade_onset"] = {
        "closed_form": CASCADE_CLOSED_FORM,
        "continuation": float(graze.parameter) if graze else None,
        "bracket": list(graze.bracket) if graze else None,
        "difference": float(graze.parameter - CASCADE_CLOSED_FORM) if graze else None,
    }
    return out


def _range_text(r: dict[str, Any], direction: str) -> str:
    text = f"stable {direction} to C = {r['extreme_stable_parameter']:.6f}"
    if r["event_parameter"] is not None:
        text += (
            f", lost at a {r['ended_by']} at C = {r['event_parameter']:.8f} (max |μ| = "
            f"{r['event_max_abs_multiplier']:.4f})"
        )
    events = ", ".join(f"{k} {c:.8f}" for k, c in r["events"]) or "none"
    return text + f" [events in order: {events}; {r['stop_reason']}]"


def _window_text(rec: dict[str, Any]) -> str:
    c = rec["coupling"]
    if rec["orbit"] is None:
        return f"C = {c}: no periodic orbit of period <= 64 after 100 periods (chaotic start)."
    o = rec["orbit"]
    mu = ", ".join(f"{m:.4g}" for m in o["multipliers_abs"])
    return (
        f"C = {c}: period {o['period']}, |μ| = ({mu}), {'stable' if o['stable'] else 'unstable'}"
        f"; {_range_text(rec['up'], 'upward')}; {_range_text(rec['down'], 'downward')}."
    )


def orbit_lines(evidence: dict[str, Any]) -> list[str]:
    """Markdown lines of the Discussion's periodic-orbit subsection."""
    onset = evidence["cascade_onset"]
    lines = [
        "### Periodic orbits behind the disputed windows (Newton + continuation)",
        "",
        "Orbits refined by Newton on the k-th stroboscopic map with the exact Jacobian "
        "(saltations, memory rows; residual <= 1e-10), multipliers on (q, v, w), the wagon's "
        "exactly 0 (reset at a wall hit); continued in C with folds (a multiplier through +1), "
        "period doublings (through −1) and grazings (the switching sequence changes) located "
        "to 1e-8.",
        "",
        "- **erf play, window C = 3.80–3.88:** " + _window_text(evidence["window_3_8"]),
        "- **erf play, C = 1.7–1.8 (fresh starts from the paper's initial condition):** "
        + " ".join(_window_text(r) for r in evidence["window_1_7"]),
    ]
    if onset["continuation"] is not None:
        lines.append(
            f"- **N = 2 cascade onset:** the period-1 orbit without switching ends at a grazing "
            f"at C = {onset['continuation']:.10f} (bracket {onset['bracket'][0]:.10f}–"
            f"{onset['bracket'][1]:.10f}), closed form 1/(2ζ) + β = {onset['closed_form']:g} "
            f"(difference {onset['difference']:.1e}); the sweep's 9.008 is its grid step."
        )
    return [*lines, ""]
