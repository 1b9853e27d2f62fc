"""Helpers shared by the emulator tests (a module with a unique name, so it never collides with
another folder's conftest)."""

from __future__ import annotations

import socket
import time

from emulator.framing import Frame, FrameError, ListenNodeFramer, encode
from emulator.settings import EmulatorSettings


class RobotSide(ListenNodeFramer):
    """Decodes robot -> client frames (CPERR included) for assertions."""

    def decode(self, buf: bytes):  # type: ignore[override]
        used, result = super().decode(buf)
        if isinstance(result, FrameError) and result.reason.startswith("unknown header") and result.raw[1:6] == b"CPERR":
            # The client-side view accepts the robot-only header.
            return used, Frame("CPERR", result.raw[result.raw.index(b",", 7) + 1:-6], result.raw)
        return used, result


class SyncClient:
    """A plain blocking socket client that reads whole frames."""

    def __init__(self, port: int, host: str = "127.0.0.1", timeout_s: float = 5.0) -> None:
        self.sock = socket.create_connection((host, port), timeout=timeout_s)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.buf = b""
        self.framer = RobotSide(EmulatorSettings(accept_one_digit_checksum=False))

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def send_frame(self, header: str, data: str) -> None:
        self.sock.sendall(encode(header, data))

    def read_frame(self) -> bytes:
        while True:
            used, result = self.framer.decode(self.buf)
            if used:
                self.buf = self.buf[used:]
                if result is not None:
                    return result.raw
                continue
            chunk = self.sock.recv(65536)
            if not chunk:
                raise ConnectionError("closed by robot")
            self.buf += chunk

    def request(self, header: str, data: str) -> bytes:
        self.send_frame(header, data)
        return self.read_frame()

    def close(self) -> None:
        self.sock.close()


def wait_until(predicate, timeout_s: float = 5.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.005)
    return False
