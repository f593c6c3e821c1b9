"""The results store's file format, without the file: stable task keys, the code version, the
lossless encoding of result dictionaries (JSON plus ``.npy`` array bytes) and the checksum that
seals every stored task. :mod:`analysis.experiments.store` holds the SQLite file itself."""

from __future__ import annotations

import functools
import hashlib
import io
import json
import math
import struct
import subprocess
from collections.abc import Iterable, Mapping, Sequence
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["task_key", "canonical_json", "code_version", "task_checksum"]

_ARRAY_TAG = "__ndarray__"


def _release(version: str) -> str:
    """A code version without the ``-dirty`` mark of its git description."""
    return version.replace("-dirty)", ")")


# ---------------------------------------------------------------------------------------------
# keys
# ---------------------------------------------------------------------------------------------


def _plain(value: Any, where: str = "params") -> Any:
    """JSON-ready copy of a parameter value (numpy scalars/arrays -> Python, tuples -> lists)."""
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise TypeError(f"{where}: keys must be strings, got {k!r}")
            out[k] = _plain(v, f"{where}.{k}")
        return out
    if isinstance(value, list | tuple):
        return [_plain(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist(), where)
    if isinstance(value, np.generic):
        return value.item()
    if value is None or isinstance(value, bool | int | float | str):
        return value
    raise TypeError(f"{where}: {type(value).__name__} is not JSON-serialisable")


def _canonical_numbers(value: Any) -> Any:
    """Integral floats become ints so that ``coupling=4`` and ``coupling=4.0`` share a key."""
    if isinstance(value, dict):
        return {k: _canonical_numbers(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_canonical_numbers(v) for v in value]
    if isinstance(value, float) and math.isfinite(value) and value.is_integer():
        return int(value)
    return value


def canonical_json(params: Mapping[str, Any]) -> str:
    """Canonical JSON of task parameters: sorted keys, no spaces, numpy types converted,
    integral floats written as integers. Equal parameter sets give equal strings."""
    return json.dumps(
        _canonical_numbers(_plain(params)), sort_keys=True, separators=(",", ":"), allow_nan=True
    )


def task_key(experiment: str, params: Mapping[str, Any]) -> str:
    """Stable key of one task: sha256 of the canonical JSON of ``{experiment, params}``.

    The seed is one of the parameters, so two realizations of the same point differ.
    """
    if not isinstance(experiment, str) or not experiment:
        raise ValueError("experiment must be a non-empty string")
    payload = canonical_json({"experiment": experiment, "params": dict(params)})
    return hashlib.sha256(payload.encode("utf-8")).hexdigest()


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """``hysteresis-toolkit <version>`` plus ``git describe --always --dirty`` when available."""

    try:
        ver = version("hysteresis-toolkit")
    except PackageNotFoundError:
        ver = "0+unknown"
    text = f"hysteresis-toolkit {ver}"
    try:
        here = Path(__file__).resolve().parent
        out = subprocess.run(
            ["git", "describe", "--always", "--dirty", "--tags"],
            cwd=here,
            capture_output=True,
            text=True,
            timeout=5,
            check=False,
        )
        if out.returncode == 0 and out.stdout.strip():
            text += f" (git {out.stdout.strip()})"
    except (OSError, subprocess.SubprocessError):
        pass
    return text


# ---------------------------------------------------------------------------------------------
# results encoding
# ---------------------------------------------------------------------------------------------


def _encode_results(value: Any, path: str, arrays: dict[str, np.ndarray]) -> Any:
    if isinstance(value, np.ndarray):
        if value.dtype == object:
            raise TypeError(f"results{path}: object arrays cannot be stored losslessly")
        name = path or "/"
        arrays[name] = value
        return {_ARRAY_TAG: name}
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise TypeError(f"results{path}: keys must be strings, got {k!r}")
            if k == _ARRAY_TAG:
                raise ValueError(f"results{path}: the key {_ARRAY_TAG!r} is reserved")
            out[k] = _encode_results(v, f"{path}/{k}", arrays)
        return out
    if isinstance(value, list | tuple):
        return [_encode_results(v, f"{path}/{i}", arrays) for i, v in enumerate(value)]
    if isinstance(value, np.generic):
        return value.item()
    if value is None or isinstance(value, bool | int | float | str):
        return value
    raise TypeError(f"results{path}: {type(value).__name__} cannot be stored")


def _decode_results(value: Any, arrays: Mapping[str, np.ndarray]) -> Any:
    if isinstance(value, dict):
        if len(value) == 1 and _ARRAY_TAG in value:
            return arrays[value[_ARRAY_TAG]]
        return {k: _decode_results(v, arrays) for k, v in value.items()}
    if isinstance(value, list):
        return [_decode_results(v, arrays) for v in value]
    return value


def _array_to_bytes(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, a, allow_pickle=False)
    return buf.getvalue()


def _array_from_bytes(b: bytes) -> np.ndarray:
    """The array of ``.npy`` bytes; ``ValueError`` (in our words) when they are not an intact
    plain array: numpy's own message about a damaged header advises loading pickles."""
    if not isinstance(b, bytes):
        raise ValueError(f"an array stored as {type(b).__name__}, not .npy bytes")
    try:
        buf = io.BytesIO(b)
        a = np.load(buf, allow_pickle=False)
    except Exception:  # noqa: BLE001 - any failure of the parser is damage of the bytes
        raise ValueError("array bytes that are not an intact .npy array") from None
    if not isinstance(a, np.ndarray) or buf.tell() != len(b):
        raise ValueError("array bytes that are not one intact .npy array")
    return a


def _field_bytes(value: Any) -> bytes:
    """One field of a stored row, typed and length-prefixed (no two rows encode alike)."""
    if value is None:
        return b"n"
    if isinstance(value, bytes):
        return b"b" + len(value).to_bytes(8, "little") + value
    if isinstance(value, str):
        data = value.encode("utf-8", "surrogatepass")
        return b"s" + len(data).to_bytes(8, "little") + data
    if isinstance(value, float | int) and not isinstance(value, bool):
        return b"f" + struct.pack("<d", float(value))
    raise TypeError(f"a stored field cannot be a {type(value).__name__}")


def task_checksum(fields: Sequence[Any], blobs: Iterable[tuple[str, bytes]]) -> str:
    """SHA-256 of one stored task exactly as it lies in the file: its row fields (key,
    experiment, params and results JSON, code version, wall time, creation time) and its
    arrays' names and ``.npy`` bytes, in name order. Computed at write, compared at read."""
    h = hashlib.sha256(b"hysteresis-toolkit stored task\x00")
    for value in fields:
        h.update(_field_bytes(value))
    for name, data in sorted(blobs, key=lambda nb: str(nb[0])):
        h.update(_field_bytes(name) + _field_bytes(data))
    return h.hexdigest()


def _column(values: list) -> np.ndarray:
    """Stack values into an array when they share a shape, else an object array."""
    try:
        arrs = [np.asarray(v) for v in values]
        if all(a.shape == arrs[0].shape for a in arrs) and all(a.dtype != object for a in arrs):
            return np.stack(arrs)
    except (ValueError, TypeError):
        pass
    col = np.empty(len(values), dtype=object)
    for i, v in enumerate(values):
        col[i] = v
    return col
