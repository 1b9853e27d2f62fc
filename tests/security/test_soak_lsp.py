"""Soak of the language server (`stvm lsp`, stdio, issue 34). Its one client is the process at
the other end of the stream, so the hostile client writes hostile messages on that stream,
between whole messages, while a well-behaved loop (hover, definition, documentSymbol on an open
document) keeps going: bodies that are not JSON or not UTF-8, JSON nested 100,000 deep,
messages that are not JSON-RPC, unknown methods, params of the wrong shape, `$/cancelRequest`
for ids never sent, didChange floods (debounced checks), open/close churn of many documents
(each its own project), and a multi-MiB document. Asserted: every request answered under its
id, no traceback on stderr, RSS and descriptors bounded, the good loop's latency within a
generous bound. A stdio server has no connections to flood: its "clients past the limit" is
not a thing, and a header it cannot resynchronise after ends the session (exit 1 from pygls).

`python bench/bench_soak_lsp.py` runs the same for longer and prints the figures."""

from __future__ import annotations

import json
import os
import queue
import time
from pathlib import Path


from soak_harness import Attackers, Sampler, fd_count, pct, rss_kb, soak_figures
from stvm.lsp.stdio_client import SharedClient

ROOT = Path(__file__).resolve().parents[2]
PROGRAM = """FUNCTION_BLOCK Counter
VAR_INPUT step : INT; END_VAR
VAR_OUTPUT total : DINT; END_VAR
total := total + step;
END_FUNCTION_BLOCK

PROGRAM Main
VAR
  c : Counter;
  n : INT;
END_VAR
n := n + 1;
c(step := n);
END_PROGRAM
"""


def _env() -> dict:
    return dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))


class Server(SharedClient):
    """`stvm lsp` shared by the good client and the attackers (stvm/lsp/stdio_client.py)."""

    def __init__(self) -> None:
        super().__init__(cwd=ROOT, env=_env(), timeout=120.0, capture_stderr=True)

    def write(self, body: bytes) -> None:
        self.frame(body)

    def request(self, method: str, params, wait: bool = True, timeout: float = 120.0) -> dict | None:
        if not wait:   # an attacker's flood: the answer is counted, nobody waits for it
            self.send({"jsonrpc": "2.0", "id": self.fresh_id(), "method": method, "params": params})
            return None
        try:
            return self.timed_request(method, params, timeout)[1]
        except queue.Empty:
            raise AssertionError(f"no answer to {method}") from None

    def close(self) -> tuple[int, str]:
        try:
            stderr = super().close()
        except (AssertionError, OSError, queue.Empty):
            self.proc.kill()
            stderr = super().close()
        return self.proc.wait(), stderr


def _open(server: Server, path: Path, text: str, version: int = 1) -> str:
    uri = path.as_uri()
    server.notify("textDocument/didOpen", {"textDocument": {"uri": uri, "languageId": "structured-text",
                                                            "version": version, "text": text}})
    return uri


def _good_round(server: Server, uri: str) -> float:
    started = time.perf_counter()
    where = {"textDocument": {"uri": uri}, "position": {"line": 12, "character": 1}}   # `c` in c(step := n)
    hover = server.request("textDocument/hover", where)
    assert "error" not in hover and hover["result"] and "Counter" in json.dumps(hover["result"]), hover
    found = server.request("textDocument/definition", where)
    assert "error" not in found and found["result"], found
    symbols = server.request("textDocument/documentSymbol", {"textDocument": {"uri": uri}})
    assert "error" not in symbols and len(symbols["result"]) >= 2, symbols
    return time.perf_counter() - started


def _attacks(server: Server, folder: Path, uri: str, big_mb: int) -> dict:
    bodies = [b"not json", b"\xff\xfe\xfd", b"[" * 100_000 + b"]" * 100_000, b"{" * 50_000, b"[1, 2]", b"42",
              b'{"jsonrpc": "1.0", "id": 1, "method": "x"}', b'{"jsonrpc": "2.0", "id": true, "method": "x"}',
              b'{"jsonrpc": "2.0", "id": 5, "method": 7}',
              b'{"jsonrpc": "2.0", "id": "deep", "method": "textDocument/hover", "params": '
              + b"[" * 20_000 + b"]" * 20_000 + b"}"]

    def bad_bodies(deadline: float) -> int:
        for body in bodies:
            server.write(body)
        server.request("workspace/symbol", {"query": "Main"})   # paced: answered after all of them
        return len(bodies)

    def bad_requests(deadline: float) -> int:
        server.request("stvm/noSuchMethod", {}, wait=False)
        server.request("textDocument/hover", {"textDocument": 5, "position": "x"}, wait=False)
        server.request("textDocument/hover", {"textDocument": {"uri": "file:///nowhere/x.st"},
                                              "position": {"line": 10**9, "character": -1}}, wait=False)
        server.request("textDocument/completion", {"textDocument": {"uri": uri},
                                                   "position": {"line": 0, "character": 10**9}}, wait=False)
        server.request("textDocument/rename", {"textDocument": {"uri": uri}, "position": {"line": 9, "character": 2},
                                               "newName": "x" * 10_000}, wait=False)
        server.request("workspace/symbol", {"query": "*" * 100_000}, wait=False)
        for i in range(50):
            server.notify("$/cancelRequest", {"id": 10**9 + i})
        server.notify("textDocument/didChange", {"textDocument": {"uri": "file:///never/opened.st", "version": 1},
                                                 "contentChanges": [{"text": "x"}]})
        server.request("textDocument/documentSymbol", {"textDocument": {"uri": uri}})   # paced
        return 57

    def change_flood(deadline: float) -> int:
        path = folder / "typing.st"
        typed = _open(server, path, PROGRAM)
        version = 1
        for i in range(100):   # a person typing fast: one check per pause (debounced)
            version += 1
            text = PROGRAM.replace("n := n + 1;", f"n := n + {i} (* {'x' * (i % 40)} *);")
            server.notify("textDocument/didChange", {"textDocument": {"uri": typed, "version": version},
                                                     "contentChanges": [{"text": text}]})
        server.notify("textDocument/didClose", {"textDocument": {"uri": typed}})
        server.request("textDocument/documentSymbol", {"textDocument": {"uri": uri}})
        return 100

    def open_close_churn(deadline: float) -> int:
        churn = folder / "churn"
        for i in range(10):
            sub = churn / f"p{i % 5}"
            sub.mkdir(parents=True, exist_ok=True)
            text = PROGRAM.replace("Main", f"Main{i}")
            (sub / f"f{i}.st").write_text(text)   # on disk: see test_unsaved_buffer_alone_in_its_folder
            opened = _open(server, sub / f"f{i}.st", text)
            server.request("textDocument/documentSymbol", {"textDocument": {"uri": opened}})
            server.notify("textDocument/didClose", {"textDocument": {"uri": opened}})
        return 10

    def huge_document(deadline: float) -> int:
        text = "(* " + "x" * (big_mb << 20) + " *)\n" + PROGRAM
        (folder / "big" / "huge.st").write_text(PROGRAM)
        opened = _open(server, folder / "big" / "huge.st", text)
        server.request("textDocument/documentSymbol", {"textDocument": {"uri": opened}})
        server.notify("textDocument/didClose", {"textDocument": {"uri": opened}})
        time.sleep(0.5)
        return 1

    return {"bodies not JSON-RPC": bad_bodies, "bad requests": bad_requests, "didChange flood": change_flood,
            "open/close churn": open_close_churn, f"{big_mb} MiB document": huge_document}


def soak(seconds: float, tmp: Path, quiet_rounds: int = 30, big_mb: int = 4) -> dict:
    folder = tmp / "soak_lsp"
    (folder / "big").mkdir(parents=True)
    main = folder / "main.st"
    main.write_text(PROGRAM)
    server = Server()
    try:
        server.request("initialize", {"processId": None, "rootUri": folder.as_uri(), "capabilities": {}})
        server.notify("initialized", {})
        uri = _open(server, main, PROGRAM)
        server.wait_diagnostics(uri)
        for _ in range(5):
            _good_round(server, uri)   # warm-up
        quiet = [_good_round(server, uri) for _ in range(quiet_rounds)]
        base = {"rss": rss_kb(server.pid), "fds": fd_count(server.pid)}
        hostile: list[float] = []
        with Sampler(server.pid) as sampler:
            with Attackers(_attacks(server, folder, uri, big_mb), seconds) as attackers:
                end = time.monotonic() + seconds
                while time.monotonic() < end:
                    hostile.append(_good_round(server, uri))
        server.request("workspace/symbol", {"query": "Main"})
        time.sleep(1.0)   # the debounced checks of the churn end
        after_lat = [_good_round(server, uri) for _ in range(quiet_rounds)]
        after = {"rss": rss_kb(server.pid), "fds": fd_count(server.pid)}
        sent, answered, internal = server.next_id, server.answered, list(server.internal)
    finally:
        code, stderr = server.close()
    return soak_figures(quiet, hostile, after_lat, base, sampler, after, attackers,
                        sent=sent, answered=answered, internal=internal, exit=code, stderr=stderr)


def test_lsp_soak_stays_flat_and_keeps_answering(tmp_path):
    figures = soak(seconds=5.0, tmp=tmp_path, big_mb=2)
    assert not figures["errors"], figures["errors"]
    assert not figures["internal"], figures["internal"]
    assert figures["exit"] == 0, figures["stderr"]
    assert "Traceback" not in figures["stderr"], figures["stderr"]
    assert all(figures["counts"].values()), figures["counts"]
    assert figures["answered"] >= figures["sent"]
    growth_mb = (figures["after"]["rss"] - figures["base"]["rss"]) / 1024
    assert growth_mb < 64, f"RSS grew {growth_mb:.1f} MB"
    assert figures["after"]["fds"] <= figures["base"]["fds"] + 2
    assert len(figures["hostile"]) >= 1
    quiet_p50 = pct(figures["quiet"], 0.5)
    # one stream, in order, and checks on one worker: a good request can wait for a round of
    # attacks (a multi-MiB document checked, a 100-change burst); the bound catches a hang
    assert pct(figures["hostile"], 0.5) <= max(100 * quiet_p50, 30.0)
    assert pct(figures["after_latencies"], 0.5) <= max(5 * quiet_p50, 0.2)


def test_unsaved_buffer_alone_in_its_folder(tmp_path):
    folder = tmp_path / "root"
    (folder / "sub").mkdir(parents=True)
    (folder / "main.st").write_text(PROGRAM)
    server = Server()
    try:
        server.request("initialize", {"processId": None, "rootUri": folder.as_uri(), "capabilities": {}})
        server.notify("initialized", {})
        uri = _open(server, folder / "sub" / "new.st", PROGRAM)   # a new file, never saved
        answer = server.request("textDocument/documentSymbol", {"textDocument": {"uri": uri}})
    finally:
        server.close()
    assert "error" not in answer, answer["error"]["message"]
    assert len(answer["result"]) >= 2
