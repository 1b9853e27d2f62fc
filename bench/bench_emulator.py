"""Commands per second against the emulator over loopback, one client.

    python bench/bench_emulator.py [--seconds 3]

Three figures: ping-pong TMSTA 00 queries (one request in flight), ping-pong short TMSCT scripts
(``QueueTag(1)``: parse, dry-run, queue, reply and tag notification), and pipelined TMSCT (100
requests in flight).  Target (issue 5): >= 5,000 short commands/s.
"""

from __future__ import annotations

import argparse
import socket
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import subprocess  # noqa: E402

from emulator.framing import ListenNodeFramer, encode  # noqa: E402

QUERY = b"$TMSTA,2,00,*41\r\n"


class Reader:
    def __init__(self, sock: socket.socket) -> None:
        self.sock, self.buf, self.framer = sock, b"", ListenNodeFramer()

    def frames(self, count: int) -> None:
        """Read ``count`` frames (robot headers count, CPERR decodes as a header error)."""
        got = 0
        while got < count:
            used, result = self.framer.decode(self.buf)
            if used:
                self.buf = self.buf[used:]
                got += result is not None
                continue
            chunk = self.sock.recv(1 << 16)
            if not chunk:
                raise ConnectionError("closed")
            self.buf += chunk


def run(name: str, seconds: float, send, expect: int, batch: int = 1) -> float:
    done, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        send(batch)
        expect_fn = expect
        expect_fn(batch)
        done += batch
    rate = done / (time.perf_counter() - start)
    print(f"{name:<44} {rate:>10,.0f} commands/s")
    return rate


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seconds", type=float, default=3.0)
    args = parser.parse_args()
    # The server runs in its own process, as it does for a real client (a PLC, another program):
    # in one process the client and the server thread would share the GIL.
    server = subprocess.Popen([sys.executable, "-m", "emulator", "--port", "0", "--quiet"],
                              cwd=Path(__file__).resolve().parents[1], stdout=subprocess.PIPE, text=True)
    port = int(server.stdout.readline().rsplit(":", 1)[1])
    try:
        sock = socket.create_connection(("127.0.0.1", port))
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        reader = Reader(sock)
        tag_script = encode("TMSCT", "1,QueueTag(1)")
        rates = [
            run("TMSTA 00 query, ping-pong", args.seconds, lambda n: sock.sendall(QUERY), reader.frames),
            run("TMSCT QueueTag(1) (OK + notification), ping-pong", args.seconds,
                lambda n: sock.sendall(tag_script), lambda n: reader.frames(2 * n)),
            run("TMSTA 00 query, 100 pipelined", args.seconds, lambda n: sock.sendall(QUERY * n),
                reader.frames, batch=100),
        ]
        sock.close()
    finally:
        server.terminate()
        server.wait(10)
    print(f"target >= 5,000 short commands/s: {'met' if min(rates) >= 5000 else 'NOT met'} "
          f"(lowest {min(rates):,.0f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
