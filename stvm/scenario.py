"""Scenario files: documented TOML (read with the standard library's tomllib) that drive a run.

    description = "PnP demo against the bundled emulator"

    [set]                                  # applied before the first scan
    Connect_Time_Out = 100                 # TOML numbers/booleans, or IEC literals as strings:
    Connect_AddressIP = "'127.0.0.1'"      #   "'text'", "T#2s", "eType#Value", "16#FF"

    [robot]                                # where the robot's address goes (demo / lockstep)
    address = "Connect_AddressIP"          # STRING variable that receives the host
    port = "Connect_Dest_PortIP"           # integer variable that receives the port

    [[at]]                                 # timed events, in any order
    time = "50ms"                          # or: scan = 50, or: when = "Cobot.Connected"
    set = { PnP_Example_Execute = true }
    fault = "drop"                         # an emulator fault (lockstep runs), as `tm-emulator --fault`

    [record]
    watch = ["PnP_Example_Instance.Prg_Step", "Cobot.*"]

    [run]                                  # defaults for `stvm trace` and golden tests
    cycles = 9000                          # scans to run (the command line wins)
    scan = "1ms"                           # period of the default task (projects with a
                                           #   CONFIGURATION use their task intervals)

    [emulator]                             # the in-process robot of lockstep runs
    latency_scans = 1                      # one-way network latency in scans (default 1), or
    # latency = "500us"                    #   as a duration
    faults = ["delay:5"]                   # faults active from the start
    settings = { time_scale = 0.1 }        # EmulatorSettings fields (docs/emulator.md)

A TOML number or boolean is read as the IEC literal it spells and checked like `--set`: `5`
into a TIME is an error (write "T#5ms"), `1` into a BOOL too (write true), a value out of the
variable's range as well. Every name and value is checked before the first scan.

`when` events fire once, at the end of the first scan in which the BOOL variable is TRUE.
Events fire at the end of the scan before the one they name (`scan = 50` is visible to the ST
code of scan 50); a fault takes effect in the emulator step that follows.
"""

from __future__ import annotations

import math

import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from emulator import DEFAULT_SETTINGS as EMULATOR_DEFAULTS, parse_faults
from stvm.project import parse_duration
from stvm.runtime.vm import PathError, UnboundInOut, coerce_python_value
from stvm.semantics import types as t
from stvm.semantics.literals import literal_value
from stvm.source import SourceError, read_limited


class ScenarioError(ValueError):
    """A scenario file that cannot be used; the message names the file and the entry."""


@dataclass
class Event:
    scan: int | None = None
    time_ns: int | None = None
    when: str | None = None
    assignments: dict[str, Any] = field(default_factory=dict)
    faults: list[str] = field(default_factory=list)
    fired: bool = False

    def describe(self) -> str:
        """One line for traces: `set A=1, B=TRUE; fault drop:50`."""
        parts = []
        if self.assignments:
            parts.append("set " + ", ".join(f"{k}={_show(v)}" for k, v in self.assignments.items()))
        if self.faults:
            parts.append("fault " + ", ".join(self.faults))
        return "; ".join(parts) or "(nothing)"


def _show(value: Any) -> str:
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    return str(value)


@dataclass
class Scenario:
    path: str = "<none>"
    description: str = ""
    initial: dict[str, Any] = field(default_factory=dict)
    events: list[Event] = field(default_factory=list)
    robot_address: str | None = None
    robot_port: str | None = None
    watch: list[str] = field(default_factory=list)
    raw: dict = field(default_factory=dict)
    cycles: int | None = None                 # [run]
    scan: str | None = None
    latency_scans: int | None = None          # [emulator]
    latency_ns: int | None = None
    faults: list[str] = field(default_factory=list)
    emulator_settings: dict[str, Any] = field(default_factory=dict)

    def emulator_plan(self):
        """The emulator's (settings, initial fault plan) for this scenario."""
        try:
            settings = EMULATOR_DEFAULTS.with_table(self.emulator_settings)
        except ValueError as exc:
            raise ScenarioError(f"{self.path}: {exc}") from exc
        try:
            return settings, parse_faults(self.faults)
        except ValueError as exc:
            raise ScenarioError(f"{self.path}: [emulator]: {exc}") from exc


def load_scenario(path: str | Path) -> Scenario:
    path = Path(path)
    try:
        data = tomllib.loads(read_limited(path, "scenario file").decode("utf-8"))
    except OSError as exc:
        raise ScenarioError(f"{path}: cannot read scenario: {exc.strerror or exc}") from exc
    except SourceError as exc:
        raise ScenarioError(f"{path}: {exc.message}") from exc
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{path}: not valid TOML: the file is not UTF-8 ({exc.reason})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError(f"{path}: not valid TOML: {exc}") from exc
    return parse_scenario(data, str(path))


_SCALAR = (bool, int, float, str)


def _assignments(value: Any, where: str) -> dict[str, Any]:
    """A table of NAME = VALUE whose values are TOML scalars (a value is checked against the
    variable's type when the scenario is applied to a VM)."""
    if not isinstance(value, dict):
        raise ScenarioError(f"{where} must be a table of NAME = VALUE, e.g. {{ Main.start = true }}, got {_kind(value)}")
    for key, item in value.items():
        if not isinstance(item, _SCALAR):
            raise ScenarioError(f"{where}: {key} must be a boolean, a number or a string (an IEC literal "
                                f"such as \"T#2s\"), got {_kind(item)}")
    return dict(value)


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, (int, float)):
        return f"the number {value}"
    if isinstance(value, str):
        return f"the string {value[:60]!r}"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def _string(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ScenarioError(f"{where} must be a non-empty string, got {_kind(value)}")
    return value


def _strings(value: Any, where: str) -> list[str]:
    """A string or a list of strings."""
    if isinstance(value, str):
        return [value]
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return list(value)
    raise ScenarioError(f"{where} must be a string or a list of strings, got {_kind(value)}")


def _table(data: dict, key: str, name: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise ScenarioError(f"{name}: {key} must be a table ([{key}]), got {_kind(value)}")
    return value


def parse_scenario(data: dict, name: str = "<scenario>") -> Scenario:
    known = {"description", "set", "robot", "at", "record", "run", "emulator"}
    unknown = set(data) - known
    if unknown:
        raise ScenarioError(f"{name}: unknown section(s) {', '.join(sorted(unknown))}; known: {', '.join(sorted(known))}")
    description = data.get("description", "")
    if not isinstance(description, str):
        raise ScenarioError(f"{name}: description must be a string, got {_kind(description)}")
    scenario = Scenario(path=name, description=description, raw=data)
    scenario.initial = _assignments(data.get("set", {}), f"{name}: [set]")
    robot = _table(data, "robot", name)
    unknown = set(robot) - {"address", "port"}
    if unknown:
        raise ScenarioError(f"{name}: [robot]: unknown key(s) {', '.join(sorted(unknown))}; known: address, port")
    scenario.robot_address = _string(robot["address"], f"{name}: [robot] address") if "address" in robot else None
    scenario.robot_port = _string(robot["port"], f"{name}: [robot] port") if "port" in robot else None
    events = data.get("at", [])
    if not isinstance(events, list):
        raise ScenarioError(f"{name}: at must be an array of tables ([[at]]), got {_kind(events)}")
    for i, entry in enumerate(events):
        where = f"{name}: [[at]] #{i + 1}"
        if not isinstance(entry, dict):
            raise ScenarioError(f"{where}: must be a table")
        unknown = set(entry) - {"scan", "time", "when", "set", "fault"}
        if unknown:
            raise ScenarioError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}; known: scan, time, when, set, fault")
        keys = [k for k in ("scan", "time", "when") if k in entry]
        if len(keys) != 1:
            raise ScenarioError(f"{where}: give exactly one of scan, time, when")
        event = Event(assignments=_assignments(entry.get("set", {}), f"{where}: set"))
        event.faults = _strings(entry.get("fault", []), f"{where}: fault")
        if "scan" in entry:
            event.scan = _count(entry["scan"], f"{where}: scan")
        elif "time" in entry:
            event.time_ns = _duration(entry["time"], f"{where}: time")
        else:
            event.when = _string(entry["when"], f"{where}: when")
        scenario.events.append(event)
    record = _table(data, "record", name)
    unknown = set(record) - {"watch"}
    if unknown:
        raise ScenarioError(f"{name}: [record]: unknown key(s) {', '.join(sorted(unknown))}; known: watch")
    scenario.watch = _strings(record.get("watch", []), f"{name}: [record] watch")
    _parse_run(scenario, data.get("run", {}), name)
    _parse_emulator(scenario, data.get("emulator", {}), name)
    return scenario


def _count(value: Any, where: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        raise ScenarioError(f"{where} must be a non-negative integer")
    return value


def _duration(value: Any, where: str) -> int:
    if not isinstance(value, str):
        raise ScenarioError(f"{where} must be a duration string such as \"50ms\", got {_kind(value)}")
    try:
        return parse_duration(str(value))
    except ValueError as exc:
        raise ScenarioError(f"{where}: {exc}") from exc


def _parse_run(scenario: Scenario, run: Any, name: str) -> None:
    if not isinstance(run, dict):
        raise ScenarioError(f"{name}: [run] must be a table")
    unknown = set(run) - {"cycles", "scan"}
    if unknown:
        raise ScenarioError(f"{name}: [run]: unknown key(s) {', '.join(sorted(unknown))}; known: cycles, scan")
    if "cycles" in run:
        scenario.cycles = _count(run["cycles"], f"{name}: [run] cycles")
    if "scan" in run:
        if not isinstance(run["scan"], str):
            raise ScenarioError(f"{name}: [run] scan must be a duration string such as \"1ms\", got {_kind(run['scan'])}")
        if _duration(run["scan"], f"{name}: [run] scan") <= 0:
            raise ScenarioError(f"{name}: [run] scan must be positive")
        scenario.scan = run["scan"]


def _parse_emulator(scenario: Scenario, emu: Any, name: str) -> None:
    if not isinstance(emu, dict):
        raise ScenarioError(f"{name}: [emulator] must be a table")
    unknown = set(emu) - {"latency_scans", "latency", "faults", "settings"}
    if unknown:
        raise ScenarioError(f"{name}: [emulator]: unknown key(s) {', '.join(sorted(unknown))}; "
                            "known: latency_scans, latency, faults, settings")
    if "latency_scans" in emu:
        scenario.latency_scans = _count(emu["latency_scans"], f"{name}: [emulator] latency_scans")
    if "latency" in emu:
        scenario.latency_ns = _duration(emu["latency"], f"{name}: [emulator] latency")
    scenario.faults = _strings(emu.get("faults", []), f"{name}: [emulator] faults")
    settings = emu.get("settings", {})
    if not isinstance(settings, dict):
        raise ScenarioError(f"{name}: [emulator] settings must be a table")
    try:
        EMULATOR_DEFAULTS.with_table(settings)   # checked now, so a bad value is never ignored
    except ValueError as exc:
        raise ScenarioError(f"{name}: {exc}") from exc
    scenario.emulator_settings = dict(settings)


def to_st_value(raw: Any, vm, path: str) -> Any:
    """A scenario value (TOML scalar or IEC literal string) converted for variable `path`."""
    ty = vm.type_of(path)
    if isinstance(raw, (bool, int, float)):
        # A TOML scalar is read as the IEC literal it spells, so it meets the checks `--set`
        # applies: `5` into a TIME is refused (it would be 5 ns), a REAL out of range is an
        # error instead of inf, `true` fits only a BOOL.
        raw = _scalar_literal(raw)
    if isinstance(raw, str):
        if isinstance(ty, t.StringType) and not raw.startswith("'"):
            return raw  # plain TOML text for a STRING
        return literal_value(raw, ty)
    raise ScenarioError(f"{path}: unsupported value {raw!r}")


def _scalar_literal(value: bool | int | float) -> str:
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{value} is not a number a variable can hold")
    return repr(value)


class ScenarioDriver:
    """Applies a scenario to a running VM: initial values now, events at the end of each scan."""

    def __init__(self, scenario: Scenario, vm, fault_sink=None, on_event=None) -> None:
        self.scenario = scenario
        self.vm = vm
        self.fault_sink = fault_sink   # callable(fault text) for emulator faults, or None
        self.on_event = on_event       # callable(event, scan it is for), e.g. a trace recorder
        self._check(vm)
        self._plan()

    def _plan(self) -> None:
        """What `after_scan` compares with so that a scan with nothing due costs two
        comparisons: whether an unfired event watches a variable (`when`, read every scan), and
        the earliest scan number and instant of the unfired events set at one."""
        never = 1 << 63
        self._watching = False
        self._next_scan = self._next_time = never
        for event in self.scenario.events:
            if event.fired:
                continue
            if event.when is not None:
                self._watching = True
            if event.scan is not None and event.scan < self._next_scan:
                self._next_scan = event.scan
            if event.time_ns is not None and event.time_ns < self._next_time:
                self._next_time = event.time_ns

    def _check(self, vm) -> None:
        """Every name and fault of the scenario, checked before the first scan (a typo found at
        scan 5000 would lose the run)."""
        where = self.scenario.path
        for i, event in enumerate(self.scenario.events):
            entry = f"{where}: [[at]] #{i + 1}"
            if event.faults:
                if self.fault_sink is None:
                    raise ScenarioError(f"{entry}: fault {event.faults[0]!r} needs an emulator: use stvm trace "
                                        f"(lockstep) or a demo project with the bundled emulator")
                try:
                    parse_faults(event.faults)
                except ValueError as exc:
                    raise ScenarioError(f"{entry}: fault: {exc}") from exc
            if event.when is not None:
                try:
                    ty = vm.type_of(event.when)
                except UnboundInOut:
                    continue
                except (PathError, ValueError) as exc:
                    raise ScenarioError(f"{entry}: when = {event.when!r}: {exc}") from exc
                if not isinstance(ty, t.BoolType):
                    raise ScenarioError(f"{entry}: when = {event.when!r} must name a BOOL variable "
                                        f"(it is {ty.name})")
            for path, raw in event.assignments.items():
                self._check_assignment(path, raw, f"{entry}: set")
        for path, raw in self.scenario.initial.items():
            self._check_assignment(path, raw, f"{where}: [set]")

    def _check_assignment(self, path: str, raw: Any, where: str) -> None:
        """The variable exists and the value is one it can hold (converted, not stored)."""
        try:
            coerce_python_value(to_st_value(raw, self.vm, path), self.vm.type_of(path))
        except UnboundInOut:
            pass
        except (PathError, ValueError, TypeError) as exc:
            raise ScenarioError(f"{where}: {path}: {exc}") from exc

    def apply_initial(self, overrides: dict[str, Any] | None = None) -> None:
        values = dict(self.scenario.initial)
        values.update(overrides or {})
        for path, raw in values.items():
            self._assign(path, raw, "[set]")
        self._fire_due(before_first=True)

    def _assign(self, path: str, raw: Any, where: str) -> None:
        try:
            self.vm.set(path, to_st_value(raw, self.vm, path))
        except (KeyError, ValueError, TypeError) as exc:
            raise ScenarioError(f"{self.scenario.path}: {where}: {path}: {exc}") from exc

    def _fire(self, event: Event) -> None:
        event.fired = True
        for path, raw in event.assignments.items():
            self._assign(path, raw, "[[at]]")
        for fault in event.faults:
            if self.fault_sink is None:
                raise ScenarioError(f"{self.scenario.path}: fault {fault!r} needs an emulator (lockstep or bundled)")
            self.fault_sink(fault)
        if self.on_event is not None:
            self.on_event(event, self.vm.scan_count)

    def _fire_due(self, before_first: bool = False) -> None:
        vm = self.vm
        try:
            for event in self.scenario.events:
                if event.fired:
                    continue
                if event.scan is not None and event.scan <= vm.scan_count:
                    self._fire(event)
                elif event.time_ns is not None and event.time_ns <= vm.now_ns:
                    self._fire(event)
                elif event.when is not None and not before_first and self._is_true(event.when):
                    self._fire(event)
        finally:
            self._plan()

    def _is_true(self, path: str) -> bool:
        try:
            return bool(self.vm.get(path))
        except UnboundInOut:   # through an in-out the FB has not been called with yet
            return False

    def after_scan(self, vm) -> None:
        """VM hook: runs at the end of every scan (the VM has not advanced its clock yet)."""
        # scan_count/now_ns still name the scan that just ran: events for the next scan fire now
        if not self._watching and vm.scan_count + 1 < self._next_scan and vm.now_ns + vm.base_ns < self._next_time:
            return   # nothing due for the next scan (`_plan`): `_fire_due` would fire nothing
        saved = vm.scan_count, vm.now_ns
        vm.scan_count, vm.now_ns = saved[0] + 1, saved[1] + vm.base_ns
        try:
            self._fire_due()
        finally:
            vm.scan_count, vm.now_ns = saved
