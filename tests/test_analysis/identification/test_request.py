"""The identification request (:mod:`analysis.identification.request`): every inconsistent
combination of options is one ``ValueError`` whose message starts with the parameter it is
about; the decisions (smoothing law, grid half-extent, the paper's reference) follow the rules
the docstrings state."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support_paths import DATA

from analysis.identification.forc_io import read_forc_file
from analysis.identification.request import (
    DEFAULT_MEASURED_SMOOTHING,
    DEFAULT_MODEL_STEP,
    IdentifyRequest,
)
from analysis.identification.variforc import VariforcParameters

FILE = DATA / "forc_erf_play_mayergoyz.csv"
HYBRID = DATA / "forc_micromag_0016_hybrid_si.frc"


def _one_line_about(exc: pytest.ExceptionInfo, parameter: str) -> None:
    message = str(exc.value)
    assert "\n" not in message
    assert message.split()[0] == parameter, message


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        (dict(workers=2), "workers"),
        (dict(grid_step=0.1), "grid_step"),
        (dict(uncertainty=True), "uncertainty"),
        (dict(bootstrap=50), "bootstrap"),
        (dict(cmap="viridis"), "cmap"),
        (dict(bootstrap_seed=3), "bootstrap_seed"),
        (dict(smoothing="variforc"), "smoothing"),
        (dict(smoothing="auto"), "smoothing"),
        (dict(normalize="mass"), "normalize"),
        (dict(columns="field,moment"), "columns"),
        (dict(mass=1e-3), "mass"),
        (dict(volume=1e-6), "volume"),
        (dict(reversible_ridge=True), "reversible_ridge"),
        (dict(drift_correction="additive"), "drift_correction"),
        (dict(file_format="micromag"), "file_format"),
    ],
)
def test_a_model_refuses_each_option_of_measured_data(kwargs, parameter):
    with pytest.raises(ValueError, match="only for measured data") as exc:
        IdentifyRequest(model="erf-play", **kwargs)
    _one_line_about(exc, parameter)


@pytest.mark.parametrize("parameter", ["step", "saturation"])
def test_measured_data_refuse_the_model_grid(parameter):
    with pytest.raises(ValueError, match="only for models") as exc:
        IdentifyRequest(inputs=(FILE,), **{parameter: 0.5})
    _one_line_about(exc, parameter)


def test_workers_only_for_a_batch(tmp_path):
    with pytest.raises(ValueError, match="only for a batch") as exc:
        IdentifyRequest(inputs=(FILE,), workers=2)
    _one_line_about(exc, "workers")
    assert IdentifyRequest(inputs=(FILE, HYBRID), workers=2).batch
    assert IdentifyRequest(inputs=(tmp_path,), workers=2).batch  # a directory
    assert not IdentifyRequest(inputs=(FILE,)).batch


def test_exactly_one_source():
    for kwargs in ({}, dict(model="play", inputs=(FILE,))):
        with pytest.raises(ValueError, match="exactly one source") as exc:
            IdentifyRequest(**kwargs)
        _one_line_about(exc, "model")


@pytest.mark.parametrize(
    ("kwargs", "parameter", "needle"),
    [
        (dict(variforc={"sc0": 2.0}), "sc0", "only for smoothing='variforc'$"),
        (dict(variforc={"lam": 0.1}), "lambda", "only for smoothing='variforc'$"),
        (dict(smoothing="auto", variforc={"sb1": 4.0}), "sb1", r"\(auto chooses\)"),
        (dict(smoothing="variforc", variforc={"sc0": 0.5}), "sc0", ">= 1"),
        (dict(smoothing="variforc", variforc={"lam": 2.0}), "lambda", r"\[0, 1\]"),
        (dict(variforc={"bu0": 1.0}), "variforc", "takes sc0"),
        (dict(smoothing=(1.0, 2.0, 3.0)), "smoothing", "one factor SF or two"),
        (dict(smoothing=0.0), "smoothing", "> 0"),
        (dict(smoothing=math.nan), "smoothing", "> 0"),
        (dict(smoothing="hann"), "smoothing", "'variforc' or 'auto'"),
        (dict(mass=1e-3), "mass", "only for normalize='mass'"),
        (dict(normalize="mass", volume=1e-6), "volume", "only for normalize='volume'"),
        (dict(normalize="mass", mass=-1.0), "mass", "> 0"),
        (dict(smoothing="variforc", window="pike"), "window", "must be 'rs'"),
        (dict(smoothing="auto", window="pike"), "window", "must be 'rs'"),
        (dict(uncertainty=True, window="pike"), "window", "must be 'rs'"),
        (dict(window="hann"), "window", "one of"),
        (dict(file_format="xml"), "file_format", "one of"),
        (dict(drift_correction="cubic"), "drift_correction", "one of"),
        (dict(columns="a,b"), "columns", "one of"),
        (dict(normalize="weight"), "normalize", "one of"),
        (dict(uncertainty=True, bootstrap=5), "bootstrap", ">= 20"),
        (dict(uncertainty=True, bootstrap_seed=-1), "bootstrap_seed", ">= 0"),
        (dict(max_memory=0.0), "max_memory", "> 0"),
        (dict(bootstrap=50), "bootstrap", "only with uncertainty"),
        (dict(bootstrap=200), "bootstrap", "only with uncertainty"),  # the default, given
        (dict(bootstrap_seed=0), "bootstrap_seed", "only with uncertainty"),
        (dict(bootstrap_seed=3), "bootstrap_seed", "only with uncertainty"),
    ],
)
def test_each_cross_check_of_measured_data_is_one_line_naming_its_parameter(
    kwargs, parameter, needle
):
    with pytest.raises(ValueError, match=needle) as exc:
        IdentifyRequest(inputs=(FILE,), **kwargs)
    _one_line_about(exc, parameter)


def test_model_checks_of_step_and_saturation():
    with pytest.raises(ValueError) as exc:
        IdentifyRequest(model="play", step=0.0)
    _one_line_about(exc, "step")
    with pytest.raises(ValueError) as exc:
        IdentifyRequest(model="play", saturation=math.inf)
    _one_line_about(exc, "saturation")
    with pytest.raises(ValueError, match="sc0 is only for smoothing='variforc'"):
        IdentifyRequest(model="play", variforc={"sc0": 2.0})


def test_smoothing_laws_and_defaults():
    assert IdentifyRequest(model="play").smoothing is None
    assert IdentifyRequest(model="play", smoothing=2.0).smoothing == (2.0, 2.0)
    assert IdentifyRequest(model="play", smoothing=(2.0, 3.0)).smoothing == (2.0, 3.0)
    measured = IdentifyRequest(inputs=(FILE,))
    assert measured.smoothing == (DEFAULT_MEASURED_SMOOTHING,) * 2
    law = IdentifyRequest(inputs=(FILE,), smoothing="variforc", variforc={"sc1": 5.0}).smoothing
    assert law == VariforcParameters(sc1=5.0)
    assert IdentifyRequest(inputs=(FILE,), smoothing="auto").smoothing == "auto"
    assert IdentifyRequest(model="play").step == DEFAULT_MODEL_STEP


def test_paper_reference_only_for_the_papers_models_and_disorder():
    assert IdentifyRequest(model="dimers").paper_reference
    assert IdentifyRequest(model="dimers").paper_figure
    assert IdentifyRequest(model="erf-play").paper_reference
    assert not IdentifyRequest(model="erf-play").paper_figure
    assert not IdentifyRequest(model="dimers", explicit_fields=True).paper_reference
    assert not IdentifyRequest(model="play").paper_reference
    assert not IdentifyRequest(model="preisach-uniform").paper_reference
    assert not IdentifyRequest(inputs=(FILE,)).paper_reference


def test_grid_half_extent():
    # default 5R + p/2, raised to the largest |threshold|; a given saturation wins
    request = IdentifyRequest(model="dimers")
    assert request.grid_half_extent(2.0, 1.0) == 6.0
    assert request.grid_half_extent(2.0, 1.0, extreme_threshold=7.5) == 7.5
    assert request.grid_half_extent(2.0, 1.0, extreme_threshold=3.0) == 6.0
    given = IdentifyRequest(model="dimers", saturation=4.0)
    assert given.grid_half_extent(2.0, 1.0, extreme_threshold=7.5) == 4.0
    # 2·ceil(H/Δ) + 1 nodes: H = 6, Δ = 1e-5 asks for 1.2e6 nodes, beyond the bound
    with pytest.raises(ValueError, match="grid nodes") as exc:
        IdentifyRequest(model="play", step=1e-5).grid_half_extent(2.0, 1.0)
    _one_line_about(exc, "step=1e-05")
    assert IdentifyRequest(model="preisach-uniform", saturation=2.0).operator_half_extent == 2.0
    assert IdentifyRequest(model="play", saturation=2.0).operator_half_extent is None


def test_reader_options_by_format():
    plain = IdentifyRequest(inputs=(FILE,))
    assert plain.reader_options("csv") == {}
    columns = IdentifyRequest(inputs=(FILE,), columns="moment,field")
    assert columns.reader_options("blocks") == {"columns": "moment,field"}
    with pytest.raises(ValueError, match="not 'csv'") as exc:
        columns.reader_options("csv")
    _one_line_about(exc, "columns")
    drift = IdentifyRequest(inputs=(FILE,), drift_correction="additive")
    assert drift.reader_options("lakeshore") == {"drift_correction": "additive"}
    # every format gets it: the reader warns where a file has no calibration points (a note,
    # not an error) and refuses a format whose calibration points it cannot use
    assert drift.reader_options("csv") == {"drift_correction": "additive"}


def test_grid_step_against_the_data():
    # a file whose curves share one field grid: a protocol lattice step would be ignored
    shared = read_forc_file(FILE).curves
    with pytest.raises(ValueError, match="share one grid") as exc:
        IdentifyRequest(inputs=(FILE,), grid_step=0.1).check_grid_step(shared)
    _one_line_about(exc, "grid_step")
    # measured fields that differ curve by curve: the lattice's own bounds apply
    measured = read_forc_file(HYBRID).curves
    IdentifyRequest(inputs=(HYBRID,)).check_grid_step(measured)  # no grid_step: nothing to check
    with pytest.raises(ValueError, match="nodes"):
        IdentifyRequest(inputs=(HYBRID,), grid_step=1e-9).check_grid_step(measured)
    step = float(np.median(np.diff(measured.fields[0])))
    IdentifyRequest(inputs=(HYBRID,), grid_step=step).check_grid_step(measured)


def test_amount_of_the_normalisation():
    header = {"Mass": "2 mg"}
    assert IdentifyRequest(inputs=(FILE,)).amount(None, header) == 1.0
    by_header = IdentifyRequest(inputs=(FILE,), normalize="mass")
    assert by_header.amount("A·m²", header) == pytest.approx(2e-6)
    given = IdentifyRequest(inputs=(FILE,), normalize="mass", mass=5e-6)
    assert given.amount("A·m²", header) == 5e-6
    with pytest.raises(ValueError, match="moment unit") as exc:
        by_header.amount(None, header)
    _one_line_about(exc, "normalize")


def test_the_request_is_frozen():
    request = IdentifyRequest(model="play")
    with pytest.raises(AttributeError):
        request.step = 1.0  # type: ignore[misc]


def test_bootstrap_defaults_are_filled_in_with_uncertainty():
    request = IdentifyRequest(inputs=(FILE,), uncertainty=True)
    assert (request.bootstrap, request.bootstrap_seed) == (200, 0)
    assert IdentifyRequest(inputs=(FILE,)).bootstrap == 200  # not given: no error
