"""`stvm dap` (stvm/debug/dap.py) through its stdio, with the small DAP client of dap_client.py."""

from __future__ import annotations

import pytest

from core_helpers import write_st
from dap_client import DapClient
from debug_helpers import MOVE_ABSOLUTE, PNP_SCENARIO, THESIS_MAIN, line_of, small_line, small_path


@pytest.fixture
def dap():
    client = DapClient()
    yield client
    assert client.close() == 0


def test_thesis_breakpoint_variables_evaluate_and_stepping_in_cbt_moveabsolute(dap):
    line = line_of(MOVE_ABSOLUTE, "ToErrorDescrip:='Robot not connected';")
    results = dap.launch(str(THESIS_MAIN), scan="1ms", set=["MoveAbs_Execute=TRUE"],
                         breakpoints={str(MOVE_ABSOLUTE): [{"line": line}, {"line": 100_000}]})
    verified = results[str(MOVE_ABSOLUTE)]["breakpoints"]
    assert verified[0]["verified"] and verified[0]["line"] == line
    assert not verified[1]["verified"] and "no statement" in verified[1]["message"]

    stop = dap.stopped("breakpoint")
    assert stop["threadId"] == 1 and stop["hitBreakpointIds"] == [verified[0]["id"]]
    assert dap.body("threads")["threads"] == [{"id": 1, "name": "task PrimaryTask"}]
    frames = dap.body("stackTrace", threadId=1)["stackFrames"]
    assert [f["name"] for f in frames] == [
        "Program_Example_Instance.CBT_MoveAbsolute_Instance (CBT_MoveAbsolute)", "Program_Example_Instance (Program_Example)"]
    assert frames[0]["line"] == line and frames[0]["source"]["path"] == str(MOVE_ABSOLUTE)
    assert frames[1]["source"]["path"].endswith("Program_Example.st")

    scopes = dap.scope_variables(frames[0]["id"])
    assert set(scopes) == {"Locals", "Inputs/Outputs", "Globals"}
    assert scopes["Locals"]["FB_status"]["value"] == "1" and scopes["Locals"]["FB_step"]["value"] == "10"
    assert scopes["Locals"]["ToErrorID"]["value"] == "153"
    assert scopes["Inputs/Outputs"]["Execute"]["value"] == "TRUE"
    assert scopes["Globals"]["MoveAbs_Execute"]["value"] == "TRUE"
    cbt = scopes["Inputs/Outputs"]["CBT"]                     # a struct in-out: expandable
    assert cbt["variablesReference"] > 0 and cbt["value"] == "stCBT_Connection"
    members = dap.variables(cbt["variablesReference"])
    assert members["Connected"]["value"] == "FALSE" and members["Connected"]["evaluateName"] == "CBT.Connected"
    send_data = scopes["Locals"]["TCP_Send_Data"]              # an array: paged
    assert send_data["indexedVariables"] == 256
    page = dap.variables(send_data["variablesReference"], filter="indexed", start=10, count=3)
    assert list(page) == ["[10]", "[11]", "[12]"] and page["[10]"]["evaluateName"] == "TCP_Send_Data[10]"
    trig = dap.variables(scopes["Locals"]["R_TRIG_Execute"]["variablesReference"])   # an FB instance
    assert trig["Q"]["value"] == "TRUE" and trig["CLK"]["value"] == "TRUE"

    frame = frames[0]["id"]
    assert dap.evaluate("R_TRIG_Execute.Q", frame)["result"] == "TRUE"
    assert dap.evaluate("TCP_Send_Data[0] + 1", frame)["result"] == "1"
    assert dap.evaluate("Program_Example_Instance.CBT_MoveAbsolute_Instance.FB_step", frame)["result"] == "10"
    params = dap.evaluate("iParameters", frame, context="hover")
    assert params["variablesReference"] > 0
    assert dap.variables(params["variablesReference"])["AccelTime"]["value"] == "0"
    failed = dap.request("evaluate", ok=False, expression="nosuch", frameId=frame, context="watch")
    assert not failed["success"] and "not declared" in failed["message"]

    dap.request("next")
    assert dap.stopped("step")
    assert dap.top_frame()["line"] == line_of(MOVE_ABSOLUTE, "CASE FB_status OF")
    locals_ref = dap.body("scopes", frameId=1)["scopes"][0]["variablesReference"]
    changed = dap.body("setVariable", variablesReference=locals_ref, name="FB_status", value="6")
    assert changed["value"] == "6"
    dap.request("stepIn")
    dap.stopped("step")
    assert dap.top_frame()["line"] == line_of(MOVE_ABSOLUTE, "Done := FALSE;", 5)   # branch 6 of the CASE
    dap.request("stepOut")
    dap.stopped("step")
    top = dap.top_frame()
    assert top["name"] == "Program_Example_Instance (Program_Example)"


def test_fault_stops_with_an_exception_and_keeps_the_variables(dap):
    dap.launch(str(small_path()), set=["Main.divisor=0"])
    stop = dap.stopped("exception")
    assert "division by zero" in stop["text"]
    info = dap.body("exceptionInfo", threadId=1)
    assert info["exceptionId"] == "RuntimeFault" and "division by zero" in info["description"]
    top = dap.top_frame()
    assert top["line"] == small_line("total := total / divisor;") and top["name"] == "Main (Main)"
    scopes = dap.scope_variables(top["id"])
    assert scopes["Locals"]["total"]["value"] == "7" and scopes["Locals"]["divisor"]["value"] == "0"
    grid = dap.variables(scopes["Locals"]["grid"]["variablesReference"])    # ARRAY[1..2, 1..3]: rows
    row2 = dap.variables(grid["[2]"]["variablesReference"])
    assert row2["[3]"]["value"] == "4" and row2["[3]"]["evaluateName"] == "grid[2,3]"   # the catalog's one path syntax
    dap.request("continue")                      # nothing can run after a fault: the session ends
    dap.wait_event("terminated")


def test_force_and_scan_from_the_debug_console(dap):
    dap.launch(str(small_path()), stopOnEntry=True)
    assert dap.stopped("entry")
    frames = dap.body("stackTrace", threadId=1)["stackFrames"]
    assert frames[0]["name"] == "between scans (before scan 0)"
    scopes = dap.body("scopes", frameId=1)["scopes"]
    assert [s["name"] for s in scopes] == ["Globals", "Programs"]
    programs = dap.variables(scopes[1]["variablesReference"])
    assert programs["Main"]["variablesReference"] > 0

    assert dap.evaluate("force Main.c.Count := 100", context="repl")["result"] == "forced Main.c.Count := 100"
    assert "Main.c.Count := 100" in dap.evaluate("forces", context="repl")["result"]
    dap.evaluate("scan 3", context="repl")
    dap.stopped("step")
    assert dap.evaluate("Main.c.Count")["result"] == "100"
    assert dap.evaluate("unforce Main.c.Count", context="repl")["result"] == "released Main.c.Count"
    dap.evaluate("scan 2", context="repl")
    dap.stopped("step")
    assert dap.evaluate("Main.c.Count")["result"] == "102"
    assert dap.evaluate("set Main.c.Count := 5", context="repl")["result"] == "Main.c.Count := 5"
    assert dap.evaluate("Main.c.Count")["result"] == "5"


def test_conditional_breakpoint_and_pause(dap):
    count_line = small_line("Count := Count + 1;")
    dap.launch(str(small_path()), breakpoints={str(small_path()): [{"line": count_line, "condition": "Count = 4"}]})
    dap.stopped("breakpoint")
    frame = dap.top_frame()
    assert frame["line"] == count_line
    assert dap.evaluate("Count", frame["id"])["result"] == "4"
    dap.body("setBreakpoints", source={"path": str(small_path())}, breakpoints=[])
    dap.evaluate("set Main.run := FALSE", frame["id"], context="repl")   # no overflow fault: runs for ever
    dap.request("continue")
    dap.request("pause", threadId=1)
    stop = dap.stopped("pause")
    assert stop["threadId"] == 1
    assert dap.body("stackTrace", threadId=1)["totalFrames"] >= 1


def test_bad_programs_and_requests_get_error_responses(dap):
    bad = write_st("PROGRAM P\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n", "bad_dap.st")
    dap.body("initialize", adapterID="stvm")
    failed = dap.request("launch", ok=False, program=str(bad))
    assert not failed["success"] and "1 error(s)" in failed["message"]
    output = dap.wait_event("output")
    assert "'y' is not declared" in output["body"]["output"]
    assert not dap.request("stackTrace", ok=False, threadId=1)["success"]
    assert not dap.request("frobnicate", ok=False)["success"]
    missing = dap.request("launch", ok=False, program="nosuch.st")
    assert "no such file" in missing["message"]


def test_thesis_lockstep_session_over_dap(dap):
    line = line_of(MOVE_ABSOLUTE, "TCP_Send_Size:=LEN(str_SendFrame);")
    dap.launch(str(THESIS_MAIN), scan="1ms", scenario=str(PNP_SCENARIO),
               breakpoints={str(MOVE_ABSOLUTE): [{"line": line}]})
    dap.stopped("breakpoint")
    top = dap.top_frame()
    assert top["name"].startswith("PnP_Example_Instance.CBT_MoveAbsolute_Instance")
    assert dap.evaluate("FB_step", top["id"])["result"] == "60"
    assert dap.evaluate("CBT.Connected", top["id"])["result"] == "TRUE"
    assert dap.evaluate("str_SendFrame", top["id"])["result"].startswith("'$$TMSCT,")
    dap.request("disconnect")


def test_one_thread_per_task_and_the_stop_names_its_task(dap):
    source = """
PROGRAM Fast
VAR
    n : INT;
END_VAR
n := n + 1;
END_PROGRAM

PROGRAM Slow
VAR
    m : INT;
END_VAR
m := m + 1;
END_PROGRAM

CONFIGURATION Two
    RESOURCE R ON CPU
        TASK FastTask (INTERVAL := T#1ms, PRIORITY := 4);
        TASK SlowTask (INTERVAL := T#4ms, PRIORITY := 10);
        PROGRAM FastInstance WITH FastTask : Fast;
        PROGRAM SlowInstance WITH SlowTask : Slow;
    END_RESOURCE
END_CONFIGURATION
"""
    path = write_st(source, "two_tasks.st")
    dap.launch(str(path), breakpoints={str(path): [{"line": line_of(source, "m := m + 1;"), "condition": "m = 1"}]})
    stop = dap.stopped("breakpoint")
    threads = dap.body("threads")["threads"]
    assert threads == [{"id": 1, "name": "task FastTask"}, {"id": 2, "name": "task SlowTask"}]
    assert stop["threadId"] == 2
    assert dap.body("stackTrace", threadId=1)["stackFrames"] == []
    top = dap.top_frame(thread_id=2)
    assert top["name"] == "SlowInstance (Slow)"
    assert dap.evaluate("FastInstance.n", top["id"])["result"] == "5"   # scans 0..4; Slow runs in 0 and 4


def test_cycles_ends_the_session_with_terminated(dap):
    dap.launch(str(small_path()), cycles=20)
    exited = dap.wait_event("exited")
    assert exited["body"]["exitCode"] == 0
    dap.wait_event("terminated")
