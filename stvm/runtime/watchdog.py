"""A task watchdog: a scan that runs longer than the limit (an endless WHILE, say) is a fault.

A controller stops a task that exceeds its timeout with a major fault. stvm checks from a helper
thread, so a normal scan pays nothing: the thread looks twice a second whether the scan counter
moved, and if one scan has run longer than `limit_s` of wall-clock time it raises `WatchdogExpired`
inside the VM's thread (`PyThreadState_SetAsyncExc`, delivered between bytecodes). The VM turns it
into a `RuntimeFault` at the ST statement that was running.
"""

from __future__ import annotations

import threading
import time

from stvm.runtime.values import STFault


class WatchdogExpired(STFault):
    """Raised asynchronously in the VM thread when one scan exceeds the watchdog limit."""

    def __init__(self, *args) -> None:
        super().__init__(*(args or ("watchdog: the scan did not finish in time (endless loop?)",)))


class Watchdog:
    def __init__(self, vm, limit_s: float) -> None:
        self.vm = vm
        self.limit_s = limit_s
        self.target = threading.get_ident()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="stvm-watchdog", daemon=True)

    def __enter__(self) -> "Watchdog":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(1.0)

    def _watch(self) -> None:
        last_scan = self.vm.scan_count
        since = time.monotonic()
        period = min(0.5, self.limit_s / 4)
        while not self._stop.wait(period):
            # a VM held between scans by a front end's run control is paused, not hanging
            if self.vm.scan_count != last_scan or self.vm.fault is not None or self.vm.held:
                last_scan, since = self.vm.scan_count, time.monotonic()
                continue
            if time.monotonic() - since > self.limit_s:
                import ctypes   # lazy: start-up (only when a scan hangs)
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(self.target), ctypes.py_object(WatchdogExpired))
                since = time.monotonic()
