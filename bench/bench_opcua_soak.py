"""OPC UA soak under a hostile client (issue 34 item 5): memory and descriptors flat, the scan's
p99 unchanged, and the time to a first value and the subscription latency.

The thesis program runs on the real-time clock (10 ms scans) with the OPC UA server on loopback
and one well-behaved client (another process) subscribed to 20 variables. Phase 1 (quiet) then
phase 2 (hostile: another process that, in a loop, sends chunk headers claiming 2 GiB followed
by MiBs of body, opens idle connections past max_connections, logs in and creates the most
subscriptions and monitored items a session may have at sampling interval 0 (and NaN), calls
methods with extra arguments) each last --seconds. Printed: the scan duration and start lateness
p50/p99 per phase, RSS and open descriptors before, during and after, the quiet client's
notification count per phase (it must keep being served). No pass/fail: figures side by side.

Also: start-up time to a first OPC UA value (`stvm run … --opcua` as a fresh process until a
client has read a value) and the subscription latency (a write by one client until another
client's data change arrives, median of 50).

    python bench/bench_opcua_soak.py [--seconds 10]
"""

from __future__ import annotations

import argparse
import asyncio
import math
import os
import socket
import statistics
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "opcua"))
FILES = [str(ROOT / "st_src" / "PnP_Example.st")]


def rss_mb() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return 0.0


def fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def pct(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(len(values) * p))] if values else float("nan")


async def attack(url: str, ns_uri: str, seconds: float) -> None:
    from asyncua import Client, ua
    host, port = url.split("//")[1].rstrip("/").rsplit(":", 1)
    port = int(port)
    end = time.monotonic() + seconds
    idle = []
    rounds = 0
    while time.monotonic() < end:
        rounds += 1
        # 1. a chunk header claiming 2 GiB, then 4 MiB of body
        try:
            reader, writer = await asyncio.open_connection(host, port)
            writer.write(b"HELF" + struct.pack("<I", 2**31) + b"\0" * (4 << 20))
            await asyncio.wait_for(writer.drain(), 2)
            writer.close()
        except (OSError, asyncio.TimeoutError):
            pass
        # 2. idle connections past max_connections
        for _ in range(30):
            try:
                idle.append(await asyncio.open_connection(host, port))
            except OSError:
                break
        # 3. a session with the most subscriptions and items at sampling 0, NaN intervals, bad calls
        try:
            async with Client(url, timeout=5) as client:
                ns = await client.get_namespace_index(ns_uri)
                nodes = [client.get_node(n.nodeid) for n in await client.get_node(ua.NodeId("@Globals", ns)).get_children()]
                leaves = []
                for node in nodes[:50]:
                    leaves += [node] + list(await node.get_children())
                for _ in range(12):
                    try:
                        sub = await client.create_subscription(1, None)
                    except Exception:   # noqa: BLE001 - refused past the cap: expected
                        break
                    try:
                        await sub.subscribe_data_change(leaves * 20, sampling_interval=0, queuesize=0)
                        await sub.subscribe_data_change(leaves[:5], sampling_interval=math.nan)
                    except Exception:   # noqa: BLE001
                        pass
                runtime = client.get_node(ua.NodeId("@Runtime", ns))
                for _ in range(5):
                    try:
                        await runtime.call_method(f"{ns}:Pause", ua.Variant(1, ua.VariantType.UInt32))
                    except Exception:   # noqa: BLE001
                        pass
        except Exception:   # noqa: BLE001 - refused sessions are part of the attack
            pass
        for _, writer in idle:
            writer.close()
        idle = []
    print(f"attack rounds: {rounds}")


def soak(seconds: float) -> None:
    import stvm
    from asyncua import Client, ua
    from stvm.opcua import load_config
    from stvm.opcua.server import OpcUaServer

    project = stvm.load(FILES)
    vm = project.start(scan="10ms", realtime=True)
    config = load_config(project.manifest, project.root, FILES, "opc.tcp://127.0.0.1:0")
    server = OpcUaServer(vm, config)
    url = server.start()
    marks: list[tuple[float, float]] = []

    def started(vm_):
        marks.append((time.perf_counter(), 0.0))

    def ended(vm_):
        start, _ = marks[-1]
        marks[-1] = (start, time.perf_counter() - start)

    vm.on_scan_start.insert(0, started)
    vm.on_scan_end.append(ended)
    stop = threading.Event()
    runner = threading.Thread(target=lambda: vm.run(until=stop.is_set), daemon=True)
    runner.start()
    notified = [0]

    class Count:
        def datachange_notification(self, *args):
            notified[0] += 1

    quiet_ready = threading.Event()
    quiet_stop = threading.Event()

    def quiet_client():
        async def body():
            async with Client(url) as client:
                ns = await client.get_namespace_index(config.namespace_uri)
                sub = await client.create_subscription(50, Count())
                nodes = [client.get_node(ua.NodeId(p, ns)) for p in ("@Runtime.ScanCount", "@Runtime.Time")]
                await sub.subscribe_data_change(nodes, sampling_interval=0)
                quiet_ready.set()
                while not quiet_stop.is_set():
                    await asyncio.sleep(0.1)
        asyncio.run(body())

    quiet = threading.Thread(target=quiet_client, daemon=True)
    quiet.start()
    quiet_ready.wait(30)
    time.sleep(1)
    rows = []

    def phase(name, hostile):
        before_rss, before_fd, first, n0 = rss_mb(), fds(), len(marks), notified[0]
        proc = None
        if hostile:
            proc = subprocess.Popen([sys.executable, __file__, "--attack", url, config.namespace_uri, str(seconds)])
            proc.wait(seconds + 60)
        else:
            time.sleep(seconds)
        sample = marks[first:]
        durations = [d * 1e3 for _, d in sample if d]
        starts = [s for s, _ in sample]
        late = [max(0.0, (b - a) * 1e3 - 10.0) for a, b in zip(starts, starts[1:])]
        rows.append((name, pct(durations, 0.5), pct(durations, 0.99), pct(late, 0.5), pct(late, 0.99),
                     before_rss, rss_mb(), before_fd, fds(), notified[0] - n0))

    phase("quiet", False)
    phase("hostile", True)
    time.sleep(12)   # login_timeout closes what the attack left open
    phase("after", False)
    quiet_stop.set()
    quiet.join(10)
    stop.set()
    server.stop()
    runner.join(10)
    vm.close()
    print(f"{'phase':8} {'scan p50':>9} {'scan p99':>9} {'late p50':>9} {'late p99':>9} "
          f"{'RSS MB':>15} {'fds':>9} {'notified':>9}")
    for name, d50, d99, l50, l99, r0, r1, f0, f1, n in rows:
        print(f"{name:8} {d50:8.3f}ms {d99:8.3f}ms {l50:8.3f}ms {l99:8.3f}ms {r0:7.1f}→{r1:6.1f} "
              f"{f0:4d}→{f1:4d} {n:9d}")
    print(f"load average: {os.getloadavg()}")


def startup_and_latency() -> None:
    from asyncua import Client, ua
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    url = f"opc.tcp://127.0.0.1:{port}"
    started = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "stvm", "run", *FILES, "--scan", "10ms", "--realtime",
                             "--duration", "120s", "--opcua", url], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env={**os.environ, "PYTHONPATH": str(ROOT)})

    async def first_value():
        while True:
            try:
                async with Client(url, timeout=2) as client:
                    ns = next(i for i, uri in enumerate(await client.get_namespace_array())
                              if uri.startswith("urn:stvm:") and uri.count(":") == 2)
                    await client.get_node(ua.NodeId("@Runtime.ScanCount", ns)).read_value()
                    return time.perf_counter() - started, ns
            except (OSError, asyncio.TimeoutError, ConnectionError):
                await asyncio.sleep(0.02)

    async def latency(ns):
        got: asyncio.Queue = asyncio.Queue()

        class Into:
            def datachange_notification(self, node, value, data):
                got.put_nowait((time.perf_counter(), value))

        async with Client(url) as reader, Client(url) as writer:
            node = ua.NodeId("Connect_Time_Out", ns)
            sub = await reader.create_subscription(10, Into())
            await sub.subscribe_data_change(reader.get_node(node), sampling_interval=0)
            await got.get()
            delays = []
            for i in range(50):
                value = 100 + i
                sent = time.perf_counter()
                await writer.get_node(node).write_value(ua.Variant(value, ua.VariantType.UInt16))
                while True:
                    at, seen = await got.get()
                    if seen == value:
                        delays.append((at - sent) * 1e3)
                        break
            return delays

    try:
        elapsed, ns = asyncio.run(first_value())
        print(f"start-up to a first OPC UA value (fresh process, warm cache): {elapsed:.2f} s")
        try:
            delays = asyncio.run(asyncio.wait_for(latency(ns), 60))
        except asyncio.TimeoutError:
            print("subscription latency: no data change arrived within 60 s (see the report: open problem)")
            return
        print(f"subscription latency (write → data change, 10 ms scans, publishing 10 ms): "
              f"median {statistics.median(delays):.1f} ms, p90 {pct(delays, 0.9):.1f} ms")
    finally:
        proc.terminate()
        proc.wait(30)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--attack", nargs=3, metavar=("URL", "NS_URI", "SECONDS"))
    parser.add_argument("--only", choices=("soak", "startup"))
    args = parser.parse_args()
    if args.attack:
        asyncio.run(attack(args.attack[0], args.attack[1], float(args.attack[2])))
        return
    if args.only != "soak":
        startup_and_latency()
    if args.only != "startup":
        soak(args.seconds)


if __name__ == "__main__":
    main()
