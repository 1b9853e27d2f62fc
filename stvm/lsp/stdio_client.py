"""A raw client of `stvm lsp` over stdio: JSON-RPC 2.0 messages framed with `Content-Length`
headers (the LSP base protocol), written to the server's stdin as given, and every message the
server writes read into a queue with the time it arrived.

No LSP client library stands in between, so a malformed message reaches the server exactly as
it was sent (tests/lsp/test_lsp_fuzz.py, tests/lsp/test_lsp_protocol.py), and the time from a
`didChange` to its `publishDiagnostics` is measured where an editor would see it
(bench/bench_lsp.py). It lives in the package rather than under tests/ because the bench, which
runs outside the test suite, uses it too; it imports nothing else of stvm, so a script (a CI
smoke test of an installed stvm) can drive the server with it as well.
"""

from __future__ import annotations

import json
import queue
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Callable

SERVER = (sys.executable, "-m", "stvm", "lsp")


class StdioClient:
    """One `stvm lsp` process (or `command`) and the messages it sends.

    `timeout` bounds every wait for a message (a loaded machine needs more than an idle one);
    with `capture_stderr` the server's stderr is kept in a temporary file and `close()` returns
    it (a test asserts it holds no traceback), else it is discarded."""

    def __init__(self, command=SERVER, cwd: str | Path | None = None, timeout: float = 60.0,
                 capture_stderr: bool = False, env: dict | None = None, first_id: int = 0) -> None:
        self.timeout = timeout
        self._stderr = tempfile.TemporaryFile() if capture_stderr else None
        self.proc = subprocess.Popen(list(command), stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=self._stderr if self._stderr is not None else subprocess.DEVNULL,
                                     cwd=cwd, env=env)
        self.messages: queue.Queue[tuple[float, dict]] = queue.Queue()
        self.next_id = first_id
        self._stderr_text: str | None = None
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        stream = self.proc.stdout
        while True:
            header = b""
            while not header.endswith(b"\r\n\r\n"):
                byte = stream.read(1)
                if not byte:
                    return
                header += byte
            length = int(next(line.split(b":")[1] for line in header.split(b"\r\n")
                              if line.lower().startswith(b"content-length")))
            body = stream.read(length)
            self.messages.put((time.perf_counter(), json.loads(body)))

    # ---- writing ---------------------------------------------------------------------------

    def frame(self, body: bytes) -> float:
        """Write `body` as one message (its Content-Length header first); the time it was sent."""
        sent = time.perf_counter()
        self.proc.stdin.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
        self.proc.stdin.flush()
        return sent

    def send(self, message) -> float:
        """Send `message`: bytes as they are (a malformed body), anything else as its JSON (a str
        too: the fuzz tests send JSON strings such as `""` as messages)."""
        if isinstance(message, bytes):
            return self.frame(message)
        return self.frame(json.dumps(message).encode())

    def fresh_id(self) -> int:
        self.next_id += 1
        return self.next_id

    def notify(self, method: str, params) -> float:
        return self.send({"jsonrpc": "2.0", "method": method, "params": params})

    # ---- reading ---------------------------------------------------------------------------

    def until(self, done: Callable[[dict], bool], timeout: float | None = None,
              timed: bool = False) -> list:
        """Every message up to and including the first one `done` accepts (with `timed`, each
        as (arrival time, message)); raises queue.Empty if none comes within the timeout."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        out = []
        while True:
            at, msg = self.messages.get(timeout=max(0.1, deadline - time.monotonic()))
            out.append((at, msg) if timed else msg)
            if done(msg):
                return out

    def timed_request(self, method: str, params) -> tuple[float, dict]:
        """(seconds from sending to the answer, the answer) of a request."""
        msg_id = self.fresh_id()
        sent = self.send({"jsonrpc": "2.0", "id": msg_id, "method": method, "params": params})
        at, answer = self.until(lambda m: m.get("id") == msg_id and "method" not in m, timed=True)[-1]
        return at - sent, answer

    def request(self, method: str, params) -> dict:
        """The answer (result or error) to a request; messages before it are passed over."""
        return self.timed_request(method, params)[1]

    def wait_diagnostics(self, uri: str, ready: Callable[[list], bool] | None = None) -> tuple[float, list]:
        """(arrival time, diagnostics) of the next `publishDiagnostics` of `uri` (whose
        diagnostics `ready` accepts, when given)."""
        def wanted(msg: dict) -> bool:
            return msg.get("method") == "textDocument/publishDiagnostics" and msg["params"]["uri"] == uri \
                and (ready is None or ready(msg["params"]["diagnostics"]))
        at, msg = self.until(wanted, timed=True)[-1]
        return at, msg["params"]["diagnostics"]

    def diagnostics(self, uri: str) -> list[dict]:
        return self.wait_diagnostics(uri)[1]

    def diagnostics_uris(self, until: str) -> list[str]:
        """The URIs of every `publishDiagnostics` up to and including one of `until`."""
        published = self.until(lambda m: m.get("method") == "textDocument/publishDiagnostics"
                               and m["params"]["uri"] == until)
        return [m["params"]["uri"] for m in published if m.get("method") == "textDocument/publishDiagnostics"]

    # ---- the end -----------------------------------------------------------------------------

    def close(self) -> str:
        """`shutdown` and `exit` (the process killed if it does not end); the server's stderr
        when it was captured, else "". Closing again returns the same text."""
        if self._stderr_text is not None:
            return self._stderr_text
        try:
            if self.proc.poll() is None:
                self.request("shutdown", None)
                self.notify("exit", None)
                self.proc.wait(timeout=30)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
        text = ""
        if self._stderr is not None:
            self._stderr.seek(0)
            text = self._stderr.read().decode("utf-8", "replace")
            self._stderr.close()
        self._stderr_text = text
        return text


class SharedClient(StdioClient):
    """A StdioClient that several threads use at once (a soak's attackers beside its good client,
    the browser bridge's concurrent HTTP requests): writes are serialised, and one router thread
    takes every message off the queue and hands each answer to the request waiting for its id.
    A request the server makes of the client is answered with a null result; it and every
    notification go to `unsolicited`. Answers are counted, and those with JSON-RPC's
    Internal error (-32603, a server bug) kept in `internal`."""

    INTERNAL_ERROR = -32603

    def __init__(self, *args, **kwargs) -> None:
        self._write_lock = threading.Lock()
        self._waiting: dict[object, queue.Queue] = {}
        self.unsolicited: queue.Queue[dict] = queue.Queue()
        self.answered = 0
        self.internal: list[str] = []
        super().__init__(*args, **kwargs)
        self.pid = self.proc.pid
        threading.Thread(target=self._route, daemon=True).start()

    def frame(self, body: bytes) -> float:
        with self._write_lock:
            return super().frame(body)

    def fresh_id(self) -> int:
        with self._write_lock:
            return super().fresh_id()

    def _route(self) -> None:
        while True:
            at, message = self.messages.get()
            if "method" not in message:
                self.answered += 1
                error = message.get("error")
                if isinstance(error, dict) and error.get("code") == self.INTERNAL_ERROR:
                    self.internal.append(str(error.get("message"))[:300])
                box = self._waiting.pop(message.get("id"), None)
                if box is not None:
                    box.put((at, message))
                continue
            if "id" in message:
                self.send({"jsonrpc": "2.0", "id": message["id"], "result": None})
            self.unsolicited.put(message)

    def _ask(self, message: dict, msg_id, timeout: float | None) -> tuple[float, dict]:
        box: queue.Queue = queue.Queue()
        self._waiting[msg_id] = box
        sent = self.send({**message, "id": msg_id})
        try:
            at, answer = box.get(timeout=self.timeout if timeout is None else timeout)
        except queue.Empty:
            self._waiting.pop(msg_id, None)
            raise
        return at - sent, answer

    def timed_request(self, method: str, params, timeout: float | None = None) -> tuple[float, dict]:
        return self._ask({"jsonrpc": "2.0", "method": method, "params": params}, self.fresh_id(), timeout)

    def forward(self, message: dict, timeout: float | None = None) -> dict:
        """The answer to `message`, a request with an id of its sender's (renumbered on the way,
        so two senders cannot collide), under that id again."""
        _, answer = self._ask(message, f"fwd-{self.fresh_id()}", timeout)
        return {**answer, "id": message.get("id")}

    def wait_diagnostics(self, uri: str, ready: Callable[[list], bool] | None = None) -> tuple[float, list]:
        deadline = time.monotonic() + self.timeout
        while True:
            msg = self.unsolicited.get(timeout=max(0.01, deadline - time.monotonic()))
            if msg.get("method") == "textDocument/publishDiagnostics" and msg["params"]["uri"] == uri \
                    and (ready is None or ready(msg["params"]["diagnostics"])):
                return time.perf_counter(), msg["params"]["diagnostics"]
