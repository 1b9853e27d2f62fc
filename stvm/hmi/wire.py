"""What the HMI server and its web app share: the limits of a request, one browser connection
(`Client`), a refused request (`Refused`) and the access token."""

from __future__ import annotations

import asyncio
import ipaddress
import json
from typing import Any
from urllib.parse import parse_qs

MAX_BODY_BYTES = 64 * 1024         # a page write is a few hundred bytes; a preset a few KiB
MAX_WEBSOCKETS = 1000              # more are refused (503); 200 open ones are a tested load
WS_MAX_MESSAGE_BYTES = 64 * 1024   # clients only ever send small messages
SEND_TIMEOUT_S = 10.0              # a client that cannot take one message in this time is dropped
TOKEN_COOKIE = "stvm_hmi_token"


class Refused(Exception):
    """A request refused with an HTTP status and a reason the page shows."""

    def __init__(self, status: int, reason: str, path: str | None = None) -> None:
        super().__init__(reason)
        self.status = status
        self.reason = reason
        self.path = path


class Client:
    """One WebSocket: the paths of its page, what is waiting to be sent, its sender task."""

    def __init__(self, websocket, page, client_id: str = "") -> None:
        self.websocket = websocket
        self.page = page
        self.id = client_id[:64]
        self.status: dict[str, Any] | None = None    # the VM's state, sent on change
        self.alarms: dict[str, Any] | None = None
        self.notices: list[str] = []
        self._sent_state: tuple | None = None
        self.paths = page.base_paths
        self._path_set = set(self.paths)
        self.popup: str | None = None
        self.robot = page.has_robot_view
        self.pending: dict[str, Any] = {}
        self.robot_pending: dict[str, Any] | None = None
        self.points: list = []
        self.full = True             # the next message carries every value (and the whole path)
        self.reset_path = False
        self.scan, self.now_ns = -1, 0
        self.wake = asyncio.Event()

    def open_popup(self, popup_id: str | None) -> bool:
        """Watch the fields of the pop-up the page opened (None: closed); False if unknown."""
        extra = self.page.popup_paths(popup_id) if popup_id else ()
        if popup_id and not extra:
            return False
        self.popup = popup_id
        self.paths = self.page.base_paths + tuple(p for p in extra if p not in self.page.base_paths)
        self._path_set = set(self.paths)
        self.full = True     # the next update carries every value of the page and pop-up
        return True

    def offer(self, server, changed: dict[str, Any], robot, new_points: list) -> None:
        if self.full:
            self.pending = {p: server._shown[p] for p in self.paths if p in server._shown}
            if self.robot:
                self.points = list(server._path)
                self.robot_pending = robot or server._robot
            self.full = False
            self.reset_path = True
        else:
            for path, value in changed.items():
                if path in self._path_set:
                    self.pending[path] = value
            if self.robot and robot is not None:
                self.robot_pending = robot
                self.points.extend(new_points)
                if len(self.points) > 2000:          # a stalled client: keep the newest points
                    del self.points[:-2000]
        self.scan, self.now_ns = server._scan, server._now_ns
        if self.pending or self.robot_pending is not None:
            self.wake.set()

    def offer_status(self, vm_state: dict[str, Any], alarms: dict[str, Any] | None, wake: bool = True) -> None:
        """The VM's state (every heartbeat: the page notices a silent server), the alarms when
        they changed."""
        self.status = dict(vm_state)
        if alarms is not None:
            self.alarms = alarms
        if wake:
            self.wake.set()

    def offer_notice(self, text: str) -> None:
        if len(self.notices) < 20:
            self.notices.append(text)
        self.wake.set()

    def take(self) -> dict[str, Any]:
        message: dict[str, Any] = {"scan": self.scan, "t": round(self.now_ns / 1e9, 3), "values": self.pending}
        self.pending = {}
        if self.status is not None:
            message["vm"] = self.status
            self.status = None
        if self.alarms is not None:
            message["alarms"] = self.alarms
            self.alarms = None
        if self.notices:
            message["notices"] = self.notices
            self.notices = []
        if self.robot_pending is not None:
            message["robot"] = dict(self.robot_pending, points=self.points,
                                    reset=self.reset_path)
            self.robot_pending = None
            self.points = []
            self.reset_path = False
        return message


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def token_from(headers: dict[str, str], query: str) -> str | None:
    """The token a request carries: `?token=`, `Authorization: Bearer`, or the page's cookie."""
    values = parse_qs(query).get("token")
    if values:
        return values[0]
    auth = headers.get("authorization", "")
    if auth.lower().startswith("bearer "):
        return auth[7:].strip()
    for part in headers.get("cookie", "").split(";"):
        name, _, value = part.strip().partition("=")
        if name == TOKEN_COOKIE:
            return value
    return None


def json_dumps(data: Any) -> str:
    return json.dumps(data, separators=(",", ":"), ensure_ascii=False)
