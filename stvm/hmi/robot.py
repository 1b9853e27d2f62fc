"""Where the robot view's TCP pose comes from: the emulator the run owns.

* Lockstep (`stvm debug --robot lockstep`, tests): the in-process robot advances in the VM
  thread, so it is read there, right after the variables of the same snapshot (one instant).
* The bundled TCP emulator (`stvm run` demo, `stvm debug --robot emulator`): its server keeps
  its own lock, so it is read from the web server's thread and costs the scan nothing.
* A real robot (`--robot HOST:PORT`): stvm does not know its pose; the view says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable


@dataclass(frozen=True)
class PoseSource:
    read: Callable[[], dict[str, Any]]   # a robot snapshot (emulator.Robot.snapshot() keys)
    in_vm_thread: bool                   # must be read by the VM thread, between scans
    name: str = "emulator"


def from_lockstep(transport) -> PoseSource:
    return PoseSource(transport.link.robot.snapshot, True, "lockstep emulator")


def from_tcp_server(server) -> PoseSource:
    """The bundled TCP emulator's robot, its pose interpolated to the moment of reading (the
    snapshot's own pose only moves on events, so sub-second moves would jump and an arc would be
    drawn as a chord)."""
    def read() -> dict[str, Any]:
        snap = server.snapshot()
        robot = getattr(getattr(server, "core", None), "robot", None)
        if robot is not None and hasattr(robot, "pose_at"):
            with server.lock:
                snap["pose"] = robot.pose_at(server.now_ns())
        return snap
    return PoseSource(read, False, f"emulator on port {server.port}")


def robot_state(snapshot: dict[str, Any] | None) -> dict[str, Any] | None:
    """The part of a robot snapshot the robot view draws (plain JSON)."""
    if not snapshot or snapshot.get("pose") is None:
        return None
    pose = [round(float(v), 2) for v in snapshot["pose"][:6]]
    return {"pose": pose, "state": str(snapshot.get("state", "?")), "moving": bool(snapshot.get("moving")),
            "paused": bool(snapshot.get("paused")), "base": snapshot.get("base")}
