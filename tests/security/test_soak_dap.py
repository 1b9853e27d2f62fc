"""Soak of the debug adapter (`stvm dap`, issue 34). The adapter has one client, the process at
the other end of its stdin/stdout, so "hostile client" means hostile messages on that stream:
while a well-behaved request loop (evaluate, stackTrace, scopes, variables, threads on a stopped
program) keeps going, another thread writes, between whole messages, bodies that are not JSON,
invalid UTF-8, JSON nested 100,000 deep, non-objects, requests with every field of the wrong
type, unknown commands, huge and deeply nested expressions, a multi-MiB expression, 100
conditional breakpoints at once (each condition is compiled: ~15 ms apiece, so 5,000 hold the
adapter for over a minute; docs/security.md), and a flood of valid scopes/variables/evaluate requests never waited for.
Asserted: every request answered under its own seq, no "internal error", no traceback, RSS and
descriptors bounded, the good client's latency within a generous factor of its quiet baseline.
A framing error (bad Content-Length) ends a session by design: sessions that end that way are
churned apart and must end with exit 2 and one line.

`python bench/bench_soak_dap.py` runs the same for longer and prints the figures."""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path

from soak_harness import Attackers, Sampler, fd_count, pct, rss_kb, soak_figures

ROOT = Path(__file__).resolve().parents[2]
PROGRAM = """TYPE Pt : STRUCT x : REAL; y : REAL; END_STRUCT END_TYPE
PROGRAM Main
VAR
  x : INT;
  arr : ARRAY[0..99] OF DINT;
  p : Pt;
END_VAR
x := x + 1;
arr[x MOD 100] := x;
p.x := p.x + 0.5;
END_PROGRAM
"""


def _env() -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))


class Adapter:
    """`stvm dap` with a reader thread; requests may be written from any thread."""

    def __init__(self) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "stvm", "dap"], cwd=ROOT, env=_env(),
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.pid = self.proc.pid
        self.lock = threading.Lock()
        self.seq = 0
        self.waiting: dict[int, queue.Queue] = {}
        self.responses = 0
        self.bad: list[str] = []   # internal errors, or a response to a seq never sent
        self.events: queue.Queue = queue.Queue()
        self.closed = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        stream = self.proc.stdout
        try:
            while True:
                length = None
                while True:
                    line = stream.readline()
                    if not line:
                        return
                    line = line.strip()
                    if not line:
                        break
                    name, _, value = line.decode().partition(":")
                    if name.lower() == "content-length":
                        length = int(value)
                message = json.loads(stream.read(length))
                if message.get("type") == "event":
                    self.events.put(message)
                    continue
                self.responses += 1
                text = message.get("message", "")
                if "internal error" in text or "Traceback" in text:
                    self.bad.append(text[:300])
                box = self.waiting.pop(message.get("request_seq"), None)
                if box is not None:
                    box.put(message)
        finally:
            self.closed.set()

    def write(self, body: bytes) -> None:
        with self.lock:
            self.proc.stdin.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
            self.proc.stdin.flush()

    def send(self, command: str, wait: bool = True, timeout: float = 120.0, **arguments) -> dict | None:
        box: queue.Queue = queue.Queue()
        with self.lock:
            self.seq += 1
            seq = self.seq
            if wait:
                self.waiting[seq] = box
            data = json.dumps({"seq": seq, "type": "request", "command": command,
                               "arguments": arguments}).encode()
            self.proc.stdin.write(b"Content-Length: %d\r\n\r\n" % len(data) + data)
            self.proc.stdin.flush()
        if not wait:
            return None
        try:
            return box.get(timeout=timeout)
        except queue.Empty:
            raise AssertionError(f"no response to {command} (seq {seq})") from None

    def event(self, name: str, timeout: float = 120.0) -> dict:
        end = time.monotonic() + timeout
        while True:
            message = self.events.get(timeout=max(0.01, end - time.monotonic()))
            if message["event"] == name:
                return message

    def close(self) -> tuple[int, str]:
        try:
            self.send("disconnect", timeout=30)
        except (AssertionError, OSError):
            pass
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        try:
            code = self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            code = self.proc.wait()
        return code, self.proc.stderr.read().decode(errors="replace")


def _launch(adapter: Adapter, program: Path) -> int:
    assert adapter.send("initialize", adapterID="stvm")["success"]
    launched = adapter.send("launch", program=str(program), stopOnEntry=True)
    assert launched["success"], launched
    adapter.event("initialized")
    adapter.send("configurationDone")
    adapter.event("stopped")
    return adapter.send("stackTrace", threadId=1)["body"]["stackFrames"][0]["id"]


def _good_round(adapter: Adapter, frame_id: int) -> float:
    started = time.perf_counter()
    answer = adapter.send("evaluate", expression="Main.x + 1", context="watch")
    assert answer["success"] and answer["body"]["result"] == "1", answer
    assert adapter.send("threads")["success"]
    scopes = adapter.send("scopes", frameId=frame_id)["body"]["scopes"]
    assert scopes
    assert adapter.send("variables", variablesReference=scopes[0]["variablesReference"])["success"]
    return time.perf_counter() - started


def _attacks(adapter: Adapter, program: Path, frame_id: int, big_mb: int) -> dict:
    bodies = [b"not json", b"[1, 2, 3]", b"42", b"\xff\xfe\xfd", b"[" * 100_000 + b"]" * 100_000,
              b"{" * 50_000, b'{"type": "request", "seq": "x", "command": 5}',
              b'{"type": "request", "seq": 1e400, "command": "threads"}',
              b'{"type": "request", "seq": 7, "command": "evaluate", "arguments": []}',
              b'{"type": "request", "seq": 8, "command": "__init__", "arguments": {}}',
              b'{"type": "request", "seq": 9, "command": "nope", "arguments": {"a": ' + b"[" * 5000 + b"]" * 5000 + b"}}"]

    def bad_bodies(deadline: float) -> int:
        for body in bodies:
            adapter.write(body)
        return len(bodies)

    def bad_requests(deadline: float) -> int:
        for expression in ("+".join(["Main.x"] * 20_000), "ABS(" * 800 + "1" + ")" * 800,
                           "Main.x" + "[0]" * 1000, "Main.nope", "1 +", "'" * 3000):
            adapter.send("evaluate", wait=False, expression=expression, context="repl")
        adapter.send("variables", wait=False, variablesReference=10**30)
        adapter.send("stackTrace", wait=False, threadId=1, startFrame=-5, levels=10**12)
        adapter.send("scopes", wait=False, frameId="x")
        adapter.send("setVariable", wait=False, variablesReference=1, name="x" * 10_000, value="1" * 10_000)
        adapter.send("launch", wait=False, program=str(program))   # a second launch: refused
        adapter.send("source", wait=False, sourceReference=-1)
        # the last one waited for: the stream is not flooded faster than it is read
        adapter.send("setBreakpoints", source={"path": str(program)},
                     breakpoints=[{"line": n % 12 + 1, "condition": "Main.x > " + str(n)} for n in range(100)])
        adapter.send("setBreakpoints", source={"path": str(program)}, breakpoints=[])
        return 14

    def huge(deadline: float) -> int:
        adapter.send("evaluate", expression="1" * (big_mb << 20), context="repl")
        time.sleep(0.2)
        return 1

    def valid_flood(deadline: float) -> int:
        for _ in range(200):
            adapter.send("scopes", wait=False, frameId=frame_id)
            adapter.send("evaluate", wait=False, expression="Main.p", context="watch")
        adapter.send("threads")
        return 400

    return {"bodies not JSON or not requests": bad_bodies, "bad requests": bad_requests,
            f"{big_mb} MiB expression": huge, "valid requests never waited for": valid_flood}


def framing_churn(sessions: int) -> list[tuple[int, str]]:
    """Sessions ended by a framing error (a header the stream cannot resynchronise after)."""
    ends = []
    bad_headers = [b"Content-Length: 99999999999\r\n\r\n", b"Content-Length: abc\r\n\r\n",
                   b"X" * 9000 + b"\r\n", b"no colon here\r\n"]
    for i in range(sessions):
        proc = subprocess.run([sys.executable, "-m", "stvm", "dap"], cwd=ROOT, env=_env(),
                              input=bad_headers[i % len(bad_headers)], capture_output=True, timeout=120)
        ends.append((proc.returncode, proc.stderr.decode(errors="replace")))
    return ends


def soak(seconds: float, tmp: Path, quiet_rounds: int = 40, big_mb: int = 8) -> dict:
    program = tmp / "soak_dap.st"
    program.write_text(PROGRAM)
    adapter = Adapter()
    try:
        frame_id = _launch(adapter, program)
        for _ in range(5):
            _good_round(adapter, frame_id)   # warm-up
        quiet = [_good_round(adapter, frame_id) for _ in range(quiet_rounds)]
        base = {"rss": rss_kb(adapter.pid), "fds": fd_count(adapter.pid)}
        hostile: list[float] = []
        with Sampler(adapter.pid) as sampler:
            with Attackers(_attacks(adapter, program, frame_id, big_mb), seconds) as attackers:
                end = time.monotonic() + seconds
                while time.monotonic() < end:
                    hostile.append(_good_round(adapter, frame_id))
        adapter.send("threads")   # everything before it has been answered
        after_lat = [_good_round(adapter, frame_id) for _ in range(quiet_rounds)]
        # the program still runs and stops
        adapter.send("continue", threadId=1)
        time.sleep(0.2)
        adapter.send("pause", threadId=1)
        adapter.event("stopped")
        after = {"rss": rss_kb(adapter.pid), "fds": fd_count(adapter.pid)}
        sent, answered, bad = adapter.seq, adapter.responses, list(adapter.bad)
    finally:
        code, stderr = adapter.close()
    return soak_figures(quiet, hostile, after_lat, base, sampler, after, attackers,
                        sent=sent, answered=answered, bad=bad, exit=code, stderr=stderr)


def test_dap_soak_stays_flat_and_keeps_answering(tmp_path):
    figures = soak(seconds=4.0, tmp=tmp_path, big_mb=4)
    assert not figures["errors"], figures["errors"]
    assert not figures["bad"], figures["bad"]
    assert figures["exit"] == 0, figures["stderr"]
    assert "Traceback" not in figures["stderr"], figures["stderr"]
    assert all(figures["counts"].values()), figures["counts"]
    # every request with an integer seq got its response (the bodies that are not requests get
    # an output event instead; 3 of them carry seq 7, 8 and 9 and are answered too)
    assert figures["answered"] >= figures["sent"]
    growth_mb = (figures["after"]["rss"] - figures["base"]["rss"]) / 1024
    assert growth_mb < 32, f"RSS grew {growth_mb:.1f} MB"
    peak_mb = (figures["peak_rss"] - figures["base"]["rss"]) / 1024
    assert peak_mb < 256, f"RSS peaked {peak_mb:.1f} MB above the baseline"
    assert figures["after"]["fds"] <= figures["base"]["fds"] + 1
    assert figures["peak_fds"] <= figures["base"]["fds"] + 4
    # one stream, served in order: a good request waits behind the hostile ones written before
    # it (each attacker waits for its last answer, so at most one round of each: an 800-deep
    # expression ~1 s, 100 conditions to compile ~1.5 s, a 4 MiB expression, on an idle machine),
    # so the bound is the cost of a round of attacks, not the quiet latency; it catches a hang
    assert len(figures["hostile"]) >= 1
    quiet_p50 = pct(figures["quiet"], 0.5)
    assert pct(figures["hostile"], 0.5) <= max(100 * quiet_p50, 30.0)
    assert pct(figures["after_latencies"], 0.5) <= max(5 * quiet_p50, 0.1)


def test_dap_framing_errors_end_the_session_with_exit_2():
    for code, stderr in framing_churn(4):
        assert code == 2, stderr
        assert "Traceback" not in stderr
        assert stderr.count("\n") == 1 and stderr.startswith("stvm: error: dap:"), stderr
