"""What `stvm debug` and `stvm dap` share: load the debug build, start the engine, and wire the run
as `stvm run`/`stvm trace` would (scenario, `--set`, the robot).

The robot, by `SessionOptions.robot`:

* `"lockstep"`: the TM emulator in-process on the VM's virtual clock (`stvm.lockstep`). The
  default when the scenario has a `[robot]` table: a stopped VM stops the robot too, so a
  breakpoint never makes a motion time out behind the user's back, and every session replays
  the same bytes.
* `"emulator"`: the bundled emulator on a loopback TCP port, in wall-clock time.
* `"HOST:PORT"`: a real robot (or an emulator started elsewhere).
* None: no robot (socket FBs connect wherever the ST code says).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from stvm.debug.build import DebugBuild, load_debug
from stvm.debug.engine import Engine
from stvm.semantics.literals import literal_value
from stvm.project import Options, parse_duration, resolve


@dataclass
class SessionOptions:
    files: Sequence[str]
    scan: str | None = None                               # default: the scenario's, else 10ms
    scenario: str | None = None
    sets: list[str] = field(default_factory=list)          # NAME=VALUE, as `stvm run --set`
    sysmac: list[str] = field(default_factory=list)        # NAME=VALUE Sysmac settings
    dialect: str | None = None                            # over the manifest's [project] dialect
    defines: list[str] = field(default_factory=list)       # NAME[=VALUE], beside the manifest's
    robot: str | None = None                              # lockstep | emulator | HOST:PORT | None
    realtime: bool = False
    max_scans: int | None = None
    latency_scans: int | None = None                      # lockstep: one-way latency in scans


class Session:
    """A prepared debug session; `close()` ends the VM and the emulator it started."""

    def __init__(self, build: DebugBuild, engine: Engine, robot: str = "none", server: Any = None,
                 transport: Any = None) -> None:
        self.build = build
        self.engine = engine
        self.robot = robot          # what the session talks to, for the banner
        self.server = server
        self.transport = transport

    def close(self) -> None:
        try:
            self.engine.terminate()
        finally:
            if self.server is not None:
                self.server.stop()
                self.server = None


def open_session(options: SessionOptions, build: DebugBuild | None = None) -> Session:
    """Load (unless `build` is given) and prepare a session; raises LoadError, ValueError (bad
    options) or ScenarioError. The engine is not started yet."""
    from stvm.scenario import Scenario, load_scenario   # lazy: start-up
    spec = resolve(list(options.files), Options(sysmac=tuple(options.sysmac), dialect=options.dialect,
                                                defines=tuple(options.defines)))
    scenario = load_scenario(options.scenario) if options.scenario else Scenario()
    scan_ns = parse_duration(options.scan or scenario.scan or "10ms")
    if scan_ns <= 0:
        raise ValueError("--scan must be positive")
    robot = options.robot
    if robot is None and (scenario.robot_address or scenario.robot_port):
        robot = "lockstep"
    if build is None:
        build = load_debug(spec)
    transport = None
    if robot == "lockstep":
        from stvm.lockstep import LockstepTransport   # lazy: start-up
        emu_settings, plan = scenario.emulator_plan()
        latency = options.latency_scans if options.latency_scans is not None else \
            (scenario.latency_scans if scenario.latency_scans is not None else 1)
        transport = LockstepTransport(latency_scans=latency, latency_ns=scenario.latency_ns,
                                      settings=emu_settings, faults=plan)
    engine = Engine(build, scan_ns=scan_ns, realtime=options.realtime, max_scans=options.max_scans,
                    transport=transport)
    session = Session(build, engine, robot or "none", transport=transport)
    try:
        _wire(session, scenario, robot, options)
        for item in options.sets:
            _apply_set(engine, item)
    except BaseException:
        session.close()
        raise
    return session


def _wire(session: Session, scenario, robot: str | None, options: SessionOptions) -> None:
    """Robot address, scenario hooks and the emulator clock, in `stvm trace`'s order: forces
    (first, see Engine), scenario events, then the emulator's step to the next scan."""
    from stvm.scenario import ScenarioDriver   # lazy: start-up
    vm = session.engine.vm
    address: tuple[str, int] | None = None
    fault_sink = None
    if robot == "lockstep":
        from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT   # lazy: start-up
        address = (LOCKSTEP_HOST, LOCKSTEP_PORT)
        fault_sink = session.transport.inject_fault
    elif robot == "emulator":
        import emulator   # lazy: start-up
        from stvm.demo import free_loopback_port   # lazy: start-up
        session.server = emulator.start_server(host="127.0.0.1", port=free_loopback_port())
        address = ("127.0.0.1", session.server.port)
        fault_sink = lambda text: _inject_fault(session.server, text)  # noqa: E731
    elif robot:
        address = _parse_robot(robot)
    driver = ScenarioDriver(scenario, vm, fault_sink)
    overrides: dict[str, Any] = {}
    if address is not None:
        if scenario.robot_address:
            overrides[scenario.robot_address] = f"'{address[0]}'"
        if scenario.robot_port:
            overrides[scenario.robot_port] = address[1]
    vm.on_scan_end.append(driver.after_scan)
    if session.transport is not None:
        session.transport.attach(vm)
    driver.apply_initial(overrides)


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


def _apply_set(engine: Engine, item: str) -> None:
    name, sep, value = item.partition("=")
    if not sep or not name.strip():
        raise ValueError(f"--set needs NAME=VALUE, got {item!r}")
    vm = engine.vm
    try:
        vm.set(name.strip(), literal_value(value.strip(), vm.type_of(name.strip())))
    except KeyError as exc:
        raise ValueError(str(exc)) from exc
