"""A client (``hyst ensemble --workers 2``-like) killed with SIGKILL: its pool workers end with
it, and the ``.sqlite`` file alone, copied elsewhere, holds every task it had stored."""

from __future__ import annotations

import os
import shutil
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from support_paths import ROOT

from analysis.experiments.store import ResultStore, task_key

CLIENT = textwrap.dedent(
    """
    import os, sys, time
    sys.path.insert(0, {here!r})
    from analysis.experiments.execution import run_tasks
    from test_client_kill import _slow_task
    tasks = [dict(x=i, pids={pids!r}) for i in range({n})]
    run_tasks("kill", tasks, _slow_task, store={store!r}, workers=2, progress=False)
    """
)
N = 40


def _slow_task(x, pids):
    """Record this worker's pid (one file per pid), then work a little."""
    Path(pids, str(os.getpid())).touch()
    time.sleep(0.2)
    return {"x2": x * x}


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is dead (it only waits to be reaped by its parent)
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return True


def _stored(path: Path) -> int:
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=5)
        try:
            return con.execute("SELECT COUNT(*) FROM tasks").fetchone()[0]
        finally:
            con.close()
    except sqlite3.OperationalError:  # not created yet
        return 0


@pytest.fixture(scope="module")
def killed_client(tmp_path_factory):
    """Run the client, SIGKILL it (it alone, not its process group) after a few stored tasks;
    yield the store path and the workers' pids."""
    tmp = tmp_path_factory.mktemp("kill")
    pids, store = tmp / "pids", tmp / "kill.sqlite"
    pids.mkdir()
    code = CLIENT.format(here=str(Path(__file__).parent), pids=str(pids), n=N, store=str(store))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests")]))
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while _stored(store) < 4:
            assert proc.poll() is None, "the client ended before it could be killed"
            assert time.monotonic() < deadline, "the client stored nothing within 60 s"
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        workers = sorted(int(p.name) for p in pids.iterdir())
        yield store, workers, time.monotonic()
    finally:
        if proc.poll() is None:
            proc.kill()
        for pid in (int(p.name) for p in pids.iterdir()):
            if _alive(pid):  # never leave one behind, even when the test fails
                os.kill(pid, signal.SIGKILL)


def test_workers_exit_when_the_client_is_killed(killed_client):
    _, workers, killed_at = killed_client
    assert len(workers) == 2  # both pool workers ran tasks
    while any(_alive(pid) for pid in workers) and time.monotonic() < killed_at + 5:
        time.sleep(0.05)
    assert not [pid for pid in workers if _alive(pid)], "workers outlived their killed client"


def test_copy_of_the_sqlite_file_alone_holds_every_stored_task(killed_client, tmp_path):
    store, _, _ = killed_client
    copy = tmp_path / "copy.sqlite"
    shutil.copyfile(store, copy)  # the file only: no -wal, -shm or -journal beside it
    # the truth: what the killed run committed, read in place with everything SQLite keeps
    con = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    committed = {k for (k,) in con.execute("SELECT key FROM tasks")}
    con.close()
    assert 4 <= len(committed) < N
    with ResultStore(copy) as copied:
        assert set(copied.keys("kill")) == committed
        for i in range(N):
            key = task_key("kill", {"x": i, "pids": str(store.parent / "pids")})
            if key in committed:
                assert copied.get(key).results == {"x2": i * i}


WATCH = textwrap.dedent(
    """
    import os, sys
    from analysis.experiments.execution import _watch_client
    if sys.argv[2] == "poll":
        del os.pidfd_open  # the portable fallback: polling the client's pid
    print("watching", flush=True)
    _watch_client(int(sys.argv[1]), os.getppid())
    """
)


@pytest.mark.parametrize("how", ["pidfd", "poll"])
def test_worker_watch_ends_the_process_when_the_client_exits(how):
    if how == "pidfd" and not hasattr(os, "pidfd_open"):
        pytest.skip("no pidfd_open on this platform")
    client = subprocess.Popen(["sleep", "60"])
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    watcher = subprocess.Popen(
        [sys.executable, "-c", WATCH, str(client.pid), how],
        env=env,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert watcher.stdout.readline().strip() == "watching"
        time.sleep(0.3)
        assert watcher.poll() is None  # the client lives: the watcher waits
        client.kill()
        client.wait()
        assert watcher.wait(timeout=5) == 1  # the client is gone: so is the watcher
    finally:
        for p in (client, watcher):
            if p.poll() is None:
                p.kill()
                p.wait()
