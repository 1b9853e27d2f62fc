"""The Schneider IF_RobotMotion-style library under test (st_src/schneider): the robot data, its link
FB and a list of up to eight commands a test issues in one PLC cycle (after the link call, as a
program calling the methods would), in lockstep with the emulated TM."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from robotlibs_helpers import PNP_TARGETS, REPO, Cell, load_library

SCHNEIDER = REPO / "st_src" / "schneider"
DEMO_FILES = ("Globals.st", "PnP_Example.st", "Configuration.st")

# ET_DiagExt / ET_Diag values (st_src/schneider/SE_Types.st; ET_DiagExt: the seed's values)
DIAG = {"Ok": 0, "ExecutionAborted": 1, "InputParameterInvalid": 2, "UnexpectedProgramBehavior": 3}
EXT = {"Ok": 0, "InterfaceInvalid": 3, "NoConnectedPathAvailable": 9, "CommandRefused": 10, "UnexpectedFeedback": 13,
       "PathPositionStartInvalid": 24, "PathPositionEndInvalid": 25, "StartSegmentIdRange": 27,
       "EndSegmentIdRange": 28, "StartSegmentIdNotFound": 31, "EndSegmentIdNotFound": 32, "NewConnectedPath": 43,
       "EndOffsetRange": 78, "PathPositionStartAlreadyPassed": 81, "StartOffsetRange": 116,
       "MaxAccelerationResultantRange": 170, "NoMoreTrackingEventsAvailable": 171,
       "ExternalPositionSourceConfigured": 205}
CS = {"Robot": 0, "User1": 1, "User2": 2, "User3": 3, "User4": 4, "LinearTracking1": 11, "LinearTracking2": 12}
COMPONENT = {"Space": 0, "Tracking": 1, "Axes": 2}
OPS = {"MoveL": 1, "MovePTP": 2, "ChangeCoordinateSystem2": 3, "SetCoordinateSystem": 4,
       "SetMaxAccelerationResultant": 5, "Execute": 6, "SetMaxVelocity": 7, "SetMaxAcceleration": 8, "MoveC": 9}

HARNESS = r"""
(* Test harness (tests/schneider). Not part of the library. *)
TYPE ST_HarnessCmd :
    STRUCT
        Op : INT;
        Id : UDINT;
        Id2 : UDINT;
        Offset : LREAL;
        Offset2 : LREAL;
        Target : ST_Vector3D;
        Circ : ST_Vector3D;
        Orientation : ST_Orientation;
        Zone : LREAL;
        Cs : ET_CoordinateSystem;
        Component : ET_RobotComponent;
        Value : LREAL;
        Flag : BOOL;
        Done : BOOL;
        Diag : ET_Diag;
        DiagExt : ET_DiagExt;
        Msg : STRING[80];
    END_STRUCT;
END_TYPE

PROGRAM S
VAR
    Robot : ST_TmRobot;
    Link : FB_TmRobotLink;
    Enable : BOOL;
    Cmds : ARRAY[0..7] OF ST_HarnessCmd;
    i : INT;
END_VAR
Link(xEnable := Enable, Robot := Robot);
FOR i := 0 TO 7 DO
    CASE Cmds[i].Op OF
        1: FC_TmMoveL(Robot := Robot, i_stTarget := Cmds[i].Target, i_stOrientation := Cmds[i].Orientation,
                      i_lrMaxZone := Cmds[i].Zone, i_udiSegmentId := Cmds[i].Id,
                      q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        2: FC_TmMovePTP(Robot := Robot, i_stTarget := Cmds[i].Target, i_stOrientation := Cmds[i].Orientation,
                        i_lrMaxZone := Cmds[i].Zone, i_udiSegmentId := Cmds[i].Id,
                        q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        3: FC_TmChangeCoordinateSystem2(Robot := Robot, i_udiStartSegmentId := Cmds[i].Id, i_lrStartOffset := Cmds[i].Offset,
                                        i_udiEndSegmentId := Cmds[i].Id2, i_lrEndOffset := Cmds[i].Offset2,
                                        q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        4: FC_TmSetCoordinateSystem(Robot := Robot, i_etCoordinateSystem := Cmds[i].Cs,
                                    q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        5: FC_TmSetMaxAccelerationResultant(Robot := Robot, i_etComponent := Cmds[i].Component, i_lrValue := Cmds[i].Value,
                                            q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        6: FC_TmExecute(Robot := Robot, i_xValue := Cmds[i].Flag,
                        q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        7: FC_TmSetDynamics(Robot := Robot, i_etComponent := Cmds[i].Component, i_xAcceleration := FALSE, i_lrValue := Cmds[i].Value,
                            q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        8: FC_TmSetDynamics(Robot := Robot, i_etComponent := Cmds[i].Component, i_xAcceleration := TRUE, i_lrValue := Cmds[i].Value,
                            q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
        9: FC_TmMoveC(Robot := Robot, i_stCircPoint := Cmds[i].Circ, i_stTarget := Cmds[i].Target,
                      i_stOrientation := Cmds[i].Orientation, i_lrMaxZone := Cmds[i].Zone, i_udiSegmentId := Cmds[i].Id,
                      q_etDiag => Cmds[i].Diag, q_etDiagExt => Cmds[i].DiagExt, q_sMsg => Cmds[i].Msg);
    END_CASE;
    IF Cmds[i].Op <> 0 THEN
        Cmds[i].Done := TRUE;
        Cmds[i].Op := 0;
    END_IF;
END_FOR;
END_PROGRAM
"""


@lru_cache(maxsize=None)
def schneider_project():
    return load_library(SCHNEIDER, HARNESS, DEMO_FILES)


def move(op: str, segment_id: int, target, zone: float = 0.0) -> dict[str, Any]:
    """A MoveL/MovePTP command to `target` (x, y, z, rx, ry, rz)."""
    x, y, z, rx, ry, rz = target
    return {"Op": OPS[op], "Id": segment_id, "Zone": zone, "Target.lrX": x, "Target.lrY": y, "Target.lrZ": z,
            "Orientation.lrRx": rx, "Orientation.lrRy": ry, "Orientation.lrRz": rz}


def move_c(segment_id: int, circ, target, zone: float = 0.0) -> dict[str, Any]:
    """A MoveC command through `circ` (x, y, z) to `target` (x, y, z, rx, ry, rz)."""
    command = move("MovePTP", segment_id, target, zone)
    command.update({"Op": OPS["MoveC"], "Circ.lrX": circ[0], "Circ.lrY": circ[1], "Circ.lrZ": circ[2]})
    return command


def change(start_id: int, start_offset: float, end_id: int, end_offset: float) -> dict[str, Any]:
    return {"Op": OPS["ChangeCoordinateSystem2"], "Id": start_id, "Offset": start_offset, "Id2": end_id,
            "Offset2": end_offset}


def set_cs(name: str) -> dict[str, Any]:
    return {"Op": OPS["SetCoordinateSystem"], "Cs": CS[name]}


def set_value(op: str, component: str, value: float) -> dict[str, Any]:
    return {"Op": OPS[op], "Component": COMPONENT[component], "Value": value}


def execute(flag: bool) -> dict[str, Any]:
    return {"Op": OPS["Execute"], "Flag": flag}


class SchneiderBench(Cell):
    def __init__(self, connect: bool = True, **cell) -> None:
        super().__init__(schneider_project(), **cell)
        if connect:
            self.set("S.Enable", True)
            self.until(lambda: self.get("S.Link.xConnected"), 2000, "TM link connected")

    def issue(self, *commands: dict[str, Any]) -> list[tuple[str, str, str]]:
        """Issue `commands` in one PLC cycle; their (ET_Diag, ET_DiagExt, q_sMsg) by name."""
        assert len(commands) <= 8
        for slot, command in enumerate(commands):
            self.set(f"S.Cmds[{slot}].Done", False)
            self.set_many(f"S.Cmds[{slot}]", command)
        self.scan(1)
        out = []
        for slot in range(len(commands)):
            assert self.get(f"S.Cmds[{slot}].Done")
            diag = {v: k for k, v in DIAG.items()}[self.get(f"S.Cmds[{slot}].Diag")]
            ext = {v: k for k, v in EXT.items()}[self.get(f"S.Cmds[{slot}].DiagExt")]
            out.append((diag, ext, self.get(f"S.Cmds[{slot}].Msg")))
        return out

    def path_diag(self) -> tuple[str, str, str]:
        return ({v: k for k, v in DIAG.items()}[self.get("S.Link.q_etDiag")],
                {v: k for k, v in EXT.items()}[self.get("S.Link.q_etDiagExt")], self.get("S.Link.q_sMsg"))

    def until_path_end(self, max_scans: int = 30000) -> int:
        return self.until(lambda: not self.get("S.Robot.xPathActive"), max_scans, "connected path finished")


PICK = [PNP_TARGETS[0], PNP_TARGETS[1], PNP_TARGETS[2]]
