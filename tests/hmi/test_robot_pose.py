"""The robot view's pose between events (issue 32 item 3): `emulator.Robot.pose_at(t)` is the
pose the robot will report at `t`, read without advancing it, so a live view at 20 Hz draws a
move (and a circle's real arc) instead of jumping from event to event."""

from __future__ import annotations

import stvm
from emulator import DEFAULT_SETTINGS
from hmi_helpers import THESIS
from stvm.semantics.literals import literal_value
from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, LockstepTransport


def connected_cell():
    """The thesis project in lockstep with the emulator at a quarter of its speed, connected."""
    transport = LockstepTransport(latency_scans=1, settings=DEFAULT_SETTINGS.with_(time_scale=0.25))
    vm = stvm.load([str(THESIS)]).start(scan="1ms", transport=transport)
    transport.attach(vm)
    vm["Connect_AddressIP"], vm["Connect_Dest_PortIP"], vm["Connect_Time_Out"] = LOCKSTEP_HOST, LOCKSTEP_PORT, 100
    vm["Connect_Execute"] = True
    vm.run(cycles=3000)
    return vm, transport


def start_ptp_move(vm) -> None:
    """CBT_MoveAbsolute to a point 350 mm out and up, PTP at 50 %."""
    for path, value in {"MoveAbs_Param.CommandID": 2, "MoveAbs_Param.MovementCommand": "PTP",
                        "MoveAbs_Param.DataFormat": "CPP_Abs", "MoveAbs_Param.Speed": 50,
                        "MoveAbs_Param.AccelTime": 200, "MoveAbs_Param.TargetPosition.X": 350.0,
                        "MoveAbs_Param.TargetPosition.Z": 350.0, "MoveAbs_Param.TargetPosition.RX": 180.0,
                        "MoveAbs_Param.TargetPosition.RZ": 90.0, "MoveAbs_Param.RobotPose.Pose2": 2,
                        "MoveAbs_Param.RobotPose.Pose3": 4}.items():
        vm[path] = literal_value(value, vm.accessor(path).type) if isinstance(value, str) else value
    vm["MoveAbs_Execute"] = True


def test_pose_at_a_later_time_is_the_pose_the_robot_then_reports():
    vm, transport = connected_cell()
    robot = transport.link.robot
    assert vm["Cobot.Connected"]
    assert robot.pose_at(robot.now_ns) == robot.snapshot()["pose"]      # at rest: the same pose
    start_ptp_move(vm)
    moving = []
    for _ in range(400):
        vm.run(cycles=20)
        if robot.snapshot()["moving"]:
            moving.append(robot.now_ns)
            break
    assert moving, (vm["MoveAbs_Error"], vm["MoveAbs_ErrorDescrip"], vm["MoveAbs_Busy"])
    start = robot.now_ns
    predicted = [robot.pose_at(start + k * 50_000_000) for k in range(1, 6)]
    reported = []
    for _ in range(5):
        vm.run(cycles=50)   # 50 ms of VM time, the robot advanced in lockstep
        reported.append(robot.snapshot()["pose"])
    assert predicted[0] != robot.pose_at(start)                        # it moves between events
    for guess, seen in zip(predicted, reported):
        assert max(abs(a - b) for a, b in zip(guess, seen)) < 1.0, (guess, seen)
    vm.close()


def test_the_lockstep_pose_source_reads_in_the_vm_thread_what_the_robot_reports():
    """`from_lockstep`: the VM thread only takes references (`read`), the server thread computes
    the pose (`finish`); the result is `Robot.snapshot()`'s, at rest and along a move."""
    from stvm.hmi.robot import from_lockstep
    vm, transport = connected_cell()
    robot = transport.link.robot
    source = from_lockstep(transport)
    assert source.in_vm_thread and source.finish is not None
    keys = ("pose", "state", "paused", "moving", "base")

    def same() -> dict:
        raw = source.read()
        expected = {k: robot.snapshot()[k] for k in keys}
        vm.run(cycles=7)            # the robot moves on before the server thread converts
        assert source.finish(raw) == expected
        return expected
    assert not same()["moving"]
    start_ptp_move(vm)
    seen_moving = 0
    for _ in range(300):
        seen_moving += same()["moving"]
    assert seen_moving >= 5         # poses along the move compared too
    vm.close()
