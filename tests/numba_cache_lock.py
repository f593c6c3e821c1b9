"""One file lock around numba's cache saves, shared by the processes that install it (pytest and
its kernel warm-up, ``tests/conftest.py`` and ``tests/kernel_warmup.py``).

Why: numba's ``IndexDataCacheFile.save`` reads a function's cache index, picks the first free
data file name and rewrites the index. Two processes saving one function at the same moment can
pick the same name for two signatures; the index then points one signature at the other's
code. Holding one lock for the read-pick-write makes the saves of these processes atomic (loads
need none: index and data are replaced atomically, a missing data file is a cache miss).
"""

from __future__ import annotations

import fcntl

from numba.core import caching

#: the environment variable naming the lock file
LOCK_ENV = "HYSTERESIS_TEST_CACHE_LOCK"


def lock_cache_saves(lock_path: str) -> bool:
    """Make numba's cache saves in this process take the file lock ``lock_path``; False (and
    nothing changed) if this numba has no ``IndexDataCacheFile.save``."""
    save = getattr(getattr(caching, "IndexDataCacheFile", None), "save", None)
    if save is None:
        return False
    if getattr(save, "_locked", False):
        return True

    def locked_save(self, key, data):  # noqa: ANN001, ANN202
        with open(lock_path, "a") as f:
            fcntl.flock(f, fcntl.LOCK_EX)
            try:
                return save(self, key, data)
            finally:
                fcntl.flock(f, fcntl.LOCK_UN)

    locked_save._locked = True
    caching.IndexDataCacheFile.save = locked_save
    return True
