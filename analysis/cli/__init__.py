"""The ``hyst`` command line.

Every subcommand lives in its own module of this package and exposes
``register(subparsers) -> None``, which adds an ``argparse`` sub-parser whose ``func`` default
is called with the parsed arguments and returns the process exit code. The commands are listed
in :data:`COMMANDS` (add a new module there). The conventions every command follows (shared
options, units, ``--json``, ``--quiet``, errors) live in :mod:`analysis.cli._options`, with the
parser pieces in :mod:`analysis.cli._parsing`, the building of library objects from options in
:mod:`analysis.cli._build` and the output in :mod:`analysis.cli._output`.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import warnings
from collections.abc import Iterator, Sequence

from analysis import __version__
from analysis.cli import (
    basins,
    bifurcation,
    continuation,
    dimension,
    ensemble,
    fit,
    identify,
    lattice,
    lyapunov,
    orbit,
    paper,
    poincare,
    trajectory,
    unmix,
    width_disorder,
)
from analysis.cli._parsing import (
    EXIT_USAGE,
    CliError,
    HelpFormatter,
    HystArgumentParser,
    fail,
    one_line,
)
from analysis.experiments.execution import TaskError
from oscillators.engines import DivergenceError
from oscillators.engines._compilation import CompilationNotice

__all__ = ["COMMANDS", "main", "build_parser"]

#: the subcommands, in the order of ``hyst --help``
COMMANDS = (
    basins,
    bifurcation,
    continuation,
    dimension,
    ensemble,
    fit,
    identify,
    lattice,
    lyapunov,
    orbit,
    paper,
    poincare,
    trajectory,
    unmix,
    width_disorder,
)


def build_parser() -> HystArgumentParser:
    """The ``hyst`` parser with every subcommand of :data:`COMMANDS` registered."""
    parser = HystArgumentParser(
        prog="hyst",
        description="Hysteresis operators and forced oscillators with hysteresis "
        "(reproduces Zech, Otto & Radons, spin dimers and the generalized play).",
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"hyst {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in COMMANDS:
        command.register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``hyst``; returns the exit status (0 success, 2 any error, 130 interrupted).

    Errors — bad options, and errors raised later inside the library or a worker process — are
    reported as one line on stderr without a traceback; ``HYST_DEBUG=1`` re-raises them. A
    :class:`~oscillators.engines.base.DivergenceError` names the parameters (C, ζ, Ω) of the
    system the command attached to it (:func:`~analysis.cli._build.naming_divergence`).
    Warnings of the library are one line each on stderr, ``hyst COMMAND: warning: <message>``,
    without source location, and each kind (category and place of origin) once per run.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, usage errors (already printed)
        return int(exc.code or 0) if not isinstance(exc.code, str) else EXIT_USAGE
    if getattr(args, "func", None) is None:  # no command: the usage, and a failure status
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    prog = f"hyst {args.command}"
    with one_line_warnings(prog):
        return _run(prog, args)


def _run(prog: str, args: argparse.Namespace) -> int:
    try:
        return int(args.func(args) or 0)
    except CliError as exc:
        return fail(prog, str(exc))
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # library and worker errors: one line, no traceback
        if os.environ.get("HYST_DEBUG"):
            raise
        if isinstance(exc, TaskError) and exc.__cause__ is not None:
            # a worker's error: name the task and the original exception, not the wrapper
            cause = exc.__cause__
            return fail(prog, f"task {exc.task} failed: {_describe(cause)}")
        message = _describe(exc)
        if isinstance(exc, DivergenceError):
            message += _parameters(getattr(exc, "system", None))
        return fail(prog, message)


@contextlib.contextmanager
def one_line_warnings(prog: str) -> Iterator[None]:
    """Within the block, show each warning as one line ``<prog>: warning: <message>`` on stderr
    (no source path, no source line), each kind — category and place of origin — once."""
    seen: set[tuple[type, str, int]] = set()

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        key = (category, str(filename), int(lineno))
        if key in seen:
            return
        seen.add(key)
        text = one_line(str(message))
        print(f"{prog}: warning: {text}", file=file or sys.stderr, flush=True)

    with warnings.catch_warnings():
        warnings.simplefilter("default")
        # the command announces the first compilation itself (announce_compilation)
        warnings.simplefilter("ignore", CompilationNotice)
        warnings.showwarning = show
        yield


def _parameters(system: object) -> str:
    """`` (coupling C = 3, ζ = 0.05, Ω = 1)`` for the system, or ``""``."""
    try:
        c, zeta, omega = system.coupling, system.damping_ratio, system.frequency  # type: ignore[attr-defined]
    except AttributeError:
        return ""
    return f" (coupling C = {c:g}, ζ = {zeta:g}, Ω = {omega:g})"


def _describe(exc: BaseException) -> str:
    text = str(exc) or type(exc).__name__
    if type(exc).__name__ in ("ValueError", "TypeError"):
        return text
    return f"{type(exc).__name__}: {text}"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
