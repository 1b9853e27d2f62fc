"""The debug engine (stvm/debug/engine.py, build.py, scope.py) driven through its Python API."""

from __future__ import annotations

import pytest

from core_helpers import write_st
from debug_helpers import (MOVE_ABSOLUTE, PNP_SCENARIO, THESIS_MAIN, line_of, small_build, small_line,
                           small_path, start_engine, thesis_build)

from stvm.debug.build import load_debug
from stvm.debug.engine import (BREAKPOINT, CONTINUE, FAULT, FAULTED, FINISH, NEXT, PAUSED, SCAN, SCANNED,
                               STEP, STEPPED, TERMINATED)
from stvm.debug.scope import DebugError

T = 30  # seconds: a stop that takes longer is a hang


@pytest.fixture
def engine():
    eng = start_engine(small_build())
    yield eng
    eng.terminate()


def at(event, snippet: str) -> None:
    """The stop is on the ST line holding `snippet` (of the small program)."""
    assert event is not None, "the engine did not stop"
    assert event.span is not None, event.describe()
    assert event.span.line == small_line(snippet), event.describe()


# ---------------------------------------------------------------- the debug build
def test_statement_map_has_every_statement_line_and_no_library_line():
    build = small_build()
    file = str(small_path())
    lines = build.statements.st_lines[file]
    for snippet in ["tmp := x * 2;", "Twice := tmp;", "IF Enable THEN", "Count := Count + 1;",
                    "c(Enable := run);", "FOR i := 1 TO 3 DO", "total := total + i;", "total := total / divisor;"]:
        assert small_line(snippet) in lines, snippet
    assert small_line("END_IF;") not in lines
    assert not any(f.startswith("<") for f in build.statements.st_lines)


@pytest.mark.parametrize("source, cycles, paths", [
    ("small", 7, ["Main.total", "Main.c.Count", "Main.c.history", "Main.c.last", "Main.grid", "Main.i"]),
    ("bench/st/for_sum.st", 3, ["ForSum.total", "ForSum.i"]),
    ("bench/st/bubble_sort.st", 1, ["BubbleSort.data", "BubbleSort.i", "BubbleSort.j"]),
])
def test_debug_build_computes_what_the_normal_build_computes(source, cycles, paths):
    import stvm
    from debug_helpers import ROOT
    files = [str(small_path())] if source == "small" else [str(ROOT / source)]
    normal = stvm.load(files, use_cache=False).start()
    debug = load_debug(files).project.start()
    normal.run(cycles=cycles)
    debug.run(cycles=cycles)
    assert [debug.format(p) for p in paths] == [normal.format(p) for p in paths]


def test_thesis_debug_build_runs_like_the_normal_build_in_lockstep():
    import stvm
    from stvm.lockstep import LockstepTransport
    from stvm.scenario import ScenarioDriver, load_scenario
    watched = ["PnP_Example_Instance.Prg_Step", "Cobot.Connected", "PnP_MoveDone",
               "PnP_Example_Instance.CBT_MoveAbsolute_Instance.FB_step"]

    def run(project):
        transport = LockstepTransport()
        vm = project.start(scan="1ms", transport=transport)
        scenario = load_scenario(PNP_SCENARIO)
        driver = ScenarioDriver(scenario, vm, transport.inject_fault)
        vm.on_scan_end.append(driver.after_scan)
        transport.attach(vm)
        driver.apply_initial({scenario.robot_address: "'127.0.0.1'", scenario.robot_port: 5890})
        seen = []
        for _ in range(400):
            vm.scan()
            seen.append(tuple(vm.format(p) for p in watched))
        vm.close()
        return seen

    normal = run(stvm.load([str(THESIS_MAIN)], use_cache=False))
    debug = run(thesis_build().project)
    assert debug == normal
    assert any(row[3] == "60" for row in debug)   # the run reached CBT_MoveAbsolute's send step


# ---------------------------------------------------------------- breakpoints and stepping
def test_breakpoint_stops_on_its_line_with_the_variables(engine):
    bp = engine.add_breakpoint("small.st", small_line("Count := Count + 1;"))
    event = engine.run(CONTINUE, timeout=T)
    at(event, "Count := Count + 1;")
    assert event.reason == BREAKPOINT and event.breakpoints == [bp.id]
    assert [f.name for f in event.frames] == ["Main.c", "Main"]
    assert event.task == "DefaultTask" and event.scan == 0
    assert engine.evaluate_text("Count") == "0"
    assert engine.evaluate_text("Enable") == "TRUE"
    assert engine.evaluate_text("history") == "[0, 0, 0, 0, 0]"
    assert engine.evaluate_text("run", 1) == "TRUE"        # the caller's frame
    at(engine.run(CONTINUE, timeout=T), "Count := Count + 1;")
    assert engine.evaluate_text("Count") == "1" and engine.stop_event.scan == 1
    assert bp.hits == 2


def test_breakpoint_on_a_line_without_a_statement_moves_to_the_next_statement(engine):
    bp = engine.add_breakpoint(str(small_path()), small_line("VAR_INPUT", 2))
    assert bp.line == small_line("IF Enable THEN") and bp.requested_line < bp.line
    at(engine.run(CONTINUE, timeout=T), "IF Enable THEN")


def test_breakpoint_errors_are_reported():
    engine = start_engine(small_build())
    try:
        with pytest.raises(DebugError, match="no ST file"):
            engine.add_breakpoint("nosuch.st", 3)
        with pytest.raises(DebugError, match="no statement"):
            engine.add_breakpoint("small.st", 10_000)
        with pytest.raises(DebugError, match="not declared"):
            engine.add_breakpoint("small.st", small_line("Count := Count + 1;"), "nosuch > 1")
        with pytest.raises(DebugError, match="BOOL"):
            engine.add_breakpoint("small.st", small_line("Count := Count + 1;"), "Count + 1")
    finally:
        engine.terminate()


def test_conditional_breakpoint_stops_only_when_true(engine):
    engine.add_breakpoint("small.st", small_line("Count := Count + 1;"), "Count = 3")
    event = engine.run(CONTINUE, timeout=T)
    at(event, "Count := Count + 1;")
    assert event.scan == 3 and engine.evaluate_text("Count") == "3"


def test_step_goes_into_calls_next_over_them_finish_out(engine):
    engine.add_breakpoint("small.st", small_line("history[Count MOD 5]"))
    at(engine.run(CONTINUE, timeout=T), "history[Count MOD 5]")
    event = engine.run(STEP, timeout=T)                       # into the FUNCTION
    at(event, "tmp := x * 2;")
    assert [f.name for f in event.frames] == ["Twice", "Main.c", "Main"]
    assert engine.evaluate_text("x") == "1"
    at(engine.run(STEP, timeout=T), "Twice := tmp;")
    assert engine.evaluate_text("tmp") == "2"
    at(engine.run(FINISH, timeout=T), "last.a := Count;")      # back in the FB, after the call
    assert engine.evaluate_text("history[1]") == "2"
    at(engine.run(NEXT, timeout=T), "total := total + c.Count;")   # the FB returned: its caller
    at(engine.run(NEXT, timeout=T), "FOR i := 1 TO 3 DO")
    at(engine.run(NEXT, timeout=T), "total := total + i;")
    at(engine.run(NEXT, timeout=T), "FOR i := 1 TO 3 DO")      # the loop's increment and test
    at(engine.run(NEXT, timeout=T), "total := total + i;")
    assert engine.evaluate_text("i") == "2"


def test_next_over_an_fb_call_and_finish_of_a_program_ends_the_scan(engine):
    engine.add_breakpoint("small.st", small_line("c(Enable := run);"))
    at(engine.run(CONTINUE, timeout=T), "c(Enable := run);")
    engine.delete_breakpoint()
    at(engine.run(NEXT, timeout=T), "total := total + c.Count;")
    assert engine.evaluate_text("c.Count") == "1"
    event = engine.run(FINISH, timeout=T)
    assert event.reason == STEPPED and event.between_scans and event.scan == 1
    at(engine.run(STEP, timeout=T), "c(Enable := run);")       # the next scan's first statement
    assert engine.stop_event.scan == 1


def test_stepping_past_the_last_statement_enters_the_next_scan(engine):
    engine.add_breakpoint("small.st", small_line("total := total / divisor;"))
    at(engine.run(CONTINUE, timeout=T), "total := total / divisor;")
    engine.delete_breakpoint()
    event = engine.run(STEP, timeout=T)
    at(event, "c(Enable := run);")
    assert event.scan == 1


def test_scan_runs_whole_scans_and_stops_between_them(engine):
    event = engine.run(SCAN, 3, timeout=T)
    assert event.reason == SCANNED and event.between_scans and event.scan == 3
    assert engine.evaluate_text("Main.c.Count") == "3"
    assert "between scans" in engine.where()


def test_pause_stops_an_endless_loop_inside_its_scan():
    path = write_st("PROGRAM Spin\nVAR\n    x : DINT;\nEND_VAR\nWHILE TRUE DO\n    x := x + 1;\nEND_WHILE;\nEND_PROGRAM\n",
                    "spin.st")
    engine = start_engine(load_debug([str(path)]))
    try:
        serial = engine.resume(CONTINUE)
        assert engine.wait(serial, 0.3) is None            # still running: nothing stops it
        engine.pause()
        event = engine.wait(serial, T)
        assert event.reason == PAUSED and event.scan == 0 and event.frames
        assert event.span.line in (5, 6)
        assert int(engine.evaluate_text("x")) > 0
    finally:
        engine.terminate()
    assert engine.state == TERMINATED


def test_a_breakpoint_set_while_running_stops_the_run(engine):
    engine.assign("Main.run", "FALSE")          # Count stays 0: the program can run for ever
    serial = engine.resume(CONTINUE)
    assert engine.wait(serial, 0.2) is None
    engine.add_breakpoint("small.st", small_line("total := total + i;"))
    event = engine.wait(serial, T)
    at(event, "total := total + i;")
    assert event.reason == BREAKPOINT


def test_terminate_while_running_ends_the_session():
    engine = start_engine(small_build())
    engine.resume(CONTINUE)
    engine.terminate()
    assert engine.state == TERMINATED
    with pytest.raises(DebugError, match="ended"):
        engine.resume(STEP)


# ---------------------------------------------------------------- data
def test_evaluate_reads_fb_members_arrays_structs_and_calls(engine):
    engine.run(SCAN, 2, timeout=T)
    assert engine.evaluate_text("Main.c.Count") == "2"                 # an output
    assert engine.evaluate_text("Main.c.history[2]") == "4"            # an internal array element
    assert engine.evaluate_text("Main.c.history") == "[0, 2, 4, 0, 0]"
    assert engine.evaluate_text("Main.c.last") == "(a := 2, b := 1.5)"  # a struct
    assert engine.evaluate_text("Main.c.last.b * 2.0") == "3.0"
    assert engine.evaluate_text("Main.grid[2, 3]") == "4"               # two dimensions
    assert engine.evaluate_text("Twice(Main.c.Count) + 1") == "5"       # a FUNCTION call
    assert engine.evaluate_text("Main.c.Count > 1 AND Main.run") == "TRUE"
    value, ty = engine.evaluate("Main.c.history[1]")
    assert value == 2 and ty.name == "INT"
    for bad, message in [("Main.nosuch", "no member"), ("Main.c.history[9]", "outside"), ("1 +", None)]:
        with pytest.raises(DebugError, match=message):
            engine.evaluate_text(bad)


def test_set_assigns_once_with_st_rules(engine):
    engine.add_breakpoint("small.st", small_line("total := total + c.Count;"))
    at(engine.run(CONTINUE, timeout=T), "total := total + c.Count;")
    assert engine.assign("c.Count", "41") == "41"                      # an FB output, from outside
    assert engine.assign("c.last.b", "2") == "2.0"                     # INT literal into REAL
    assert engine.assign("c.history[4]", "c.Count * 2") == "82"
    with pytest.raises(DebugError, match="out of range"):
        engine.assign("c.Count", "70000")
    with pytest.raises(DebugError):
        engine.assign("Twice(1)", "3")
    engine.delete_breakpoint()
    engine.run(NEXT, timeout=T)
    assert engine.evaluate_text("total") == "41"                       # the statement saw the new value
    engine.run(SCAN, 2, timeout=T)                                     # the end of this scan, and one more
    assert engine.evaluate_text("Main.c.Count") == "42"                # set once: the code moves on


def test_force_holds_a_value_at_the_start_and_end_of_every_scan(engine):
    forced = engine.force("Main.c.Count", "100")
    assert forced.key == "main.c.count"
    assert engine.evaluate_text("Main.c.Count") == "100"               # applied at once
    engine.add_breakpoint("small.st", small_line("last.a := Count;"))
    at(engine.run(CONTINUE, timeout=T), "last.a := Count;")
    assert engine.evaluate_text("Count") == "101"                      # the code ran on the forced value
    engine.delete_breakpoint()
    for _ in range(3):
        event = engine.run(SCAN, 1, timeout=T)
        assert event.between_scans
        assert engine.evaluate_text("Main.c.Count") == "100"           # forced again at every scan end
    engine.unforce("main.c.count")
    assert not engine.forces
    engine.run(SCAN, 2, timeout=T)
    assert engine.evaluate_text("Main.c.Count") == "102"


def test_force_by_a_local_name_holds_only_at_scan_start_and_end(engine):
    engine.add_breakpoint("small.st", small_line("IF Enable THEN"))
    at(engine.run(CONTINUE, timeout=T), "IF Enable THEN")
    forced = engine.force("Enable", "FALSE")
    assert forced.key == "main.c.enable" and forced.key_display == "Main.c.Enable"
    engine.delete_breakpoint()
    engine.run(SCAN, 1, timeout=T)
    assert engine.evaluate_text("Main.c.Count") == "0"       # the IF saw the forced FALSE at once
    assert engine.evaluate_text("Main.c.Enable") == "FALSE"
    engine.run(SCAN, 1, timeout=T)
    # Main's call passes Enable := TRUE during the scan: a force holds at the scan's start and end
    # only, as a controller's does, so the FB counted; at the scan end it is FALSE again
    assert engine.evaluate_text("Main.c.Count") == "1"
    assert engine.evaluate_text("Main.c.Enable") == "FALSE"
    released = engine.unforce("Main.c.Enable")
    assert [f.key for f in released] == ["main.c.enable"]
    with pytest.raises(DebugError, match="not forced"):
        engine.unforce("Main.run")


def test_force_of_an_input_nobody_writes_holds_across_scans(engine):
    engine.force("Main.run", "FALSE")
    engine.run(SCAN, 5, timeout=T)
    assert engine.evaluate_text("Main.c.Count") == "0" and engine.evaluate_text("Main.run") == "FALSE"
    engine.unforce(None)
    engine.run(SCAN, 5, timeout=T)
    assert engine.evaluate_text("Main.run") == "FALSE"       # released: the last value stays
    engine.assign("Main.run", "TRUE")
    engine.run(SCAN, 2, timeout=T)
    assert engine.evaluate_text("Main.c.Count") == "2"


def test_force_in_a_function_is_refused(engine):
    engine.add_breakpoint("small.st", small_line("tmp := x * 2;"))
    at(engine.run(CONTINUE, timeout=T), "tmp := x * 2;")
    with pytest.raises(DebugError, match="FUNCTION"):
        engine.force("tmp", "1")


# ---------------------------------------------------------------- faults
def test_a_fault_stops_post_mortem_at_its_line_with_variables_intact(engine):
    engine.assign("Main.divisor", "0")
    event = engine.run(CONTINUE, timeout=T)
    at(event, "total := total / divisor;")
    assert event.reason == FAULT and engine.state == FAULTED
    assert "division by zero" in event.message
    assert [f.name for f in event.frames] == ["Main"]
    assert engine.evaluate_text("total") == "7"         # 1 + (1+2+3): the scan's work is all there
    assert engine.evaluate_text("c.Count") == "1"
    assert "Main (Main) at" in engine.where()
    with pytest.raises(DebugError, match="fault"):
        engine.resume(CONTINUE)


def test_a_fault_inside_a_function_keeps_the_function_frame():
    source = ("FUNCTION Bad : INT\nVAR_INPUT\n    n : INT;\nEND_VAR\nVAR\n    arr : ARRAY[0..2] OF INT;\nEND_VAR\n"
              "arr[0] := n;\nBad := arr[n];\nEND_FUNCTION\n"
              "PROGRAM P\nVAR\n    k : INT;\n    r : INT;\nEND_VAR\nk := k + 2;\nr := Bad(k);\nEND_PROGRAM\n")
    engine = start_engine(load_debug([str(write_st(source, "bad.st"))]))
    try:
        event = engine.run(CONTINUE, timeout=T)
        assert event.reason == FAULT and event.scan == 1 and event.span.line == line_of(source, "Bad := arr[n];")
        assert [f.name for f in event.frames] == ["Bad", "P"]
        assert engine.evaluate_text("n") == "4" and engine.evaluate_text("arr[0]") == "4"
        assert engine.evaluate_text("k", 1) == "4"
    finally:
        engine.terminate()


# ---------------------------------------------------------------- the thesis code
def test_thesis_breakpoint_in_cbt_moveabsolute_without_a_robot():
    engine = start_engine(thesis_build(), scan_ns=1_000_000)
    try:
        engine.vm.set("MoveAbs_Execute", True)
        line = line_of(MOVE_ABSOLUTE, "ToErrorDescrip:='Robot not connected';")
        bp = engine.add_breakpoint("CBT_MoveAbsolute.st", line)
        event = engine.run(CONTINUE, timeout=T)
        assert event.reason == BREAKPOINT and event.span.line == line
        assert event.span.file.endswith("CBT_MoveAbsolute.st")
        assert [f.name for f in event.frames] == ["Program_Example_Instance.CBT_MoveAbsolute_Instance",
                                                  "Program_Example_Instance"]
        assert event.frames[0].pou.name == "CBT_MoveAbsolute" and bp.pou.name == "CBT_MoveAbsolute"
        assert engine.evaluate_text("Execute") == "TRUE"
        assert engine.evaluate_text("CBT.Connected") == "FALSE"
        assert engine.evaluate_text("FB_status") == "1" and engine.evaluate_text("FB_step") == "10"
        assert engine.evaluate_text("ToErrorID") == "153"               # 16#99, the line before
        assert engine.evaluate_text("R_TRIG_Execute.Q") == "TRUE"       # an FB member of the FB
        assert engine.evaluate_text("iParameters.Speed") == "0"
        assert engine.evaluate_text("TCP_Send_Data[0]") == "0"
        event = engine.run(STEP, timeout=T)
        assert event.span.line == line_of(MOVE_ABSOLUTE, "CASE FB_status OF")
        assert engine.evaluate_text("ToErrorDescrip") == "'Robot not connected'"
    finally:
        engine.terminate()


def test_thesis_breakpoint_in_cbt_moveabsolute_with_the_robot_in_lockstep():
    from stvm.debug.session import SessionOptions, open_session
    session = open_session(SessionOptions([str(THESIS_MAIN)], scan="1ms", scenario=str(PNP_SCENARIO)),
                           build=thesis_build())
    engine = session.engine
    try:
        assert session.robot == "lockstep"
        engine.start()
        engine.wait_started(T)
        line = line_of(MOVE_ABSOLUTE, "TCP_Send_Size:=LEN(str_SendFrame);")
        engine.add_breakpoint("CBT_MoveAbsolute.st", line)
        event = engine.run(CONTINUE, timeout=T)
        assert event.span.line == line
        assert event.frames[0].name == "PnP_Example_Instance.CBT_MoveAbsolute_Instance"
        assert engine.evaluate_text("CBT.Connected") == "TRUE"
        assert engine.evaluate_text("FB_step") == "60"
        assert engine.evaluate_text("iParameters.TargetPosition.Z") == "300.0"
        script = engine.evaluate_text("Script_Command")
        assert script.startswith("'PTP(\"CPP\",+400,-150,+300,+180,+0,+90,50,200,0,false)")
        assert engine.evaluate_text("str_SendFrame").startswith("'$$TMSCT,")
        assert engine.evaluate_text("TCP_Send_Data[0]") == "36"          # '$'
        event = engine.run(NEXT, timeout=T)
        assert event.span.line == line_of(MOVE_ABSOLUTE, "ToAryByte(In:=str_SendFrame")
        assert engine.evaluate_text("TCP_Send_Size") == engine.evaluate_text("Length")
    finally:
        session.close()
