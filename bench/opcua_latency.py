"""Subscription latency of the OPC UA server: a write by one asyncua client until the data change
reaches another client's subscription (issue 32's note).

    PYTHONPATH=. python bench/opcua_latency.py [--writes 50] [--scan 10ms] [--publishing 10]

In-process (the VM scans on the real-time clock in a thread, the server beside it, both clients
over loopback), so the figure is the server's latency, not a process start-up's. Prints p50 /
p90 / max in ms and how many writes were never notified (the previous attempt, through a fresh
`stvm run` process, saw none: that process was still compiling the project when the client gave
up, see docs/opcua.md "Latency").
"""

from __future__ import annotations

import argparse
import asyncio
import statistics
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import stvm  # noqa: E402
from asyncua import Client, ua  # noqa: E402
from stvm.opcua import load_config  # noqa: E402
from stvm.opcua.server import OpcUaServer  # noqa: E402

THESIS = [str(ROOT / "st_src" / "PnP_Example.st")]
PATH = "Connect_Time_Out"   # a writable global the program only reads (limits 10..300 s)


async def measure(url: str, ns_uri: str, writes: int, publishing_ms: float) -> tuple[list[float], int]:
    got: asyncio.Queue = asyncio.Queue()

    class Into:
        def datachange_notification(self, node, value, data):
            got.put_nowait((time.perf_counter(), value))

    async with Client(url) as reader, Client(url) as writer:
        ns = await reader.get_namespace_index(ns_uri)
        node = ua.NodeId(PATH, ns)
        variant = (await writer.get_node(node).read_data_value()).Value.VariantType
        sub = await reader.create_subscription(publishing_ms, Into())
        await sub.subscribe_data_change(reader.get_node(node), sampling_interval=0)
        await asyncio.wait_for(got.get(), 10)   # the initial value
        delays, missed = [], 0
        for i in range(writes):
            value = 100 + i % 150
            sent = time.perf_counter()
            await writer.get_node(node).write_value(ua.Variant(value, variant))
            try:
                while True:
                    at, seen = await asyncio.wait_for(got.get(), 5)
                    if seen == value:
                        delays.append((at - sent) * 1e3)
                        break
            except asyncio.TimeoutError:
                missed += 1
        return delays, missed


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--writes", type=int, default=50)
    parser.add_argument("--scan", default="10ms")
    parser.add_argument("--publishing", type=float, default=10.0, help="publishing interval, ms")
    args = parser.parse_args()
    project = stvm.load(THESIS)
    vm = project.start(scan=args.scan, realtime=True)
    manifest = dict(project.manifest)
    manifest["opcua"] = {k: v for k, v in manifest.get("opcua", {}).items() if k != "endpoint"}
    config = load_config(manifest, project.root, THESIS, "opc.tcp://127.0.0.1:0")
    started = time.perf_counter()
    server = OpcUaServer(vm, config)
    url = server.start()
    print(f"server start (address space of {len(server.variables)} variables): {time.perf_counter() - started:.2f} s")
    stop = threading.Event()
    thread = threading.Thread(target=lambda: vm.run(until=stop.is_set), daemon=True)
    thread.start()
    try:
        delays, missed = asyncio.run(measure(url, config.namespace_uri, args.writes, args.publishing))
    finally:
        stop.set()
        thread.join(10)
        server.stop()
        vm.close()
    delays.sort()
    p90 = delays[int(0.9 * (len(delays) - 1))] if delays else float("nan")
    print(f"subscription latency (write → data change; {args.scan} scans, publishing {args.publishing:g} ms, "
          f"sampling every scan): p50 {statistics.median(delays):.1f} ms, p90 {p90:.1f} ms, "
          f"max {max(delays):.1f} ms over {len(delays)} writes; never notified: {missed}")


if __name__ == "__main__":
    main()
