"""One recorded lockstep run: project + scenario + emulator + recorder, wired in a fixed order.

`run_trace(spec)` is what `stvm trace`, the pytest plugin and the benchmarks call. Hook order at
the end of each scan (a contract, because it decides what a trace shows):

1. the recorder samples the watched variables (what the programs of this scan left);
2. the scenario fires the events due for the next scan (sets inputs, injects faults);
3. the emulator advances to the start of the next scan.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

from stvm.trace.model import Trace
from stvm.trace.recorder import Recorder
from stvm.trace.signals import WatchError, select_signals

DEFAULT_CYCLES = 1000


@dataclass
class TraceSpec:
    """What to run and record. `cycles` None: the scenario's `[run] cycles`, else 1000.
    `watch` empty: the scenario's `[record] watch`. `latency_scans` None: the scenario's, else 1."""

    files: Sequence[str | Path]
    scan: str | int | None = None
    cycles: int | None = None
    watch: Sequence[str] = ()
    scenario: str | Path | None = None
    latency_scans: int | None = None
    latency_ns: int | None = None
    faults: Sequence[str] = ()
    settings_overrides: Sequence[str] = ()     # `--sysmac NAME=VALUE`
    use_cache: bool = True
    record_frames: bool = True
    record_tcp: bool = False                   # sample the robot's TCP (stvm trace -o path.svg)
    # the driver's resolution of `files` (stvm.project.resolve); None: resolved from `files`
    # and `settings_overrides`, as `stvm trace` does
    resolved: object = None


@dataclass
class TraceRun:
    trace: Trace
    vm: object
    transport: object
    project: object
    fault: Exception | None = None
    scenario: object = None
    signals: list = field(default_factory=list)
    tcp_path: object = None                    # a TcpPathRecorder when `record_tcp`


class Prepared:
    """A VM wired to its robot and scenario, ready for scan 0 (shared by the recorder and the
    writer search, which replays a run to a given scan)."""

    def __init__(self, spec: TraceSpec, project=None) -> None:
        from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, LockstepTransport   # lazy: start-up
        from stvm.project import Options, load, resolve   # lazy: start-up
        from stvm.scenario import Scenario, ScenarioDriver, load_scenario   # lazy: start-up
        self.spec = spec
        if project is None:
            resolved = spec.resolved or resolve(list(spec.files), Options(sysmac=tuple(spec.settings_overrides),
                                                                           use_cache=spec.use_cache))
            project = load(resolved)
        self.project = project
        self.scenario = load_scenario(spec.scenario) if spec.scenario else Scenario()
        scenario = self.scenario
        emu_settings, plan = scenario.emulator_plan()
        from emulator import parse_fault   # lazy: start-up
        for text in spec.faults:
            plan = parse_fault(text, plan)
        latency_scans = spec.latency_scans if spec.latency_scans is not None else \
            (scenario.latency_scans if scenario.latency_scans is not None else 1)
        latency_ns = spec.latency_ns if spec.latency_ns is not None else scenario.latency_ns
        self.transport = LockstepTransport(latency_scans=latency_scans, latency_ns=latency_ns,
                                           settings=emu_settings, faults=plan)
        scan = spec.scan if spec.scan is not None else (scenario.scan or "1ms")
        self.vm = self.project.start(scan=scan, transport=self.transport)
        self.cycles = spec.cycles if spec.cycles is not None else (
            scenario.cycles if scenario.cycles is not None else DEFAULT_CYCLES)
        self.events: list[tuple[int, str]] = []
        self.driver = ScenarioDriver(scenario, self.vm, self.transport.inject_fault,
                                     on_event=lambda event, scan: self.events.append((scan, event.describe())))
        if scenario.robot_address:
            self.driver._assign(scenario.robot_address, f"'{LOCKSTEP_HOST}'", "[robot]")
        if scenario.robot_port:
            self.driver._assign(scenario.robot_port, LOCKSTEP_PORT, "[robot]")

    def wire(self, sampler: Callable | None = None) -> None:
        vm = self.vm
        if sampler is not None:
            vm.on_scan_end.append(sampler)
        vm.on_scan_end.append(self.driver.after_scan)
        self.transport.attach(vm)   # appends the emulator step last
        self.driver.apply_initial()


def run_trace(spec: TraceSpec, project=None, progress: Callable[[int], None] | None = None) -> TraceRun:
    """Run `spec` in lockstep and record it. A runtime fault ends the run early; it is recorded
    as an event and returned in `TraceRun.fault` (not raised)."""
    from stvm.runtime.vm import RuntimeFault   # lazy: start-up
    prepared = Prepared(spec, project)
    vm = prepared.vm
    patterns = list(spec.watch) or list(prepared.scenario.watch)
    if not patterns:
        raise WatchError("nothing to record: give --watch PATTERN (or [record] watch in the scenario)")
    signals = select_signals(vm, patterns)
    recorder = Recorder(vm, signals)
    tcp_path = None
    if spec.record_tcp:
        from stvm.trace.tcp_path import TcpPathRecorder   # lazy: start-up
        tcp_path = TcpPathRecorder(prepared.transport)

        def sample(vm, recorder_sample=recorder.sample) -> None:
            recorder_sample(vm)
            tcp_path.sample(vm)
        prepared.wire(sample)
    else:
        prepared.wire(recorder.sample)
    if spec.record_frames:
        prepared.transport.on_frame.append(recorder.on_frame)
    fault = None
    try:
        for i in range(prepared.cycles):
            vm.scan()
            if progress is not None and i % 1000 == 999:
                progress(i + 1)
    except RuntimeFault as exc:
        fault = exc
        recorder.sample(vm)   # the state the fault left, as the scan's sample
        where = f"{os.path.basename(exc.span.file)}:{exc.span.line}:{exc.span.column}: " if exc.span else ""
        prepared.events.append((exc.scan, f"runtime fault: {where}{exc.message}"))
    for scan, text in prepared.events:
        recorder.event(text, scan)
    meta = {
        "files": [os.path.basename(str(f)) for f in spec.files],
        "scenario": os.path.basename(str(spec.scenario)) if spec.scenario else None,
        "latency_ns": prepared.transport.latency_ns,
        "watch": patterns,
    }
    trace = recorder.finish(meta)
    vm.close()
    return TraceRun(trace, vm, prepared.transport, prepared.project, fault, prepared.scenario, signals, tcp_path)
