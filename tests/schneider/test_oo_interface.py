"""The object-oriented form of the Schneider library (st_src/schneider/IF_RobotMotion.st,
FB_TmRobot.st, the demo st_src/schneider/oo): FB_TmRobot IMPLEMENTS IF_RobotMotion, its methods
called through an interface variable, must behave exactly as the functions tests/schneider checks
(test_robot_motion.py): the same diagnostics, the same TM frames for the PnP cycle.

They use METHOD / INTERFACE / IMPLEMENTS / interface variables / `=>` on method calls (issue 11)."""

from __future__ import annotations

from functools import lru_cache

import stvm
from robotlibs_helpers import REPO, Cell, load_library, manifest_files, motion_commands, script_of

OO_FOLDER = REPO / "st_src" / "schneider" / "oo"


HARNESS = r"""
(* Test harness (tests/schneider/test_oo_interface.py). Not part of the library. *)
PROGRAM O
VAR
    Cfg : ST_TmRobotCfg;
    TM : FB_TmRobot;
    Motion : IF_RobotMotion;
    Enable : BOOL;
    Go : INT;
    Diag : ARRAY[0..3] OF ET_Diag;
    DiagExt : ARRAY[0..3] OF ET_DiagExt;
    Msg : ARRAY[0..3] OF STRING[80];
    Target : ST_Vector3D;
    Orientation : ST_Orientation;
END_VAR
TM(xEnable := Enable, stCfg := Cfg);
Motion := TM;
CASE Go OF
    1:  // no path yet, then a bad start id, then one segment and (same cycle) a change: refused
        Motion.ChangeCoordinateSystem2(i_udiStartSegmentId := 1, i_lrStartOffset := 0.0, i_udiEndSegmentId := 1,
                                       i_lrEndOffset := 0.0, q_etDiag => Diag[0], q_etDiagExt => DiagExt[0], q_sMsg => Msg[0]);
        Motion.ChangeCoordinateSystem2(i_udiStartSegmentId := 0, i_lrStartOffset := 0.0, i_udiEndSegmentId := 1,
                                       i_lrEndOffset := 0.0, q_etDiag => Diag[1], q_etDiagExt => DiagExt[1], q_sMsg => Msg[1]);
        Target.lrX := 400.0; Target.lrY := -150.0; Target.lrZ := 300.0;
        Orientation.lrRx := 180.0; Orientation.lrRz := 90.0;
        Motion.MovePTP(i_stTarget := Target, i_stOrientation := Orientation, i_lrMaxZone := 0.0, i_udiSegmentId := 1,
                       q_etDiag => Diag[2], q_etDiagExt => DiagExt[2], q_sMsg => Msg[2]);
        Motion.ChangeCoordinateSystem2(i_udiStartSegmentId := 1, i_lrStartOffset := 0.0, i_udiEndSegmentId := 1,
                                       i_lrEndOffset := 0.0, q_etDiag => Diag[3], q_etDiagExt => DiagExt[3], q_sMsg => Msg[3]);
    2:  // tracking: a TM has none
        Motion.SetMaxAccelerationResultant(i_etComponent := ET_RobotComponent#Tracking, i_lrValue := 0.0,
                                           q_etDiag => Diag[0], q_etDiagExt => DiagExt[0], q_sMsg => Msg[0]);
        Motion.SetCoordinateSystem(i_etCoordinateSystem := ET_CoordinateSystem#LinearTracking1,
                                   q_etDiag => Diag[1], q_etDiagExt => DiagExt[1], q_sMsg => Msg[1]);
        Motion.ChangeCoordinateSystem2(i_udiStartSegmentId := 1, i_lrStartOffset := 0.0, i_udiEndSegmentId := 1,
                                       i_lrEndOffset := 0.0, q_etDiag => Diag[2], q_etDiagExt => DiagExt[2], q_sMsg => Msg[2]);
END_CASE;
Go := 0;
END_PROGRAM
"""

LIBRARY = ("SE_Types.st", "SE_TmPath.st", "FB_TmRobotLink.st", "IF_RobotMotion.st", "FB_TmRobot.st")


@lru_cache(maxsize=None)
def oo_project():
    return load_library(OO_FOLDER, HARNESS, ("Globals.st", "PnP_Example_OO.st", "Configuration.st"))


def test_the_oo_manifest_lists_the_library_and_the_interface():
    names = [p.name for p in manifest_files(OO_FOLDER)]
    assert all(name in names for name in LIBRARY)
    oo_project()                                      # loads: the interface and its implementation check


def test_methods_through_the_interface_answer_like_the_functions():
    b = Cell(oo_project())
    try:
        b.set("O.Enable", True)
        b.until(lambda: b.get("O.TM.xConnected"), 2000, "connected")
        b.set("O.Go", 1)
        b.scan(1)
        got = [(b.get(f"O.Diag[{i}]"), b.get(f"O.DiagExt[{i}]")) for i in range(4)]
        assert got == [(1, 9), (2, 27), (0, 43), (1, 10)]   # NoConnectedPath, StartSegmentIdRange, NewConnectedPath, CommandRefused
        b.set("O.Go", 2)
        b.scan(1)
        got = [(b.get(f"O.Diag[{i}]"), b.get(f"O.DiagExt[{i}]")) for i in range(3)]
        assert got == [(2, 170), (0, 0), (1, 170)]          # Tracking 0.0 out of range; not set -> 170
    finally:
        b.close()


def _demo_frames(folder):
    from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT, LockstepTransport
    from stvm.scenario import ScenarioDriver, load_scenario
    import tomllib
    with (folder / "stvm.toml").open("rb") as fh:
        demo = tomllib.load(fh)["demo"]
    scenario = load_scenario(folder / demo["scenario"])
    transport = LockstepTransport(latency_scans=1)
    vm = stvm.load([str(folder)]).start(scan="1ms", transport=transport)
    driver = ScenarioDriver(scenario, vm, transport.inject_fault)
    vm.on_scan_end.append(driver.after_scan)
    transport.attach(vm)
    driver.apply_initial({scenario.robot_address: LOCKSTEP_HOST, scenario.robot_port: LOCKSTEP_PORT})
    try:
        previous = None
        for _ in range(40000):
            vm.scan()
            step = vm.get(demo["step_variable"])
            if previous == 26 and step == 10:
                break
            previous = step
        else:
            raise AssertionError("no PnP cycle")
    finally:
        vm.close()
    return [f.data for f in transport.frames if f.direction == "rx"]


def test_oo_demo_sends_the_same_frames_as_the_function_demo():
    oo = _demo_frames(OO_FOLDER)
    plain = _demo_frames(REPO / "st_src" / "schneider")
    assert len(motion_commands(oo)) == 6
    assert [script_of(f) for f in oo if f.startswith(b"$TMSCT")] == [script_of(f) for f in plain if f.startswith(b"$TMSCT")]
