"""Dormand–Prince 8(5,3): the 12 stages of the 8th-order solution and the one RK8 step.

Source: E. Hairer, S. P. Nørsett and G. Wanner, *Solving Ordinary Differential Equations I:
Nonstiff Problems*, 2nd ed., Springer (1993), Sec. II.10, and the authors' Fortran code
``dop853.f`` (coefficients of J. R. Dormand and P. J. Prince, "Practical Runge–Kutta processes",
SIAM J. Sci. Stat. Comput. 10 (1989) 977–989). Carried here as plain numbers so that the
compiled kernels depend on no private module of another library; the values are the decimal
representations of the published rational/real coefficients rounded to float64.
``tests/test_oscillators/test_dop853.py`` checks the order conditions up to order 8.
:func:`rk8_step` is the fixed-step RK8 step of the play and continuous kernels.
"""

from __future__ import annotations

import numpy as np
from numba import njit

N_STAGES = 12

#: Nodes c_i.
C = np.array(
    [
        np.float64(0.0),
        np.float64(0.05260015195876773),
        np.float64(0.0789002279381516),
        np.float64(0.1183503419072274),
        np.float64(0.2816496580927726),
        np.float64(0.3333333333333333),
        np.float64(0.25),
        np.float64(0.3076923076923077),
        np.float64(0.6512820512820513),
        np.float64(0.6),
        np.float64(0.8571428571428571),
        np.float64(1.0),
    ]
)

#: Weights b_i of the 8th-order solution.
B = np.array(
    [
        np.float64(0.054293734116568765),
        np.float64(0.0),
        np.float64(0.0),
        np.float64(0.0),
        np.float64(0.0),
        np.float64(4.450312892752409),
        np.float64(1.8915178993145003),
        np.float64(-5.801203960010585),
        np.float64(0.3111643669578199),
        np.float64(-0.1521609496625161),
        np.float64(0.20136540080403034),
        np.float64(0.04471061572777259),
    ]
)

#: Runge–Kutta matrix a_ij (lower triangular, 12 x 12).
A = np.zeros((N_STAGES, N_STAGES))
A[1, 0] = np.float64(0.05260015195876773)
A[2, 0] = np.float64(0.0197250569845379)
A[2, 1] = np.float64(0.0591751709536137)
A[3, 0] = np.float64(0.02958758547680685)
A[3, 2] = np.float64(0.08876275643042054)
A[4, 0] = np.float64(0.2413651341592667)
A[4, 2] = np.float64(-0.8845494793282861)
A[4, 3] = np.float64(0.924834003261792)
A[5, 0] = np.float64(0.037037037037037035)
A[5, 3] = np.float64(0.17082860872947386)
A[5, 4] = np.float64(0.12546768756682242)
A[6, 0] = np.float64(0.037109375)
A[6, 3] = np.float64(0.17025221101954405)
A[6, 4] = np.float64(0.06021653898045596)
A[6, 5] = np.float64(-0.017578125)
A[7, 0] = np.float64(0.03709200011850479)
A[7, 3] = np.float64(0.17038392571223998)
A[7, 4] = np.float64(0.10726203044637328)
A[7, 5] = np.float64(-0.015319437748624402)
A[7, 6] = np.float64(0.008273789163814023)
A[8, 0] = np.float64(0.6241109587160757)
A[8, 3] = np.float64(-3.3608926294469414)
A[8, 4] = np.float64(-0.868219346841726)
A[8, 5] = np.float64(27.59209969944671)
A[8, 6] = np.float64(20.154067550477894)
A[8, 7] = np.float64(-43.48988418106996)
A[9, 0] = np.float64(0.47766253643826434)
A[9, 3] = np.float64(-2.4881146199716677)
A[9, 4] = np.float64(-0.590290826836843)
A[9, 5] = np.float64(21.230051448181193)
A[9, 6] = np.float64(15.279233632882423)
A[9, 7] = np.float64(-33.28821096898486)
A[9, 8] = np.float64(-0.020331201708508627)
A[10, 0] = np.float64(-0.9371424300859873)
A[10, 3] = np.float64(5.186372428844064)
A[10, 4] = np.float64(1.0914373489967295)
A[10, 5] = np.float64(-8.149787010746927)
A[10, 6] = np.float64(-18.52006565999696)
A[10, 7] = np.float64(22.739487099350505)
A[10, 8] = np.float64(2.4936055526796523)
A[10, 9] = np.float64(-3.0467644718982196)
A[11, 0] = np.float64(2.273310147516538)
A[11, 3] = np.float64(-10.53449546673725)
A[11, 4] = np.float64(-2.0008720582248625)
A[11, 5] = np.float64(-17.9589318631188)
A[11, 6] = np.float64(27.94888452941996)
A[11, 7] = np.float64(-2.8589982771350235)
A[11, 8] = np.float64(-8.87285693353063)
A[11, 9] = np.float64(12.360567175794303)
A[11, 10] = np.float64(0.6433927460157636)

# The nonzero pattern (the play kernel's specialised steps sum over it: adding 0·K changes no bit
# of a finite sum, so they give the full table's results exactly): stage i uses the columns
# NZ_COL[NZ_START[i]:NZ_START[i + 1]] of A, the step the weights B[NZ_B].
_NZ = [(i, j) for i in range(N_STAGES) for j in range(i) if A[i, j] != 0.0]
NZ_START = np.searchsorted([i for i, _ in _NZ], np.arange(N_STAGES + 1)).astype(np.int64)
NZ_COL = np.array([j for _, j in _NZ], dtype=np.int64)
NZ_B = np.flatnonzero(B).astype(np.int64)


@njit(cache=True, inline="always")
def rk8_stage(i, t, y, h, K, tmp, n):
    """The argument of stage i >= 1 of the RK8 step from (t, y) over h: its time
    ``t + c_i h`` (returned) and state ``tmp = y + h Σ_{j<i} a_ij K[j]`` (first ``n`` entries)."""
    for r in range(n):
        acc = 0.0
        for j in range(i):
            acc += A[i, j] * K[j, r]
        tmp[r] = y[r] + h * acc
    return t + C[i] * h


@njit(cache=True, inline="always")
def rk8_end(y, h, K, out, n):
    """The end of the RK8 step: ``out = y + h Σ_i b_i K[i]`` (first ``n`` entries)."""
    for r in range(n):
        acc = 0.0
        for i in range(N_STAGES):
            acc += B[i] * K[i, r]
        out[r] = y[r] + h * acc


@njit(cache=True, inline="always")
def rk8_step(rhs, args, t, y, h, out, K, tmp, n, first):
    """One step of the 8th-order Dormand–Prince scheme from (t, y) over h into ``out``.

    Plain reading: stage i evaluates ``K[i] = rhs(t + c_i h, y + h Σ_j a_ij K[j])`` and the
    step is ``out = y + h Σ_i b_i K[i]``, over the first ``n`` entries of ``y``::

        if first == 0: K[0] = rhs(t, y)          # c_0 = 0, no a_0j
        for i in 1..11: K[i] = rhs(rk8_stage(i, t, y, h, K, tmp, n), tmp)
        rk8_end(y, h, K, out, n)

    The sums run over the full table (skipping its zeros through the index arrays ``NZ_*``
    gives the same bits but made the continuous engine's steps ~15 % slower: an indirect load
    per term). ``rhs(t, y, dy, args)`` writes the derivative into ``dy``; ``first = 1`` skips
    stage 0 when the caller has already put ``K[0] = rhs(t, y)`` there (it does not depend on
    h). A kernel whose right-hand side takes arrays writes this loop itself around
    :func:`rk8_stage` and :func:`rk8_end` (the continuous kernel's ``_stages``): an ``args``
    tuple of arrays, unpacked at every stage, costs reference counting that made its steps
    ~20 % slower. All three are inlined into their callers (``inline="always"``): a compiled
    function passed as a run-time argument would embed its address and so disable numba's
    on-disk cache.
    """
    if first == 0:
        rhs(t, y, K[0], args)
    for i in range(1, N_STAGES):
        ti = rk8_stage(i, t, y, h, K, tmp, n)
        rhs(ti, tmp, K[i], args)
    rk8_end(y, h, K, out, n)
