"""One session: a loaded project's VM with its clock, its robot, its scenario and the front ends
serving it, wired and torn down in one documented order. `stvm run`, `stvm trace` and
`stvm debug`/`stvm dap` are configurations of it (`SessionConfig`); the project comes from the
driver (stvm/project.py).

The robot (`SessionConfig.robot`):

* `"lockstep"`: the TM emulator in-process on the VM's virtual clock (stvm/lockstep.py). The
  default when the scenario has a `[robot]` table: every run replays the same bytes, and a VM
  stopped in the debugger stops the robot too.
* `"emulator"`: the bundled emulator on a loopback TCP port, in wall-clock time.
* `"HOST:PORT"`: a real robot (or an emulator started elsewhere).
* `"none"`: no robot (socket FBs connect wherever the ST code says; `stvm run` without a demo).

Hooks at the end of each scan, in this order (a contract, because it decides what a trace shows;
`wire`):

1. the sampler, when there is one (a trace recorder reads what the programs of this scan left);
2. the scenario fires the events due for the next scan (sets inputs, injects faults);
3. the lockstep emulator advances to the start of the next scan.

(The debugger's engine puts its forces before all of these when it makes the VM.)

Teardown (`close`), in this order: the front ends stop serving (the HMI, OPC UA: no client
reaches a VM being closed), newest first; then the VM closes (and its sockets); then the robot
stops (a bundled emulator's server, a demo's).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence


@dataclass
class SessionConfig:
    """How a session runs: task period, scenario, robot link, front ends and limits."""

    scan: str | int | None = None          # the default task period; None: the scenario's, else default_scan
    default_scan: str = "10ms"
    scenario: str | Path | None = None
    robot: str | None = None               # lockstep | emulator | HOST:PORT | none; None: see the module
    latency_scans: int | None = None       # lockstep: one-way latency in scans (None: the scenario's, else 1)
    latency_ns: int | None = None          # lockstep: extra latency (None: the scenario's)
    faults: Sequence[str] = ()             # emulator faults from the start (tm-emulator --fault)
    realtime: bool = False
    record_events: bool = False            # keep (scan, text) of each scenario event in `events`


class Session:
    """A project's VM with its robot, scenario and front ends. Raises ValueError (a bad scan or
    robot address) and ScenarioError; on any error the parts already started are stopped."""

    def __init__(self, project, config: SessionConfig | None = None,
                 start_vm: Callable[..., Any] | None = None, close_vm: Callable[[], None] | None = None) -> None:
        """`start_vm(scan_ns=, realtime=, transport=)` makes the VM (default: `project.start`; the
        debugger's engine makes its own); `close_vm` ends it (default: `vm.close`)."""
        from stvm.project import parse_duration   # lazy: start-up
        self.project = project
        self.config = config = config or SessionConfig()
        self.scenario = _NO_SCENARIO
        if config.scenario:
            from stvm.scenario import load_scenario   # lazy: start-up (scenario and emulator)
            self.scenario = load_scenario(config.scenario)
        elif config.robot not in (None, "none"):
            from stvm.scenario import Scenario   # lazy: start-up
            self.scenario = Scenario()
        scan = config.scan if config.scan is not None else (self.scenario.scan or config.default_scan)
        self.scan_ns = parse_duration(scan) if isinstance(scan, str) else int(scan)
        if self.scan_ns <= 0:
            raise ValueError("--scan must be positive")
        robot = config.robot
        if robot is None:
            robot = "lockstep" if (self.scenario.robot_address or self.scenario.robot_port) else "none"
        self.robot = robot
        self.address: tuple[str, int] | None = None if robot in ("none", "lockstep", "emulator") else _parse_robot(robot)
        self.transport = None          # the lockstep transport
        self.server = None             # the bundled emulator's server (robot "emulator")
        self.front_ends: list[Any] = []
        self.robots: list[Any] = []    # what stops after the VM (a demo's robot and status)
        self.events: list[tuple[int, str]] = []
        self.vm = None
        self._close_vm = close_vm
        try:
            fault_sink = self._start_robot()
            start = start_vm or (lambda **kw: project.start(scan=kw["scan_ns"], realtime=kw["realtime"],
                                                             transport=kw["transport"]))
            self.vm = start(scan_ns=self.scan_ns, realtime=config.realtime, transport=self.transport)
            on_event = (lambda event, scan: self.events.append((scan, event.describe()))) \
                if config.record_events else None
            self.driver = None          # a run without scenario and robot never loads their code
            if self.scenario is not _NO_SCENARIO:
                from stvm.scenario import ScenarioDriver   # lazy: start-up
                self.driver = ScenarioDriver(self.scenario, self.vm, fault_sink, on_event=on_event)
        except BaseException:
            self.close()
            raise

    def _start_robot(self):
        """The robot of the session; returns where emulator faults go (None: no emulator)."""
        if self.robot == "lockstep":
            from emulator import parse_fault   # lazy: start-up
            from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, LockstepTransport   # lazy: start-up
            config, scenario = self.config, self.scenario
            emu_settings, plan = scenario.emulator_plan()
            for text in config.faults:
                plan = parse_fault(text, plan)
            latency_scans = config.latency_scans if config.latency_scans is not None else \
                (scenario.latency_scans if scenario.latency_scans is not None else 1)
            latency_ns = config.latency_ns if config.latency_ns is not None else scenario.latency_ns
            self.transport = LockstepTransport(latency_scans=latency_scans, latency_ns=latency_ns,
                                               settings=emu_settings, faults=plan)
            self.address = (LOCKSTEP_HOST, LOCKSTEP_PORT)
            return self.transport.inject_fault
        if self.robot == "emulator":
            import emulator   # lazy: start-up
            from stvm.demo import free_loopback_port   # lazy: start-up
            self.server = emulator.start_server(host="127.0.0.1", port=free_loopback_port())
            self.address = ("127.0.0.1", self.server.port)
            server = self.server
            return lambda text: _inject_fault(server, text)
        return None

    def wire(self, sampler: Callable | None = None) -> None:
        """Hook the sampler, the scenario and the lockstep robot to the VM in the module's order,
        then apply the scenario's initial values (the robot's address over the scenario's)."""
        vm = self.vm
        if sampler is not None:
            vm.on_scan_end.append(sampler)
        if self.driver is not None and self.scenario.events:   # without events: nothing to do between scans
            vm.on_scan_end.append(self.driver.after_scan)
        if self.transport is not None:
            self.transport.attach(vm)   # appends the emulator step last
        overrides: dict[str, Any] = {}
        if self.address is not None:
            if self.scenario.robot_address:
                overrides[self.scenario.robot_address] = f"'{self.address[0]}'"
            if self.scenario.robot_port:
                overrides[self.scenario.robot_port] = self.address[1]
        if self.driver is not None:
            self.driver.apply_initial(overrides)

    def add_front_end(self, front_end) -> None:
        """A server on the VM (`stop()`): stopped before the VM closes."""
        if front_end is not None:
            self.front_ends.append(front_end)

    def add_robot(self, robot) -> None:
        """A part that stops after the VM (`stop()`), e.g. a demo's emulator and status view."""
        if robot is not None:
            self.robots.append(robot)

    def close(self) -> None:
        """Front ends (newest first), the VM, then the robot; each step runs even if one before
        it failed, and the first failure is raised at the end."""
        steps = [front.stop for front in reversed(self.front_ends)]
        self.front_ends = []
        if self.vm is not None:
            steps.append(self._close_vm or self.vm.close)
        steps += [robot.stop for robot in self.robots]
        self.robots = []
        if self.server is not None:
            steps.append(self.server.stop)
            self.server = None
        failure: BaseException | None = None
        for step in steps:
            try:
                step()
            except BaseException as exc:  # noqa: BLE001 - the rest still stops; raised below
                failure = failure or exc
        self._close_vm = lambda: None   # closed once
        if failure is not None:
            raise failure


class _NoScenario:
    """What a session without a scenario file reads of one (stvm.scenario.Scenario's defaults)."""
    events: tuple = ()
    initial: dict = {}
    watch: tuple = ()
    robot_address = robot_port = scan = cycles = latency_scans = latency_ns = None


_NO_SCENARIO = _NoScenario()


def _parse_robot(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"robot: expected lockstep, emulator or HOST:PORT, got {text!r}")
    return host, int(port)


def _inject_fault(server: Any, text: str) -> None:
    from emulator import parse_fault   # lazy: start-up

    def apply(core, now_ns):
        plan = parse_fault(text, core.faults)
        core.faults = plan
        core.robot.faults = plan
    server.call(apply)
