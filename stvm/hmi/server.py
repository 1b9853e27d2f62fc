"""The web HMI: a Starlette app served by uvicorn in a thread beside the scan loop.

The VM stays the owner of time. Everything the server shows comes from `VariableBridge`
snapshots (taken by the VM thread between two scans), everything it writes goes through
`VariableBridge.submit` (applied at the start of the next scan, all of a batch or none of it).

Threads and queues (why a slow browser never slows the scan):

    VM thread       bridge watch → `_on_snapshot`: keeps the newest snapshot (and, in lockstep,
                    a copy of the robot's frames of the same instant) in one reference; it wakes
                    nobody (waking a thread costs the scan a system call, ~20 µs on a virtual
                    machine, and may hand the GIL to the server mid-scan), never waits for the
                    loop, formats nothing and touches no socket
    event loop      `_pump`: picks the newest snapshot up when the next one is due (the watch
                    samples every `update_ns` of wall time: it looks again that long after each
                    one it found, then every `PUMP_RETRY_S`, so a value waits at most a few ms)
                    `_publish`: compares with what was published, formats the changed values
                    only, merges them into each client's pending dict (latest value per path:
                    a client that cannot keep up skips intermediate values, its backlog is
                    bounded by the number of paths) and wakes each client's sender task
    sender tasks    one per WebSocket, sends what is pending, with a timeout; a client that
                    vanished or stalls is dropped

The watch covers only the pages that have a browser open, and of a page's pop-ups only the one
open (`{"popup": ID}` / `{"popup": null}` from the page); with no browser the scan pays nothing. It
samples at most every `update_ns` of VM time and of wall-clock time (20 per second by default).

HTTP contract (docs/hmi.md; kept stable for black-box tests):

    GET  /                       → redirect to /page/<start page>
    GET  /page/<Name>            the page (server-side HTML; widgets carry data-var/data-action)
    GET  /api/vars?path=P&…      {P: IEC literal} (variables some page shows)
    POST /api/vars {P: literal}  write (variables some page writes; others 403), 4xx + reason
    POST /api/presets/<name>     apply a preset (its steps in consecutive scans)
    GET  /api/pages              the pages and what they map (JSON)
    WS   /ws?page=<Name>         live values of that page: changed values only
"""

from __future__ import annotations

import asyncio
import secrets
import socket
import threading
from collections import deque
from typing import Any

import re
import time
from datetime import datetime

from stvm.numeric import utf16_text
from stvm.frontend import VariableBridge, WriteRejected
from stvm.frontend.alarms import AlarmList
from stvm.frontend.limits import LimitTable
from stvm.hmi.pages import Hmi, RunParameter, check_limits
from stvm.hmi.robot import PoseSource, robot_state
from stvm.hmi.app import build_app
from stvm.hmi.render import PageRenderer
from stvm.hmi.guard import ServerLimits, guarded_protocol, quiet_exception_handler
from stvm.hmi.wire import Client, Refused, is_loopback
from stvm.semantics import types as t

MAX_PATHS_PER_REQUEST = 512
WRITE_WAIT_S = 2.0                 # a write answers 200 once applied, 202 if the VM did not scan by then
UPDATE_NS = 50_000_000             # 20 updates per second (the issue asks for at least 10)
PUMP_RETRY_S = 0.002             # a snapshot not there yet when due: looked for again this soon
HEARTBEAT_S = 0.5                  # VM state and alarms reach every page at least this often
STALE_S = 1.0                      # no scan for this long: the page shows the VM as stopped
_DECIMAL = re.compile(r"[+-]?(\d+([.,]\d*)?|[.,]\d+)([eE][+-]?\d+)?\Z")



def _now_text() -> str:
    return datetime.now().strftime("%Y-%m-%d %H:%M:%S")


def _operator_time(literal: str) -> str:
    """`DT#2026-12-07-13:23:34.5` → `2026-12-07 13:23:34.5`; `D#…` → the date; `TOD#…` → the time."""
    body = literal.split("#", 1)[-1]
    if literal.upper().startswith(("DT#", "DATE_AND_TIME#", "LDT#")) and body.count("-") >= 3:
        date, _, clock = body.rpartition("-")
        return f"{date} {clock}"
    return body


def _labels(hmi: Hmi) -> dict[str, str]:
    """The operator's name of each variable: its widget's label (pop-up: with the pop-up title)."""
    labels: dict[str, str] = {}
    for page in hmi.pages.values():
        for popup in page.popups:
            for w in popup.widgets:
                if w.var and w.label and w.var not in labels:
                    labels[w.var] = f"{popup.title} › {w.label}"
        for area in page.areas:
            for w in area.widgets:
                if w.var and w.label and w.kind not in ("toggle", "momentary", "set"):
                    labels.setdefault(w.var, w.label)
        for w in page.widgets():
            if w.var and w.label:
                labels.setdefault(w.var, w.label)
    return labels


def machine_addresses(ipv6: bool = False) -> list[str]:
    """This machine's addresses another host can reach: the one its default route leaves by
    (a UDP socket "connected" to a documentation address sends nothing), the addresses its name
    resolves to, then its name; loopback addresses are left out."""
    found: dict[str, None] = {}
    probes = [(socket.AF_INET, "192.0.2.1")] + ([(socket.AF_INET6, "2001:db8::1")] if ipv6 else [])
    for family, probe in probes:
        try:
            with socket.socket(family, socket.SOCK_DGRAM) as s:
                s.connect((probe, 9))
                found[s.getsockname()[0]] = None
        except OSError:
            pass
    name = socket.gethostname()
    try:
        for info in socket.getaddrinfo(name, None, socket.AF_INET6 if ipv6 else socket.AF_INET):
            found[info[4][0]] = None
    except OSError:
        pass
    addresses = [a for a in found if not is_loopback(a.split("%")[0])]
    if name and name != "localhost":
        addresses.append(name)
    return addresses


class HmiServer:
    """Serve `hmi` for the VM behind `bridge`. `start()` binds (raises OSError if it cannot) and
    returns once the server accepts connections; `stop()` ends it and its thread."""

    def __init__(self, hmi: Hmi, bridge: VariableBridge, host: str = "127.0.0.1", port: int = 0,
                 token: str | None = None, pose: PoseSource | None = None,
                 run_parameters: dict[str, Any] | None = None, update_ns: int = UPDATE_NS,
                 limits: ServerLimits | None = None, limit_table: LimitTable | None = None,
                 alarms: AlarmList | None = None) -> None:
        self.hmi = hmi
        self.limits = limits or ServerLimits()
        # one source of limits (stvm/frontend/limits.py): the project's table, the pages merged in
        self.limit_table = limit_table if limit_table is not None else LimitTable.for_project(None, bridge.vm)
        self.limit_table.merge_pages(hmi.writable)
        self.alarms = alarms
        self.labels = _labels(hmi)
        self.vm_state: dict[str, Any] = {"state": "starting", "since": _now_text(), "reason": ""}
        self._last_scan_seen = -1
        self._last_scan_wall = time.monotonic()
        self._alarm_version = -1
        self.bridge = bridge
        self.host = host
        self.requested_port = port
        self.port = port
        self.token = token if token is not None else (None if is_loopback(host) else secrets.token_urlsafe(18))
        self.pose = pose
        self.run_parameters = dict(run_parameters or {})
        self.update_ns = update_ns
        self.loop: asyncio.AbstractEventLoop | None = None
        self.clients: set[Client] = set()
        self._raw: dict[str, Any] = {}
        self._shown: dict[str, Any] = {}
        self._scan = -1
        self._now_ns = 0
        self._robot: dict[str, Any] | None = None
        self._history_s = max((w.history_s for p in hmi.pages.values() for w in p.widgets()
                               if w.kind == "robot_view"), default=0.0)
        self._path: deque = deque(maxlen=20_000)
        self._watch = None
        self._watch_paths: tuple[str, ...] = ()
        self._latest: tuple | None = None
        self._server = None
        self._socket: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._failure: BaseException | None = None
        self.stats = {"published": 0, "dropped_clients": 0}
        self.renderer = PageRenderer(hmi, self.limit_table)

    # ------------------------------------------------------------------ lifecycle
    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        base = f"http://{host}:{self.port}/"
        return base + (f"?token={self.token}" if self.token else "")

    def urls(self) -> list[str]:
        """Addresses an operator can open: for a server on every interface (0.0.0.0, ::) the
        machine's own addresses and name instead of the unspecified address (issue 32 item 7)."""
        if self.host not in ("0.0.0.0", "::", ""):
            return [self.url]
        suffix = f":{self.port}/" + (f"?token={self.token}" if self.token else "")
        hosts = [h if ":" not in h else f"[{h}]" for h in machine_addresses(ipv6=self.host == "::")]
        return [f"http://{h}{suffix}" for h in hosts] or [self.url]

    def start(self) -> "HmiServer":
        import uvicorn
        family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((self.host, self.requested_port))
            sock.listen(128)
        except OSError:
            sock.close()
            raise
        sock.setblocking(False)
        self._socket = sock
        self.port = sock.getsockname()[1]
        lim = self.limits
        # every bound is a ServerLimits field (docs/hmi.md "Server limits"); the connection cap
        # and the header timeout are GuardedH11Protocol's, the rest uvicorn's own settings
        config = uvicorn.Config(self._app(), http=guarded_protocol(lim), log_level="warning", access_log=False,
                                lifespan="off", ws="websockets-sansio", ws_max_size=lim.ws_max_message_bytes,
                                ws_ping_interval=20.0, ws_ping_timeout=20.0, timeout_graceful_shutdown=1,
                                server_header=False, h11_max_incomplete_event_size=lim.max_header_bytes,
                                timeout_keep_alive=lim.keep_alive_s,
                                limit_concurrency=lim.max_connections + lim.max_websockets + 64,
                                backlog=min(2048, lim.max_connections * 2))
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(target=self._serve, name=f"stvm-hmi:{self.port}", daemon=True)
        self._thread.start()
        self._ready.wait(10)
        if self._failure is not None:
            raise RuntimeError(f"HMI server did not start: {self._failure}")
        return self

    def _serve(self) -> None:
        async def main() -> None:
            self.loop = asyncio.get_running_loop()
            self.loop.set_exception_handler(quiet_exception_handler)
            if self.alarms is None:
                self.alarms = AlarmList.attach(self.bridge)
            heartbeat = asyncio.create_task(self._heartbeat())
            pump = asyncio.create_task(self._pump())
            self._ready.set()
            try:
                await self._server.serve(sockets=[self._socket])
            finally:
                heartbeat.cancel()
                pump.cancel()
        try:
            asyncio.run(main())
        except BaseException as exc:   # noqa: BLE001 - reported by start()/stop(), never silently
            self._failure = exc
            self._ready.set()

    def stop(self, timeout_s: float = 5.0) -> None:
        if self._server is not None:
            self._server.should_exit = True
        if self._thread is not None:
            self._thread.join(timeout_s)
            self._thread = None
        if self._watch is not None:
            self._watch.close()
            self._watch = None
        if self.alarms is not None:
            self.alarms.close()
        if self._socket is not None:
            self._socket.close()
            self._socket = None

    # ------------------------------------------------------------------ VM thread
    def _on_snapshot(self, snapshot) -> None:
        pose = self.pose.read() if self.pose is not None and self.pose.in_vm_thread else None
        self._latest = (snapshot, pose)

    # ------------------------------------------------------------------ event loop
    async def _pump(self) -> None:
        """Publish each new snapshot soon after the VM thread took it, without being woken."""
        period = self.update_ns / 1e9
        delay = retry = PUMP_RETRY_S
        while True:
            await asyncio.sleep(delay)
            if self._latest is not None:
                try:
                    self._publish()
                except Exception:   # noqa: BLE001 - one bad update must not end the updates
                    pass
                delay = max(PUMP_RETRY_S, period - PUMP_RETRY_S)   # the next sample is about one period away
                retry = PUMP_RETRY_S
            else:   # not there yet: look again soon, less and less often while none comes (no page
                delay = retry   # open, the VM paused or slower than the update period)
                retry = min(retry * 1.5, max(period, PUMP_RETRY_S))

    def _publish(self) -> None:
        latest, self._latest = self._latest, None
        if latest is None:
            return
        snapshot, pose = latest
        if pose is None and self.pose is not None and not self.pose.in_vm_thread:
            pose = self.pose.read()
        elif pose is not None and self.pose.finish is not None:
            pose = self.pose.finish(pose)   # the costly part of a VM-thread reading, here
        changed: dict[str, Any] = {}
        raw_seen = self._raw
        for path, value in snapshot.values.items():
            if path not in raw_seen or raw_seen[path] != value or type(raw_seen[path]) is not type(value):
                raw_seen[path] = value
                shown = self._display(path, value)
                self._shown[path] = shown
                changed[path] = shown
        self._scan, self._now_ns = snapshot.scan, snapshot.now_ns
        robot = robot_state(pose)
        new_points: list = []
        if robot is not None:
            self._robot = robot
            point = [round(snapshot.now_ns / 1e9, 3)] + robot["pose"][:3]
            if not self._path or self._path[-1][1:] != point[1:]:
                self._path.append(point)
                new_points.append(point)
            horizon = point[0] - self._history_s
            while self._path and self._path[0][0] < horizon:
                self._path.popleft()
        self.stats["published"] += 1
        for client in list(self.clients):
            client.offer(self, changed, robot, new_points)

    async def _heartbeat(self) -> None:
        """Every HEARTBEAT_S: is the VM scanning (liveness), a VM fault (an alarm), and the
        alarm list to every page when it changed."""
        while True:
            try:
                self.check_vm()
                self.send_status()
            except Exception:   # noqa: BLE001 - the heartbeat must outlive a bad moment
                pass
            await asyncio.sleep(HEARTBEAT_S)

    def check_vm(self) -> dict[str, Any]:
        vm = self.bridge.vm
        scan = vm.scan_count
        wall = time.monotonic()
        if scan != self._last_scan_seen:
            self._last_scan_seen, self._last_scan_wall = scan, wall
        fault = getattr(vm, "fault", None)
        if fault is not None:
            state, reason = "fault", f"the VM stopped on a fault: {getattr(fault, 'message', fault)}"
            if self.alarms is not None:
                self.alarms.poll_vm(vm)
        elif wall - self._last_scan_wall > STALE_S:
            state, reason = "stopped", (f"no scan for {wall - self._last_scan_wall:.0f} s: the VM is "
                                        f"stopped, paused or held in the debugger")
        else:
            state, reason = "running", ""
        if state != self.vm_state["state"]:
            self.vm_state = {"state": state, "since": _now_text(), "reason": reason, "scan": scan}
        else:
            self.vm_state = dict(self.vm_state, reason=reason or self.vm_state["reason"], scan=scan)
        return self.vm_state

    def send_status(self, force: bool = False) -> None:
        alarms = None
        if self.alarms is not None and (force or self.alarms.version != self._alarm_version):
            self._alarm_version = self.alarms.version
            alarms = self.alarm_json()
        for client in list(self.clients):
            client.offer_status(self.vm_state, alarms)

    def alarm_json(self) -> dict[str, Any]:
        current = self.alarms.current() if self.alarms is not None else []
        return {"current": [a.as_json() for a in current],
                "unacknowledged": sum(1 for a in current if not a.acknowledged),
                "active": sum(1 for a in current if a.active)}

    def notify_write(self, writer: str | None, literals: dict[str, str]) -> None:
        """Tell every other open page showing one of these variables that it was written."""
        for client in list(self.clients):
            if client.id and client.id == writer:
                continue
            shown = [p for p in literals if p in client._path_set]
            if shown:
                text = ", ".join(f"{self.labels.get(p, p)} = {self._operator_text(p, literals[p])}" for p in shown[:4])
                client.offer_notice(f"changed from another HMI screen at {_now_text()}: {text}")

    def _operator_text(self, path: str, literal: str) -> str:
        return literal[1:-1] if len(literal) >= 2 and literal[0] == literal[-1] == "'" else literal

    def _display(self, path: str, value: Any) -> Any:
        """A value as the page shows it: BOOL → true/false, integers and REAL → numbers (the page
        rounds to the variable's decimals), STRING → its text, enumerations → the member name,
        DATE_AND_TIME/DATE/TOD → `2026-12-07 13:23:34`, anything else (TIME, …) → its IEC literal."""
        ty = self.hmi.types.get(path)
        if value is None:
            return None
        if isinstance(ty, t.RealType):
            number = float(value)
            return number if number == number and abs(number) != float("inf") else str(number)
        if isinstance(ty, t.TimeType) and ty.family in ("DATE_AND_TIME", "DATE", "TIME_OF_DAY"):
            return _operator_time(self.bridge.format(path, value))
        if isinstance(ty, t.BoolType):
            return bool(value)
        if isinstance(ty, t.IntType):
            return int(value)
        if isinstance(ty, t.StringType):
            if isinstance(value, str):
                return utf16_text(value)   # a WSTRING's code units
            return bytes(value).decode("utf-8", "replace")
        if isinstance(ty, t.EnumType):
            return ty.name_of(value) or str(value)
        return self.bridge.format(path, value)

    def _update_watch(self) -> None:
        """Watch exactly the paths of the pages that have a client (none: no watch at all)."""
        wanted: dict[str, None] = {}
        for client in self.clients:
            for path in client.paths:
                wanted[path] = None
        paths = tuple(wanted)
        if set(paths) == set(self._watch_paths) and (self._watch is not None or not paths):
            return
        if self._watch is not None:
            self._watch.close()
            self._watch = None
        self._watch_paths = paths
        if paths:
            self._watch = self.bridge.watch(paths, every_ns=self.update_ns, every_wall_ns=self.update_ns,
                                            on_snapshot=self._on_snapshot)

    async def read_now(self, paths: list[str]) -> tuple[dict[str, Any], int] | None:
        """Raw values of `paths` from one snapshot: the live watch's if it covers them, else a
        one-off watch (None if the VM does not scan within WRITE_WAIT_S, e.g. a debugger stop)."""
        if self._watch is not None and all(p in self._watch_paths for p in paths):
            snap = self._watch.latest()
            if snap is not None:
                return {p: snap.values[p] for p in paths}, snap.scan
        future: asyncio.Future = self.loop.create_future()

        def deliver(snap) -> None:
            self.loop.call_soon_threadsafe(lambda: future.done() or future.set_result(snap))
        watch = self.bridge.watch(paths, on_snapshot=deliver)
        try:
            snap = await asyncio.wait_for(future, WRITE_WAIT_S)
        except asyncio.TimeoutError:
            return None
        finally:
            watch.close()
        return dict(snap.values), snap.scan

    # ------------------------------------------------------------------ writes
    def check_writes(self, body: Any) -> tuple[dict[str, Any], dict[str, str]]:
        """Validate a POST /api/vars body: ({path: value}, {path: literal}) or raise `Refused`."""
        if not isinstance(body, dict):
            raise Refused(400, "the body must be a JSON object {\"<variable path>\": \"<IEC literal>\"}")
        if not body:
            raise Refused(400, "nothing to write: the object is empty")
        if len(body) > MAX_PATHS_PER_REQUEST:
            raise Refused(413, f"too many variables in one write ({len(body)} > {MAX_PATHS_PER_REQUEST})")
        values: dict[str, Any] = {}
        literals: dict[str, str] = {}
        for path, raw in body.items():
            limits = self.hmi.writable.get(path)
            if limits is None:
                known = path in self.hmi.types
                raise Refused(403, f"{path}: not written by any HMI page" if known else
                               f"{path}: not a variable any HMI page maps", path)
            label = self.labels.get(path, path)
            if not self.limit_table.limits_for(path).writable:
                # outputs and status are read-only for every front end unless the limits table
                # opens them (`"@outputs" = { writable = true }`, docs/hmi.md)
                raise Refused(403, f"{label}: read-only (an output or status of the controller)", path)
            if isinstance(raw, bool):
                text = "TRUE" if raw else "FALSE"
            elif isinstance(raw, (int, float)):
                text = repr(raw)
            elif isinstance(raw, str):
                text = raw.strip()
            else:
                raise Refused(400, f"{label}: the value must be an IEC literal string, got {type(raw).__name__}", path)
            if len(text) > 4096:
                raise Refused(413, f"{label}: value too long", path)
            ty = self.hmi.types.get(path)
            if isinstance(ty, (t.IntType, t.RealType)) and not isinstance(ty, t.BoolType) and text and \
                    (text[0].isdigit() or text[0] in "+-.,"):
                text = self._decimal(label, path, text, ty)
                # the operator's range first: -1 for a 0..4500 field is "below the minimum 0",
                # not the UINT's 0..65535 the literal reader would name
                number = float(text)
                problem = self._limit_problem(limits, path, number, text) or \
                    self.limit_table.limits_for(path).check(number)
                if problem:
                    raise Refused(422, f"{label}: {problem}", path)
            try:
                value = self.bridge.parse(path, text)
            except WriteRejected as exc:
                raise Refused(422, f"{label}: {self._operator_reason(ty, text, exc.reason)}", path) from None
            problem = self._limit_problem(limits, path, value, text)
            if problem is None and not isinstance(value, bool):
                problem = self.limit_table.limits_for(path).check(value)
            if problem:
                raise Refused(422, f"{label}: {problem}", path)
            values[path] = value
            literals[path] = text
        return values, literals

    @staticmethod
    def _limit_problem(limits, path: str, value: Any, text: str) -> str | None:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return None
        return check_limits(limits, path, value)

    @staticmethod
    def _decimal(label: str, path: str, text: str, ty: t.Type) -> str:
        """A number as an operator types it: decimal digits, one decimal point or comma
        (Choice: `350,5` is read as 350.5, as a German or French panel shows it), an exponent.
        Anything else (`0x10`, `16#10`, `1_000`, `1.2.3`, `350,5,1`) is refused: an IEC literal
        is the API's form, not the operator's."""
        if not _DECIMAL.match(text):
            raise Refused(422, f"{label}: {text!r} is not a number (digits with one decimal point "
                               f"or comma, e.g. 350.5)", path)
        text = text.replace(",", ".")
        if isinstance(ty, t.IntType):
            number = float(text)
            if not number.is_integer():
                raise Refused(422, f"{label}: {text} is not a whole number", path)
            if abs(number) >= 1e18:
                raise Refused(422, f"{label}: {text} is out of range", path)
            return str(int(number))
        if text.startswith(".") or text.startswith(("+.", "-.")):
            text = text.replace(".", "0.", 1)
        if text.endswith("."):
            text += "0"
        return text

    @staticmethod
    def _operator_reason(ty: t.Type | None, text: str, reason: str) -> str:
        """A refused literal explained without ST words (`'' is not an ST literal`)."""
        if not text:
            return "nothing entered"
        if isinstance(ty, t.EnumType):
            return f"{text!r} is not one of the choices ({', '.join(n for n, _ in ty.members)})"
        if isinstance(ty, t.BoolType):
            return f"{text!r} is not on or off (TRUE / FALSE)"
        if isinstance(ty, t.StringType):
            m = re.match(r"(\d+) (bytes|code units) is longer than .*?\((\d+)", reason)
            if m:
                return f"text too long ({m.group(1)} characters; at most {m.group(3)})"
            return "not a valid text"
        if isinstance(ty, (t.IntType, t.RealType)):
            if "range" in reason or "cannot store" in reason or "does not fit" in reason:
                lo, hi = (ty.lo, ty.hi) if isinstance(ty, t.IntType) else (None, None)
                return f"{text} is out of range" + (f" ({lo} to {hi})" if lo is not None else "")
            return f"{text!r} is not a number"
        return reason

    async def submit(self, values: dict[str, Any]) -> int | None:
        """Submit one batch; the scan count once applied (None: not applied within WRITE_WAIT_S)."""
        future = self.bridge.submit(values)   # raises WriteRejected (checked again, busy)
        try:
            # shielded: a timeout answers 202 and the batch stays queued (cancelling the wait
            # must not cancel the write, or "queued" would be a lie)
            await asyncio.wait_for(asyncio.shield(asyncio.wrap_future(future)), WRITE_WAIT_S)
        except asyncio.TimeoutError:
            return None
        return self.bridge.vm.scan_count

    def preset_steps(self, name: str) -> list[dict[str, Any]]:
        preset = self.hmi.presets.get(name)
        if preset is None:
            raise Refused(404, f"no preset named {name!r}")
        steps = []
        for batch in preset.steps:
            values = {}
            for path, item in batch:
                if not self.limit_table.limits_for(path).writable:
                    raise Refused(403, f"preset {name}: {self.labels.get(path, path)} is read-only "
                                       f"(an output or status of the controller)", path)
                if isinstance(item, RunParameter):
                    if item.name not in self.run_parameters:
                        raise Refused(409, f"preset {name}: {path} takes the run's {item.name}, "
                                            f"and this run has none (no robot)")
                    item = self.run_parameters[item.name]
                    values[path] = item.encode() if isinstance(item, str) else item
                else:
                    values[path] = self.bridge.parse(path, item)
            steps.append(values)
        return steps

    async def guard_problem(self, values: dict[str, Any]) -> str | None:
        """A page's `[[guard]]` refusing this write (e.g. Execute of an all-zero relative move)."""
        for path, value in values.items():
            for guard in self.hmi.guards.get(path, ()):
                if value != guard.value:
                    continue
                got = await self.read_now(list(guard.all_zero))
                if got is None:
                    continue
                current = {p: values.get(p, v) for p, v in got[0].items()}
                if all(not v for v in current.values()):
                    return guard.message
        return None

    # ------------------------------------------------------------------ the web app
    def _app(self):
        return build_app(self)
