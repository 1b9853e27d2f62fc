"""Lockstep mode: the TM emulator in-process, behind the socket FBs, on the VM's virtual clock.

`LockstepTransport` is a `stvm.stdlib.sockets.SocketTable` whose links are `ClientEndpoint`s of
one `emulator.InProcessLink`. Nothing here reads the wall clock, opens a socket or starts a thread,
so the same project, scenario and latency give the same bytes at the same nanosecond on every run
and every machine.

Timeline of one scan `k` (period `P`, VM time `k*P` at its start)::

    scan k runs         the FBs poll their links: bytes that reached the PLC by k*P are readable;
                        what they send is stamped k*P and reaches the robot at k*P + latency
    on_scan_end hooks   the scenario fires its events for scan k+1 (and faults), then
    advance             the emulator processes everything up to (k+1)*P: the robot reads, moves,
                        answers; answers reach the PLC `latency` after the robot sent them

The modelled latency is one way; the default is one scan period, so a request sent in scan k is
read by the robot at the end of scan k and its answer can be read in scan k+2 (the thesis FBs poll
once more before they look, sysmac.md 8.8, so the first reaction shows in scan k+3 or later).

Use::

    from stvm.lockstep import LockstepTransport
    transport = LockstepTransport(latency_scans=1)
    vm = project.start(scan="1ms", transport=transport)
    transport.attach(vm)                 # registers the clock hook; sets the latency
    vm.run(cycles=5000)
    transport.link.robot.snapshot()      # the robot's state
    transport.frames                     # the last KEEP_FRAMES frames, as `FrameRecord`s

Any host and port connect to the one emulated robot (the address is not checked); a scenario's
`[robot]` globals receive `LOCKSTEP_HOST` and `LOCKSTEP_PORT`. A cell of several robots:
`transport.add_robot(host, port)` adds another emulated robot, reached by connections to exactly
that address, stepped on the same clock (`transport.robots[i]`; frames carry `robot`, the index).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Callable

from emulator import DEFAULT_SETTINGS, NO_FAULTS, EmulatorSettings, FaultPlan, InProcessLink, parse_fault
from stvm.stdlib.sockets import (CONNECTING, ESTABLISHED, FAILED, PEER_CLOSED, RESET, SocketError,
                                 SocketTable)

LOCKSTEP_HOST = "127.0.0.1"
LOCKSTEP_PORT = 5890   # the TM Listen Node's default port (tm_protocol.md 1.2)
KEEP_FRAMES = 1_000    # frames kept in `LockstepTransport.frames` (a long run must not grow;
                       # a trace recorder or `log_path` sees every frame through `on_frame`)

# ClientEndpoint.status -> Link state (sockets.py)
_STATES = {"connecting": CONNECTING, "connected": ESTABLISHED, "peer_closed": PEER_CLOSED,
           "refused": FAILED, "closed": RESET}


@dataclass(frozen=True)
class FrameRecord:
    """One Listen Node frame as the robot saw it: `direction` "rx" (robot received, i.e. the PLC
    sent it) or "tx" (robot sent); `t_ns` the emulator time; `conn` the robot's connection id."""

    t_ns: int
    direction: str
    data: bytes
    conn: int
    robot: int = 0    # index in `LockstepTransport.robots` (0: the default robot)


class EmulatorLink:
    """One socket of the PLC, as a `sockets.Link` over an in-process `ClientEndpoint`."""

    def __init__(self, transport: "LockstepTransport", robot: InProcessLink, src_port: int, host: str,
                 port: int) -> None:
        self._endpoint = robot.endpoint()
        self.failure: str | None = None
        self.local_address = ("", 0)
        self.remote_address = (host, port)
        self._src_port = src_port
        self._transport = transport
        self._closed = False
        self._endpoint.connect(host, port)
        self.state = CONNECTING

    def _update(self) -> None:
        if self._closed:
            return
        state = _STATES[self._endpoint.status]
        if state == FAILED and self.state == CONNECTING:
            self.failure = "wrong_state"  # RST answer to the SYN: "refused" (sysmac.md 5: 16#2003)
        if state == ESTABLISHED and self.state == CONNECTING:
            # Choice: a deterministic local address; ephemeral ports count up per connection
            self.local_address = (LOCKSTEP_HOST, self._src_port or self._transport._next_ephemeral())
        self.state = state

    def poll(self, now_ns: int) -> bytes:
        endpoint = self._endpoint
        if self.state == ESTABLISHED and endpoint.status == "connected":
            # the steady state, where `_update` changes nothing (a closed link is RESET): a
            # receive FB polls here every scan while it waits for the robot's answer
            return endpoint.recv(1 << 20)
        self._update()
        if self.state in (ESTABLISHED, PEER_CLOSED):
            # after the robot's FIN the bytes it sent before are still readable
            return self._endpoint.recv(1 << 20)
        return b""

    def send(self, data: bytes) -> None:
        self._update()
        if self.state == PEER_CLOSED:
            return  # half-closed: the robot discards what arrives (no RST is modelled)
        if self.state != ESTABLISHED:
            raise SocketError("wrong_state", f"send while {self.state}")
        self._endpoint.send(data)

    def close(self) -> None:
        if not self._closed:
            self._endpoint.close()
            self._closed = True
            self.state = RESET


class LockstepTransport(SocketTable):
    """The socket service of the VM wired to an in-process emulated TM robot.

    `latency_ns` (one way) wins over `latency_scans` (a multiple of the VM's base period, known
    at `attach`). `faults` is the initial fault plan; `inject_fault` changes it during the run.
    `on_frame(record)` callbacks see every frame (the trace recorder uses them).
    """

    def __init__(self, latency_scans: int = 1, latency_ns: int | None = None,
                 settings: EmulatorSettings = DEFAULT_SETTINGS, faults: FaultPlan = NO_FAULTS,
                 log_path: str | None = None) -> None:
        super().__init__(self._open_link)
        if latency_scans < 0 or (latency_ns is not None and latency_ns < 0):
            raise ValueError("latency must not be negative")
        self.latency_scans = latency_scans
        self._explicit_latency = latency_ns is not None
        self.frames: deque[FrameRecord] = deque(maxlen=KEEP_FRAMES)
        self.on_frame: list[Callable[[FrameRecord], None]] = []
        self._ephemeral = 49152   # IANA dynamic range start (Choice: deterministic, counts up)
        self.robots: list[InProcessLink] = []
        self._by_address: dict[tuple[str, int], InProcessLink] = {}
        self.link = self._new_robot(settings, faults, latency_ns if latency_ns is not None else 0, log_path)
        self.vm = None

    def _new_robot(self, settings: EmulatorSettings, faults: FaultPlan, latency_ns: int,
                   log_path: str | None) -> InProcessLink:
        link = InProcessLink(settings=settings, faults=faults, latency_ns=latency_ns, log_path=log_path)
        index = len(self.robots)
        original_log = link.core.frame_log

        def frame_log(t_ns: int, direction: str, data: bytes, conn: int) -> None:
            if original_log is not None:
                original_log(t_ns, direction, data, conn)
            record = FrameRecord(t_ns, direction, bytes(data), conn, index)
            self.frames.append(record)
            for callback in self.on_frame:
                callback(record)

        link.core.frame_log = frame_log
        self.robots.append(link)
        return link

    def add_robot(self, host: str, port: int, settings: EmulatorSettings = DEFAULT_SETTINGS,
                  faults: FaultPlan = NO_FAULTS) -> InProcessLink:
        """Another emulated robot, reached by connections to exactly (`host`, `port`) (before `attach`)."""
        if self.vm is not None:
            raise ValueError("add_robot: add the robots before attach")
        if (host, port) in self._by_address:
            raise ValueError(f"add_robot: {host}:{port} has a robot already")
        link = self._new_robot(settings, faults, self.link.latency_ns, None)
        self._by_address[(host, port)] = link
        return link

    # --- wiring -----------------------------------------------------------------------------

    def attach(self, vm) -> "LockstepTransport":
        """Step the emulator with `vm` (call once, right after `project.start(transport=self)`)."""
        if vm.ctx.transport is not self:
            raise ValueError("attach: the VM was started with another transport")
        if self.vm is not None:
            raise ValueError("attach: already attached to a VM")
        self.vm = vm
        for robot in self.robots:
            if not self._explicit_latency:
                robot.latency_ns = self.latency_scans * vm.base_ns
            if robot.now_ns < vm.now_ns:
                robot.advance_to(vm.now_ns)
        vm.on_scan_end.append(self.after_scan)
        return self

    def after_scan(self, vm) -> None:
        """VM hook: advance the emulated robots to the start of the next scan."""
        target = vm.now_ns + vm.base_ns
        for robot in self.robots:
            if target < robot._quiet_until and robot._robot._deadline_known and target >= robot.now_ns:
                # `InProcessLink.advance_to`'s quiet step, without its call (every robot, nearly
                # every scan): nothing is due by `target`, only the link's clock moves
                robot.now_ns = target
                robot._behind = True
            else:
                robot.advance_to(target)

    @property
    def latency_ns(self) -> int:
        return self.link.latency_ns

    # --- a receive FB waiting for the robot polls these every scan ----------------------------

    def poll(self, handle: int, now_ns: int) -> str:
        # `SocketTable.poll` when the link is established and nothing arrived (it would change
        # nothing and return ESTABLISHED), without its three calls; anything else takes it
        entry = self._sockets.get(handle)
        if entry is not None:
            link = entry.link
            if link.state == ESTABLISHED:
                endpoint = link._endpoint
                if endpoint.status == "connected" and not endpoint.available:
                    return ESTABLISHED
        return super().poll(handle, now_ns)

    def quiet_receive(self, handle: int) -> bool:
        # `poll` (above) would return ESTABLISHED by its first branch and nothing is buffered
        entry = self._sockets.get(handle)
        if entry is None or entry.received:
            return False
        link = entry.link
        if link.state != ESTABLISHED:
            return False
        endpoint = link._endpoint
        return endpoint.status == "connected" and not endpoint._rx   # (`available` without its call)

    def pending(self, handle: int) -> int:
        entry = self._sockets.get(handle)
        return len(entry.received) if entry is not None else super().pending(handle)

    def _next_ephemeral(self) -> int:
        port = self._ephemeral
        self._ephemeral += 1
        return port

    def _open_link(self, src_port: int, host: str, port: int, now_ns: int) -> EmulatorLink:
        for robot in self.robots:
            if robot.now_ns < now_ns:
                robot.advance_to(now_ns)  # a VM used without attach: keep the clocks together
        return EmulatorLink(self, self._by_address.get((host, port), self.link), src_port, host, port)

    # --- faults -----------------------------------------------------------------------------

    def inject_fault(self, text: str) -> FaultPlan:
        """Apply one `tm-emulator --fault` text (e.g. "drop:50", "error:1") from now on.

        Timed faults count from the injection: `stop:MS` stops the project MS ms after it,
        `unsolicited:MS` sends the first frame MS ms after it, and `drop:MS` during a motion
        drops the connections MS ms after the injection (otherwise MS ms after the next motion
        starts, as with the fault given at start-up). Returns the new plan.
        """
        core = self.link.core
        plan = parse_fault(text, core.faults)
        name = text.strip().partition(":")[0].lower().replace("-", "_")
        core.apply_faults(plan, self.link.now_ns, name)
        return plan

    def clear_faults(self) -> None:
        """Back to a robot without faults (timers armed by faults are disarmed)."""
        self.link.core.clear_faults()

    def close_all(self) -> None:
        super().close_all()
        for robot in self.robots:
            robot.close()


def start_lockstep(project, scan: str | int = "1ms", latency_scans: int = 1, latency_ns: int | None = None,
                   faults: FaultPlan = NO_FAULTS, settings: EmulatorSettings = DEFAULT_SETTINGS,
                   start_dt_ns: int = 0):
    """A fresh VM of `project` wired to a fresh emulated robot: returns (vm, transport)."""
    transport = LockstepTransport(latency_scans=latency_scans, latency_ns=latency_ns,
                                  settings=settings, faults=faults)
    vm = project.start(scan=scan, transport=transport, start_dt_ns=start_dt_ns)
    transport.attach(vm)
    return vm, transport
