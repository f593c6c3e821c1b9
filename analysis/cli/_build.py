"""From the options to the library's objects: model parameters, operator, system, initial state,
run window and results store, each built once, with the library's errors reported against the
option that carried the value (:func:`~analysis.cli._parsing.library_errors`)."""

from __future__ import annotations

import argparse
import math
import warnings
from collections.abc import Callable, Collection, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from analysis.cli._options import models_reading
from analysis.cli._parsing import CliError, given_options, library_errors
from analysis.cli._parsing import option_error as _option_error
from analysis.experiments.models import MODELS, ModelParameters, parameters_read, parse_model
from analysis.experiments.models import build_operator as build_model
from analysis.experiments.models import model_record as record_model
from analysis.experiments.store import ResultStore, StoreError
from oscillators import MAX_PERIODS, ForcedOscillator
from oscillators.engines import DivergenceError

__all__ = [
    "MODEL_OPTIONS",
    "OPTION_OF",
    "OSCILLATOR_OPTIONS",
    "option_error",
    "RUN_OPTIONS",
    "build_operator",
    "build_system",
    "check_model_options",
    "check_no_model_options",
    "check_run_length",
    "check_store",
    "check_transient",
    "initial_operator_state",
    "naming_divergence",
    "initial_record",
    "model_parts",
    "play_type",
    "model_parameters",
    "model_record",
    "store_error",
    "store_path",
    "transient_time",
]

#: library parameter name -> the option that carries it (model options)
MODEL_OPTIONS = {
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
    **{f"bw_{n}": f"--bw-{n}" for n in ("a", "beta", "gamma", "n")},
    **{f"ja_{n}": f"--ja-{n}" for n in ("ms", "a", "k", "c", "alpha")},
    "lattice": "--lattice",
    "shape": "--lattice",
    "disorder": "--disorder",
}
#: library parameter name -> option, for the oscillator and its initial condition
OSCILLATOR_OPTIONS = {
    "coupling": "--coupling",
    "damping_ratio": "--damping-ratio",
    "frequency": "--frequency",
    "q0": "--q0",
    "v0": "--v0",
    "u0": "--q0",
    "position": "--w0",
    "w0": "--w0",
}
#: library parameter name -> option, for the run window
RUN_OPTIONS = {"t_end": "--t-end", "transient": "--transient"}


#: every library parameter the commands pass from an option
OPTION_OF = {**MODEL_OPTIONS, **OSCILLATOR_OPTIONS, **RUN_OPTIONS}


def option_error(exc: BaseException, default_option: str | None = None) -> CliError:
    """A :class:`CliError` naming the option behind a library ``ValueError``/``TypeError`` (any
    of :data:`OPTION_OF`), else ``default_option``."""
    return _option_error(exc, OPTION_OF, default_option)


def model_parameters(args: argparse.Namespace, half_extent: float | None = None) -> Any:
    """The :class:`~analysis.experiments.models.ModelParameters` given by the options
    (``half_extent``: the ``preisach-uniform`` triangle of a command that gives it one, e.g.
    ``hyst identify --saturation``)."""
    spins = args.spins[0] if isinstance(args.spins, list) else args.spins
    defaults = ModelParameters()
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
        half_extent=half_extent,
        **{f: getattr(args, f, getattr(defaults, f)) for f in DUHEM_FIELDS},
        lattice=tuple(getattr(args, "lattice", defaults.lattice)),
        disorder=getattr(args, "disorder", defaults.disorder),
    )


def model_parts(args: argparse.Namespace) -> tuple[str, ...]:
    """The registry names ``--model`` is made of: one name, or the parts of a weighted sum."""
    if args.model in MODELS:
        return (args.model,)
    return parse_model(args.model).names  # canonical text (the option's type made it)


def play_type(args: argparse.Namespace) -> bool:
    """Whether ``--model`` is a play-type model (its memory one wagon: ``--w0`` applies); never
    a sum, whose state is its parts' states."""
    spec = MODELS.get(args.model)
    return spec is not None and spec.play_type


#: model options (their ``dest``) that select one model's feature: given to a model without
#: it, the user meant another model, and the command refuses
#: the Duhem models' parameters (``bouc-wen``, ``jiles-atherton``)
DUHEM_FIELDS = (
    *("bw_a", "bw_beta", "bw_gamma", "bw_n"),
    *("ja_ms", "ja_a", "ja_k", "ja_c", "ja_alpha"),
)
MODEL_SPECIFIC = (
    *("width_spread", "plays", "fields", "alpha", "beta"),
    *DUHEM_FIELDS,
    *("lattice", "disorder"),
)
#: model options the paper's models share: given to a model that does not read them (a script
#: running several models with one set of options), the command warns and goes on
MODEL_SHARED = ("spins", "seed", "width", "spread", "spin_coupling")


def _option(dest: str) -> str:
    return "--" + dest.replace("_", "-")


def check_model_options(
    args: argparse.Namespace,
    command_reads: Collection[str] = (),
    half_extent: float | None = None,
) -> None:
    """Cross-option checks that one option's type cannot express; raises :class:`CliError`.
    A weighted sum is checked as each of its parts (the options apply to every part).

    A model option given on the command line that neither the model (any part of a sum,
    :func:`~analysis.experiments.models.parameters_read`) nor the command itself
    (``command_reads``: ``dest`` names) reads is refused in one line when it is one model's
    feature (:data:`MODEL_SPECIFIC`: ``--plays`` with ``erf-play``) and warned about once,
    listing every such option, when the models share it (:data:`MODEL_SHARED`: ``--spins``
    with ``erf-play``, the N -> infinity limit). Options left at their defaults never count.
    ``half_extent``: as for :func:`model_parameters`.
    """
    model = args.model
    parts = model_parts(args)
    fields = getattr(args, "fields", None)
    if fields is not None:
        if "dimers" not in parts:
            raise CliError("argument --fields: only for --model dimers (or a sum with dimers)")
        if len(fields) % 2:
            raise CliError(f"argument --fields: needs pairs b1 b2 (got {len(fields)} values)")
    spins = args.spins if isinstance(args.spins, list) else [args.spins]
    if "dimers" in parts and fields is None:
        for n in spins:
            if n < 2 or n % 2:
                raise CliError(f"argument --spins: dimers need an even N >= 2, got {n}")
        if not args.width < 2.0 * args.spin_coupling:
            raise CliError(
                f"argument --width: dimers need p < 2J = {2.0 * args.spin_coupling:g} "
                f"(--spin-coupling), got {args.width:g}"
            )
    if "relay" in parts:
        alpha = 0.5 * args.width if args.alpha is None else args.alpha
        beta = -0.5 * args.width if args.beta is None else args.beta
        if alpha < beta:
            raise CliError(f"argument --alpha: must be >= --beta, got {alpha:g} < {beta:g}")
    elif args.alpha is not None or args.beta is not None:
        raise CliError("argument --alpha/--beta: only for --model relay (or a sum with relay)")
    if "preisach-gauss" in parts and args.width_spread <= 0:
        raise CliError("argument --width-spread: preisach-gauss needs sigma_r > 0, got 0")
    w0 = getattr(args, "w0", None)
    if w0 is not None:
        if not play_type(args):
            raise CliError(
                f"argument --w0: only for play-type models (erf-play, play), not {model}"
            )
        if abs(args.q0 - w0) > 0.5 * args.width * (1.0 + 1e-12):
            raise CliError(
                f"argument --w0: needs |q0 - w0| <= p/2 = {0.5 * args.width:g}, "
                f"got q0 = {args.q0:g}, w0 = {w0:g}"
            )
    _check_unread(args, command_reads, half_extent)


def _check_unread(
    args: argparse.Namespace, command_reads: Collection[str], half_extent: float | None
) -> None:
    """Refuse or warn about the model options given that nothing reads (see
    :func:`check_model_options`)."""
    given = given_options(args)
    if not given & {*MODEL_SPECIFIC, *MODEL_SHARED}:
        return
    reads = parameters_read(args.model, model_parameters(args, half_extent)) | set(command_reads)
    for dest in MODEL_SPECIFIC:
        if dest in given and dest not in reads:
            readers = models_reading(dest, list(MODELS))
            which = " or ".join(readers)
            one = "it" if len(readers) == 1 else "one of them"
            raise CliError(
                f"argument {_option(dest)}: only for --model {which} (or a sum with {one}), "
                f"not {args.model}"
            )
    unread = [_option(d) for d in MODEL_SHARED if d in given and d not in reads]
    if unread:
        read = [_option(d) for d in (*MODEL_SHARED, *MODEL_SPECIFIC) if d in reads]
        it_reads = f"it reads {', '.join(read)}" if read else "it reads no model option"
        warnings.warn(
            f"--model {args.model} does not read {', '.join(unread)}: ignored ({it_reads})",
            UserWarning,
            stacklevel=3,
        )


def check_no_model_options(args: argparse.Namespace, source: str, active: bool) -> None:
    """Refuse, when ``active``, a model option given with ``source`` (e.g. ``hyst identify
    --input``: the files are identified and no model is built, so ``--model`` or ``--spins``
    there means the user expected another source or a comparison the command does not make)."""
    if not active:
        return
    given = given_options(args)
    for dest in ("model", *MODEL_SHARED, *MODEL_SPECIFIC):
        if dest in given:
            raise CliError(
                f"argument {_option(dest)}: a model option, not read with {source} (no model "
                f"is built); give --model or {source}, not both"
            )


def model_record(args: argparse.Namespace, half_extent: float | None = None) -> dict[str, Any]:
    """The model and the parameters it reads, JSON-ready (``half_extent``: as for
    :func:`model_parameters`)."""
    return record_model(args.model, model_parameters(args, half_extent))


def initial_record(args: argparse.Namespace) -> dict[str, Any]:
    """``q0``, ``v0`` and, for play-type models, the effective ``w0`` (default ``q0 - p/2``)."""
    out: dict[str, Any] = {"q0": args.q0, "v0": args.v0}
    if play_type(args):
        out["w0"] = args.q0 - 0.5 * args.width if args.w0 is None else args.w0
    return out


def build_operator(args: argparse.Namespace) -> Any:
    """The operator of ``--model``, a weighted sum's built by the library (library errors
    reported against the option)."""
    with library_errors(MODEL_OPTIONS, "--model"):
        return build_model(args.model, model_parameters(args))


def build_system(
    args: argparse.Namespace, operator: Any = None, coupling: float | None = None
) -> Any:
    """``ForcedOscillator(operator, C, zeta, Omega)`` from the options, built once: the library
    checks C, zeta and Omega against its bounds and its message names the option."""
    c = args.coupling if coupling is None else coupling
    op = build_operator(args) if operator is None else operator
    with library_errors(OSCILLATOR_OPTIONS, "--model"):
        return ForcedOscillator(op, c, args.damping_ratio, args.frequency)


@contextmanager
def naming_divergence(current_system: Callable[[], Any]) -> Iterator[None]:
    """Within the block, a :class:`~oscillators.engines.base.DivergenceError` carries the
    system it came from (attribute ``system``, for the error line's C, ζ, Ω):
    called when the error passes — a one-system command gives ``lambda: system``, a sweep the
    system it built last (it builds one per value, in order). An inner block's system wins."""
    try:
        yield
    except DivergenceError as exc:
        if getattr(exc, "system", None) is None:
            exc.system = current_system()  # type: ignore[attr-defined]
        raise


def initial_operator_state(args: argparse.Namespace, operator: Any) -> Any:
    """``None`` (the operator's ``initial_state(q0)``) or, with ``--w0``, the play state
    ``operator.state(position=w0, input=q0)``."""
    if getattr(args, "w0", None) is None:
        return None
    with library_errors(OSCILLATOR_OPTIONS, "--w0"):
        return operator.state(position=args.w0, input=args.q0)


def transient_time(args: argparse.Namespace, frequency: float | None = None) -> float:
    """``--transient`` (forcing periods) as a time."""
    omega = args.frequency if frequency is None else frequency
    return float(args.transient) * 2.0 * math.pi / omega


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


def store_path(args: argparse.Namespace) -> Path:
    """``--store``, or ``results.sqlite`` in ``--out``."""
    return Path(args.store) if args.store is not None else Path(args.out) / "results.sqlite"


def store_error(exc: BaseException) -> CliError:
    """A :class:`CliError` naming ``--store`` for a
    :class:`~analysis.experiments.store.StoreError` (the library's advice
    ``allow_version_mismatch=True`` spelled as the option)."""
    msg = str(exc).replace("pass allow_version_mismatch=True", "pass --allow-version-mismatch")
    return CliError(f"argument --store: {msg}")


def check_store(args: argparse.Namespace, experiments: Sequence[str] | None = None) -> Path:
    """Refuse, before any work, a damaged or foreign ``--store`` file and (unless
    ``--allow-version-mismatch``) one whose ``experiments`` hold results of other code versions
    (``None``: every experiment in the store). A missing store is fine (a new one)."""
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
