"""Conventions shared by every ``hyst`` subcommand (one place, so the commands cannot drift).

* **Options.** Model options (``--model``, ``--spins``, ``--seed``, ``--width``, ``--spread``,
  ``--spin-coupling``, ``--width-spread`` and the model-specific ``--fields``, ``--alpha``,
  ``--beta``, ``--plays``, Bouc–Wen's ``--bw-a``, ``--bw-beta``, ``--bw-gamma``, ``--bw-n`` and
  Jiles–Atherton's ``--ja-ms``, ``--ja-a``, ``--ja-k``, ``--ja-c``, ``--ja-alpha``), oscillator
  options (``--coupling``, ``--damping-ratio``, ``--frequency``), the initial condition
  (``--q0``, ``--v0``, ``--w0``) and the output options (``--out``, ``--json``, ``--quiet``)
  are defined here and added to each subcommand from here;
  their defaults are the paper's (:mod:`analysis.experiments.parameters`), their bounds the
  library's (a value out of range is reported with the library's message, naming the option).
* **Units.** Times (``--t-end``) are in the oscillator's time unit (undamped natural period
  2π); transients (``--transient``) are counted in forcing periods ``T = 2π/Ω``, as in the paper.
* **Output.** ``--out`` defaults to :data:`DEFAULT_OUT` for every command. ``--json`` prints
  exactly one JSON object on stdout; non-finite numbers are encoded as the strings ``"inf"``,
  ``"-inf"`` and ``"nan"`` (:func:`to_json`), never as bare ``Infinity``/``NaN`` tokens (not
  JSON) or ``null`` (ambiguous).
* **Progress.** Progress bars go to stderr; they are on when stderr is a terminal and off with
  ``--quiet`` or when stderr is not a TTY. Library functions are quiet by default.
* **Errors.** Every option is validated before any work starts (model and oscillator values by the
  library, when the command builds its system, which it does once, before any work). A bad value, or
  an error raised later inside the library or a worker process, ends the command with one line
  ``hyst COMMAND: error: ...`` on stderr and exit status 2, never a traceback (set the environment
  variable ``HYST_DEBUG=1`` to see the traceback of an unexpected error).
* **Options nothing reads.** A model option given on the command line that the model does not
  read is refused when it is another model's feature (``--plays`` with ``erf-play``,
  ``--width-spread`` with ``dimers``) and warned about in one line when the models share it
  (``--spins`` with ``erf-play``); ``hyst identify --input`` refuses every model option.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from analysis.cli._parsing import (
    Given,
    finite_float,
    int_at_least,
    nonnegative_float,
    positive_float,
)
from analysis.experiments.models import MODELS, ModelExpressionError, ModelParameters, parse_model
from analysis.experiments.parameters import DAMPING_RATIO, DEFAULT_Q0, FREQUENCY, V0
from hysteresis.spin_dimers import MAX_SPINS
from oscillators import FREQUENCY_RANGE, MAX_COUPLING, MAX_DAMPING_RATIO, MAX_PERIODS

__all__ = [
    "DEFAULT_OUT",
    "add_execution_options",
    "add_initial_options",
    "add_model_options",
    "add_oscillator_options",
    "add_output_options",
    "add_store_options",
    "add_transient_option",
]

#: the default output directory of every command (each writes its own file names into it)
DEFAULT_OUT = "hyst-out"


#: model option (its ``dest``) -> the models that read it, for the options that are not among
#: the parameters of a :class:`~analysis.experiments.models.ModelSpec`
_OPTION_MODELS = {"fields": ("dimers",), "alpha": ("relay",), "beta": ("relay",)}


def models_reading(dest: str, names: Sequence[str]) -> list[str]:
    """The models among ``names`` that read the model option ``dest`` (``"spins"``,
    ``"width_spread"``, ``"alpha"``, ...)."""
    if dest in _OPTION_MODELS:
        return [n for n in names if n in _OPTION_MODELS[dest]]
    return [n for n in names if dest in MODELS[n].parameters]


#: the example of a weighted sum in ``--help`` and the errors (when its names are choices)
SUM_EXAMPLE = "0.7*erf-play + 0.3*preisach"


def _sum_example(names: Sequence[str]) -> str:
    if all(n in names for n in ("erf-play", "preisach")) or len(names) < 2:
        return SUM_EXAMPLE
    return f"0.7*{names[1]} + 0.3*{names[0]}"


def add_model_options(
    parser: argparse.ArgumentParser,
    models: Sequence[str] | None = None,
    default: str = "dimers",
    multiple_spins: bool = False,
    sums: bool = True,
) -> None:
    """``--model`` and the model parameters (paper Table I defaults).

    ``models`` restricts the choices (default: every registered model); ``multiple_spins``
    makes ``--spins`` take one or more values (ensembles); ``sums`` lets ``--model`` be a
    weighted sum of the choices (:func:`~analysis.experiments.models.parse_model`; the
    namespace holds its canonical text). Only the options that one of the choices reads are
    offered (the others keep their default in the namespace), and each option's help names the
    models that read it unless every choice does. The options given on the command line are
    recorded (:class:`~analysis.cli._parsing.Given`), so that one the model does not read is
    refused or warned about (:func:`~analysis.cli._build.check_model_options`).
    """
    d = ModelParameters()
    names = list(models) if models is not None else list(MODELS)
    g = parser.add_argument_group("model (shared by every command; see docs: CLI)")
    sum_help = (
        f"; or a weighted sum of these names, e.g. '{_sum_example(names)}' (terms NAME, "
        "NUMBER*NAME or NAME*NUMBER joined by + or -, each name at most once; the model "
        "options below apply to every part; a leading minus needs --model=-NAME)"
        if sums
        else ""
    )
    g.add_argument(
        "--model",
        type=_model_name(names, sums),
        default=default,
        action=Given,
        metavar="{" + ",".join(names) + "}",
        help="hysteresis operator M: "
        + "; ".join(f"{n}: {MODELS[n].description}" for n in names)
        + " (erf_play is a deprecated spelling of erf-play)"
        + sum_help,
    )

    def add(option: str, default: Any, help: str, **kwargs: Any) -> None:
        dest = option[2:].replace("-", "_")
        readers = models_reading(dest, names)
        if not readers:  # no model of this command reads it: not offered
            parser.set_defaults(**{dest: default})
            return
        if len(readers) < len(names):
            help = f"{help} [{', '.join(readers)}]"
        g.add_argument(option, default=default, help=help, action=Given, **kwargs)

    add(
        "--spins",
        [d.spins] if multiple_spins else d.spins,
        "N, number of spins (dimers: even, N/2 dimers) or relays (preisach)"
        + ("; one or more values" if multiple_spins else ""),
        type=int_at_least(1, MAX_SPINS),
        nargs="+" if multiple_spins else None,
    )
    add("--seed", d.seed, "disorder seed (>= 0)", type=int_at_least(0))
    add("--width", d.width, "p, loop width (> 0)", type=positive_float)
    add("--spread", d.spread, "R, spread of loop centres (> 0)", type=positive_float)
    add(
        "--spin-coupling",
        d.spin_coupling,
        "J, spin-spin coupling of the dimers (> 0, with p < 2J)",
        type=positive_float,
    )
    add(
        "--width-spread",
        d.width_spread,
        "sigma_r, spread of the relay half-widths (preisach >= 0, preisach-gauss > 0)",
        type=nonnegative_float,
    )
    add(
        "--fields",
        None,
        "dimers: explicit local fields b1 b2 [b1 b2 ...], one pair per dimer "
        "(overrides --spins/--width/--spread/--seed)",
        type=finite_float,
        nargs="+",
    )
    add("--alpha", None, "relay: upper threshold (default p/2)", type=finite_float)
    add("--beta", None, "relay: lower threshold (default -p/2)", type=finite_float)
    add("--plays", d.plays, "pi: number K of plays", type=int_at_least(1, 10**5))
    add("--bw-a", d.bw_a, "Bouc-Wen A, the initial slope (> 0)", type=positive_float)
    add("--bw-beta", d.bw_beta, "Bouc-Wen beta (>= 0, beta + gamma > 0)", type=nonnegative_float)
    add("--bw-gamma", d.bw_gamma, "Bouc-Wen gamma (beta + gamma > 0)", type=finite_float)
    add("--bw-n", d.bw_n, "Bouc-Wen n, sharpness of saturation (>= 1)", type=finite_float)
    add(
        "--ja-ms", d.ja_ms, "Jiles-Atherton ms, saturation magnetisation (> 0)", type=positive_float
    )
    add(
        "--ja-a", d.ja_a, "Jiles-Atherton a, anhysteretic shape, a field (> 0)", type=positive_float
    )
    add("--ja-k", d.ja_k, "Jiles-Atherton k, pinning, a field (> 0)", type=positive_float)
    add("--ja-c", d.ja_c, "Jiles-Atherton c, reversible fraction in [0, 1)", type=nonnegative_float)
    add(
        "--ja-alpha",
        d.ja_alpha,
        "Jiles-Atherton alpha, mean-field coupling (>= 0, alpha ms/(3a) < 1)",
        type=nonnegative_float,
    )
    add(
        "--lattice",
        d.lattice,
        "side lengths L [L [L]] of the periodic random-field Ising lattice (1 to 3 values >= 3)",
        type=int_at_least(3, 10**6),
        nargs="+",
    )
    add(
        "--disorder",
        d.disorder,
        "R, standard deviation of the random fields in units of J (>= 0; 3-D R_c ~ 2.16)",
        type=nonnegative_float,
    )


def _model_name(names: Sequence[str], sums: bool) -> Callable[[str], str]:
    """The type of ``--model``: the canonical name, or (``sums``) the canonical text of a
    weighted sum of ``names``; any other text is refused in one line."""
    choices = ", ".join(names)
    or_sum = f" or a weighted sum of them such as '{_sum_example(names)}'" if sums else ""

    def parse(text: str) -> str:
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                expr = parse_model(text)
        except ModelExpressionError as exc:
            if exc.unknown is None:
                raise argparse.ArgumentTypeError(exc.detail) from None
            where = "" if exc.unknown == text.strip() else f" in {text!r}"
            raise argparse.ArgumentTypeError(
                f"must be one of {choices}{or_sum}; got {exc.unknown!r}{where}"
            ) from None
        for w in caught:
            print(f"hyst: warning: {w.message}", file=sys.stderr)
        if expr.plain is None and not sums:
            raise argparse.ArgumentTypeError(
                f"must be one of {choices} (this command takes no sum of models); got {text!r}"
            )
        outside = [n for n in expr.names if n not in names]
        if outside:
            got = repr(text) if expr.plain is not None else f"{outside[0]!r} in {text!r}"
            raise argparse.ArgumentTypeError(
                f"must be one of {choices}{or_sum} for this command; got {got}"
            )
        return expr.plain or str(expr)

    parse.__name__ = "model"
    return parse


def add_oscillator_options(parser: argparse.ArgumentParser, coupling: str = "required") -> None:
    """``--coupling`` (``"required"``, ``"optional"`` or ``"multiple"``), ``--damping-ratio``,
    ``--frequency`` (paper Table II defaults)."""
    g = parser.add_argument_group("oscillator q'' + 2 zeta q' + q = cos(Omega t) + C M[q]")
    kw: dict[str, Any] = {"type": finite_float}
    if coupling == "required":
        kw["required"] = True
    elif coupling == "multiple":
        kw.update(nargs="+", required=True)
    else:
        kw["default"] = None
    g.add_argument(
        "--coupling",
        help=f"C, strength of the hysteresis force, |C| <= {MAX_COUPLING:g}"
        + ("; one or more values" * (coupling == "multiple")),
        **kw,
    )
    g.add_argument(
        "--damping-ratio",
        type=finite_float,
        default=DAMPING_RATIO,
        help=f"zeta, damping ratio in [0, {MAX_DAMPING_RATIO:g}] (< 1 for play-type models)",
    )
    g.add_argument(
        "--frequency",
        type=finite_float,
        default=FREQUENCY,
        help="Omega, forcing frequency in [{:g}, {:g}]".format(*FREQUENCY_RANGE),
    )


def add_initial_options(parser: argparse.ArgumentParser) -> None:
    """``--q0``, ``--v0``, ``--w0`` (paper Table II: q0 = -1, v0 = 0.1)."""
    g = parser.add_argument_group("initial condition")
    g.add_argument("--q0", type=finite_float, default=DEFAULT_Q0, help="initial position q(0)")
    g.add_argument("--v0", type=finite_float, default=V0, help="initial velocity q'(0)")
    g.add_argument(
        "--w0",
        type=finite_float,
        default=None,
        help="play-type models: initial wagon position, |q0 - w0| <= p/2 (default: q0 - p/2, "
        "the state after rising from -inf)",
    )


def add_output_options(parser: argparse.ArgumentParser, writes: str = "") -> None:
    """``--out`` (default :data:`DEFAULT_OUT`), ``--json`` and ``--quiet``."""
    g = parser.add_argument_group("output")
    g.add_argument(
        "--out",
        type=Path,
        default=Path(DEFAULT_OUT),
        help="output directory" + (f" (writes {writes})" if writes else ""),
    )
    g.add_argument(
        "--json",
        action="store_true",
        help='print one JSON object on stdout (non-finite numbers as "inf", "-inf", "nan")',
    )
    g.add_argument(
        "--quiet",
        action="store_true",
        help="no progress bars or notices (they are on when stderr is a terminal)",
    )


def add_execution_options(group: Any) -> None:
    """Where task sweeps run and are kept: :func:`add_store_options`, ``--workers`` (local
    worker processes) and ``--scheduler`` (a Dask cluster)."""
    add_store_options(group)
    group.add_argument(
        "--workers",
        type=int_at_least(1, 1024),
        default=None,
        help="local worker processes (default: one per core)",
    )
    group.add_argument("--scheduler", default=None, help="Dask distributed scheduler address")


def add_store_options(group: Any) -> None:
    """``--store`` (default ``DIR/results.sqlite``) and ``--allow-version-mismatch``."""
    group.add_argument(
        "--store",
        type=Path,
        default=None,
        help="SQLite results file; a rerun resumes from it (default: DIR/results.sqlite)",
    )
    group.add_argument(
        "--allow-version-mismatch",
        action="store_true",
        help="reuse results that another code version stored in --store (refused by default: "
        "it would mix results of different code)",
    )


def add_transient_option(
    parser: argparse.ArgumentParser, default: float, *aliases: str, integer: bool = False
) -> None:
    """``--transient``: in forcing periods T = 2 pi/Omega (as the paper counts them)."""
    parser.add_argument(
        "--transient",
        *aliases,
        dest="transient",
        type=int_at_least(0, MAX_PERIODS) if integer else nonnegative_float,
        default=default,
        help="transient skipped before measuring, in forcing periods T = 2 pi/Omega",
    )
