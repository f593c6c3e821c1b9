"""Stored results that never lie: checksums of every stored task, damaged arrays reported in our
own words, schema-1 stores still opened, a full disk named as such, read-only media read."""

from __future__ import annotations

import io
import os
import shutil
import sqlite3
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from support_paths import ROOT

import analysis.experiments.store as store_module
from analysis.experiments.execution import run_tasks
from analysis.experiments.store import ResultStore, StoreError, task_key


def _npy(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, a, allow_pickle=False)
    return buf.getvalue()


def _three(path: Path) -> list[str]:
    with ResultStore(path) as store:
        return [
            store.put("e", {"i": i}, {"d": 1.25 + i, "v": np.arange(4.0) * i}) for i in range(3)
        ]


def _assert_damage(info: pytest.ExceptionInfo, key: str) -> None:
    msg = str(info.value)
    assert "\n" not in msg and "damaged" in msg and key in msg, msg
    assert "pickle" not in msg.lower(), msg


def test_one_changed_digit_in_a_stored_result_is_damage_not_a_value(tmp_path):
    path = tmp_path / "s.sqlite"
    keys = _three(path)
    with sqlite3.connect(path) as con:
        (results,) = con.execute("SELECT results FROM tasks WHERE key = ?", (keys[1],)).fetchone()
        assert "2.25" in results
        con.execute(
            "UPDATE tasks SET results = ? WHERE key = ?",
            (results.replace("2.25", "2.26"), keys[1]),
        )
    with ResultStore(path) as store:
        assert store.get(keys[0]).results["d"] == 1.25  # the intact tasks still read
        for read in (lambda: store.get(keys[1]), lambda: store.load("e"), lambda: store.table("e")):
            with pytest.raises(StoreError) as info:
                read()
            _assert_damage(info, keys[1])


@pytest.mark.parametrize("where", ["data", "header"])
def test_one_changed_byte_in_a_stored_array_is_damage(tmp_path, where):
    path = tmp_path / "s.sqlite"
    keys = _three(path)
    with sqlite3.connect(path) as con:
        (data,) = con.execute("SELECT data FROM arrays WHERE key = ?", (keys[2],)).fetchone()
        if where == "data":
            data = data[:-1] + bytes([data[-1] ^ 1])  # one bit of the last float
        else:
            data = data.replace(b"<f8", b"|O8")  # numpy would advise allow_pickle=True here
        con.execute("UPDATE arrays SET data = ? WHERE key = ?", (data, keys[2]))
    with ResultStore(path) as store, pytest.raises(StoreError) as info:
        store.load("e")
    _assert_damage(info, keys[2])


def test_removed_checksum_of_a_sealed_task_is_damage(tmp_path):
    path = tmp_path / "s.sqlite"
    keys = _three(path)
    with sqlite3.connect(path) as con:
        con.execute("UPDATE tasks SET checksum = NULL WHERE key = ?", (keys[0],))
    with ResultStore(path) as store, pytest.raises(StoreError, match="checksum is missing"):
        store.get(keys[0])


def _schema1_store(path: Path) -> list[str]:
    """A store as the previous version wrote it: schema 1, WAL mode, no checksum column."""
    con = sqlite3.connect(path, isolation_level=None)
    con.execute("PRAGMA journal_mode=WAL")
    con.execute("CREATE TABLE meta (name TEXT PRIMARY KEY, value TEXT)")
    con.execute(
        "CREATE TABLE tasks (key TEXT PRIMARY KEY, experiment TEXT NOT NULL, params TEXT NOT "
        "NULL, results TEXT NOT NULL, code_version TEXT, wall_time REAL, created TEXT NOT NULL)"
    )
    con.execute(
        "CREATE TABLE arrays (key TEXT NOT NULL REFERENCES tasks (key) ON DELETE CASCADE, "
        "name TEXT NOT NULL, data BLOB NOT NULL, PRIMARY KEY (key, name))"
    )
    con.execute("INSERT INTO meta VALUES ('schema_version', '1')")
    keys = []
    for i in range(2):
        key = task_key("e", {"i": i})
        con.execute(
            "INSERT INTO tasks VALUES (?, 'e', ?, ?, ?, 0.5, '2026-01-01T00:00:00.000+00:00')",
            (key, f'{{"i": {i}}}', '{"v": {"__ndarray__": "/v"}}', store_module.code_version()),
        )
        con.execute("INSERT INTO arrays VALUES (?, '/v', ?)", (key, _npy(np.arange(3.0) + i)))
        keys.append(key)
    con.close()
    return keys


def test_schema1_store_opens_its_tasks_unverified_and_new_ones_sealed(tmp_path):
    path = tmp_path / "old.sqlite"
    keys = _schema1_store(path)
    with ResultStore(path) as store:
        for i, key in enumerate(keys):
            np.testing.assert_array_equal(store.get(key).results["v"], np.arange(3.0) + i)
        new = store.put("e", {"i": 2}, {"v": np.arange(3.0) + 2})
    with sqlite3.connect(path) as con:
        rows = dict(con.execute("SELECT key, checksum FROM tasks"))
        meta = dict(con.execute("SELECT name, value FROM meta"))
        assert con.execute("PRAGMA journal_mode").fetchone()[0] == "delete"
    assert rows[keys[0]] is None and rows[keys[1]] is None  # old tasks: unverified
    assert rows[new] is not None and len(rows[new]) == 64  # new tasks: sealed
    assert meta["schema_version"] == "2" and meta["unverified_through"] == "2"
    # an unverified task's damaged array is still reported in our words, not numpy's
    with sqlite3.connect(path) as con:
        (data,) = con.execute("SELECT data FROM arrays WHERE key = ?", (keys[1],)).fetchone()
        con.execute(
            "UPDATE arrays SET data = ? WHERE key = ?", (data.replace(b"<f8", b"|O8"), keys[1])
        )
    with ResultStore(path) as store, pytest.raises(StoreError) as info:
        store.get(keys[1])
    _assert_damage(info, keys[1])


DISK_FULL = textwrap.dedent(
    """
    import os, resource, signal, sys
    import numpy as np
    from analysis.experiments.store import ResultStore, StoreError
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails with EFBIG instead
    path = sys.argv[1]
    store = ResultStore(path)
    store.put("e", {"i": 0}, {"v": np.zeros(2000)})
    limit = os.path.getsize(path) + 64 * 1024
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))
    for i in range(1, 100):
        try:
            store.put("e", {"i": i}, {"v": np.full(2000, float(i))})
        except StoreError as exc:
            print(i, exc, sep="|")
            break
    """
)


def test_full_disk_is_reported_as_such_and_stored_tasks_stay(tmp_path):
    path = tmp_path / "full.sqlite"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run(
        [sys.executable, "-c", DISK_FULL, str(path)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    failed_at, message = out.stdout.strip().split("|", 1)
    failed_at = int(failed_at)
    assert "\n" not in message and "could not be written" in message, message
    assert "disk full" in message and "file-size limit" in message, message
    assert "rollback" not in message and "no transaction" not in message, message
    assert 2 <= failed_at < 99  # some tasks fit under the limit, then one did not
    with ResultStore(path) as store:  # every task stored before is there, intact
        assert store.keys("e") == [task_key("e", {"i": i}) for i in range(failed_at)]
        for i in range(1, failed_at):
            np.testing.assert_array_equal(
                store.get(task_key("e", {"i": i})).results["v"], np.full(2000, float(i))
            )


def _never_called(i):
    raise AssertionError("a complete store needs no computation")


def test_complete_store_on_read_only_media_is_read_and_aggregated(tmp_path, monkeypatch):
    made = tmp_path / "made" / "s.sqlite"
    made.parent.mkdir()
    tasks = [{"i": i} for i in range(3)]
    expected = run_tasks("agg", tasks, _square, store=made, workers=1, progress=False)
    media = tmp_path / "media"
    media.mkdir()
    path = media / "s.sqlite"
    shutil.copyfile(made, path)
    before = path.read_bytes()
    path.chmod(0o444)
    media.chmod(0o555)
    try:
        if os.access(path, os.W_OK):
            # running as root: permissions do not bind, so let the store see the mode bits
            # (it then opens the file with mode=ro and immutable=1, which do bind)
            monkeypatch.setattr(
                store_module, "_writable", lambda p: bool(os.stat(p).st_mode & 2**7)
            )
        with ResultStore(path) as store:
            assert store.read_only
            assert [r for _, r in store.load("agg")] == expected
            with pytest.raises(StoreError, match="read-only"):
                store.put("agg", {"i": 9}, {"y": 81})
        got = run_tasks("agg", tasks, _never_called, store=path, workers=1, progress=False)
        assert got == expected
        more = [*tasks, {"i": 3}]  # a task missing: refused before anything is computed
        with pytest.raises(StoreError, match="1 of 4 tasks are not stored"):
            run_tasks("agg", more, _never_called, store=path, workers=1, progress=False)
    finally:
        media.chmod(0o755)
        path.chmod(0o644)
    assert path.read_bytes() == before and sorted(os.listdir(media)) == ["s.sqlite"]


def test_read_only_opening_writes_nothing(tmp_path):
    path = tmp_path / "s.sqlite"
    keys = _three(path)
    before = path.read_bytes()
    with ResultStore(path, read_only=True) as store:
        assert store.keys("e") == keys and store.get(keys[2]).results["d"] == 3.25
    assert path.read_bytes() == before and sorted(os.listdir(tmp_path)) == ["s.sqlite"]
    with pytest.raises(StoreError, match="no such results store"):
        ResultStore(tmp_path / "absent.sqlite", read_only=True)


def _square(i):
    return {"y": i * i}


def test_schema1_store_killed_with_tasks_in_its_write_ahead_log(tmp_path):
    # what the previous version left after a SIGKILL: tasks committed only to the -wal file
    live = tmp_path / "live" / "old.sqlite"
    live.parent.mkdir()
    keys = _schema1_store(live)
    con = sqlite3.connect(live, isolation_level=None)
    con.execute("PRAGMA wal_autocheckpoint=0")
    con.execute(
        """INSERT INTO tasks VALUES (?, 'e', '{"i": 9}', '{"y": 81}', ?, 0.5, 'now')""",
        (task_key("e", {"i": 9}), store_module.code_version()),
    )
    killed = tmp_path / "killed"
    killed.mkdir()
    for name in ("old.sqlite", "old.sqlite-wal"):  # the files as a kill leaves them
        shutil.copyfile(live.parent / name, killed / name)
    con.close()
    ro = tmp_path / "ro"
    shutil.copytree(killed, ro)
    # read-only, the log cannot be folded in: refused rather than read without those tasks
    with pytest.raises(StoreError, match="write-ahead log"):
        ResultStore(ro / "old.sqlite", read_only=True)
    # writable: folded into the file, which then holds all three tasks by itself
    with ResultStore(killed / "old.sqlite") as store:
        assert set(store.keys("e")) == {*keys, task_key("e", {"i": 9})}
        assert store.get(task_key("e", {"i": 9})).results == {"y": 81}
    assert not (killed / "old.sqlite-wal").exists()


@pytest.mark.parametrize("needle", [b"ZZZZZZZZ", b"exp_utf8", b"experiment"])
def test_bytes_that_are_not_utf8_name_the_file(tmp_path, needle):
    # random bytes inside a stored text (a task's params, or a name SQLite's integrity check
    # reads) pass the page checks; reading them must name the file and the cause in one line,
    # not SQLite's bare "Could not decode to UTF-8" or a UnicodeDecodeError
    path = tmp_path / "r.sqlite"
    with ResultStore(path) as store:
        key = store.put("exp_utf8", {"coupling": 4.0, "marker": "ZZZZZZZZ"}, {"d_ky": 1.4})
    raw = bytearray(path.read_bytes())
    at = raw.find(needle)
    assert at > 0
    raw[at : at + 4] = b"\xff\xfe\xff\xfe"
    path.write_bytes(bytes(raw))
    with pytest.raises(StoreError) as exc:
        with ResultStore(path) as store:
            store.load("exp_utf8")
            store.get(key)
    text = str(exc.value)
    assert text.startswith(f"{path}:") and "UTF-8" in text and "\n" not in text
