"""What `stvm debug` and `stvm dap` share: the debug build (through the project driver), and the
run session of `stvm run`/`stvm trace` (stvm/session.py: the robot, the scenario, the teardown
order) with the engine making its VM; then `--set`.

The robot, by `SessionOptions.robot` (stvm/session.py): `"lockstep"` (the TM emulator on the VM's
virtual clock; the default when the scenario has a `[robot]` table: a stopped VM stops the robot
too, so a breakpoint never makes a motion time out behind the user's back), `"emulator"` (the
bundled emulator on a loopback port), `"HOST:PORT"`, or None (no robot).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from stvm.debug.build import DebugBuild, load_debug
from stvm.debug.engine import Engine
from stvm.semantics.literals import literal_value
from stvm.project import Options, resolve
from stvm.session import Session as RunSession, SessionConfig


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


class Session(RunSession):
    """A prepared debug session: the run session (stvm/session.py) whose VM the engine makes;
    `close()` ends the engine, then the emulator it started."""

    def __init__(self, build: DebugBuild, options: SessionOptions) -> None:
        self.build = build
        self.engine: Engine | None = None

        def start_vm(scan_ns: int, realtime: bool, transport: Any):
            # the engine makes the VM, its forces the first hook of every scan
            self.engine = Engine(build, scan_ns=scan_ns, realtime=realtime, max_scans=options.max_scans,
                                 transport=transport)
            return self.engine.vm

        config = SessionConfig(scan=options.scan, default_scan="10ms", scenario=options.scenario,
                               robot=options.robot, latency_scans=options.latency_scans, realtime=options.realtime)
        super().__init__(build.project, config, start_vm=start_vm, close_vm=lambda: self.engine.terminate())


def open_session(options: SessionOptions, build: DebugBuild | None = None) -> Session:
    """Load (unless `build` is given, through the project driver) and prepare a session; raises
    LoadError, ValueError (bad options) or ScenarioError. The engine is not started yet."""
    if build is None:
        spec = resolve(list(options.files), Options(sysmac=tuple(options.sysmac), dialect=options.dialect,
                                                    defines=tuple(options.defines)))
        build = load_debug(spec)
    session = Session(build, options)
    try:
        session.wire()
        for item in options.sets:
            _apply_set(session.engine, item)
    except BaseException:
        session.close()
        raise
    return session


def _apply_set(engine: Engine, item: str) -> None:
    name, sep, value = item.partition("=")
    if not sep or not name.strip():
        raise ValueError(f"--set needs NAME=VALUE, got {item!r}")
    vm = engine.vm
    try:
        vm.set(name.strip(), literal_value(value.strip(), vm.type_of(name.strip())))
    except KeyError as exc:
        raise ValueError(str(exc)) from exc
