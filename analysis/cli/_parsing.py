"""The parser of ``hyst`` and the value types of its options: argparse pieces shared by every
subcommand, and the one-line error of every failure.

A bad value is refused while parsing, naming the option (``argument --x: ...``); an error the
library raises for a value the command passed on is reported as the library's own message,
prefixed with the option that carried the value (:func:`library_errors`).
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from typing import Any, NoReturn

__all__ = [
    "EXIT_USAGE",
    "CliError",
    "Given",
    "HelpFormatter",
    "HystArgumentParser",
    "add_subcommand",
    "fail",
    "finite_float",
    "given_options",
    "int_at_least",
    "library_errors",
    "nonnegative_float",
    "one_line",
    "option_error",
    "positive_float",
]

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
        self.exit(EXIT_USAGE, f"{self.prog}: error: {one_line(message)}\n")


#: the namespace attribute where :class:`Given` records the options given on the command line
GIVEN = "given_options"


class Given(argparse.Action):
    """``store``, and the option's ``dest`` recorded in the namespace's set
    :data:`GIVEN`: an option the user gave is told apart from one at its default (even when
    given its default value)."""

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        setattr(namespace, self.dest, values)
        given = set(getattr(namespace, GIVEN, None) or ())
        given.add(self.dest)
        setattr(namespace, GIVEN, given)


def given_options(args: argparse.Namespace) -> frozenset[str]:
    """The ``dest`` of every :class:`Given` option given on the command line."""
    return frozenset(getattr(args, GIVEN, None) or ())


def one_line(text: str) -> str:
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


# -- errors -------------------------------------------------------------------------------------


def _parameter(message: str) -> str:
    """The parameter a library message is about: by the library's convention its first word
    (``"coupling must lie in [...]"``)."""
    end = 0
    while end < len(message) and (message[end].isalnum() or message[end] == "_"):
        end += 1
    return message[:end]


def option_error(
    exc: BaseException, options: Mapping[str, str], default: str | None = None
) -> CliError:
    """A :class:`CliError` with the library's message of ``exc``, prefixed with the option that
    carried the parameter it names (``options``: library parameter -> option), else
    ``default``."""
    message = one_line(str(exc))
    option = options.get(_parameter(message), default)
    return CliError(f"argument {option}: {message}" if option else message)


@contextmanager
def library_errors(options: Mapping[str, str], default: str | None = None) -> Iterator[None]:
    """Report a library ``ValueError``/``TypeError`` raised inside the block as a
    :class:`CliError` (:func:`option_error`): the library's own message, prefixed with the option
    that carried the value of the parameter it names.

    ``options`` maps the library's parameter names to the options the command passed them from
    (e.g. ``{"coupling": "--coupling"}``); a message about another parameter names ``default``.
    The bounds and their wording stay in the library.
    """
    try:
        yield
    except CliError:
        raise
    except (ValueError, TypeError) as exc:
        raise option_error(exc, options, default) from exc


def fail(prog: str, message: str) -> int:
    """Print the one-line error and return the exit status."""
    print(f"{prog}: error: {one_line(message)}", file=sys.stderr, flush=True)
    return EXIT_USAGE
