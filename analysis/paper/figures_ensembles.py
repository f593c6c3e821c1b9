"""Figures of bifurcations and disorder ensembles: fig:bif_0, fig:bif, fig:dim, fig:sap, fig:mag,
fig:mag_his.

Every long computation is an independent task run through
:func:`analysis.experiments.execution.run_tasks` (process pool or Dask, results store, resume):

* a bifurcation sweep with continuation is sequential in C, so one sweep is one task
  (:func:`bifurcation_task`); the sweeps of one figure run in parallel;
* an ensemble is one task per (N, C, realization)
  (:func:`analysis.experiments.ensemble.ensemble_task`); the limit values one task per C
  (:func:`limit_dimension_task`); the iid reference one task
  per (N, realization) (:func:`analysis.experiments.iid.iid_task`).

fig:dim, fig:sap, fig:mag and fig:mag_his share one ensemble computation: it is computed by the
first of them that runs and cached for the others (module-level, keyed by output directory,
run size and seed); with a results store a second ``hyst paper`` run reads it back.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from analysis.experiments.parameters import (
    DAMPING_RATIO,
    DEFAULT_Q0,
    ENSEMBLE_COUPLINGS,
    FREQUENCY,
    PAPER_LARGEST_N,
    PAPER_REGULAR_FRACTION,
    SPIN_COUPLING,
    SPREAD,
    V0,
    WIDTH,
)
from analysis.paper import decisions as dec
from analysis.paper.context import (
    AGREE,
    DISAGREE,
    INCONCLUSIVE,
    Claim,
    FigureSpec,
    PaperContext,
    reading,
    verdict,
)

__all__ = ["FIGURES", "bifurcation_task", "limit_dimension_task"]

#: minimum number of grid values of C inside a window of fig:bif for its claim to be decided
MIN_WINDOW_VALUES = 3
#: fig:bif_0 cascade: the grazing value C = 1/(2ζ) + β = 10 − 1 = 9 (period-1 orbit with
#: amplitude 1/(2ζ) around q = C touches the down threshold β = −1 of the dimer b = (1, −1))
CASCADE_ZOOM = (9.3, 7.0)


# ---------------------------------------------------------------------------------------------
# task functions (top level: picklable for process pools and Dask)
# ---------------------------------------------------------------------------------------------


def _make_operator(kind: str, spins: int, seed: int):
    """The operator of a task ``kind``: ``"dimer_pair"`` (fig:bif_0's dimer b = (1, -1)) or a
    model name of :mod:`analysis.experiments.models` (``"dimers"``, ``"erf-play"``) at the paper's
    parameters."""
    from analysis.experiments.models import MODELS, build_operator, canonical_model_name

    params = dict(width=WIDTH, spread=SPREAD, spin_coupling=SPIN_COUPLING)
    if kind == "dimer_pair":  # fig:bif_0: one dimer, b = (1, -1), J = 2
        return build_operator("dimers", fields=[[1.0, -1.0]], **params)
    if kind == "erf_play" or kind in MODELS:
        kind = canonical_model_name(kind)
    if kind == "dimers":
        return build_operator("dimers", spins=spins, seed=seed, **params)
    if kind == "erf-play":
        return build_operator("erf-play", **params)
    raise ValueError(f"kind must be 'dimer_pair', 'dimers' or 'erf-play', got {kind!r}")


def bifurcation_task(
    kind: str,
    c_start: float,
    c_stop: float,
    n_values: int,
    n_periods: int,
    transient: int,
    lyapunov_t: float,
    spins: int = 2,
    seed: int = 0,
) -> dict:
    """One continuation sweep ``C = linspace(c_start, c_stop, n_values)`` (in that order).

    ``kind``: ``"dimer_pair"`` (b = (1, −1), J = 2), ``"dimers"`` (``SpinDimerEnsemble.random
    (spins, 2, 1, 2, seed)``) or ``"erf-play"`` (the limit). Returns the Poincaré points q, v
    (n_values × n_periods), the spectra, λ_max and the orbit period per C (0: none found).
    """
    from analysis.dynamics.bifurcation import bifurcation_diagram, section_period
    from oscillators import ForcedOscillator

    operator = _make_operator(kind, spins, seed)
    values = np.linspace(c_start, c_stop, int(n_values))
    bd = bifurcation_diagram(
        lambda c: ForcedOscillator(operator, c, DAMPING_RATIO, FREQUENCY),
        values,
        n_periods=n_periods,
        transient_periods=transient,
        continuation=True,
        lyapunov=True,
        lyapunov_t_end=lyapunov_t,
        q0=DEFAULT_Q0,
        v0=V0,
        progress=False,
    )
    periods = [section_period(bd.q[i], bd.v[i], 1e-6) for i in range(values.size)]
    return {
        "couplings": values,
        "q": bd.q,
        "v": bd.v,
        "max_exponent": bd.max_exponent,
        "exponents": bd.exponents,
        "period": np.array(periods, dtype=int),
    }


def limit_dimension_task(
    coupling: float, t_end: float, transient: float, section_periods: int, section_transient: int
) -> dict:
    """D_KY (Lyapunov spectrum over [transient, t_end]) and D_BC (box counting of the Poincaré
    section (q, v), ``section_periods`` points after ``section_transient`` periods) of the
    erf-play limit at coupling C, from the paper's initial condition (w0 = q0 − p/2)."""
    from analysis.dynamics.dimensions import box_counting_dimension
    from analysis.dynamics.lyapunov import lyapunov_spectrum
    from oscillators import ForcedOscillator

    system = ForcedOscillator(_make_operator("erf-play", 0, 0), coupling, DAMPING_RATIO, FREQUENCY)
    ly = lyapunov_spectrum(system, t_end, transient, DEFAULT_Q0, V0, progress=False)
    sec = system.poincare_section(int(section_periods), int(section_transient), DEFAULT_Q0, V0)
    try:
        bc = box_counting_dimension(np.column_stack([sec.q, sec.v]))
        d_bc, d_bc_err = float(bc.dimension), float(bc.stderr)
    except ValueError:  # too few points for a scaling region (smoke sizes)
        d_bc, d_bc_err = float("nan"), float("nan")
    return {
        "exponents": np.asarray(ly.exponents, dtype=float),
        "kaplan_yorke": float(ly.kaplan_yorke),
        "box_counting": d_bc,
        "box_counting_stderr": d_bc_err,
        "section_points": int(sec.q.size),
    }


def _fmt(x: float, digits: int = 3) -> str:
    return "nan" if not np.isfinite(x) else f"{x:.{digits}f}"


# ---------------------------------------------------------------------------------------------
# fig:bif_0
# ---------------------------------------------------------------------------------------------


def _cascade_claim(zoom: dict, n_periods: int, run: str) -> Claim:
    """Onset of the period-adding cascade and the periods below it (zoomed sweep)."""
    cs = np.asarray(zoom["couplings"])
    per = np.asarray(zoom["period"])
    no_switch = np.nonzero(per == 1)[0]
    # the onset: between the last C (coming from above) still on the period-1 orbit and the next
    first = int(np.argmax(per != 1)) if np.any(per != 1) else cs.size
    onset = 0.5 * (cs[first - 1] + cs[first]) if 0 < first < cs.size else float("nan")
    below = [(float(c), int(p)) for c, p in zip(cs[first:], per[first:], strict=True)]
    # periodic windows in sweep order (C decreasing); "wide" ones hold for >= 2 successive C
    windows: list[list[int]] = []  # [period, number of successive C]
    for _, p in below:
        if windows and windows[-1][0] == p:
            windows[-1][1] += 1
        else:
            windows.append([p, 1])
    wide = [p for p, count in windows if p > 1 and count >= 2]
    steps = np.diff(wide) if len(wide) > 1 else np.array([], dtype=int)
    # period-adding: the periods of the periodic windows fall monotonically as C moves away from
    # the onset (grow without bound as C -> onset), by small steps
    # (period 0: none up to n/2 found, i.e. longer, or chaos)
    long_near_onset = any(p == 0 or p >= 20 for _, p in below[:5])
    adding = bool(len(wide) >= 3 and np.all(steps < 0) and np.all(steps >= -2) and long_near_onset)
    narrow = [p for p, count in windows if p > 1 and count < 2]
    seq = ", ".join(f"{c:.2f}:{p if p else f'>{n_periods // 2}'}" for c, p in below[:10])
    step = float(abs(cs[1] - cs[0])) if cs.size > 1 else float("inf")
    outcome = cascade_verdict(onset, step, adding, len(below), int(per[0]) if per.size else 0)
    return Claim(
        claim="N=2, b=(1,-1): coming from large C, a period-adding cascade starts at C ≈ 9 "
        "(verdict: onset within 0.25 of 9; periods >= 20 right below the onset; the periods of "
        "successive windows (>= 2 grid values wide) fall monotonically by 1 or 2 as C decreases)",
        paper="period-adding cascade at C = 9 (theory: 1/(2ζ) + β = 9)",
        measured=f"period-1 orbit (no switch) down to C="
        f"{cs[no_switch[-1]] if no_switch.size else float('nan'):.3f}; onset C≈"
        f"{_fmt(onset)}; periodic windows (>= 2 successive C) in sweep order {wide} "
        f"(steps {sorted(set(steps.tolist()))}); narrow windows between them {narrow}; "
        f"C:period {seq}",
        run=run,
        verdict=outcome,
        evidence=f"zoom grid step ΔC = {step:.3f}: the onset is known to ±{0.5 * step:.3f} "
        f"against the tolerance 0.25; {len(below)} grid values below the onset (all if none "
        f"found; three windows of >= 2 values need >= {2 * CASCADE_MIN_WINDOWS}); "
        f"{len(wide)} wide windows found; "
        f"periods are resolved up to {n_periods // 2} forcing periods ({n_periods} section "
        "points per C)",
        explanation=reading(outcome, disagree=CASCADE_DISAGREE, inconclusive=CASCADE_INCONCLUSIVE),
    )


#: the period-adding test needs this many wide (>= 2 grid values) windows
CASCADE_MIN_WINDOWS = 3
CASCADE_DISAGREE = (
    "The closed-form grazing value 1/(2ζ) + β = 9 is where the period-1 orbit without switching "
    "(amplitude 1/(2ζ) around q = C) touches the dimer's down threshold β = −1; the quick and "
    "full runs locate the onset at C ≈ 9.008. A disagreement therefore points at the sweep: too "
    "few section points to resolve the long periods right below the onset (a period above half "
    "the section length counts as unresolved), or transients, which grow near the onset, longer "
    "than the run's."
)
CASCADE_INCONCLUSIVE = (
    "The zoomed sweep is too coarse to place the onset within the tolerance, or holds too few "
    "values of C below it to show three successive periodic windows; a larger run size "
    "(more couplings, longer sections) decides it."
)


def cascade_verdict(
    onset: float, step: float, adding: bool, values_below: int, first_period: int = 1
) -> str:
    """Verdict of the fig:bif_0 cascade claim: the onset within 0.25 of C = 9 (known to ± half
    the grid step, :func:`~analysis.paper.decisions.onset_within`) and period adding below it;
    the absence of period adding decides only if the grid holds enough values below the onset
    for three windows of two values. A sweep whose first value (above the onset) has no
    resolved period (``first_period == 0``) never saw the period-1 orbit: no onset can be
    placed, which is inconclusive, not a disagreement."""
    if not np.isfinite(onset) and first_period == 0:
        return INCONCLUSIVE
    if adding:
        adding_outcome = AGREE
    elif values_below < 2 * CASCADE_MIN_WINDOWS:
        adding_outcome = INCONCLUSIVE
    else:
        adding_outcome = DISAGREE
    return dec.combine(dec.onset_within(onset, 9.0, 0.25, step), adding_outcome)


def _regular_claims(main: dict, run: str) -> list[Claim]:
    zeta = DAMPING_RATIO
    exps = np.asarray(main["exponents"])
    per = np.asarray(main["period"])
    total = exps.sum(axis=1)
    sum_err = float(np.nanmax(np.abs(total + 2 * zeta)))
    periodic = per > 0
    dev = np.nanmax(np.abs(exps + zeta), axis=1)
    close = dev <= 0.005
    n_per = int(np.sum(periodic))
    n_close = int(np.sum(close & periodic))
    only_p1 = periodic & (per == 1)
    worst = int(np.nanargmax(np.where(periodic, dev, -np.inf))) if n_per else 0
    cs = np.asarray(main["couplings"])
    regular_outcome = (
        verdict(n_close >= 0.9 * n_per) if n_per > 0 else INCONCLUSIVE
    )  # no periodic C in the sweep: nothing to test the claim on
    return [
        Claim(
            claim="N=2: the exponents in the section (q, v) sum to the phase-space contraction "
            "-2ζ at every C (regular or chaotic)",
            paper="Σλ = ∇·F = -2ζ = -0.1",
            measured=f"max |λ1+λ2+2ζ| = {sum_err:.1e} over {cs.size} values of C",
            run=run,
            verdict=verdict(sum_err < 1e-6),
            evidence=f"{cs.size} values of C, exponents from the tangent flow over the run's λ "
            "time; the sum is an identity of the flow, independent of run length",
            explanation=reading(
                verdict(sum_err < 1e-6),
                disagree="The sum of the exponents is the phase-space contraction rate, an "
                "identity of the linear flow between switches (a switch changes only the "
                "acceleration, so its saltation matrix has determinant 1); a violation is a "
                "defect of the tangent integration, not physics.",
            ),
        ),
        Claim(
            claim="N=2: regular (periodic) behaviour gives λ = (0, -ζ, -ζ), i.e. λ1 = λ2 = -ζ in "
            "the section (within 0.005)",
            paper="λ1 = 0, λ2 = λ3 = -ζ = -0.05 for regular behaviour",
            measured=f"{n_close} of {n_per} periodic C have both within 0.005 of -ζ "
            f"(all {int(np.sum(only_p1))} period-1 orbits without switching do); worst C="
            f"{cs[worst]:.3f} (period {per[worst]}): λ = ({exps[worst, 0]:.4f}, "
            f"{exps[worst, 1]:.4f})",
            run=run,
            verdict=regular_outcome,
            evidence=f"{n_per} of {cs.size} values of C periodic (period detected up to "
            f"{np.asarray(main['q']).shape[1] // 2} forcing periods), "
            f"{int(np.sum(only_p1))} of them period-1 without switching; criterion: >= 90 % "
            "within 0.005 of -ζ",
            explanation=reading(
                regular_outcome,
                disagree="Periodic orbits that switch have real Floquet multipliers of different "
                "modulus, so λ1 ≠ λ2 while their sum stays −2ζ; the paper's λ = (0, −ζ, −ζ) "
                "holds for orbits whose multipliers are a complex pair (the period-1 orbit "
                "without switching, a damped linear oscillator).",
                inconclusive="No value of C in this sweep gave a detected periodic orbit, so "
                "the statement about regular behaviour has nothing to be tested on.",
            ),
        ),
    ]


def fig_bif_0(ctx: PaperContext) -> list[Claim]:
    """Paper fig:bif_0: bifurcation diagram of one dimer (b = (1, −1), J = 2) vs C."""
    import matplotlib.pyplot as plt

    s = ctx.size
    c_lo, c_hi = s.bif0_c_range
    base = {"kind": "dimer_pair", "spins": 2, "seed": 0}
    main_task = {
        **base,
        "c_start": float(c_hi),
        "c_stop": float(c_lo),
        "n_values": int(s.bif0_couplings),
        "n_periods": int(s.bif0_periods),
        "transient": int(s.bif0_transient),
        "lyapunov_t": float(s.bif0_lyapunov_t),
    }
    # a finer sweep through the cascade onset with longer sections, to resolve long periods
    zoom_periods = 5 * int(s.bif0_periods)
    zoom_task = {
        **base,
        "c_start": CASCADE_ZOOM[0],
        "c_stop": CASCADE_ZOOM[1],
        "n_values": max(int(s.bif0_couplings) // 2, 8),
        "n_periods": zoom_periods,
        "transient": 2 * int(s.bif0_transient),
        "lyapunov_t": float(s.bif0_lyapunov_t),
    }
    main, zoom = ctx.run("paper-bif0", [main_task, zoom_task], bifurcation_task)

    cs = np.asarray(main["couplings"])
    q = np.asarray(main["q"])
    lam = np.asarray(main["max_exponent"])
    fig = plt.figure(figsize=(7, 7.5))
    grid = fig.add_gridspec(3, 1, height_ratios=[1.2, 1.0, 0.8], hspace=0.35)
    ax_q = fig.add_subplot(grid[0])
    ax_l = fig.add_subplot(grid[1], sharex=ax_q)
    ax_z = fig.add_subplot(grid[2])
    ax_q.plot(np.repeat(cs, q.shape[1]), q.ravel(), ".", ms=0.8, color="k")
    ax_q.set_ylabel("q(φ=0)")
    ax_l.plot(cs, lam, "-", lw=0.8, color="tab:blue")
    ax_l.axhline(0.0, color="grey", lw=0.6)
    ax_l.axhline(-DAMPING_RATIO, color="tab:green", lw=0.6, ls="--", label="-ζ")
    ax_l.set_ylabel("$\\lambda_{max}$")
    ax_l.set_xlabel("C (stepped downward, continuation)")
    ax_l.legend(fontsize=8)
    for ax in (ax_q, ax_l, ax_z):
        ax.axvline(9.0, color="tab:green", lw=0.6, ls=":")
    ax_q.set_title("N=2, b=(1,-1), J=2: period-adding cascade below C=9 (dotted)", fontsize=9)
    zc, zp = np.asarray(zoom["couplings"]), np.asarray(zoom["period"])
    found = zp > 0
    ax_z.plot(zc[found], zp[found], "o", ms=3, color="tab:green", label="orbit period")
    ax_z.plot(
        zc[~found],
        np.full(np.sum(~found), zoom_periods // 2),
        "x",
        ms=3,
        color="grey",
        label=f"> {zoom_periods // 2} or aperiodic",
    )
    ax_z.set_xlabel("C (zoom into the cascade)")
    ax_z.set_ylabel("period (forcing periods)")
    ax_z.legend(fontsize=7)
    ctx.save_figure(
        fig,
        "fig:bif_0",
        {
            "coupling": cs,
            "q": q,
            "v": main["v"],
            "max_exponent": lam,
            "exponents": main["exponents"],
            "period": main["period"],
            "zoom_coupling": zoom["couplings"],
            "zoom_period": zoom["period"],
            "zoom_max_exponent": zoom["max_exponent"],
        },
    )
    run = (
        f"{cs.size} values of C in [{c_lo:g}, {c_hi:g}] downward, {s.bif0_periods} section points "
        f"after {s.bif0_transient} periods, λ over t={s.bif0_lyapunov_t:g}"
    )
    zoom_run = (
        f"zoom: {len(zoom['couplings'])} values of C from {CASCADE_ZOOM[0]} down to "
        f"{CASCADE_ZOOM[1]}, {zoom_periods} section points after {2 * s.bif0_transient} periods; "
        "period = smallest P with x_(i+P) = x_i (tolerance 1e-6)"
    )
    return [_cascade_claim(zoom, zoom_periods, zoom_run), *_regular_claims(main, run)]


# ---------------------------------------------------------------------------------------------
# fig:bif
# ---------------------------------------------------------------------------------------------


def _window(cs: np.ndarray, lo: float, hi: float) -> np.ndarray:
    return (cs >= lo - 1e-9) & (cs <= hi + 1e-9)


def fig_bif(ctx: PaperContext) -> list[Claim]:
    """Paper fig:bif: bifurcation diagrams and λ_max, N dimers (top) vs the erf-play limit."""
    import matplotlib.pyplot as plt

    s = ctx.size
    c_lo, c_hi = s.bif_c_range
    common = {
        "c_start": float(c_hi),
        "c_stop": float(c_lo),
        "n_values": int(s.bif_couplings),
        "n_periods": int(s.bif_periods),
        "transient": int(s.bif_transient),
        "lyapunov_t": float(s.bif_lyapunov_t),
    }
    tasks = [
        {"kind": "dimers", "spins": int(s.bif_spins), "seed": int(ctx.seed), **common},
        {"kind": "erf-play", "spins": 0, "seed": 0, **common},
    ]
    dimers, limit = ctx.run("paper-bif", tasks, bifurcation_task)
    cs = np.asarray(dimers["couplings"])
    lam_n = np.asarray(dimers["max_exponent"])
    lam_inf = np.asarray(limit["max_exponent"])

    fig, axes = plt.subplots(4, 1, figsize=(7, 9), sharex=True)
    for (ax_q, ax_l), res, color, name in (
        (axes[:2], dimers, "tab:blue", f"N = {s.bif_spins} (seed {ctx.seed})"),
        (axes[2:], limit, "tab:red", "N = ∞ (erf play)"),
    ):
        q = np.asarray(res["q"])
        ax_q.plot(np.repeat(cs, q.shape[1]), q.ravel(), ".", ms=1.0, color=color)
        ax_q.set_ylabel("q(φ=0)")
        ax_q.set_title(name, fontsize=9)
        ax_l.plot(cs, res["max_exponent"], "o-", ms=2, lw=0.8, color=color)
        ax_l.axhline(0.0, color="grey", lw=0.6)
        ax_l.set_ylabel("$\\lambda_{max}$")
    # the windows of the paper's claims (checked below), with a legend saying what each claims
    windows = (
        (1.7, 1.8, "tab:orange", "paper: N periodic ($\\lambda^N<0$), limit chaotic"),
        (2.5, 3.0, "tab:orange", None),
        (3.8, 4.2, "tab:green", "paper: both chaotic ($\\lambda^N, \\lambda^\\infty > 0$)"),
    )
    for ax in axes:
        for lo, hi, col, label in windows:
            if lo < c_hi and hi > c_lo:
                ax.axvspan(lo, hi, color=col, alpha=0.12, label=label if ax is axes[0] else None)
    if axes[0].get_legend_handles_labels()[0]:
        axes[0].legend(fontsize=7, loc="upper left", framealpha=0.9)
    fig.suptitle(
        f"fig:bif — dimers p = {WIDTH:g}, R = {SPREAD:g}, J = {SPIN_COUPLING:g} vs the erf-play "
        f"limit; ζ = {DAMPING_RATIO:g}, Ω = {FREQUENCY:g}",
        fontsize=9,
    )
    axes[-1].set_xlabel("C (stepped downward, continuation)")
    ctx.save_figure(
        fig,
        "fig:bif",
        {
            "coupling": cs,
            "dimers_q": dimers["q"],
            "dimers_max_exponent": lam_n,
            "limit_q": limit["q"],
            "limit_max_exponent": lam_inf,
            "dimers_period": dimers["period"],
            "limit_period": limit["period"],
        },
    )
    run = (
        f"N={s.bif_spins} (seed {ctx.seed}) and the limit, {cs.size} values of C in "
        f"[{c_lo:g}, {c_hi:g}] downward (step {(c_hi - c_lo) / max(cs.size - 1, 1):.3g}), "
        f"{s.bif_periods} points after {s.bif_transient} periods, λ over t={s.bif_lyapunov_t:g}"
    )

    def listing(mask: np.ndarray) -> str:
        return "; ".join(
            f"C={c:.2f}: {a:+.4f}/{b:+.4f}"
            for c, a, b in zip(cs[mask], lam_n[mask], lam_inf[mask], strict=True)
        )

    claims = []
    w = _window(cs, 3.8, 4.2)
    n_both = int(np.sum((lam_n[w] > 0) & (lam_inf[w] > 0)))
    outcome = dec.needs_size(
        dec.every_in_window(n_both, int(w.sum()), MIN_WINDOW_VALUES), s.bif_spins, PAPER_LARGEST_N
    )

    def bif_evidence(count: int) -> str:
        return (
            f"{count} grid values of C in the window (step "
            f"{(c_hi - c_lo) / max(cs.size - 1, 1):.3g}; >= {MIN_WINDOW_VALUES} needed to "
            f"decide); N = {s.bif_spins} dimers (paper: {PAPER_LARGEST_N}), one disorder "
            f"realization (seed {ctx.seed}); λ_max is a finite-time estimate over t = "
            f"{s.bif_lyapunov_t:g} after {s.bif_transient} periods, from continuation in C"
        )

    claims.append(
        Claim(
            claim="C in [3.8, 4.2]: both the N-dimer system and the limit are chaotic "
            "(λ_max^N > 0 and λ_max^∞ > 0 at every C of the window)",
            paper="both chaotic",
            measured=(f"λ^N/λ^∞: {listing(w)}" if w.any() else "no value of C in the window"),
            run=run,
            verdict=outcome,
            evidence=bif_evidence(int(w.sum())),
            explanation=reading(
                outcome,
                disagree=BIF_WINDOW_38_42 + " Caveats of the sweep: " + BIF_CAVEATS,
                inconclusive=BIF_INCONCLUSIVE,
            ),
        )
    )
    window_readings = {
        (2.5, 3.0): BIF_DISAGREE,
        (1.7, 1.8): BIF_WINDOW_17_18 + " Caveats of the sweep: " + BIF_CAVEATS,
    }
    for lo, hi in ((2.5, 3.0), (1.7, 1.8)):
        w = _window(cs, lo, hi)
        n_neg = int(np.sum(lam_n[w] < 0))
        n_pos = int(np.sum(lam_inf[w] > 0))
        k = int(w.sum())
        outcome = dec.needs_size(
            dec.combine(
                dec.majority_in_window(n_neg, k, MIN_WINDOW_VALUES),
                dec.majority_in_window(n_pos, k, MIN_WINDOW_VALUES),
            ),
            s.bif_spins,
            PAPER_LARGEST_N,
        )
        claims.append(
            Claim(
                claim=f"C in [{lo}, {hi}]: λ_max^N < 0 (long periodic motion) while the limit is "
                "chaotic, λ_max^∞ > 0 (verdict: at least half of the C values in the window each)",
                paper="λ_max^N < 0 and λ_max^∞ > 0",
                measured=(
                    f"λ^N < 0 at {n_neg} of {k}, λ^∞ > 0 at {n_pos} of {k}; λ^N/λ^∞: {listing(w)}"
                    if k
                    else "no value of C in the window"
                ),
                run=run,
                verdict=outcome,
                evidence=bif_evidence(k),
                explanation=reading(
                    outcome,
                    disagree=window_readings[(lo, hi)],
                    inconclusive=BIF_INCONCLUSIVE,
                ),
            )
        )
    return claims


# Checked separately with fresh starts from the paper's initial condition at each C (not by
# continuation): lyapunov_spectrum(ForcedOscillator(build_operator("erf-play"), C), 2e4, 1e3).
BIF_WINDOW_38_42 = (
    "Checked separately with fresh starts of the limit from the paper's initial condition at "
    "each C (no continuation; λ over t = 2·10⁴ after 10³): regular at C = 3.80, 3.82, 3.85, "
    "3.88 (λ_max = −0.058, −0.029, −0.012, −0.066), chaotic at 3.90 (0.039). The limit has a "
    "periodic window at the lower edge of the paper's window whatever the start, so the "
    "statement fails below C ≈ 3.89; above it both systems are chaotic at every grid value of "
    "this run."
)
BIF_WINDOW_17_18 = (
    "Checked separately with fresh starts of the limit from the paper's initial condition at "
    "each C (no continuation; λ over t = 2·10⁴ after 10³): chaotic at C = 1.70, 1.72, 1.74, "
    "1.76, 1.78 (λ_max = 0.075, 0.098, 0.111, 0.118, 0.126), regular at 1.80 (−0.071). The "
    "downward continuation follows a periodic orbit that coexists with the chaotic attractor "
    "at 1.74–1.80; from the paper's initial condition the limit is chaotic at 5 of these 6 "
    "values, as the paper says, and the N-dimer system is regular at all 11 grid values. The "
    "disagreement belongs to the continuation path, not to the limit."
)
BIF_CAVEATS = (
    "λ_max is a finite-time estimate, and for a long periodic orbit (or a long chaotic "
    "transient) its sign settles only after many orbit periods, so values near 0 are the least "
    "reliable; the N-dimer diagram is one disorder realization, while the paper's windows may "
    "depend on its realization; and continuation in C carries the attractor of the previous C, "
    "so coexisting attractors can make the diagram differ from one started afresh at each C."
)
BIF_DISAGREE = "Not explained by this run. What the evidence allows: " + BIF_CAVEATS
BIF_INCONCLUSIVE = (
    "The sweep has too few values of C inside the window (or too few dimers for the paper's "
    "N = 20 000) to test the statement; more couplings (a larger run size) decide it."
)


# ---------------------------------------------------------------------------------------------
# the shared ensemble computation
# ---------------------------------------------------------------------------------------------


def _ensemble_data(ctx: PaperContext) -> dict[str, Any]:
    """Ensembles at C = 2.9, 4.0, the limit values and the iid reference (computed once)."""
    key = "ensemble_data"
    if key in ctx.cache:
        return ctx.cache[key]
    from analysis.experiments.ensemble import (
        EXPERIMENT,
        aggregate_ensemble,
        ensemble_task,
        ensemble_tasks,
    )
    from analysis.experiments.iid import iid_variance_scaling

    s = ctx.size
    tasks = ensemble_tasks(
        s.ensemble_spins,
        ENSEMBLE_COUPLINGS,
        s.ensemble_realizations,
        ctx.seed,
        s.ensemble_t_end,
        s.ensemble_transient,
    )
    # run_ensemble would do the same; calling run_tasks here keeps the ctx's executor settings
    results = ctx.run(EXPERIMENT, tasks, ensemble_task)
    points = {
        (p.spins, p.coupling): p for p in aggregate_ensemble(zip(tasks, results, strict=True))
    }

    period = 2 * math.pi / FREQUENCY
    window_periods = int(
        math.floor(s.ensemble_t_end / period) - math.ceil(s.ensemble_transient / period)
    )
    limit_tasks = [
        {
            "coupling": c,
            "t_end": float(s.dky_t_end),
            "transient": float(s.dky_transient),
            # as many section points as one realization of the ensemble has: box counting is
            # biased by the number of points, so the comparison is like for like
            "section_periods": max(window_periods, 10),
            "section_transient": int(math.ceil(s.ensemble_transient / period)),
        }
        for c in ENSEMBLE_COUPLINGS
    ]
    limits = dict(
        zip(
            ENSEMBLE_COUPLINGS,
            ctx.run("paper-limit-dims", limit_tasks, limit_dimension_task),
            strict=True,
        )
    )
    iid = iid_variance_scaling(
        s.iid_spins,
        s.iid_steps,
        s.iid_realizations,
        ctx.seed,
        store=ctx.store_path,
        workers=ctx.task_workers,
        scheduler=ctx.scheduler,
        progress=ctx.progress,
        allow_version_mismatch=ctx.allow_version_mismatch,
    )
    data = {"points": points, "limits": limits, "iid": iid, "window_periods": window_periods}
    ctx.cache[key] = data
    return data


def _ens_run(ctx: PaperContext) -> str:
    s = ctx.size
    return (
        f"{s.ensemble_realizations} realizations per (N, C) (paper: 500), N in "
        f"{list(s.ensemble_spins)}, t_end={s.ensemble_t_end:g}, transient="
        f"{s.ensemble_transient:g} (paper: 1e6 steps), seed {ctx.seed}"
    )


def _series(data: dict, c: float, attr: str) -> tuple[np.ndarray, np.ndarray]:
    pts = sorted((p for (n, cc), p in data["points"].items() if cc == c), key=lambda p: p.spins)
    return np.array([p.spins for p in pts]), np.array([getattr(p, attr) for p in pts], dtype=float)


def _sem(values: np.ndarray) -> float:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return float(np.std(v) / math.sqrt(v.size)) if v.size > 1 else float("nan")


# ---------------------------------------------------------------------------------------------
# fig:dim
# ---------------------------------------------------------------------------------------------

ENSEMBLE_INCONCLUSIVE = (
    "The paper's statement is about large N (its largest is N = 20 000) and its ensembles of 500 "
    "realizations; this run's largest N is smaller, or the 95 % interval of its statistic over "
    "the run's realizations straddles the criterion (the evidence above says which). Below the "
    "paper's size a larger run size decides it; at the paper's size (500 realizations, N up to "
    "20 000) the paper's own ensembles could not decide it either, and more realizations or "
    "larger N are needed."
)
DIM_KY_DISAGREE = (
    "The finite system's Kaplan–Yorke dimension does not converge to the limit's: at N = 20 000 "
    "and C = 4.0 the tangent-flow spectrum gives λ ≈ (0.045, −0.145), D_KY ≈ 1.31 for every seed "
    "tried, clearly below the erf play's 1.42, where the paper finds the two nearly converge "
    "(the box-counting dimensions do agree, 1.32 vs 1.36). Measured with finite perturbations "
    "(`python examples/scale_dependent_lyapunov.py`), λ1 grows from 0.045 (δ = 1e-8) to 0.075 "
    "(δ = 1e-3) once δ exceeds the spacing of the switching thresholds: the infinitesimal "
    "exponent of the finite system and the exponent of its smooth limit differ. A finite "
    "system of relays never sees the limit's smooth branch at infinitesimal scale, so the "
    "tangent-space quantity D_KY need not converge with N even when the attractor (D_BC) does."
)
DIM_BC_DISAGREE = (
    "Box counting is biased by the number of section points and by the range of box sizes "
    "fitted; the limit's D_BC is computed from as many section points as one realization has, "
    "so the comparison is like for like, but a short run (few points) leaves little scaling "
    "region. At paper scale the two agree (1.32 vs 1.36 at N = 20 000, C = 4.0)."
)


def fig_dim(ctx: PaperContext) -> list[Claim]:
    """Paper fig:dim: disorder-averaged D_BC and D_KY vs N, with the limit values."""
    import matplotlib.pyplot as plt

    data = _ensemble_data(ctx)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    out: dict[str, np.ndarray] = {}
    for ax, c, tag in zip(axes, (4.0, 2.9), ("(a)", "(b)"), strict=True):
        pts = sorted((p for (n, cc), p in data["points"].items() if cc == c), key=lambda p: p.spins)
        ns = np.array([p.spins for p in pts])
        for attr, arr, marker, color, label in (
            ("mean_box_counting", "box_counting", "s", "tab:blue", "$\\overline{D}_{BC}$"),
            ("mean_kaplan_yorke", "kaplan_yorke", "o", "tab:red", "$\\overline{D}_{KY}$"),
        ):
            means = np.array([getattr(p, attr) for p in pts])
            errs = np.array([_sem(getattr(p, arr)) for p in pts])
            ax.errorbar(ns, means, yerr=errs, fmt=marker + "-", ms=4, color=color, label=label)
            out[f"{arr}_mean_C{c:g}"] = means
            out[f"{arr}_sem_C{c:g}"] = errs
        lim = data["limits"][c]
        ax.axhline(lim["box_counting"], color="tab:blue", ls="--", lw=1, label="$D_{BC}^\\infty$")
        ax.axhline(lim["kaplan_yorke"], color="tab:red", ls=":", lw=1.2, label="$D_{KY}^\\infty$")
        out[f"limit_box_counting_C{c:g}"] = np.array(lim["box_counting"])
        out[f"limit_kaplan_yorke_C{c:g}"] = np.array(lim["kaplan_yorke"])
        out["spins"] = ns
        ax.set_xscale("log")
        ax.set_xlabel("N")
        ax.set_title(f"{tag} C = {c:g}", fontsize=9)
    axes[0].set_ylabel("fractal dimension")
    axes[0].legend(fontsize=8)
    ctx.save_figure(fig, "fig:dim", out)

    run = _ens_run(ctx)
    claims = []
    p4 = max((p for (n, c), p in data["points"].items() if c == 4.0), key=lambda p: p.spins)
    lim4 = data["limits"][4.0]
    for name, attr, arr, key in (
        ("D_KY", "mean_kaplan_yorke", "kaplan_yorke", "kaplan_yorke"),
        ("D_BC", "mean_box_counting", "box_counting", "box_counting"),
    ):
        mean, limit_value = getattr(p4, attr), lim4[key]
        sem = _sem(getattr(p4, arr))
        outcome = dec.needs_size(
            dec.mean_within(mean, sem, limit_value, 0.1), p4.spins, PAPER_LARGEST_N
        )
        extra = (
            f" (limit D_BC from {lim4['section_points']} section points, as one realization)"
            if key == "box_counting"
            else f" (limit: t_end={ctx.size.dky_t_end:g}; paper's D_KY^∞ at C=4: 1.42–1.48)"
        )
        claims.append(
            Claim(
                claim=f"C=4.0: at the largest N the disorder-averaged {name} nearly converges to "
                "the limit value (verdict: within 0.1)",
                paper=f"{name} nearly converges to {name}^∞",
                measured=f"N={p4.spins}: mean {name} = {_fmt(mean)} ± "
                f"{_fmt(_sem(getattr(p4, arr)))}"
                f" vs {name}^∞ = {_fmt(limit_value)}{extra}; all N: "
                + ", ".join(
                    f"{n}:{_fmt(x)}" for n, x in zip(*_series(data, 4.0, attr), strict=True)
                ),
                run=run,
                verdict=outcome,
                evidence=f"difference {_fmt(mean - limit_value)} ± {_fmt(dec.Z95 * sem)} (95 % "
                f"interval of the mean over {p4.realizations} realizations) against the "
                f"criterion 0.1; largest N {p4.spins} (paper: {PAPER_LARGEST_N}); convergence "
                "with N: "
                + ", ".join(
                    f"{n}:{_fmt(x)}" for n, x in zip(*_series(data, 4.0, attr), strict=True)
                )
                + f"; limit value from one run, t_end={ctx.size.dky_t_end:g}, its own "
                "finite-time error not included",
                explanation=reading(
                    outcome,
                    disagree=DIM_KY_DISAGREE if key == "kaplan_yorke" else DIM_BC_DISAGREE,
                    inconclusive=ENSEMBLE_INCONCLUSIVE,
                ),
            )
        )
    p29 = max((p for (n, c), p in data["points"].items() if c == 2.9), key=lambda p: p.spins)
    lim29 = data["limits"][2.9]
    # one threshold: D̄_KY < 1 and D_KY^∞ − D̄_KY > 0.2 <=> D̄_KY < min(1, D_KY^∞ − 0.2)
    threshold = min(1.0, lim29["kaplan_yorke"] - 0.2)
    sem29 = _sem(p29.kaplan_yorke)
    outcome = dec.needs_size(
        dec.below(p29.mean_kaplan_yorke, dec.Z95 * sem29, threshold), p29.spins, PAPER_LARGEST_N
    )
    claims.append(
        Claim(
            claim="C=2.9: even at the largest N the mean D_KY is below 1 and considerably "
            "different (by > 0.2) from the limit",
            paper="D̄_KY < 1 at N = 20 000, D_KY^∞ ≈ 1.37–1.45",
            measured=f"N={p29.spins}: D̄_KY={_fmt(p29.mean_kaplan_yorke)} ± "
            f"{_fmt(_sem(p29.kaplan_yorke))}, D_KY^∞={_fmt(lim29['kaplan_yorke'])}; D̄_BC="
            f"{_fmt(p29.mean_box_counting)}, D_BC^∞={_fmt(lim29['box_counting'])}",
            run=run,
            verdict=outcome,
            evidence=f"D̄_KY = {_fmt(p29.mean_kaplan_yorke)} ± {_fmt(dec.Z95 * sem29)} (95 % "
            f"interval over {p29.realizations} realizations) against min(1, D_KY^∞ − 0.2) = "
            f"{_fmt(threshold)}; largest N {p29.spins} (paper: {PAPER_LARGEST_N}); with N: "
            + ", ".join(
                f"{n}:{_fmt(x)}"
                for n, x in zip(*_series(data, 2.9, "mean_kaplan_yorke"), strict=True)
            ),
            explanation=reading(
                outcome,
                disagree="The mean over realizations mixes regular ones (D_KY = 0, about a fifth "
                "at C = 2.9) with chaotic ones near the limit's value; a mean at or above 1 "
                "means fewer regular realizations than the paper's, see the fig:sap claim on "
                "their fraction.",
                inconclusive=ENSEMBLE_INCONCLUSIVE,
            ),
        )
    )
    return claims


# ---------------------------------------------------------------------------------------------
# fig:sap
# ---------------------------------------------------------------------------------------------


def sap_falls(sap: np.ndarray, realizations: int) -> str:
    """Verdict of "the SAP at the largest N is below the SAP at the smallest N": the log ratio
    against 0, known to ± 1.96 · 2/sqrt(K − 1) (a ratio of two variance estimates over K
    realizations each, Gaussian approximation)."""
    sap = np.asarray(sap, dtype=float)
    if sap.size < 2 or realizations < 2 or not np.all(np.isfinite(sap[[0, -1]])):
        return INCONCLUSIVE
    if sap[0] <= 0 or sap[-1] <= 0:  # a zero SAP (all realizations alike) has no log
        return verdict(bool(sap[-1] < sap[0])) if sap[0] != sap[-1] else INCONCLUSIVE
    rel = 2.0 / math.sqrt(realizations - 1)
    return dec.below(math.log(sap[-1] / sap[0]), dec.Z95 * rel, 0.0)


def _counts(ns: np.ndarray, counts: np.ndarray) -> str:
    return ", ".join(f"{n}:{int(r)}" for n, r in zip(ns, counts, strict=True))


def fig_sap(ctx: PaperContext) -> list[Claim]:
    """Paper fig:sap: SAP of D_BC and D_KY vs N (a), realizations with D_KY = 0 (b)."""
    import matplotlib.pyplot as plt

    data = _ensemble_data(ctx)
    k = ctx.size.ensemble_realizations
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(10, 3.8))
    out: dict[str, np.ndarray] = {}
    for c, color in ((4.0, "tab:blue"), (2.9, "tab:green")):
        for attr, marker, ls in (("sap_box_counting", "s", "--"), ("sap_kaplan_yorke", "o", "-")):
            ns, sap = _series(data, c, attr)
            shown = np.where(sap > 0, sap, np.nan)
            name = "BC" if "box" in attr else "KY"
            ax_a.plot(ns, shown, marker + ls, ms=4, color=color, label=f"SAP[D_{name}], C={c:g}")
            out[f"{attr}_C{c:g}"] = sap
            out["spins"] = ns
        ns, reg = _series(data, c, "regular_count")
        ax_b.plot(ns, reg, "o-", color=color, label=f"C={c:g}")
        out[f"regular_count_C{c:g}"] = reg
    ax_b.axhline(
        PAPER_REGULAR_FRACTION * k, color="grey", ls=":", label=f"paper: 100/500 × {k} realizations"
    )
    for ax in (ax_a, ax_b):
        ax.set_xscale("log")
        ax.set_xlabel("N")
        ax.legend(fontsize=7)
    ax_a.set_yscale("log")
    ax_a.set_ylabel("SAP[D]")
    ax_b.set_ylabel(f"# realizations with $D_{{KY}}=0$ (of {k})")
    ax_a.set_title("(a)", fontsize=9)
    ax_b.set_title("(b)", fontsize=9)
    ctx.save_figure(fig, "fig:sap", out)

    run = _ens_run(ctx)
    ns, ky4 = _series(data, 4.0, "sap_kaplan_yorke")
    _, bc4 = _series(data, 4.0, "sap_box_counting")
    _, ky29 = _series(data, 2.9, "sap_kaplan_yorke")
    _, bc29 = _series(data, 2.9, "sap_box_counting")
    _, reg29 = _series(data, 2.9, "regular_count")
    _, reg4 = _series(data, 4.0, "regular_count")
    largest = int(ns[-1]) if ns.size else 0
    falls = dec.combine(sap_falls(ky4, k), sap_falls(bc4, k))
    nonzero = dec.needs_size(
        verdict(bool(ky29[-1] > 0.05 and ky29[-1] > ky4[-1])), largest, PAPER_LARGEST_N
    )
    fraction = dec.needs_size(
        dec.fraction_matches(int(reg29[-1]), k, PAPER_REGULAR_FRACTION), largest, PAPER_LARGEST_N
    )
    size_txt = (
        f"{k} realizations per (N, C) (paper: 500), largest N {largest} (paper: "
        f"{PAPER_LARGEST_N}), t_end={ctx.size.ensemble_t_end:g} after "
        f"{ctx.size.ensemble_transient:g}"
    )

    def row(v: np.ndarray) -> str:
        return ", ".join(f"{n}:{_fmt(x, 4)}" for n, x in zip(ns, v, strict=True))

    claims = [
        Claim(
            claim="C=4.0: SAP[D_KY] and SAP[D_BC] decrease towards 0 with N (self-averaging; "
            "verdict: value at the largest N below the smallest N's)",
            paper="SAP[D] -> 0 algebraically",
            measured=f"SAP[D_KY] {row(ky4)}; SAP[D_BC] {row(bc4)}",
            run=run,
            verdict=falls,
            evidence=f"{size_txt}; the ratio SAP(largest N)/SAP(smallest N) is decided only "
            f"if below 1 beyond its 95 % sampling scale (relative error of a ratio of two "
            f"variances ≈ 2/sqrt(K−1) = {2 / math.sqrt(max(k - 1, 1)):.2f} for K = {k})",
            explanation=reading(
                falls,
                disagree="Not explained by this run: at paper scale SAP[D_KY] falls to 0.010 at "
                "N = 20 000 (5 of 500 realizations regular). A few regular realizations "
                "(D_KY = 0) among chaotic ones dominate the SAP, so with few realizations its "
                "value at one N can jump by their count.",
                inconclusive="The SAP is a relative variance over the realizations; with this "
                "run's realizations its sampling error is as large as the change between the "
                "smallest and the largest N.",
            ),
        ),
        Claim(
            claim="C=2.9: SAP[D_KY] stays non-zero at large N (no self-averaging; verdict: "
            "> 0.05 and above C=4.0's at the largest N)",
            paper="non-zero SAP remains (≈0.25 for 20% regular realizations at D_KY≈1.4)",
            measured=f"SAP[D_KY] {row(ky29)}; SAP[D_BC] {row(bc29)}",
            run=run,
            verdict=nonzero,
            evidence=f"{size_txt}; regular realizations per N at C=2.9: {_counts(ns, reg29)}",
            explanation=reading(
                nonzero,
                disagree="The non-zero SAP at C = 2.9 comes from the regular realizations "
                "(D_KY = 0) among chaotic ones near D_KY ≈ 1.4; a SAP at or below C = 4.0's "
                "means this run found few regular realizations at its largest N (see the next "
                "claim).",
                inconclusive=ENSEMBLE_INCONCLUSIVE,
            ),
        ),
    ]
    lo, hi = dec.wilson(int(reg29[-1]), k)
    claims.append(
        Claim(
            claim="C=2.9, large N: a constant fraction ≈ 20% of the realizations is regular "
            "(D_KY = 0) (verdict: 0.2 inside the 95% Wilson interval at the largest N)",
            paper="≈100 of 500 (20%)",
            measured=f"{int(reg29[-1])} of {k} ({reg29[-1] / k:.0%}, 95% CI [{lo:.2f}, {hi:.2f}]) "
            f"at N={ns[-1]}; per N: {_counts(ns, reg29)}; at C=4.0: {_counts(ns, reg4)}",
            run=run,
            verdict=fraction,
            evidence=f"{size_txt}; 95 % Wilson interval [{lo:.2f}, {hi:.2f}] of width "
            f"{hi - lo:.2f}: decided only when 0.2 lies outside it or it is narrower than 0.2 "
            "itself (it must tell ≈20 % from none or 40 %)",
            explanation=reading(
                fraction,
                disagree="Not explained by this run: at paper scale (N = 20 000, 500 "
                "realizations, t_end = 2e4) 96 of 500 realizations are regular, as in the "
                "paper. Whether a realization counts as regular can depend on the run "
                "length (long chaotic transients turn regular late, see fig:mboa at C = 2.92), "
                "so a shorter t_end may count fewer regular ones.",
                inconclusive=ENSEMBLE_INCONCLUSIVE,
            ),
        )
    )
    return claims


# ---------------------------------------------------------------------------------------------
# fig:mag and fig:mag_his
# ---------------------------------------------------------------------------------------------


def _local_exponent(ns: np.ndarray, var: np.ndarray) -> float:
    """log-log slope of VAR[M] between the two largest N."""
    if ns.size < 2 or var[-1] <= 0 or var[-2] <= 0:
        return float("nan")
    return float(np.log(var[-1] / var[-2]) / np.log(ns[-1] / ns[-2]))


def fig_mag(ctx: PaperContext) -> list[Claim]:
    """Paper fig:mag: VAR[M] vs N for C = 2.9, 4.0 (a) and for iid input with its power law (b)."""
    import matplotlib.pyplot as plt

    from analysis.dynamics.statistics import power_law_fit

    data = _ensemble_data(ctx)
    iid = data["iid"]
    k = ctx.size.ensemble_realizations
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(10, 3.8))
    out: dict[str, np.ndarray] = {}
    for c, color in ((4.0, "tab:blue"), (2.9, "tab:green")):
        ns, var = _series(data, c, "var_magnetization")
        err = var * math.sqrt(2.0 / max(k - 1, 1))
        ax_a.errorbar(ns, var, yerr=err, fmt="o-", ms=4, color=color, label=f"C={c:g}")
        out[f"var_magnetization_C{c:g}"] = var
        out["spins"] = ns
    ns = out["spins"]
    guide = out["var_magnetization_C2.9"][0] * (ns / ns[0]) ** -1.0
    ax_a.plot(ns, guide, "k:", lw=0.8, label="$\\propto N^{-1}$")
    ax_b.errorbar(
        iid.spins, iid.variance, yerr=iid.variance_stderr, fmt="o", color="k", label="iid input"
    )
    ax_b.plot(
        iid.spins,
        iid.fit(iid.spins),
        "k-",
        lw=0.8,
        label=f"fit $N^{{{iid.fit.exponent:.2f}\\pm{iid.fit.stderr:.2f}}}$",
    )
    out["iid_spins"] = iid.spins
    out["iid_variance"] = iid.variance
    out["iid_exponent"] = np.array(iid.fit.exponent)
    for ax, tag in ((ax_a, "(a) coupled"), (ax_b, "(b) iid input, no feedback")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("N")
        ax.set_ylabel("VAR[M]")
        ax.set_title(tag, fontsize=9)
        ax.legend(fontsize=8)
    ctx.save_figure(fig, "fig:mag", out)

    s = ctx.size
    iid_run = (
        f"{s.iid_realizations} realizations per N in {list(s.iid_spins)}, {s.iid_steps} iid "
        "steps u ~ N(0, 2²) (σ not given in the paper), one common input sequence"
    )
    fit = iid.fit
    iid_outcome = dec.power_law_exponent(fit.exponent, fit.stderr, -1.0, 0.1)
    claims = [
        Claim(
            claim="iid input (no feedback): VAR[M] ∝ N^-1 (verdict: fitted exponent within "
            "max(3σ, 0.1) of -1)",
            paper="∝ N^-1",
            measured=f"exponent {fit.exponent:.3f} ± {fit.stderr:.3f}",
            run=iid_run,
            verdict=iid_outcome,
            evidence=f"least-squares fit of log VAR[M] over {len(s.iid_spins)} values of N up "
            f"to {max(s.iid_spins)}, {s.iid_realizations} realizations each; 3σ = "
            f"{_fmt(3 * fit.stderr)}: decided only with a finite σ and, for an agreement, a "
            "3σ interval that excludes 0 (no decay)",
            explanation=reading(
                iid_outcome,
                disagree="Without feedback the N dimers switch independently given the common "
                "input, so VAR[M] = VAR[σ]/N (central limit theorem) up to correlations through "
                "the common input sequence; at paper scale the fit gives −0.996 ± 0.021. A "
                "different exponent points at too few steps for the time average to forget "
                "the initial state, or too few realizations per N.",
                inconclusive="The fit's standard error is not finite (too few N) or so large "
                "that no decay at all is also consistent; more realizations per N decide it.",
            ),
        )
    ]
    for c in (2.9, 4.0):
        ns, var = _series(data, c, "var_magnetization")
        slope = _local_exponent(ns, var)
        slope_err = variance_slope_stderr(ns, k)
        outcome = dec.needs_size(
            dec.below(-slope, dec.Z95 * slope_err, 0.5),  # slope > -0.5 beyond its 95 % scale
            int(ns[-1]) if ns.size else 0,
            PAPER_LARGEST_N,
        )
        try:
            full = power_law_fit(ns.astype(float), var)
            full_txt = f"; fit over all N: {full.exponent:.2f}"
        except ValueError:
            full_txt = ""
        claims.append(
            Claim(
                claim=f"C={c:.1f}: VAR[M] stops decaying like N^-1 at large N (non-self-averaging "
                "magnetization; verdict: log-log slope between the two largest N above -0.5)",
                paper="VAR[M] constant and non-zero for large N"
                + (" (decays ~N^-1 up to N≈5000)" if c == 2.9 else " (it seems; ~N^-1 to 10^4)"),
                measured="VAR[M] "
                + ", ".join(f"{n}:{v:.2e}" for n, v in zip(ns, var, strict=True))
                + f"; slope between N={ns[-2] if ns.size > 1 else '-'} and {ns[-1]}: "
                f"{_fmt(slope, 2)}{full_txt}",
                run=_ens_run(ctx),
                verdict=outcome,
                evidence=f"slope {_fmt(slope, 2)} ± {_fmt(dec.Z95 * slope_err, 2)} (95 %: each "
                f"VAR[M] from K = {k} realizations has relative error sqrt(2/(K−1)) = "
                f"{math.sqrt(2 / max(k - 1, 1)):.2f}) against −0.5; largest N "
                f"{int(ns[-1]) if ns.size else 0} (paper: {PAPER_LARGEST_N}); t_end="
                f"{s.ensemble_t_end:g} after {s.ensemble_transient:g} (paper: 1e6 steps)",
                explanation=reading(
                    outcome, disagree=MAG_DISAGREE[c], inconclusive=ENSEMBLE_INCONCLUSIVE
                ),
            )
        )
    return claims


MAG_DISAGREE = {
    2.9: "Not explained by this run. The paper's non-self-averaging magnetization at C = 2.9 "
    "sets in above N ≈ 5000; with the two largest N of this run the slope still follows the "
    "N^-1 of independent dimers. A time average over a shorter window than the paper's 1e6 "
    "steps carries more temporal noise, which for weakly correlated spins also decays like "
    "N^-1 and can hide a small N-independent part of VAR[M].",
    4.0: "The paper itself hedges at C = 4.0 (“it seems”, ~N^-1 up to 10^4). A slope near −1 "
    "between the two largest N means VAR[M] is still dominated by the N^-1 part there; a "
    "time average over a shorter window than the paper's 1e6 steps carries more temporal "
    "noise, which for weakly correlated spins also decays like N^-1 and can hide a small "
    "N-independent part.",
}


def variance_slope_stderr(ns: np.ndarray, realizations: int) -> float:
    """Standard error of the log-log slope of VAR[M] between the two largest N: each variance
    from K independent realizations has relative error sqrt(2/(K−1)) (Gaussian), so the slope
    has ``sqrt(2 · 2/(K−1)) / ln(N2/N1)``."""
    if len(ns) < 2 or realizations < 2 or ns[-1] <= ns[-2]:
        return float("nan")
    return math.sqrt(4.0 / (realizations - 1)) / math.log(ns[-1] / ns[-2])


def fig_mag_his(ctx: PaperContext) -> list[Claim]:
    """Paper fig:mag_his: empirical PDFs of M_T for the two largest N (C = 4.0, 2.9, iid)."""
    import matplotlib.pyplot as plt

    from analysis.dynamics.statistics import empirical_pdf

    data = _ensemble_data(ctx)
    iid = data["iid"]
    rows: list[tuple[str, str, list[tuple[int, np.ndarray]]]] = []
    for c, color in ((4.0, "tab:blue"), (2.9, "tab:green")):
        pts = sorted((p for (n, cc), p in data["points"].items() if cc == c), key=lambda p: p.spins)
        rows.append((f"C={c:g}", color, [(p.spins, p.magnetization) for p in pts[-2:]]))
    iid_pairs = list(zip(iid.spins.tolist(), iid.magnetizations, strict=True))
    rows.append(("iid", "k", iid_pairs[-2:]))

    fig, axes = plt.subplots(3, 2, figsize=(8, 7.5))
    out: dict[str, np.ndarray] = {}
    ratios: dict[str, tuple[float, float]] = {}
    for r, (name, color, pairs) in enumerate(rows):
        allv = np.concatenate([m for _, m in pairs])
        lo, hi = float(allv.min()), float(allv.max())
        if not hi > lo:
            lo, hi = lo - 0.5, hi + 0.5
        bins = np.linspace(lo, hi, 21)
        for col in range(2):
            ax = axes[r, col]
            if col >= len(pairs):
                ax.axis("off")
                continue
            n, m = pairs[col]
            pdf = empirical_pdf(m, bins)
            ax.stairs(pdf.density, pdf.edges, color=color, lw=1.2)
            ax.set_title(f"{name}, N={n} (std {np.std(m):.3g})", fontsize=9)
            ax.set_xlabel("$M_T$")
            ax.set_ylabel("PDF")
            out[f"{name.replace('=', '')}_N{n}_magnetization"] = m
        if len(pairs) == 2:
            (n1, m1), (n2, m2) = pairs
            ratios[name] = (float(np.std(m2) / np.std(m1)), math.sqrt(n1 / n2))
    fig.tight_layout()
    ctx.save_figure(fig, "fig:mag_his", out)

    def txt(name: str) -> str:
        got, clt = ratios.get(name, (float("nan"), float("nan")))
        return f"{name}: {_fmt(got, 2)} (CLT {_fmt(clt, 2)})"

    claims = []
    run = _ens_run(ctx)
    k_ens, k_iid = ctx.size.ensemble_realizations, ctx.size.iid_realizations
    for name, paper_c in (("C=4", "4.0"), ("C=2.9", "2.9")):
        got, clt = ratios.get(name, (float("nan"), float("nan")))
        ns = [n for n, _ in rows[0 if name == "C=4" else 1][2]]
        outcome = dec.needs_size(
            std_ratio_verdict(got, clt, k_ens, narrows=False),
            max(ns) if ns else 0,
            PAPER_LARGEST_N,
        )
        claims.append(
            Claim(
                claim=f"C={paper_c}: the PDF of M_T does not narrow from N={ns[0]} to N={ns[-1]} "
                "(verdict: std ratio above the midpoint between the CLT ratio sqrt(N1/N2) and 1)",
                paper="PDF becomes stationary (does not narrow) for large N",
                measured=f"std ratio {txt(name)}",
                run=run,
                verdict=outcome,
                evidence=std_ratio_evidence(got, clt, k_ens, max(ns) if ns else 0),
                explanation=reading(
                    outcome, disagree=MAG_HIS_DISAGREE, inconclusive=ENSEMBLE_INCONCLUSIVE
                ),
            )
        )
    got, clt = ratios.get("iid", (float("nan"), float("nan")))
    iid_outcome = std_ratio_verdict(got, clt, k_iid, narrows=True)
    claims.append(
        Claim(
            claim="iid input: the PDF of M_T narrows as the central limit theorem says (verdict: "
            "std ratio of the two largest N below the midpoint between sqrt(N1/N2) and 1)",
            paper="variance of the distribution decreases with N",
            measured=f"std ratio {txt('iid')}",
            run=f"{ctx.size.iid_realizations} realizations, N in {list(ctx.size.iid_spins)[-2:]}",
            verdict=iid_outcome,
            evidence=std_ratio_evidence(got, clt, k_iid, None),
            explanation=reading(
                iid_outcome,
                disagree="Without feedback the dimers switch independently given the common "
                "input, so the std of M_T must shrink like N^-1/2; a ratio near 1 points at too "
                "few steps for the time averages to forget the initial state.",
                inconclusive="With this run's realizations the sampling error of the std ratio "
                "straddles the midpoint; more realizations decide it.",
            ),
        )
    )
    return claims


MAG_HIS_DISAGREE = (
    "Not explained by this run. At the two largest N of the run the PDF of M_T still narrows "
    "nearly as the central limit theorem says, i.e. the N-independent part of VAR[M] (see "
    "fig:mag) is not yet dominant there; the paper's stationary PDF appears above its "
    "crossover N (≈ 5000 at C = 2.9, ≈ 10^4 at C = 4.0) and with time averages over 1e6 steps."
)


def std_ratio_verdict(ratio: float, clt: float, realizations: int, narrows: bool) -> str:
    """Verdict of a std-ratio claim of fig:mag_his: the ratio std(N2)/std(N1) against the
    midpoint between the CLT ratio sqrt(N1/N2) and 1 — below it if ``narrows``, above it
    otherwise — known to ± 1.96 · ratio/sqrt(K − 1) (two stds of K Gaussian samples each)."""
    if not (np.isfinite(ratio) and np.isfinite(clt)):
        return INCONCLUSIVE
    mid = 0.5 * (1.0 + clt)
    half = dec.Z95 * ratio * dec.std_ratio_relative_error(realizations)
    return dec.below(ratio, half, mid) if narrows else dec.below(-ratio, half, -mid)


def std_ratio_evidence(ratio: float, clt: float, realizations: int, largest: int | None) -> str:
    mid = 0.5 * (1.0 + clt) if np.isfinite(clt) else float("nan")
    rel = dec.std_ratio_relative_error(realizations)
    size = f"; largest N {largest} (paper: {PAPER_LARGEST_N})" if largest is not None else ""
    return (
        f"std ratio {_fmt(ratio, 2)} ± {_fmt(dec.Z95 * ratio * rel, 2)} (95 %, K = "
        f"{realizations} realizations per N) against the midpoint {_fmt(mid, 2)} between the "
        f"CLT ratio {_fmt(clt, 2)} and 1{size}"
    )


FIGURES = [
    FigureSpec("fig:bif_0", "bifurcation diagram, one dimer b=(1,-1)", fig_bif_0),
    FigureSpec("fig:bif", "bifurcation diagrams, N dimers vs the erf-play limit", fig_bif),
    FigureSpec("fig:dim", "disorder-averaged D_BC and D_KY vs N", fig_dim),
    FigureSpec("fig:sap", "self-averaging parameter of D and regular realizations", fig_sap),
    FigureSpec("fig:mag", "variance of the time-averaged magnetization vs N", fig_mag),
    FigureSpec("fig:mag_his", "empirical PDFs of the time-averaged magnetization", fig_mag_his),
]
