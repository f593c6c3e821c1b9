"""Figures of the coupled dynamics: sheets, trajectories, attractors, D_KY vs initial conditions.

Every long computation is an independent task run through
:func:`analysis.experiments.execution.run_tasks` so ``--full`` runs are parallel and resumable
through the results store.
"""

from __future__ import annotations

import numpy as np

from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.statistics import ks_sampling_scale
from analysis.experiments.models import build_operator
from analysis.experiments.parameters import (
    DAMPING_RATIO,
    DEFAULT_Q0,
    FREQUENCY,
    PAPER_LARGEST_N,
    V0,
)
from analysis.paper import decisions as dec
from analysis.paper.context import Claim, FigureSpec, PaperContext, reading, verdict
from oscillators import ForcedOscillator

__all__ = ["FIGURES"]

# The paper gives no coupling for its N = 2 section and N = 4 trajectory figures. For N = 4 we
# use the coupling of its large-N comparison, C = 4.0. For N = 2 the section at C = 4.0 never
# enters the bistable region -2 < q < 0, so the overlap the caption describes cannot show there;
# a scan of C = 0.5, 1.0, ..., 10 (1000 periods each) found points in that region only at
# C = 1.0, which we therefore use. The report states this choice next to the claim.
C_SHEETS = 4.0
C_N2_SECTION = 1.0


def _dimers(fields, coupling_j: float = 2.0):

    pairs = np.asarray(fields, dtype=float).reshape(-1, 2)
    return build_operator("dimers", fields=pairs, spin_coupling=coupling_j)


def _system(operator, coupling: float):
    return ForcedOscillator(operator, coupling, DAMPING_RATIO, FREQUENCY)


def _erf_play():

    return build_operator("erf-play", width=2.0, spread=1.0)


def fig_n2_schema(ctx: PaperContext) -> list[Claim]:
    """Paper fig:N=2_schema (b): Poincaré section of one dimer (J=2, p=2, b=(2,0)), two sheets."""
    import matplotlib.pyplot as plt

    periods = max(ctx.size.attractor_periods, 20)
    system = _system(build_operator("n2", spin_coupling=2.0), C_N2_SECTION)
    sec = system.poincare_section(periods, transient_periods=min(100, periods))
    down = sec.M < 0
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    scale = max(float(np.ptp(sec.q)), float(np.ptp(sec.v)), 1e-12)
    # the bistable region where both sheets exist, shaded so the claim's overlap is seen
    ax.axvspan(-2.0, 0.0, color="0.92", zorder=0, label="bistable $-2<q<0$")
    for sel, marker, color, name in ((down, "s", "tab:blue", "$S_1$ (M=-1)"),
                                     (~down, "x", "tab:red", "$S_2$ (M=+1)")):  # fmt: skip
        # a periodic section repeats its points: the legend says how many sites they fill
        sites = _sites(np.c_[sec.q[sel], sec.v[sel]], 0.01 * scale)
        ax.plot(
            sec.q[sel],
            sec.v[sel],
            marker,
            ms=5,
            mew=1.2,
            color=color,
            linestyle="none",
            label=f"{name}: {int(np.sum(sel))} points on {sites} sites",
        )
    lo, hi = float(np.min(sec.q, initial=-2.0)), float(np.max(sec.q, initial=0.0))
    pad = 0.08 * (max(hi, 0.0) - min(lo, -2.0))
    ax.set_xlim(min(lo, -2.0) - pad, max(hi, 0.0) + pad)  # both region edges inside
    ax.set_xlabel("q")
    ax.set_ylabel("v")
    ax.set_title(f"N=2, J=2, b=(2,0), C={C_N2_SECTION:g}: Poincaré section φ=0", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    fig.tight_layout()
    ctx.save_figure(fig, "fig:N=2_schema", {"q": sec.q, "v": sec.v, "M": sec.M})
    bistable = (sec.q > -2.0) & (sec.q < 0.0)
    n1, n2 = int(np.sum(bistable & down)), int(np.sum(bistable & ~down))
    return [
        Claim(
            claim="N=2: in the bistable region -2 < q < 0 the sections of both sheets overlap",
            paper="points of S1 and S2 in -2 < q < 0",
            measured=f"{n1} points on S1 and {n2} on S2 in -2 < q < 0",
            run=f"C={C_N2_SECTION:g} (not given in the paper; the only C of a 0.5-step scan whose "
            f"section reaches -2<q<0), {periods} periods after 100",
            verdict=verdict(n1 > 0 and n2 > 0),
            evidence=f"{sec.q.size} section points, {int(np.sum(bistable))} of them in "
            f"-2 < q < 0, from q0={DEFAULT_Q0:g}, v0={V0:g}",
            explanation=reading(
                verdict(n1 > 0 and n2 > 0),
                disagree="The paper gives no coupling for this figure; at most couplings the "
                "section never enters the bistable region, and at C = 1.0 it does only after "
                "long runs. A disagreement with few section points means the run was too short "
                "to visit the region on both sheets.",
            ),
        )
    ]


def _sites(points: np.ndarray, radius: float) -> int:
    """How many places ``points`` mark at a figure's resolution: greedy clusters, each point
    joining the first site within ``radius`` (max norm) or opening a new one."""
    sites: list[np.ndarray] = []
    for x in points:
        if not any(np.max(np.abs(x - c)) <= radius for c in sites):
            sites.append(x)
    return len(sites)


def fig_n4_traj(ctx: PaperContext) -> list[Claim]:
    """Paper fig:N=4_traj: a trajectory of two dimers coloured by sheet, and its thresholds."""
    import matplotlib.pyplot as plt

    system = _system(build_operator("n4", spin_coupling=2.0), C_SHEETS)
    t_end = 40 * system.period if ctx.size.name != "smoke" else 10 * system.period
    traj = system.trajectory(t_end, sample_dt=0.005)
    fig, ax = plt.subplots(figsize=(5.5, 4))
    styles = {
        -1.0: ("tab:purple", ":", "$S_1$"),
        0.0: ("tab:green", "--", "$S_2$"),
        1.0: ("salmon", "-", "$S_3$"),
    }
    for m, (color, ls, name) in styles.items():
        q = np.where(np.isclose(traj.M, m), traj.q, np.nan)
        ax.plot(
            q,
            np.where(np.isclose(traj.M, m), traj.v, np.nan),
            ls,
            color=color,
            lw=1,
            label=f"{name} (M={m:g})",
        )
    ax.set_xlabel("q")
    ax.set_ylabel("v")
    ax.legend(fontsize=8)
    ax.set_title(f"N=4, J=2, b=(2,0,-0.5,-2.5), C={C_SHEETS:g}", fontsize=9)
    sw = traj.switches
    ctx.save_figure(
        fig,
        "fig:N=4_traj",
        {
            "t": traj.t,
            "q": traj.q,
            "v": traj.v,
            "M": traj.M,
            "switch_time": sw["time"],
            "switch_q": sw["q"],
            "switch_jump": sw["jump"],
        },
    )
    ups = np.unique(np.round(sw["q"][sw["jump"] > 0], 9))
    downs = np.unique(np.round(sw["q"][sw["jump"] < 0], 9))
    ok = set(ups) <= {0.0, 2.5} and set(downs) <= {-2.0, 0.5} and len(ups) > 0 and len(downs) > 0
    return [
        Claim(
            claim="N=4 trajectory switches up at alpha=(0, 2.5) and down at beta=(-2, 0.5)",
            paper="alpha1=0, beta1=-2, alpha2=2.5, beta2=0.5",
            measured=f"up at {sorted(float(x) for x in ups)}, down at "
            f"{sorted(float(x) for x in downs)}",
            run=f"C={C_SHEETS:g} (not given in the paper), {len(sw)} switches in t <= {t_end:.0f}",
            verdict=verdict(ok),
            evidence=f"{int(np.sum(sw['jump'] > 0))} up and {int(np.sum(sw['jump'] < 0))} down "
            f"switches in t <= {t_end:.0f}; thresholds compared to 1e-9",
            explanation=reading(
                verdict(ok),
                disagree="The thresholds are closed-form (Table I); a switch elsewhere is a "
                "defect of the event location, none switching means the trajectory never "
                "reached the thresholds at this coupling.",
            ),
        )
    ]


def fig_erf_10000(ctx: PaperContext) -> list[Claim]:
    """Paper fig:erf_10000: attractors at C = 4.0, limit (a) and N = 20 000 dimers (b)."""
    import matplotlib.pyplot as plt

    n_spins = ctx.size.bif_spins
    periods = ctx.size.attractor_periods
    transient = 100
    systems = {
        "limit": _system(_erf_play(), 4.0),
        "dimers": _system(build_operator("dimers", spins=n_spins, seed=ctx.seed), 4.0),
    }
    data: dict[str, np.ndarray] = {}
    # v and C·M are different quantities: phase portraits above, the force C·M[q] below
    fig, grid = plt.subplots(
        2, 2, figsize=(10, 6.4), sharex=True, sharey="row", gridspec_kw={"height_ratios": [3, 2]}
    )
    for ax, ax_m, (name, system) in zip(grid[0], grid[1], systems.items(), strict=True):
        sec = system.poincare_section(periods, transient_periods=transient)
        show = min(30, periods)
        traj = system.trajectory(
            show * system.period,
            q0=sec.final.q,
            v0=sec.final.v,
            operator_state=sec.final.operator_state,
            sample_dt=0.02,
        )
        ax.plot(traj.q, traj.v, "-", color="0.75", lw=0.5, label="trajectory")
        ax.plot(sec.q, sec.v, ".", ms=2.5, color="tab:blue", label="Poincaré φ=0")
        ax_m.plot(traj.q, traj.M * 4.0, "-", color="tab:red", lw=0.8)
        ax.set_title("N = ∞ (erf play)" if name == "limit" else f"N = {n_spins} dimers", fontsize=9)
        ax_m.set_xlabel("q")
        data.update(
            {
                f"{name}_section_q": sec.q,
                f"{name}_section_v": sec.v,
                f"{name}_traj_q": traj.q,
                f"{name}_traj_v": traj.v,
                f"{name}_traj_M": traj.M,
            }
        )
    grid[0, 0].set_ylabel("v")
    grid[1, 0].set_ylabel("C·M[q]  (C = 4)")
    grid[0, 0].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    ctx.save_figure(fig, "fig:erf_10000", data)

    # deliberately lazy: scipy.stats costs about a second at every `hyst` start
    from scipy.stats import ks_2samp

    ks = ks_2samp(data["limit_section_q"], data["dimers_section_q"]).statistic
    n1, n2 = data["limit_section_q"].size, data["dimers_section_q"].size
    outcome = dec.needs_size(dec.ks_below(ks, n1, n2, 0.15), n_spins, PAPER_LARGEST_N)
    return [
        Claim(
            claim="C=4.0: attractor of N=20 000 dimers resembles the limit's (Poincaré q "
            "distributions, Kolmogorov–Smirnov distance < 0.15)",
            paper="trajectory, section and magnetization behave in a similar way",
            measured=f"KS distance of q on the sections = {ks:.3f}",
            run=f"{periods} periods after {transient}, N={n_spins}, seed {ctx.seed}",
            verdict=outcome,
            evidence=f"{n1} and {n2} section points: the KS sampling scale 1.36·sqrt((n1+n2)/"
            f"(n1·n2)) = {ks_sampling_scale(n1, n2):.3f} (a lower bound: successive section "
            f"points are correlated) against |KS − 0.15| = {abs(ks - 0.15):.3f}; N = {n_spins} "
            f"(paper: {PAPER_LARGEST_N}), one disorder realization",
            explanation=reading(
                outcome,
                disagree="Not explained by this run. The limit and the N-dimer system share "
                "the attractor's shape (their box-counting dimensions agree at N = 20 000), "
                "but the branches of one disorder realization of N dimers deviate from the "
                "limit's erf by O(N^-1/2) (the sampled loop centres), which shifts where the "
                "section points fall.",
                inconclusive="Too few section points (or too few dimers) for the KS distance "
                "to be told from 0.15 by more than its sampling noise; more periods (a larger "
                "run size) decide it.",
            ),
        )
    ]


def dky_task(
    coupling: float, q0: float, w0: float, v0: float, t_end: float, transient: float
) -> dict:
    """One Kaplan–Yorke dimension of the erf-play limit (task function, picklable)."""

    play = _erf_play()
    res = lyapunov_spectrum(
        _system(play, coupling),
        t_end=t_end,
        transient=transient,
        q0=q0,
        v0=v0,
        operator_state=play.state(position=w0, input=q0),  # the initial memory is the state
        progress=False,
    )
    exps = [float(x) for x in res.exponents]
    return {"exponents": exps, "kaplan_yorke": float(res.kaplan_yorke)}


def fig_mboa(ctx: PaperContext) -> list[Claim]:
    """Paper fig:mboa: D_KY of the limit vs the initial conditions q0 (outside) and w0 (inside)."""
    import matplotlib.pyplot as plt

    s = ctx.size
    n = s.mboa_points
    q0s = np.linspace(-2.5, 2.5, n)
    w0s = np.linspace(-1.95, -0.05, n)  # inside the play for q0 = -1: |q0 - w0| < p/2 = 1
    base = {"v0": 0.1, "t_end": s.dky_t_end, "transient": s.dky_transient}
    panels = {
        "a": [(c, float(q), float(q) - 1.0) for c in (2.9, 4.0) for q in q0s],
        "b": [(c, -1.0, float(w)) for c in (2.9, 4.0) for w in w0s],
        "c": [(2.92, float(q), float(q) - 1.0) for q in q0s],
        "d": [(1.9, float(q), float(q) - 1.0) for q in q0s],
    }
    tasks = [{"coupling": c, "q0": q, "w0": w, **base} for p in panels.values() for c, q, w in p]
    results = ctx.run("mboa", tasks, dky_task)
    by_key = {(t["coupling"], t["q0"], t["w0"]): r for t, r in zip(tasks, results, strict=True)}

    fig, axes = plt.subplots(1, 3, figsize=(12, 3.9))
    data: dict[str, np.ndarray] = {"q0": q0s, "w0": w0s}
    for ax, key, xs, xlabel, title in (
        (axes[0], "a", q0s, "$q_0$ ($w_0=q_0-p/2$)", "start outside the play"),
        (axes[1], "b", w0s, "$w_0$ ($q_0=-1$)", "start inside the play"),
        (axes[2], "c", q0s, "$q_0$ ($w_0=q_0-p/2$)", "C = 2.92: regular or chaotic"),
    ):
        ax.set_title(f"({key}) {title}", fontsize=9, loc="left")
        for c in sorted({c for c, _, _ in panels[key]}):
            d = [by_key[(c, q, w)]["kaplan_yorke"] for cc, q, w in panels[key] if cc == c]
            ax.plot(xs, d, "o-", ms=3, label=f"C={c:g}")
            data[f"dky_{key}_C{c:g}"] = np.array(d)
        ax.set_xlabel(xlabel)
        ax.set_ylabel("$D_{KY}^\\infty$")
        ax.legend(fontsize=8)
    fig.suptitle(
        f"$D_{{KY}}^\\infty$ of the erf-play limit (p = 2, R = 1, ζ = 0.05, Ω = 1, v0 = 0.1) vs "
        f"initial conditions; t_end = {s.dky_t_end:g}",
        fontsize=10,
    )
    fig.tight_layout()
    lam_d = [by_key[(c, q, w)]["exponents"][0] for c, q, w in panels["d"]]
    data["lmax_d_C1.9"] = np.array(lam_d)
    ctx.save_figure(fig, "fig:mboa", data)

    run = f"t_end={s.dky_t_end:g}, transient={s.dky_transient:g}, {n} initial conditions"
    evidence = (
        f"{n} initial conditions per panel (q0 in [-2.5, 2.5] outside the play, w0 in "
        f"[-1.95, -0.05] inside it at q0 = -1), each one Lyapunov spectrum over t = "
        f"{s.dky_t_end:g} (≈{s.dky_t_end / (2 * np.pi):.0f} forcing periods) after "
        f"{s.dky_transient:g}; finite-time D_KY, no error bar per run"
    )
    claims = []
    for c, lo, hi in ((2.9, 1.37, 1.45), (4.0, 1.42, 1.48)):
        vals = np.concatenate([data[f"dky_a_C{c:g}"], data[f"dky_b_C{c:g}"]])
        claims.append(
            Claim(
                claim=f"C={c:g}: D_KY of the limit independent of q0 and w0, within [{lo}, {hi}]",
                paper=f"[{lo}, {hi}]",
                measured=f"[{vals.min():.3f}, {vals.max():.3f}] (mean {vals.mean():.3f})",
                run=run,
                verdict=verdict(bool(vals.min() >= lo and vals.max() <= hi)),
                evidence=f"{evidence}; spread over the initial conditions "
                f"{vals.max() - vals.min():.3f}",
                explanation=reading(
                    verdict(bool(vals.min() >= lo and vals.max() <= hi)),
                    disagree=MBOA_DISAGREE[c],
                ),
            )
        )
    d292 = data["dky_c_C2.92"]
    regular = int(np.sum(d292 == 0.0))
    chaotic = d292[d292 > 0]
    ok292 = bool(regular > 0 and chaotic.size > 0 and np.all((chaotic >= 1.0) & (chaotic <= 1.5)))
    claims.append(
        Claim(
            claim="C=2.92: depending on q0 the limit is regular (D_KY=0) or chaotic, "
            "D_KY in [1.0, 1.5]",
            paper="both regular and chaotic, chaotic D_KY in [1.0, 1.5]",
            measured=f"{regular} regular, {chaotic.size} chaotic"
            + (f" with D_KY in [{chaotic.min():.3f}, {chaotic.max():.3f}]" if chaotic.size else ""),
            run=run,
            verdict=verdict(ok292),
            evidence=evidence,
            explanation=reading(verdict(ok292), disagree=MBOA_292_DISAGREE),
        )
    )
    lam = np.array(lam_d)
    claims.append(
        Claim(
            claim="C=1.9: regular for every q0, with slightly different negative λ_max",
            paper="λ_max < 0 for all q0",
            measured=f"λ_max in [{lam.min():.4f}, {lam.max():.4f}]",
            run=run,
            verdict=verdict(bool(lam.max() < 0)),
            evidence=evidence,
            explanation=reading(
                verdict(bool(lam.max() < 0)),
                disagree="At paper scale C = 1.9 is regular with λ1 = −0.0207 for every q0; a "
                "positive finite-time λ_max means the run has not left a chaotic transient.",
            ),
        )
    )
    return claims


MBOA_DISAGREE = {
    2.9: "At paper scale the limit's D_KY at C = 2.9 is 1.395 (`hyst lyapunov --model erf-play "
    "--coupling 2.9 --t-end 200000 --transient 1592`: λ = (0.0805, −0.2037, −inf)), inside the "
    "paper's 1.37–1.45. A value outside the range from a short run is the finite-time error "
    "of D_KY (it converges like t^-1/2), or a start that has not yet left a transient.",
    4.0: "The limit's D_KY at C = 4.0 sits at the lower edge of the paper's 1.42–1.48: one run "
    "of 2e5 time units gives λ = (0.0771, −0.1846, −inf), D_KY = 1.418, and 22 initial "
    "conditions of 1e5 time units each give 1.409–1.423. The attractor's dimension is "
    "independent of the initial condition, as the paper says; only the paper's interval "
    "starts about 0.01 higher than our long-run value, which is within the finite-time spread "
    "over initial conditions. A value far outside the interval from a short run is the "
    "finite-time error of D_KY (it converges like t^-1/2).",
}
MBOA_292_DISAGREE = (
    "Long chaotic transients: runs of 1e4 time units look chaotic for about a third of the "
    "initial conditions (D_KY 1.0–1.45, as in the paper), but every one of 61 starts is "
    "regular by 1e5 time units. The paper's picture at C = 2.92 (regular or chaotic depending "
    "on q0) is what a run of its length sees; the attractor itself is regular, so the outcome "
    "of this claim depends on t_end."
)


FIGURES = [
    FigureSpec("fig:N=2_schema", "N = 2 Poincaré section on two sheets", fig_n2_schema),
    FigureSpec("fig:N=4_traj", "N = 4 trajectory with sheets", fig_n4_traj),
    FigureSpec("fig:erf_10000", "attractors at C = 4: limit vs N = 20 000", fig_erf_10000),
    FigureSpec("fig:mboa", "D_KY of the limit vs initial conditions", fig_mboa),
]
