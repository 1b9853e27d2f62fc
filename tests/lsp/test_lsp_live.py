"""Live values as inlay hints (stvm/lsp/live.py): `stvm run --opcua` runs a counter program, the
language server reads its variables over OPC UA and shows them beside the names; a second
request a moment later shows the counter further on. Without a running VM: no hints."""

from __future__ import annotations

import socket
import subprocess
import sys
import time

import pytest
import pytest_lsp
from lsprotocol import types as lsp
from pytest_lsp import ClientServerConfig, LanguageClient

from lsp_helpers import FIXTURES, doc, open_file

pytestmark = pytest.mark.asyncio(loop_scope="module")

COUNTER = FIXTURES / "live" / "counter.st"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


PORT = free_port()
ENDPOINT = f"opc.tcp://127.0.0.1:{PORT}"


@pytest.fixture(scope="module")
def running_vm():
    proc = subprocess.Popen([sys.executable, "-m", "stvm", "run", str(COUNTER.parent), "--opcua", ENDPOINT,
                             "--realtime", "--scan", "10ms", "--duration", "300s"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            pytest.fail(f"stvm run --opcua ended: {proc.stderr.read().decode(errors='replace')}")
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", PORT)) == 0:
                break
        time.sleep(0.5)
    else:
        proc.kill()
        pytest.fail("stvm run --opcua did not listen within 90 s")
    yield proc
    proc.terminate()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


@pytest_lsp.fixture(scope="module", config=ClientServerConfig(server_command=[sys.executable, "-m", "stvm", "lsp"]))
async def client(lsp_client: LanguageClient):
    await lsp_client.initialize_session(lsp.InitializeParams(
        capabilities=lsp.ClientCapabilities(), initialization_options={"liveValues": {"endpoint": ENDPOINT}}))
    yield
    await lsp_client.shutdown_session()


def hints_by_line(hints) -> dict[int, str]:
    return {h.position.line: h.label for h in hints}


async def test_inlay_hints_show_the_running_values(client, running_vm):
    await open_file(client, COUNTER)
    whole = lsp.Range(lsp.Position(0, 0), lsp.Position(20, 0))
    deadline = time.monotonic() + 60
    while True:     # the server connects on the first request; a refused attempt is retried after 5 s
        first = hints_by_line(await client.text_document_inlay_hint_async(lsp.InlayHintParams(doc(COUNTER), whole)))
        if first or time.monotonic() > deadline:
            break
        time.sleep(1)
    assert first[5] == "= TRUE" and first[6] == "= E_Mode#Fast"       # declarations of running, mode
    n_first = int(first[4].removeprefix("= "))
    assert n_first > 0
    time.sleep(0.5)
    second = hints_by_line(await client.text_document_inlay_hint_async(lsp.InlayHintParams(doc(COUNTER), whole)))
    assert int(second[8].removeprefix("= ")) > n_first                  # `n := n + 1;` further on
    hint = (await client.text_document_inlay_hint_async(lsp.InlayHintParams(doc(COUNTER), whole)))[0]
    assert hint.position == lsp.Position(4, 5)                           # right after `n` on its declaration line


async def test_no_running_vm_means_no_hints():
    from stvm.lsp.live import LiveValues
    live = LiveValues(f"opc.tcp://127.0.0.1:{free_port()}")
    assert await live.read(["Counter.n"]) == {}
    assert live.client is None and live.failed_at > 0
    failed_at = live.failed_at
    assert await live.read(["Counter.n"]) == {}
    assert live.failed_at == failed_at                                  # no new attempt for a while
