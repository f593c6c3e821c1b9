"""Bad-input corpus of the library API (``hysteresis`` and ``analysis``, not the CLI).

Table-driven: every case is a snippet of code that must end in a ``ValueError`` or ``TypeError``
whose message names the parameter (any of ``names``, case-insensitive), never in a silent result,
a hang or a crash. Cases that could hang or kill the interpreter (``isolate=True``) run in a
child process with a time limit. ``tests/corpus_audit.py`` runs every case the same way and
classifies it clear / unclear / silent / crash (also against an older checkout, through
``PYTHONPATH``), so this module imports nothing from the packages at import time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Case:
    id: str
    code: str
    names: tuple[str, ...]
    isolate: bool = False
    #: known failure owned by another change (the reader rewrite): reported, not hidden
    pending: str | None = None
    #: run after the imports only, without the shared objects (an out-of-bounds read then
    #: hits unmapped memory and crashes, as in a user's fresh interpreter, instead of reading
    #: the heap of the objects built before it)
    bare: bool = False


def C(  # noqa: N802
    id: str,
    code: str,
    *names: str,
    isolate: bool = False,
    pending: str | None = None,
    bare: bool = False,
) -> Case:
    return Case(id, code, names, isolate or bare, pending, bare)


# objects shared by the cases; only names that exist in every version of the API are used
PRELUDE = """
import os
import numpy as np
from hysteresis import (
    GeneralizedPlay, PIState, PlayOperator, PlayState, PrandtlIshlinskii, PreisachModel,
    PreisachState, Relay, RelayState, SpinDimerEnsemble,
)
from analysis.dynamics.dimensions import box_counting_dimension, box_counts, kaplan_yorke_dimension
from analysis.dynamics.statistics import (
    empirical_pdf, magnetization_variance, power_law_fit, self_averaging_parameter,
)
from analysis.dynamics.bifurcation import bifurcation_diagram, distinct_points, orbit_period
from analysis.experiments.ensemble import ensemble_tasks, run_ensemble
from analysis.experiments.iid import iid_inputs, iid_magnetization
from analysis.experiments.execution import run_tasks, spawn_seeds
from analysis.experiments.store import ResultStore
from analysis.identification import identify_preisach
from analysis.identification.forc_io import read_csv, read_forc, read_micromag

def write(name, data):
    path = os.path.join(TMP, name)
    with open(path, "wb") as fh:
        fh.write(data)
    return path
"""

OBJECTS = """
relay = Relay(1.0, -1.0)
play = PlayOperator(1.0)
gp = GeneralizedPlay.erf(1.0, 1.0)
pi = PrandtlIshlinskii([0.0, 1.0], [1.0, 0.5])
disc = PreisachModel.from_relays([1.0, 2.0, 0.5], [0.0, -1.0, 0.5])
disc_same = PreisachModel.from_relays([1.5, 2.5, 0.7], [0.2, -1.0, 0.1])
disc_w = PreisachModel.from_relays([1.0, 2.0, 0.5], [0.0, -1.0, 0.5], [0.5, 0.25, 0.25])
disc_small = PreisachModel.from_relays([1.0], [0.0])
E_ok = lambda a, b: ((a - b) / 2.0) ** 2
E_nonmono = lambda a, b: ((a - b) / 2.0) ** 2 + 0.3 * np.sin(3 * (a - b)) * (a - b) * (2 - (a - b))
cont = PreisachModel.from_everett(E_ok, -1.0, 1.0)
cont2 = PreisachModel.from_everett(lambda a, b: ((a - b) / 4.0) ** 2, -2.0, 2.0)
dens = lambda a, b: np.full(np.shape(a), 0.5)
dimers = SpinDimerEnsemble.random(6, 1.0, 1.0, 2.0, seed=0)
dimers2 = SpinDimerEnsemble.random(6, 1.0, 1.0, 2.0, seed=1)
pts = np.random.default_rng(0).random((300, 2))
make = lambda c: None
"""

CASES: list[Case] = [
    # --- Relay
    C("relay-numeric-strings", "Relay('1', '0')", "alpha"),
    C("relay-complex", "Relay(1 + 0j, 0)", "alpha"),
    C("relay-nan", "Relay(np.nan, 0)", "alpha"),
    C("relay-inf", "Relay(np.inf, 0)", "alpha"),
    C("relay-alpha-below-beta", "Relay(0.0, 1.0)", "alpha"),
    C("relay-none", "Relay(None, 0.0)", "alpha"),
    C("relay-huge-width", "Relay(1e308, -1e308)", "alpha"),
    C("relay-array-threshold", "Relay([1.0, 2.0], 0.0)", "alpha"),
    C("relay-empty-inputs", "relay.apply([])", "inputs"),
    C("relay-2d-inputs", "relay.apply([[1.0, 2.0]])", "inputs"),
    C("relay-nan-input", "relay.apply([1.0, np.nan])", "inputs"),
    C("relay-string-inputs", "relay.apply(['1', '2'])", "inputs"),
    C("relay-complex-inputs", "relay.apply([1 + 1j])", "inputs"),
    C("relay-none-inputs", "relay.apply(None)", "inputs"),
    C(
        "relay-masked-inputs",
        "relay.apply(np.ma.masked_array([0.0, 5.0, 1.0], mask=[0, 1, 0]))",
        "inputs",
    ),
    C("relay-masked-threshold", "Relay(np.ma.masked, 0.0)", "alpha"),
    C("relay-state-half", "relay.apply([0.0], RelayState(0.5, 0.0))", "state"),
    C("relay-play-state", "relay.apply([0.0], play.initial_state(0.0))", "state"),
    C("relay-string-state", "relay.apply([0.0], 'up')", "state"),
    C("relay-unreachable-state", "relay.apply([0.0], RelayState(1.0, -5.0))", "state"),
    C("relay-u0-string", "relay.initial_state('0')", "u0"),
    C("relay-state-output", "relay.state(0.5, 0.0)", "output"),
    # --- play
    C("play-negative-width", "PlayOperator(-1.0)", "width"),
    C("play-string-width", "PlayOperator('2')", "width"),
    C("play-nan-width", "PlayOperator(np.nan)", "width"),
    C("play-huge-width", "PlayOperator(1e305)", "width"),
    C("play-nan-position", "play.apply([0.0], PlayState(np.nan, 0.0))", "state", "position"),
    C("play-position-out-of-reach", "play.apply([0.0], PlayState(5.0, 0.0))", "state"),
    C("play-relay-state", "play.apply([0.0], relay.initial_state(0.0))", "state"),
    C("play-2d-inputs", "play.apply(np.zeros((2, 2)))", "inputs"),
    C(
        "play-masked-inputs",
        "play.apply(np.ma.masked_array([0.0, 5.0, 1.0], mask=[0, 1, 0]))",
        "inputs",
    ),
    C("play-complex-inputs", "play.apply(np.array([1.0, 2.0], dtype=complex))", "inputs"),
    C("play-huge-inputs", "play.apply([1e308, -1e308])", "inputs"),
    C("play-explicit-state", "play.state(10.0, 0.0)", "position"),
    C("play-u0-inf", "play.initial_state(np.inf)", "u0"),
    C("play-bool-width", "PlayOperator(True)", "width"),
    # --- generalized play
    C("gp-decreasing", "GeneralizedPlay(1.0, lambda w: -w, lambda w: -np.ones_like(w))", "shape"),
    C(
        "gp-nan-shape",
        "GeneralizedPlay(1.0, lambda w: np.full_like(w, np.nan), np.ones_like)",
        "shape",
    ),
    C("gp-wrong-length", "GeneralizedPlay(1.0, lambda w: w[:-1], np.ones_like)", "shape"),
    C(
        "gp-bad-derivative",
        "GeneralizedPlay(1.0, np.tanh, lambda w: 2.0 * np.ones_like(w))",
        "shape_derivative",
    ),
    C("gp-string-shape", "GeneralizedPlay(1.0, 'tanh', np.tanh)", "shape"),
    C("gp-negative-spread", "GeneralizedPlay.erf(1.0, -1.0)", "spread"),
    C("gp-zero-spread", "GeneralizedPlay.erf(1.0, 0.0)", "spread"),
    C("gp-string-width", "GeneralizedPlay.erf('1', 1.0)", "width"),
    C("gp-state-out-of-reach", "gp.apply([0.0], PlayState(100.0, 0.0))", "state"),
    # --- Prandtl-Ishlinskii
    C("pi-length-mismatch", "PrandtlIshlinskii([0.0, 1.0], [1.0])", "weights"),
    C("pi-negative-width", "PrandtlIshlinskii([-1.0, 1.0], [1.0, 1.0])", "widths"),
    C("pi-repeated-width", "PrandtlIshlinskii([1.0, 1.0], [0.5, 0.5])", "widths"),
    C("pi-nan-width", "PrandtlIshlinskii([0.0, np.nan], [1.0, 1.0])", "widths"),
    C("pi-string-widths", "PrandtlIshlinskii(['0', '1'], [1.0, 1.0])", "widths"),
    C("pi-complex-weights", "PrandtlIshlinskii([0.0, 1.0], [1 + 1j, 1.0])", "weights"),
    C("pi-state-more-plays", "pi.apply([0.0], PIState(np.zeros(3), 0.0))", "state"),
    C("pi-state-fewer-plays", "pi.apply([0.0], PIState(np.zeros(1), 0.0))", "state"),
    C("pi-state-out-of-reach", "pi.apply([0.0], PIState(np.array([0.0, 50.0]), 0.0))", "state"),
    C("pi-play-state", "pi.apply([0.0], play.initial_state(0.0))", "state"),
    C(
        "pi-overflowing-output",
        "PrandtlIshlinskii([0.0, 1.0], [1e300, 1e300]).apply([1e300])",
        "inputs",
        "weights",
    ),
    C("pi-inverse-bad-weights", "PrandtlIshlinskii([0.0, 1.0], [-1.0, 0.5]).inverse()", "weights"),
    C("pi-2d-widths", "PrandtlIshlinskii([[0.0, 1.0]], [[1.0, 1.0]])", "widths"),
    C(
        "pi-masked-weights",
        "PrandtlIshlinskii([0.0, 1.0, 2.0], np.ma.masked_array([0.0, 5.0, 1.0], mask=[0, 1, 0]))",
        "weights",
    ),
    # --- discrete Preisach
    C(
        "preisach-issue-segfault",
        "PreisachModel.from_relays([-1e308], [-1e308]).apply([1e308])",
        "alpha",
        bare=True,
    ),
    C(
        "preisach-huge-thresholds",
        "PreisachModel.from_relays([1e308, 0.0], [-1e308, 0.0]).apply([1e308, -1e308, 0.0])",
        "alpha",
        bare=True,
    ),
    C("preisach-alpha-below-beta", "PreisachModel.from_relays([0.0], [1.0])", "alpha"),
    C(
        "preisach-weights-sum",
        "PreisachModel.from_relays([1.0, 2.0], [0.0, 0.0], [0.5, 0.6])",
        "weights",
    ),
    C(
        "preisach-negative-weight",
        "PreisachModel.from_relays([1.0, 2.0], [0.0, 0.0], [1.5, -0.5])",
        "weights",
    ),
    C("preisach-empty", "PreisachModel.from_relays([], [])", "alpha"),
    C("preisach-length-mismatch", "PreisachModel.from_relays([1.0], [0.0, 0.0])", "alpha", "beta"),
    C("preisach-strings", "PreisachModel.from_relays(['1'], ['0'])", "alpha"),
    C("preisach-complex", "PreisachModel.from_relays([1 + 0j], [0.0])", "alpha"),
    C("preisach-2d", "PreisachModel.from_relays([[1.0]], [[0.0]])", "alpha"),
    C("preisach-nan", "PreisachModel.from_relays([np.nan], [0.0])", "alpha"),
    C(
        "preisach-state-other-model-same-n",
        "disc.apply([0.0], disc_same.initial_state(1.0))",
        "state",
    ),
    C("preisach-state-smaller-model", "disc.apply([0.0], disc_small.initial_state(0.5))", "state"),
    C("preisach-state-other-weights", "disc.apply([0.0], disc_w.initial_state(1.5))", "state"),
    C("preisach-continuous-state", "disc.apply([0.0], cont.initial_state(0.0))", "state"),
    C("preisach-relay-state", "disc.apply([0.0], RelayState(1.0, 0.0))", "state"),
    C("preisach-bare-state", "disc.apply([0.0], PreisachState(np.array([0.0]), 0.5))", "state"),
    C(
        "preisach-forged-counts",
        "m = PreisachModel.from_relays([1.0, 2.0, 0.5], [0.0, -1.0, 0.5])\n"
        "m.apply([3.0, -3.0], PreisachState(np.array([5.0, -5.0]), 0.0,"
        " np.array([10**6, 0]), np.array([0, -7])))",
        "state",
        bare=True,
    ),
    C("preisach-switching-relay-state", "disc.switching(RelayState(1.0, 0.0))", "state"),
    C("preisach-saturation-name", "disc.state_from_extrema([1.0], saturation='up')", "saturation"),
    C(
        "disc-masked-alpha",
        "PreisachModel.from_relays(np.ma.masked_array([1.0, 2.0], mask=[0, 1]), [0.0, 0.0])",
        "alpha",
    ),
    # --- continuous Preisach
    C("everett-negative-density", "PreisachModel.from_everett(E_nonmono, -1.0, 1.0)", "everett"),
    C(
        "everett-nan",
        "PreisachModel.from_everett("
        "lambda a, b: np.where(a > 0.5, np.nan, ((a - b) / 2.0) ** 2), -1.0, 1.0)",
        "everett",
    ),
    C("everett-upper-below-lower", "PreisachModel.from_everett(E_ok, 1.0, -1.0)", "upper"),
    C("everett-not-callable", "PreisachModel.from_everett('E', -1.0, 1.0)", "everett"),
    C("everett-huge-bounds", "PreisachModel.from_everett(E_ok, -1e308, 1e308)", "lower"),
    C(
        "density-negative",
        "PreisachModel.from_density(lambda a, b: 0.5 - 2.0 * (a > 0.5), -1.0, 1.0)",
        "density",
    ),
    C(
        "density-mass-2",
        "PreisachModel.from_density(lambda a, b: np.ones(np.shape(a)), -1, 1)",
        "density",
    ),
    C(
        "density-huge-resolution",
        "PreisachModel.from_density(dens, -1.0, 1.0, resolution=10**6)",
        "resolution",
        isolate=True,
    ),
    C(
        "density-float-resolution",
        "PreisachModel.from_density(dens, -1.0, 1.0, resolution=2.5)",
        "resolution",
    ),
    C("continuous-discrete-state", "cont.apply([0.0], disc.initial_state(0.0))", "state"),
    C("continuous-other-model-state", "cont.apply([0.0], cont2.initial_state(0.0))", "state"),
    C(
        "cont-masked-inputs",
        "cont.apply(np.ma.masked_array([0.0, 5.0, 1.0], mask=[0, 1, 0]))",
        "inputs",
    ),
    # --- spin dimers
    C("dimers-odd-spins", "SpinDimerEnsemble.random(101, 1.0, 1.0, 2.0, seed=0)", "n_spins"),
    C("dimers-no-seed", "SpinDimerEnsemble.random(100, 1.0, 1.0, 2.0, seed=None)", "seed"),
    C("dimers-width-too-large", "SpinDimerEnsemble.random(100, 5.0, 1.0, 2.0, seed=0)", "width"),
    C("dimers-string-spins", "SpinDimerEnsemble.random('100', 1.0, 1.0, 2.0, seed=0)", "n_spins"),
    C("dimers-negative-spread", "SpinDimerEnsemble.random(100, 1.0, -1.0, 2.0, seed=0)", "spread"),
    C("dimers-fields-shape", "SpinDimerEnsemble(np.zeros((3, 3)), 1.0)", "fields"),
    C("dimers-zero-coupling", "SpinDimerEnsemble(np.zeros((3, 2)), 0.0)", "coupling"),
    C("dimers-string-coupling", "SpinDimerEnsemble(np.zeros((3, 2)), '1')", "coupling"),
    C("dimers-spins-zero", "dimers.simulate([0.0], spins=np.zeros(6))", "spins"),
    C("dimers-spins-state", "dimers.simulate([0.0], spins=disc.initial_state(0.0))", "spins"),
    C("dimers-other-ensemble-state", "dimers.apply([0.0], dimers2.initial_state(0.0))", "state"),
    C(
        "dimers-huge-ensemble",
        "SpinDimerEnsemble.random(10**12, 1.0, 1.0, 2.0, seed=0)",
        "n_spins",
        isolate=True,
    ),
    C(
        "dimers-masked-fields",
        "SpinDimerEnsemble(np.ma.masked_array([[1.0, 0.0]], mask=[[0, 1]]), 2.0)",
        "fields",
    ),
    # --- dimensions and statistics
    C("ky-empty", "kaplan_yorke_dimension([])", "exponents"),
    C("ky-nan", "kaplan_yorke_dimension([np.nan, -1.0])", "exponents"),
    C("ky-complex", "kaplan_yorke_dimension([1 + 1j, -1.0])", "exponents"),
    C("bc-one-point", "box_counting_dimension(np.zeros((1, 2)))", "points"),
    C("bc-nan-point", "box_counting_dimension([[0.0, np.nan], [1.0, 1.0]])", "points"),
    C("bc-huge-n-sizes", "box_counting_dimension(pts, n_sizes=100000)", "n_sizes", isolate=True),
    C("bc-huge-offsets", "box_counts(pts, [0.1], offsets=10**7)", "offsets", isolate=True),
    C("bc-negative-size", "box_counts(pts, [-0.1])", "sizes"),
    C("bc-string-max-fill", "box_counting_dimension(pts, max_fill='0.1')", "max_fill"),
    C("bc-complex-points", "box_counting_dimension(pts + 1j)", "points"),
    C("sap-empty", "self_averaging_parameter([])", "values"),
    C("sap-complex", "self_averaging_parameter([1 + 1j, 2.0])", "values"),
    C("variance-2d", "magnetization_variance([[1.0, 2.0], [3.0, 4.0]])", "values"),
    C("pdf-zero-bins", "empirical_pdf([1.0, 2.0, 3.0], bins=0)", "bins"),
    C("pdf-string-values", "empirical_pdf(['1', '2'])", "values"),
    C("power-law-negative", "power_law_fit([1.0, 2.0, 3.0], [1.0, -1.0, 2.0])", "y"),
    C("orbit-period-nan", "orbit_period([1.0, np.nan, 1.0])", "q"),
    C(
        "distinct-points-nan-tolerance",
        "distinct_points([1.0, 2.0], tolerance=np.nan)",
        "tolerance",
    ),
    # --- bifurcation sweeps
    C(
        "bif-nan-value",
        "bifurcation_diagram(make, [np.nan], 10, 5, progress=False)",
        "parameter_values",
    ),
    C("bif-zero-periods", "bifurcation_diagram(make, [1.0], 0, 5, progress=False)", "n_periods"),
    C(
        "bif-huge-periods",
        "bifurcation_diagram(make, np.linspace(0, 1, 10), 10**9, 10, progress=False)",
        "n_periods",
        isolate=True,
    ),
    C("bif-not-callable", "bifurcation_diagram('f', [1.0], 10, 5, progress=False)", "make_system"),
    C(
        "bif-empty-values",
        "bifurcation_diagram(make, [], 10, 5, progress=False)",
        "parameter_values",
    ),
    # --- ensembles, iid, execution
    C(
        "ensemble-odd-spins-worker",
        "run_ensemble([101], [1.0], 1, 0, 20.0, 10.0, workers=1, progress=False)",
        "spins",
        isolate=True,
    ),
    C(
        "ensemble-zero-realizations",
        "ensemble_tasks([100], [1.0], 0, 0, 20.0, 10.0)",
        "realizations",
    ),
    C("ensemble-t-end-before-transient", "ensemble_tasks([100], [1.0], 1, 0, 10.0, 20.0)", "t_end"),
    C(
        "ensemble-unknown-option",
        "ensemble_tasks([100], [1.0], 1, 0, 20.0, 10.0, widht=1.0)",
        "widht",
    ),
    C("ensemble-nan-coupling", "ensemble_tasks([100], [np.nan], 1, 0, 20.0, 10.0)", "couplings"),
    C("ensemble-huge-t-end", "ensemble_tasks([100], [1.0], 1, 0, 1e300, 10.0)", "t_end"),
    C("iid-odd-spins", "iid_magnetization(101, 10, 2, seed=0)", "n_spins", isolate=True),
    C("iid-zero-steps", "iid_magnetization(100, 0, 2, seed=0)", "n_steps"),
    C("iid-negative-std", "iid_inputs(10, -1.0, 0)", "input_std"),
    C("iid-huge-steps", "iid_inputs(10**12, 1.0, 0)", "n_steps", isolate=True),
    C(
        "run-tasks-zero-workers",
        "run_tasks('e', [{'x': 1}], dict, workers=0, progress=False)",
        "workers",
    ),
    C("run-tasks-func-not-callable", "run_tasks('e', [{'x': 1}], 'f', progress=False)", "func"),
    C("spawn-seeds-string", "spawn_seeds('5', 3)", "base_seed"),
    # --- results store files
    C(
        "store-binary-garbage",
        "ResultStore(write('garbage.sqlite', bytes(range(256)) * 16))",
        "garbage.sqlite",
    ),
    C("store-text-file", "ResultStore(write('text.sqlite', b'a,b,c\\n1,2,3\\n'))", "text.sqlite"),
    C(
        "store-truncated",
        "import sqlite3\n"
        "p = os.path.join(TMP, 'trunc.sqlite')\n"
        "s = ResultStore(p)\n"
        "[s.put('e', {'i': i}, {'v': np.ones(200) * i}) for i in range(100)]\n"
        "s.close()\n"
        "c = sqlite3.connect(p); c.execute('PRAGMA wal_checkpoint(TRUNCATE)'); c.close()\n"
        "d = open(p, 'rb').read(); open(p, 'wb').write(d[: len(d) // 2])\n"
        "s = ResultStore(p)\n"
        "[s.get(k) for k in s.keys('e')]",
        "trunc.sqlite",
    ),
    # --- identification (grid bound) and data files (generic reader cases)
    C("identify-tiny-step", "identify_preisach(gp, 1e-5, 6.0)", "step", isolate=True),
    C("identify-negative-step", "identify_preisach(gp, -0.1, 6.0)", "step"),
    C("identify-nan-saturation", "identify_preisach(gp, 0.1, np.nan)", "saturation"),
    C("csv-empty-file", "read_csv(write('empty.csv', b''))", "empty.csv", "line"),
    C(
        "csv-binary-garbage",
        "read_csv(write('garbage.csv', bytes(range(256)) * 8))",
        "garbage.csv",
        "line",
    ),
    C(
        "csv-short-row",
        "read_csv(write('short.csv', b'1.0,0.5,0.1\\n1.0,0.4\\n'))",
        "short.csv",
        "line",
    ),
    C("csv-text-values", "read_csv(write('text.csv', b'1.0,abc,0.1\\n'))", "text.csv", "line"),
    C("micromag-empty-file", "read_micromag(write('empty.frc', b''))", "empty.frc", "line"),
    C(
        "micromag-binary-garbage",
        "read_micromag(write('garbage.frc', bytes(range(256)) * 8))",
        "garbage.frc",
        "line",
    ),
    C("forc-unknown-format", "read_forc(write('x.csv', b'1,1,1\\n'), format='xyz')", "format"),
    # issue 21: binary, compressed, UTF-16 without BOM, no FORC format, absurd values, rows out
    # of measurement order
    C(
        "forc-gzip",
        "read_forc(write('g.frc', __import__('gzip').compress(b'MicroMag 2900\\n')), 'auto')",
        "not a text FORC file (gzip",
    ),
    C(
        "forc-png",
        "read_micromag(write('p.frc', b'\\x89PNG\\r\\n\\x1a\\n' + b'MicroMag\\n' * 20))",
        "not a text FORC file (a PNG",
    ),
    C(
        "forc-utf16-without-bom",
        "read_csv(write('u.csv', '1,1,0.5\\n0,0,0.1\\n0,1,0.5\\n'.encode('utf-16-le')))",
        "not a text FORC file (UTF-16",
    ),
    # --- masked arrays at the remaining entry points (issue 21)
    C(
        "disc-masked-relay-outputs",
        "disc.state_from_relay_outputs(np.ma.masked_array([1.0, 1.0, -1.0], mask=[0, 1, 0]), 1.0)",
        "outputs",
    ),
    C(
        "relay-masked-relay-outputs",
        "relay.state_from_relay_outputs(np.ma.masked_array([1.0], mask=[1]), 0.0)",
        "outputs",
    ),
    C(
        "engine-masked-times",
        "from oscillators import ForcedOscillator\n"
        "osc = ForcedOscillator(relay, coupling=0.5)\n"
        "osc.engine(osc.initial_state()).advance(np.ma.masked_array([1.0, 2.0], mask=[0, 1]))",
        "times",
    ),
    C(
        "fit-masked-record",
        "from analysis.identification.fitting import fit_prandtl_ishlinskii\n"
        "u = np.sin(np.linspace(0, 20, 50))\n"
        "fit_prandtl_ishlinskii(np.ma.masked_array(u, mask=u > 0.9), u, [0.5, 1.0])",
        "u",
    ),
    C(
        "fit-masked-relay-thresholds",
        "from analysis.identification.fitting import relay_outputs\n"
        "relay_outputs([0.0, 1.0], np.ma.masked_array([0.5], mask=[1]), [0.0])",
        "alpha",
    ),
    C(
        "pike-masked-coordinates",
        "from analysis.identification.curves import preisach_to_pike\n"
        "preisach_to_pike(np.ma.masked_array([1.0, 2.0], mask=[0, 1]), [0.0, 0.0])",
        "alpha",
    ),
    C(
        "cdf-masked-samples",
        "from analysis.identification.metrics import empirical_cdf\n"
        "empirical_cdf(np.ma.masked_array([1.0, 2.0], mask=[0, 1]))",
        "samples",
    ),
    C(
        "forc-readme-text",
        "read_forc(write('README.md', b'# Tool\\n\\nPlots moment (emu), field (Oe).\\n'), 'auto')",
        "not a FORC file this toolkit recognises",
    ),
    C(
        "forc-absurd-moment",
        "read_csv(write('huge.csv', b'1,1,1e300\\n0.5,0.5,0.1\\n0.5,1,0.2\\n'))",
        "line 1: moment 1e+300 is absurd",
    ),
    C(
        "forc-exponent-typo-field",
        "read_csv(write('typo.csv', (''.join(f'-1,{h / 10},{h / 100}\\n' for h in range(-10, 30))"
        " + '-1,4e9,0.3\\n').encode()))",
        "line 41: field 4e+09 is absurd",
    ),
    C(
        "forc-lakeshore-time-out-of-order",
        "read_forc(write('t.csv', b'Time [s],Field [mT],Moment [emu]\\n0,10,1\\n1,11,2\\n'"
        " b'0.5,12,3\\n'), 'lakeshore')",
        "line 4: time stamp 0.5",
    ),
    C(
        "forc-lakeshore-curves-out-of-order",
        "read_forc(write('c.csv', ('Field [mT],Moment [emu]\\n' + ''.join(f'{h},{h}\\n' for r in"
        " (10, 8, 6, 7, 4) for h in range(r, 13))).encode()), 'lakeshore')",
        "line 17: a curve starts at 7 mT",
    ),
]

CASE_BY_ID = {c.id: c for c in CASES}
assert len(CASE_BY_ID) == len(CASES), "duplicate case ids"


def namespace(tmp: str, objects: bool = True) -> dict:
    """A fresh namespace with the prelude's imports and (``objects``) its shared objects."""
    ns: dict = {"TMP": tmp}
    exec(PRELUDE, ns)
    if objects:
        exec(OBJECTS, ns)
    return ns


def classify(case: Case, ns: dict) -> tuple[str, str]:
    """Run one case in ``ns``: ``("clear" | "unclear" | "silent", detail)``."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exec(case.code, dict(ns))
    except (ValueError, TypeError) as exc:
        msg = str(exc)
        if any(n.lower() in msg.lower() for n in case.names):
            return "clear", f"{type(exc).__name__}: {msg}"
        return "unclear", f"{type(exc).__name__} not naming {case.names}: {msg}"
    except Exception as exc:  # noqa: BLE001 - the classification is the point
        return "unclear", f"{type(exc).__name__}: {exc}"
    return "silent", "no error"


def child_main(objects: bool = True) -> None:
    """Worker loop: read case ids on stdin, answer one JSON line per case."""
    tmp = tempfile.mkdtemp(prefix="corpus_")
    base = namespace(tmp, objects)
    print(json.dumps({"ready": True}), flush=True)
    for line in sys.stdin:
        cid = line.strip()
        if not cid:
            continue
        sub = tempfile.mkdtemp(dir=tmp)
        ns = dict(base, TMP=sub)
        verdict, detail = classify(CASE_BY_ID[cid], ns)
        print(json.dumps({"id": cid, "verdict": verdict, "detail": detail[:300]}), flush=True)


CHILD = (
    "import sys; sys.path.insert(0, {here!r}); import test_bad_input_corpus as c; "
    "c.child_main({objects})"
)


def run_isolated(case: Case, timeout: float) -> tuple[str, str]:
    """One case in a fresh child process: a crash or a time-out is classified, not suffered."""
    code = CHILD.format(here=str(HERE), objects=not case.bare)
    try:
        proc = subprocess.run(
            [sys.executable, "-c", code],
            input=case.id + "\n",
            capture_output=True,
            text=True,
            timeout=timeout,
            env=dict(os.environ),
            cwd=tempfile.gettempdir(),  # keep a PYTHONPATH checkout first on sys.path
        )
    except subprocess.TimeoutExpired:
        return "crash", f"no answer within {timeout} s (hang)"
    lines = [json.loads(x) for x in proc.stdout.splitlines() if x.startswith("{")]
    answers = [x for x in lines if x.get("id") == case.id]
    if proc.returncode != 0 or not answers:
        return "crash", f"child exited with {proc.returncode}: {proc.stderr[-300:]}"
    return answers[0]["verdict"], answers[0]["detail"]


@pytest.fixture(scope="module")
def shared_namespace(tmp_path_factory):
    return namespace(str(tmp_path_factory.mktemp("corpus")))


def test_corpus_is_large_enough():
    assert len(CASES) >= 80


def _param(case: Case):
    marks = [pytest.mark.xfail(reason=case.pending, strict=False)] if case.pending else []
    return pytest.param(case, id=case.id, marks=marks)


@pytest.mark.parametrize("case", [_param(c) for c in CASES if not c.isolate])
def test_case_ends_in_a_clear_error(case, shared_namespace, tmp_path):
    verdict, detail = classify(case, dict(shared_namespace, TMP=str(tmp_path)))
    assert verdict == "clear", detail


@pytest.mark.parametrize("case", [_param(c) for c in CASES if c.isolate])
def test_isolated_case_ends_in_a_clear_error(case):
    # child process and time limit: a regression must show as a failure, not a dead pytest
    verdict, detail = run_isolated(case, timeout=240.0)
    assert verdict == "clear", detail
