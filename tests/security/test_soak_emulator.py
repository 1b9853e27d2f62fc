"""Soak of the TM emulator's Listen Node port (issue 34): a hostile client does its worst for a
few seconds on loopback while a well-behaved client keeps asking; the server's memory and
descriptors stay bounded and the good client keeps being answered, in about the time it was
before the attack (a generous factor of the quiet baseline measured in the same test).

The attacks, each in its own thread: malformed frames (garbage, bad checksums, a length above
max_data_length, scripts nested past the parser's limit) at full speed; valid frames sent by a
client that never reads the answers; half-open frames left hanging; connect/close churn (every
other close a reset); and connections opened past `--max-connections`, held.

`python bench/bench_soak_emulator.py` runs the same for longer and prints the figures."""

from __future__ import annotations

import os
import random
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

from soak_harness import Attackers, Sampler, fd_count, pct, rss_kb, soak_figures

ROOT = Path(__file__).resolve().parents[2]
QUERY = b"$TMSTA,2,00,*41\r\n"
IN_NODE = b"$TMSTA,15,00,true,Listen1,*79\r\n"


def _frame(header: str, data: str) -> bytes:
    body = f"{header},{len(data.encode())},{data},"
    checksum = 0
    for byte in body.encode():
        checksum ^= byte
    return b"$" + body.encode() + b"*%02X\r\n" % checksum


MALFORMED = [
    b"\x00\xff" * 300,
    b"$TMSCT,5,1,abc,*00\r\n",                                    # bad checksum
    b"$TMSCT,99999999," + b"A" * 4000,                              # length above max_data_length
    b"$NOPE,3,abc,*11\r\n",                                        # unknown header
    b"$TMSCT,-3,abc,*11\r\n",
    b"$$$$$$\r\n\r\n,,,,*\r\n",
    _frame("TMSCT", "7,var_a = " + "(" * 400 + "1" + ")" * 400),   # nesting past the limit
    _frame("TMSCT", "7,var_a = " + "+".join(["1"] * 5000)),
    _frame("TMSCT", "7,var_a = " + "9" * 5000),
    _frame("TMSTA", "99,zz"),
]


class EmulatorProcess:
    """`tm-emulator` as its own process (its RSS and descriptors are its own)."""

    def __init__(self, max_connections: int) -> None:
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        self.proc = subprocess.Popen([sys.executable, "-u", "-m", "emulator", "--port", "0", "--quiet",
                                      "--max-connections", str(max_connections)],
                                     cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self.proc.stdout.readline()
        found = re.search(r"listening on [\d.]+:(\d+)", line)
        if not found:
            self.proc.kill()
            raise AssertionError(f"tm-emulator did not start: {line!r} {self.proc.stderr.read()}")
        self.port = int(found.group(1))
        self.pid = self.proc.pid

    def connect(self, timeout: float = 10.0) -> socket.socket:
        sock = socket.create_connection(("127.0.0.1", self.port), timeout=timeout)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return sock

    def close(self) -> str:
        self.proc.terminate()
        try:
            _, err = self.proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return err


class GoodClient:
    """One connection opened before the attack, asking the Listen Node status again and again."""

    def __init__(self, server: EmulatorProcess) -> None:
        self.sock = server.connect()
        self.buf = b""

    def ask(self) -> float:
        started = time.perf_counter()
        self.sock.sendall(QUERY)
        while IN_NODE not in self.buf:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise ConnectionError("the emulator closed the good client's connection")
            self.buf += chunk
        self.buf = self.buf.replace(IN_NODE, b"", 1)
        assert not self.buf, f"unexpected bytes for the good client: {self.buf[:200]!r}"
        return time.perf_counter() - started

    def latencies(self, count: int | None = None, until: float | None = None) -> list[float]:
        out = []
        while (count is None or len(out) < count) and (until is None or time.monotonic() < until):
            out.append(self.ask())
        return out


def _attacks(server: EmulatorProcess, max_connections: int, held: list[socket.socket],
             resets: list[int]) -> dict:
    rng = random.Random(34)

    def malformed(deadline: float) -> int:
        try:
            sock = server.connect()
        except OSError:
            return 0
        sock.settimeout(0.05)
        sent = 0
        try:
            while time.monotonic() < deadline and sent < 2000:
                sock.sendall(rng.choice(MALFORMED))
                sent += 1
                try:
                    sock.recv(65536)   # read what comes, so this one is not the slow reader
                except (socket.timeout, BlockingIOError):
                    pass
        except OSError:
            pass   # the server may close a connection that sent garbage, or refuse it: reconnect
        finally:
            sock.close()
        return sent

    def never_reads(deadline: float) -> int:
        try:
            sock = server.connect()
        except OSError:   # refused while the other attacks hold every slot
            return 0
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        sock.settimeout(0.5)
        batch = QUERY * 500
        sent = 0
        try:
            while time.monotonic() < deadline:
                sock.sendall(batch)
                sent += 500
        except OSError:
            pass   # the server stopped reading us (back-pressure), dropped or refused us
        finally:
            sock.close()
        return sent

    def half_open(deadline: float) -> int:
        try:
            sock = server.connect()
        except OSError:
            time.sleep(0.05)
            return 0
        try:
            sock.sendall(b"$TMSCT,200,1,var_a = 1")   # a frame begun and never finished
            held.append(sock)
        except OSError:
            sock.close()
        time.sleep(0.05)
        return 1

    def churn(deadline: float) -> int:
        for i in range(20):
            try:
                sock = server.connect()
            except OSError:
                continue
            if i % 2:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
            else:
                try:
                    sock.sendall(QUERY)
                except OSError:
                    pass
            sock.close()
        return 20

    def past_the_limit(deadline: float) -> int:
        opened = 0
        for _ in range(max_connections + 8):
            try:
                sock = server.connect(timeout=2)
            except OSError:
                resets[0] += 1
                continue
            sock.settimeout(0.2)
            try:
                if sock.recv(1) == b"":
                    resets[0] += 1   # accepted and closed at once: over the limit
                    sock.close()
                    continue
            except socket.timeout:
                pass   # served (idle): hold it
            except ConnectionError:
                resets[0] += 1
                sock.close()
                continue
            held.append(sock)
            opened += 1
        time.sleep(0.2)
        while held and len(held) > max_connections // 2:   # let some go, so the churn gets in again
            held.pop(0).close()
        return opened

    return {"malformed frames": malformed, "valid frames, never read": never_reads,
            "half-open frames": half_open, "connect/close churn": churn,
            "connections past the limit": past_the_limit}


def soak(seconds: float, max_connections: int = 16, quiet_requests: int = 300) -> dict:
    """The three phases; returns the figures (RSS in KiB, latencies in seconds)."""
    server = EmulatorProcess(max_connections)
    held: list[socket.socket] = []
    resets = [0]
    try:
        good = GoodClient(server)
        good.latencies(count=50)   # warm-up: imports, caches, the first frames
        quiet = good.latencies(count=quiet_requests)
        base = {"rss": rss_kb(server.pid), "fds": fd_count(server.pid)}
        with Sampler(server.pid) as sampler:
            with Attackers(_attacks(server, max_connections, held, resets), seconds) as attackers:
                hostile = good.latencies(until=time.monotonic() + seconds)
            for sock in held:
                sock.close()
            held.clear()
        time.sleep(0.5)   # the server sees the closes
        after_lat = good.latencies(count=quiet_requests)
        after = {"rss": rss_kb(server.pid), "fds": fd_count(server.pid)}
        good.sock.close()
        alive = server.proc.poll() is None
    finally:
        for sock in held:
            sock.close()
        stderr = server.close()
    return soak_figures(quiet, hostile, after_lat, base, sampler, after, attackers,
                        resets=resets[0], alive=alive, stderr=stderr)


def test_emulator_soak_stays_flat_and_keeps_serving():
    max_connections = 16
    figures = soak(seconds=4.0, max_connections=max_connections)
    assert figures["alive"], figures["stderr"]
    assert not figures["errors"], figures["errors"]
    assert "Traceback" not in figures["stderr"], figures["stderr"]
    counts = figures["counts"]
    assert all(counts.values()), counts   # every attack did something
    assert figures["resets"] > 0          # the connections past the limit were refused
    # memory: bounded growth whatever was sent (a reply queue for a client that never reads
    # used to grow without limit)
    growth_mb = (figures["peak_rss"] - figures["base"]["rss"]) / 1024
    assert growth_mb < 48, f"RSS grew {growth_mb:.1f} MB during the attack"
    # descriptors: at most the connection limit during the attack, back to the baseline after
    assert figures["peak_fds"] <= figures["base"]["fds"] + max_connections + 2
    assert figures["after"]["fds"] <= figures["base"]["fds"] + 1
    # the good client was answered throughout, in a bounded multiple of its quiet time
    assert len(figures["hostile"]) >= 10
    quiet_p50 = pct(figures["quiet"], 0.5)
    assert pct(figures["hostile"], 0.5) <= max(50 * quiet_p50, 0.25), (quiet_p50, pct(figures["hostile"], 0.5))
    assert pct(figures["after_latencies"], 0.5) <= max(5 * quiet_p50, 0.05)
