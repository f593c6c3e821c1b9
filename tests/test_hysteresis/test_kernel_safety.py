"""Compiled Preisach kernels: never out of bounds whatever the data, and the SIMD lane sums
agree bit for bit with their plain scalar fallback."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from hysteresis import PreisachModel
from hysteresis.preisach import _kernels as k

ADVERSARIAL = textwrap.dedent(
    """
    import numpy as np
    from hysteresis import PreisachModel
    from hysteresis.preisach import _kernels as k

    rng = np.random.default_rng(7)
    beta = rng.normal(size=600)
    m = PreisachModel.from_relays(beta + rng.random(600), beta)
    specials = np.array([np.nan, np.inf, -np.inf, 1e308, -1e308, 0.0, 5e-324])
    mode = k.lane_mode()
    for trial in range(300):
        u = rng.choice(np.concatenate([specials, rng.normal(size=8)]), size=rng.integers(1, 40))
        depth = int(rng.integers(1, 12))
        cap = depth + 2 + u.size + 4
        vals = np.empty(cap)
        vals[:2] = (np.inf, -np.inf)
        vals[2 : depth + 2] = rng.choice(specials, size=depth)
        # forged relay counts: negative, beyond n, anything
        cnt_a = rng.integers(-10**6, 10**6, size=cap)
        cnt_b = rng.integers(-10**6, 10**6, size=cap)
        grid = rng.choice(np.array([0.0, np.nan, np.inf, -np.inf, 1e308, 1.0]), size=4)
        k.discrete_apply(u, m._alpha_by_a, m._beta_key_a, m._w_by_a, m._table_a,
                         m._alpha_key_b, m._beta_by_b, m._w_by_b, m._table_b,
                         m._starts_a, m._starts_b, grid, vals, cnt_a, cnt_b, depth + 1, 0.0, mode)
        k.discrete_switching(m._alpha_by_a, m._beta_key_a, m._w_by_a, m._table_a,
                             m._alpha_key_b, m._beta_by_b, m._w_by_b, m._table_b,
                             vals, cnt_a, cnt_b, depth + 1, mode)
        v2 = vals.copy()
        refs = np.full(cap, -1, dtype=np.int64)
        k.continuous_staircase(u, v2, refs, depth + 1)
        for x in specials:
            for starts, values in ((m._starts_a, m._alpha_by_a), (m._starts_b, m._beta_by_b)):
                for lo, inv_h in ((0.0, np.nan), (-1e308, np.inf), (np.nan, 1.0), (0.0, 0.0)):
                    c = k._count_le_bucket(values, starts, lo, inv_h, x)
                    assert 0 <= c <= values.size
            assert 0 <= k._count_le(m._alpha_by_a, int(rng.integers(-10**6, 10**6)), x) <= 600
    print("ok")
    """
)


def test_kernels_never_index_out_of_bounds_on_adversarial_data():
    # run in a child: a regression would be a segmentation fault, which must not kill pytest
    proc = subprocess.run(
        [sys.executable, "-c", ADVERSARIAL], capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip().endswith("ok")


def test_issue_crash_case_is_refused_at_construction():
    with pytest.raises(ValueError, match=r"alpha must have magnitude <= 1e\+300"):
        PreisachModel.from_relays([-1e308], [-1e308])


def test_huge_but_admissible_thresholds_give_the_exact_relay_answer():
    # thresholds at the magnitude bound: centres and widths finite, result the plain relay one
    m = PreisachModel.from_relays([1e300, -1e300], [-1e300, -1e300], [0.5, 0.5])
    out, _ = m.apply([-1e300, 0.0, 1e300, 0.0, -1e300 * 0.5])
    # relay 1 (1e300, -1e300): up only at 1e300; relay 2 (-1e300, -1e300): up from -1e300 on
    np.testing.assert_array_equal(out, [0.0, 0.0, 1.0, 1.0, 1.0])


@pytest.mark.parametrize("seed", range(5))
def test_simd_and_scalar_lane_sums_agree_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 700))
    keys = rng.normal(size=n)
    keys[rng.random(n) < 0.1] = -np.inf
    weights = rng.random(n) / n
    for _ in range(50):
        a = int(rng.integers(0, n))
        b = int(rng.integers(a, n + 1))
        x = float(rng.normal())
        simd = k.masked_sums(keys, weights, a, b, x, k.SIMD_MODE)
        scalar = k.masked_sums(keys, weights, a, b, x, k.SCALAR_MODE)
        assert simd == scalar  # same additions in the same order
        # and both equal the plain four-lane reading of the docstring
        lanes = [[0.0] * 4, [0.0] * 4]
        for i in range(a, a + 4 * ((b - a) // 4)):
            lanes[0][(i - a) % 4] += weights[i] if keys[i] > x else 0.0
            lanes[1][(i - a) % 4] += weights[i] if keys[i] <= x else 0.0
        for i in range(a + 4 * ((b - a) // 4), b):
            lanes[0][0] += weights[i] if keys[i] > x else 0.0
            lanes[1][0] += weights[i] if keys[i] <= x else 0.0
        want = tuple((s[0] + s[1]) + (s[2] + s[3]) for s in lanes)
        assert simd == want


def test_model_outputs_identical_with_the_scalar_fallback(monkeypatch):
    rng = np.random.default_rng(3)
    alpha = rng.normal(size=3000) + 0.5
    m = PreisachModel.from_relays(alpha, alpha - rng.random(3000), rng.dirichlet(np.ones(3000)))
    u = np.cumsum(rng.normal(size=4000)) * 0.3
    monkeypatch.setattr(k, "USE_SIMD", True)
    out_simd, st_simd = m.apply(u)
    sw_simd = m.switching(st_simd)
    monkeypatch.setattr(k, "USE_SIMD", False)
    assert k.lane_mode() is k.SCALAR_MODE
    out_scalar, st_scalar = m.apply(u)
    np.testing.assert_array_equal(out_simd, out_scalar)
    assert st_simd == st_scalar and sw_simd == m.switching(st_scalar)


def test_environment_variable_selects_the_scalar_path():
    env = dict(os.environ, HYSTERESIS_NO_SIMD="1")
    code = (
        "from hysteresis.preisach import _kernels as k, PreisachModel\n"
        "assert k.lane_mode() is k.SCALAR_MODE\n"
        "print(PreisachModel.from_relays([1.0, 0.0], [-1.0, 0.0]).apply([2.0, -0.5])[0])\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["[1.", "0.]"]
