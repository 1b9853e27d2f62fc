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
    """The in-process robot: the VM thread takes references to what the pose is made of (the
    active motions and the executor's time, the rest pose, the base frame: objects the emulator
    replaces rather than changes) and the state flags, about a µs; the server thread computes the
    pose from them. `Robot.snapshot()` in the VM thread would cost the scan about 0.2 ms (joint
    angles, Euler angles in deterministic math), the TCP alone of a moving robot 40 µs."""
    robot = transport.link.robot
    executor = robot.executor

    def capture() -> tuple:
        if executor.catch_up is not None:
            # quiet lockstep steps leave the robot's clocks behind the link's until something
            # reads them (emulator/transport.py, docs/lockstep_cost.md): bring them to this scan
            executor.catch_up()
        return (tuple(executor.active), executor.time_ns, executor.rest_tcp, robot.base, robot.state.value,
                robot.paused, executor.moving, robot.base_name)

    def finish(raw: tuple) -> dict[str, Any]:
        active, time_ns, rest_tcp, base, state, paused, moving, base_name = raw
        if not active:                  # as MotionExecutor.current_tcp(), at the captured time
            tcp = rest_tcp
        else:
            tcp = active[-1].tcp_at(time_ns).copy()
            for older in active[:-1]:   # what is left of blended motions
                tcp[:3, 3] += older.tcp_at(time_ns)[:3, 3] - older.end_tcp[:3, 3]
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
