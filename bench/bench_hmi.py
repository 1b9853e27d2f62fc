"""HMI scan cost: the thesis PnP scan with 5 WebSocket clients on pgPnP_sequence vs none, same run.

    python bench/bench_hmi.py [--seconds 5] [--rounds 2] [--clients 5]

The thesis project runs its PnP cycle (st_src/scenarios/pnp_demo.toml) on the real-time clock at
1 ms against the in-process emulator, with the HMI server attached. The scan time measured is the
whole scan as the VM thread spends it: from the first scan-start hook (the bridge's write queue)
to the last scan-end hook (the bridge's sampling, the emulator step), the ST programs in between.
Phases alternate: no client / N clients (in another process, like browsers, each reading every
update of pgPnP_sequence: 120 variables and the robot view), `--rounds` times each.
Target: the median rises by at most 10 %.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

CLIENT = r"""
import json, sys, threading, time
from websockets.sync.client import connect
url, n, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
counts = [0] * n
def run(i):
    with connect(url) as ws:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            try:
                json.loads(ws.recv(timeout=1))
            except TimeoutError:
                continue
            counts[i] += 1
threads = [threading.Thread(target=run, args=(i,)) for i in range(n)]
for t in threads: t.start()
for t in threads: t.join()
print(json.dumps([c / seconds for c in counts]))
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=5.0, help="length of each phase")
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--clients", type=int, default=5)
    parser.add_argument("--switch-interval", type=float, default=None, help="sys.setswitchinterval (s) for the run")
    args = parser.parse_args()
    if args.switch_interval:
        sys.setswitchinterval(args.switch_interval)

    import stvm
    from stvm.frontend import VariableBridge
    from stvm.hmi import HmiServer, from_lockstep, load_pages
    from stvm.hmi.cli import page_files
    from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, LockstepTransport
    from stvm.scenario import ScenarioDriver, load_scenario

    project = stvm.load([str(ROOT / "st_src" / "PnP_Example.st")])
    transport = LockstepTransport(latency_scans=1)
    vm = project.start(scan="1ms", realtime=True, transport=transport)
    vm.collect_stats = False
    driver = ScenarioDriver(load_scenario(ROOT / "st_src" / "scenarios" / "pnp_demo.toml"), vm)
    vm.on_scan_end.append(driver.after_scan)
    transport.attach(vm)
    driver.apply_initial({"Connect_AddressIP": LOCKSTEP_HOST, "Connect_Dest_PortIP": LOCKSTEP_PORT})
    bridge = VariableBridge(vm)
    files, start = page_files(project)
    hmi = load_pages(files, bridge.type_of, start)
    server = HmiServer(hmi, bridge, port=0, pose=from_lockstep(transport)).start()

    durations: list[int] = []
    started = [0]
    vm.on_scan_start.insert(0, lambda _vm: started.__setitem__(0, time.perf_counter_ns()))
    vm.on_scan_end.append(lambda _vm: durations.append(time.perf_counter_ns() - started[0]))
    stop = threading.Event()
    thread = threading.Thread(target=lambda: vm.run(until=stop.is_set), daemon=True)
    thread.start()

    url = f"ws://127.0.0.1:{server.port}/ws?page=pgPnP_sequence"
    results: dict[str, list[int]] = {"none": [], "clients": []}
    rates: list[float] = []
    try:
        time.sleep(2.0)   # connect and start the cycle
        for _ in range(args.rounds):
            first = len(durations)
            time.sleep(args.seconds)
            results["none"] += durations[first:]
            proc = subprocess.Popen([sys.executable, "-c", CLIENT, url, str(args.clients), str(args.seconds + 1.0)],
                                    stdout=subprocess.PIPE, text=True)
            time.sleep(1.0)   # clients connected and receiving
            first = len(durations)
            time.sleep(args.seconds - 0.5)
            results["clients"] += durations[first:]
            out, _ = proc.communicate(timeout=60)
            rates += [float(r) for r in __import__("json").loads(out)]
    finally:
        stop.set()
        thread.join(5)
        server.stop()
        vm.close()
    step = vm["PnP_Example_Instance.Prg_Step"]
    none_med = statistics.median(results["none"]) / 1e3
    with_med = statistics.median(results["clients"]) / 1e3
    none_mean = statistics.fmean(results["none"]) / 1e3
    with_mean = statistics.fmean(results["clients"]) / 1e3
    load = os.getloadavg()
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; PnP step at the end {step}; "
          f"{len(results['none'])} + {len(results['clients'])} scans")
    print(f"{'':28} {'median µs':>10} {'mean µs':>10} {'p99 µs':>10}")
    for name, data in (("no client", results["none"]), (f"{args.clients} WebSocket clients", results["clients"])):
        ordered = sorted(data)
        print(f"{name:28} {statistics.median(data) / 1e3:10.1f} {statistics.fmean(data) / 1e3:10.1f} "
              f"{ordered[int(len(ordered) * 0.99)] / 1e3:10.1f}")
    print(f"client update rate: min {min(rates):.1f}/s, mean {statistics.fmean(rates):.1f}/s (target >= 10/s)")
    ratio = with_med / none_med
    print(f"median scan with clients / without: {ratio:.3f} (target <= 1.10); mean {with_mean / none_mean:.3f}")
    return 0 if ratio <= 1.10 and min(rates) >= 10 else 1


if __name__ == "__main__":
    raise SystemExit(main())
