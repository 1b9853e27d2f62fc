"""Waking a front end's event loop from the VM thread without handing it the GIL mid-scan.

`loop.call_soon_threadsafe` writes a byte to the loop's self-pipe, and a socket write releases the
GIL for the system call. If the loop's thread (or any other) is waiting for the GIL at that moment,
it may take it, and the VM thread then waits for that thread's whole burst of Python (an HMI update
formatted and sent to every client: hundreds of µs) in the middle of its scan-end hooks: measured
as the scan's p99 with HMI clients (bench/bench_hmi.py, issue 33 item 3).

`LoopWaker.wake()` only releases a lock (a futex wake; CPython keeps the GIL for it). A relay thread
blocked on that lock then asks for the GIL like any other thread: it gets it when the VM thread
next lets go (the sleep until the next scan, at the latest the switch interval later) and makes the
`call_soon_threadsafe` call itself, outside the scan. The callback's latency grows by that wait
(under a scan period); nothing else changes.
"""

from __future__ import annotations

import asyncio
import threading
from typing import Callable


class LoopWaker:
    """Call `callback` in `loop`'s thread after `wake()` (any thread; a wake while one is already
    on its way may be merged with it: the callback reads the newest state itself)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, callback: Callable[[], None], name: str = "stvm-waker") -> None:
        self.loop = loop
        self.callback = callback
        self._signal = threading.Lock()
        self._signal.acquire()          # held: the relay blocks on it until `wake` releases it
        self._closed = False
        self._thread = threading.Thread(target=self._relay, name=name, daemon=True)
        self._thread.start()

    def wake(self) -> None:
        """VM thread (or any): never blocks, never releases the GIL."""
        try:
            self._signal.release()
        except RuntimeError:            # already released: a wake is on its way
            pass

    def close(self, timeout_s: float = 1.0) -> None:
        self._closed = True
        self.wake()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout_s)

    def _relay(self) -> None:
        while True:
            self._signal.acquire()
            if self._closed:
                return
            try:
                self.loop.call_soon_threadsafe(self.callback)
            except RuntimeError:        # the loop has closed (shutting down)
                return
