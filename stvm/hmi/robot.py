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

from emulator import detmath as dm
from emulator.motion import matrix_to_pose


@dataclass(frozen=True)
class PoseSource:
    read: Callable[[], Any]              # a robot snapshot (emulator.Robot.snapshot() keys), or
                                         # what `finish` turns into one
    in_vm_thread: bool                   # must be read by the VM thread, between scans
    name: str = "emulator"
    finish: Callable[[Any], dict[str, Any]] | None = None   # server thread: `read()`'s data → snapshot


def from_lockstep(transport) -> PoseSource:
    """The in-process robot: the VM thread copies the TCP and base frames and the state flags
    (a few µs), the server thread turns them into the pose. `Robot.snapshot()` there would cost
    the scan about 0.2 ms (the joint angles, the pose's Euler angles in deterministic math)."""
    robot = transport.link.robot

    def capture() -> tuple:
        return (robot.executor.current_tcp().copy(), robot.base.copy(), robot.state.value, robot.paused,
                robot.executor.moving, robot.base_name)

    def finish(raw: tuple) -> dict[str, Any]:
        tcp, base, state, paused, moving, base_name = raw
        pose = matrix_to_pose(dm.matmul(dm.rigid_inverse(base), tcp))   # as Robot.snapshot()'s pose
        return {"pose": [round(float(v), 3) for v in pose], "state": state, "paused": paused,
                "moving": moving, "base": base_name}
    return PoseSource(capture, True, "lockstep emulator", finish)


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
