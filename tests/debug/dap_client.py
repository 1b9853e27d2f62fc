"""A small Debug Adapter Protocol client for the tests: runs `python -m stvm dap` as a subprocess
and talks to it over its stdin/stdout, as VS Code does."""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any, Callable

ROOT = Path(__file__).resolve().parents[2]
TIMEOUT_S = 60.0


class DapError(AssertionError):
    pass


class DapClient:
    def __init__(self, cwd: Path = ROOT) -> None:
        env = dict(os.environ)
        env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
        self.proc = subprocess.Popen([sys.executable, "-m", "stvm", "dap"], cwd=str(cwd), env=env,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.seq = 0
        self.messages: queue.Queue = queue.Queue()
        self.events: list[dict] = []
        self.responses: dict[int, dict] = {}
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    # ---- wire
    def _read(self) -> None:
        stream = self.proc.stdout
        while True:
            length = None
            while True:
                line = stream.readline()
                if not line:
                    self.messages.put(None)
                    return
                line = line.strip()
                if not line:
                    break
                name, _, value = line.decode().partition(":")
                if name.lower() == "content-length":
                    length = int(value)
            assert length is not None, "message without Content-Length"
            self.messages.put(json.loads(stream.read(length)))

    def _send(self, message: dict) -> None:
        data = json.dumps(message).encode()
        self.proc.stdin.write(b"Content-Length: %d\r\n\r\n" % len(data) + data)
        self.proc.stdin.flush()

    def _pump(self, timeout: float) -> bool:
        try:
            message = self.messages.get(timeout=timeout)
        except queue.Empty:
            return False
        if message is None:
            raise DapError("the adapter closed its output; stderr:\n" + self.stderr())
        if message["type"] == "event":
            self.events.append(message)
        elif message["type"] == "response":
            self.responses[message["request_seq"]] = message
        return True

    # ---- API
    def request(self, command: str, ok: bool = True, **arguments: Any) -> dict:
        """Send a request and return its response (asserting success unless ok=False)."""
        self.seq += 1
        seq = self.seq
        self._send({"seq": seq, "type": "request", "command": command, "arguments": arguments})
        while seq not in self.responses:
            if not self._pump(TIMEOUT_S):
                raise DapError(f"no response to {command}")
        response = self.responses.pop(seq)
        if ok and not response["success"]:
            raise DapError(f"{command} failed: {response.get('message')}")
        return response

    def body(self, command: str, **arguments: Any) -> dict:
        return self.request(command, **arguments).get("body", {})

    def wait_event(self, name: str, predicate: Callable[[dict], bool] | None = None,
                   timeout: float = TIMEOUT_S) -> dict:
        """The first not yet consumed event `name` (matching `predicate`), consuming it."""
        import time
        deadline = time.monotonic() + timeout
        while True:
            for i, event in enumerate(self.events):
                if event["event"] == name and (predicate is None or predicate(event)):
                    return self.events.pop(i)
            left = deadline - time.monotonic()
            if left <= 0:
                raise DapError(f"no {name} event; events: {[e['event'] for e in self.events]}")
            self._pump(min(left, 0.5))

    def stopped(self, reason: str | None = None) -> dict:
        event = self.wait_event("stopped")
        if reason is not None:
            assert event["body"]["reason"] == reason, event
        return event["body"]

    def top_frame(self, thread_id: int = 1) -> dict:
        return self.body("stackTrace", threadId=thread_id)["stackFrames"][0]

    def variables(self, reference: int, **kwargs: Any) -> dict[str, dict]:
        return {v["name"]: v for v in self.body("variables", variablesReference=reference, **kwargs)["variables"]}

    def scope_variables(self, frame_id: int) -> dict[str, dict[str, dict]]:
        scopes = self.body("scopes", frameId=frame_id)["scopes"]
        return {s["name"]: self.variables(s["variablesReference"]) for s in scopes}

    def evaluate(self, expression: str, frame_id: int | None = None, context: str = "watch") -> dict:
        args: dict[str, Any] = {"expression": expression, "context": context}
        if frame_id is not None:
            args["frameId"] = frame_id
        return self.body("evaluate", **args)

    def launch(self, program: Any, breakpoints: dict[str, list[dict]] | None = None, **arguments: Any) -> dict:
        """initialize, launch, setBreakpoints per file, configurationDone; returns the
        setBreakpoints bodies by file."""
        self.body("initialize", adapterID="stvm", linesStartAt1=True, columnsStartAt1=True)
        self.request("launch", program=program, **arguments)
        self.wait_event("initialized")
        results = {}
        for path, specs in (breakpoints or {}).items():
            results[path] = self.body("setBreakpoints", source={"path": str(path)}, breakpoints=specs)
        self.body("setExceptionBreakpoints", filters=["fault"])
        self.request("configurationDone")
        return results

    def stderr(self) -> str:
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        try:
            return self.proc.stderr.read().decode(errors="replace") if self.proc.poll() is not None else ""
        except (OSError, ValueError):
            return ""

    def close(self) -> int:
        """Disconnect (if still running) and return the adapter's exit code."""
        if self.proc.poll() is None:
            try:
                self.request("disconnect", ok=False)
            except (DapError, OSError):
                pass
            try:
                self.proc.stdin.close()
            except OSError:
                pass
        try:
            return self.proc.wait(timeout=30)
        finally:
            for stream in (self.proc.stdout, self.proc.stderr):
                try:
                    stream.close()
                except OSError:
                    pass
