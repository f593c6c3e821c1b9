"""Results store under stress: concurrent writers, damaged files, other code versions, and
errors raised inside worker processes."""

from __future__ import annotations

import sqlite3
import subprocess
import sys
import textwrap
import traceback
from pathlib import Path

import numpy as np
import pytest
from support_paths import ROOT, TESTS

from analysis.experiments.execution import TaskError, run_tasks
from analysis.experiments.store import ResultStore, StoreError, task_key

REPO = ROOT

WRITER = textwrap.dedent(
    """
    import sys
    import numpy as np
    from analysis.experiments.store import ResultStore
    path, who, start = sys.argv[1], sys.argv[2], int(sys.argv[3])
    with ResultStore(path, timeout=120) as store:
        for i in range(start, start + 150):
            # overlapping keys between the writers: (x) alone decides the key
            store.put("race", {"x": i}, {"x": i, "who": who, "a": np.arange(i % 7 + 1.0)})
    print("done")
    """
)


def test_two_processes_writing_one_store_lose_and_duplicate_nothing(tmp_path):
    path = tmp_path / "race.sqlite"
    ResultStore(path).close()
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", WRITER, str(path), who, str(start)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=REPO,
        )
        for who, start in (("A", 0), ("B", 100))
    ]
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err[-2000:]
    with ResultStore(path) as store:
        keys = store.keys("race")
        assert len(keys) == len(set(keys)) == 250  # x = 0 .. 249, each once
        for x in range(250):
            task = store.get(task_key("race", {"x": x}))
            assert task.results["x"] == x
            # the first writer wins on overlapping keys; the arrays belong to that row
            assert task.results["who"] in ("A", "B")
            np.testing.assert_array_equal(task.results["a"], np.arange(x % 7 + 1.0))
    with sqlite3.connect(path) as conn:
        n_arrays = conn.execute("SELECT COUNT(*) FROM arrays").fetchone()[0]
    assert n_arrays == 250


def _square(x):
    return {"y": x * x}


def test_two_concurrent_run_tasks_agree(tmp_path):
    code = textwrap.dedent(
        f"""
        import sys, json
        sys.path[:0] = [{str(Path(__file__).parent)!r}, {str(TESTS)!r}]
        from test_store_robustness import _square
        from analysis.experiments.execution import run_tasks
        res = run_tasks("sq", [dict(x=i) for i in range(60)], _square,
                        store={str(tmp_path / "sq.sqlite")!r}, workers=1, progress=False)
        print(json.dumps([r["y"] for r in res]))
        """
    )
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    outs = []
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err[-2000:]
        outs.append(out.strip().splitlines()[-1])
    assert outs[0] == outs[1] == str([i * i for i in range(60)]).replace(" ", " ")
    with ResultStore(tmp_path / "sq.sqlite") as store:
        assert len(store) == 60


@pytest.fixture(scope="module")
def full_store(tmp_path_factory) -> bytes:
    """The bytes of a store of 200 tasks (written once: each commit is synced to disk)."""
    path = tmp_path_factory.mktemp("full") / "s.sqlite"
    with ResultStore(path) as store:
        for i in range(200):
            store.put("e", {"i": i}, {"v": np.full(50, float(i))})
    # the file alone holds the data (rollback journal: nothing lies beside it)
    assert not path.with_name(path.name + "-wal").exists()
    return path.read_bytes()


@pytest.mark.parametrize(
    "damage",
    ["truncate_half", "truncate_to_header", "garbage_middle", "binary_garbage", "text"],
)
def test_damaged_store_is_refused_and_left_untouched(tmp_path, damage, full_store):
    path = tmp_path / "s.sqlite"
    data = full_store
    if damage == "truncate_half":
        data = data[: len(data) // 2]
    elif damage == "truncate_to_header":
        data = data[:100]
    elif damage == "garbage_middle":
        mid = len(data) // 2
        data = data[:4096] + bytes(range(256)) * 64 + data[4096 + 256 * 64 :]
        assert mid > 0
    elif damage == "binary_garbage":
        data = np.random.default_rng(0).bytes(8192)
    else:
        data = b"reversal_field,field,moment\n1,2,3\n"
    path.write_bytes(data)
    for extra in (path.with_name(path.name + "-wal"), path.with_name(path.name + "-shm")):
        extra.unlink(missing_ok=True)
    with pytest.raises(StoreError, match="s.sqlite") as info:
        store = ResultStore(path)
        # a damage that the header and quick check cannot see must still surface on reading
        for key in store.keys("e"):
            store.get(key)
        store.close()
        raise AssertionError("damaged store read without error")
    assert isinstance(info.value, ValueError)
    assert path.read_bytes() == data  # nothing overwritten


def test_foreign_sqlite_database_is_refused(tmp_path):
    path = tmp_path / "other.db"
    with sqlite3.connect(path) as conn:
        conn.execute("CREATE TABLE people (name TEXT)")
    before = path.read_bytes()
    with pytest.raises(StoreError, match="not a results store"):
        ResultStore(path)
    assert path.read_bytes() == before


def _odd(x):
    if x == 2:
        raise ValueError("n_spins must be even (pairs of spins), got 101")
    return {"x": x}


def test_worker_exception_reaches_the_caller_as_one_clear_error(tmp_path):
    with pytest.raises(TaskError) as info:
        run_tasks("odd", [dict(x=i) for i in range(4)], _odd, workers=2, progress=False)
    err = info.value
    message = str(err)
    assert "\n" not in message
    assert "'x': 2" in message and "ValueError" in message and "n_spins must be even" in message
    assert isinstance(err.error, ValueError)
    # the pool's remote traceback is kept for debugging but not chained into the report
    assert err.remote_traceback is not None and "_odd" in err.remote_traceback
    printed = "".join(traceback.format_exception(err))
    assert "_RemoteTraceback" not in printed and printed.count("Traceback") <= 2


def test_version_check_refuses_other_commits_not_a_dirty_tree(tmp_path, monkeypatch):
    import analysis.experiments.store as store_module

    path = tmp_path / "v.sqlite"
    with ResultStore(path) as store:
        store.put("e", {"i": 1}, {"v": 1.0})
    monkeypatch.setattr(store_module, "code_version", lambda: "hysteresis-toolkit 0.1.0 (git abc)")
    for stored, refused in (
        ("hysteresis-toolkit 0.1.0 (git abc)", False),
        ("hysteresis-toolkit 0.1.0 (git abc-dirty)", False),
        ("hysteresis-toolkit 0.1.0 (git def)", True),
        ("hysteresis-toolkit 0.0.9 (git abc)", True),
    ):
        with sqlite3.connect(path) as conn:
            conn.execute("UPDATE tasks SET code_version = ?", (stored,))
        with ResultStore(path) as store:
            if refused:
                with pytest.raises(StoreError, match="allow_version_mismatch"):
                    store.check_versions("e")
                assert store.check_versions("e", allow_version_mismatch=True) == [stored]
            else:
                store.check_versions("e")


def test_empty_file_becomes_a_new_store(tmp_path):
    # an empty file holds nothing to lose, and is what SQLite leaves while another process is
    # creating the same store: it is initialised, not refused
    path = tmp_path / "new.sqlite"
    path.write_bytes(b"")
    with ResultStore(path) as store:
        store.put("e", {"i": 1}, {"v": 2.0})
    with ResultStore(path) as store:
        assert store.load("e") == [({"i": 1}, {"v": 2.0})]
