"""Helpers of the HMI tests: the thesis project with its pages, served live beside a running VM.

`live_hmi` runs the VM in a thread on the real-time clock against the in-process (lockstep)
emulator, with motions sped up (`time_scale`), and serves the thesis pages on an ephemeral
loopback port: what `stvm run st_src/PnP_Example.st --hmi PORT` does, without a subprocess.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path

from stvm.frontend import VariableBridge
from stvm.frontend.limits import LimitTable
from stvm.hmi import HmiServer, from_lockstep, load_pages
from stvm.hmi.cli import page_files

ROOT = Path(__file__).resolve().parents[2]
THESIS = ROOT / "st_src" / "PnP_Example.st"


@dataclass
class LiveHmi:
    server: HmiServer
    vm: object
    transport: object
    thread: threading.Thread
    stop_flag: threading.Event

    @property
    def base(self) -> str:
        return f"http://127.0.0.1:{self.server.port}"

    def stop(self) -> None:
        self.stop_flag.set()
        self.thread.join(10)
        self.server.stop()
        self.vm.close()


def start_live_hmi(project, time_scale: float = 0.25, host: str = "127.0.0.1", token: str | None = None,
                   emulator_settings: dict | None = None, update_ns: int | None = None) -> LiveHmi:
    from emulator import DEFAULT_SETTINGS
    from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, LockstepTransport
    settings = DEFAULT_SETTINGS.with_(time_scale=time_scale, **(emulator_settings or {}))
    transport = LockstepTransport(latency_scans=1, settings=settings)
    vm = project.start(scan="1ms", realtime=True, transport=transport)
    transport.attach(vm)
    vm["Connect_AddressIP"] = LOCKSTEP_HOST   # what the HMI scenario's [robot] table does
    vm["Connect_Dest_PortIP"] = LOCKSTEP_PORT
    bridge = VariableBridge(vm)
    files, start = page_files(project)
    hmi = load_pages(files, bridge.type_of, start)
    kwargs = {"update_ns": update_ns} if update_ns else {}
    kwargs["limit_table"] = LimitTable.for_project(project, vm)   # st_src/hmi/limits.toml
    server = HmiServer(hmi, bridge, host=host, port=0, token=token, pose=from_lockstep(transport),
                       run_parameters={"robot_host": LOCKSTEP_HOST, "robot_port": LOCKSTEP_PORT}, **kwargs)
    server.start()
    stop_flag = threading.Event()
    thread = threading.Thread(target=lambda: vm.run(until=stop_flag.is_set), name="test-vm", daemon=True)
    thread.start()
    return LiveHmi(server, vm, transport, thread, stop_flag)

