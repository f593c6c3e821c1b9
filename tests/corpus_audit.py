"""Run every case of the bad-input corpus and classify it: clear / unclear / silent / crash.

Not collected by pytest (the name does not start with ``test_``). Usage::

    python tests/corpus_audit.py                       # the installed/worktree packages
    PYTHONPATH=/path/to/old/checkout python tests/corpus_audit.py   # an older version

One worker process runs the cases one after another; a case that kills it (segmentation fault)
or gives no answer within ``--timeout`` seconds is a *crash* (crash or hang), and a fresh worker
continues with the next case. Cases marked ``isolate`` run in a fresh child each. Prints one
line per case that is not clear, the counts, and as the
last line a JSON object with the counts.
"""

from __future__ import annotations

import argparse
import json
import selectors
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import test_bad_input_corpus as corpus  # noqa: E402


class Worker:
    def __init__(self, ready_timeout: float) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-c", corpus.CHILD.format(here=str(HERE), objects=True)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            bufsize=1,
            # not the checkout's directory: ``python -c`` puts the working directory first on
            # sys.path, which would shadow a PYTHONPATH pointing at another version
            cwd=tempfile.gettempdir(),
        )
        self.sel = selectors.DefaultSelector()
        self.sel.register(self.proc.stdout, selectors.EVENT_READ)
        line = self.read(ready_timeout)
        if line is None or not json.loads(line).get("ready"):
            raise RuntimeError("corpus worker did not start (prelude failed?)")

    def read(self, timeout: float) -> str | None:
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not self.sel.select(left):
                return None
            line = self.proc.stdout.readline()
            if not line:
                return None  # the worker died
            if line.startswith("{"):
                return line

    def ask(self, cid: str, timeout: float) -> dict | None:
        try:
            self.proc.stdin.write(cid + "\n")
            self.proc.stdin.flush()
        except BrokenPipeError:
            return None
        line = self.read(timeout)
        return None if line is None else json.loads(line)

    def kill(self) -> None:
        self.proc.kill()
        self.proc.wait()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=30.0, help="seconds per case")
    parser.add_argument("--verbose", action="store_true", help="print every case")
    args = parser.parse_args()
    import hysteresis

    print(f"packages from {Path(hysteresis.__file__).parent.parent}")
    counts = {"clear": 0, "unclear": 0, "silent": 0, "crash": 0}
    worker = Worker(ready_timeout=600.0)
    for case in corpus.CASES:
        if case.isolate:
            # hang- or crash-prone: a fresh child of its own, as the pytest corpus runs it
            verdict, detail = corpus.run_isolated(case, args.timeout)
            counts[verdict] += 1
            if verdict != "clear" or args.verbose:
                print(f"{verdict:8s} {case.id:36s} {detail[:150]}")
            continue
        answer = worker.ask(case.id, args.timeout)
        if answer is None:
            code = worker.proc.poll()
            worker.kill()
            verdict = "crash"
            detail = f"worker died (exit {code})" if code is not None else "hang (time-out)"
            worker = Worker(ready_timeout=600.0)
        else:
            verdict, detail = answer["verdict"], answer["detail"]
        counts[verdict] += 1
        if verdict != "clear" or args.verbose:
            print(f"{verdict:8s} {case.id:36s} {detail[:150]}")
    worker.kill()
    print(f"{len(corpus.CASES)} cases: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
    print(json.dumps({"cases": len(corpus.CASES), **counts}))


if __name__ == "__main__":
    main()
