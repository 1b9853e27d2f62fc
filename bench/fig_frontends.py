"""Issue 33 item 3: what the front ends cost the scan loop (the VM thread).

* OPC UA with 200 monitored items: the bridge watch the OPC UA server makes for a group of
  monitored items (every scan, changes only, its callback drops the snapshot into a slot), on the
  thesis PnP in lockstep; the figure is the VM thread's time in the bridge's scan hooks per scan
  (median; target <= 1 µs added to the median scan).
* HMI with 5 clients: the one watch the HMI server makes for the pages its clients show (the
  union of their paths; pgPnP_sequence: its variables), sampled at the HMI's update period of
  wall time; same figure.
* scan p99 with 5 real WebSocket clients against none (bench/bench_hmi.py in a child process:
  the real server thread, the GIL hand-over included; target <= 1.5x).

The server threads' own CPU (asyncua, websockets) is not the scan's; bench/bench_opcua.py and
bench/bench_hmi.py measure the servers end to end.
"""

from __future__ import annotations

import re
import statistics
import subprocess
import sys
import time

from bench.registry import ROOT, Row, figure, for_loop_us

SCENARIO = ROOT / "st_src" / "scenarios" / "golden_pnp_cycle.toml"
FILES = [ROOT / "st_src" / "PnP_Example.st"]


def _session():
    from stvm.project import load
    from stvm.trace import TraceSpec
    from stvm.trace.run import trace_session
    session = trace_session(TraceSpec(FILES, scenario=SCENARIO), load([str(f) for f in FILES]))
    session.wire()
    return session


def _hook_cost(attach, scans: int, warm: int = 1000) -> tuple[float, float]:
    """(median, mean) µs per scan of the bridge's scan hooks, attached by `attach(vm)` after
    `warm` scans (the robot connected and moving)."""
    session = _session()
    vm = session.vm
    vm.run(cycles=warm)
    start_before, end_before = len(vm.on_scan_start), len(vm.on_scan_end)
    attach(vm)
    added = vm.on_scan_start[start_before:] + vm.on_scan_end[end_before:]
    del vm.on_scan_start[start_before:], vm.on_scan_end[end_before:]
    costs: list[int] = []
    clock = time.perf_counter_ns

    def start_hooks(vm_, hooks=[h for h in added if h.__name__ == "_apply_pending"]):
        started = clock()
        for hook in hooks:
            hook(vm_)
        costs.append(clock() - started)

    def end_hooks(vm_, hooks=[h for h in added if h.__name__ != "_apply_pending"]):
        started = clock()
        for hook in hooks:
            hook(vm_)
        costs[-1] += clock() - started

    empty = _timer_floor()
    vm.on_scan_start.append(start_hooks)
    vm.on_scan_end.insert(0, end_hooks)
    vm.run(cycles=scans)
    session.close()
    return (max(0.0, statistics.median(costs) - empty) / 1000, max(0.0, statistics.fmean(costs) - empty) / 1000)


def _timer_floor() -> float:
    """ns the two timing wrappers cost with no hook in them."""
    clock = time.perf_counter_ns
    samples = []
    for _ in range(2000):
        a = clock()
        b = clock()
        c = clock()
        d = clock()
        samples.append((b - a) + (d - c))
    return statistics.median(samples)


def opcua_like(vm, items: int = 200):
    """The bridge watch the OPC UA server makes for `items` monitored items asking for every scan
    (read every FORWARD_S of VM time: stvm/opcua/server.py `_rebuild_watches`)."""
    from stvm.frontend import VariableBridge
    from stvm.opcua.server import FORWARD_NS   # lazy: asyncua
    from stvm.runtime.catalog import Catalog
    paths = [node.path for node in Catalog(vm).walk()
             if node.leaf and node.type.kind in ("bool", "int", "real", "time", "string", "enum")][:items]
    inbox = {}
    bridge = VariableBridge(vm)
    bridge.watch(paths, FORWARD_NS, lambda snapshot: inbox.__setitem__("group", snapshot), changes_only=True)
    return len(paths)


def alarms_like(vm):
    """The alarm list the OPC UA server (and the HMI: one list per VM) attaches: every FB's Error
    flag read at every scan end (a one-scan Error must not be missed), ErrorID/ErrorDescrip only
    of the FBs whose Error is TRUE (`VariableBridge.watch_flags`; none in this cycle)."""
    from stvm.frontend import VariableBridge
    from stvm.frontend.alarms import AlarmList
    return len(AlarmList.attach(VariableBridge(vm)).sources)


def hmi_like(vm, update_ns: int = 50_000_000):
    """The watch the HMI server makes for clients on pgPnP_sequence (one watch, its paths)."""
    from stvm.frontend import VariableBridge
    from stvm.hmi import load_pages
    from stvm.hmi.cli import page_files
    bridge = VariableBridge(vm)
    files, start = page_files(vm.project)
    hmi = load_pages(files, bridge.type_of, start)
    page = next(p for name, p in hmi.pages.items() if name.lower() == "pgpnp_sequence") \
        if isinstance(getattr(hmi, "pages", None), dict) else None
    paths = sorted(getattr(page, "paths", None) or hmi.types)
    latest = {}
    bridge.watch(paths, every_ns=update_ns, every_wall_ns=update_ns,
                 on_snapshot=lambda snapshot: latest.__setitem__("s", snapshot))
    return len(paths)


@figure("front ends: VM-side cost per scan", item="issue 33 item 3", tags=("frontends",))
def frontends_figure(smoke: bool) -> list[Row]:
    scans = 300 if smoke else 8000
    yard = for_loop_us()
    count = []
    opc = _hook_cost(lambda vm: count.append(opcua_like(vm)), scans)
    hmi = _hook_cost(lambda vm: count.append(hmi_like(vm)), scans)
    alarms = _hook_cost(lambda vm: count.append(alarms_like(vm)), scans)
    yard = min(yard, for_loop_us())
    return [Row(f"OPC UA, {count[0]} monitored items every scan: bridge hooks, median per scan", opc[0], "us",
                "FOR-100", yard, "us", "<= 1 us", note=f"mean {opc[1]:.2f} us"),
            Row(f"HMI, pgPnP_sequence ({count[1]} paths) for its clients: bridge hooks, median per scan", hmi[0], "us",
                "FOR-100", yard, "us", "<= 1 us", note=f"mean {hmi[1]:.2f} us"),
            Row(f"alarm list ({count[2]} FBs' Error/ErrorID/ErrorDescrip, OPC UA and HMI share it): median per scan",
                alarms[0], "us", "FOR-100", yard, "us", "<= 1 us", note=f"mean {alarms[1]:.2f} us")]


@figure("front ends: scan p99 with 5 HMI clients", item="issue 33 item 3", tags=("frontends", "hmi"))
def hmi_p99_figure(smoke: bool) -> list[Row]:
    seconds = "1" if smoke else "4"
    done = subprocess.run([sys.executable, str(ROOT / "bench" / "bench_hmi.py"), "--seconds", seconds,
                           "--rounds", "1" if smoke else "2"], capture_output=True, text=True, cwd=ROOT, timeout=300)
    text = done.stdout
    none = re.search(r"no client\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)", text)
    clients = re.search(r"5 WebSocket clients\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)", text)
    if none is None or clients is None:
        raise RuntimeError(f"bench_hmi.py printed no table (exit {done.returncode}): {done.stderr[-800:]}")
    n_med, _, n_p99 = (float(x) for x in none.groups())
    c_med, _, c_p99 = (float(x) for x in clients.groups())
    return [Row("scan p99 with 5 HMI WebSocket clients (real time, 1 ms)", c_p99, "us", "p99, no client", n_p99, "us",
                "<= 1.5x", note=f"median {c_med:.0f} vs {n_med:.0f} us"),
            ]
