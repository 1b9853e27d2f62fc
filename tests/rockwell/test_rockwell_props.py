"""Property test of raM_Robot_Opr_LoadPath and its device handler (issue 31): hypothesis drives every
input of two instances on one handler -- the configuration, tracking, every member of the path
points, the handler's Enable/Stop/Reset -- with the types' extremes, inputs changed while In
Process and EnableIn toggled every scan, against the emulated TM in lockstep. No run may fault the
controller, every Sts_ERR is one of the seed's codes (seed 2.3), Sts_PC and Sts_ER (and Sts_DN and
Sts_ER) are never TRUE together. Bounded and derandomized here; bench/bench_robotlibs_props.py runs more."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, given, settings

from robotlibs_helpers import Probe, run_schedule, schedules
from rockwell_harness import RockwellBench, pnp_point

# seed 2.3 (Sts_ERR): every code the instruction documents
SEED_CODES = frozenset([1000, 1001, 1002, 1003, 1005, 1006, 1007, 1010, 1012, 1013, 1014, 1015, 1017, 1018, 1019,
                        1020, 1021, 1022, 1023, 1024, 1025, 1026, 1027, 1028, 1029, 1030, 1031, 1032, 1033, 1034,
                        1035, 1036, 1037, 1038, 1039, 1040, 1041, 1042, 1043, 1044, 1045, 1046, 1047, 1048, 1049,
                        1050, 1051, 1052, 1053, 1055, 1056, 1057, 1058, 1059, 1060, 1061])

POINT_FIELDS = {"MoveID": "DINT", "MoveType": "DINT", "TargetPointType": "SINT", "InterpolationType": "SINT",
                "Pose.X": "REAL", "Pose.Y": "REAL", "Pose.Z": "REAL", "Pose.Rx": "REAL", "Pose.Ry": "REAL",
                "Pose.Rz": "REAL", "Pose.FrameType": "DINT", "Pose.ID": "DINT", "Pose.RefFrameType": "DINT",
                "Pose.RefFrameID": "DINT", "TerminationType": "DINT", "CommandTolerance": "REAL",
                "RobotConfiguration": "SINT", "ProfileType": "SINT", "Speed": "REAL", "Acceleration": "REAL",
                "Deceleration": "REAL", "AccelerationJerk": "REAL", "DecelerationJerk": "REAL",
                "OrientationSpeed": "REAL", "OrientationAcceleration": "REAL", "OrientationDeceleration": "REAL"}
INPUTS = {"R.AStart": "DINT", "R.ANumber": "DINT", "R.ATracking0": "BOOL", "R.ATracking1": "BOOL",
          "R.BEnable": "BOOL", "R.BStart": "DINT", "R.BNumber": "DINT", "R.Stop": "BOOL", "R.Reset": "BOOL",
          "R.HandlerEnable": "BOOL",
          "R.Robot.Cfg.StatusPollPeriod": (0, 1_000_000, 20_000_000, 200_000_000)}     # TIME in ns: off, 1 ms .. 200 ms
# the points the demo path uses (0..5) and the last one, every member
INPUTS |= {f"R.Path[{i}].{field}": kind for i in (0, 1, 2, 5, 19) for field, kind in POINT_FIELDS.items()}
INPUTS |= {f"R.Path[1].Joints[{j}]": "REAL" for j in range(9)}

PROBES = [Probe(f"LoadPath {inst}", f"R.{inst}.Sts_PC", f"R.{inst}.Sts_ER", f"R.{inst}.Sts_ERR", SEED_CODES)
          for inst in "AB"] + \
         [Probe(f"LoadPath {inst} DN", f"R.{inst}.Sts_DN", f"R.{inst}.Sts_ER", f"R.{inst}.Sts_ERR", SEED_CODES)
          for inst in "AB"]

EXAMPLES = int(os.environ.get("STVM_PROPS_EXAMPLES", "12"))


def play(steps) -> int:
    b = RockwellBench()
    try:
        b.path([pnp_point(i) for i in range(6)])
        b.set("R.ANumber", 3)
        b.set("R.BStart", 3)
        b.set("R.BNumber", 3)
        return run_schedule(b, steps, "R.AEnable", PROBES)
    finally:
        b.close()


@settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
          suppress_health_check=list(HealthCheck))
@given(schedules(INPUTS))
def test_load_path_never_faults_and_answers_with_seed_codes(steps):
    play(steps)
