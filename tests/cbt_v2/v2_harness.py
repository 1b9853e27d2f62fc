"""The CBT_Commands V2 library under test: a harness program with one instance of every V2 FB on one
connection (as the thesis's ladder rungs, section 5.4), loaded once per session, and helpers to
build the scripts the FBs must send (from the TM spec, tm_protocol.md 7)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from robotlibs_helpers import V2, Cell, load_library

V2_NS = "CBT_Commands_Lib_V2"
DEMO_FILES = ("Globals.st", "PnP_Example.st", "Configuration.st")

HARNESS = r"""
(* Test harness (tests/cbt_v2): every V2 FB on one connection. Not part of the library. *)
PROGRAM T
VAR
    Cobot : CBT_Commands_Lib_V2\stCBT_Connection;
    Conn : CBT_Commands_Lib_V2\CBT_Connect;
    ConnExecute : BOOL;
    IP : STRING[50] := '127.0.0.1';
    Port : UINT := 5890;
    TimeOut : UINT := 10;
    Decimals : USINT := 2;
    Abs : CBT_Commands_Lib_V2\CBT_MoveAbsolute;
    AbsExecute : BOOL;
    AbsParam : CBT_Commands_Lib_V2\stCBT_MovAbsParam;
    Rel : CBT_Commands_Lib_V2\CBT_MoveRelative;
    RelExecute : BOOL;
    RelParam : CBT_Commands_Lib_V2\stCBT_MovRelParam;
    Circ : CBT_Commands_Lib_V2\CBT_MoveCircle;
    CircExecute : BOOL;
    CircParam : CBT_Commands_Lib_V2\stCBT_MovCircleParam;
    Base : CBT_Commands_Lib_V2\CBT_ChangeBase;
    BaseExecute : BOOL;
    BaseParam : CBT_Commands_Lib_V2\stCBT_BaseParam;
    Tcp : CBT_Commands_Lib_V2\CBT_ChangeTCP;
    TcpExecute : BOOL;
    TcpParam : CBT_Commands_Lib_V2\stCBT_TCParam;
    Prg : CBT_Commands_Lib_V2\CBT_ProgramControl;
    PrgExecute : BOOL;
    PrgParam : CBT_Commands_Lib_V2\stCBT_PrgControl;
    Stop : CBT_Commands_Lib_V2\CBT_StopAndClear;
    StopExecute : BOOL;
    StopPriority : BOOL := TRUE;
    DOut : CBT_Commands_Lib_V2\CBT_SetDigitalOutput;
    DOutExecute : BOOL;
    DOutModule : CBT_Commands_Lib_V2\eCBT_IOModule;
    DOutChannel : USINT;
    DOutValue : BOOL;
    DOutInstant : BOOL;
    TagQuery : CBT_Commands_Lib_V2\CBT_QueueTagStatus;
    TagExecute : BOOL;
    TagNumber : UINT := 1;
    ExitNode : CBT_Commands_Lib_V2\CBT_ExitNode;
    ExitExecute : BOOL;
END_VAR
Conn(CBT := Cobot, Execute := ConnExecute, IPAddress := IP, IPPort := Port, Time_Out := TimeOut, Decimals := Decimals);
Abs(CBT := Cobot, Execute := AbsExecute, Parameters := AbsParam);
Rel(CBT := Cobot, Execute := RelExecute, Parameters := RelParam);
Circ(CBT := Cobot, Execute := CircExecute, Parameters := CircParam);
Base(CBT := Cobot, Execute := BaseExecute, Parameters := BaseParam);
Tcp(CBT := Cobot, Execute := TcpExecute, Parameters := TcpParam);
Prg(CBT := Cobot, Execute := PrgExecute, Parameters := PrgParam);
Stop(CBT := Cobot, Execute := StopExecute, Priority := StopPriority);
DOut(CBT := Cobot, Execute := DOutExecute, Module := DOutModule, Channel := DOutChannel, Value := DOutValue, Instant := DOutInstant);
TagQuery(CBT := Cobot, Execute := TagExecute, Tag := TagNumber);
ExitNode(CBT := Cobot, Execute := ExitExecute);
END_PROGRAM
"""

#: FB instance -> its Execute and Parameters variables in T (None: inputs set one by one)
PINS = {"Abs": ("AbsExecute", "AbsParam"), "Rel": ("RelExecute", "RelParam"), "Circ": ("CircExecute", "CircParam"),
        "Base": ("BaseExecute", "BaseParam"), "Tcp": ("TcpExecute", "TcpParam"), "Prg": ("PrgExecute", "PrgParam"),
        "Stop": ("StopExecute", None), "DOut": ("DOutExecute", None), "TagQuery": ("TagExecute", None),
        "ExitNode": ("ExitExecute", None)}


@lru_cache(maxsize=None)
def v2_project():
    return load_library(V2, HARNESS, DEMO_FILES)


def fb_watch(*instances: str) -> dict[str, str]:
    watch = {"Connected": "T.Cobot.Connected", "WaitingReturn": "T.Cobot.WaitingReturn",
             "InNode": "T.Cobot.InListenNode"}
    for inst in instances:
        for pin in ("Busy", "Done", "Error", "ErrorID"):
            watch[f"{inst}.{pin}"] = f"T.{inst}.{pin}"
    return watch


class V2Bench(Cell):
    """The harness in lockstep with the emulator, connected (unless connect=False)."""

    def __init__(self, *instances: str, connect: bool = True, **cell) -> None:
        super().__init__(v2_project(), **cell)
        self.watch = fb_watch("Conn", *instances)
        if connect:
            self.connect()

    def connect(self) -> None:
        self.set("T.ConnExecute", True)
        self.until(lambda: self.get("T.Cobot.Connected") or self.get("T.Conn.Error"), 2000, "connected")
        assert self.get("T.Cobot.Connected"), f"connect failed: {self.get('T.Conn.ErrorID'):#x}"

    def start(self, inst: str, params: dict[str, Any] | None = None, **inputs: Any) -> int:
        """Set the FB's parameters / inputs and raise Execute; returns the scan that sees it."""
        execute, param = PINS[inst]
        if params:
            self.set_many(f"T.{param}", params)
        for key, value in inputs.items():
            self.set(f"T.{key}", value)
        self.set(f"T.{execute}", True)
        return self.vm.scan_count

    def stop(self, inst: str) -> None:
        self.set(f"T.{PINS[inst][0]}", False)

    def finish(self, inst: str, max_scans: int = 30000) -> dict:
        """Scan until the FB reports Done or Error; returns its outputs then."""
        self.until(lambda: self.get(f"T.{inst}.Done") or self.get(f"T.{inst}.Error"), max_scans, f"{inst} end")
        return {pin: self.get(f"T.{inst}.{pin}") for pin in ("Done", "Error", "ErrorID", "ErrorDescrip")}


def move_params(movement="PTP", fmt="CPP_Abs", target=(417.5, -122.3, 350.0, 180.0, 0.0, 90.0), speed=50,
                accel=200, blend=None, precise=True, pose=None, exit_node=False) -> dict:
    p = {"MovementCommand": movement, "DataFormat": fmt, "Speed": speed, "AccelTime": accel,
         "BlendingEnable": blend is not None, "BlendingValue": blend or 0, "PrecisePositioning": precise,
         "RobotPoseEnable": pose is not None, "ExitNode": exit_node}
    p.update({f"TargetPosition.{k}": v for k, v in zip(("X", "Y", "Z", "RX", "RY", "RZ"), target)})
    if pose is not None:
        p.update({"RobotPose.Pose1": pose[0], "RobotPose.Pose2": pose[1], "RobotPose.Pose3": pose[2]})
    return p


def number(value: float, decimals: int = 2) -> str:
    """The V2 coordinate text: fixed decimals, no '+', zero never negative (CBT_FormatNumber)."""
    text = f"{value:.{decimals}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text


def pose_text(values, decimals: int = 2) -> str:
    return ",".join(number(v, decimals) for v in values)
