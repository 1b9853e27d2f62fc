"""The bridge between the scan loop (the VM thread) and front ends running in other threads.

The VM owns time (design: "Front ends beside the scan loop"). A front end never reads or writes a
variable itself:

* **Reads** come from a `Snapshot`: the values of a `Watch`'s paths, all taken by the VM thread at
  the end of one scan, so every value in it belongs to the same instant. A watch samples at most
  once per scan, at least `every_ns` of VM time apart and, if asked, `every_wall_ns` of wall-clock
  time apart (on the virtual clock VM time may run many times faster than a display needs);
  sampling costs the scan loop one getter call per path and nothing when no watch is due.
* **Writes** are submitted as a batch `{path: value}`. The batch is checked against the variables'
  types in the caller's thread (a bad value is rejected at once, the VM untouched), queued, and
  applied by the VM thread at the start of the next scan, all of it or none of it, never in the
  middle of a scan (as an NA HMI's variable mapping or an NJ's OPC UA server writes). A scan
  applies the batches queued before it started, in order; a batch submitted after an earlier one
  was applied therefore lands in a later scan (a momentary button's TRUE is seen by at least one
  scan before its FALSE). `parse(path, text)` turns IEC literal text (`TRUE`, `16#FF`, `'abc'`,
  `T#1s`, `PTP`) into the value `submit` takes.

The queue is bounded: a front end that floods writes gets `WriteRejected("busy")` instead of slowing
the scan. Nothing here blocks the VM thread.
"""

from __future__ import annotations

import queue
import threading
import time
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Mapping

from stvm.runtime.format import format_value
from stvm.runtime.vm import VM, PathError, UnboundInOut, coerce_python_value
from stvm.semantics import types as t

MAX_PENDING_WRITES = 1024
"""Write batches queued for the next scan; more are rejected (a front end cannot stall the VM)."""


class WriteRejected(ValueError):
    """A write batch that was not applied; `path` names the offending variable (None: the batch)."""

    def __init__(self, reason: str, path: str | None = None) -> None:
        super().__init__(f"{path}: {reason}" if path else reason)
        self.reason = reason
        self.path = path


@dataclass(frozen=True)
class Snapshot:
    """Values of one watch, all read between the same two scans."""

    scan: int                   # the scan (0-based) whose end state this is
    now_ns: int                 # that scan's start time on the VM clock (virtual or real time)
    values: Mapping[str, Any]   # path → Python value (see stvm.semantics.types for the table)
    version: int                # increases with every new snapshot of this watch


class Watch:
    """A set of paths sampled by the VM thread; `latest()` is safe from any thread."""

    def __init__(self, bridge: "VariableBridge", paths: list[str], every_ns: int,
                 on_snapshot: Callable[[Snapshot], None] | None, every_wall_ns: int = 0) -> None:
        self.bridge = bridge
        self.paths = list(paths)
        self.every_ns = max(0, int(every_ns))
        self.every_wall_ns = max(0, int(every_wall_ns))
        self.on_snapshot = on_snapshot
        self._accessors = [bridge.vm.accessor(p) for p in self.paths]
        self._next_ns = 0
        self._next_wall_ns = 0
        self._version = 0
        self._latest: Snapshot | None = None

    def latest(self) -> Snapshot | None:
        """The newest snapshot, or None before the first sample."""
        return self._latest

    def close(self) -> None:
        self.bridge._remove_watch(self)

    def _sample(self, vm: VM) -> None:
        # VM thread, between scans. A path through a VAR_IN_OUT not bound yet reads as None.
        values = {}
        for path, accessor in zip(self.paths, self._accessors):
            try:
                values[path] = accessor.get()
            except UnboundInOut:
                values[path] = None
        self._version += 1
        snapshot = Snapshot(vm.scan_count, vm.now_ns, values, self._version)
        self._latest = snapshot   # one reference assignment: readers see the old or the new one
        if self.on_snapshot is not None:
            self.on_snapshot(snapshot)


class VariableBridge:
    """Attach front ends to a VM. Create it in the VM's thread before the run starts."""

    def __init__(self, vm: VM, max_pending: int = MAX_PENDING_WRITES) -> None:
        self.vm = vm
        self._pending: queue.Queue = queue.Queue(maxsize=max_pending)
        self._watches: list[Watch] = []
        self._lock = threading.Lock()
        vm.on_scan_start.append(self._apply_pending)
        vm.on_scan_end.append(self._sample_due)

    # ---- reads
    def type_of(self, path: str) -> t.Type:
        """The ST type of `path` (raises `PathError` for an unknown path)."""
        return self.vm.accessor(path).type

    def watch(self, paths: Iterable[str], every_ns: int = 0,
              on_snapshot: Callable[[Snapshot], None] | None = None, every_wall_ns: int = 0) -> Watch:
        """Sample `paths` between scans, at most once per scan, `every_ns` VM-time apart and
        `every_wall_ns` wall-clock time apart (0: no limit).

        `on_snapshot` runs in the VM thread: it must only hand the snapshot over (for example
        `loop.call_soon_threadsafe`), never block."""
        watch = Watch(self, list(paths), every_ns, on_snapshot, every_wall_ns)
        with self._lock:
            self._watches = self._watches + [watch]
        return watch

    def _remove_watch(self, watch: Watch) -> None:
        with self._lock:
            self._watches = [w for w in self._watches if w is not watch]

    def format(self, path: str, value: Any) -> str:
        """`value` of `path` as the IEC literal `--print` shows (safe from any thread)."""
        return format_value(value, self.type_of(path), self.vm.model.pous)

    def _sample_due(self, vm: VM) -> None:
        now = vm.now_ns
        wall = 0
        for watch in self._watches:   # the list is replaced, never mutated: no lock needed here
            if now >= watch._next_ns:
                if watch.every_wall_ns:
                    wall = wall or time.monotonic_ns()
                    if wall < watch._next_wall_ns:
                        continue
                    watch._next_wall_ns = wall + watch.every_wall_ns
                watch._next_ns = now + watch.every_ns
                watch._sample(vm)

    # ---- writes
    def parse(self, path: str, text: str) -> Any:
        """IEC literal `text` (as `--set` takes it) as the Python value `submit` takes for `path`.

        Raises `WriteRejected` for an unknown path or text that is no literal of the type."""
        from stvm.cli import literal_value   # Choice: the one literal reader `--set` uses
        try:
            ty = self.vm.accessor(path).type
        except PathError as exc:
            raise WriteRejected(str(exc), path) from None
        try:
            value = literal_value(text, ty)
        except ValueError as exc:
            raise WriteRejected(str(exc), path) from None
        if isinstance(ty, t.StringType):
            # Choice: a front end's text that does not fit is refused, not cut to the length
            # (an ST assignment truncates; an operator should see that the text was too long)
            data = value.encode("utf-8") if isinstance(value, str) else bytes(value)
            if len(data) > ty.max_bytes:
                raise WriteRejected(f"{len(data)} bytes is longer than {ty.name} ({ty.max_bytes} bytes)", path)
        try:
            return coerce_python_value(value, ty)
        except ValueError as exc:
            raise WriteRejected(str(exc), path) from None

    def submit(self, values: Mapping[str, Any]) -> Future:
        """Queue `{path: Python value}` for the start of the next scan.

        Raises `WriteRejected` at once for an unknown path or a value the type cannot hold; the
        returned future completes (result None) once the VM thread has applied the whole batch,
        or fails with `WriteRejected` if it could not (nothing of the batch is then applied)."""
        checked: list[tuple[Any, Any, str]] = []
        for path, value in values.items():
            try:
                accessor = self.vm.accessor(path)
            except PathError as exc:
                raise WriteRejected(str(exc), path) from None
            try:
                checked.append((accessor, coerce_python_value(value, accessor.type), path))
            except ValueError as exc:
                raise WriteRejected(str(exc), path) from None
        future: Future = Future()
        try:
            self._pending.put_nowait((checked, future))
        except queue.Full:
            raise WriteRejected("busy: too many writes waiting for the next scan") from None
        return future

    def _apply_pending(self, vm: VM) -> None:
        pending = self._pending
        # only the batches queued before this scan started: one submitted while these are applied
        # (say, in reply to an earlier one being done) waits for the next scan
        for _ in range(pending.qsize()):
            try:
                checked, future = pending.get_nowait()
            except queue.Empty:
                return
            if not future.set_running_or_notify_cancel():
                continue
            # resolve every target first, so a batch that cannot be applied whole changes nothing
            try:
                targets = [(accessor.bind(), value) for accessor, value, _ in checked]
            except PathError as exc:
                future.set_exception(WriteRejected(str(exc)))
                continue
            for setter, value in targets:
                setter(value)
            future.set_result(None)
