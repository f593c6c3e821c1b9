"""The compiled Householder QR of the Benettin loop against LAPACK (``np.linalg.qr``)."""

import numpy as np
import pytest

from analysis.dynamics.lyapunov import householder_qr


@pytest.mark.parametrize("shape", [(2, 2), (3, 3), (5, 3), (3, 5), (1, 2), (40, 7)])
def test_householder_qr_matches_lapack(shape):
    rng = np.random.default_rng(sum(shape))
    for trial in range(40):
        y = rng.normal(size=shape) * 10.0 ** rng.uniform(-8, 8)
        if trial % 5 == 0:
            y[:, 0] = 0.0  # a collapsed direction: R_00 = 0
        q, diag, finite = householder_qr(y)
        assert finite
        q_ref, r_ref = np.linalg.qr(y)
        scale = np.abs(np.diag(r_ref)).max()
        np.testing.assert_allclose(diag, np.abs(np.diag(r_ref)), rtol=0, atol=1e-13 * scale)
        m = min(shape)
        np.testing.assert_allclose(q.T @ q, np.eye(m), atol=1e-13)
        # the same reflections as LAPACK: the same columns wherever R_jj != 0
        live = np.abs(np.diag(r_ref)) > 1e-12 * scale
        np.testing.assert_allclose(np.abs(q[:, live]), np.abs(q_ref[:, live]), atol=1e-12)


def test_householder_qr_reports_non_finite():
    y = np.eye(3)
    y[1, 2] = np.nan
    assert not householder_qr(y)[2]
    y[1, 2] = np.inf
    assert not householder_qr(y)[2]
