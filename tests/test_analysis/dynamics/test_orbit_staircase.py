"""Periodic orbits of continuous Preisach systems (staircase coordinates, closed-loop map, frozen
older extrema): residual, frozen multipliers exactly 1, the Jacobian of the closed-loop map
against central finite differences, the compiled engine against the generic one."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest

from analysis.dynamics.continuation import continue_orbit
from analysis.dynamics.memory import memory_frozen_exponents
from analysis.dynamics.orbit_coordinates import StateCoordinates
from analysis.dynamics.periodic_orbits import find_periodic_orbit, refine_periodic_orbit, shoot
from analysis.dynamics.staircase_orbits import closed_loop_shot
from hysteresis import ContinuousPreisachModel
from oscillators import ForcedOscillator


@pytest.fixture(scope="module")
def gaussian_orbit():
    # width-disorder model p = 2, R = 1, σ_r = 0.1 at C = 1: the motion settles on a stable
    # period-1 orbit inside the density's support (a minor loop of the staircase)
    system = ForcedOscillator(ContinuousPreisachModel.gaussian(2.0, 1.0, 0.1), 1.0)
    return system, find_periodic_orbit(system, transient=200, max_period=4)


def test_gaussian_orbit_structure_and_frozen_extrema(gaussian_orbit):
    system, orbit = gaussian_orbit
    assert orbit.period == 1 and orbit.stable
    assert orbit.residual <= orbit.tolerance * max(1.0, float(np.max(np.abs(orbit.points))))
    labels = orbit.tangent_space
    assert labels[:2] == ("q", "v") and all(lab[0] in "Mm" for lab in labels[2:])
    # the older extrema are frozen (a leading part of the staircase), the last one is the
    # orbit's own minimum, wiped out and pushed again every period
    n = len(orbit.frozen)
    assert n >= 1 and orbit.frozen == labels[2 : 2 + n] and len(labels) == 2 + n + 1
    tags = np.array(orbit.multiplier_labels)
    is_frozen = np.char.startswith(tags, "frozen: ")
    assert is_frozen.sum() == n
    assert np.all(orbit.multipliers[is_frozen] == 1.0) and np.all(orbit.exponents[is_frozen] == 0)
    others = orbit.multipliers[~is_frozen]
    assert orbit.max_abs_multiplier == float(np.max(np.abs(others))) < 1.0
    # the frozen extrema are the start's: Newton held them
    extrema = np.asarray(orbit.start.operator_state.extrema)
    assert np.array_equal(orbit.points[0, 2 : 2 + n], extrema[:n])
    # the orbit points are one orbit: the staircase of the start comes back (own minimum
    # pushed again at the same value to the tolerance)
    d = orbit.to_dict()
    assert d["frozen"] == list(orbit.frozen) and len(d["multiplier_labels"]) == len(labels)


def _closed_loop_map(system, orbit):
    """The orbit's coordinates and ``x -> P̃(x)`` over one period (``closed_loop_shot``)."""
    coords = StateCoordinates(system, orbit.start)
    n = len(orbit.frozen)

    def p_tilde(x):
        state = coords.state(x, orbit.start)
        return coords.vector(closed_loop_shot(system, state, 1, n).states[-1])

    return coords, p_tilde


def test_gaussian_closed_loop_jacobian_against_central_differences(gaussian_orbit):
    system, orbit = gaussian_orbit
    coords, p_tilde = _closed_loop_map(system, orbit)
    x = coords.vector(orbit.start)
    n = len(orbit.frozen)
    free = [0, 1, *range(2 + n, x.size)]
    # h well inside the distance from the orbit's extrema to the nearest frozen extremum (a
    # wipe-out border of the map): a fiftieth of it
    extrema = np.asarray(orbit.start.operator_state.extrema)
    own = extrema[n:-1]
    gap = float(np.min(np.abs(extrema[:n, None] - own[None, :])))
    h = gap / 50.0
    cols = []
    for j in free:
        e = np.zeros(x.size)
        e[j] = h
        cols.append(((p_tilde(x + e) - p_tilde(x - e)) / (2 * h))[free])
    fd = np.column_stack(cols)
    jac = orbit.monodromy[np.ix_(free, free)]
    print("h", h, "|FD − J|", np.max(np.abs(fd - jac)))
    # truncation h²/6·|D³P| (h ~ 1e-7: negligible) plus the map's own noise (the compiled
    # engine's event location to ~1e-13) divided by h: ~1e-6 at most
    scale = max(1.0, float(np.max(np.abs(jac))))
    assert np.max(np.abs(fd - jac)) < 1e-5 * scale
    mu_fd = np.sort(np.abs(np.linalg.eigvals(fd)))
    mu = np.sort(np.abs(orbit.multipliers[[not t for t in orbit.multiplier_labels]]))
    assert np.max(np.abs(mu_fd[-mu.size :] - mu)) < 1e-5 * scale


def test_gaussian_orbit_generic_engine_agrees(gaussian_orbit):
    system, orbit = gaussian_orbit
    generic = refine_periodic_orbit(
        system, orbit.start, orbit.period, engine_options={"method": "generic"}
    )
    assert generic.frozen == orbit.frozen
    # the two engines integrate to ~1e-11 (DOP853 rtol 1e-11 vs RK8 with exact events); over
    # one period with |J| ~ 1 the orbits differ by that order
    assert np.max(np.abs(generic.points - orbit.points)) < 1e-8
    assert np.max(np.abs(generic.multipliers - orbit.multipliers)) < 1e-6


def _bump(alpha, beta):
    """A smooth density on the triangle −3 <= β <= α <= 3, normalised by its mass (a fine
    midpoint rule below: from_density wants mass 1 to 1e-3)."""
    return np.exp(-((alpha - beta - 2.0) ** 2) - 0.5 * (alpha + beta) ** 2) / _BUMP_MASS


def _bump_mass(n: int = 1200) -> float:
    x = -3.0 + 6.0 * (np.arange(n) + 0.5) / n
    a, b = np.meshgrid(x, x, indexing="ij")
    f = np.exp(-((a - b - 2.0) ** 2) - 0.5 * (a + b) ** 2) * (b <= a)
    return float(f.sum() * (6.0 / n) ** 2)


_BUMP_MASS = _bump_mass()


@pytest.fixture(scope="module")
def from_density_orbits():
    # a from_density model (C¹ Everett table, 64 cells) at C = 1: a stable period-1 orbit,
    # refined with the compiled engine and again with the generic one
    model = ContinuousPreisachModel.from_density(_bump, -3.0, 3.0, resolution=64)
    system = ForcedOscillator(model, 1.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        orbit = find_periodic_orbit(system, transient=200, max_period=4)
        generic = refine_periodic_orbit(
            system, orbit.start, orbit.period, engine_options={"method": "generic"}
        )
    return system, orbit, generic, caught


def test_from_density_orbit_found_and_refined_generic(from_density_orbits):
    _, orbit, generic, _ = from_density_orbits
    assert orbit.stable
    assert orbit.residual <= orbit.tolerance * max(1.0, float(np.max(np.abs(orbit.points))))
    assert generic.frozen == orbit.frozen
    assert np.max(np.abs(generic.points - orbit.points)) < 1e-8


def test_from_density_orbit_sits_on_a_kink_of_the_closed_loop_map(from_density_orbits):
    # measured defect of the smoothness argument (staircase_orbits docstring): at this orbit
    # the closed-loop map P̃ has a kink. Independent truth: one-sided finite differences of
    # P̃ (compiled engine) in the q and M4 columns; the error of a one-sided quotient at h is
    # bounded by twice its change from h to h/10 (truncation O(h)) plus the round-off of the
    # h/10 quotient (the engine integrates to ~1e-12). Each engine's Jacobian column is one
    # of the two one-sided derivatives (which one is decided by round-off at the border);
    # the engine whose Jacobian lost the structural reset direction warns
    system, orbit, generic, caught = from_density_orbits
    coords, p_tilde = _closed_loop_map(system, orbit)
    x = coords.vector(orbit.start)
    p0 = p_tilde(x)
    h = 1e-6
    m4 = orbit.tangent_space.index("M4")
    for col in (0, m4):
        sides, errors = [], []
        for sign in (1.0, -1.0):
            e = np.zeros(x.size)
            e[col] = sign * h
            d_h = sign * (p_tilde(x + e) - p0) / h
            d_h10 = sign * (p_tilde(x + e / 10) - p0) / (h / 10)
            sides.append(d_h10)
            errors.append(2 * np.max(np.abs(d_h - d_h10)) + 2e-12 / (h / 10))
        jump = float(np.max(np.abs(sides[0] - sides[1])))
        print(f"column {col}: one-sided derivatives differ by {jump:.3g}, errors {errors}")
        assert jump > 10 * sum(errors)  # a kink, not finite-difference noise
        for o in (orbit, generic):
            got = [float(np.max(np.abs(o.monodromy[:, col] - s))) for s in sides]
            assert min(got) <= max(errors)
    warned = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    own = len(orbit.tangent_space) - 2 - len(orbit.frozen)  # the orbit's own extrema
    lost = [o for o in (orbit, generic) if o.multiplier_labels.count("reset") < own]
    assert len(warned) == len(lost)  # a Jacobian of full rank is reported, never zeroed
    assert all("not smooth" in m for m in warned)


def test_gaussian_multipliers_against_the_direct_convergence_rate(gaussian_orbit):
    # independent truth: the true motion (the engine, full staircase, no closed loop) from a
    # start off the orbit. It converges geometrically onto a neighbouring orbit of the family
    # (turning back inside the orbit's loop it leaves new remembered extrema: the staircase
    # grows), at the rate of the non-frozen multipliers. Successive section differences
    # d_n = |x_{n+1} − x_n| behave as |μ|^n times a factor between σ_min and σ_max of the real
    # basis (Re e, Im e) of the complex pair's eigenvector: the least-squares slope of log d_n
    # over n = 1 .. 16 is log|μ| within log(σ_max/σ_min)/15 (16 periods bring d_n from 1e-4
    # to ~1e-10, above the integration noise)
    system, orbit = gaussian_orbit
    free = [i for i, lab in enumerate(orbit.tangent_space) if lab not in orbit.frozen]
    jac = orbit.monodromy[np.ix_(free, free)]
    mu, vec = np.linalg.eig(jac)
    top = int(np.argmax(np.abs(mu)))
    assert abs(mu[top].imag) > 0.1  # a complex pair
    basis = np.column_stack([vec[:, top].real, vec[:, top].imag])
    sv = np.linalg.svd(basis, compute_uv=False)
    bound = math.log(sv[0] / sv[1]) / 15.0
    n = 18
    for dv in (1e-4, -1e-4):
        start = replace(orbit.start, v=orbit.start.v + dv)
        eng = system.engine(start)
        out = np.empty((n, len(eng.sample_columns)))
        eng.advance(np.arange(1, n + 1) * system.period, out)
        d = np.hypot(*np.diff(out[:, :2], axis=0).T)[:16]
        slope = np.polyfit(np.arange(16), np.log(d), 1)[0]
        print("direct rate", math.exp(slope), "|μ|", abs(mu[top]), "bound", bound)
        assert abs(slope - math.log(abs(mu[top]))) <= bound
        extrema = eng.state().operator_state.extrema
        assert len(extrema) >= len(orbit.start.operator_state.extrema)


def test_gaussian_continuation_upward_matches_newton_at_fixed_coupling(gaussian_orbit):
    # as C grows the orbit shrinks inside its loop: no frozen extremum is reached, one smooth
    # branch. Every point is a periodic orbit of the true motion (the engine over one period
    # returns to its (q, v) to the tolerance) and is what Newton at that fixed C finds from the
    # branch state (settled anew: the same frozen extrema, the same point and multipliers)
    system, orbit = gaussian_orbit
    branch = continue_orbit(system, orbit, 1.0, 1.06, step=0.02)
    assert branch.stop_reason == "reached stop" and not branch.events
    assert branch.points[-1].parameter == 1.06
    for p in branch.points[1:]:
        fixed = ForcedOscillator(system.operator, p.parameter)
        end = shoot(fixed, p.state, 1).states[-1]
        assert max(abs(end.q - p.point[0]), abs(end.v - p.point[1])) < 1e-9
        direct = refine_periodic_orbit(fixed, p.state, 1)
        assert direct.frozen == orbit.frozen
        assert np.max(np.abs(direct.points[0, :2] - p.point[:2])) < 1e-8
        assert abs(direct.max_abs_multiplier - p.max_abs_multiplier) < 1e-8
        assert p.to_dict()["frozen"] == list(orbit.frozen)


@pytest.fixture(scope="module")
def border_orbit():
    # Gaussian(2, 1, 0.1) at C = 2: a stable period-3 border orbit (its extremes reach the
    # remembered extrema at the very reversals that replace them)
    system = ForcedOscillator(ContinuousPreisachModel.gaussian(2.0, 1.0, 0.1), 2.0)
    orbit = find_periodic_orbit(system, transient=200, max_period=8)
    assert orbit.period == 3 and orbit.stable
    return system, orbit


def _active_eigensystem(orbit):
    """Multipliers (by decreasing modulus) and eigenvectors of the non-frozen block J_rr."""
    free = [i for i, lab in enumerate(orbit.tangent_space) if lab not in orbit.frozen]
    mu, vec = np.linalg.eig(orbit.monodromy[np.ix_(free, free)])
    order = np.argsort(-np.abs(mu))
    return free, mu[order], vec[:, order]


def test_border_orbit_true_motion_converges_at_the_floquet_rate(border_orbit):
    # independent truth, no tangent code: the engine's nonlinear motion from the orbit point
    # displaced by ε·w1 (w1 the real eigenvector of the leading multiplier μ1, unit in (q, v)).
    # On one side of the border every maximum/minimum wipes the remembered one out (the
    # staircase keeps the orbit's length: there P^k is the closed-loop map, the orbit point is
    # the limit); on the other side the motion turns back inside the loop, leaves a new pair
    # (+2 entries) and converges onto a neighbouring orbit of the family. On the wipe-out side
    # d_n = |(q_n, v_n) − (q*, v*)| = c·μ1^n·(1 + O(d_n) + O((μ2/μ1)^n)). The least-squares
    # slope of log d_n over the orbit periods with d_n >= 1e-8 (from n = 2: (μ2/μ1)² ≈ 2e-4)
    # is log μ1 up to (i) the nonlinearity, a shift of log d_n by O(d_n) <= O(ε) = 1e-4, and
    # (ii) the noise of x* (Newton residual 1e-12) and of the integration (~1e-12), <= 1e-4
    # relative at d_n >= 1e-8: a slope error <= 2e-4 per orbit period, i.e. 1e-5 in the
    # exponent (÷ k·T = 18.8), ten times below the 1e-4 that is asserted
    system, orbit = border_orbit
    kt = orbit.period * system.period
    free, mu, vec = _active_eigensystem(orbit)
    assert mu[0].imag == 0.0 and 0.0 < mu[0].real < 1.0 and abs(mu[1]) < 0.1 * abs(mu[0])
    w = np.zeros(len(orbit.tangent_space))
    w[free] = vec[:, 0].real / np.linalg.norm(vec[:2, 0].real)
    coords = StateCoordinates(system, orbit.start)
    x = coords.vector(orbit.start)
    n_ext = len(orbit.start.operator_state.extrema)
    exponent = math.log(mu[0].real) / kt
    lengths, slopes = {}, {}

    def rate(d):
        n_fit = np.array([n for n in range(2, 16) if d[n - 1] >= 1e-8])
        assert n_fit.size >= 8
        return np.polyfit(n_fit, np.log([d[n - 1] for n in n_fit]), 1)[0]

    for eps in (1e-4, -1e-4):
        eng = system.engine(coords.state(x + eps * w, orbit.start))
        out = np.empty((1, len(eng.sample_columns)))
        pts, sizes = [], set()
        for n in range(1, 17):
            eng.advance(np.array([n * kt]), out)
            pts.append(out[0, :2].copy())
            sizes.add(len(eng.state().operator_state.extrema))
        pts = np.array(pts)
        lengths[eps] = sizes
        # to the orbit point (the limit on the wipe-out side), and successive differences
        # (which decay at the rate whatever the limit: on the other side a neighbouring orbit)
        slopes[eps] = (rate(np.hypot(*(pts - x[:2]).T)), rate(np.hypot(*np.diff(pts, axis=0).T)))
        print(
            f"ε = {eps:+.0e}: staircase sizes {sizes}, direct exponents "
            f"{slopes[eps][0] / kt:.8f} / {slopes[eps][1] / kt:.8f}, Floquet {exponent:.8f}"
        )
    wipe = [eps for eps, sizes in lengths.items() if sizes == {n_ext}]
    assert len(wipe) == 1  # exactly one side keeps the orbit's staircase
    other = -wipe[0]
    assert lengths[other] == {n_ext + 2}  # the other leaves one new pair and keeps it
    assert abs(slopes[wipe[0]][0] / kt - exponent) < 1e-4
    # turning back inside, the motion follows a neighbouring orbit of the family, whose
    # multiplier differs from μ1 by O(ε): the same rate within the same bound, measured by
    # the successive differences (the neighbouring orbit's distance from x* is not known;
    # measured below 1e-11)
    assert abs(slopes[other][1] / kt - exponent) < 1e-4


def test_gaussian_floquet_equals_memory_frozen_lyapunov_exponents(border_orbit):
    # the Lyapunov counterpart of the closed-loop map: memory_frozen_exponents follows (q, v)
    # and the memory younger than the projection interval, dropping the long-lived (frozen)
    # extrema. Projection every k = 3 periods (the own extrema are pushed again within one
    # orbit period). At this border orbit the base trajectory (started on the orbit) sits on
    # the border to round-off and leaves pairs of near-duplicate extrema (1e-15 .. 1e-13
    # apart); its own extrema come back at bit-identical values in many periods, which the
    # former "same label, same value" test took for frozen memory (it zeroed their fresh
    # rows: -0.0142 or -0.0175 instead of -0.0338, depending on round-off). The survival
    # probe is exact.
    # Finite-time error: from the start columns (e_q, e_v) the QR average is the Floquet
    # exponent plus a boundary term B/t, computed here from the eigenvectors (c = V⁻¹ e_q:
    # the first column grows as |c_1|·|w1[q, v]|·μ1^n; the sum of the two as
    # |det W_qv · det C|·(μ1 μ2)^n); the remainder after it is of order
    # (μ2/μ1)/(1 − μ2/μ1)·|c_2 w2|/|c_1 w1| / t =: r (the second mode's transient summed as
    # a geometric series; |log(1 + x)| <= 2|x| for |x| <= 1/2 gives the factor 2), plus 1e-12
    # for the start's Newton residual (1e-12) over the first periods
    system, orbit = border_orbit
    k, kt = orbit.period, orbit.period * system.period
    n = 2000
    start = orbit.start
    ly = memory_frozen_exponents(
        system, n * kt, 0.0, start.q, start.v, start.operator_state, projection_periods=k
    )
    active = np.array([not t for t in orbit.multiplier_labels])
    floquet = np.sort(orbit.exponents[active])[::-1][:2]
    print("Floquet", floquet, "memory-frozen Lyapunov", ly.exponents)
    assert np.max(np.abs(floquet - ly.exponents)) < 1e-4
    free, mu, vec = _active_eigensystem(orbit)
    mu, vec = mu.real, vec.real  # the two leading multipliers are real
    c = np.linalg.solve(vec, np.eye(len(free))[:, :2])
    w_qv = vec[:2, :2]
    b1 = math.log(abs(c[0, 0]) * np.linalg.norm(w_qv[:, 0]))
    b_sum = math.log(abs(np.linalg.det(w_qv) * np.linalg.det(c[:2, :2])))
    predicted = floquet + np.array([b1, b_sum - b1]) / (n * kt)
    ratio = abs(mu[1] / mu[0])
    cross = ratio / (1 - ratio) * abs(c[1, 0]) * np.linalg.norm(w_qv[:, 1])
    remainder = cross / (abs(c[0, 0]) * np.linalg.norm(w_qv[:, 0])) / (n * kt)
    print("boundary term", predicted - floquet, "left", ly.exponents - predicted, remainder)
    assert np.max(np.abs(ly.exponents - predicted)) <= 2 * remainder + 1e-12
