"""An embedded SQLite results file for long parameter sweeps and disorder ensembles.

Every finished task is written at once, in one transaction, under a stable key derived from its
parameters; a rerun skips what is stored. SQLite's transactions make the file safe when the
process is killed at any point: a task is either fully stored or absent, never half-written.

The store is one self-contained file after every commit: it uses SQLite's rollback journal
(``journal_mode=DELETE``), not a write-ahead log, so a committed task is in the ``.sqlite`` file
itself, and a copy of that file alone holds every finished task (only while a write is under way
does a ``-journal`` file lie beside it; a copy must not be taken then). A store written in WAL
mode by an earlier version is folded into its file when it is first opened writable.

Layout (schema version 2)::

    tasks(key TEXT PRIMARY KEY, experiment, params JSON, results JSON, code_version,
          wall_time REAL, created TEXT, checksum TEXT)
    arrays(key, name, data BLOB, PRIMARY KEY (key, name))   -- numpy arrays as .npy bytes
    meta(name TEXT PRIMARY KEY, value TEXT)

Every task carries the SHA-256 of its stored bytes (row and arrays, computed when written); a
task whose bytes changed since is reported as damaged (:class:`StoreError` naming the task) when
read, never returned. Schema-1 stores (no checksums) are migrated when opened writable: the
column is added and their old tasks stay *unverified* (their bytes were never sealed, and
sealing them now would bless whatever they hold); every task written afterwards is sealed.

Robustness: several processes may write one store at once (SQLite locking, ``BEGIN IMMEDIATE``
transactions and ``INSERT OR IGNORE``: no result is lost or duplicated, the first one wins). A
file that is not an intact results store (truncated, corrupted, another program's database)
is refused with :class:`StoreError` (a ``ValueError``) naming the file, before anything
is written to it. A write that fails (disk full, file-size limit, I/O error) raises a
:class:`StoreError` naming that cause; what was stored before is intact. A store on read-only
media (or opened with ``read_only=True``) is read without writing anything. Each row records
the code version that computed it; :meth:`ResultStore.check_versions` refuses to mix versions
unless told to.

Result dictionaries may hold JSON scalars, strings, lists, nested dicts and numpy arrays; the
arrays are stored losslessly (dtype, shape and every bit) as ``.npy`` bytes and referenced from
the JSON as ``{"__ndarray__": "<name>"}``.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import sqlite3
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from analysis.experiments.store_format import (
    _array_from_bytes,
    _array_to_bytes,
    _canonical_numbers,
    _column,
    _decode_results,
    _encode_results,
    _plain,
    _release,
    canonical_json,
    code_version,
    task_checksum,
    task_key,
)

__all__ = [
    "ResultStore",
    "StoredTask",
    "StoreError",
    "task_key",
    "canonical_json",
    "code_version",
]

SCHEMA_VERSION = "2"
_READABLE_SCHEMAS = ("1", "2")  # 1: before checksums (migrated when opened writable)
_SQLITE_MAGIC = b"SQLite format 3\x00"
_COLUMNS = "key, experiment, params, results, code_version, wall_time, created"


class StoreError(ValueError):
    """A results file that cannot be used: corrupted, truncated, not a store, a stored task
    whose bytes changed, results of other code versions, or a write that failed (disk full,
    file-size limit, read-only). The message names the file and the cause in one line."""


def _writable(path: Path) -> bool:
    """Whether this process may write ``path`` (a file or a directory)."""
    return os.access(path, os.W_OK)


# SQLite's primary result codes of a write that failed for a reason outside the store
_WRITE_CAUSES = {
    "SQLITE_FULL": "disk full or file-size limit reached",
    "SQLITE_IOERR": "input/output error (disk full, file-size limit or a failing disk)",
    "SQLITE_READONLY": "the file or its directory is read-only",
    "SQLITE_CANTOPEN": "its journal file cannot be created (is the directory writable?)",
    "SQLITE_BUSY": "another process held it locked for longer than the timeout",
    "SQLITE_LOCKED": "another process held it locked for longer than the timeout",
}


def _sqlite_text(exc: sqlite3.Error) -> str:
    """SQLite's own words for an error, with its extended code (``SQLITE_IOERR_WRITE: ...``)."""
    name = getattr(exc, "sqlite_errorname", None)
    return f"{name}: {exc}" if name else str(exc)


def _write_cause(exc: sqlite3.Error) -> str | None:
    """The cause, in words, of an SQLite error that is a failed write, else ``None``."""
    name = getattr(exc, "sqlite_errorname", "") or ""
    for prefix, cause in _WRITE_CAUSES.items():
        if name == prefix or name.startswith(prefix + "_"):
            return cause
    text = str(exc).lower()
    if "disk is full" in text:
        return _WRITE_CAUSES["SQLITE_FULL"]
    if "disk i/o error" in text:
        return _WRITE_CAUSES["SQLITE_IOERR"]
    return None


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
    """Embedded SQLite results file (rollback journal): one row per finished task, never
    duplicated, each sealed by a checksum.

    Usage::

        store = ResultStore("results.sqlite")
        key = store.put("ensemble", {"spins": 100, "coupling": 4.0, "seed": 1}, {"d_ky": 1.4})
        store.has(key); store.get(key).results; store.load("ensemble")

    ``read_only``: ``None`` (default) opens an existing store read-only when this process may
    not write the file or its directory (read-only media), else writable; ``True`` always
    read-only (nothing is written, not even a journal); ``False`` always writable.

    The connection is opened in the process that creates the object; workers of a pool or of
    a Dask cluster never write (``run_tasks`` writes from the parent/client process as results
    arrive): one writer, and workers on other machines need no shared filesystem.
    """

    def __init__(
        self, path: str | Path, timeout: float = 60.0, read_only: bool | None = None
    ) -> None:
        if not isinstance(path, str | os.PathLike):
            raise TypeError(f"path must be a str or path, got {type(path).__name__}")
        self.path = Path(path)
        if read_only is None:
            read_only = self.path.is_file() and not (
                _writable(self.path) and _writable(self.path.absolute().parent)
            )
        self.read_only = bool(read_only)
        if self.read_only and not self.path.exists():
            raise StoreError(f"{self.path}: no such results store to open read-only")
        if not self.read_only and self.path.parent and not self.path.parent.exists():
            self.path.parent.mkdir(parents=True, exist_ok=True)
        _check_store_file(self.path)
        existed = self.path.exists()
        self._lock = threading.RLock()
        self._unverified_through = 0  # tasks up to this rowid predate checksums
        self._checksums = True
        try:
            self._conn = self._connect(timeout)
        except sqlite3.Error as exc:
            raise StoreError(f"{self.path}: cannot be opened ({exc})") from exc
        self._conn.text_factory = self._text
        try:
            with self._lock:
                if existed:
                    self._check_intact()
                if self.read_only:
                    self._read_schema()
                else:
                    self._open_for_writing()
        except sqlite3.Error as exc:
            self._conn.close()
            cause = _write_cause(exc)
            if cause is not None:
                raise StoreError(
                    f"{self.path}: the results store could not be written: {cause} "
                    f"({_sqlite_text(exc)})"
                ) from exc
            raise StoreError(
                f"{self.path}: not a readable results store ({exc}); it was left untouched"
            ) from exc
        except UnicodeDecodeError as exc:  # SQLite's own message quotes the damaged bytes
            self._conn.close()
            raise StoreError(
                f"{self.path}: corrupted results store (bytes that are not UTF-8 text in its "
                "schema); it was left untouched"
            ) from exc
        except BaseException:
            self._conn.close()
            raise

    def _text(self, raw: bytes) -> str:
        """The connection's text factory: UTF-8, and bytes that are not (random bytes written
        into a stored text pass SQLite's page checks) a one-line error naming the file."""
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError:
            raise StoreError(
                f"{self.path}: corrupted results store (a stored text is not UTF-8: "
                f"{raw[:40]!r}); restore it from a copy"
            ) from None

    def _connect(self, timeout: float) -> sqlite3.Connection:
        if not self.read_only:
            return sqlite3.connect(
                str(self.path), timeout=timeout, check_same_thread=False, isolation_level=None
            )
        for side, why in (
            ("-wal", "tasks in a write-ahead log"),
            ("-journal", "an interrupted write to roll back"),
        ):
            extra = self.path.with_name(self.path.name + side)
            if extra.exists() and extra.stat().st_size > 0:
                raise StoreError(
                    f"{self.path}: opened read-only but holds {why} ({extra.name}), which only "
                    "a writable opening can fold in; open it once where it can be written"
                )
        uri = f"file:{quote(str(self.path.absolute()))}?mode=ro"
        if not _writable(self.path.absolute().parent):
            # no process can write a store whose directory is read-only (a write needs a
            # journal beside it), so SQLite may read it without any locking files
            uri += "&immutable=1"
        return sqlite3.connect(
            uri, uri=True, timeout=timeout, check_same_thread=False, isolation_level=None
        )

    def _check_intact(self) -> None:
        """Read-only integrity check first: a damaged or foreign file is refused untouched."""
        problems = self._conn.execute("PRAGMA quick_check").fetchall()
        if problems != [("ok",)]:
            raise StoreError(
                f"{self.path}: corrupted results store ({problems[0][0]}); it was left untouched"
            )
        tables = {
            r[0] for r in self._conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")
        }
        if (tables or self.read_only) and not {"meta", "tasks", "arrays"} <= tables:
            raise StoreError(
                f"{self.path}: an SQLite database that is not a results store "
                f"(tables {sorted(tables)}); it was left untouched"
            )

    def _open_for_writing(self) -> None:
        c = self._conn
        # a rollback journal, not WAL: every commit lands in the .sqlite file itself, so the
        # file alone is the whole store (and read-only media need no -shm/-wal files)
        mode = c.execute("PRAGMA journal_mode=DELETE").fetchone()[0]
        if str(mode).lower() != "delete":
            raise StoreError(
                f"{self.path}: cannot leave journal mode {mode!r} (another process of an older "
                "version has it open?); close that process and retry"
            )
        # NORMAL: a killed process never loses a commit; only a power cut at the wrong moment
        # might (FULL would sync the directory too, at a cost per task)
        c.execute("PRAGMA synchronous=NORMAL")
        c.execute("PRAGMA foreign_keys=ON")
        c.execute("BEGIN IMMEDIATE")
        try:
            self._create_schema()
            c.execute("COMMIT")
        except BaseException:
            if c.in_transaction:
                c.execute("ROLLBACK")
            raise

    def _read_schema(self) -> None:
        """Schema version and checksum state of a store opened read-only."""
        row = self._conn.execute("SELECT value FROM meta WHERE name = 'schema_version'").fetchone()
        stored = None if row is None else row[0]
        if stored not in _READABLE_SCHEMAS:
            raise StoreError(
                f"{self.path}: results store schema {stored}, this code reads "
                f"{', '.join(_READABLE_SCHEMAS)}"
            )
        self._load_checksum_state()

    def _load_checksum_state(self) -> None:
        c = self._conn
        self._checksums = any(r[1] == "checksum" for r in c.execute("PRAGMA table_info(tasks)"))
        if not self._checksums:
            self._unverified_through = -1  # every task: read-only schema-1 store
            return
        row = c.execute("SELECT value FROM meta WHERE name = 'unverified_through'").fetchone()
        self._unverified_through = 0 if row is None else int(row[0])

    def _create_schema(self) -> None:
        c = self._conn
        c.execute("CREATE TABLE IF NOT EXISTS meta (name TEXT PRIMARY KEY, value TEXT)")
        c.execute(
            "CREATE TABLE IF NOT EXISTS tasks (key TEXT PRIMARY KEY, experiment TEXT NOT NULL, "
            "params TEXT NOT NULL, results TEXT NOT NULL, code_version TEXT, wall_time REAL, "
            "created TEXT NOT NULL, checksum TEXT)"
        )
        c.execute("CREATE INDEX IF NOT EXISTS tasks_experiment ON tasks (experiment)")
        c.execute(
            "CREATE TABLE IF NOT EXISTS arrays (key TEXT NOT NULL REFERENCES tasks (key) "
            "ON DELETE CASCADE, name TEXT NOT NULL, data BLOB NOT NULL, PRIMARY KEY (key, name))"
        )
        row = c.execute("SELECT value FROM meta WHERE name = 'schema_version'").fetchone()
        if row is None:
            c.execute("INSERT INTO meta VALUES ('schema_version', ?)", (SCHEMA_VERSION,))
        elif row[0] == "1":
            # schema 1 had no checksums: its tasks stay unverified, every later one is sealed
            columns = {r[1] for r in c.execute("PRAGMA table_info(tasks)")}
            if "checksum" not in columns:
                c.execute("ALTER TABLE tasks ADD COLUMN checksum TEXT")
            last = c.execute("SELECT COALESCE(MAX(rowid), 0) FROM tasks").fetchone()[0]
            c.execute("INSERT OR REPLACE INTO meta VALUES ('unverified_through', ?)", (str(last),))
            c.execute("UPDATE meta SET value = ? WHERE name = 'schema_version'", (SCHEMA_VERSION,))
        elif row[0] != SCHEMA_VERSION:
            raise StoreError(
                f"{self.path}: results store schema {row[0]}, this code reads {SCHEMA_VERSION}"
            )
        self._load_checksum_state()

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

        A task whose key is already stored is left untouched (first result wins). A failed
        write raises :class:`StoreError` naming its cause (disk full, ...); nothing of the
        task is stored then, and what was stored before is intact."""
        if not isinstance(results, Mapping):
            raise TypeError(f"results must be a dict, got {type(results).__name__}")
        if key is None:
            key = task_key(experiment, params)
        if self.read_only:
            raise StoreError(f"{self.path}: opened read-only; task {key} was not stored")
        params_json = json.dumps(_plain(params), sort_keys=True, allow_nan=True)
        arrays: dict[str, np.ndarray] = {}
        results_json = json.dumps(_encode_results(results, "", arrays), allow_nan=True)
        blobs = [(key, name, _array_to_bytes(a)) for name, a in arrays.items()]
        created = _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="milliseconds")
        fields = (
            key,
            experiment,
            params_json,
            results_json,
            code_version(),
            None if wall_time is None else float(wall_time),
            created,
        )
        checksum = task_checksum(fields, [(name, data) for _, name, data in blobs])
        with self._lock:
            c = self._conn
            try:
                c.execute("BEGIN IMMEDIATE")
                cur = c.execute(
                    "INSERT OR IGNORE INTO tasks VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                    (*fields, checksum),
                )
                if cur.rowcount == 1 and blobs:
                    c.executemany("INSERT INTO arrays VALUES (?, ?, ?)", blobs)
                c.execute("COMMIT")
            except BaseException as exc:
                # SQLite itself rolls back after some failures (disk full): then there is no
                # transaction left, and a ROLLBACK would hide the cause behind its own error
                if c.in_transaction:
                    try:
                        c.execute("ROLLBACK")
                    except sqlite3.Error:
                        pass
                cause = _write_cause(exc) if isinstance(exc, sqlite3.Error) else None
                if cause is not None:
                    raise StoreError(
                        f"{self.path}: the results store could not be written: {cause} "
                        f"({_sqlite_text(exc)}); "
                        f"task {key} was not stored, the tasks stored before are intact"
                    ) from exc
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

    def _select(self) -> str:
        checksum = "checksum" if self._checksums else "NULL"
        return f"SELECT rowid, {_COLUMNS}, {checksum} FROM tasks"

    def _task_from_row(self, row: tuple) -> StoredTask:
        """The task of a row, after checking its bytes against the checksum it was sealed with."""
        rowid, key, experiment, params, results, version, wall, created, checksum = row
        blobs = self._conn.execute(
            "SELECT name, data FROM arrays WHERE key = ? ORDER BY name", (key,)
        ).fetchall()

        def damaged(why: str) -> StoreError:
            return StoreError(
                f"{self.path}: stored task {key} of experiment {experiment!r} is damaged "
                f"({why}); its result is not used: recompute it in a new store"
            )

        if checksum is None:
            if self._unverified_through >= 0 and rowid > self._unverified_through:
                raise damaged("its checksum is missing")
        elif checksum != task_checksum(row[1:8], blobs):
            raise damaged("its stored bytes differ from the checksum written with them")
        try:
            arrays = {name: _array_from_bytes(data) for name, data in blobs}
            decoded = _decode_results(json.loads(results), arrays)
            params_dict = json.loads(params)
        except (ValueError, TypeError, KeyError) as exc:
            raise damaged(f"unreadable: {exc}") from None
        return StoredTask(
            key=key,
            experiment=experiment,
            params=params_dict,
            results=decoded,
            code_version=version,
            wall_time=wall,
            created=created,
        )

    def get(self, key: str) -> StoredTask:
        """The stored task with this key; ``KeyError`` if absent, :class:`StoreError` if its
        stored bytes were damaged."""
        with self._lock:
            row = self._conn.execute(f"{self._select()} WHERE key = ?", (key,)).fetchone()
            if row is None:
                raise KeyError(key)
            return self._task_from_row(row)

    def tasks(self, experiment: str) -> list[StoredTask]:
        """Every stored task of an experiment, in insertion order (damage raises)."""
        with self._lock:
            rows = self._conn.execute(
                f"{self._select()} WHERE experiment = ? ORDER BY rowid", (experiment,)
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
