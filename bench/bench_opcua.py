"""OPC UA server cost (issue 13's bar: the PnP demo's median scan time rises ≤ 10 % with the server
on and 200 monitored items).

The thesis PnP demo (scenario `pnp_demo.toml`, the in-process robot, 1 ms scans) runs the same
scans twice per repeat, interleaved: without a server, and with the server and one OPC UA client
in another process (as SCADA would be) subscribed to 200 published variables at sampling
interval 0 (every scan). Each run starts from a fresh VM, so scan k does the same ST work in both.

Figures per run:
  program   median of the VM's own scan time (the ST code: what `--stats` shows)
  full      median time from the first scan-start hook to the last scan-end hook: hooks
            included (the watch sampling of the 200 items, the hand-over to the server thread)
            and any wait for the GIL the server thread holds
  sampling  median time of the bridge's scan-end hook alone (all the VM thread does for the server:
            the monitored items' watch, read every 20 ms of VM time, and the alarm list, every scan)
Also: server start-up (construct + listen) for the default 283 variables and for all ~7,100
with FB internals, and the cost of importing asyncua.

    python bench/bench_opcua.py                       # 3000 scans, 3 repeats, virtual clock
    python bench/bench_opcua.py --realtime            # the demo's real-time clock (1 ms deadlines)
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "opcua"))

FILES = [str(ROOT / "st_src" / "PnP_Example.st")]

CLIENT = textwrap.dedent("""
    import asyncio, sys
    from asyncua import Client, ua
    url, uri, paths = sys.argv[1], sys.argv[2], sys.argv[3].split("|")
    async def main():
        count = 0
        class Handler:
            def datachange_notification(self, node, value, data):
                nonlocal count
                count += 1
        async with Client(url, timeout=60) as client:
            ns = await client.get_namespace_index(uri)
            sub = await client.create_subscription(50, Handler())
            await sub.subscribe_data_change([client.get_node(ua.NodeId(p, ns)) for p in paths], sampling_interval=0)
            print("subscribed", flush=True)
            await asyncio.get_running_loop().run_in_executor(None, sys.stdin.readline)
            print(count, flush=True)
    asyncio.run(main())
""")


def fresh_vm(project, realtime: bool):
    from opcua_helpers import wire_demo
    from stvm.lockstep import LockstepTransport
    transport = LockstepTransport(latency_scans=1)
    vm = project.start(scan="1ms", transport=transport, realtime=realtime)
    transport.attach(vm)
    wire_demo(vm)
    return vm


def timed_scans(vm, scans: int) -> tuple[float, float]:
    """(median program µs, median full scan µs: from the first start hook to the last end hook,
    so the watch sampling counts and a real-time run's sleep to the next deadline does not)."""
    from stvm.runtime.vm import timing_us
    full = []
    clock = time.perf_counter_ns
    started = [0]
    vm.on_scan_start.insert(0, lambda vm: started.__setitem__(0, clock()))
    vm.on_scan_end.append(lambda vm: full.append(clock() - started[0]))
    vm.run(cycles=scans)
    return timing_us(vm.scan_durations_ns)[1], statistics.median(full) / 1000


def time_hook(vm, hook) -> list[int]:
    """Time one scan-end hook (the bridge's sampling) in place; the list fills as scans run."""
    spent: list[int] = []
    clock = time.perf_counter_ns

    def timed(vm) -> None:
        started = clock()
        hook(vm)
        spent.append(clock() - started)
    vm.on_scan_end[vm.on_scan_end.index(hook)] = timed
    return spent


def run_off(project, scans: int, realtime: bool) -> tuple[float, float]:
    vm = fresh_vm(project, realtime)
    try:
        return timed_scans(vm, scans)
    finally:
        vm.close()


def run_on(project, scans: int, items: int, realtime: bool) -> tuple[float, float, int, int]:
    from stvm.opcua import load_config
    from stvm.opcua.server import OpcUaServer
    vm = fresh_vm(project, realtime)
    config = load_config(project.manifest, project.root, FILES, "opc.tcp://127.0.0.1:0")
    server = OpcUaServer(vm, config)
    url = server.start()
    paths = list(server.variables)[:items]
    client = subprocess.Popen([sys.executable, "-c", CLIENT, url, config.namespace_uri, "|".join(paths)],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        assert client.stdout.readline().strip() == "subscribed"
        deadline = time.monotonic() + 30
        while len(server.monitored_paths) < len(paths) and time.monotonic() < deadline:
            time.sleep(0.02)
        monitored = len(server.monitored_paths)
        hook_ns = time_hook(vm, server.bridge._sample_due)
        program, full = timed_scans(vm, scans)
        time.sleep(0.3)   # the last publishing interval
        client.stdin.write("\n")
        client.stdin.flush()
        notifications = int(client.stdout.readline())
        return (program, full, monitored, notifications, statistics.median(hook_ns) / 1000,
                sum(hook_ns) / len(hook_ns) / 1000)
    finally:
        client.kill()
        server.stop()
        vm.close()


def startup(project) -> list[tuple[str, float, int]]:
    from stvm.opcua import load_config
    from stvm.opcua.server import OpcUaServer
    rows = []
    for label, publish in (("default (globals, programs)", None),
                           ("with FB internals", ["@globals", "@programs", "@fb_internals"])):
        manifest = dict(project.manifest, opcua={"publish": publish} if publish else {})
        vm = project.start(scan="1ms")
        started = time.perf_counter()
        server = OpcUaServer(vm, load_config(manifest, project.root, FILES, "opc.tcp://127.0.0.1:0"))
        server.start()
        rows.append((label, time.perf_counter() - started, len(server.variables)))
        server.stop()
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scans", type=int, default=3000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--items", type=int, default=200)
    parser.add_argument("--realtime", action="store_true")
    args = parser.parse_args()
    os.environ.setdefault("STVM_CACHE_DIR", tempfile.mkdtemp(prefix="stvm-bench-"))
    started = time.perf_counter()
    import asyncua  # noqa: F401
    import_s = time.perf_counter() - started
    from stvm.project import load
    project = load(FILES)
    print(f"load average {os.getloadavg()[0]:.2f}; importing asyncua took {import_s:.2f} s")
    for label, seconds, count in startup(project):
        print(f"server start-up, {label}: {seconds:.2f} s for {count} variables")
    offs, ons = [], []
    clock = "real-time" if args.realtime else "virtual"
    print(f"\nPnP demo, {args.scans} scans of 1 ms ({clock} clock), median µs per scan")
    print(f"{'run':>4} {'off program':>12} {'off full':>9} {'on program':>11} {'on full':>8} {'items':>6} "
          f"{'notif.':>7} {'sampling':>9}")
    for i in range(args.repeat):
        off = run_off(project, args.scans, args.realtime)
        on = run_on(project, args.scans, args.items, args.realtime)
        offs.append(off)
        ons.append(on)
        print(f"{i + 1:>4} {off[0]:>12.1f} {off[1]:>9.1f} {on[0]:>11.1f} {on[1]:>8.1f} {on[2]:>6} {on[3]:>7} "
              f"{on[4]:>9.1f}")
    off_program = statistics.median(o[0] for o in offs)
    off_full = statistics.median(o[1] for o in offs)
    on_program = statistics.median(o[0] for o in ons)
    on_full = statistics.median(o[1] for o in ons)
    sampling, sampling_mean = statistics.median(o[4] for o in ons), statistics.median(o[5] for o in ons)
    print(f"\nsampling hook (the VM thread's whole share: the monitored items' watch, read every 20 ms of VM "
          f"time, and the alarm list's FB outputs, read every scan; compare, hand over): median "
          f"{sampling:.1f} µs a scan = {sampling / off_program:.0%} of the program scan; mean {sampling_mean:.1f} µs "
          f"(the scans that hand a changed sample over, and wait for the GIL the server thread holds then)")
    print(f"median of runs: program {off_program:.1f} → {on_program:.1f} µs ({on_program / off_program:.2f}×), "
          f"full scan {off_full:.1f} → {on_full:.1f} µs ({on_full / off_full:.2f}×); target ≤ 1.10×")
    print(f"load average now {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
