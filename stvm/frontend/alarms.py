"""Alarms: every FB instance's `Error` / `ErrorID` / `ErrorDescrip` outputs, and a fault of the VM.

Detection. `AlarmList.attach(bridge)` finds every FB instance (in programs, globals, structs and
arrays: the catalog's tree) whose type has a BOOL output `Error`, and watches those outputs with
one flag watch of the bridge (`VariableBridge.watch_flags`): after each scan the VM thread runs one
generated probe that reads the Error flag of every source without an active error and, for a
source whose Error is TRUE, its Error, ErrorID and ErrorDescrip compared with their last values.
Only a difference makes a snapshot (all the outputs, read at that scan) and reaches `_on_change`,
so an alarm's VM time is the scan that changed and its code and text are what the FB output then;
ErrorID/ErrorDescrip changing while Error is FALSE change no alarm and cost nothing. The thesis
project has 35 such instances: 35 flag reads a scan while no error is active.

Model (after ISA-18.2 / OPC UA Part 9's AlarmConditionType, simplified):

    rising Error          → a new alarm: active, unacknowledged; raised_at = host time, VM time
    ErrorID/text change   → the active alarm's code/text are updated (same alarm)
    falling Error         → active = False (returned); it stays listed until acknowledged
    acknowledge(id)       → acknowledged = True; an alarm returned and acknowledged leaves the
                            active list (`current()`) but stays in the history (`history()`)
    VM fault              → source "VM", code None, text the fault message (`poll_vm`)

One list per VM: `attach` hands every front end of a VM (the HMI, the OPC UA server) the same
list, so an alarm acknowledged in one is acknowledged in all; each `attach` is matched by a
`close()`, and the last one stops the watch.

Listeners (`subscribe(fn)`) are called with the `Alarm` after every change, in the thread that made
it (the VM thread for FB alarms, the caller's for acknowledge/poll_vm): they must only hand it
over (`loop.call_soon_threadsafe`), never block. Everything else is safe from any thread.
"""

from __future__ import annotations

import threading
import time
import weakref
from collections import deque
from dataclasses import dataclass, replace
from datetime import datetime, timezone
from typing import Any, Callable

from stvm.semantics import types as t

# id(vm) → its list while attached; weak: a VM dropped without close() takes its list with it
_SHARED: "weakref.WeakValueDictionary[int, AlarmList]" = weakref.WeakValueDictionary()
_SHARED_LOCK = threading.Lock()

HISTORY = 500
"""Alarms kept after they returned and were acknowledged (newest first in `history()`)."""


@dataclass(frozen=True)
class AlarmSource:
    """One FB instance whose outputs raise an alarm."""

    path: str                   # `PnP_Example_Instance.MoveRel` (the instance's stvm path)
    fb_type: str                # `CBT_MoveRelative`
    error: str                  # path of its Error output
    code: str | None            # path of ErrorID (None: the FB has none)
    text: str | None            # path of ErrorDescrip (None: the FB has none)


@dataclass(frozen=True)
class Alarm:
    id: int                     # increases with every new alarm of this list
    source: str                 # FB instance path, or "VM" for a fault of the VM
    fb_type: str
    code: int | None
    text: str
    active: bool
    acknowledged: bool
    raised_at: float            # host time (seconds since the epoch) the VM saw the rising edge
    raised_vm_ns: int           # VM clock at the scan that raised it
    cleared_at: float | None = None
    severity: int = 700         # OPC UA severity 1..1000: FB errors 700, a VM fault 1000

    @property
    def time_text(self) -> str:
        return datetime.fromtimestamp(self.raised_at, timezone.utc).astimezone().strftime("%Y-%m-%d %H:%M:%S")

    def as_json(self) -> dict[str, Any]:
        return {"id": self.id, "source": self.source, "fb_type": self.fb_type, "code": self.code,
                "code_text": "" if self.code is None else f"16#{self.code:04X}", "text": self.text,
                "active": self.active, "acknowledged": self.acknowledged, "time": self.time_text,
                "raised_at": self.raised_at, "cleared_at": self.cleared_at, "severity": self.severity}


def find_sources(vm: Any) -> list[AlarmSource]:
    """Every FB instance of the running project with a BOOL output `Error`, in catalog order."""
    from stvm.runtime.catalog import catalog   # lazy: start-up
    sources = []
    for root in catalog(vm):
        for node in root.walk():
            if not isinstance(node.type, t.FBType) or node.type.is_program:
                continue
            members = {c.name.lower(): c for c in node.children}
            error = members.get("error")
            if error is None or not isinstance(error.type, t.BoolType) or error.section != "VAR_OUTPUT":
                continue
            code = members.get("errorid")
            text = members.get("errordescrip") or members.get("errortext")
            sources.append(AlarmSource(
                node.path, node.type.name, error.path,
                code.path if code is not None and isinstance(code.type, t.IntType) else None,
                text.path if text is not None and isinstance(text.type, t.StringType) else None))
    return sources


class AlarmList:
    """The alarms of one VM (see the module docstring)."""

    def __init__(self, sources: list[AlarmSource] | None = None, clock: Callable[[], float] = time.time) -> None:
        self.sources = list(sources or [])
        self.clock = clock
        self._lock = threading.Lock()
        self._next_id = 1
        self._active: dict[str, Alarm] = {}          # source → its current alarm (active or unacked)
        self._history: deque[Alarm] = deque(maxlen=HISTORY)
        self._listeners: list[Callable[[Alarm], None]] = []
        self._watch = None
        self._paths: list[str] = []
        self._fault_seen = False
        self._users = 0
        self.version = 0                              # increases with every change

    # ---- wiring
    @classmethod
    def attach(cls, bridge: Any, clock: Callable[[], float] = time.time) -> "AlarmList":
        """The alarm list of `bridge.vm`, watching every FB instance with an Error output: the one
        already attached to that VM if a front end has it (then `clock` is that list's)."""
        with _SHARED_LOCK:
            alarms = _SHARED.get(id(bridge.vm))
            if alarms is not None and alarms.vm is bridge.vm:
                alarms._users += 1
                return alarms
            alarms = cls._watching(bridge, clock)
            alarms._users = 1
            _SHARED[id(bridge.vm)] = alarms
            return alarms

    @classmethod
    def _watching(cls, bridge: Any, clock: Callable[[], float]) -> "AlarmList":
        alarms = cls(find_sources(bridge.vm), clock)
        alarms.vm = bridge.vm
        groups = [tuple(p for p in (s.error, s.code, s.text) if p is not None) for s in alarms.sources]
        alarms._paths = [path for group in groups for path in group]
        if groups:
            # ErrorID/ErrorDescrip change nothing while Error is FALSE (`update`): only the Error
            # flags are read every scan, a source's code and text only while its Error is TRUE
            alarms._watch = bridge.watch_flags(groups, on_snapshot=alarms._on_change)
        return alarms

    def close(self) -> None:
        """Release this front end's use; the last user's close stops the watch."""
        with _SHARED_LOCK:
            self._users = max(0, self._users - 1)
            if self._users:
                return
            vm = getattr(self, "vm", None)
            if vm is not None and _SHARED.get(id(vm)) is self:
                del _SHARED[id(vm)]
        if self._watch is not None:
            self._watch.close()
            self._watch = None

    def subscribe(self, listener: Callable[[Alarm], None]) -> Callable[[], None]:
        """Call `listener(alarm)` after every change; returns a function that unsubscribes."""
        with self._lock:
            self._listeners = self._listeners + [listener]

        def unsubscribe() -> None:
            with self._lock:
                self._listeners = [fn for fn in self._listeners if fn is not listener]
        return unsubscribe

    # ---- detection
    def _on_change(self, snapshot) -> None:
        values = snapshot.values
        for source in self.sources:
            error = bool(values.get(source.error))
            code = values.get(source.code) if source.code else None
            text = _text(values.get(source.text)) if source.text else ""
            self.update(source, error, code, text, snapshot.now_ns)

    def update(self, source: AlarmSource, error: bool, code: int | None, text: str, vm_ns: int = 0) -> None:
        """The state of one source's outputs (called by the watch; tests may call it directly)."""
        changed: Alarm | None = None
        with self._lock:
            current = self._active.get(source.path)
            if error and (current is None or not current.active):
                changed = Alarm(self._next_id, source.path, source.fb_type, code, text, True, False,
                                self.clock(), vm_ns)
                self._next_id += 1
                if current is not None:          # returned but not acknowledged: superseded
                    self._history.appendleft(current)
                self._active[source.path] = changed
            elif error and (current.code != code or current.text != text):
                changed = replace(current, code=code, text=text)
                self._active[source.path] = changed
            elif not error and current is not None and current.active:
                changed = replace(current, active=False, cleared_at=self.clock())
                if changed.acknowledged:
                    del self._active[source.path]
                    self._history.appendleft(changed)
                else:
                    self._active[source.path] = changed
            if changed is not None:
                self.version += 1
        if changed is not None:
            self._notify(changed)

    def poll_vm(self, vm: Any | None = None) -> Alarm | None:
        """Raise the VM-fault alarm once if the VM stopped on a fault (call from any thread)."""
        vm = vm if vm is not None else getattr(self, "vm", None)
        fault = getattr(vm, "fault", None) if vm is not None else None
        if fault is None or self._fault_seen:
            return None
        self._fault_seen = True
        message = getattr(fault, "message", None) or str(fault)
        source = AlarmSource("VM", "VM", "", None, None)
        with self._lock:
            alarm = Alarm(self._next_id, "VM", "VM", None, f"the VM stopped on a fault: {message}",
                          True, False, self.clock(), getattr(fault, "now_ns", 0) or 0, severity=1000)
            self._next_id += 1
            self._active[source.path] = alarm
            self.version += 1
        self._notify(alarm)
        return alarm

    # ---- operator
    def acknowledge(self, alarm_id: int) -> Alarm | None:
        """Acknowledge one alarm (None: no current alarm has that id)."""
        with self._lock:
            for key, alarm in self._active.items():
                if alarm.id == alarm_id:
                    break
            else:
                return None
            if alarm.acknowledged:
                return alarm
            alarm = replace(alarm, acknowledged=True)
            if alarm.active:
                self._active[key] = alarm
            else:
                del self._active[key]
                self._history.appendleft(alarm)
            self.version += 1
        self._notify(alarm)
        return alarm

    def acknowledge_all(self) -> int:
        ids = [a.id for a in self.current() if not a.acknowledged]
        for alarm_id in ids:
            self.acknowledge(alarm_id)
        return len(ids)

    # ---- reading
    def current(self) -> list[Alarm]:
        """Active or unacknowledged alarms, newest first."""
        with self._lock:
            return sorted(self._active.values(), key=lambda a: -a.id)

    def history(self) -> list[Alarm]:
        """Alarms that returned and were acknowledged, newest first (at most HISTORY)."""
        with self._lock:
            return list(self._history)

    def _notify(self, alarm: Alarm) -> None:
        for listener in self._listeners:
            try:
                listener(alarm)
            except Exception:   # noqa: BLE001 - a front end's bug must not stop the scan
                pass


def _text(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, (bytes, bytearray)):
        return bytes(value).decode("utf-8", "replace")
    return str(value)
