"""A running thesis VM with its OPC UA server, as `stvm run … --opcua` runs it, for asyncua clients.

The VM runs in its own thread on the virtual clock, wired to the in-process emulated robot
(lockstep: deterministic, no robot socket) and the PnP demo scenario; the server listens on
127.0.0.1 on an ephemeral port. Tests drive it with asyncua's real client over loopback.
"""

from __future__ import annotations

import asyncio
import copy
import threading
from pathlib import Path

from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, start_lockstep
from stvm.opcua import load_config
from stvm.opcua.server import OpcUaServer
from stvm.scenario import ScenarioDriver, load_scenario

ROOT = Path(__file__).resolve().parents[2]
THESIS = [str(ROOT / "st_src" / "PnP_Example.st")]
DEMO_SCENARIO = ROOT / "st_src" / "scenarios" / "pnp_demo.toml"
LOOPBACK = "opc.tcp://127.0.0.1:0"


def wire_demo(vm) -> None:
    """The PnP demo scenario with the lockstep robot's address, as `stvm debug` wires it."""
    scenario = load_scenario(DEMO_SCENARIO)
    driver = ScenarioDriver(scenario, vm)
    driver.apply_initial({scenario.robot_address: f"'{LOCKSTEP_HOST}'", scenario.robot_port: LOCKSTEP_PORT})
    vm.on_scan_end.append(driver.after_scan)


class Running:
    """The VM's scan loop in a thread beside a started OPC UA server; `close()` ends both."""

    def __init__(self, project, opcua: dict | None = None, demo: bool = True, files=None,
                 limits: dict | None = None) -> None:
        self.vm, self.transport = start_lockstep(project, "1ms")
        if demo:
            wire_demo(self.vm)
        manifest = copy.deepcopy(project.manifest)
        manifest["opcua"] = {"start": "paused", **(opcua or {})}
        if limits is not None:   # entries over the project's own [limits] table
            manifest["limits"] = {**manifest.get("limits", {}), **limits}
        self.config = load_config(manifest, project.root, files or THESIS, LOOPBACK)
        self.server = OpcUaServer(self.vm, self.config)
        self.url = self.server.start()
        self.ns_uri = self.config.namespace_uri
        self._stop = threading.Event()
        self.errors: list[BaseException] = []
        self.thread = threading.Thread(target=self._loop, daemon=True)
        self.thread.start()

    def _loop(self) -> None:
        try:
            self.vm.run(until=self._stop.is_set)
        except BaseException as exc:   # noqa: BLE001 - asserted by close()
            self.errors.append(exc)

    def close(self) -> None:
        self._stop.set()
        self.server.stop()          # releases a paused VM
        self.thread.join(10)
        self.vm.close()
        assert not self.thread.is_alive(), "the scan loop did not stop"
        assert not self.errors, self.errors


def run_async(coro, timeout: float = 60):
    """Run one client coroutine to completion (each test owns its event loop)."""
    return asyncio.run(asyncio.wait_for(coro, timeout))
