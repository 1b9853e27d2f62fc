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


def trace_session(spec: TraceSpec, project=None):
    """The session `spec` records (stvm/session.py: the lockstep robot, the scenario), not yet
    wired; also what the writer search replays to a given scan. Loads the project through the
    driver unless given."""
    from stvm.project import Options, load, resolve   # lazy: start-up
    from stvm.session import Session, SessionConfig   # lazy: start-up
    if project is None:
        resolved = spec.resolved or resolve(list(spec.files), Options(sysmac=tuple(spec.settings_overrides),
                                                                       use_cache=spec.use_cache))
        project = load(resolved)
    config = SessionConfig(scan=spec.scan, default_scan="1ms", scenario=spec.scenario, robot="lockstep",
                           latency_scans=spec.latency_scans, latency_ns=spec.latency_ns, faults=spec.faults,
                           record_events=True)
    return Session(project, config)


def trace_cycles(spec: TraceSpec, session) -> int:
    """Scans to run: the spec's, else the scenario's `[run] cycles`, else DEFAULT_CYCLES."""
    if spec.cycles is not None:
        return spec.cycles
    return session.scenario.cycles if session.scenario.cycles is not None else DEFAULT_CYCLES


def run_trace(spec: TraceSpec, project=None, progress: Callable[[int], None] | None = None) -> TraceRun:
    """Run `spec` in lockstep and record it. A runtime fault ends the run early; it is recorded
    as an event and returned in `TraceRun.fault` (not raised)."""
    from stvm.runtime.vm import RuntimeFault   # lazy: start-up
    session = trace_session(spec, project)
    vm = session.vm
    vm.collect_stats = False   # a trace reports no scan times: two clock reads a scan saved
    patterns = list(spec.watch) or list(session.scenario.watch)
    if not patterns:
        raise WatchError("nothing to record: give --watch PATTERN (or [record] watch in the scenario)")
    signals = select_signals(vm, patterns)
    recorder = Recorder(vm, signals)
    tcp_path = None
    if spec.record_tcp:
        from stvm.trace.tcp_path import TcpPathRecorder   # lazy: start-up
        tcp_path = TcpPathRecorder(session.transport)

        def sample(vm, recorder_sample=recorder.sample) -> None:
            recorder_sample(vm)
            tcp_path.sample(vm)
        session.wire(sample)
    else:
        session.wire(recorder.sample)
    if spec.record_frames:
        session.transport.on_frame.append(recorder.on_frame)
    fault = None
    try:
        for i in range(trace_cycles(spec, session)):
            vm.scan()
            if progress is not None and i % 1000 == 999:
                progress(i + 1)
    except RuntimeFault as exc:
        fault = exc
        recorder.sample(vm)   # the state the fault left, as the scan's sample
        where = f"{os.path.basename(exc.span.file)}:{exc.span.line}:{exc.span.column}: " if exc.span else ""
        session.events.append((exc.scan, f"runtime fault: {where}{exc.message}"))
    for scan, text in session.events:
        recorder.event(text, scan)
    meta = {
        "files": [os.path.basename(str(f)) for f in spec.files],
        "scenario": os.path.basename(str(spec.scenario)) if spec.scenario else None,
        "latency_ns": session.transport.latency_ns,
        "watch": patterns,
    }
    trace = recorder.finish(meta)
    session.close()
    return TraceRun(trace, vm, session.transport, session.project, fault, session.scenario, signals, tcp_path)
