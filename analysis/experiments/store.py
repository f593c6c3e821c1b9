"""An embedded SQLite results file for long parameter sweeps and disorder ensembles.

Every finished task is written at once, in one transaction, under a stable key derived from its
parameters; a rerun skips what is stored. SQLite's transactions make the file safe when the
process is killed at any point: a task is either fully stored or absent, never half-written.

Layout (schema version 1)::

    tasks(key TEXT PRIMARY KEY, experiment, params JSON, results JSON, code_version,
          wall_time REAL, created TEXT)
    arrays(key, name, data BLOB, PRIMARY KEY (key, name))   -- numpy arrays as .npy bytes
    meta(name TEXT PRIMARY KEY, value TEXT)

Robustness: several processes may write one store at once (SQLite locking, ``BEGIN IMMEDIATE``
transactions and ``INSERT OR IGNORE``: no result is lost or duplicated, the first one wins). A
file that is not an intact results store (truncated, corrupted, another program's database)
is refused with :class:`StoreError` (a ``ValueError``) naming the file, before anything
is written to it. Each row records the code version that computed it;
:meth:`ResultStore.check_versions` refuses to mix versions unless told to.

Result dictionaries may hold JSON scalars, strings, lists, nested dicts and numpy arrays; the
arrays are stored losslessly (dtype, shape and every bit) as ``.npy`` bytes and referenced from
the JSON as ``{"__ndarray__": "<name>"}``.
"""

from __future__ import annotations

import datetime as _dt
import functools
import hashlib
import io
import json
import math
import os
import sqlite3
import subprocess
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "ResultStore",
    "StoredTask",
    "StoreError",
    "task_key",
    "canonical_json",
    "code_version",
]

SCHEMA_VERSION = "1"
_ARRAY_TAG = "__ndarray__"
_SQLITE_MAGIC = b"SQLite format 3\x00"


def _release(version: str) -> str:
    """A code version without the ``-dirty`` mark of its git description."""
    return version.replace("-dirty)", ")")


class StoreError(ValueError):
    """A results file that cannot be used: corrupted, truncated, not a store, or holding
    results of other code versions. The message names the file; the file is left untouched."""


def _check_store_file(path: Path) -> None:
    """Refuse, before SQLite opens it for writing, a file that is not an SQLite database."""
    if not path.exists():
        return
    if path.is_dir():
        raise StoreError(f"{path}: is a directory, not a results store")
    with open(path, "rb") as fh:
        head = fh.read(len(_SQLITE_MAGIC))
    if len(head) == 0:
        # nothing to lose, and another process may be creating this very store right now
        # (SQLite creates the file before it writes the header): a new store
        return
    if head != _SQLITE_MAGIC:
        raise StoreError(
            f"{path}: not a results store (no SQLite header: corrupted, truncated or another "
            "kind of file); it was left untouched"
        )


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
    return np.load(io.BytesIO(b), allow_pickle=False)


# ---------------------------------------------------------------------------------------------
# the store
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StoredTask:
    """One stored task: its parameters, results and provenance."""

    key: str
    experiment: str
    params: dict
    results: dict
    code_version: str
    wall_time: float | None
    created: str


class ResultStore:
    """Embedded SQLite results file (WAL mode): one row per finished task, never duplicated.

    Usage::

        store = ResultStore("results.sqlite")
        key = store.put("ensemble", {"spins": 100, "coupling": 4.0, "seed": 1}, {"d_ky": 1.4})
        store.has(key); store.get(key).results; store.load("ensemble")

    The connection is opened in the process that creates the object; workers of a pool or of
    a Dask cluster never write (``run_tasks`` writes from the parent/client process as results
    arrive): one writer, and workers on other machines need no shared filesystem.
    """

    def __init__(self, path: str | Path, timeout: float = 60.0) -> None:
        if not isinstance(path, str | os.PathLike):
            raise TypeError(f"path must be a str or path, got {type(path).__name__}")
        self.path = Path(path)
        if self.path.parent and not self.path.parent.exists():
            self.path.parent.mkdir(parents=True, exist_ok=True)
        _check_store_file(self.path)
        existed = self.path.exists()
        self._lock = threading.RLock()
        self._conn = sqlite3.connect(
            str(self.path), timeout=timeout, check_same_thread=False, isolation_level=None
        )
        try:
            with self._lock:
                if existed:
                    # read-only integrity check first: a damaged store is refused untouched
                    problems = self._conn.execute("PRAGMA quick_check").fetchall()
                    if problems != [("ok",)]:
                        raise StoreError(
                            f"{self.path}: corrupted results store ({problems[0][0]}); it was "
                            "left untouched"
                        )
                    tables = {
                        r[0]
                        for r in self._conn.execute(
                            "SELECT name FROM sqlite_master WHERE type = 'table'"
                        )
                    }
                    if tables and not {"meta", "tasks", "arrays"} <= tables:
                        raise StoreError(
                            f"{self.path}: an SQLite database that is not a results store "
                            f"(tables {sorted(tables)}); it was left untouched"
                        )
                self._conn.execute("PRAGMA journal_mode=WAL")
                # NORMAL is durable against a killed process (not power loss) in WAL mode
                self._conn.execute("PRAGMA synchronous=NORMAL")
                self._conn.execute("PRAGMA foreign_keys=ON")
                self._conn.execute("BEGIN IMMEDIATE")
                try:
                    self._create_schema()
                    self._conn.execute("COMMIT")
                except BaseException:
                    self._conn.execute("ROLLBACK")
                    raise
        except sqlite3.DatabaseError as exc:
            self._conn.close()
            raise StoreError(
                f"{self.path}: not a readable results store ({exc}); it was left untouched"
            ) from exc
        except BaseException:
            self._conn.close()
            raise

    def _create_schema(self) -> None:
        c = self._conn
        c.execute("CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY, value TEXT)")
        c.execute(
            "CREATE TABLE IF NOT EXISTS tasks (key TEXT PRIMARY KEY, experiment TEXT NOT NULL, "
            "params TEXT NOT NULL, results TEXT NOT NULL, code_version TEXT, wall_time REAL, "
            "created TEXT NOT NULL)"
        )
        c.execute("CREATE INDEX IF NOT EXISTS tasks_experiment ON tasks (experiment)")
        c.execute(
            "CREATE TABLE IF NOT EXISTS arrays (key TEXT NOT NULL REFERENCES tasks (key) "
            "ON DELETE CASCADE, name TEXT NOT NULL, data BLOB NOT NULL, PRIMARY KEY (key, name))"
        )
        row = c.execute("SELECT value FROM meta WHERE name = 'schema_version'").fetchone()
        if row is None:
            c.execute("INSERT INTO meta VALUES ('schema_version', ?)", (SCHEMA_VERSION,))
        elif row[0] != SCHEMA_VERSION:
            raise StoreError(
                f"{self.path}: results store schema {row[0]}, this code reads {SCHEMA_VERSION}"
            )

    # -- context manager / lifetime ----------------------------------------------------------

    def close(self) -> None:
        with self._lock:
            self._conn.close()

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"ResultStore({str(self.path)!r})"

    # -- writing -----------------------------------------------------------------------------

    def put(
        self,
        experiment: str,
        params: Mapping[str, Any],
        results: Mapping[str, Any],
        wall_time: float | None = None,
        key: str | None = None,
    ) -> str:
        """Store one finished task in one transaction (INSERT OR IGNORE) and return its key.

        A task whose key is already stored is left untouched (first result wins)."""
        if not isinstance(results, Mapping):
            raise TypeError(f"results must be a dict, got {type(results).__name__}")
        if key is None:
            key = task_key(experiment, params)
        params_json = json.dumps(_plain(params), sort_keys=True, allow_nan=True)
        arrays: dict[str, np.ndarray] = {}
        results_json = json.dumps(_encode_results(results, "", arrays), allow_nan=True)
        blobs = [(key, name, _array_to_bytes(a)) for name, a in arrays.items()]
        created = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="milliseconds")
        with self._lock:
            c = self._conn
            c.execute("BEGIN IMMEDIATE")
            try:
                cur = c.execute(
                    "INSERT OR IGNORE INTO tasks VALUES (?, ?, ?, ?, ?, ?, ?)",
                    (
                        key,
                        experiment,
                        params_json,
                        results_json,
                        code_version(),
                        None if wall_time is None else float(wall_time),
                        created,
                    ),
                )
                if cur.rowcount == 1 and blobs:
                    c.executemany("INSERT INTO arrays VALUES (?, ?, ?)", blobs)
                c.execute("COMMIT")
            except BaseException:
                c.execute("ROLLBACK")
                raise
        return key

    # -- versions ----------------------------------------------------------------------------

    def code_versions(self, experiment: str | None = None) -> list[str]:
        """Distinct code versions that computed the stored tasks (of one experiment or all)."""
        with self._lock:
            if experiment is None:
                rows = self._conn.execute("SELECT DISTINCT code_version FROM tasks").fetchall()
            else:
                rows = self._conn.execute(
                    "SELECT DISTINCT code_version FROM tasks WHERE experiment = ?", (experiment,)
                ).fetchall()
        return sorted(str(r[0]) for r in rows)

    def check_versions(self, experiment: str, allow_version_mismatch: bool = False) -> list[str]:
        """Refuse (:class:`StoreError`) to mix results of other code versions into
        ``experiment`` unless ``allow_version_mismatch``; returns the other versions found."""
        current = code_version()
        stored = self.code_versions(experiment)
        others = [v for v in stored if v != current]
        # a work-tree that is merely dirty on the same commit cannot be told apart from the
        # clean one by its version string: reported by the caller, not refused
        conflicting = [v for v in others if _release(v) != _release(current)]
        if conflicting and not allow_version_mismatch:
            raise StoreError(
                f"{self.path}: experiment {experiment!r} holds results computed by other code "
                f"versions {conflicting} (now {current!r}); refusing to mix them. Use a new store, "
                "or pass allow_version_mismatch=True to reuse them knowingly"
            )
        return others

    # -- reading -----------------------------------------------------------------------------

    def has(self, key: str) -> bool:
        with self._lock:
            row = self._conn.execute("SELECT 1 FROM tasks WHERE key = ?", (key,)).fetchone()
        return row is not None

    __contains__ = has

    def __len__(self) -> int:
        with self._lock:
            return int(self._conn.execute("SELECT COUNT(*) FROM tasks").fetchone()[0])

    def experiments(self) -> list[str]:
        with self._lock:
            rows = self._conn.execute(
                "SELECT DISTINCT experiment FROM tasks ORDER BY experiment"
            ).fetchall()
        return [r[0] for r in rows]

    def keys(self, experiment: str | None = None) -> list[str]:
        """Keys in insertion order, of one experiment or of all."""
        with self._lock:
            if experiment is None:
                rows = self._conn.execute("SELECT key FROM tasks ORDER BY rowid").fetchall()
            else:
                rows = self._conn.execute(
                    "SELECT key FROM tasks WHERE experiment = ? ORDER BY rowid", (experiment,)
                ).fetchall()
        return [r[0] for r in rows]

    def _arrays_of(self, key: str) -> dict[str, np.ndarray]:
        rows = self._conn.execute("SELECT name, data FROM arrays WHERE key = ?", (key,)).fetchall()
        return {name: _array_from_bytes(data) for name, data in rows}

    def _task_from_row(self, row: tuple) -> StoredTask:
        key, experiment, params, results, version, wall, created = row
        return StoredTask(
            key=key,
            experiment=experiment,
            params=json.loads(params),
            results=_decode_results(json.loads(results), self._arrays_of(key)),
            code_version=version,
            wall_time=wall,
            created=created,
        )

    def get(self, key: str) -> StoredTask:
        """The stored task with this key; ``KeyError`` if absent."""
        with self._lock:
            row = self._conn.execute("SELECT * FROM tasks WHERE key = ?", (key,)).fetchone()
            if row is None:
                raise KeyError(key)
            return self._task_from_row(row)

    def tasks(self, experiment: str) -> list[StoredTask]:
        """Every stored task of an experiment, in insertion order."""
        with self._lock:
            rows = self._conn.execute(
                "SELECT * FROM tasks WHERE experiment = ? ORDER BY rowid", (experiment,)
            ).fetchall()
            return [self._task_from_row(r) for r in rows]

    def load(self, experiment: str) -> list[tuple[dict, dict]]:
        """``[(params, results), ...]`` of an experiment, in insertion order."""
        return [(t.params, t.results) for t in self.tasks(experiment)]

    def table(
        self,
        experiment: str,
        fields: Iterable[str] | None = None,
        where: Mapping[str, Any] | None = None,
    ) -> dict[str, np.ndarray]:
        """Columns of an experiment as numpy arrays: one per parameter and per result field.

        ``fields`` selects result fields (default: all scalar-or-array fields present in every
        task). A field whose values are arrays of one common shape is stacked into an array
        with a leading task axis; otherwise an object array is returned. ``where`` keeps only
        tasks whose parameters equal the given values (integral floats match ints).
        """
        tasks = self.tasks(experiment)
        if where:
            want = {k: _canonical_numbers(_plain(v)) for k, v in where.items()}
            tasks = [
                t
                for t in tasks
                if all(_canonical_numbers(t.params.get(k)) == v for k, v in want.items())
            ]
        if not tasks:
            return {}
        param_names = sorted(set().union(*(t.params for t in tasks)))
        if fields is None:
            common = set(tasks[0].results)
            for t in tasks[1:]:
                common &= set(t.results)
            fields = sorted(f for f in common if not isinstance(tasks[0].results[f], dict))
        out: dict[str, np.ndarray] = {}
        for name in param_names:
            out[name] = _column([t.params.get(name) for t in tasks])
        for name in fields:
            if name in out:
                raise ValueError(f"result field {name!r} clashes with a parameter name")
            try:
                out[name] = _column([t.results[name] for t in tasks])
            except KeyError:
                raise KeyError(f"result field {name!r} missing in some tasks") from None
        return out


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
