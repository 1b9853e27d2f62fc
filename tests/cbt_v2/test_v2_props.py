"""Property test of the CBT_Commands V2 FBs (issue 31): CBT_MoveAbsolute, CBT_MoveRelative,
CBT_MoveCircle, CBT_ChangeBase, CBT_ChangeTCP, CBT_SetDigitalOutput, CBT_QueueTagStatus,
CBT_StopAndClear and CBT_Connect on one connection, every parameter with the types' extremes,
Execute toggled every scan, inputs changed while Busy, against the emulated TM in lockstep. No run
may fault the controller; every ErrorID is one the thesis or V2 documents; Done and Error are never
TRUE together. Bounded here; bench/bench_robotlibs_props.py runs more."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, given, settings

from robotlibs_helpers import V2_ERROR_IDS, Probe, run_schedule, schedules
from v2_harness import V2Bench, move_params

POSE = {k: "REAL" for k in ("X", "Y", "Z", "RX", "RY", "RZ")}
MOVE = {"Speed": "UINT", "AccelTime": "UINT", "BlendingEnable": "BOOL", "BlendingValue": "UINT",
        "PrecisePositioning": "BOOL", "ExitNode": "BOOL"}
INPUTS = {f"T.AbsParam.{k}": v for k, v in MOVE.items()} | {f"T.AbsParam.TargetPosition.{k}": v for k, v in POSE.items()}
INPUTS |= {f"T.RelParam.{k}": v for k, v in MOVE.items()} | {f"T.RelParam.TargetPosition.{k}": v for k, v in POSE.items()}
INPUTS |= {f"T.CircParam.{k}": v for k, v in MOVE.items() }
INPUTS |= {"T.CircParam.ArcAngle": "UINT"} | {f"T.CircParam.{p}.{k}": v for p in ("ArcPoint", "EndPoint")
                                               for k, v in POSE.items()}
INPUTS |= {f"T.BaseParam.Transformation.{k}": v for k, v in POSE.items()} | {f"T.TcpParam.TCPOffset.{k}": v for k, v in POSE.items()} | {"T.TcpParam.Weight": "REAL"}
INPUTS |= {"T.RelExecute": "BOOL", "T.CircExecute": "BOOL", "T.BaseExecute": "BOOL", "T.TcpExecute": "BOOL",
           "T.StopExecute": "BOOL", "T.StopPriority": "BOOL", "T.DOutExecute": "BOOL", "T.DOutChannel": "USINT",
           "T.DOutValue": "BOOL", "T.DOutInstant": "BOOL", "T.TagExecute": "BOOL", "T.TagNumber": "UINT",
           "T.Decimals": "USINT", "T.ConnExecute": "BOOL", "T.TimeOut": "UINT"}

PROBES = [Probe(fb, f"T.{fb}.Done", f"T.{fb}.Error", f"T.{fb}.ErrorID", V2_ERROR_IDS)
          for fb in ("Conn", "Abs", "Rel", "Circ", "Base", "Tcp", "Stop", "DOut", "TagQuery")]

EXAMPLES = int(os.environ.get("STVM_PROPS_EXAMPLES", "12"))


def play(steps) -> int:
    b = V2Bench()
    try:
        b.set_many("T.AbsParam", move_params())
        b.set_many("T.RelParam", {"Speed": 50, "AccelTime": 200, "TargetPosition.Z": -20.0})
        return run_schedule(b, steps, "T.AbsExecute", PROBES)
    finally:
        b.close()


@settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(schedules(INPUTS, max_steps=8))
def test_v2_fbs_never_fault_and_answer_with_documented_codes(steps):
    play(steps)
