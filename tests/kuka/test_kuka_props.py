"""Property test of the KUKA-style blocks (issue 31): KRC_MoveDirectAbsolute, KRC_MoveLinearAbsolute,
KRC_MoveAxisAbsolute, KRC_ReadActualPosition on KRC_TMAxisGroup, every input (E6POS/E6AXIS
members, COORDSYS, APO, velocity, acceleration, buffer mode, OriType, the group index) with the
types' extremes and ExecuteCmd toggled every scan, against the emulated TM in lockstep. No run may
fault the controller; every ErrorID is one the library documents (KRC_Checks.st header, 501, and
10000 + a CBT_Commands V2 code); Done and Error are never TRUE together."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, given, settings

from kuka_harness import KukaBench
from robotlibs_helpers import Probe, run_schedule, schedules
from robotlibs_helpers import V2_ERROR_IDS

KUKA_CODES = frozenset([501, 510, 511, 512, 520, 521, 522, 530, 531, 532, 540, 541, 542]) | {10000 + c for c in V2_ERROR_IDS}

E6POS = {**{k: "REAL" for k in ("X", "Y", "Z", "A", "B", "C", "E1", "E2", "E3", "E4", "E5", "E6")}, "S": "INT", "T": "INT"}
APO = {"PTP_MODE": "INT", "CP_MODE": "INT", "CPTP": "INT", "CDIS": "REAL", "CORI": "REAL", "CVEL": "INT"}
COORDSYS = {"Tool": "INT", "Base": "INT", "IPO_MODE": "INT"}
INPUTS = {"K.PtpVelocity": "INT", "K.PtpAcceleration": "INT", "K.PtpBufferMode": "INT", "K.PtpGroup": "INT",
          "K.LinExecute": "BOOL", "K.LinVelocity": "INT", "K.LinAcceleration": "INT", "K.LinOriType": "INT",
          "K.AxisExecute": "BOOL", "K.AxisVelocity": "INT", "K.Ptp2Execute": "BOOL", "K.Ptp2BufferMode": "INT",
          "K.GroupEnable": "BOOL"}
INPUTS |= {f"K.{fb}Position.{k}": v for fb in ("Ptp", "Lin") for k, v in E6POS.items()}
INPUTS |= {f"K.AxisPosition.{a}": "REAL" for a in ("A1", "A2", "A3", "A4", "A5", "A6", "E1", "E3", "E6")}
INPUTS |= {f"K.{fb}Apo.{k}": v for fb in ("Ptp", "Lin", "Axis") for k, v in APO.items()}
INPUTS |= {f"K.{fb}CoordSys.{k}": v for fb in ("Ptp", "Lin") for k, v in COORDSYS.items()}

PROBES = [Probe(fb, f"K.{fb}.Done", f"K.{fb}.Error", f"K.{fb}.ErrorID", KUKA_CODES)
          for fb in ("Ptp", "Ptp2", "Lin", "Axis")] + \
         [Probe(fb, None, f"K.{fb}.Error", f"K.{fb}.ErrorID", KUKA_CODES) for fb in ("Read", "ReadAxis")]

EXAMPLES = int(os.environ.get("STVM_PROPS_EXAMPLES", "12"))


def play(steps) -> int:
    b = KukaBench()
    try:
        b.pos("K.PtpPosition", 400.0, -150.0, 300.0, 90.0, 0.0, 180.0)
        b.pos("K.LinPosition", 400.0, -150.0, 250.0, 90.0, 0.0, 180.0)
        return run_schedule(b, steps, "K.PtpExecute", PROBES)
    finally:
        b.close()


@settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(schedules(INPUTS, max_steps=8))
def test_kuka_blocks_never_fault_and_answer_with_documented_codes(steps):
    play(steps)
