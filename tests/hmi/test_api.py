"""The HMI's web contract without a browser: pages, /api/vars, presets, WebSocket, token, limits.

The server is the real one (uvicorn on an ephemeral loopback port) beside a VM scanning on the
real-time clock in a thread; clients are httpx, websockets and raw sockets.
"""

from __future__ import annotations

import contextlib
import json
import re
import socket
import threading
import time

import httpx
import pytest
from websockets.sync.client import connect as ws_connect

import stvm
from small_project import write_project
from stvm.frontend import VariableBridge
from stvm.hmi import HmiServer, load_pages
from stvm.hmi.cli import page_files
from stvm.hmi.wire import MAX_BODY_BYTES


class Live:
    def __init__(self, main, token=None, robot=None):
        self.project = stvm.load([str(main)])
        self.vm = self.project.start(scan="1ms", realtime=True)
        bridge = VariableBridge(self.vm)
        files, start = page_files(self.project)
        self.hmi = load_pages(files, bridge.type_of, start)
        self.server = HmiServer(self.hmi, bridge, port=0, token=token, pose=robot).start()
        self.stop_flag = threading.Event()
        self.thread = threading.Thread(target=lambda: self.vm.run(until=self.stop_flag.is_set), daemon=True)
        self.thread.start()
        self.base = f"http://127.0.0.1:{self.server.port}"
        self.ws = f"ws://127.0.0.1:{self.server.port}/ws"
        self.http = httpx.Client(base_url=self.base, timeout=10)

    def close(self):
        self.http.close()
        self.stop_flag.set()
        self.thread.join(5)
        self.server.stop()

    def write(self, values, **kwargs):
        return self.http.post("/api/vars", json=values, **kwargs)


@pytest.fixture
def live(tmp_path):
    served = Live(write_project(tmp_path))
    yield served
    served.close()


def wait_for(condition, timeout_s=5.0, what="condition"):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what}")


# ---------------------------------------------------------------------------- pages

def test_root_redirects_to_the_start_page(live):
    response = live.http.get("/", follow_redirects=False)
    assert response.status_code == 302 and response.headers["location"] == "/page/Main"


def test_page_html_carries_the_contract(live):
    html = live.http.get("/page/Test").text
    for path in ("Lamp", "Speed", "Gain", "M", "Pose", "Name", "Msg", "Count", "Start", "Hold", "Target.X"):
        assert f'data-var="{path}"' in html, path
    assert re.search(r'class="lamp" data-var="Lamp" data-state="off"', html)
    for action in ("set:Start=TRUE", "momentary:Hold", "set:Speed=50", "preset:Defaults", "page:Main", "popup:Axis-X"):
        assert f'data-action="{action}"' in html, action
    assert 'data-min="10"' in html and 'data-max="100"' in html
    assert '<option value="Run">Run</option>' in html and '<option value="1">LEFTY</option>' in html
    assert 'data-maxbytes="10"' in html    # STRING[11] holds 10 bytes (Omron counts the NUL)
    assert "data-robot-view" in html and 'id="popup-Axis-Y"' in html
    assert "http://" not in html.replace(live.base, "") and "https://" not in html   # no CDN
    assert live.http.get("/static/hmi.js").status_code == 200
    assert live.http.get("/page/Nope").status_code == 404


def test_page_list(live):
    data = live.http.get("/api/pages").json()
    assert data["start"] == "Main" and set(data["pages"]) == {"Main", "Test"}
    assert "Speed" in data["writable"] and "Lamp" not in data["writable"]


# ---------------------------------------------------------------------------- reads and writes

def test_get_vars_returns_iec_literals(live):
    live.vm  # values written before through the API land at the next scan start
    assert live.write({"Name": "'it''s'"}).status_code in (200, 422)
    assert live.write({"Name": "'a$'b'", "M": "Mode#Stop", "Gain": "2.5", "Start": "TRUE"}).status_code == 200
    data = live.http.get("/api/vars", params=[("path", "Name"), ("path", "M"), ("path", "Gain"),
                                              ("path", "Start"), ("path", "Lamp")]).json()
    assert data["Name"] == "'a$'b'" and data["M"] == "Mode#Stop" and data["Gain"] == "2.5"
    assert data["Start"] == "TRUE"
    wait_for(lambda: live.http.get("/api/vars", params={"path": "Lamp"}).json()["Lamp"] == "TRUE", what="Lamp")


def test_get_vars_refuses_unknown_and_unshown(live):
    assert live.http.get("/api/vars").status_code == 400
    unknown = live.http.get("/api/vars", params={"path": "Nope"})
    assert unknown.status_code == 404 and "unknown variable" in unknown.json()["error"]
    hidden = live.http.get("/api/vars", params={"path": "Secret"})
    assert hidden.status_code == 403


@pytest.mark.parametrize("values, expected", [
    ({"Speed": "75"}, {"Speed": 75}),                          # numeric
    ({"Speed": 42}, {"Speed": 42}),                            # JSON number accepted as literal
    ({"Gain": "-0.25"}, {"Gain": -0.25}),
    ({"M": "Run"}, {"M": 1}),                                  # drop-down over an enumeration
    ({"Pose": "1"}, {"Pose": 1}),                              # drop-down over an integer
    ({"Name": "'cell 1'"}, {"Name": b"cell 1"}),               # text
    ({"Start": "TRUE"}, {"Start": True}),                      # toggle / set button
    ({"Hold": True}, {"Hold": True}),                          # momentary press
    ({"Target.Y": "-120.5"}, {"Target.Y": -120.5}),            # pop-up field
])
def test_each_writing_widget_kind(live, values, expected):
    response = live.write(values)
    assert response.status_code == 200, response.text
    assert response.json()["ok"] is True
    for path, value in expected.items():
        assert live.vm[path] == value


@pytest.mark.parametrize("values, status, reason", [
    ({"Speed": "101"}, 422, "above the maximum 100"),
    ({"Speed": "9"}, 422, "below the minimum 10"),
    ({"Speed": "abc"}, 422, "Speed:"),
    ({"Speed": "-1"}, 422, "below the minimum 10"),           # the page's range, not UINT's
    ({"Pose": "2"}, 422, "not one of the choices 0, 1"),
    ({"M": "Walk"}, 422, "'Walk' is not one of the choices (Idle, Run, Stop)"),
    ({"Name": "'" + "x" * 11 + "'"}, 422, "text too long (11 characters; at most 10)"),
    ({"Speed": "0x10"}, 422, "'0x10' is not a number"),
    ({"Speed": "50,5"}, 422, "50.5 is not a whole number"),
    ({"Gain": "1.2.3"}, 422, "is not a number"),
    ({"Target.X": "501"}, 422, "above the maximum 500"),
    ({"Lamp": "TRUE"}, 403, "not written by any HMI page"),   # shown, read-only
    ({"Secret": "1"}, 403, "not a variable any HMI page maps"),
    ({"Nope.x": "1"}, 403, "not a variable any HMI page maps"),
    ({"Speed": [1]}, 400, "IEC literal string"),
    ({}, 400, "nothing to write"),
])
def test_bad_writes_are_refused_with_a_reason(live, values, status, reason):
    response = live.write(values)
    assert response.status_code == status, response.text
    body = response.json()
    assert body["ok"] is False and reason in body["error"], body


def test_a_refused_batch_changes_nothing(live):
    assert live.write({"Speed": "30"}).status_code == 200
    response = live.write({"Gain": "9.5", "Speed": "500"})   # the second value is out of range
    assert response.status_code == 422
    time.sleep(0.05)
    assert live.vm["Gain"] == 0.0 and live.vm["Speed"] == 30


def test_malformed_bodies(live):
    bad_json = live.http.post("/api/vars", content=b"{not json", headers={"Content-Type": "application/json"})
    assert bad_json.status_code == 400 and "malformed JSON" in bad_json.json()["error"]
    not_object = live.write(["Speed", 1])
    assert not_object.status_code == 400
    wrong_type = live.http.post("/api/vars", content=b'{"Speed": "20"}', headers={"Content-Type": "text/plain"})
    assert wrong_type.status_code == 415
    binary = live.http.post("/api/vars", content=b"\xff\xfe\x00", headers={"Content-Type": "application/json"})
    assert binary.status_code == 400
    huge = live.http.post("/api/vars", content=b"{" + b" " * (MAX_BODY_BYTES + 10) + b"}",
                          headers={"Content-Type": "application/json"})
    assert huge.status_code == 413

    def chunks():   # no Content-Length: the limit holds while streaming
        for _ in range(100):
            yield b" " * 4096
    streamed = live.http.post("/api/vars", content=chunks(), headers={"Content-Type": "application/json"})
    assert streamed.status_code == 413
    assert live.http.post("/api/nothing", json={}).status_code == 404
    assert live.http.delete("/api/vars").status_code == 405
    assert live.write({"Speed": "20"}).status_code == 200   # still serving


def test_presets_apply_in_one_scan_and_steps_in_consecutive_scans(live):
    response = live.http.post("/api/presets/Defaults", json={})
    assert response.status_code == 200, response.text
    assert (live.vm["Speed"], live.vm["Gain"], live.vm["Name"], live.vm["M"]) == (20, 1.5, b"hello", 1)
    before = live.vm["Edges"]
    for _ in range(3):   # FALSE then TRUE in the next scan: each press is one rising edge
        assert live.http.post("/api/presets/Pulse").status_code == 200
    wait_for(lambda: live.vm["Edges"] == before + 3, what="three rising edges")
    assert live.http.post("/api/presets/Nope").status_code == 404


def test_momentary_press_is_seen_even_when_released_at_once(live):
    before = live.vm["Edges"]
    for _ in range(5):
        assert live.write({"Hold": "TRUE"}).status_code == 200
        assert live.write({"Hold": "FALSE"}).status_code == 200
    wait_for(lambda: live.vm["Edges"] == before + 5, what="five presses")


# ---------------------------------------------------------------------------- the WebSocket

def test_websocket_sends_the_page_then_changed_values_only(live):
    with ws_connect(live.ws + "?page=Test") as ws:
        first = json.loads(ws.recv(timeout=5))
        assert {"Lamp", "Speed", "Name", "Count", "Target.X", "Target.Z"} <= set(first["values"])
        assert first["values"]["Lamp"] is False and first["values"]["M"] == "Idle"
        assert live.write({"Name": "'hi'"}).status_code == 200
        seen = {}
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and seen.get("Msg") != "hi":
            update = json.loads(ws.recv(timeout=5))
            assert "Lamp" not in update["values"]      # unchanged values are not sent again
            seen.update(update["values"])
        assert seen["Msg"] == "hi" and seen["Name"] == "hi"


def test_websocket_rate_is_at_least_10_per_second(live):
    with ws_connect(live.ws + "?page=Test") as ws:
        ws.recv(timeout=5)
        start = time.monotonic()
        count = 0
        while time.monotonic() - start < 1.0:
            ws.recv(timeout=5)      # Count changes every scan: every sample is an update
            count += 1
        assert count >= 10


def test_unknown_page_websocket_is_refused(live):
    from websockets.exceptions import InvalidStatus
    with pytest.raises(InvalidStatus) as exc:
        ws_connect(live.ws + "?page=Nope")
    assert exc.value.response.status_code == 403


def test_200_websockets_and_clients_that_vanish(live):
    with contextlib.ExitStack() as stack:
        sockets = [stack.enter_context(ws_connect(live.ws + "?page=Test", open_timeout=20)) for _ in range(200)]
        for ws in sockets:
            assert "values" in json.loads(ws.recv(timeout=20))
        assert live.http.get("/api/vars", params={"path": "Speed"}).status_code == 200
        for ws in sockets[:100]:
            ws.socket.close()           # gone without a close frame; the rest close properly
    # half a request, half a WebSocket frame, then gone
    for junk in (b"GET /page/Test HTTP/1.1\r\nHost: 127.0.0.1\r\n",
                 b"POST /api/vars HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\nContent-Length: 50\r\n\r\n{\"Sp",
                 b"\x00\xff garbage \r\n\r\n"):
        with socket.create_connection(("127.0.0.1", live.server.port)) as raw:
            raw.sendall(junk)
    with ws_connect(live.ws + "?page=Test") as ws:
        raw_ws = ws.socket
        ws.recv(timeout=5)
        raw_ws.sendall(b"\x81\xfe\x00")   # the start of a masked text frame, then nothing
    wait_for(lambda: len(live.server.clients) == 0, 10, "every client to be gone")
    assert live.write({"Speed": "33"}).status_code == 200
    assert live.server._watch is None      # no client: nothing is sampled any more


def test_slow_client_does_not_slow_the_scan_or_other_clients(live):
    slow = socket.create_connection(("127.0.0.1", live.server.port))
    slow.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    key = "dGhlIHNhbXBsZSBub25jZQ=="
    slow.sendall(f"GET /ws?page=Test HTTP/1.1\r\nHost: 127.0.0.1:{live.server.port}\r\nUpgrade: websocket\r\n"
                 f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n".encode())
    try:
        time.sleep(0.3)   # the slow client now reads nothing at all
        scans = live.vm.scan_count
        with ws_connect(live.ws + "?page=Test") as fast:
            fast.recv(timeout=5)
            got = 0
            start = time.monotonic()
            while time.monotonic() - start < 1.5:
                fast.recv(timeout=5)
                got += 1
        assert got >= 15
        assert live.vm.scan_count - scans > 1000     # the VM kept its 1 ms scan meanwhile
        slow_clients = [c for c in live.server.clients]
        for client in slow_clients:                    # backlog: at most one value per path
            assert len(client.pending) <= len(client.paths)
    finally:
        slow.close()


# ---------------------------------------------------------------------------- token and origin

@pytest.fixture
def guarded(tmp_path):
    served = Live(write_project(tmp_path), token="s3cret-token")
    yield served
    served.close()


def test_token_is_required_when_the_server_has_one(guarded):
    assert guarded.http.get("/page/Test").status_code == 401
    refused = guarded.write({"Speed": "20"})
    assert refused.status_code == 401 and "token" in refused.json()["error"]
    assert guarded.http.get("/page/Test?token=wrong").status_code == 401
    page = guarded.http.get("/page/Test?token=s3cret-token")
    assert page.status_code == 200 and "stvm_hmi_token" in page.headers["set-cookie"]
    assert guarded.http.get("/api/vars", params={"path": "Speed"},
                            headers={"Authorization": "Bearer s3cret-token"}).status_code == 200
    with_cookie = httpx.post(guarded.base + "/api/vars", json={"Speed": "20"}, cookies={"stvm_hmi_token": "s3cret-token"})
    assert with_cookie.status_code == 200
    with pytest.raises(Exception):
        with ws_connect(guarded.ws + "?page=Test") as ws:
            ws.recv(timeout=5)
    with ws_connect(guarded.ws + "?page=Test&token=s3cret-token") as ws:
        assert "values" in json.loads(ws.recv(timeout=5))


def test_a_non_loopback_host_gets_a_token(live):
    server = HmiServer(live.hmi, live.server.bridge, host="0.0.0.0", port=0)
    assert server.token and len(server.token) >= 20 and f"?token={server.token}" in server.url
    assert HmiServer(live.hmi, live.server.bridge, host="127.0.0.1").token is None


def test_other_hosts_and_origins_are_refused(live):
    assert live.http.get("/page/Test", headers={"Host": "evil.example"}).status_code == 403
    cross = live.write({"Speed": "20"}, headers={"Origin": "http://evil.example"})
    assert cross.status_code == 403 and "cross-origin" in cross.json()["error"]
    same = live.write({"Speed": "20"}, headers={"Origin": live.base})
    assert same.status_code == 200


def test_a_popup_is_watched_only_while_open(live_hmi):
    # the thesis PnP page: six segment editors of 20 fields each, sampled only when shown
    url = f"ws://127.0.0.1:{live_hmi.server.port}/ws?page=pgPnP_sequence"
    field = "PnP_MoveParameters[1].Speed"
    with ws_connect(url) as ws:
        first = json.loads(ws.recv(timeout=5))
        assert field not in first["values"] and field not in live_hmi.server._watch_paths
        ws.send(json.dumps({"popup": "Segment-1"}))
        seen = {}
        deadline = time.monotonic() + 5
        while field not in seen and time.monotonic() < deadline:
            seen.update(json.loads(ws.recv(timeout=5))["values"])
        assert seen[field] == 0
        ws.send(json.dumps({"popup": None}))
        wait_for(lambda: field not in live_hmi.server._watch_paths, what="the pop-up unwatched")
        ws.send("not json")                       # ignored
        ws.send(json.dumps({"popup": "Nope-9"}))  # unknown: ignored
        assert json.loads(ws.recv(timeout=5))["scan"] >= first["scan"]
