"""`stvm run … --opcua` and `stvm debug … --opcua` as a user starts them, driven by an OPC UA client."""

from __future__ import annotations

import asyncio
import os
import re
import signal
import subprocess
import sys
import threading
import time

from asyncua import Client, ua
from opcua_helpers import LOOPBACK, ROOT, run_async

SERVER_LINE = re.compile(r"OPC UA server on (opc\.tcp://\S+): namespace (\S+) \(ns=(\d+)\)")


class Process:
    """A `stvm` subprocess whose stderr is collected line by line (the server line is on stderr)."""

    def __init__(self, *args: str, stdin: bool = False) -> None:
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen([sys.executable, "-m", "stvm", *args], cwd=ROOT, env=env, text=True,
                                     stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.err: list[str] = []
        self.out: list[str] = []
        for stream, sink in ((self.proc.stderr, self.err), (self.proc.stdout, self.out)):
            threading.Thread(target=lambda s=stream, k=sink: k.extend(iter(s.readline, "")), daemon=True).start()

    def wait_for(self, pattern: re.Pattern, lines: list[str], timeout: float = 90) -> re.Match:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(lines):
                match = pattern.search(line)
                if match:
                    return match
            if self.proc.poll() is not None:
                break
            time.sleep(0.05)
        raise AssertionError(f"no {pattern.pattern!r}; stderr: {''.join(self.err)} stdout: {''.join(self.out)[-2000:]}")

    def finish(self, timeout: float = 30) -> int:
        try:
            return self.proc.wait(timeout)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()


def test_run_thesis_demo_browsed_and_driven(tmp_path):
    """The issue's acceptance: `stvm run st_src/PnP_Example.st --opcua` (real-time demo, bundled
    emulator over TCP): browse, see Cobot.Connected go TRUE as the connect runs, write a segment."""
    run = Process("run", "st_src/PnP_Example.st", "--opcua", LOOPBACK, "--duration", "120s")
    try:
        url, uri, _ = run.wait_for(SERVER_LINE, run.err).groups()

        async def body():
            async with Client(url) as client:
                ns = await client.get_namespace_index(uri)
                globals_folder = await client.nodes.objects.get_child(f"{ns}:Globals")
                connected = await globals_folder.get_child([f"{ns}:Cobot", f"{ns}:Connected"])
                assert connected.nodeid == ua.NodeId("Cobot.Connected", ns)
                changes = []
                became_true = asyncio.Event()

                class Handler:
                    def datachange_notification(self, monitored, value, data):
                        changes.append(value)
                        if value is True:
                            became_true.set()
                subscription = await client.create_subscription(50, Handler())
                await subscription.subscribe_data_change(connected)
                await asyncio.wait_for(became_true.wait(), 60)
                speed = client.get_node(ua.NodeId("PnP_MoveParameters[1].Speed", ns))
                await speed.write_value(ua.Variant(35, ua.VariantType.UInt16))
                assert await speed.read_value() == 35
                runtime = await client.nodes.objects.get_child(f"{ns}:Runtime")
                clock = await runtime.get_child(f"{ns}:Clock")
                assert await clock.read_value() == "real-time"
                names = {(await m.read_browse_name()).Name for m in await runtime.get_methods()}
                assert names == set()   # no stepping on the real-time clock
                return changes
        changes = run_async(body(), timeout=120)
        assert changes[-1] is True
    finally:
        run.proc.send_signal(signal.SIGINT)
        code = run.finish()
    assert code == 0, "".join(run.err)


def test_bad_opcua_options_are_usage_errors(tmp_path):
    (tmp_path / "main.st").write_text("PROGRAM Main VAR x : INT; END_VAR x := x + 1; END_PROGRAM\n")
    (tmp_path / "stvm.toml").write_text('[opcua]\npublish = ["Main.nope"]\n')
    bad_url = subprocess.run([sys.executable, "-m", "stvm", "run", str(tmp_path / "main.st"), "--opcua", "http://x:1"],
                             capture_output=True, text=True, cwd=ROOT)
    assert bad_url.returncode == 2 and "expected opc.tcp://HOST:PORT" in bad_url.stderr
    bad_rule = subprocess.run([sys.executable, "-m", "stvm", "run", str(tmp_path / "main.st"), "--opcua", LOOPBACK],
                              capture_output=True, text=True, cwd=ROOT)
    assert bad_rule.returncode == 2 and "publish: 'Main.nope' matches no variable" in bad_rule.stderr
    assert "Traceback" not in bad_url.stderr + bad_rule.stderr
    remote = subprocess.run([sys.executable, "-m", "stvm", "run", str(tmp_path / "main.st"), "--opcua",
                             "opc.tcp://0.0.0.0:4840"], capture_output=True, text=True, cwd=ROOT)
    assert remote.returncode == 2 and "not a loopback address" in remote.stderr


def test_debug_session_read_between_scans(tmp_path):
    debug = Process("debug", "st_src/PnP_Example.st", "--scenario", "st_src/scenarios/pnp_demo.toml",
                    "--scan", "1ms", "--opcua", LOOPBACK, stdin=True)
    try:
        url, uri, _ = debug.wait_for(SERVER_LINE, debug.err).groups()
        debug.proc.stdin.write("scan 1500\n")
        debug.proc.stdin.flush()
        debug.wait_for(re.compile(r"Scan end"), debug.out)

        async def body():
            async with Client(url) as client:
                ns = await client.get_namespace_index(uri)
                values = await client.read_values([client.get_node(ua.NodeId(p, ns)) for p in
                                                   ("Cobot.Connected", "@Runtime.ScanCount")])
                runtime = client.get_node(ua.NodeId("@Runtime", ns))
                return values, await runtime.get_methods()
        (connected, scans), methods = run_async(body())
        assert connected is True and scans == 1500   # the lockstep robot connected, read between scans
        assert methods == []                          # the debugger is the run control
        debug.proc.stdin.write("quit\n")
        debug.proc.stdin.flush()
        assert debug.finish() == 0
    finally:
        if debug.proc.poll() is None:
            debug.proc.kill()
