"""The relay engine on arbitrary discrete Preisach models against independent truth.

References written here from the paper only: scipy's DOP853 (rtol = atol = 1e-12) with terminal
events on the nearest thresholds, the relays switched by hand (up once q >= alpha, down once
q < beta, all relays at one threshold together), M = Σ w·y; finite differences of the flow map;
and the equality of the three methods (nested O(1) kernel, heap kernel, Python reference path
through ``switching()``/``apply()``) switch by switch.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from relay_test_support import relay_brute_force

from analysis.dynamics.lyapunov import lyapunov_spectrum
from hysteresis import PreisachModel, Relay, SpinDimerEnsemble
from oscillators import ForcedOscillator
from oscillators.engines import GrazingError, RelayEngine
from oscillators.results import OscillatorState

ZETA = 0.05
OMEGA = 1.0
T = 2.0 * math.pi


def random_width_model(n, seed, weights="random", grid=None):
    """Centres N(0, 1), half-widths U(0.5, 1.5) (optionally on a grid: ties), random weights."""
    rng = np.random.default_rng(seed)
    c = rng.normal(size=n)
    r = rng.uniform(0.5, 1.5, size=n)
    if grid is not None:
        c, r = np.round(c / grid) * grid, np.round(r / grid) * grid
    if weights == "random":
        w = rng.random(n) + 0.05
        w /= w.sum()
        w[np.argmax(w)] += 1.0 - w.sum()
    else:
        w = None
    return PreisachModel.from_relays(c + r, c - r, w)


def brute_force(alpha, beta, w, c, t_end, q0=-1.0, v0=0.1):
    """Switch events (time, q, v, ΔM) and final outputs, relays by hand (relay_test_support)."""
    return relay_brute_force(alpha, beta, w, c, t_end, q0, v0, ZETA, OMEGA)


def start(q0=-1.0, v0=0.1, opstate=None, phi0=0.0):
    return OscillatorState(q=q0, v=v0, phi=phi0, operator_state=opstate, t=0.0)


def run(system, t_end, method, state=None, taylor=True):
    eng = RelayEngine(system, state or start(), method=method, taylor=taylor)
    eng.advance(t_end, record=True)
    return eng, eng.records()["switches"]


def assert_same_switches(a, b, tol):
    assert a.size == b.size, (a.size, b.size)
    for name in ("time", "q", "v"):
        np.testing.assert_allclose(a[name], b[name], rtol=0, atol=tol)
    np.testing.assert_allclose(a["jump"], b["jump"], rtol=0, atol=1e-12)


# -- against the brute force ---------------------------------------------------------------------
@pytest.mark.parametrize("c", [2.9, 4.0])
def test_random_width_preisach_matches_brute_force(c):
    model = random_width_model(50, seed=1)
    assert model.relay_table().nested_plan() is None  # a genuinely general model
    t_end = 20 * T
    ref, y_end = brute_force(model.alpha, model.beta, model.weights, c, t_end)
    eng, sw = run(ForcedOscillator(model, c), t_end, "auto")
    assert eng.method == "heap"
    assert ref.shape[0] >= 100
    ref_arr = np.zeros(ref.shape[0], dtype=sw.dtype)
    for j, name in enumerate(sw.dtype.names):
        ref_arr[name] = ref[:, j]
    assert_same_switches(sw, ref_arr, 1e-8)
    # the final operator state, rebuilt from the kernel's relays, has the brute force's relays
    fin = eng.state()
    np.testing.assert_array_equal(model.relay_outputs(fin.operator_state), y_end)
    assert abs(model.output(fin.operator_state) - eng.output) < 1e-12


def test_ties_and_zero_widths_match_brute_force():
    """Thresholds on a grid (several relays share alpha or beta) and zero-width relays."""
    rng = np.random.default_rng(7)
    n = 40
    c = np.round(rng.normal(size=n) / 0.25) * 0.25
    r = np.round(rng.uniform(0.0, 1.5, size=n) / 0.25) * 0.25
    r[:8] = 0.0
    w = np.full(n, 1.0 / n)
    w[:10] *= 2.0
    w /= w.sum()
    w[-1] = 1.0 - w[:-1].sum()
    model = PreisachModel.from_relays(c + r, c - r, w)
    assert np.unique(model.alpha).size < n and model.relay_table().nested_plan() is None
    cc = 3.0
    t_end = 20 * T
    ref, y_end = brute_force(model.alpha, model.beta, model.weights, cc, t_end)
    eh, sw = run(ForcedOscillator(model, cc), t_end, "heap")
    _, sg = run(ForcedOscillator(model, cc), t_end, "generic")
    assert ref.shape[0] >= 50
    assert sw.size == ref.shape[0] == sg.size
    np.testing.assert_allclose(sw["time"], ref[:, 0], rtol=0, atol=1e-8)
    np.testing.assert_allclose(sw["jump"], ref[:, 3], rtol=0, atol=1e-12)
    assert_same_switches(sw, sg, 1e-9)
    # several relays at one threshold flip in one event: some jumps are sums of weights
    assert np.any(np.abs(sw["jump"]) > 2 * w.max() + 1e-12)
    np.testing.assert_array_equal(model.relay_outputs(eh.state().operator_state), y_end)


# -- the three methods agree switch by switch ----------------------------------------------------
def test_heap_equals_nested_equals_generic_on_dimers():
    ens = SpinDimerEnsemble.random(200, 2.0, 1.0, 2.0, seed=0)
    sysm = ForcedOscillator(ens, 4.0)
    en, sn = run(sysm, 10 * T, "nested")
    eh, sh = run(sysm, 10 * T, "heap")
    eg, sg = run(sysm, 10 * T, "generic")
    assert (en.method, eh.method, eg.method) == ("nested", "heap", "generic")
    assert sn.size > 300
    assert_same_switches(sh, sn, 1e-11)
    assert_same_switches(sg, sn, 1e-10)
    for e in (eh, eg):
        np.testing.assert_array_equal(
            ens.relay_outputs(e.state().operator_state),
            ens.relay_outputs(en.state().operator_state),
        )


def test_heap_equals_generic_random_widths_and_weights():
    model = random_width_model(200, seed=3)
    sysm = ForcedOscillator(model, 4.0)
    eh, sh = run(sysm, 8 * T, "heap")
    eg, sg = run(sysm, 8 * T, "generic")
    assert sh.size > 300
    assert_same_switches(sh, sg, 1e-10)
    assert eh.n_events == eg.n_events == sh.size
    np.testing.assert_array_equal(
        model.relay_outputs(eh.state().operator_state),
        model.relay_outputs(eg.state().operator_state),
    )
    # the heap kernel's output never drifts from the correctly rounded sum of its relays
    y = eh.relay_outputs()
    assert abs(eh.output - math.fsum(model.weights * y)) < 1e-15


def test_heap_taylor_hops_equal_exact_scan():
    model = random_width_model(2000, seed=4, weights="equal")
    sysm = ForcedOscillator(model, 4.0)
    _, a = run(sysm, 3 * T, "heap", taylor=True)
    _, b = run(sysm, 3 * T, "heap", taylor=False)
    assert a.size > 1000
    # round-off amplified by low-velocity saltations (see test_oscillator_pc): 1e-11
    assert_same_switches(a, b, 1e-11)


def test_continuing_from_the_final_state_equals_one_run():
    model = random_width_model(300, seed=5)
    sysm = ForcedOscillator(model, 3.5)
    long = RelayEngine(sysm, start(), method="heap")
    out_long = np.empty((2, 3))
    long.advance(np.array([3 * T, 5 * T]), out_long)
    first = RelayEngine(sysm, start(), method="heap")
    first.advance(3 * T)
    mid = first.state()
    assert mid.t == pytest.approx(3 * T)
    second = RelayEngine(sysm, mid, method="heap")
    out = np.empty((1, 3))
    second.advance(2 * T, out)
    np.testing.assert_allclose(out[0], out_long[1], rtol=0, atol=1e-12)


def test_single_relay_and_nested_method_errors():
    sysm = ForcedOscillator(Relay(0.5, -0.5), 2.0)
    for method in ("nested", "heap", "generic"):
        eng, sw = run(sysm, 5 * T, method)
        assert sw.size >= 4 and set(np.abs(sw["jump"])) == {2.0}
    model = random_width_model(20, seed=0)
    with pytest.raises(ValueError, match="nested"):
        RelayEngine(ForcedOscillator(model, 1.0), start(), method="nested")
    with pytest.raises(ValueError, match="method"):
        RelayEngine(ForcedOscillator(model, 1.0), start(), method="fast")
    eng = RelayEngine(ForcedOscillator(model, 1.0), start())
    eng.advance(1.0)
    with pytest.raises(ValueError, match="elapsed"):
        eng.advance(0.5)
    with pytest.raises(ValueError, match="finite"):
        eng.advance(np.inf)
    with pytest.raises(ValueError, match="start_tangent"):
        eng.deviations()


def test_zero_weight_relays_are_silent():
    """Relays of weight 0 never change M: no events (like switching()), same orbit."""
    rng = np.random.default_rng(9)
    n = 30
    c = rng.normal(size=n)
    r = rng.uniform(0.5, 1.5, size=n)
    w = rng.random(n)
    w[::3] = 0.0
    w /= w.sum()
    w[np.argmax(w)] += 1.0 - w.sum()
    full = PreisachModel.from_relays(c + r, c - r, w)
    keep = w > 0
    reduced = PreisachModel.from_relays(c[keep] + r[keep], c[keep] - r[keep], w[keep])
    eh, sh = run(ForcedOscillator(full, 3.0), 10 * T, "heap")
    er, sr = run(ForcedOscillator(reduced, 3.0), 10 * T, "heap")
    _, sg = run(ForcedOscillator(full, 3.0), 10 * T, "generic")
    assert_same_switches(sh, sr, 0.0)
    assert_same_switches(sh, sg, 1e-10)
    np.testing.assert_array_equal(
        full.relay_outputs(eh.state().operator_state)[keep],
        reduced.relay_outputs(er.state().operator_state),
    )


# -- tangent flow --------------------------------------------------------------------------------
def _flow(system, duration, x0, opstate, method):
    eng = RelayEngine(system, start(x0[0], x0[1], opstate, x0[2]), method=method)
    eng.advance(duration)
    s = eng.state()
    return np.array([s.q, s.v]), eng.n_events


@pytest.mark.parametrize(
    "method, seed, c", [("heap", 1, 4.0), ("heap", 2, 2.9), ("generic", 3, 4.0), ("heap", 4, -3.0)]
)
def test_tangent_flow_equals_finite_differences(method, seed, c):
    model = random_width_model(50, seed=seed)
    sysm = ForcedOscillator(model, c)
    x0 = np.array([-1.0, 0.1, 0.3])
    opstate = model.initial_state(-1.0)
    duration = 3 * T
    eng = RelayEngine(sysm, start(x0[0], x0[1], opstate, x0[2]), method=method)
    eng.start_tangent(include_phase=True)
    assert eng.tangent_space == ("q", "v", "phi")
    eng.advance(duration)
    jac = eng.deviations()
    assert eng.n_events >= 10 and eng.rank_bound() == 3
    eps = 1e-7
    fd = np.empty((2, 3))
    for j in range(3):
        dx = np.zeros(3)
        dx[j] = eps
        fp, n_p = _flow(sysm, duration, x0 + dx, opstate, method)
        fm, n_m = _flow(sysm, duration, x0 - dx, opstate, method)
        assert n_p == n_m == eng.n_events  # the same switch sequence on both sides
        fd[:, j] = (fp - fm) / (2 * eps)
    np.testing.assert_allclose(jac[:2, :], fd, atol=1e-5 * np.max(np.abs(fd)))
    np.testing.assert_array_equal(jac[2], [0.0, 0.0, 1.0])
    # Liouville: det of the (q, v) block is exp(-2ζt) (saltation matrices have det 1)
    assert math.isclose(np.linalg.det(jac[:2, :2]), math.exp(-2 * ZETA * duration), rel_tol=1e-8)


def test_heap_and_nested_tangent_agree_on_dimers():
    ens = SpinDimerEnsemble.random(400, 2.0, 1.0, 2.0, seed=6)
    sysm = ForcedOscillator(ens, 4.0)
    jacs = []
    for method in ("nested", "heap", "generic"):
        eng = RelayEngine(sysm, start(), method=method)
        eng.start_tangent()
        eng.advance(np.linspace(1.0, 4 * T, 7))
        jacs.append(eng.deviations())
    np.testing.assert_allclose(jacs[1], jacs[0], rtol=1e-9)
    np.testing.assert_allclose(jacs[2], jacs[0], rtol=1e-8)


def test_set_deviations_is_linear():
    model = random_width_model(80, seed=8)
    sysm = ForcedOscillator(model, 4.0)
    a = RelayEngine(sysm, start(), method="heap")
    a.start_tangent()
    a.advance(2 * T)
    jac = a.deviations()
    b = RelayEngine(sysm, start(), method="heap")
    b.start_tangent()
    y0 = np.array([[0.3, -1.0], [2.0, 0.5]])
    b.set_deviations(y0)
    b.advance(2 * T)
    np.testing.assert_allclose(b.deviations(), jac @ y0, rtol=1e-12, atol=1e-12)
    with pytest.raises(ValueError, match="shape"):
        b.set_deviations(np.eye(3))


def test_generic_grazing_switch_raises(monkeypatch):
    """A switch found at a turning point (v* = 0) has an infinite saltation: a clear error."""
    from oscillators.engines import _relay_kernels as kern

    sysm = ForcedOscillator(Relay(0.5, -0.5), 2.0)
    scan = kern.scan_crossing
    calls = []

    def switch_here_once(par, force, q, v, c, s, tau, horizon, up, down):
        calls.append(v)
        if len(calls) == 1:
            return 0.0, 1  # the crossing is the current point, where v = 0
        return scan(par, force, q, v, c, s, tau, horizon, up, down)

    monkeypatch.setattr(kern, "scan_crossing", switch_here_once)
    eng = RelayEngine(sysm, start(0.0, 0.0), method="generic")
    eng.start_tangent()
    with pytest.raises(GrazingError, match="grazing"):
        eng.advance(1.0)
    # the trajectory itself is defined there: the relay switches (u >= alpha), no error
    calls.clear()
    eng, sw = run(sysm, 0.05, "generic", state=start(0.0, 0.0))
    assert sw["v"][0] == 0.0 and sw["jump"][0] == 2.0


# -- Lyapunov spectra through the one QR loop ------------------------------------------------------
@pytest.mark.parametrize("seed, c", [(0, 4.0), (1, 2.9), (2, -3.0)])
def test_random_width_spectrum_sum_is_phase_space_contraction(seed, c):
    """λ1 + λ2 = −2ζ in (q, v): Liouville (det of every saltation matrix is 1)."""
    model = random_width_model(300, seed=seed)
    sysm = ForcedOscillator(model, c)
    res = lyapunov_spectrum(sysm, 400.0, 40.0, engine_options={"method": "heap"})
    assert res.extra["engine"].startswith("relay kernel (heap")
    assert res.n_switches > 1000
    assert res.tangent_space == ("q", "v")
    assert abs(res.exponents.sum() + 2 * ZETA) < 1e-9


def test_heap_and_generic_spectra_agree():
    model = random_width_model(60, seed=11)
    sysm = ForcedOscillator(model, 3.5)
    a = lyapunov_spectrum(sysm, 60.0, engine_options={"method": "heap"})
    b = lyapunov_spectrum(sysm, 60.0, engine_options={"method": "generic"})
    assert a.n_switches == b.n_switches > 100
    np.testing.assert_allclose(a.exponents, b.exponents, atol=1e-8)


def test_uncoupled_random_width_exponents():
    """C = 0: the linear oscillator, λ = −ζ twice (underdamped), whatever the relays do."""
    sysm = ForcedOscillator(random_width_model(100, seed=12), 0.0)
    res = lyapunov_spectrum(sysm, 600.0, engine_options={"method": "heap"})
    assert res.n_switches > 50
    np.testing.assert_allclose(res.exponents, [-ZETA, -ZETA], atol=2e-3)


def test_generic_path_matches_the_heap_and_the_relay_contract_is_required():
    """The Python reference path (switching()/apply()) gives the heap's switches; an operator
    without the relay contract cannot be built (its methods are abstract, hysteresis.base)."""
    from hysteresis.base import PiecewiseConstantHysteron

    class Wrapped(PiecewiseConstantHysteron):
        def __init__(self, inner):
            self.inner = inner

        def initial_state(self, u0):
            return self.inner.initial_state(u0)

        def apply(self, inputs, state=None):
            return self.inner.apply(inputs, state)

        def output(self, state):
            return self.inner.output(state)

        def switching(self, state):
            return self.inner.switching(state)

    model = random_width_model(30, seed=13)
    eng, sw = run(ForcedOscillator(model, 3.0), 5 * T, "generic")
    assert eng.method == "generic"
    _, ref = run(ForcedOscillator(model, 3.0), 5 * T, "heap")
    assert_same_switches(sw, ref, 1e-10)
    with pytest.raises(TypeError, match="relay_table"):
        Wrapped(model)
