"""`stvm debug … --hmi`: the pages on the debugged VM. While the debugger holds the VM, reads have
no new snapshot (503) and writes wait for the next scan (202, queued, not lost)."""

from __future__ import annotations

import queue
import subprocess
import sys
import threading
import time

import httpx

from hmi_helpers import ROOT


def test_debug_session_serves_the_pages_and_queues_writes_while_stopped():
    proc = subprocess.Popen([sys.executable, "-m", "stvm", "debug", str(ROOT / "st_src" / "PnP_Example.st"),
                             "--scan", "1ms", "--scenario", str(ROOT / "st_src" / "scenarios" / "pnp_hmi.toml"),
                             "--hmi", "127.0.0.1:0"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in proc.stdout], daemon=True).start()
    seen: list[str] = []

    def wait_line(prefix: str, timeout_s: float = 120) -> str:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            try:
                line = lines.get(timeout=1)
            except queue.Empty:
                continue
            seen.append(line)
            if line.removeprefix("(stvm) ").startswith(prefix):
                return line
        raise AssertionError(f"no line starting {prefix!r} in:\n{''.join(seen)}")

    def command(text: str) -> None:
        proc.stdin.write(text + "\n")
        proc.stdin.flush()

    try:
        url = wait_line("HMI: ")[5:].strip().rstrip("/")
        with httpx.Client(base_url=url, timeout=10) as http:
            assert "data-var=\"Connect_Time_Out\"" in http.get("/page/pgConnect").text
            # stopped at entry, between scans: the debugger runs the VM's idle hooks, so the bridge
            # applies the write at once (as a controller in program mode), no scan needed
            applied = http.post("/api/vars", json={"Connect_Time_Out": "120"})
            assert applied.status_code == 200, applied.text
            assert http.get("/api/vars", params={"path": "Connect_Time_Out"}).status_code == 503
            command("scan 3")
            wait_line("Scan end")
            command("print Connect_Time_Out")
            assert wait_line("Connect_Time_Out =").strip().endswith("= 120")
            # the [robot] table of the scenario gave the lockstep robot's address
            command("print Connect_Dest_PortIP")
            assert wait_line("Connect_Dest_PortIP =").strip().endswith("= 5890")
        command("quit")
        assert proc.wait(30) == 0, "".join(seen)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert "Traceback" not in "".join(seen)
