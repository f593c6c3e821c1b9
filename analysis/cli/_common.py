"""Conventions shared by every ``hyst`` subcommand (one place, so the commands cannot drift).

* **Options.** Model options (``--model``, ``--spins``, ``--seed``, ``--width``, ``--spread``,
  ``--spin-coupling``, ``--width-spread`` and the model-specific ``--fields``, ``--alpha``,
  ``--beta``, ``--plays``), oscillator options (``--coupling``, ``--damping-ratio``,
  ``--frequency``), the initial condition (``--q0``, ``--v0``, ``--w0``) and the output options
  (``--out``, ``--json``, ``--quiet``) are defined here and added to each subcommand from here.
* **Units.** Times (``--t-end``) are in the oscillator's time unit (undamped natural period
  2π); transients (``--transient``) are counted in forcing periods ``T = 2π/Ω``, as in the paper.
* **Output.** ``--out`` defaults to :data:`DEFAULT_OUT` for every command. ``--json`` prints
  exactly one JSON object on stdout; non-finite numbers are encoded as the strings ``"inf"``,
  ``"-inf"`` and ``"nan"`` (:func:`to_json`), never as bare ``Infinity``/``NaN`` tokens (not
  JSON) or ``null`` (ambiguous).
* **Progress.** Progress bars go to stderr; they are on when stderr is a terminal and off with
  ``--quiet`` or when stderr is not a TTY. Library functions are quiet by default.
* **Errors.** Every option is validated before any work starts. A bad value, or an error raised
  later inside the library or a worker process, ends the command with one line
  ``hyst COMMAND: error: ...`` on stderr and exit status 2, never a traceback (set the
  environment variable ``HYST_DEBUG=1`` to see the traceback of an unexpected error).
"""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

__all__ = [
    "DEFAULT_OUT",
    "EXIT_USAGE",
    "CliError",
    "HelpFormatter",
    "HystArgumentParser",
    "add_initial_options",
    "add_model_options",
    "add_oscillator_options",
    "add_output_options",
    "add_execution_options",
    "add_store_options",
    "add_subcommand",
    "announce_compilation",
    "build_operator",
    "build_system",
    "check_store",
    "check_model_options",
    "check_run_length",
    "check_transient",
    "emit",
    "figure_title",
    "finite_float",
    "initial_operator_state",
    "initial_record",
    "int_at_least",
    "model_parameters",
    "model_record",
    "nonnegative_float",
    "option_error",
    "positive_float",
    "prepare_out",
    "progress_enabled",
    "store_error",
    "to_json",
    "transient_time",
]

#: the default output directory of every command (each writes its own file names into it)
DEFAULT_OUT = "hyst-out"
#: exit status of every error (bad option, failed run): the argparse usage-error status
EXIT_USAGE = 2


class CliError(ValueError):
    """A bad option value; the message already names the option (``argument --x: ...``)."""


class HelpFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows every default in ``--help`` (an option without a default value says how its
    default is derived in its own help text instead of ``(default: None)``)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if action.default is None or action.default is False or "default" in text:
            return text
        return super()._get_help_string(action)


class HystArgumentParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose usage errors are one line on stderr and exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {_one_line(message)}\n")


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def add_subcommand(
    subparsers: Any, name: str, help: str, description: str
) -> argparse.ArgumentParser:
    """A sub-parser with the shared formatter (defaults in ``--help``)."""
    return subparsers.add_parser(
        name,
        help=help,
        description=description,
        formatter_class=HelpFormatter,
    )


# -- argparse value types: reject bad values while parsing, naming the option ------------------


def _float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a real number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return value


def finite_float(text: str) -> float:
    """A finite real number."""
    return _float(text)


def positive_float(text: str) -> float:
    """A finite real number > 0."""
    value = _float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text!r}")
    return value


def nonnegative_float(text: str) -> float:
    """A finite real number >= 0."""
    value = _float(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text!r}")
    return value


def int_at_least(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    """An integer in ``[minimum, maximum]`` (the type's ``__name__`` appears in messages)."""

    def parse(text: str) -> int:
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None
        if value < minimum or (maximum is not None and value > maximum):
            hi = "" if maximum is None else f" and <= {maximum}"
            raise argparse.ArgumentTypeError(f"must be an integer >= {minimum}{hi}, got {text!r}")
        return value

    parse.__name__ = f"int>={minimum}"
    return parse


# -- shared options -----------------------------------------------------------------------------

#: the largest ensemble a command builds (memory: a few GB of thresholds and state)
MAX_SPINS = 10**8


def add_model_options(
    parser: argparse.ArgumentParser,
    models: Sequence[str] | None = None,
    default: str = "dimers",
    multiple_spins: bool = False,
) -> None:
    """``--model`` and the model parameters (paper Table I defaults).

    ``models`` restricts the choices (default: every registered model); ``multiple_spins``
    makes ``--spins`` take one or more values (ensembles).
    """
    from analysis.models import MODELS, ModelParameters

    d = ModelParameters()
    names = list(models) if models is not None else list(MODELS)
    g = parser.add_argument_group("model (shared by every command; see docs: CLI)")
    g.add_argument(
        "--model",
        type=_model_name(names),
        default=default,
        metavar="{" + ",".join(names) + "}",
        help="hysteresis operator M: "
        + "; ".join(f"{n}: {MODELS[n].description}" for n in names)
        + " (erf_play is a deprecated spelling of erf-play)",
    )
    g.add_argument(
        "--spins",
        type=int_at_least(1, MAX_SPINS),
        nargs="+" if multiple_spins else None,
        default=[d.spins] if multiple_spins else d.spins,
        help="N, number of spins (dimers: even, N/2 dimers) or relays (preisach)"
        + ("; one or more values" if multiple_spins else ""),
    )
    g.add_argument("--seed", type=int_at_least(0), default=d.seed, help="disorder seed (>= 0)")
    g.add_argument("--width", type=positive_float, default=d.width, help="p, loop width (> 0)")
    g.add_argument(
        "--spread", type=positive_float, default=d.spread, help="R, spread of loop centres (> 0)"
    )
    g.add_argument(
        "--spin-coupling",
        type=positive_float,
        default=d.spin_coupling,
        help="J, spin-spin coupling of the dimers (> 0, with p < 2J)",
    )
    g.add_argument(
        "--width-spread",
        type=nonnegative_float,
        default=d.width_spread,
        help="sigma_r, spread of the relay half-widths (preisach >= 0, preisach-gauss > 0)",
    )
    g.add_argument(
        "--fields",
        type=finite_float,
        nargs="+",
        default=None,
        help="dimers: explicit local fields b1 b2 [b1 b2 ...], one pair per dimer "
        "(overrides --spins/--width/--spread/--seed)",
    )
    g.add_argument(
        "--alpha", type=finite_float, default=None, help="relay: upper threshold (default p/2)"
    )
    g.add_argument(
        "--beta", type=finite_float, default=None, help="relay: lower threshold (default -p/2)"
    )
    g.add_argument(
        "--plays", type=int_at_least(1, 10**5), default=d.plays, help="pi: number K of plays"
    )


def _model_name(names: Sequence[str]) -> Callable[[str], str]:
    def parse(text: str) -> str:
        import warnings

        from analysis.models import canonical_model_name

        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                name = canonical_model_name(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"must be one of {', '.join(names)}; got {text!r}"
            ) from None
        for w in caught:
            print(f"hyst: warning: {w.message}", file=sys.stderr)
        if name not in names:
            raise argparse.ArgumentTypeError(
                f"must be one of {', '.join(names)} for this command; got {text!r}"
            )
        return name

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
        help="C, strength of the hysteresis force"
        + ("; one or more values" * (coupling == "multiple")),
        **kw,
    )
    g.add_argument(
        "--damping-ratio",
        type=nonnegative_float,
        default=0.05,
        help="zeta, damping ratio (>= 0; < 1 for play-type models)",
    )
    g.add_argument("--frequency", type=positive_float, default=1.0, help="Omega, forcing frequency")


def add_initial_options(parser: argparse.ArgumentParser) -> None:
    """``--q0``, ``--v0``, ``--w0`` (paper Table II: q0 = -1, v0 = 0.1)."""
    g = parser.add_argument_group("initial condition")
    g.add_argument("--q0", type=finite_float, default=-1.0, help="initial position q(0)")
    g.add_argument("--v0", type=finite_float, default=0.1, help="initial velocity q'(0)")
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


def store_path(args: argparse.Namespace) -> Path:
    """``--store``, or ``results.sqlite`` in ``--out``."""
    return Path(args.store) if args.store is not None else Path(args.out) / "results.sqlite"


def store_error(exc: BaseException) -> CliError:
    """A :class:`CliError` naming ``--store`` for a :class:`~analysis.store.StoreError` (the
    library's advice ``allow_version_mismatch=True`` spelled as the option)."""
    msg = str(exc).replace("pass allow_version_mismatch=True", "pass --allow-version-mismatch")
    return CliError(f"argument --store: {msg}")


def check_store(args: argparse.Namespace, experiments: Sequence[str] | None = None) -> Path:
    """Refuse, before any work, a damaged or foreign ``--store`` file and (unless
    ``--allow-version-mismatch``) one whose ``experiments`` hold results of other code versions
    (``None``: every experiment in the store). A missing store is fine (a new one)."""
    from analysis.store import ResultStore, StoreError

    path = store_path(args)
    if not path.exists():
        return path
    try:
        with ResultStore(path) as store:
            names = store.experiments() if experiments is None else list(experiments)
            for name in names:
                store.check_versions(name, args.allow_version_mismatch)
    except StoreError as exc:
        raise store_error(exc) from exc
    return path


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


# -- from options to objects ------------------------------------------------------------------

#: library parameter name -> command line option (used to name the option in library errors)
_OPTION_OF = {
    "n_spins": "--spins",
    "spins": "--spins",
    "seed": "--seed",
    "width_spread": "--width-spread",
    "width": "--width",
    "spread": "--spread",
    "spin_coupling": "--spin-coupling",
    "fields": "--fields",
    "alpha": "--alpha",
    "beta": "--beta",
    "plays": "--plays",
    "coupling": "--coupling",
    "damping_ratio": "--damping-ratio",
    "frequency": "--frequency",
    "position": "--w0",
    "w0": "--w0",
    "q0": "--q0",
    "v0": "--v0",
    "u0": "--q0",
    "t_end": "--t-end",
    "transient": "--transient",
}


def option_error(exc: BaseException, default_option: str | None = None) -> CliError:
    """A :class:`CliError` naming the option behind a library ``ValueError``/``TypeError``.

    The library names the parameter first (``"width must be ..."``); that name is mapped to
    its option. Otherwise ``default_option`` (if given) is named.
    """
    msg = _one_line(str(exc))
    for name in sorted(_OPTION_OF, key=len, reverse=True):
        if re.match(rf"{re.escape(name)}\b", msg):
            return CliError(f"argument {_OPTION_OF[name]}: {msg}")
    if default_option is not None:
        return CliError(f"argument {default_option}: {msg}")
    return CliError(msg)


def model_parameters(args: argparse.Namespace) -> Any:
    """The :class:`~analysis.models.ModelParameters` given by the options."""
    from analysis.models import ModelParameters

    spins = args.spins[0] if isinstance(args.spins, list) else args.spins
    fields = None
    if getattr(args, "fields", None) is not None:
        fields = tuple(zip(args.fields[0::2], args.fields[1::2], strict=True))
    return ModelParameters(
        spins=spins,
        seed=args.seed,
        width=args.width,
        spread=args.spread,
        spin_coupling=args.spin_coupling,
        width_spread=args.width_spread,
        fields=fields,
        alpha=args.alpha,
        beta=args.beta,
        plays=args.plays,
        # set by commands that give preisach-uniform its half-extent (hyst identify --saturation)
        half_extent=getattr(args, "half_extent", None),
    )


def check_model_options(args: argparse.Namespace) -> None:
    """Cross-option checks that one option's type cannot express; raises :class:`CliError`."""
    from analysis.models import MODELS

    model = args.model
    spec = MODELS[model]
    fields = getattr(args, "fields", None)
    if fields is not None:
        if model != "dimers":
            raise CliError("argument --fields: only for --model dimers")
        if len(fields) % 2:
            raise CliError(f"argument --fields: needs pairs b1 b2 (got {len(fields)} values)")
    spins = args.spins if isinstance(args.spins, list) else [args.spins]
    if model == "dimers" and fields is None:
        for n in spins:
            if n < 2 or n % 2:
                raise CliError(f"argument --spins: dimers need an even N >= 2, got {n}")
        if not args.width < 2.0 * args.spin_coupling:
            raise CliError(
                f"argument --width: dimers need p < 2J = {2.0 * args.spin_coupling:g} "
                f"(--spin-coupling), got {args.width:g}"
            )
    if model == "relay":
        alpha = 0.5 * args.width if args.alpha is None else args.alpha
        beta = -0.5 * args.width if args.beta is None else args.beta
        if alpha < beta:
            raise CliError(f"argument --alpha: must be >= --beta, got {alpha:g} < {beta:g}")
    elif args.alpha is not None or args.beta is not None:
        raise CliError("argument --alpha/--beta: only for --model relay")
    if model == "preisach-gauss" and args.width_spread <= 0:
        raise CliError("argument --width-spread: preisach-gauss needs sigma_r > 0, got 0")
    w0 = getattr(args, "w0", None)
    if w0 is not None:
        if not spec.play_type:
            raise CliError(
                f"argument --w0: only for play-type models (erf-play, play), not {model}"
            )
        if abs(args.q0 - w0) > 0.5 * args.width * (1.0 + 1e-12):
            raise CliError(
                f"argument --w0: needs |q0 - w0| <= p/2 = {0.5 * args.width:g}, "
                f"got q0 = {args.q0:g}, w0 = {w0:g}"
            )


def model_record(args: argparse.Namespace) -> dict[str, Any]:
    """The model and the parameters it reads, JSON-ready."""
    from analysis.models import model_record as record

    return record(args.model, model_parameters(args))


def initial_record(args: argparse.Namespace) -> dict[str, Any]:
    """``q0``, ``v0`` and, for play-type models, the effective ``w0`` (default ``q0 - p/2``)."""
    from analysis.models import MODELS

    out: dict[str, Any] = {"q0": args.q0, "v0": args.v0}
    if MODELS[args.model].play_type:
        out["w0"] = args.q0 - 0.5 * args.width if args.w0 is None else args.w0
    return out


def build_operator(args: argparse.Namespace) -> Any:
    """The operator of ``--model`` (library errors re-raised naming the option)."""
    from analysis.models import build_operator as build

    try:
        return build(args.model, model_parameters(args))
    except (ValueError, TypeError) as exc:
        raise option_error(exc, "--model") from exc


#: bounds on abs(C), zeta and Omega beyond which the arithmetic of a run overflows or the run has
#: no end (a forcing period of 2 pi/Omega > MAX_PERIOD time units)
MAX_PARAMETER = 1e6
MAX_PERIOD = 1e6


def check_oscillator_values(coupling: float, damping_ratio: float, frequency: float) -> None:
    """Refuse oscillator parameters whose runs cannot be meaningful, naming the option."""
    if not all(math.isfinite(x) for x in (coupling, damping_ratio, frequency)):
        raise CliError("argument --coupling/--damping-ratio/--frequency: must be finite")
    if damping_ratio < 0:
        raise CliError(f"argument --damping-ratio: must be >= 0, got {damping_ratio:g}")
    if frequency <= 0:
        raise CliError(f"argument --frequency: must be > 0, got {frequency:g}")
    if abs(coupling) > MAX_PARAMETER:
        raise CliError(f"argument --coupling: |C| must be <= {MAX_PARAMETER:g}, got {coupling:g}")
    if damping_ratio > MAX_PARAMETER:
        raise CliError(
            f"argument --damping-ratio: must be <= {MAX_PARAMETER:g}, got {damping_ratio:g}"
        )
    if frequency > MAX_PARAMETER:
        raise CliError(f"argument --frequency: must be <= {MAX_PARAMETER:g}, got {frequency:g}")
    if 2.0 * math.pi / frequency > MAX_PERIOD:
        raise CliError(
            f"argument --frequency: the forcing period 2 pi/Omega = {2 * math.pi / frequency:.3g} "
            f"exceeds {MAX_PERIOD:g} time units (Omega >= {2 * math.pi / MAX_PERIOD:.3g})"
        )


def build_system(
    args: argparse.Namespace, operator: Any = None, coupling: float | None = None
) -> Any:
    """``ForcedOscillator(operator, C, zeta, Omega)`` from the options."""
    from oscillators import ForcedOscillator

    c = args.coupling if coupling is None else coupling
    check_oscillator_values(c, args.damping_ratio, args.frequency)
    op = build_operator(args) if operator is None else operator
    try:
        return ForcedOscillator(op, c, args.damping_ratio, args.frequency)
    except (ValueError, TypeError, NotImplementedError) as exc:
        raise option_error(exc, "--model") from exc


def initial_operator_state(args: argparse.Namespace, operator: Any) -> Any:
    """``None`` (the operator's ``initial_state(q0)``) or, with ``--w0``, the play state
    ``operator.state(position=w0, input=q0)``."""
    if getattr(args, "w0", None) is None:
        return None
    try:
        return operator.state(position=args.w0, input=args.q0)
    except (ValueError, TypeError) as exc:
        raise option_error(exc, "--w0") from exc


def transient_time(args: argparse.Namespace, frequency: float | None = None) -> float:
    """``--transient`` (forcing periods) as a time."""
    omega = args.frequency if frequency is None else frequency
    return float(args.transient) * 2.0 * math.pi / omega


#: the longest run a command accepts, in forcing periods (refused up front, not run for days)
MAX_PERIODS = 10**8


def check_run_length(args: argparse.Namespace, t_end: float, option: str = "--t-end") -> None:
    """Refuse a run longer than :data:`MAX_PERIODS` forcing periods, naming the option."""
    periods = (
        t_end * args.frequency / (2.0 * math.pi) if not isinstance(args.frequency, list) else 0
    )
    if periods > MAX_PERIODS:
        raise CliError(
            f"argument {option}: {t_end:g} time units are {periods:.3g} forcing periods, more "
            f"than the limit {MAX_PERIODS:.0e}"
        )


def check_transient(args: argparse.Namespace, t_end: float) -> float:
    """``--transient`` as a time, checked to be shorter than ``t_end`` (and ``t_end`` against
    :data:`MAX_PERIODS`)."""
    check_run_length(args, t_end)
    transient = transient_time(args)
    if transient >= t_end:
        raise CliError(
            f"argument --transient: {args.transient:g} periods = {transient:g} time units must "
            f"be shorter than --t-end {t_end:g}"
        )
    return transient


def progress_enabled(args: argparse.Namespace) -> bool:
    """Progress bars: on when stderr is a terminal, off with ``--quiet``."""
    if getattr(args, "quiet", False):
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def announce_compilation(args: argparse.Namespace) -> None:
    """Say on stderr that the first run compiles the numba kernels (once; cached after).

    The kernels are compiled with ``cache=True``; when no cache file exists yet next to the
    compiled modules (nor in ``NUMBA_CACHE_DIR``), this run compiles them.
    """
    if getattr(args, "quiet", False):
        return
    import hysteresis
    import oscillators

    places = [Path(hysteresis.__file__).parent, Path(oscillators.__file__).parent]
    cache_dir = os.environ.get("NUMBA_CACHE_DIR")
    if cache_dir:
        places.append(Path(cache_dir))
    for place in places:
        if any(place.rglob("*.nbi")):
            return
    print(
        "hyst: first run: compiling the numerical kernels (once, about a minute; "
        "cached for later runs)",
        file=sys.stderr,
        flush=True,
    )


# -- output -------------------------------------------------------------------------------------


def to_json(record: Any, indent: int | None = None) -> str:
    """JSON text of ``record`` (see :func:`analysis._json.to_json`): numpy values as Python
    numbers, paths as strings, non-finite floats as the strings ``"inf"``, ``"-inf"``,
    ``"nan"`` (strict JSON)."""
    from analysis._json import to_json as encode

    return encode(record, indent=indent)


def emit(args: argparse.Namespace, record: dict[str, Any], lines: Sequence[str]) -> None:
    """Print the record as one JSON object (``--json``) or the human-readable lines."""
    if args.json:
        sys.stdout.write(to_json(record) + "\n")
    else:
        for line in lines:
            print(line)


def figure_title(args: argparse.Namespace, what: str, **extra: Any) -> str:
    """``"<what>: <model and parameters>, C=..., zeta=..., Omega=..."`` for a figure title."""
    from analysis.models import describe_model

    pairs: list[tuple[str, Any]] = []
    if getattr(args, "coupling", None) is not None and not isinstance(args.coupling, list):
        pairs.append(("C", float(args.coupling)))
    for symbol, name in (("ζ", "damping_ratio"), ("Ω", "frequency")):
        if getattr(args, name, None) is not None:  # commands without an oscillator omit them
            pairs.append((symbol, float(getattr(args, name))))
    pairs.extend(extra.items())
    return f"{what}: {describe_model(model_record(args), pairs)}"


def prepare_out(args: argparse.Namespace) -> Path:
    """Check ``--out`` (a directory or a new path) before any work; create it."""
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CliError(f"argument --out: {out} exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CliError(f"argument --out: cannot create {out}: {exc.strerror or exc}") from exc
    if not os.access(out, os.W_OK):
        raise CliError(f"argument --out: {out} is not writable")
    return out


def fail(prog: str, message: str) -> int:
    """Print the one-line error and return the exit status."""
    print(f"{prog}: error: {_one_line(message)}", file=sys.stderr, flush=True)
    return EXIT_USAGE
