"""Periodic orbits of memory operators: Prandtl–Ishlinskii, a play with a user shape (tanh), and
frozen memory (a wagon strictly inside its play for the whole orbit) — against the Lyapunov
spectrum of the same orbit, central finite differences of P^k, the linear oscillator's closed
form and Newton on neighbouring members of the family."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from analysis.cli import main
from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.lyapunov import lyapunov_spectrum
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import (
    find_periodic_orbit,
    frozen_coordinates,
    refine_periodic_orbit,
    shoot,
)
from hysteresis import GeneralizedPlay, PlayOperator, PrandtlIshlinskii
from oscillators import ForcedOscillator


def tanh_derivative(w):
    return 1.0 / np.cosh(w) ** 2


def _pi_system() -> ForcedOscillator:
    # four plays; the widest (p = 6) is never reached by the orbit (|q| < 3): its wagon is frozen
    op = PrandtlIshlinskii([0.5, 1.0, 2.0, 6.0], [0.4, 0.3, 0.2, 0.1])
    return ForcedOscillator(op, 0.8)


def _tanh_system() -> ForcedOscillator:
    return ForcedOscillator(GeneralizedPlay(2.0, np.tanh, tanh_derivative), 2.0)


def _reduced_differences(system, orbit, h: float) -> np.ndarray:
    """Central differences of P^k in the non-frozen coordinates at the orbit's start."""
    coords = StateCoordinates(system, orbit.start)
    x = coords.vector(orbit.start)
    free = [i for i, lab in enumerate(orbit.tangent_space) if lab not in orbit.frozen]
    cols = []
    for j in free:
        e = np.zeros(x.size)
        e[j] = h
        plus = shoot(system, coords.state(x + e, orbit.start), orbit.period).states[-1]
        minus = shoot(system, coords.state(x - e, orbit.start), orbit.period).states[-1]
        cols.append(((coords.vector(plus) - coords.vector(minus)) / (2 * h))[free])
    return np.column_stack(cols)


@pytest.mark.parametrize("which", ["pi", "tanh-play"])
def test_memory_orbit_floquet_equals_lyapunov_and_differences(which):
    system = _pi_system() if which == "pi" else _tanh_system()
    orbit = find_periodic_orbit(system, transient=200, max_period=8)
    k = orbit.period
    assert orbit.residual <= orbit.tolerance * max(1.0, float(np.max(np.abs(orbit.points))))
    assert orbit.stable
    if which == "pi":
        assert orbit.period == 1 and orbit.frozen == ("w3",)
        assert orbit.tangent_space == ("q", "v", "w0", "w1", "w2", "w3")
    else:
        assert orbit.frozen == () and orbit.tangent_space == ("q", "v", "w")
    # frozen directions: exactly 1, labelled, exponent exactly 0
    tags = np.array(orbit.multiplier_labels)
    is_frozen = np.char.startswith(tags, "frozen: ")
    assert [t[len("frozen: ") :] for t in tags[is_frozen]] == list(orbit.frozen)
    assert np.all(orbit.multipliers[is_frozen] == 1.0)
    assert np.all(orbit.exponents[is_frozen] == 0.0)
    # the QR average on a periodic orbit converges as B/t (B = O(1), the log of the
    # eigenvector basis' condition); over 4000 orbit periods (t ≈ 2.5e4·k) it is below 1e-4
    ly = lyapunov_spectrum(
        system, 4000 * k * system.period, 0.0, state=orbit.start, renormalize_dt=k * system.period
    )
    floquet = np.sort(orbit.exponents)[::-1]
    print(which, "period", k, "Floquet", orbit.exponents, "Lyapunov", ly.exponents)
    finite = floquet[np.isfinite(floquet)]
    assert finite.size == 2 + len(orbit.frozen)
    # the whole spectrum, frozen directions included: the neutral wagon's exponent 0 keeps its
    # slot in the QR (it used to fall into a -inf slot), the reset wagons are -inf
    assert np.array_equal(np.isfinite(ly.exponents), np.isfinite(floquet))
    assert np.max(np.abs(finite - ly.exponents[: finite.size])) < 1e-4
    # the reduced monodromy against central differences of P^k (truncation h²/6·|D³P| and
    # round-off ~ε|x||J|/h ≈ 1e-10|J|: far below 1e-6·max(1, |J|)); at a point strictly inside
    # every moving play the ±h stay on one branch
    free = ~np.isin(np.array(orbit.tangent_space), orbit.frozen)
    jac = orbit.monodromy[np.ix_(free, free)]
    fd = _reduced_differences(system, orbit, 1e-6)
    scale = max(1.0, float(np.max(np.abs(jac))))
    assert np.max(np.abs(fd - jac)) < 1e-6 * scale
    mu_fd = np.sort(np.abs(np.linalg.eigvals(fd)))
    mu = np.sort(np.abs(orbit.multipliers[~is_frozen]))
    assert np.max(np.abs(mu_fd - mu)) < 1e-6 * scale
    d = json.loads(json.dumps(orbit.to_dict()))
    assert d["frozen"] == list(orbit.frozen)
    assert d["multiplier_labels"] == list(orbit.multiplier_labels)


def test_interior_wagon_orbit_is_a_family_with_the_closed_form():
    # a play of width 4 driven at Ω = 0.5 (amplitude ≈ 1.3 < p/2 = 2): after the transient the
    # wagon stays inside the play and the system is the linear oscillator with the constant
    # force C·w, q(t) = q_C0(t) + C·w — a family of orbits parametrised by w (refused before:
    # J − I singular)
    zeta, omega, c = 0.1, 0.5, 0.5
    system = ForcedOscillator(PlayOperator(4.0), c, zeta, omega)
    orbit = find_periodic_orbit(system, transient=200, max_period=4)
    assert orbit.period == 1 and orbit.frozen == ("w",) and orbit.stable
    assert frozen_coordinates(orbit.monodromy).tolist() == [False, False, True]
    t = system.period
    wd = math.sqrt(1.0 - zeta**2)
    expected = np.exp((-zeta + 1j * np.array([wd, -wd])) * t)
    got = orbit.multipliers[np.array(orbit.multiplier_labels) == ""]
    # the play engine integrates the linear motion in closed form: round-off only
    assert np.max(np.abs(np.sort_complex(got) - np.sort_complex(expected))) < 1e-10
    assert orbit.multipliers[0] == 1.0 and orbit.multiplier_labels[0] == "frozen: w"
    # the frozen direction's eigenvector is the family's tangent: dq/dw = C, dv/dw = 0
    vec = orbit.eigenvectors[:, 0].real
    assert np.allclose(vec / vec[2], [c, 0.0, 1.0], atol=1e-9)
    # the family: move the wagon by 0.1 and Newton converges again, to the orbit shifted by C·Δw
    coords = StateCoordinates(system, orbit.start)
    x = coords.vector(orbit.start)
    moved = coords.state(x + np.array([0.0, 0.0, 0.1]), orbit.start)
    other = refine_periodic_orbit(system, moved, 1)
    assert other.frozen == ("w",)
    assert other.points[0, 2] == x[2] + 0.1
    assert np.allclose(other.points[0, :2], x[:2] + [0.1 * c, 0.0], atol=1e-9)


def test_pi_family_moving_the_frozen_wagon():
    system = _pi_system()
    orbit = find_periodic_orbit(system, transient=200, max_period=4)
    coords = StateCoordinates(system, orbit.start)
    x = coords.vector(orbit.start)
    j = orbit.tangent_space.index("w3")
    for dw in (-0.05, 0.05):
        y = x.copy()
        y[j] += dw
        other = refine_periodic_orbit(system, coords.state(y, orbit.start), 1)
        assert other.frozen == ("w3",) and other.points[0, j] == y[j]
        # the family's tangent (eigenvector of the frozen multiplier) predicts the shift of
        # (q, v, w0..w2); plays are translation invariant, so moving w3 translates the orbit:
        # q and the moving wagons by δ = C·a3·Δw3 / (1 − C·(a0 + a1 + a2)), v unchanged —
        # linear in Δw3, so the first-order prediction is exact up to the Newton tolerance
        vec = orbit.eigenvectors[:, list(orbit.multiplier_labels).index("frozen: w3")].real
        predicted = x + dw * vec / vec[j]
        assert np.allclose(other.points[0], predicted, atol=1e-8)
        delta = 0.8 * 0.1 * dw / (1.0 - 0.8 * 0.9)
        assert np.allclose(other.points[0] - y, [delta, 0.0, delta, delta, delta, 0.0], atol=1e-8)


def test_continuation_holds_the_frozen_wagon():
    # the interior-wagon family continued in C: the wagon is held (a parameter of the family),
    # the orbit is the C = 0 orbit shifted by C·w, so q at the section is linear in C with slope
    # w, and the multipliers stay the linear oscillator's (|μ| = exp(−ζT)) — no event
    zeta, omega = 0.1, 0.5
    system = ForcedOscillator(PlayOperator(4.0), 0.5, zeta, omega)
    orbit = find_periodic_orbit(system, transient=200, max_period=4)
    branch = continue_orbit(system, orbit, 0.5, 0.7, step=0.05)
    assert branch.stop_reason == "reached stop" and not branch.events
    w = orbit.points[0, 2]
    for p in branch.points:
        assert p.point[2] == w
        assert abs(p.point[0] - (orbit.points[0, 0] + (p.parameter - 0.5) * w)) < 1e-9
        assert abs(p.max_abs_multiplier - math.exp(-zeta * system.period)) < 1e-10
        assert p.to_dict()["frozen"] == ["w"]


def test_cli_orbit_json_lists_frozen_memory(tmp_path, monkeypatch, capsys):
    # hyst orbit on the interior-wagon play: the JSON carries the frozen labels next to the
    # existing keys, and stable is judged without the frozen multiplier
    monkeypatch.chdir(tmp_path)
    argv = ["orbit", "--model", "play", "--width", "4", "--frequency", "0.5"]
    assert main([*argv, "--damping-ratio", "0.1", "--coupling", "0.5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    for key in ("period", "multipliers", "exponents", "tangent_space", "residual", "stable"):
        assert key in d
    assert d["period"] == 1 and d["stable"] is True and d["frozen"] == ["w"]
    assert d["multiplier_labels"] == ["frozen: w", "", ""]
    assert d["multipliers"][0] == [1.0, 0.0] and d["exponents"][0] == 0.0
    assert d["max_abs_multiplier"] < 1.0
