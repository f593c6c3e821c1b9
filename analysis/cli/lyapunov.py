"""``hyst lyapunov``: Lyapunov spectrum and Kaplan–Yorke dimension of one system.

Defaults are the paper's Table II: ζ = 0.05, Ω = 1, q0 = −1, v0 = 0.1, p = 2, R = 1, J = 2,
N = 20 000 spins (seed 0), all spins down relaxed at q0; for the play limit w0 = q0 − p/2.

This module also holds the model/initial-condition arguments shared by ``hyst trajectory`` and
``hyst poincare``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

import numpy as np

MODELS = ("erf-play", "play", "dimers", "relay")


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    """Model selection and parameters (paper Table II defaults)."""
    g = parser.add_argument_group("model")
    g.add_argument(
        "--model",
        choices=MODELS,
        default="dimers",
        help="operator M: erf generalized play (N = inf), play, spin dimers, relay",
    )
    g.add_argument("--coupling", type=float, required=True, help="C, hysteresis force strength")
    g.add_argument("--spins", type=int, default=20000, help="N, number of spins (dimers: N/2)")
    g.add_argument("--seed", type=int, default=0, help="disorder realization of the dimers")
    g.add_argument("--width", type=float, default=2.0, help="p, loop width")
    g.add_argument("--spread", type=float, default=1.0, help="R, spread of the loop centres")
    g.add_argument("--spin-coupling", type=float, default=2.0, help="J, spin-spin coupling")
    g.add_argument(
        "--fields",
        type=float,
        nargs="+",
        default=None,
        help="explicit local fields b1 b2 b3 b4 ... (pairs per dimer)",
    )
    g.add_argument("--alpha", type=float, default=None, help="relay: upper threshold (p/2)")
    g.add_argument("--beta", type=float, default=None, help="relay: lower threshold (-p/2)")
    g.add_argument("--damping-ratio", type=float, default=0.05, help="zeta")
    g.add_argument("--frequency", type=float, default=1.0, help="Omega")


def add_initial_arguments(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("initial condition")
    g.add_argument("--q0", type=float, default=-1.0)
    g.add_argument("--v0", type=float, default=0.1)
    g.add_argument(
        "--w0",
        type=float,
        default=None,
        help="play wagon position (default q0 - p/2, i.e. the initial state)",
    )


def build_operator(args: argparse.Namespace) -> Any:
    if args.model == "erf-play":
        from hysteresis.play import GeneralizedPlay

        return GeneralizedPlay.erf(args.width, args.spread)
    if args.model == "play":
        from hysteresis.play import PlayOperator

        return PlayOperator(args.width)
    if args.model == "relay":
        from hysteresis.relay import Relay

        alpha = 0.5 * args.width if args.alpha is None else args.alpha
        beta = -0.5 * args.width if args.beta is None else args.beta
        return Relay(alpha, beta)
    from hysteresis.spin_dimers import SpinDimerEnsemble

    if args.fields is not None:
        if len(args.fields) % 2:
            raise ValueError("--fields needs an even number of values (b1 b2 per dimer)")
        return SpinDimerEnsemble(np.reshape(args.fields, (-1, 2)), args.spin_coupling)
    return SpinDimerEnsemble.random(
        args.spins, args.width, args.spread, args.spin_coupling, args.seed
    )


def build_system(args: argparse.Namespace) -> Any:
    from oscillators import ForcedOscillator

    return ForcedOscillator(build_operator(args), args.coupling, args.damping_ratio, args.frequency)


def model_parameters(args: argparse.Namespace) -> dict:
    """Parameters that define the run, for the JSON record."""
    out = {
        "model": args.model,
        "coupling": args.coupling,
        "damping_ratio": args.damping_ratio,
        "frequency": args.frequency,
        "q0": args.q0,
        "v0": args.v0,
    }
    if args.model in ("erf-play", "play"):
        out["width"] = args.width
        out["w0"] = args.q0 - 0.5 * args.width if args.w0 is None else args.w0
        if args.model == "erf-play":
            out["spread"] = args.spread
    elif args.model == "relay":
        out["alpha"] = 0.5 * args.width if args.alpha is None else args.alpha
        out["beta"] = -0.5 * args.width if args.beta is None else args.beta
    elif args.fields is not None:
        out["fields"] = list(args.fields)
        out["spin_coupling"] = args.spin_coupling
        out["spins"] = len(args.fields)
    else:
        out.update(
            spins=args.spins,
            seed=args.seed,
            width=args.width,
            spread=args.spread,
            spin_coupling=args.spin_coupling,
        )
    return out


def play_w0(args: argparse.Namespace) -> float | None:
    return args.w0 if args.model in ("erf-play", "play") else None


def play_state(args: argparse.Namespace, system) -> object | None:
    """The play's initial state at wagon position ``--w0`` (None: the operator's default)."""
    w0 = play_w0(args)
    return None if w0 is None else system.operator.state(w0, args.q0)


def _json_float(x: float) -> float | str:
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return float(x)


def register(subparsers: Any) -> None:
    p = subparsers.add_parser(
        "lyapunov",
        help="Lyapunov spectrum and Kaplan-Yorke dimension",
        description="Lyapunov spectrum by the tangent flow with saltation matrices and QR "
        "(paper Sec. Lyapunov exponents); phase direction excluded unless --include-phase.",
    )
    add_model_arguments(p)
    add_initial_arguments(p)
    p.add_argument("--t-end", type=float, default=10000.0, help="end time T")
    p.add_argument("--transient", type=float, default=0.0, help="transient T0 (< T)")
    p.add_argument("--include-phase", action="store_true", help="also follow the phase direction")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from analysis.lyapunov import lyapunov_spectrum

    try:
        system = build_system(args)
        if args.w0 is not None and args.model not in ("erf-play", "play"):
            raise ValueError("--w0 is only meaningful for --model erf-play/play")
        res = lyapunov_spectrum(
            system,
            args.t_end,
            args.transient,
            args.q0,
            args.v0,
            operator_state=play_state(args, system),
            include_phase=args.include_phase,
            progress=not args.no_progress and not args.json,
        )
    except (ValueError, NotImplementedError) as exc:
        print(f"hyst lyapunov: error: {exc}", file=sys.stderr)
        return 2
    record = dict(model_parameters(args))
    record.update(
        exponents=[_json_float(x) for x in res.exponents],
        tangent_space=list(res.tangent_space),
        kaplan_yorke=_json_float(res.kaplan_yorke),
        switches=res.n_switches,
        t_end=res.t_end,
        transient=res.transient,
        include_phase=bool(args.include_phase),
    )
    if args.json:
        print(json.dumps(record))
    else:
        print(
            f"model {args.model}, C = {args.coupling}, averaged over "
            f"[{res.transient}, {res.t_end}], {res.n_switches} switches"
        )
        print(f"  tangent space ({', '.join(res.tangent_space)})")
        for i, lam in enumerate(res.exponents, start=1):
            print(f"  lambda_{i} = {lam: .6f}")
        print(f"  D_KY = {res.kaplan_yorke:.4f}")
    return 0
