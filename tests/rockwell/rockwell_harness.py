"""The Rockwell-style library under test: a device handler and two raM_Robot_Opr_LoadPath instances
on one path array, in lockstep with the emulated TM."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from robotlibs_helpers import PNP_TARGETS, ROCKWELL, Cell, load_library

DEMO_FILES = ("Globals.st", "PnP_Example.st", "Configuration.st")

HARNESS = r"""
(* Test harness (tests/rockwell). Not part of the library. *)
PROGRAM R
VAR
    Robot : raM_UDT_Robot_Dvc_DataHndl;
    Path : ARRAY[0..19] OF raM_UDT_Robot_Opr_PathPoint;
    Handler : raM_Robot_Dvc_TMHandler;
    HandlerEnable : BOOL;
    Stop : BOOL;
    Reset : BOOL;
    A : raM_Robot_Opr_LoadPath;
    AEnable : BOOL;
    AStart : DINT;
    ANumber : DINT := 1;
    ATracking0 : BOOL;
    ATracking1 : BOOL;
    B : raM_Robot_Opr_LoadPath;
    BEnable : BOOL;
    BStart : DINT;
    BNumber : DINT := 1;
END_VAR
Handler(Enable := HandlerEnable, Cmd_Stop := Stop, Cmd_Reset := Reset, Ref_Handle := Robot);
A(EnableIn := AEnable, Cfg_StartIndex := AStart, Cfg_NumberOfMoves := ANumber, Cfg_EnableTracking0 := ATracking0,
  Cfg_EnableTracking1 := ATracking1, Ref_Handle := Robot, Ref_Path := Path);
B(EnableIn := BEnable, Cfg_StartIndex := BStart, Cfg_NumberOfMoves := BNumber, Ref_Handle := Robot, Ref_Path := Path);
END_PROGRAM
"""

OUTPUTS = ("Sts_EO", "Sts_EN", "Sts_ER", "Sts_ERR", "Sts_EXERR", "Sts_MtdID", "Sts_IP", "Sts_DN", "Sts_AC", "Sts_PC",
           "Sts_ActivePathPoint", "Sts_PendingPathPoints")


@lru_cache(maxsize=None)
def rockwell_project():
    return load_library(ROCKWELL, HARNESS, DEMO_FILES)


def cartesian(target, move_id=0, speed=90.0, accel=450.0, interpolation=0, termination=0, tolerance=0.0,
              move_type=0, frame_type=2, ref_type=1, tool_id=0, ref_id=0, config=0) -> dict[str, Any]:
    """A Cartesian path point (flange in the robot frame, stop at the point unless told)."""
    x, y, z, rx, ry, rz = target
    p = {"MoveID": move_id, "MoveType": move_type, "TargetPointType": 1, "InterpolationType": interpolation,
         "Pose.X": x, "Pose.Y": y, "Pose.Z": z, "Pose.Rx": rx, "Pose.Ry": ry, "Pose.Rz": rz,
         "Pose.FrameType": frame_type, "Pose.ID": tool_id, "Pose.RefFrameType": ref_type, "Pose.RefFrameID": ref_id,
         "TerminationType": termination, "CommandTolerance": tolerance, "RobotConfiguration": config, "ProfileType": 2,
         "Speed": speed, "Acceleration": accel, "Deceleration": accel, "AccelerationJerk": 100.0,
         "DecelerationJerk": 100.0}
    if interpolation == 1:
        p.update({"OrientationSpeed": 90.0, "OrientationAcceleration": 450.0, "OrientationDeceleration": 450.0})
    return p


def joints(values, move_id=0, speed=90.0, accel=450.0, interpolation=0, move_type=0, termination=0, tolerance=0.0):
    p = cartesian((0, 0, 0, 0, 0, 0), move_id, speed, accel, interpolation, termination, tolerance, move_type)
    p["TargetPointType"] = 0
    p.update({f"Joints[{i}]": float(v) for i, v in enumerate(values)})
    return p


def pnp_point(i: int, move_id: int | None = None) -> dict[str, Any]:
    """The demo's path point i (st_src/rockwell/scenarios/pnp_demo.toml): thesis segment i."""
    speed = 90.0 if i in (0, 3) else 36.0
    return cartesian(PNP_TARGETS[i], move_id if move_id is not None else 101 + i, speed=speed, accel=speed * 5)


class RockwellBench(Cell):
    def __init__(self, enable_handler: bool = True, **cell) -> None:
        super().__init__(rockwell_project(), **cell)
        if enable_handler:
            self.set("R.HandlerEnable", True)
            self.until(lambda: self.get("R.Robot.Sts.Available"), 2000, "handler available")

    def path(self, points: list[dict], start: int = 0) -> None:
        for i, point in enumerate(points):
            self.set_many(f"R.Path[{start + i}]", point)

    def outputs(self, inst: str = "A") -> dict[str, Any]:
        return {k: self.get(f"R.{inst}.{k}") for k in OUTPUTS}

    def run(self, inst: str, start: int, number: int) -> None:
        self.set(f"R.{inst}Start", start)
        self.set(f"R.{inst}Number", number)
        self.set(f"R.{inst}Enable", True)
