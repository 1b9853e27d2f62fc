"""The bridge between the scan loop (the VM thread) and front ends running in other threads.

The VM owns time (design: "Front ends beside the scan loop"). A front end never reads or writes a
variable itself:

* **Reads** come from a `Snapshot`: the values of a `Watch`'s paths, all taken by the VM thread at
  the end of one scan, so every value in it belongs to the same instant. A watch samples at most
  once per scan, at least `every_ns` of VM time apart and, if asked, `every_wall_ns` of wall-clock
  time apart (on the virtual clock VM time may run many times faster than a display needs);
  sampling costs the scan loop one call of a generated reader (about 0.05 µs a value) and nothing
  when no watch is due.
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

* **One-shot reads** (`sample(paths)`) are answered by the VM thread at the next point between two
  scans: the end of the running scan, or at once when the VM is held between scans (a paused
  `RunControl`, a debugger stopped after a scan: they call the `vm.on_idle` hooks). A front end that reads values nobody watches (an OPC UA Read) costs the
  scan loop only those paths, once.
"""

from __future__ import annotations

import queue
import threading
import time
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Mapping

from stvm.runtime.catalog import Catalog
from stvm.runtime.format import format_value
from stvm.runtime.vm import VM, PathError, UnboundInOut, coerce_python_value
from stvm.semantics import types as t
from stvm.semantics.literals import literal_value   # Choice: the one literal reader `--set` uses
from stvm.trace.signals import Signal, build_reader, compile_reads, make_sampler

MAX_PENDING_WRITES = 1024
"""Write batches queued for the next scan; more are rejected (a front end cannot stall the VM)."""

MAX_PENDING_SAMPLES = 1024
"""One-shot read requests waiting for the next point between scans; more are rejected ("busy")."""


class WriteRejected(ValueError):
    """A write batch that was not applied; `path` names the offending variable (None: the batch)."""

    def __init__(self, reason: str, path: str | None = None) -> None:
        super().__init__(f"{path}: {reason}" if path else reason)
        self.reason = reason
        self.path = path


@dataclass(frozen=True)
class Snapshot:
    """Values of one watch, all read between the same two scans."""

    scan: int                   # the scan (0-based) whose end state this is; -1: before the first scan
    now_ns: int                 # that scan's start time on the VM clock (virtual or real time)
    values: Mapping[str, Any]   # path → Python value (see stvm.semantics.types for the table)
    version: int                # increases with every new snapshot of this watch


class SnapshotValues(Mapping):
    """The values of one snapshot as a read-only mapping path -> value. The VM thread only keeps
    the sampled tuple (one step, no dict per scan); the dict is built on the first look, in the
    front end's thread."""

    __slots__ = ("_paths", "_values", "_dict")

    def __init__(self, paths: list[str], values: tuple) -> None:
        self._paths = paths
        self._values = values
        self._dict: dict[str, Any] | None = None

    def _mapping(self) -> dict[str, Any]:
        mapping = self._dict
        if mapping is None:   # two threads may both build it: the same dict either way
            mapping = self._dict = dict(zip(self._paths, self._values))
        return mapping

    def __getitem__(self, path: str) -> Any:
        return self._mapping()[path]

    def __iter__(self):
        return iter(self._mapping())

    def __len__(self) -> int:
        return len(self._mapping())

    def items(self):
        return self._mapping().items()

    def __repr__(self) -> str:
        return repr(self._mapping())


class Watch:
    """A set of paths sampled by the VM thread; `latest()` is safe from any thread."""

    def __init__(self, bridge: "VariableBridge", paths: list[str], every_ns: int,
                 on_snapshot: Callable[[Snapshot], None] | None, every_wall_ns: int = 0,
                 changes_only: bool = False) -> None:
        self.bridge = bridge
        self.paths = list(paths)
        self.every_ns = max(0, int(every_ns))
        self.every_wall_ns = max(0, int(every_wall_ns))
        self.on_snapshot = on_snapshot
        self.changes_only = changes_only
        self._read = bridge._reader(self.paths)   # raises PathError for an unknown path
        self._last: tuple | None = None
        self._next_ns = 0
        self._next_wall_ns = 0
        self._version = 0
        self._latest: Snapshot | None = None

    def latest(self) -> Snapshot | None:
        """The newest snapshot, or None before the first sample."""
        return self._latest

    def close(self) -> None:
        self.bridge._remove_watch(self)

    def _sample(self, scan: int, now_ns: int) -> None:
        # VM thread, between scans.
        values = self._read()
        if self.changes_only:
            if values == self._last:
                return          # nothing changed: no snapshot, nothing handed over
            self._last = values
        self._emit(scan, now_ns, values)

    def _emit(self, scan: int, now_ns: int, values: tuple) -> None:
        self._version += 1
        snapshot = Snapshot(scan, now_ns, SnapshotValues(self.paths, values), self._version)
        self._latest = snapshot   # one reference assignment: readers see the old or the new one
        if self.on_snapshot is not None:
            self.on_snapshot(snapshot)


class FlagWatch(Watch):
    """A watch of groups `(flag, detail, ...)` whose details matter only while the flag is TRUE
    (an FB's `Error` and its `ErrorID` / `ErrorDescrip`); made by `VariableBridge.watch_flags`.

    Every scan end the VM thread calls one generated probe: it reads the flag of each group whose
    flag was FALSE at the last snapshot (`a.v_error or b.v_error or ...`, stopping at the first
    TRUE) and, for the groups whose flag was TRUE, the whole group compared with its last values
    as one tuple. Only when the probe finds a difference are all paths read (by the watch's one
    reader) and a snapshot made, at that scan, so a flag TRUE for one scan is never missed and the
    snapshot holds every value of that scan. A detail that changes while its flag stays FALSE makes
    no snapshot. One probe is compiled per set of TRUE flags (kept, so a flag that comes and goes
    compiles nothing new). The probe starts each read at the deepest FB instance its path reaches
    through members alone (`VariableBridge._anchored`): one attribute read per flag. A path the
    compiled readers cannot reach (through a VAR_IN_OUT) makes this an ordinary `changes_only`
    watch of every path."""

    MAX_PROBES = 64   # compiled probes kept (one per set of TRUE flags seen)

    def __init__(self, bridge: "VariableBridge", groups: list[tuple[str, ...]],
                 on_snapshot: Callable[[Snapshot], None] | None) -> None:
        paths = [path for group in groups for path in group]
        super().__init__(bridge, paths, 0, on_snapshot, changes_only=True)
        self._spans: list[tuple[int, int]] = []
        start = 0
        for group in groups:
            self._spans.append((start, start + len(group)))
            start += len(group)
        self._signals = bridge._signals(paths)   # None: some path has no compiled route
        self._probes: dict[tuple[int, ...], Callable[[tuple], bool]] = {}
        self._probe: Callable[[tuple], bool] | None = None   # None: the next sample reads all
        self._hot_last: tuple = ()
        if self._signals is not None:
            self._probe_for(())   # compiled here, not in the VM thread: the probe of "no flag TRUE"

    def _sample(self, scan: int, now_ns: int) -> None:
        # VM thread, between scans.
        probe = self._probe
        if probe is not None and not probe(self._hot_last):
            return              # no flag rose, no TRUE group changed: nothing read, nothing handed over
        values = self._read()
        if values == self._last:
            return
        self._last = values
        if self._signals is not None:
            spans = self._spans
            hot = tuple(i for i, (start, _) in enumerate(spans) if values[start])
            self._hot_last = tuple(v for i in hot for v in values[spans[i][0]:spans[i][1]])
            self._probe = self._probe_for(hot)
        self._emit(scan, now_ns, values)

    def _probe_for(self, hot: tuple[int, ...]) -> Callable[[tuple], bool]:
        probe = self._probes.get(hot)
        if probe is None:
            if len(self._probes) >= self.MAX_PROBES:
                self._probes.clear()
            hot_set = set(hot)
            signals = self._signals
            cold = [signals[start] for i, (start, _) in enumerate(self._spans) if i not in hot_set]
            hot_signals = [signal for i in hot for signal in signals[self._spans[i][0]:self._spans[i][1]]]
            anchored = self.bridge._anchored
            probe = self._probes[hot] = make_probe([anchored(s) for s in cold], [anchored(s) for s in hot_signals])
        return probe


def make_probe(flags: list[Signal], group: list[Signal]) -> Callable[[tuple], bool]:
    """A compiled `probe(last)`: whether one of `flags` is TRUE or the values of `group` differ
    from the tuple `last`, reading from the roots as `make_sampler` does (shared prefixes once,
    one attribute or item access per step; only validated storage names and integer indices go
    into the text) and stopping at the first TRUE flag."""
    reads = compile_reads(flags + group)
    tests = reads.expressions[:len(flags)]
    if group:
        tests.append(f"({', '.join(reads.expressions[len(flags):])},) != last")
    return build_reader(reads, "probe", "last", " or ".join(tests) or "False", "<stvm-bridge-probe>")


def _read_all(paths: list[str], accessors: list) -> dict[str, Any]:
    """VM thread, between scans. A path through a VAR_IN_OUT not bound yet reads as None."""
    values = {}
    for path, accessor in zip(paths, accessors):
        try:
            values[path] = accessor.get()
        except UnboundInOut:
            values[path] = None
    return values


class VariableBridge:
    """Attach front ends to a VM. Create it in the VM's thread before the run starts."""

    def __init__(self, vm: VM, max_pending: int = MAX_PENDING_WRITES) -> None:
        self.vm = vm
        self._pending: queue.Queue = queue.Queue(maxsize=max_pending)
        self._samples: queue.Queue = queue.Queue(maxsize=MAX_PENDING_SAMPLES)
        self._watches: list[Watch] = []
        self._routes: dict | None = None   # path → (type, root, steps), built on the first watch
        self._fb_routes: set | None = None   # (id(root), steps) of every FB instance, for `_anchored`
        self._lock = threading.Lock()
        # `_apply_pending` is a scan-start hook only while writes wait (`_arm`): a scan without
        # writes calls nothing of the bridge before it
        self._armed = False
        self._arm_lock = threading.Lock()
        vm.on_scan_end.append(self._sample_due)
        vm.on_idle.append(self.serve_between_scans)

    # ---- reads
    def type_of(self, path: str) -> t.Type:
        """The ST type of `path` (raises `PathError` for an unknown path)."""
        return self.vm.accessor(path).type

    def watch(self, paths: Iterable[str], every_ns: int = 0,
              on_snapshot: Callable[[Snapshot], None] | None = None, every_wall_ns: int = 0,
              changes_only: bool = False) -> Watch:
        """Sample `paths` between scans, at most once per scan, `every_ns` VM-time apart and
        `every_wall_ns` wall-clock time apart (0: no limit).

        `on_snapshot` runs in the VM thread: it must only hand the snapshot over (for example
        `loop.call_soon_threadsafe`), never block. With `changes_only`, a sample equal to the
        previous one makes no snapshot (a subscriber that forwards changes pays one comparison)."""
        watch = Watch(self, list(paths), every_ns, on_snapshot, every_wall_ns, changes_only)
        with self._lock:
            self._watches = self._watches + [watch]
        return watch

    def watch_flags(self, groups: Iterable[Iterable[str]],
                    on_snapshot: Callable[[Snapshot], None] | None = None) -> FlagWatch:
        """Watch groups of paths `(flag, detail, ...)` at every scan end, where a group's details
        matter only while its BOOL flag is TRUE (an FB's Error, ErrorID, ErrorDescrip: the alarm
        list). A snapshot of every path is made at the scan where a flag changed or a detail of a
        group whose flag is TRUE changed; the scan loop pays one read per FALSE flag otherwise
        (see `FlagWatch`). `on_snapshot` runs in the VM thread, as for `watch`."""
        watch = FlagWatch(self, [tuple(group) for group in groups], on_snapshot)
        with self._lock:
            self._watches = self._watches + [watch]
        return watch

    def read_now(self, paths: Iterable[str]) -> dict[str, Any]:
        """The values of `paths` read at once: only in the VM's thread between two scans, or before
        the run starts (a front end's initial values). Raises `PathError` for an unknown path."""
        paths = list(paths)
        return dict(zip(paths, self._reader(paths)()))

    def _reader(self, paths: list[str]) -> Callable[[], tuple]:
        """A function returning the values of `paths` as a tuple, for the VM thread.

        Paths the trace's compiled sampler can reach (every variable the catalog lists) are read
        by one generated function, one attribute or item access per step from the globals or a
        program instance (~0.05 µs a value instead of a path lookup per value); the rest (paths
        through a VAR_IN_OUT) through their accessors."""
        fast: list[Signal] = []
        slow: list[int] = []
        for index, path in enumerate(paths):
            signal = self._signal(path)
            if signal is None:
                slow.append(index)
            else:
                fast.append(signal)
        sampler = make_sampler(fast) if fast else (lambda: ())
        if not slow:
            return sampler
        slow_paths = [paths[i] for i in slow]
        slow_accessors = [self.vm.accessor(p) for p in slow_paths]
        order = [i for i in range(len(paths)) if i not in set(slow)] + slow

        def read() -> tuple:
            merged = sampler() + tuple(_read_all(slow_paths, slow_accessors).values())
            values = [None] * len(paths)
            for position, value in zip(order, merged):
                values[position] = value
            return tuple(values)
        return read

    def _index(self) -> dict:
        """path → (type, root, steps) of every variable the catalog lists, built once, on the first
        watch, in the thread that makes it (the catalog walk takes a while on a large project)."""
        if self._routes is None:
            nodes = [node for node in Catalog(self.vm).walk() if node.kind != "program"]
            self._fb_routes = {(id(node.root), tuple(node.steps)) for node in nodes
                               if isinstance(node.type, t.FBType) and not node.type.is_program}
            self._routes = {node.path.lower(): (node.type, node.root, node.steps) for node in nodes}
        return self._routes

    def _signal(self, path: str) -> Signal | None:
        """How a compiled reader reaches `path` (None: not from a root, e.g. through a VAR_IN_OUT)."""
        route = self._index().get(path.lower().replace(" ", ""))
        if route is None or route[0].kind not in ("bool", "int", "real", "time", "string", "enum"):
            return None
        return Signal(path, *route)

    def _anchored(self, signal: Signal) -> Signal:
        """`signal` read from the deepest FB instance its route reaches through members alone (no
        array element) instead of from its root, for readers compiled once and called every scan.

        Such an instance object lives as long as the VM: an ST assignment of an FB instance copies
        into it (`_assign`), `vm.set` refuses FB values, and programs and globals are made once.
        An array's elements can be replaced (an array assigned as a whole stores copies), so an
        index ends the anchor."""
        self._index()
        depth = 0
        for k, step in enumerate(signal.steps[:-1]):
            if not isinstance(step, str) or (id(signal.root), tuple(signal.steps[:k + 1])) not in self._fb_routes:
                break
            depth = k + 1
        if depth == 0:
            return signal
        instance = signal.root
        for step in signal.steps[:depth]:
            instance = getattr(instance, step)
        return Signal(signal.name, signal.type, instance, tuple(signal.steps[depth:]))

    def _signals(self, paths: list[str]) -> list[Signal] | None:
        """The compiled routes of every path, or None if one has none."""
        signals = [self._signal(path) for path in paths]
        return None if None in signals else signals   # type: ignore[return-value]

    def _remove_watch(self, watch: Watch) -> None:
        with self._lock:
            self._watches = [w for w in self._watches if w is not watch]

    def format(self, path: str, value: Any) -> str:
        """`value` of `path` as the IEC literal `--print` shows (safe from any thread)."""
        return format_value(value, self.type_of(path), self.vm.layouts)

    def sample(self, paths: Iterable[str]) -> Future:
        """One snapshot of `paths`, taken by the VM thread at the next point between two scans.

        Raises `PathError` at once for an unknown path and `WriteRejected("busy")` when too many
        requests wait; the future's result is a `Snapshot` (version 0). It stays pending while
        the VM is stopped inside a scan (a debugger breakpoint): callers wait with a timeout."""
        paths = list(paths)
        accessors = [self.vm.accessor(p) for p in paths]
        future: Future = Future()
        try:
            self._samples.put_nowait((paths, accessors, future))
        except queue.Full:
            raise WriteRejected("busy: too many reads waiting for the next scan") from None
        return future

    def serve_between_scans(self, vm: VM) -> None:
        """Apply queued writes and answer one-shot reads now (a `vm.on_idle` hook: called by a loop
        holding the VM between two scans, a paused `RunControl` or a debugger stopped after a scan),
        so a paused controller still reads and writes. Watches sample again after a write, so their
        snapshots show the written values."""
        # the VM waits before scan `vm.scan_count`: the state is the end of the scan before it
        scan, now_ns = vm.scan_count - 1, max(0, vm.now_ns - vm.base_ns)
        if not self._pending.empty():
            self._apply_pending(vm)
            for watch in self._watches:
                watch._sample(scan, now_ns)
        self._answer_samples(scan, now_ns)

    def _sample_due(self, vm: VM) -> None:
        now = vm.now_ns
        wall = 0
        for watch in self._watches:   # the list is replaced, never mutated: no lock needed here
            if now >= watch._next_ns:
                if watch.every_wall_ns:
                    wall = wall or time.monotonic_ns()
                    if wall < watch._next_wall_ns:
                        # VM time runs faster than the wall clock (a virtual clock): the wall
                        # interval ends at the earliest this much VM time later, so the clock is
                        # not read at every scan until then
                        watch._next_ns = now + (watch._next_wall_ns - wall)
                        continue
                    watch._next_wall_ns = wall + watch.every_wall_ns
                watch._next_ns = now + watch.every_ns
                watch._sample(vm.scan_count, now)
        if self._samples.queue:   # (the deque itself: `empty()` takes the queue's lock every scan)
            self._answer_samples(vm.scan_count, now)
        if self._armed and not self._pending.queue:
            self._disarm()

    def _answer_samples(self, scan: int, now_ns: int) -> None:
        while True:
            try:
                paths, accessors, future = self._samples.get_nowait()
            except queue.Empty:
                return
            if future.set_running_or_notify_cancel():
                future.set_result(Snapshot(scan, now_ns, _read_all(paths, accessors), 0))

    # ---- writes
    def parse(self, path: str, text: str) -> Any:
        """IEC literal `text` (as `--set` takes it) as the Python value `submit` takes for `path`.

        Raises `WriteRejected` for an unknown path or text that is no literal of the type."""
        try:
            ty = self.vm.accessor(path).type
        except PathError as exc:
            raise WriteRejected(str(exc), path) from None
        try:
            value = literal_value(text, ty)
        except ValueError as exc:
            raise WriteRejected(str(exc), path) from None
        if t.is_wide(ty):
            units = coerce_python_value(value, t.WSTRING)   # its code units, not yet cut to ty
            if len(units) > ty.max_bytes:
                raise WriteRejected(f"{len(units)} code units is longer than {ty.name} ({ty.max_bytes})", path)
        elif isinstance(ty, t.StringType):
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
        self._arm()
        return future

    def _arm(self) -> None:
        """Any thread, after queueing a batch: make `_apply_pending` a scan-start hook. The VM
        thread takes it out again at a scan end that finds the queue empty (`_disarm`); the lock
        orders the two, so a batch queued meanwhile always finds the hook in place."""
        with self._arm_lock:
            if not self._armed:
                self._armed = True
                self.vm.on_scan_start.append(self._apply_pending)   # (list.append: atomic)

    def _disarm(self) -> None:
        # VM thread, in the scan-end hook: not while the VM iterates its scan-start hooks
        with self._arm_lock:
            if self._armed and not self._pending.queue:
                self._armed = False
                try:
                    self.vm.on_scan_start.remove(self._apply_pending)
                except ValueError:   # someone replaced the hook list: nothing to take out
                    pass

    def _apply_pending(self, vm: VM) -> None:
        pending = self._pending
        if not pending.queue:   # the common case, without `qsize()`'s lock (a deque's length is atomic)
            return
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
