"""The first call of each signature of a compiled function, one thread at a time."""

import threading

from . import stored


class FirstCalls:
    """The first call of each signature of a compiled function runs under a lock of its own: another thread that
    calls the same signature meanwhile waits for it and then finds the program compiled, instead of tracing and
    lowering it a second time (JAX shares the compilation between threads, not always the tracing: two threads
    that compiled a bucket's solve at once traced it twice, 1.5 s each). Calls of other signatures, and every later
    call, never wait. Stored programs (``stored.py``) do not come here: their exports share one lock there."""

    def __init__(self) -> None:
        self._guard = threading.Lock()
        self._locks: dict = {}  # signature → its lock while a first call runs, None once one has ended

    def run(self, key, action):
        with self._guard:
            new = key not in self._locks
            lock = self._locks.setdefault(key, threading.Lock())
        if lock is None:
            return action()
        if new:
            stored.count_trace()
        with lock:
            result = action()
        with self._guard:
            self._locks[key] = None
        return result
