"""What every ``hyst`` command writes: progress and notices on stderr, the ``--json`` record or
the human-readable lines on stdout, figure titles, and the ``--out`` directory."""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import hysteresis
import oscillators
from analysis._json import to_json as encode
from analysis.cli._build import model_record
from analysis.cli._parsing import CliError
from analysis.experiments.models import describe_model

__all__ = [
    "announce_compilation",
    "emit",
    "figure_title",
    "prepare_out",
    "progress_enabled",
    "to_json",
]


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


def to_json(record: Any, indent: int | None = None) -> str:
    """JSON text of ``record`` (see :func:`analysis._json.to_json`): numpy values as Python
    numbers, paths as strings, non-finite floats as the strings ``"inf"``, ``"-inf"``,
    ``"nan"`` (strict JSON)."""
    return encode(record, indent=indent)


def write_record(out: Path, name: str, record: dict[str, Any]) -> None:
    """Write ``record`` as ``out/name`` (indented JSON) and note the file in ``record["json"]``."""
    path = out / name
    path.write_text(to_json(record, indent=2) + "\n")
    record["json"] = str(path)


def emit(args: argparse.Namespace, record: dict[str, Any], lines: Sequence[str]) -> None:
    """Print the record as one JSON object (``--json``) or the human-readable lines."""
    if args.json:
        sys.stdout.write(to_json(record) + "\n")
    else:
        for line in lines:
            print(line)


def figure_title(
    args: argparse.Namespace, what: str, model: dict[str, Any] | None = None, **extra: Any
) -> str:
    """``"<what>: <model and parameters>, C=..., zeta=..., Omega=..."`` for a figure title
    (``model``: the model record, default :func:`~analysis.cli._build.model_record` of the
    options)."""
    pairs: list[tuple[str, Any]] = []
    if getattr(args, "coupling", None) is not None and not isinstance(args.coupling, list):
        pairs.append(("C", float(args.coupling)))
    for symbol, name in (("ζ", "damping_ratio"), ("Ω", "frequency")):
        if getattr(args, name, None) is not None:  # commands without an oscillator omit them
            pairs.append((symbol, float(getattr(args, name))))
    pairs.extend(extra.items())
    record = model_record(args) if model is None else model
    return f"{what}: {describe_model(record, pairs)}"


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
