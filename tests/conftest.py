"""Session set-up: on a checkout without a numba cache, a second process compiles the kernels
that the later test modules need while pytest runs the first ones (``kernel_warmup.py``).

Only for a broad run (the default suite, not a few files or ``-m slow``) on two or more cores,
only when a kernel module has no cache yet, and not with ``HYSTERESIS_TEST_WARMUP=0`` (``=1``
starts it for any run). pytest ends the process at the end of the session if it still runs.
Both processes save numba's cache under one file lock (``numba_cache_lock.py``), so a kernel
compiled by both at once is cached consistently. Fresh clone, 2 cores: 774 s -> 534 s.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numba
import pytest
from numba_cache_lock import LOCK_ENV, lock_cache_saves

import hysteresis
from oscillators.engines._compilation import has_cache

#: a run with fewer tests than this (a few files, ``-m slow``) compiles what it needs itself
MIN_ITEMS = 1000
#: kernel modules of the warm-up; any of them without a cache means a cold checkout
KERNEL_MODULES = (
    "analysis.dynamics._relay_benettin",
    "oscillators.engines._duhem_engine_kernels",
    "oscillators.engines._switching_kernels",
    "hysteresis._rfim_bits_kernels",
)

_warmup: dict[str, object] = {}


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _cold() -> bool:
    for name in KERNEL_MODULES:
        importlib.import_module(name)
    return not all(has_cache(name) for name in KERNEL_MODULES)


def pytest_collection_finish(session: pytest.Session) -> None:
    setting = os.environ.get("HYSTERESIS_TEST_WARMUP", "")
    if setting == "0" or session.config.option.collectonly or numba.config.DISABLE_JIT:
        return
    if setting != "1" and (len(session.items) < MIN_ITEMS or _cores() < 2 or not _cold()):
        return
    lock = Path(tempfile.mkdtemp(prefix="hysteresis-tests-")) / "numba-cache.lock"
    if not lock_cache_saves(str(lock)):
        return
    # the warm-up compiles this checkout's sources (numba's cache is keyed on the source file)
    root = str(Path(hysteresis.__file__).resolve().parents[1])
    path = os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)
    env = dict(os.environ, PYTHONPATH=path, **{LOCK_ENV: str(lock)})
    _warmup["process"] = subprocess.Popen(
        [sys.executable, str(Path(__file__).with_name("kernel_warmup.py"))],
        env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    _warmup["lock"] = lock


def pytest_sessionfinish(session: pytest.Session) -> None:
    process = _warmup.pop("process", None)
    if isinstance(process, subprocess.Popen) and process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
    lock = _warmup.pop("lock", None)
    if isinstance(lock, Path):
        lock.unlink(missing_ok=True)
        lock.parent.rmdir()
