"""Commands per second against the emulator over loopback, one client.

    python bench/bench_emulator.py [--seconds 3] [--runs 1]

Three figures: ping-pong TMSTA 00 queries (one request in flight), ping-pong short TMSCT scripts
(``QueueTag(1)``: parse, argument check, queue, reply and tag notification), and pipelined TMSTA
(100 requests in flight).  Target (issue 5): >= 5,000 short commands/s.

Ping-pong means: send one command, wait until every reply frame of it has arrived, send the next.
The server runs in its own process (as for a real client); the client is a plain blocking socket
that reads until it holds the expected reply bytes and compares them with the expected frames (so
every reply of the run is checked byte for byte, at the cost of one ``bytes`` comparison).  It does
not decode frames with the emulator's framer: that Python work would be charged to the server.

On Linux the CPU time of both processes is read from ``/proc`` and printed per command, which says
where the time goes and stays meaningful on a busy machine, where the rate depends on scheduling.
With ``--runs N`` each figure is measured N times (a fresh server each run) and the median is kept.
"""

from __future__ import annotations

import argparse
import os
import socket
import statistics
import struct
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from emulator.framing import encode  # noqa: E402

QUERY = b"$TMSTA,2,00,*41\r\n"
QUERY_REPLY = encode("TMSTA", "00,true,Listen1")
TAG_SCRIPT = encode("TMSCT", "1,QueueTag(1)")
# notify_before_ok only concerns QueueTag(n,1): the OK of QueueTag(1) comes first.
TAG_REPLY = encode("TMSCT", "1,OK") + encode("TMSTA", "01,01,true")
PIPELINE = 100


class Client:
    """One blocking TCP client that expects exact reply bytes."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port))
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        # A missing reply fails the run instead of hanging it.  Not settimeout(): with a Python
        # timeout every recv/send is preceded by a poll() system call.
        try:
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, struct.pack("ll", 10, 0))
        except (OSError, AttributeError, struct.error):
            pass

    def exchange(self, request: bytes, reply: bytes) -> None:
        """Send ``request``, wait for exactly ``reply`` (raises if anything else arrives)."""
        self.sock.sendall(request)
        recv = self.sock.recv
        got = recv(65536)  # (a timeout raises BlockingIOError)
        while len(got) < len(reply):
            chunk = recv(65536)
            if not chunk:
                raise ConnectionError("closed by the emulator")
            got += chunk
        if got != reply:
            raise AssertionError(f"unexpected reply {got[:80]!r}, expected {reply[:80]!r}")

    def close(self) -> None:
        self.sock.close()


def _cpu_s(pid: int | None = None) -> float | None:
    """User + system CPU seconds of a process (Linux /proc), or None."""
    try:
        with open(f"/proc/{pid or os.getpid()}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, AttributeError):
        return None


def measure(seconds: float, request: bytes, reply: bytes,
            per_exchange: int) -> tuple[float, float | None, float | None]:
    """(commands/s, server CPU us/command, client CPU us/command) with a fresh server."""
    # The server runs in its own process, as it does for a real client (a PLC, another program):
    # in one process the client and the server thread would share the GIL.
    server = subprocess.Popen([sys.executable, "-m", "emulator", "--port", "0", "--quiet"],
                              cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        port = int(server.stdout.readline().rsplit(":", 1)[1])
        client = Client(port)
        exchange = client.exchange
        for _ in range(200):  # warm-up: connection, caches
            exchange(request, reply)
        server_cpu0, client_cpu0 = _cpu_s(server.pid), _cpu_s()
        done, start = 0, time.perf_counter()
        deadline = start + seconds
        while time.perf_counter() < deadline:
            for _ in range(20):
                exchange(request, reply)
            done += 20 * per_exchange
        elapsed = time.perf_counter() - start
        server_cpu1, client_cpu1 = _cpu_s(server.pid), _cpu_s()
        client.close()
    finally:
        server.terminate()
        server.wait(10)
    server_us = None if server_cpu0 is None or server_cpu1 is None else 1e6 * (server_cpu1 - server_cpu0) / done
    client_us = None if client_cpu0 is None or client_cpu1 is None else 1e6 * (client_cpu1 - client_cpu0) / done
    return done / elapsed, server_us, client_us


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=3.0, help="duration of each figure (default 3)")
    parser.add_argument("--runs", type=int, default=1, help="runs per figure; the median is reported")
    args = parser.parse_args()
    cases = [
        ("TMSTA 00 query, ping-pong", QUERY, QUERY_REPLY, 1),
        ("TMSCT QueueTag(1) (OK + notification), ping-pong", TAG_SCRIPT, TAG_REPLY, 1),
        (f"TMSTA 00 query, {PIPELINE} pipelined", QUERY * PIPELINE, QUERY_REPLY * PIPELINE, PIPELINE),
    ]
    rates = []
    for name, request, reply, per_exchange in cases:
        runs = [measure(args.seconds, request, reply, per_exchange) for _ in range(max(1, args.runs))]
        rate = statistics.median(r[0] for r in runs)
        rates.append(rate)
        cpu = ""
        if all(r[1] is not None and r[2] is not None for r in runs):
            cpu = (f"  (CPU per command: server {statistics.median(r[1] for r in runs):5.1f} us, "
                   f"client {statistics.median(r[2] for r in runs):5.1f} us)")
        detail = "" if len(runs) == 1 else "  [" + ", ".join(f"{r[0]:,.0f}" for r in runs) + "]"
        print(f"{name:<50} {rate:>8,.0f} commands/s{cpu}{detail}", flush=True)
    print(f"target >= 5,000 short commands/s: {'met' if min(rates) >= 5000 else 'NOT met'} "
          f"(lowest {min(rates):,.0f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
