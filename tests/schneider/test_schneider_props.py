"""Property test of the IF_RobotMotion commands and FB_TmRobotLink (issue 31): hypothesis issues
up to four commands a PLC cycle -- every method, every input with the types' extremes (ids 0 and
the UDINT maximum, offsets, zones and dynamics NaN/inf/huge), the link's Enable toggled every scan
-- against the emulated TM in lockstep. No run may fault the controller; a command answering with
q_etDiag <> Ok, and the link's path diagnostic, carry one of the seed's ET_DiagExt values.
(The methods answer in the call and have no Done/Error pair.) Bounded here; the bench runs more."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, given, settings

from robotlibs_helpers import Probe, run_schedule, schedules
from schneider_harness import CS, COMPONENT, SchneiderBench

# seed (ChangeCoordinateSystem2's q_etDiagExt table): every value it documents
SEED_EXT = frozenset([0, 10, 205, 27, 28, 31, 32, 9, 116, 78, 81, 24, 25, 171, 170, 3, 13])

COMMAND_FIELDS = {"Op": tuple(range(10)), "Id": "UDINT", "Id2": "UDINT", "Offset": "LREAL", "Offset2": "LREAL",
                  "Zone": "LREAL", "Cs": tuple(CS.values()), "Component": tuple(COMPONENT.values()),
                  "Value": "LREAL", "Flag": "BOOL"}
COMMAND_FIELDS |= {f"{v}.lr{a}": "LREAL" for v in ("Target", "Circ") for a in "XYZ"}
COMMAND_FIELDS |= {f"Orientation.lr{a}": "LREAL" for a in ("Rx", "Ry", "Rz")}
INPUTS = {f"S.Cmds[{k}].{f}": kind for k in range(4) for f, kind in COMMAND_FIELDS.items()}
INPUTS |= {"S.Robot.Cfg.xExternalPositionSource": "BOOL", "S.Robot.Cfg.axUserFrameConfigured[1]": "BOOL",
           "S.Robot.Cfg.astUserFrame[1].lrX": "LREAL", "S.Robot.Cfg.astUserFrame[1].lrRz": "LREAL"}

PROBES = [Probe(f"command slot {k}", None, None, f"S.Cmds[{k}].DiagExt", SEED_EXT,
                error_when=lambda cell, k=k: cell.get(f"S.Cmds[{k}].Diag") != 0) for k in range(4)] + \
         [Probe("FB_TmRobotLink", None, None, "S.Link.q_etDiagExt", SEED_EXT,
                error_when=lambda cell: cell.get("S.Link.q_etDiag") != 0)]

EXAMPLES = int(os.environ.get("STVM_PROPS_EXAMPLES", "12"))


def play(steps) -> int:
    b = SchneiderBench()
    try:
        return run_schedule(b, steps, "S.Enable", PROBES)
    finally:
        b.close()


@settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(schedules(INPUTS, max_steps=10))
def test_motion_commands_never_fault_and_answer_with_seed_codes(steps):
    play(steps)
