"""A real distributed run: ``dask scheduler`` and ``dask worker`` processes on localhost.

The in-process ``LocalCluster`` of ``test_execution.py`` shares one Python process with the
client; here the scheduler and every worker are separate OS processes started from the ``dask``
command line (as on a cluster), talking TCP over the loopback interface only. The ensemble goes
through ``hyst ensemble --scheduler tcp://127.0.0.1:PORT --store FILE`` (a client process of its
own); one worker is SIGKILLed (nanny and worker process together: a machine that vanishes) while
it is computing a task. The store must end identical to a serial run's store: the same keys and,
bit for bit, the same parameters, results and arrays — nothing lost, nothing duplicated.

The run recovers by itself: the scheduler notices the closed connection, reschedules the task
that was in flight (and any finished result held only by the dead worker) on the surviving
worker, and the client writes each result once, as it arrives. No rerun is needed; the test
checks that the first run already exits 0 with a complete store.

Every process is started in a session of its own and killed by its process-group id in a
``finally``; every wait is bounded.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")

TWO_PI = 6.283185307179586

#: wall-time bounds (s): generous for two loaded cores, but every wait ends
STARTUP_TIMEOUT = 90.0
RUN_TIMEOUT = 240.0
#: the HTTP (health/metrics) server runs even with --no-dashboard: keep it on loopback too
LOOPBACK_HTTP = "127.0.0.1:0"


def _dask_command() -> list[str]:
    """The ``dask`` console script of this interpreter's environment (or ``python -m dask``)."""
    script = Path(sys.executable).with_name("dask")
    return [str(script)] if script.exists() else [sys.executable, "-m", "dask"]


def _spawn(cmd: list[str], log: Path) -> subprocess.Popen:
    env = dict(os.environ)
    # no dashboards, no config files of the user's; one BLAS thread per process
    env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    with open(log, "wb") as fh:
        # a session of its own: the process group id is the pid, so the nanny and its worker
        # process die together and nothing outlives the test
        return subprocess.Popen(
            cmd, stdout=fh, stderr=subprocess.STDOUT, start_new_session=True, env=env
        )


def _kill_group(proc: subprocess.Popen, sig: int = signal.SIGKILL) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(proc.pid, sig)


def _stop(proc: subprocess.Popen) -> None:
    """SIGTERM, a bounded grace period, then SIGKILL of the whole process group."""
    if proc.poll() is None:
        _kill_group(proc, signal.SIGTERM)
        with contextlib.suppress(subprocess.TimeoutExpired):
            proc.wait(timeout=5)
    _kill_group(proc, signal.SIGKILL)
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=10)


@dataclass
class Cluster:
    address: str
    scheduler: subprocess.Popen
    workers: list[subprocess.Popen]
    logs: list[Path] = field(default_factory=list)

    def log_tail(self) -> str:
        return "\n".join(
            f"--- {p.name}\n{p.read_text(errors='replace')[-3000:]}" for p in self.logs
        )


@contextlib.contextmanager
def _cluster(tmp_path: Path, n_workers: int, preload: Path | None = None) -> Iterator[Cluster]:
    """A ``dask scheduler`` and ``n_workers`` single-process, single-thread ``dask worker``s
    (each loading ``preload`` at start-up, if given)."""
    dask = _dask_command()
    extra = ["--preload", str(preload)] if preload is not None else []
    sched_file = tmp_path / "scheduler.json"
    procs: list[subprocess.Popen] = []
    logs = [tmp_path / "scheduler.log"]
    try:
        procs.append(
            _spawn(
                [*dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                 "--dashboard-address", LOOPBACK_HTTP, "--scheduler-file", str(sched_file),
                 "--idle-timeout", "600"],
                logs[0],
            )
        )  # fmt: skip
        deadline = time.monotonic() + STARTUP_TIMEOUT
        address = None
        while address is None:
            if procs[0].poll() is not None or time.monotonic() > deadline:
                raise RuntimeError("dask scheduler did not start:\n" + logs[0].read_text())
            with contextlib.suppress(OSError, ValueError):
                address = json.loads(sched_file.read_text())["address"]
            time.sleep(0.1)
        assert address.startswith("tcp://127.0.0.1:"), address
        for i in range(n_workers):
            logs.append(tmp_path / f"worker{i}.log")
            procs.append(
                _spawn(
                    [*dask, "worker", "--scheduler-file", str(sched_file), "--nworkers", "1",
                     "--nthreads", "1", "--host", "127.0.0.1", "--no-dashboard",
                     "--dashboard-address", LOOPBACK_HTTP, "--local-directory",
                     str(tmp_path / f"worker{i}"), "--death-timeout", "60", *extra],
                    logs[-1],
                )
            )  # fmt: skip
        yield Cluster(address, procs[0], procs[1:], logs)
    finally:
        for proc in reversed(procs):
            _stop(proc)


def _listening_hosts(pids: list[int]) -> set[str]:
    """Local addresses the processes listen on (TCP)."""
    import psutil  # a dependency of distributed

    hosts = set()
    for pid in pids:
        proc = psutil.Process(pid)
        get = getattr(proc, "net_connections", None) or proc.connections  # psutil < 6
        hosts |= {c.laddr.ip for c in get(kind="tcp") if c.status == psutil.CONN_LISTEN}
    return hosts


def _store_rows(path: Path) -> tuple[dict, dict]:
    """The store's content read straight from SQLite (not through ResultStore): per key the
    (experiment, params JSON, results JSON) and per (key, array name) the .npy bytes."""
    conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        tasks = conn.execute("SELECT key, experiment, params, results FROM tasks").fetchall()
        arrays = conn.execute("SELECT key, name, data FROM arrays").fetchall()
    finally:
        conn.close()
    task_rows = {k: (e, p, r) for k, e, p, r in tasks}
    assert len(task_rows) == len(tasks)
    return task_rows, {(k, n): bytes(d) for k, n, d in arrays}


def _stored_count(path: Path) -> int:
    if not path.exists():
        return 0
    try:
        conn = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=1.0)
        try:
            return int(conn.execute("SELECT COUNT(*) FROM tasks").fetchone()[0])
        finally:
            conn.close()
    except sqlite3.Error:  # not created yet
        return 0


#: tasks that run without waiting; every later start waits for the gate's release file
FREE_TASKS = 2

#: loaded by every worker (``dask worker --preload``): the task wrapper ``_timed_call`` the
#: client submits by reference is replaced, in the worker only, by one that numbers its starts
#: across all workers (an O_EXCL file per start) and holds every start after the first
#: FREE_TASKS until the file ``release`` exists. The test thereby kills a worker while it
#: certainly holds a task, however fast the tasks are (a kill timed against the tasks' speed
#: fell after the run once the relay kernel got faster).
GATE_PRELOAD = """
import os
import time
from pathlib import Path

import analysis.experiments.execution as execution

GATE = Path({gate!r})
FREE = {free}
# dask may import a preload file twice: wrap the original once, never the wrapper
_timed_call = getattr(execution._timed_call, "unwrapped", execution._timed_call)


def _claim_start():
    n = 0
    while True:
        try:
            os.close(os.open(GATE / f"started-{{n}}", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            return n
        except FileExistsError:
            n += 1


def _gated_call(func, task):
    if _claim_start() >= FREE:
        deadline = time.monotonic() + {timeout}
        while not (GATE / "release").exists():
            if time.monotonic() > deadline:
                raise RuntimeError("the test never released the gate")
            time.sleep(0.02)
    return _timed_call(func, task)


_gated_call.unwrapped = _timed_call
execution._timed_call = _gated_call
"""


def _write_gate(tmp_path: Path) -> tuple[Path, Path]:
    """The gate folder and the worker preload file that watches it."""
    gate = tmp_path / "gate"
    gate.mkdir()
    preload = tmp_path / "gate_preload.py"
    preload.write_text(GATE_PRELOAD.format(gate=str(gate), free=FREE_TASKS, timeout=RUN_TIMEOUT))
    return gate, preload


def _wait_for(condition, what: str, proc: subprocess.Popen, cluster: Cluster) -> None:
    deadline = time.monotonic() + RUN_TIMEOUT
    while not condition():
        if proc.poll() is not None or time.monotonic() > deadline:
            pytest.fail(f"{what} never happened\n" + cluster.log_tail())
        time.sleep(0.05)


def _ensemble_args(couplings: list[str], realizations: int, t_end: float) -> list[str]:
    return [
        "ensemble", "--spins", "200", "--coupling", *couplings,
        "--realizations", str(realizations), "--seed", "11", "--t-end", f"{t_end:g}",
        "--transient", "20", "--box-max-fill", "0.5", "--box-min-boxes", "2", "--quiet",
    ]  # fmt: skip


def _serial_reference(tmp_path: Path, args: list[str], n_tasks: int) -> tuple[dict, dict]:
    """The ensemble run serially (``--workers 1``) in this process; its store's content."""
    from analysis.cli import main

    serial_store = tmp_path / "serial.sqlite"
    # in this process: also compiles (or loads) the numba kernels the workers will load
    assert main([*args, "--workers", "1", "--store", str(serial_store),
                 "--out", str(tmp_path / "serial")]) == 0  # fmt: skip
    reference, reference_arrays = _store_rows(serial_store)
    assert len(reference) == n_tasks and reference_arrays
    return reference, reference_arrays


def _start_client(
    tmp_path: Path, cluster: Cluster, args: list[str], store: Path, tag: str
) -> subprocess.Popen:
    """``hyst ensemble ... --scheduler ADDR --store FILE`` in a process of its own."""
    log = tmp_path / f"client-{tag}.log"
    cluster.logs.append(log)
    return _spawn(
        [sys.executable, "-m", "analysis.cli", *args, "--scheduler", cluster.address,
         "--store", str(store), "--out", str(tmp_path / "dist")],
        log,
    )  # fmt: skip


def _wait_stored(store: Path, at_least: int, proc: subprocess.Popen, cluster: Cluster) -> None:
    deadline = time.monotonic() + RUN_TIMEOUT
    while _stored_count(store) < at_least:
        if proc.poll() is not None or time.monotonic() > deadline:
            pytest.fail(f"fewer than {at_least} results stored\n" + cluster.log_tail())
        time.sleep(0.05)


def _assert_same_as_reference(tmp_path: Path, store: Path, reference: dict, arrays: dict):
    rows, dist_arrays = _store_rows(store)
    # nothing lost, nothing duplicated: the same keys (PRIMARY KEY: one row each) ...
    assert sorted(rows) == sorted(reference)
    # ... and bit-identical values: the JSON text round-trips every float exactly, arrays are
    # compared as raw .npy bytes (dtype, shape and every bit)
    assert rows == reference
    assert dist_arrays == arrays
    # the summaries written by both runs agree too
    summary = [json.loads((tmp_path / d / "ensemble.json").read_text()) for d in ("serial", "dist")]
    assert summary[0]["points"] == summary[1]["points"]


def _run_with_worker_killed(tmp_path: Path, args: list[str], n_tasks: int) -> None:
    """Serial reference, then the same ensemble on a 2-worker cluster with one worker killed
    while it holds a task (the gate: FREE_TASKS results stored, then both workers each hold a
    started task); the two stores must be identical."""
    assert n_tasks > FREE_TASKS + 2, "both workers must hold a task at the kill"
    reference, reference_arrays = _serial_reference(tmp_path, args, n_tasks)
    dist_store = tmp_path / "dist.sqlite"
    gate, preload = _write_gate(tmp_path)
    with _cluster(tmp_path, n_workers=2, preload=preload) as cluster:
        client_proc = None
        try:
            with distributed.Client(cluster.address, timeout="60s") as observer:
                observer.wait_for_workers(2, timeout=STARTUP_TIMEOUT)
                # worker address -> our Popen (the worker process is in its nanny's group)
                pids = observer.run(os.getpid)
                proc_of = {
                    addr: next(p for p in cluster.workers if os.getpgid(pid) == p.pid)
                    for addr, pid in pids.items()
                }
                assert len(set(map(id, proc_of.values()))) == 2
                # loopback only: no process of the cluster listens on another interface
                everyone = [
                    cluster.scheduler.pid,
                    *(p.pid for p in cluster.workers),
                    *pids.values(),
                ]
                assert _listening_hosts(everyone) == {"127.0.0.1"}
                client_proc = _start_client(tmp_path, cluster, args, dist_store, "run")
                # the free tasks are stored; the next two starts wait at the gate, one on each
                # worker (a single-thread worker holding a waiting task starts no other)
                _wait_stored(dist_store, FREE_TASKS, client_proc, cluster)
                held = [gate / f"started-{FREE_TASKS + i}" for i in range(2)]
                _wait_for(lambda: all(f.exists() for f in held), "two held starts",
                          client_proc, cluster)  # fmt: skip
                busy = [a for a, keys in observer.processing().items() if keys]
                assert sorted(busy) == sorted(proc_of), "both workers hold a task"
                victim = busy[-1]
                _kill_group(proc_of[victim], signal.SIGKILL)
                assert _stored_count(dist_store) == FREE_TASKS, "nothing passes the gate"
                # the scheduler notices the dead worker (closed connection)
                deadline = time.monotonic() + 60
                while victim in observer.scheduler_info()["workers"]:
                    assert time.monotonic() < deadline, "scheduler kept the killed worker"
                    time.sleep(0.1)
                (gate / "release").touch()
            try:
                rc = client_proc.wait(timeout=RUN_TIMEOUT)
            except subprocess.TimeoutExpired:
                pytest.fail("the distributed run did not finish\n" + cluster.log_tail())
            # Dask rescheduled the lost work: the first run completes, no rerun needed
            assert rc == 0, cluster.log_tail()
        finally:
            if client_proc is not None:
                _stop(client_proc)
        assert proc_of[victim].poll() is not None  # it is really gone
    # the task the victim held started again on the survivor: more starts than tasks
    assert (gate / f"started-{n_tasks}").exists()
    _assert_same_as_reference(tmp_path, dist_store, reference, reference_arrays)


def test_distributed_run_survives_a_killed_worker(tmp_path):
    """2 couplings x 3 realizations of N = 200 dimers; one of two workers SIGKILLed while it
    holds a task (held at the gate, so the kill falls inside the run however fast tasks are)."""
    _run_with_worker_killed(tmp_path, _ensemble_args(["2.9", "4.0"], 3, 8000.0), n_tasks=6)


@pytest.mark.slow
def test_distributed_ensemble_survives_a_killed_worker_full(tmp_path):
    """2 couplings x 6 realizations of N = 200 dimers; one of two workers SIGKILLed mid-run."""
    _run_with_worker_killed(tmp_path, _ensemble_args(["2.9", "4.0"], 6, 15000.0), n_tasks=12)


@pytest.mark.slow
def test_lost_scheduler_fails_clearly_and_a_rerun_resumes(tmp_path):
    """The scheduler is SIGKILLed mid-run: the client exits (bounded) with one clear error that
    says what is stored; the same command against a new cluster completes the store, identical
    to the serial run's."""
    args = _ensemble_args(["2.9", "4.0"], 3, 8000.0)
    reference, reference_arrays = _serial_reference(tmp_path, args, 6)
    dist_store = tmp_path / "dist.sqlite"
    first = tmp_path / "cluster1"
    first.mkdir()
    gate, preload = _write_gate(first)
    with _cluster(first, n_workers=2, preload=preload) as cluster:
        client_proc = _start_client(tmp_path, cluster, args, dist_store, "lost")
        try:
            # killed while the tasks after the free ones wait at the gate (never released)
            _wait_stored(dist_store, FREE_TASKS, client_proc, cluster)
            held = gate / f"started-{FREE_TASKS}"
            _wait_for(held.exists, "a held start", client_proc, cluster)
            _kill_group(cluster.scheduler, signal.SIGKILL)
            try:
                rc = client_proc.wait(timeout=120)
            except subprocess.TimeoutExpired:
                pytest.fail("the client hung after losing its scheduler\n" + cluster.log_tail())
        finally:
            _stop(client_proc)
        log = cluster.logs[-1].read_text(errors="replace")
    stored = _stored_count(dist_store)
    assert rc == 2, log[-3000:]
    assert stored == FREE_TASKS
    error = [ln for ln in log.splitlines() if ln.startswith("hyst ensemble: error:")]
    assert len(error) == 1, log[-3000:]
    assert "ConnectionError" in error[0] and "lost the Dask scheduler" in error[0], error[0]
    assert f"{stored} of 6 tasks are stored" in error[0], error[0]
    assert "failed" not in error[0]  # no task is blamed
    second = tmp_path / "cluster2"
    second.mkdir()
    with _cluster(second, n_workers=2) as cluster:
        client_proc = _start_client(tmp_path, cluster, args, dist_store, "rerun")
        try:
            rc = client_proc.wait(timeout=RUN_TIMEOUT)
        except subprocess.TimeoutExpired:
            pytest.fail("the rerun did not finish\n" + cluster.log_tail())
        finally:
            _stop(client_proc)
        assert rc == 0, cluster.log_tail()
    _assert_same_as_reference(tmp_path, dist_store, reference, reference_arrays)


def _process_group(pgid: int) -> list[int]:
    """Pids of the live (not zombie) processes in process group ``pgid`` (Linux /proc)."""
    members = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        # fields after the command name "(...)": state, ppid, pgrp
        state, _ppid, pgrp = stat.rsplit(")", 1)[1].split()[:3]
        if int(pgrp) == pgid and state != "Z":
            members.append(int(entry.name))
    return members


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_killed_client_leaves_no_process_and_no_work_behind(tmp_path):
    """Issue 21: SIGKILL of ``hyst ensemble --scheduler ADDR`` mid-run (the client process
    only, not its group). The client starts no process of its own on the Dask path (no local
    cluster, nanny or worker: ``--scheduler`` takes an address, ``'local'`` is refused), so
    nothing is orphaned: its process group is empty once it is dead. The cluster drops the dead
    client's work: within a bounded time the scheduler holds none of its tasks and no worker
    computes for nobody; the cluster's own workers stay (they belong to the cluster)."""
    args = _ensemble_args(["2.9", "4.0"], 3, 8000.0)
    store = tmp_path / "dist.sqlite"
    with _cluster(tmp_path, n_workers=2) as cluster:
        with distributed.Client(cluster.address, timeout="60s") as observer:
            observer.wait_for_workers(2, timeout=STARTUP_TIMEOUT)
            client_proc = _start_client(tmp_path, cluster, args, store, "killed")
            try:
                deadline = time.monotonic() + RUN_TIMEOUT
                while not any(observer.processing().values()):
                    if client_proc.poll() is not None or time.monotonic() > deadline:
                        pytest.fail("the cluster never computed\n" + cluster.log_tail())
                    time.sleep(0.05)
                assert _process_group(client_proc.pid) == [client_proc.pid]
                os.kill(client_proc.pid, signal.SIGKILL)
                client_proc.wait(timeout=30)
                assert _process_group(client_proc.pid) == []  # nothing outlived the client
            finally:
                _stop(client_proc)
            # the scheduler forgets the dead client's tasks (closed connection), bounded
            deadline = time.monotonic() + 60
            while True:
                held = observer.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))
                if held == 0 and not any(observer.processing().values()):
                    break
                assert time.monotonic() < deadline, f"{held} tasks kept for a dead client"
                time.sleep(0.2)
            assert len(observer.scheduler_info()["workers"]) == 2  # the cluster is intact
    assert _stored_count(store) < 6  # the kill fell inside the run
