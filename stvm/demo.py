"""The thesis demo: `stvm run st_src/PnP_Example.st --scan 1ms` against the bundled TM emulator.

When the project's manifest (`stvm.toml`) has a `[demo]` table, `stvm run` becomes the demo:
it starts the emulator on a loopback port (unless `--robot HOST:PORT` names a robot), applies the
manifest's scenario (robot address, PnP segments, Execute inputs), runs on the real-time clock
(the robot moves in wall-clock time) and shows a live status until Ctrl-C, `--cycles N` scans,
`--duration`, `--until EXPR`, or the number of complete cycles the manifest asks for (`[demo]
cycles = N`, or the short flag it declares: `cycles_flag = "--pnp-cycles"` makes `--pnp-cycles N`).
"""

from __future__ import annotations

import contextlib
import errno
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from emulator.terminal_text import plain, printable

# lazy: start-up (`stvm` imports this module to look for `stvm.demo.cli`; the scenario reader,
# the VM and the emulator load when a demo runs)

TM_LISTEN_PORT = 5890


def free_loopback_port(preferred: int = TM_LISTEN_PORT, below: int = 32768) -> int:
    """A free TCP port on 127.0.0.1, `preferred` if possible.

    The thesis HMI variable for the port (`Connect_Dest_PortIP`, Table 6.2.1) is an INT, so the
    demo only uses ports up to 32767 (the Listen Node default 5890 first)."""
    import random   # lazy: start-up (`stvm` imports this module on every call)
    import socket
    candidates = [preferred] + random.Random().sample(range(20000, below), 200)
    for port in candidates:
        with contextlib.closing(socket.socket(socket.AF_INET, socket.SOCK_STREAM)) as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError(f"no free loopback port below {below}")


def parse_robot(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"--robot needs HOST:PORT, got {text!r}")
    return host, int(port)


@dataclass
class DemoState:
    cycles: int = 0
    last_step: Any = None
    step_since_ns: int = 0
    history: list[str] = field(default_factory=list)


class Demo:
    """Everything the demo adds around a VM run."""

    def __init__(self, project, vm, args, cycles: int | None = None) -> None:
        """`cycles`: stop after this many complete cycles (None: no limit)."""
        self.project = project
        self.vm = vm
        self.args = args
        self.cycle_limit = cycles
        self.config = project.manifest.get("demo", {})
        self.server = None
        self.robot_address: tuple[str, int] | None = None
        self.state = DemoState()
        self.step_variable = self.config.get("step_variable")
        self.cycle_from = self.config.get("cycle_from")
        self.cycle_to = self.config.get("cycle_to")
        self.status_paths = list(self.config.get("status", []))
        # STRING variables with the last error text (CBT_Connect's Connect_ErrorDescrip, …):
        # shown in the table and, whenever not empty, on the line-a-second output too
        self.error_paths = list(self.config.get("errors", []))
        # the manifest names its demo (libraries other than the thesis's have one each)
        self.title = str(self.config.get("title", "thesis PnP demo"))
        self.started = time.monotonic()

    # ---- setup
    def start(self) -> None:
        root = self.project.root or Path(".")
        config_scenario = self.config.get("scenario")
        hmi_table = self.project.manifest.get("hmi", {})
        if getattr(self.args, "hmi", None) and isinstance(hmi_table, dict) and "scenario" in hmi_table:
            config_scenario = hmi_table["scenario"]   # the operator drives the cell from the pages
        scenario_path = self.args.scenario or (root / config_scenario if config_scenario else None)
        from stvm.scenario import ScenarioDriver, load_scenario   # lazy: start-up
        scenario = load_scenario(scenario_path) if scenario_path else None
        if self.args.robot:
            self.robot_address = parse_robot(self.args.robot)
        else:
            import emulator   # lazy: start-up
            for attempt in range(5):
                # another process may take the port between the probe and the bind (parallel
                # demos, a test suite on several cores): then take another one
                port = free_loopback_port()
                try:
                    self.server = emulator.start_server(host="127.0.0.1", port=port,
                                                        log_path=self.args.emulator_log)
                    break
                except OSError as exc:
                    if exc.errno != errno.EADDRINUSE or attempt == 4:
                        raise
            self.robot_address = ("127.0.0.1", self.server.port)
        overrides: dict[str, Any] = {}
        if scenario is not None:
            if scenario.robot_address:
                overrides[scenario.robot_address] = self.robot_address[0]
            if scenario.robot_port:
                overrides[scenario.robot_port] = self.robot_address[1]
            driver = ScenarioDriver(scenario, self.vm)
            driver.apply_initial(overrides)
            self.vm.on_scan_end.append(driver.after_scan)
        self.vm.on_scan_end.append(self.after_scan)

    def stop(self) -> None:
        if self.server is not None:
            self.server.stop()

    # ---- per scan
    def after_scan(self, vm) -> None:
        if not self.step_variable:
            return
        step = vm.get(self.step_variable)
        if step != self.state.last_step:
            if self.state.last_step == self.cycle_from and step == self.cycle_to:
                self.state.cycles += 1
            self.state.last_step = step
            self.state.step_since_ns = vm.now_ns

    def error_rows(self) -> list[tuple[str, str]]:
        """The error variables that are not empty (connection refused, motion rejected, …)."""
        rows = []
        for path in self.error_paths:
            try:
                text = self.vm.format(path)
            except KeyError:
                continue
            if text not in ("''", '""'):
                rows.append((path, text))
        return rows

    def done(self) -> bool:
        return self.cycle_limit is not None and self.state.cycles >= self.cycle_limit

    # ---- display
    def status_rows(self) -> list[tuple[str, str]]:
        rows = [("robot", f"{self.robot_address[0]}:{self.robot_address[1]}" + (" (bundled emulator)" if self.server else "")),
                ("VM time", f"{self.vm.now_ns / 1e9:.3f} s, scan {self.vm.scan_count}"),
                ("PnP cycles done", str(self.state.cycles))]
        for path in self.status_paths + [p for p in self.error_paths if p not in self.status_paths]:
            try:
                rows.append((path, self.vm.format(path)))
            except KeyError:
                rows.append((path, "?"))
        if self.server is not None:
            snap = self.server.snapshot()
            pose = snap.get("pose") or snap.get("tcp_pose") or snap.get("cartesian")
            if pose is not None:
                rows.append(("robot pose", ", ".join(f"{float(v):.1f}" for v in pose)))
            rows.append(("robot state", f"{snap.get('state', '?')}, moving {snap.get('moving')}, "
                                        f"queue {snap.get('queue_length', '?')}, paused {snap.get('paused')}"))
            frames = snap.get("recent_frames") or []
            last_rx = next((f for f in reversed(frames) if _frame_dir(f) == "rx"), None)
            last_tx = next((f for f in reversed(frames) if _frame_dir(f) == "tx"), None)
            rows.append(("last frame PLC→robot", _frame_text(last_rx)))
            rows.append(("last frame robot→PLC", _frame_text(last_tx)))
        from stvm.runtime.vm import timing_us   # lazy: start-up
        scan = timing_us(self.vm.scan_durations_ns)
        if scan is not None:
            rows.append(("scan time", f"mean {scan[0]:.0f} µs, p99 {scan[2]:.0f} µs, max {scan[3]:.0f} µs"))
        from stvm.stdlib.sockets import socket_service_us   # lazy: start-up
        service = socket_service_us(self.vm)
        if service is not None:
            rows.append(("socket service", f"between scans, mean {service[0]:.0f} µs, p99 {service[2]:.0f} µs"))
        if self.vm.realtime:
            rows.append(("deadlines", f"overruns {self.vm.overruns}, catch-up scans {self.vm.catch_up_scans}, "
                                      f"over the period {self.vm.long_scans}, max lateness {self.vm.max_lateness_ns / 1000:.0f} µs"))
        return rows


def _frame_dir(frame: Any) -> str | None:
    if isinstance(frame, dict):
        return frame.get("dir")
    if isinstance(frame, (tuple, list)) and len(frame) >= 2:
        return frame[1]
    return None


def _frame_text(frame: Any) -> str:
    if frame is None:
        return "-"
    data = frame.get("data") if isinstance(frame, dict) else frame[2] if isinstance(frame, (tuple, list)) and len(frame) > 2 else frame
    if isinstance(data, bytes):
        data = data.decode("latin-1")
    return printable(str(data)[:110])


def run_with_status(demo: Demo, run_scans, stream=None) -> None:
    """Run the VM while showing the status: a rich live table on a terminal, else a line a second."""
    stream = stream or sys.stdout
    if stream.isatty():
        from rich.live import Live
        from rich.table import Table

        def render() -> Table:
            table = Table(title=f"stvm — {demo.title} (Ctrl-C to stop)", show_header=False)
            table.add_column("what", style="bold")
            table.add_column("value")
            # plain text, control characters escaped: frames and ST strings (error
            # descriptions) come from the robot and the program (issue 34 item 6)
            for name, value in demo.status_rows():
                table.add_row(plain(name), plain(value))
            return table

        with Live(render(), refresh_per_second=8, transient=False) as live:
            def refresh(vm) -> None:
                if vm.scan_count % 100 == 0:
                    live.update(render())
            demo.vm.on_scan_end.append(refresh)
            run_scans()
            live.update(render())
        return
    last_print = [-1]

    def line(vm) -> None:
        second = vm.now_ns // 1_000_000_000
        if second != last_print[0]:
            last_print[0] = second
            fields = printable("  ".join(f"{k}={v}" for k, v in demo.status_rows()[1:6] + demo.error_rows()))
            print(fields, file=stream, flush=True)
    demo.vm.on_scan_end.append(line)
    run_scans()
