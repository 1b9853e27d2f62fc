"""The KUKA mxAutomation-style library under test: axis group 1 on the emulated TM, one instance of
each motion and read FB, and the pose conversion functions behind plain inputs/outputs."""

from __future__ import annotations

from functools import lru_cache

from robotlibs_helpers import KUKA, Cell, load_library

DEMO_FILES = ("Globals.st", "PnP_Example.st", "Configuration.st")

HARNESS = r"""
(* Test harness (tests/kuka). Not part of the library. *)
PROGRAM K
VAR
    Group : KRC_TMAxisGroup;
    GroupEnable : BOOL;
    GroupIdx : INT := 1;
    Ptp : KRC_MoveDirectAbsolute;
    PtpExecute : BOOL;
    PtpPosition : E6POS;
    PtpVelocity : INT := 50;
    PtpAcceleration : INT := 50;
    PtpCoordSys : COORDSYS;
    PtpApo : APO;
    PtpBufferMode : INT := 2;
    PtpGroup : INT := 1;
    Ptp2 : KRC_MoveDirectAbsolute;
    Ptp2Execute : BOOL;
    Ptp2Position : E6POS;
    Ptp2BufferMode : INT := 2;
    Lin : KRC_MoveLinearAbsolute;
    LinExecute : BOOL;
    LinPosition : E6POS;
    LinVelocity : INT := 20;
    LinAcceleration : INT := 50;
    LinCoordSys : COORDSYS;
    LinApo : APO;
    LinOriType : INT;
    Axis : KRC_MoveAxisAbsolute;
    AxisExecute : BOOL;
    AxisPosition : E6AXIS;
    AxisVelocity : INT := 50;
    AxisApo : APO;
    Read : KRC_ReadActualPosition;
    ReadAxis : KRC_ReadActualAxisPosition;
    (* the conversions, for the numeric proof *)
    InA, InB, InC : REAL;
    OutTM : CBT_Commands_Lib_V2\stCBT_Transformation;
    InTM : CBT_Commands_Lib_V2\stCBT_Transformation;
    OutE6 : E6POS;
END_VAR
Group(AxisGroupIdx := GroupIdx, Enable := GroupEnable, IPAddress := '127.0.0.1', Port := 5890);
Ptp(AxisGroupIdx := PtpGroup, ExecuteCmd := PtpExecute, Position := PtpPosition, Velocity := PtpVelocity,
    Acceleration := PtpAcceleration, CoordinateSystem := PtpCoordSys, Approximate := PtpApo, BufferMode := PtpBufferMode);
Ptp2(AxisGroupIdx := 1, ExecuteCmd := Ptp2Execute, Position := Ptp2Position, Velocity := 50, Acceleration := 50,
     BufferMode := Ptp2BufferMode);
Lin(AxisGroupIdx := 1, ExecuteCmd := LinExecute, Position := LinPosition, Velocity := LinVelocity,
    Acceleration := LinAcceleration, CoordinateSystem := LinCoordSys, OriType := LinOriType, Approximate := LinApo);
Axis(AxisGroupIdx := 1, ExecuteCmd := AxisExecute, AxisPosition := AxisPosition, Velocity := AxisVelocity,
     Acceleration := 50, Approximate := AxisApo);
Read(AxisGroupIdx := 1);
ReadAxis(AxisGroupIdx := 1);
OutTM := KRC_ToTM(0.0, 0.0, 0.0, InA, InB, InC);
OutE6 := KRC_TMToE6POS(InTM);
END_PROGRAM
"""


@lru_cache(maxsize=None)
def kuka_project():
    return load_library(KUKA, HARNESS, DEMO_FILES)


class KukaBench(Cell):
    def __init__(self, connect: bool = True, **cell) -> None:
        super().__init__(kuka_project(), **cell)
        if connect:
            self.set("K.GroupEnable", True)
            self.until(lambda: self.get("K.Group.Valid"), 2000, "axis group valid")

    def pos(self, prefix: str, x, y, z, a, b, c) -> None:
        self.set_many(prefix, {"X": x, "Y": y, "Z": z, "A": a, "B": b, "C": c})

    def finish(self, inst: str, max_scans: int = 30000) -> dict:
        self.until(lambda: any(self.get(f"K.{inst}.{o}") for o in ("Done", "Error", "Aborted")), max_scans, f"{inst} end")
        return {o: self.get(f"K.{inst}.{o}") for o in ("Busy", "Active", "Done", "Aborted", "Error", "ErrorID")}
