"""One controller commanding four robots at once (the thesis's multi-robot estimate, l.4052: "as many
robots as the maximum number of TCP connections"): one VM, four CBT_Connect and four PnP_Sequence
instances of the V2 library, four emulated robots in lockstep on the same clock, each reached at its
own address. Each robot runs the demo's Pick-and-Place cycle, shifted sideways by 100 mm per robot."""

from __future__ import annotations

import pytest

from robotlibs_helpers import PNP_ACCEL_MS, PNP_SPEEDS, PNP_TARGETS, V2, Cell, load_library, motion_commands, script_of
from v2_harness import DEMO_FILES

ROBOTS = 4
PORTS = [5891 + i for i in range(ROBOTS)]

HARNESS = r"""
(* Test harness (tests/cbt_v2): one controller, four robots. Not part of the library. *)
TYPE Cell4_Path : STRUCT Segments : ARRAY[0..5] OF CBT_Commands_Lib_V2\stCBT_MovAbsParam; END_STRUCT; END_TYPE

PROGRAM Cell4
VAR
    Execute : BOOL;
    Cobots : ARRAY[1..4] OF CBT_Commands_Lib_V2\stCBT_Connection;
    Connects : ARRAY[1..4] OF CBT_Commands_Lib_V2\CBT_Connect;
    Sequences : ARRAY[1..4] OF CBT_Commands_Lib_V2\PnP_Sequence;
    Paths : ARRAY[1..4] OF Cell4_Path;
    Run : ARRAY[1..4] OF BOOL;
    i : INT;
END_VAR
FOR i := 1 TO 4 DO
    Connects[i](CBT := Cobots[i], Execute := Execute, IPAddress := '127.0.0.1', IPPort := INT_TO_UINT(5890 + i));
    Run[i] := Execute AND (Run[i] OR Cobots[i].Connected) AND Sequences[i].Cycles < 1;   (* one cycle each *)
    Sequences[i](CBT := Cobots[i], Segments := Paths[i].Segments, Execute := Run[i]);
END_FOR;
END_PROGRAM
"""


def offset_target(target, robot: int):
    x, y, z, rx, ry, rz = target
    return (x, y + 50.0 * robot - 75.0, z, rx, ry, rz)


@pytest.fixture(scope="module")
def cell_run():
    cell = Cell(load_library(V2, HARNESS, DEMO_FILES), robots=[("127.0.0.1", p) for p in PORTS])
    for r in range(ROBOTS):
        for i, target in enumerate(PNP_TARGETS):
            prefix = f"Cell4.Paths[{r + 1}].Segments[{i}]"
            cell.set_many(prefix, {"MovementCommand": "PTP", "DataFormat": "CPP_Abs", "Speed": PNP_SPEEDS[i],
                                   "AccelTime": PNP_ACCEL_MS[i], "PrecisePositioning": True})
            cell.set_many(f"{prefix}.TargetPosition", dict(zip(("X", "Y", "Z", "RX", "RY", "RZ"), offset_target(target, r))))
    cell.set("Cell4.Execute", True)
    cell.until(lambda: all(cell.get(f"Cell4.Sequences[{r + 1}].Cycles") >= 1 for r in range(ROBOTS)), 40000,
               "one cycle on every robot")
    yield cell
    cell.close()


def test_every_robot_ran_the_cycle(cell_run):
    cell = cell_run
    for r in range(ROBOTS):
        assert not cell.get(f"Cell4.Sequences[{r + 1}].Error")
        assert cell.rx(0) == []                                   # nothing reached the default robot
        sent = cell.rx(r + 1)
        moves = motion_commands(sent)
        for (name, args), target in zip(moves, PNP_TARGETS, strict=True):
            assert name == "PTP" and args[0] == "CPP"
            assert args[1:7] == pytest.approx(list(offset_target(target, r)))
        # CommandIDs per connection: every robot sees 1, 2, ... from its own controller FBs
        ids = [int(script_of(f)[0]) for f in sent if f.startswith(b"$TMSCT")]
        assert ids == list(range(1, 9))                           # 6 motions + 2 gripper outputs
        gripper = [script_of(f)[1].split("\r\n")[0] for f in sent if b"IO[" in f]
        assert gripper == ['IO["ControlBox"].DO[0]=1', 'IO["ControlBox"].DO[0]=0']


def test_each_robot_ends_its_cycle_at_the_last_target(cell_run):
    cell = cell_run
    for r in range(ROBOTS):
        tags = [f for f in cell.transport.frames if f.robot == r + 1 and f.direction == "tx" and b",01," in f.data]
        assert len(tags) == 8
        assert cell.pose(r + 1)[:3] == pytest.approx(list(offset_target(PNP_TARGETS[5], r))[:3], abs=0.02)
        assert cell.robot(r + 1).snapshot()["do"]["ControlBox"][0] == 0     # released at the place point


def test_the_robots_moved_at_the_same_time(cell_run):
    cell = cell_run
    starts = []
    for r in range(ROBOTS):
        first_motion = next(f for f in cell.transport.frames
                            if f.robot == r + 1 and f.direction == "rx" and b"PTP(" in f.data)
        starts.append(first_motion.t_ns)
    assert max(starts) - min(starts) < 5_000_000                  # within 5 ms of each other
