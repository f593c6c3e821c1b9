"""run_tasks: resume after SIGKILL, identical results on every executor, seeds."""

from __future__ import annotations

import importlib
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
import time
from concurrent.futures import Executor, Future, ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from support_paths import ROOT

import analysis.experiments.store as store_module
from analysis.experiments.execution import TaskError, run_tasks, spawn_seeds
from analysis.experiments.store import ResultStore, StoreError

REPO = ROOT

# A task module written to a temporary directory so that the killed subprocess, the process-pool
# workers and this process all import the very same top-level function.
HELPERS = textwrap.dedent(
    """
    import time
    import numpy as np

    CALLS = []

    def task(x, seed, sleep=0.0):
        CALLS.append((x, seed))
        time.sleep(sleep)
        rng = np.random.default_rng(seed)
        return {
            "y": x * x,
            "noise": rng.normal(size=4),
            "walk": np.cumsum(rng.integers(-1, 2, size=(3, 5)), axis=1),
            "label": f"x={x}",
            "nested": {"sum": float(rng.uniform()), "items": [x, seed]},
        }

    def failing(x, seed, sleep=0.0):
        if x == 3:
            raise RuntimeError("boom")
        return task(x, seed)

    # the same tasks, runnable in batches: tasks of equal x // 4 share a batch (at most 3),
    # x = 7 runs alone; BATCHES records each batch's xs
    from analysis.experiments.execution import Batching

    BATCHES = []

    def run_batch(tasks):
        BATCHES.append([t["x"] for t in tasks])
        return [task(**t) for t in tasks]

    def batch_key(t):
        return None if t["x"] == 7 else t["x"] // 4

    def batched(x, seed, sleep=0.0):
        return task(x, seed, sleep)

    batched.batching = Batching(run=run_batch, size=3, key=batch_key)

    def failing_batch(tasks):
        if any(t["x"] == 5 for t in tasks):
            raise RuntimeError("the batch failed")
        return [task(**t) for t in tasks]

    def batched_failing(x, seed, sleep=0.0):
        if x == 5:
            raise ValueError("x = 5 fails alone too")
        return task(x, seed, sleep)

    batched_failing.batching = Batching(run=failing_batch, size=3, key=batch_key)
    """
)

SWEEP = textwrap.dedent(
    """
    import sys
    sys.path.insert(0, {helpers_dir!r})
    import sweep_helpers
    from analysis.experiments.execution import run_tasks, spawn_seeds
    seeds = spawn_seeds(2024, {n})
    tasks = [dict(x=i, seed=s, sleep={sleep}) for i, s in enumerate(seeds)]
    run_tasks("sweep", tasks, sweep_helpers.task, store={store!r}, workers={workers},
              progress=False)
    """
)

N_TASKS = 16


@pytest.fixture()
def helpers(tmp_path, monkeypatch):
    d = tmp_path / "helpers"
    d.mkdir()
    (d / "sweep_helpers.py").write_text(HELPERS)
    monkeypatch.syspath_prepend(str(d))
    sys.modules.pop("sweep_helpers", None)
    mod = importlib.import_module("sweep_helpers")
    yield mod
    sys.modules.pop("sweep_helpers", None)


def _tasks(n=N_TASKS, sleep=0.0):
    return [dict(x=i, seed=s, sleep=sleep) for i, s in enumerate(spawn_seeds(2024, n))]


def _equal(a, b) -> bool:
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return isinstance(b, list) and len(a) == len(b) and all(map(_equal, a, b))
    if isinstance(a, np.ndarray):
        return (
            isinstance(b, np.ndarray)
            and a.dtype == b.dtype
            and a.shape == b.shape
            and a.tobytes() == b.tobytes()
        )
    return type(a) is type(b) and a == b


def _dump(path: Path) -> dict:
    """Everything stored, keyed by task key, checked for duplicates."""
    con = sqlite3.connect(path)
    n, distinct = con.execute("SELECT COUNT(*), COUNT(DISTINCT key) FROM tasks").fetchone()
    na, distinct_a = con.execute(
        "SELECT COUNT(*), COUNT(DISTINCT key || '/' || name) FROM arrays"
    ).fetchone()
    con.close()
    assert n == distinct and na == distinct_a
    with ResultStore(path) as store:
        return {k: (store.get(k).params, store.get(k).results) for k in store.keys()}


def _count_rows(path: Path) -> int:
    if not path.exists():
        return 0
    try:
        con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=5)
        try:
            return con.execute("SELECT COUNT(*) FROM tasks").fetchone()[0]
        finally:
            con.close()
    except sqlite3.OperationalError:  # schema not created yet
        return 0


def test_sigkill_mid_run_then_resume_equals_uninterrupted(tmp_path, helpers):
    store_path = tmp_path / "killed.sqlite"
    script = tmp_path / "sweep.py"
    script.write_text(
        SWEEP.format(
            helpers_dir=str(tmp_path / "helpers"),
            n=N_TASKS,
            sleep=0.15,
            store=str(store_path),
            workers=2,
        )
    )
    env = dict(os.environ, PYTHONPATH=str(REPO))
    # own session: the SIGKILL reaches the sweep and its pool workers, nothing else
    proc = subprocess.Popen([sys.executable, str(script)], env=env, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while _count_rows(store_path) < 4:
            assert proc.poll() is None, "sweep ended before it could be killed"
            assert time.monotonic() < deadline, "sweep stored nothing within 60 s"
            time.sleep(0.02)
        os.killpg(proc.pid, signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL
    stored_at_kill = _count_rows(store_path)
    assert 4 <= stored_at_kill < N_TASKS  # killed mid-run

    # resume in-process and serially: only the missing tasks run
    helpers.CALLS.clear()
    resumed = run_tasks(
        "sweep", _tasks(sleep=0.15), helpers.task, store=store_path, workers=1, progress=False
    )
    assert len(helpers.CALLS) == N_TASKS - stored_at_kill

    reference_path = tmp_path / "reference.sqlite"
    reference = run_tasks(
        "sweep", _tasks(sleep=0.15), helpers.task, store=reference_path, workers=1, progress=False
    )
    assert all(map(_equal, resumed, reference))
    killed, ref = _dump(store_path), _dump(reference_path)
    assert set(killed) == set(ref) and len(ref) == N_TASKS
    for key in ref:
        assert _equal(killed[key][0], ref[key][0]) and _equal(killed[key][1], ref[key][1])

    # a second rerun changes nothing
    helpers.CALLS.clear()
    again = run_tasks(
        "sweep", _tasks(sleep=0.15), helpers.task, store=store_path, workers=1, progress=False
    )
    assert helpers.CALLS == [] and all(map(_equal, again, reference))
    assert len(_dump(store_path)) == N_TASKS


def test_serial_pool_dask_and_given_executor_agree(tmp_path, helpers):
    distributed = pytest.importorskip("distributed")
    tasks = _tasks(8)
    serial = run_tasks("sweep", tasks, helpers.task, workers=1, progress=False)
    pool = run_tasks("sweep", tasks, helpers.task, workers=2, progress=False)
    with ThreadPoolExecutor(2) as ex:
        threads = run_tasks("sweep", tasks, helpers.task, executor=ex, progress=False)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        dask = run_tasks(
            "sweep",
            tasks,
            helpers.task,
            scheduler=cluster.scheduler_address,
            progress=False,
            store=tmp_path / "dask.sqlite",
        )
    stored_serial = run_tasks(
        "sweep", tasks, helpers.task, workers=1, progress=False, store=tmp_path / "serial.sqlite"
    )
    for other in (pool, threads):
        assert all(map(_equal, serial, other))
    assert all(map(_equal, stored_serial, dask))
    # results come back in task order whatever the completion order
    assert [r["y"] for r in serial] == [i * i for i in range(8)]
    assert [r["label"] for r in dask] == [f"x={i}" for i in range(8)]
    # arrays survive the store bit for bit
    for a, b in zip(serial, dask, strict=True):
        assert a["noise"].tobytes() == b["noise"].tobytes()
    assert _dump(tmp_path / "dask.sqlite").keys() == _dump(tmp_path / "serial.sqlite").keys()


def test_duplicate_tasks_run_once_and_wall_time_recorded(tmp_path, helpers):
    tasks = _tasks(3)
    helpers.CALLS.clear()
    out = run_tasks(
        "sweep",
        tasks + tasks[:2],
        helpers.task,
        store=tmp_path / "s.sqlite",
        workers=1,
        progress=False,
    )
    assert len(helpers.CALLS) == 3 and len(out) == 5
    assert _equal(out[3], out[0]) and _equal(out[4], out[1])
    with ResultStore(tmp_path / "s.sqlite") as store:
        walls = [store.get(k).wall_time for k in store.keys("sweep")]
    assert len(walls) == 3 and all(w is not None and w >= 0 for w in walls)


def test_resume_across_code_versions_refused_unless_allowed(tmp_path, helpers, monkeypatch):
    path = tmp_path / "s.sqlite"
    tasks = _tasks(2)
    # stored by another code version (written by it, so sealed with that version: a version
    # changed afterwards inside the file would be damage, see test_store_integrity)
    with monkeypatch.context() as m:
        m.setattr(store_module, "code_version", lambda: "hysteresis-toolkit 0.0.1")
        first = run_tasks("sweep", tasks, helpers.task, store=path, workers=1, progress=False)
    helpers.CALLS.clear()
    before = path.read_bytes()
    with pytest.raises(StoreError, match="allow_version_mismatch"):
        run_tasks("sweep", _tasks(3), helpers.task, store=path, workers=1, progress=False)
    assert helpers.CALLS == [] and _count_rows(path) == 2  # nothing run, nothing added
    assert path.read_bytes() == before
    with pytest.warns(UserWarning, match="other code versions"):
        again = run_tasks(
            "sweep",
            tasks,
            helpers.task,
            store=path,
            workers=1,
            progress=False,
            allow_version_mismatch=True,
        )
    assert helpers.CALLS == [] and all(_equal(a, b) for a, b in zip(first, again, strict=True))


def test_failing_task_raises_with_its_parameters_and_keeps_finished(tmp_path, helpers):
    path = tmp_path / "f.sqlite"
    with pytest.raises(TaskError, match="'x': 3") as info:
        run_tasks("sweep", _tasks(6), helpers.failing, store=path, workers=1, progress=False)
    assert isinstance(info.value.__cause__, RuntimeError)
    assert _count_rows(path) == 3  # x = 0, 1, 2 were stored before the failure


class _DroppingExecutor(Executor):
    """Runs the first ``keep`` submissions at once, then drops (cancels) the rest, as a Dask
    client does with every pending future when it loses its scheduler."""

    def __init__(self, keep):
        self.keep = keep

    def submit(self, fn, /, *args, **kwargs):
        fut = Future()
        if self.keep > 0:
            self.keep -= 1
            fut.set_result(fn(*args, **kwargs))
        else:
            fut.cancel()
            fut.set_running_or_notify_cancel()
        return fut


def test_lost_executor_raises_connection_error_not_task_error(tmp_path, helpers):
    path = tmp_path / "lost.sqlite"
    tasks = _tasks(5)
    with pytest.raises(ConnectionError, match="2 of 5 tasks are stored") as info:
        run_tasks("sweep", tasks, helpers.task, store=path, executor=_DroppingExecutor(2),
                  progress=False)  # fmt: skip
    assert not isinstance(info.value, TaskError) and "run the same sweep again" in str(info.value)
    assert _count_rows(path) == 2
    # the rerun computes only the missing three and ends with the full, duplicate-free store
    helpers.CALLS.clear()
    run_tasks("sweep", tasks, helpers.task, store=path, workers=1, progress=False)
    assert sorted(x for x, _ in helpers.CALLS) == [2, 3, 4]
    assert _count_rows(path) == 5
    with pytest.raises(ConnectionError, match="nothing was stored"):
        run_tasks("sweep", tasks, helpers.task, executor=_DroppingExecutor(0), progress=False)


def test_spawn_seeds_independent_and_reproducible():
    a = spawn_seeds(7, 100)
    assert a == spawn_seeds(7, 100)
    assert a[:10] == spawn_seeds(7, 10)
    assert len(set(a)) == 100 and all(isinstance(s, int) and 0 <= s < 2**63 for s in a)
    assert set(a).isdisjoint(spawn_seeds(8, 100))
    # streams from neighbouring seeds are uncorrelated: |r| of 10⁴ normal pairs ~ 0.01
    x = np.random.default_rng(a[0]).normal(size=10_000)
    y = np.random.default_rng(a[1]).normal(size=10_000)
    assert abs(np.corrcoef(x, y)[0, 1]) < 0.04
    with pytest.raises(ValueError):
        spawn_seeds(-1, 3)


def test_bad_arguments():
    with pytest.raises(ValueError):
        run_tasks("e", [], dict, workers=0)
    with ThreadPoolExecutor(1) as ex, pytest.raises(ValueError):
        run_tasks("e", [], dict, executor=ex, scheduler="tcp://x:1")
    assert run_tasks("e", [], dict, progress=False) == []


def test_scheduler_must_be_an_address_no_local_cluster_is_started():
    # issue 21: nothing in the toolkit starts a Dask LocalCluster (whose nannies and workers
    # could outlive a killed client); '--scheduler local' is refused in one line naming it
    pytest.importorskip("distributed")
    with pytest.raises(ValueError, match="scheduler 'local' is not a Dask scheduler address") as e:
        run_tasks("x", [{"seed": 1}], dict, scheduler="local", progress=False)
    assert "\n" not in str(e.value) and "--workers" in str(e.value)


def test_batched_tasks_give_the_unbatched_results_one_row_each(tmp_path, helpers):
    """A task function with ``batching`` runs runs of consecutive same-key tasks in one call
    (at most ``size``; key None alone), and the results and the store are those of the tasks
    run one by one."""
    tasks = _tasks(10)
    plain = run_tasks("sweep", tasks, helpers.task, workers=1, progress=False,
                      store=tmp_path / "plain.sqlite")  # fmt: skip
    helpers.BATCHES.clear()
    serial = run_tasks("sweep", tasks, helpers.batched, workers=1, progress=False,
                       store=tmp_path / "serial.sqlite")  # fmt: skip
    # keys 0,0,0,0 | 1,1,1,None | 2,2: runs of at most 3; x = 3 (the run's rest) and x = 7
    # (key None) run alone, as func(**task), not through the batch function
    assert helpers.BATCHES == [[0, 1, 2], [4, 5, 6], [8, 9]]
    pool = run_tasks("sweep", tasks, helpers.batched, workers=2, progress=False,
                     store=tmp_path / "pool.sqlite")  # fmt: skip
    assert all(map(_equal, plain, serial)) and all(map(_equal, plain, pool))
    reference = _dump(tmp_path / "plain.sqlite")
    for name in ("serial", "pool"):
        stored = _dump(tmp_path / f"{name}.sqlite")
        assert stored.keys() == reference.keys()
        assert all(_equal(list(stored[k]), list(reference[k])) for k in reference)
    # resume: only the missing tasks are batched
    helpers.BATCHES.clear()
    run_tasks("sweep", _tasks(12), helpers.batched, workers=1, progress=False,
              store=tmp_path / "serial.sqlite")  # fmt: skip
    assert helpers.BATCHES == [[10, 11]]


@pytest.mark.parametrize("workers", [1, 2])
def test_a_failing_batch_names_its_failing_task(tmp_path, helpers, workers):
    """The batch raises; its tasks then run alone, and the error names the one that fails."""
    with pytest.raises(TaskError, match="'x': 5") as info:
        run_tasks("sweep", _tasks(8), helpers.batched_failing, workers=workers, progress=False)
    assert isinstance(info.value.error, ValueError) and "fails alone" in str(info.value)
