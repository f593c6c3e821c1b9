"""Write a hysteresis operator from scratch on the contract and analyse it with the toolkit.

    python examples/custom_operator.py [--smoke] [--out out/examples]

The operator is a play whose output is the smooth saturating shape ``f(w) = tanh(w)`` of its
wagon position ``w``, written only on the operator contract (``hysteresis.base``): its
own state class and the three methods a continuous operator must write, ``initial_state``,
``apply`` and ``branch_flow``. Coupled to the forced oscillator it gets, with no further code, a
trajectory, a Lyapunov spectrum and a periodic orbit with its Floquet multipliers (the generic
continuous engine integrates it, tangent flow included).

Every result is checked against independent truth: the library's ``GeneralizedPlay`` with the
same shape (a different implementation, integrated by the compiled play kernel: another
integrator) gives the same trajectory to 1e-8, the same Lyapunov exponents, the same periodic
orbit; the orbit's Floquet multipliers give its Lyapunov exponents ``log|μ|/T``; and the
stroboscopic map returns the orbit's point to itself. The walk-through is the tutorial
``docs/tutorials/writing_operators.rst``. About 20 s (``--smoke``: shorter runs, the same
checks).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis import lyapunov_spectrum  # noqa: E402
from analysis.dynamics.periodic_orbits import find_periodic_orbit  # noqa: E402
from hysteresis import ContinuousHysteron, GeneralizedPlay  # noqa: E402
from hysteresis.flow import BranchFlow  # noqa: E402
from oscillators import ForcedOscillator  # noqa: E402


def shape(w):
    """The output as a function of the wagon position: smooth, increasing, saturating at ±1."""
    return np.tanh(np.asarray(w, dtype=np.float64))


def shape_derivative(w):
    """``f'(w) = 1 / cosh²(w)``."""
    return 1.0 / np.cosh(np.asarray(w, dtype=np.float64)) ** 2


# -- the operator: a state class and three methods -----------------------------------------------
@dataclass(frozen=True)
class WagonState:
    """The memory: the wagon position, and the input last seen (every state has ``input``)."""

    position: float
    input: float


class SaturatingPlay(ContinuousHysteron[WagonState]):
    """A play of width ``p`` with output ``f(w)``: the wagon ``w`` stays put while the input
    moves inside ``[w - p/2, w + p/2]`` and is dragged along by the wall it touches."""

    def __init__(self, width: float) -> None:
        self.width = float(width)
        self.half_width = 0.5 * self.width

    def initial_state(self, u0: float) -> WagonState:
        # rising from negative saturation to u0 leaves the wagon on its right wall
        return WagonState(u0 - self.half_width, float(u0))

    def apply(self, inputs, state: WagonState | None = None) -> tuple[np.ndarray, WagonState]:
        u = np.asarray(inputs, dtype=np.float64)
        if state is None:
            state = self.initial_state(float(u[0]))
        w = np.empty(u.size)
        position = state.position
        for k, uk in enumerate(u):
            position = max(uk - self.half_width, min(uk + self.half_width, position))
            w[k] = position
        return shape(w), WagonState(float(position), float(u[-1]))

    def branch_flow(self, state: WagonState, direction: int) -> BranchFlow:
        w0, u0, h = state.position, state.input, self.half_width
        # on the wall the input pushes against? (a rounding tolerance: after a wall hit the
        # engine sets the input exactly on the breakpoint w0 ± h, and apply's u ∓ h may come
        # back one ulp away from w0)
        tolerance = 8.0 * np.finfo(float).eps * max(abs(u0), abs(w0), h, 1.0)
        if direction * (u0 - w0) >= h - tolerance:
            # dragged: w = w0 + (u - u0) follows the input (slaved), no breakpoint ahead
            return BranchFlow(
                direction=direction,
                input=u0,
                labels=("w",),
                memory=np.array([w0]),
                slaved=np.array([True]),
                output=lambda u: shape(w0 + (np.asarray(u, dtype=np.float64) - u0))[()],
                partials=lambda u: (
                    np.zeros(np.shape(u))[()],
                    shape_derivative(w0 + (np.asarray(u, dtype=np.float64) - u0))[..., None],
                ),
                breakpoint=direction * math.inf,
            )
        # inside: w frozen, the output constant until the input reaches the wall ahead, where
        # the wagon starts moving (its perturbation is reset there: δw := δu)
        y0, slope_w = float(shape(w0)), float(shape_derivative(w0))
        return BranchFlow(
            direction=direction,
            input=u0,
            labels=("w",),
            memory=np.array([w0]),
            slaved=np.array([False]),
            output=lambda u: np.full(np.shape(u), y0)[()],
            partials=lambda u: (np.zeros(np.shape(u))[()], np.full(np.shape(u) + (1,), slope_w)),
            breakpoint=w0 + direction * h,
            breakpoint_resets=("w",),
            constant_partials=True,
        )

    # what the periodic-orbit finder uses to set the memory from a coordinate vector
    def state(self, position: float, input: float) -> WagonState:
        return WagonState(float(position), float(input))


# -- the analyses, each against an independent truth ----------------------------------------------
WIDTH, COUPLING, DAMPING, FREQUENCY = 1.0, 0.8, 0.1, 1.2


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="The defaults are the full size (about 15 s on a quiet machine).",
    )
    parser.add_argument("--out", default="out/examples", help="output directory")
    parser.add_argument("--smoke", action="store_true", help="shorter runs (a test)")
    args = parser.parse_args(argv)
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    t_end = 40.0 if args.smoke else 80.0
    t_lyap = 120.0 if args.smoke else 300.0

    mine = ForcedOscillator(SaturatingPlay(WIDTH), COUPLING, DAMPING, FREQUENCY)
    builtin = ForcedOscillator(
        GeneralizedPlay(WIDTH, shape, shape_derivative), COUPLING, DAMPING, FREQUENCY
    )
    print(f"engines: {mine.engine_class.__name__} (mine), {builtin.engine_class.__name__}")

    # 1. trajectory: the same motion as the library's play with this shape
    traj = mine.trajectory(t_end, q0=0.0, v0=0.5, sample_dt=0.05)
    ref = builtin.trajectory(t_end, q0=0.0, v0=0.5, sample_dt=0.05)
    dq = float(np.max(np.abs(traj.q - ref.q)))
    print(f"trajectory to t = {t_end:g}: max |q - q_builtin| = {dq:.1e}, {traj.events.size} events")
    assert dq < 1e-8 and float(np.max(np.abs(traj.M - ref.M))) < 1e-8
    assert traj.events.size >= 10  # the orbit hits the walls and turns inside: all branches

    # 2. Lyapunov spectrum (the w direction is reset at every wall hit: -inf)
    lyap = lyapunov_spectrum(mine, t_lyap, transient=60.0, q0=0.0, v0=0.5)
    lyap_ref = lyapunov_spectrum(builtin, t_lyap, transient=60.0, q0=0.0, v0=0.5)
    print(f"Lyapunov exponents {lyap.tangent_space}: {lyap.exponents}")
    assert lyap.tangent_space == ("q", "v", "w") and lyap.exponents[-1] == -math.inf
    np.testing.assert_allclose(lyap.exponents[:2], lyap_ref.exponents[:2], rtol=0, atol=1e-6)

    # 3. the periodic orbit the motion settles on, and its Floquet multipliers
    orbit = find_periodic_orbit(mine, q0=0.0, v0=0.5, transient=30, max_period=4)
    orbit_ref = find_periodic_orbit(builtin, q0=0.0, v0=0.5, transient=30, max_period=4)
    print(f"period-{orbit.period} orbit at {orbit.points[0]}, multipliers {orbit.multipliers}")
    assert orbit.period == orbit_ref.period and orbit.stable
    np.testing.assert_allclose(orbit.points, orbit_ref.points, rtol=0, atol=1e-8)
    np.testing.assert_allclose(
        np.sort(np.abs(orbit.multipliers)), np.sort(np.abs(orbit_ref.multipliers)), atol=1e-7
    )
    # the stroboscopic map returns the orbit's point to itself ...
    back = orbit.states[0]
    for _ in range(orbit.period):
        back = mine.stroboscopic_map(back)
    assert abs(back.q - orbit.states[0].q) < 1e-9 and abs(back.v - orbit.states[0].v) < 1e-9
    # ... and the attractor's Lyapunov exponents tend to the multipliers' log|μ| per unit time:
    # finite-time exponents over a window of length L carry an O(1/L) term (the alignment of
    # the start basis, log of a condition number of order one), so they agree to a few 1/L
    nonzero = np.sort(np.abs(orbit.multipliers))[::-1][:2]
    from_multipliers = np.log(nonzero) / (orbit.period * mine.period)
    window = t_lyap - 60.0
    print(f"log|μ|/T = {from_multipliers}, finite-time exponents over L = {window:g}")
    np.testing.assert_allclose(lyap.exponents[:2], from_multipliers, rtol=0, atol=2.0 / window)

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ax1.plot(traj.q, traj.v, lw=0.7, label="trajectory")
    ax1.plot(orbit.points[:, 0], orbit.points[:, 1], "ro", label=f"period-{orbit.period} orbit")
    ax1.set(xlabel="q", ylabel="v", title="SaturatingPlay, written on the contract")
    ax1.legend()
    ax2.plot(traj.q, traj.M, lw=0.7)
    ax2.set(xlabel="q", ylabel="M", title="its hysteresis loop along the motion")
    fig.tight_layout()
    fig.savefig(out_dir / "custom_operator.png", dpi=100)
    print(f"wrote {out_dir / 'custom_operator.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
