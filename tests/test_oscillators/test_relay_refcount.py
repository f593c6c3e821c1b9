"""The relay event loop without numba's reference counting against the plain loop.

``oscillators.engines._relay_kernels`` compiles its event loop with ``_nrt=False``, an option
outside numba's public API (module docstring there); ``HYSTERESIS_RELAY_REFCOUNT=1`` compiles
the plain, reference-counted loop instead. Both must integrate the same motion: the plain loop
runs in a subprocess with its own numba cache directory (the cache index does not tell the two
builds apart) and the results are compared with this process's.

Truth and tolerance: the two builds run the same arithmetic; where a compiler fuses other
multiply-adds they differ by about one ulp per hop. Over ``t = 20`` of a regular dimers motion
(about 10⁴ switches, no exponential growth beyond the orbit's own contraction) that bounds the
difference by ~1e4 ulp of O(1) values: 1e-11. On numba 0.68 the two are bit-identical.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from oscillators.engines import _relay_kernels

SCRIPT = textwrap.dedent(
    """
    import json
    import numpy as np
    from analysis.experiments.models import build_operator
    from oscillators import ForcedOscillator
    from analysis.dynamics.lyapunov import lyapunov_spectrum

    op = build_operator("dimers", spins=2000, seed=3)  # the paper's disorder
    system = ForcedOscillator(op, coupling=2.9)
    traj = system.trajectory(20.0, sample_dt=0.5)
    spectrum = lyapunov_spectrum(system, 40.0)
    print(json.dumps({"q": traj.q.tolist(), "v": traj.v.tolist(),
                      "lyapunov": list(map(float, spectrum.exponents))}))
    """
)


def _run(env_extra: dict[str, str], cache: str) -> dict:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, **env_extra)
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_event_loop_without_refcounting_matches_the_plain_loop(tmp_path):
    plain = _run({_relay_kernels.PLAIN_LOOP_ENV: "1"}, str(tmp_path / "plain"))
    fast = _run({_relay_kernels.PLAIN_LOOP_ENV: "0"}, str(tmp_path / "fast"))
    for key in ("q", "v", "lyapunov"):
        np.testing.assert_allclose(np.array(fast[key]), np.array(plain[key]), rtol=0, atol=1e-11)


def test_the_loop_options_are_probed_not_assumed():
    """Without the environment switch the loop is built with ``_nrt=False`` exactly when numba
    accepts the option; with it, always plain."""
    assert _relay_kernels._LOOP_OPTIONS in ({}, {"_nrt": False})
    env = dict(os.environ, **{_relay_kernels.PLAIN_LOOP_ENV: "1"})
    probe = "import oscillators.engines._relay_kernels as k; print(k._LOOP_OPTIONS)"
    out = subprocess.run(
        [sys.executable, "-c", probe], env=env, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "{}"
