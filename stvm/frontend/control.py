"""Run control from another thread: pause, resume and step a VM by whole scans.

A test tool stepping the controller (OPC UA `Runtime.Scan(n)`, a web HMI's Pause button) must not
call `vm.scan()` itself: the VM belongs to the thread running the scan loop (`stvm run`'s loop,
the debugger's worker). `RunControl` puts a gate in front of every scan instead
(`vm.on_scan_start[0]`), which any loop calling `vm.scan()` obeys without knowing about it:

* `pause()`: the VM thread stops before its next scan and waits there (between two scans, so
  every variable is a scan's end state);
* `resume()`: it runs on;
* `step(n)`: it runs `n` scans, then waits again; the returned future completes once the n-th
  scan's end hooks (watch snapshots included) have run, with the number of scans done so far.

While it waits, the gate calls the `vm.on_idle` hooks every `poll_s` (a `VariableBridge` answers
one-shot reads and applies writes there), so a paused controller can still be
read and written, as a real one in program mode. `vm.held` tells the watchdog not to count the
wait as a scan that hangs. Only for the virtual clock: pausing a real-time run would make every
later deadline an overrun.
"""

from __future__ import annotations

import threading
from concurrent.futures import Future

from stvm.runtime.vm import VM


class RunControl:
    """Pause/resume/step `vm` from any thread; create it before the run starts."""

    def __init__(self, vm: VM, poll_s: float = 0.005) -> None:
        if vm.realtime:
            raise ValueError("run control (pause, resume, scan steps) needs the virtual clock")
        self.vm = vm
        self.poll_s = poll_s
        self._cond = threading.Condition()
        self._engaged = False          # fast path: False while running freely
        self._hold = False
        self._budget: int | None = None
        self._steps: list[Future] = []
        self._closed = False
        vm.on_scan_start.insert(0, self._gate)   # before the bridge applies writes

    # ---- any thread
    @property
    def paused(self) -> bool:
        """The VM thread is waiting between two scans."""
        return self.vm.held

    def pause(self) -> None:
        """Stop before the next scan (a step in progress is cancelled)."""
        with self._cond:
            self._hold, self._budget = True, None
            self._fail_steps("paused")
            self._engaged = True
            self._cond.notify_all()

    def resume(self) -> None:
        with self._cond:
            self._hold, self._budget = False, None
            self._fail_steps("resumed")
            self._engaged = False
            self._cond.notify_all()

    def step(self, scans: int) -> Future:
        """Run `scans` (≥ 1) more scans, then wait; the future's result is `vm.scan_count` then."""
        if scans < 1:
            raise ValueError(f"scan count must be at least 1, got {scans}")
        future: Future = Future()
        with self._cond:
            if self._closed:
                future.set_exception(RuntimeError("the run has ended"))
                return future
            self._budget = (self._budget or 0) + scans
            self._steps.append(future)
            self._engaged = True
            self._cond.notify_all()
        return future

    def wait_paused(self, timeout: float | None = None) -> bool:
        """Wait until the VM thread is held (after `pause()` or a finished step)."""
        with self._cond:
            return self._cond.wait_for(lambda: self.vm.held or self._closed, timeout) and self.vm.held

    def close(self) -> None:
        """Let the VM run freely for good (the run is ending); pending steps fail."""
        with self._cond:
            self._closed = True
            self._hold, self._budget, self._engaged = False, None, False
            self._fail_steps("the run has ended")
            self._cond.notify_all()

    def _fail_steps(self, why: str) -> None:
        for future in self._steps:
            if not future.done():
                future.set_exception(RuntimeError(f"step cancelled: {why}"))
        self._steps = []

    # ---- VM thread, at the start of every scan
    def _gate(self, vm: VM) -> None:
        if not self._engaged:
            return
        try:
            with self._cond:
                while not self._closed:
                    if self._budget is not None:
                        if self._budget > 0:
                            self._budget -= 1
                            return
                        # the step is done: the previous scan's end hooks have all run
                        self._budget, self._hold = None, True
                        for future in self._steps:
                            if not future.done():
                                future.set_result(vm.scan_count)
                        self._steps = []
                    if not self._hold:
                        return
                    if not vm.held:
                        vm.held = True
                        self._cond.notify_all()   # wake wait_paused()
                    self._cond.wait(self.poll_s)
                    for hook in vm.on_idle:
                        hook(vm)
        finally:
            vm.held = False
