"""Start-up time to a usable HMI page and update latency to the page (issue 32's note).

    PYTHONPATH=. python bench/hmi_latency.py [--writes 50]

1. runs `stvm run st_src/PnP_Example.st --scan 1ms --hmi 127.0.0.1:0` (bundled emulator, real
   time) and measures: process start → the "HMI:" line; → Chromium (Debian's) shows pgConnect live
   (body data-live="on", every value filled in);
2. with a WebSocket client on pgMoveAbsolute, writes MoveAbs_Param.Speed over POST /api/vars and
   measures write sent → the new value in a WebSocket message (p50 / p95 / max).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
from websockets.sync.client import connect

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--writes", type=int, default=50)
    args = parser.parse_args()
    started = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "stvm", "run", str(ROOT / "st_src" / "PnP_Example.st"),
                             "--scan", "1ms", "--hmi", "127.0.0.1:0"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    found = threading.Event()
    lines: list[str] = []

    def read() -> None:
        for line in proc.stderr:
            lines.append(line)
            if line.startswith("HMI: "):
                found.set()
    threading.Thread(target=read, daemon=True).start()
    try:
        assert found.wait(120), "".join(lines)
        t_url = time.perf_counter() - started
        url = next(x for x in lines if x.startswith("HMI: "))[5:].split()[0]
        base = url.rstrip("/")
        from playwright.sync_api import sync_playwright
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path="/usr/bin/chromium", headless=True,
                                         args=["--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"])
            tab = browser.new_page(viewport={"width": 800, "height": 480})
            t0 = time.perf_counter()
            tab.goto(base + "/page/pgConnect")
            tab.wait_for_selector("body[data-live='on']", timeout=30_000)
            t_page = time.perf_counter() - t0
            browser.close()
        latencies = []
        with connect(base.replace("http", "ws") + "/ws?page=pgMoveAbsolute") as ws:
            ws.recv(timeout=5)
            for i in range(args.writes):
                value = 100 + i
                sent = time.perf_counter()
                reply = httpx.post(base + "/api/vars", json={"MoveAbs_Param.Speed": str(value)}, timeout=5)
                assert reply.status_code == 200, reply.text
                while True:
                    message = json.loads(ws.recv(timeout=5))
                    if message.get("values", {}).get("MoveAbs_Param.Speed") == value:
                        latencies.append((time.perf_counter() - sent) * 1000)
                        break
        latencies.sort()
        print(f"start-up: process → HMI URL printed      {t_url:6.2f} s")
        print(f"start-up: page opened → live in Chromium  {t_page:6.2f} s  (total {t_url + t_page:.2f} s)")
        print(f"update latency write → WebSocket ({len(latencies)} writes): p50 {statistics.median(latencies):.1f} ms, "
              f"p95 {latencies[int(len(latencies) * 0.95) - 1]:.1f} ms, max {latencies[-1]:.1f} ms")
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()


if __name__ == "__main__":
    main()
