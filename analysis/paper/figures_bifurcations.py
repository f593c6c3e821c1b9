"""Figures of the bifurcation diagrams: fig:bif_0 (one dimer) and fig:bif (N dimers vs the
erf-play limit). The sweeps are tasks of :mod:`analysis.paper.ensemble_tasks`."""

from __future__ import annotations

import numpy as np

from analysis.dynamics.period_adding import period_adding
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    FREQUENCY,
    PAPER_LARGEST_N,
    SPIN_COUPLING,
    SPREAD,
    WIDTH,
)
from analysis.paper import decisions as dec
from analysis.paper.context import (
    INCONCLUSIVE,
    Claim,
    FigureSpec,
    PaperContext,
    reading,
    verdict,
)
from analysis.paper.ensemble_tasks import (
    bifurcation_task,
)
from analysis.paper.prose import (
    BIF_CAVEATS,
    BIF_DISAGREE,
    BIF_INCONCLUSIVE,
    BIF_WINDOW_17_18,
    BIF_WINDOW_38_42,
    CASCADE_DISAGREE,
    CASCADE_INCONCLUSIVE,
    fmt_value,
)
from analysis.paper.verdicts import (
    CASCADE_MIN_WINDOWS,
    MIN_WINDOW_VALUES,
    cascade_verdict,
    is_period_adding,
    window_mask,
)

__all__ = ["FIGURES", "fig_bif_0", "fig_bif", "CASCADE_ZOOM"]


#: fig:bif_0 cascade: the grazing value C = 1/(2ζ) + β = 10 − 1 = 9 (period-1 orbit with
#: amplitude 1/(2ζ) around q = C touches the down threshold β = −1 of the dimer b = (1, −1))
CASCADE_ZOOM = (9.3, 7.0)


def _cascade_claim(zoom: dict, n_periods: int, run: str) -> Claim:
    """Onset of the period-adding cascade and the periods below it (zoomed sweep)."""
    per = np.asarray(zoom["period"])
    cascade = period_adding(zoom["couplings"], per)
    below, wide, step = cascade.below, list(cascade.wide), cascade.grid_step
    seq = ", ".join(f"{c:.2f}:{p if p else f'>{n_periods // 2}'}" for c, p in below[:10])
    outcome = cascade_verdict(
        cascade.onset,
        step,
        is_period_adding(cascade),
        len(below),
        int(per[0]) if per.size else 0,
    )
    return Claim(
        claim="N=2, b=(1,-1): coming from large C, a period-adding cascade starts at C ≈ 9 "
        "(verdict: onset within 0.25 of 9; periods >= 20 right below the onset; the periods of "
        "successive windows (>= 2 grid values wide) fall monotonically by 1 or 2 as C decreases)",
        paper="period-adding cascade at C = 9 (theory: 1/(2ζ) + β = 9)",
        measured=f"period-1 orbit (no switch) down to C={cascade.no_switch_end:.3f}; onset C≈"
        f"{fmt_value(cascade.onset)}; periodic windows (>= 2 successive C) in sweep order {wide} "
        f"(steps {sorted(set(cascade.steps))}); narrow windows between them "
        f"{list(cascade.narrow)}; C:period {seq}",
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
    w = window_mask(cs, 3.8, 4.2)
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
        w = window_mask(cs, lo, hi)
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


FIGURES = [
    FigureSpec("fig:bif_0", "bifurcation diagram, one dimer b=(1,-1)", fig_bif_0),
    FigureSpec("fig:bif", "bifurcation diagrams, N dimers vs the erf-play limit", fig_bif),
]
