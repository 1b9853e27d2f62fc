"""The `stvm debug` console (stvm/debug/console.py, cli.py), driven through its input stream."""

from __future__ import annotations

import io
import re
import sys

import pytest

from core_helpers import cli, write_st
from debug_helpers import MOVE_ABSOLUTE, PNP_SCENARIO, THESIS_MAIN, line_of, small_build, small_line, small_path, thesis_build

from stvm.debug.console import Console, parse_assignment
from stvm.debug.engine import Engine
from stvm.debug.scope import DebugError


def transcript(build, commands: list[str], **engine_args) -> str:
    """Run the console on `commands` (one per line, then end of input); the whole output."""
    engine = Engine(build, **engine_args)
    out = io.StringIO()
    code = Console(engine, io.StringIO("\n".join(commands) + "\n"), out, echo=True).run()
    assert code == 0
    assert engine.state == "terminated"
    return out.getvalue()


def section(text: str, command: str) -> str:
    """The output of the first `(stvm) command` up to the next prompt."""
    start = text.index(f"(stvm) {command}\n") + len(f"(stvm) {command}\n")
    end = text.find("(stvm) ", start)
    return text[start:end if end >= 0 else None]


def test_break_continue_print_where_step_list_on_the_small_program():
    count_line = small_line("Count := Count + 1;")
    out = transcript(small_build(), [
        f"break {count_line}",
        "continue",
        "print Count",
        "print history[1] + 10",
        "where",
        "step",
        "step",          # into the FUNCTION Twice
        "watch tmp",
        "step",
        "up",
        "print Count",
        "list",
        "next",          # from Twice's last statement: back in the FB
        "finish",        # out of the FB: the program's next statement
        "",              # repeats finish: from the program, the end of the scan
        "info breakpoints",
        "quit",
    ])
    assert f"Breakpoint 1 at {small_path()}:{count_line} in Counter" in out
    stop = section(out, "continue")
    assert re.search(rf"Breakpoint 1: .*small\.st:{count_line} in Main\.c \(task DefaultTask, scan 0, t=T#0s\)", stop)
    assert f"=>B{count_line:5d}      Count := Count + 1;" in stop
    assert "Count = 0" in section(out, "print Count")
    assert "history[1] + 10 = 10" in out
    where = section(out, "where")
    assert "task DefaultTask, scan 0, t=T#0s" in where
    assert re.search(r"#0 Main\.c \(Counter\) at .*small\.st:\d+", where)
    assert re.search(r"#1 Main \(Main\) at .*small\.st:\d+", where)
    assert f"small.st:{small_line('tmp := x * 2;')} in Twice" in out
    assert "watch 1: tmp = 0" in section(out, "watch tmp")
    assert f"small.st:{small_line('Twice := tmp;')} in Twice" in out
    assert "#1 Main.c (Counter) at" in section(out, "up")
    assert "Count = 1" in out
    listing = section(out, "list")
    assert f"=> {small_line('history[Count MOD 5]'):5d}" in listing and "END_FUNCTION_BLOCK" in listing
    assert f"small.st:{small_line('last.a := Count;')} in Main.c" in section(out, "next")
    assert f"small.st:{small_line('total := total + c.Count;')} in Main" in section(out, "finish")
    assert "Stopped: before scan 1" in section(out, "")
    assert "hit 1 time(s)" in section(out, "info breakpoints")


def test_set_force_unforce_scan_and_watch():
    out = transcript(small_build(), [
        "force Main.c.Count := 100",
        "force",
        "watch Main.c.Count",
        "scan 3",
        "unforce Main.c.Count",
        "scan 2",
        "set Main.divisor := 4",
        "print Main.divisor",
        "set Main.divisor = 4",
        "unwatch 1",
        "info force",
        "quit",
    ])
    assert "Forced Main.c.Count := 100" in out
    assert "forced Main.c.Count := 100" in section(out, "force")
    scan3 = section(out, "scan 3")
    assert "Scan end: before scan 3" in scan3 and "watch 1: Main.c.Count = 100" in scan3
    assert "Released Main.c.Count" in out
    assert "watch 1: Main.c.Count = 102" in section(out, "scan 2")
    assert "Main.divisor := 4" in out and "Main.divisor = 4" in out
    assert "error: set needs VAR := VALUE" in section(out, "set Main.divisor = 4")
    assert "Nothing is forced." in section(out, "info force")


def test_a_fault_stops_post_mortem_and_nothing_more_runs():
    out = transcript(small_build(), [
        "set Main.divisor := 0",
        "continue",
        "print total",
        "print divisor",
        "where",
        "step",
        "quit",
    ])
    fault = section(out, "continue")
    assert re.search(rf"Fault: .*small\.st:{small_line('total := total / divisor;')} in Main", fault)
    assert "integer division by zero" in fault and "Post-mortem" in fault
    assert "total = 7" in out and "divisor = 0" in out
    assert "error: the program stopped on a fault" in section(out, "step")


def test_errors_are_messages_not_tracebacks():
    out = transcript(small_build(), [
        "print nosuch",
        "print 1 +",
        "break nosuch.st:3",
        "break small.st:abc",
        "frame 3",
        "delete 9",
        "unwatch 4",
        "frobnicate",
        "set Main.c.Count := 'text'",
        "help",
        "quit",
    ])
    assert "Traceback" not in out
    assert "error: 'nosuch' is not declared" in out
    assert "error: no ST file 'nosuch.st'" in out
    assert "error: break needs FILE:LINE" in out
    assert "error: no frames: the program is between scans" in out
    assert "error: no breakpoint 9" in out
    assert "unknown command 'frobnicate'" in out
    assert "force VAR := VALUE" in section(out, "help")


def test_assignment_splits_at_the_top_level_assign():
    assert parse_assignment("a[1] := F(x := 2)", "set") == ("a[1]", "F(x := 2)")
    assert parse_assignment("s := 'a := b'", "set") == ("s", "'a := b'")
    with pytest.raises(DebugError):
        parse_assignment("a = 1", "set")


def test_thesis_console_breakpoint_in_cbt_moveabsolute():
    line = line_of(MOVE_ABSOLUTE, "ToErrorDescrip:='Robot not connected';")
    engine = Engine(thesis_build(), scan_ns=1_000_000)
    engine.vm.set("MoveAbs_Execute", True)
    out = io.StringIO()
    Console(engine, io.StringIO("\n".join([
        f"break CBT_MoveAbsolute.st:{line} if NOT CBT.Connected",
        "continue",
        "print Execute",
        "print FB_status",
        "print CBT",
        "print Program_Example_Instance.CBT_MoveAbsolute_Instance.R_TRIG_Execute.Q",
        "where",
        "next",
        "quit"]) + "\n"), out, echo=True).run()
    text = out.getvalue()
    assert re.search(rf"Breakpoint 1: .*CBT_MoveAbsolute\.st:{line} in Program_Example_Instance\.CBT_MoveAbsolute_Instance", text)
    assert "Execute = TRUE" in text and "FB_status = 1" in text
    assert "CBT = (Socket := (Handle := 0" in text and "Connected := FALSE" in text
    assert "R_TRIG_Execute.Q = TRUE" in text
    assert "#1 Program_Example_Instance (Program_Example) at" in text
    assert f"CBT_MoveAbsolute.st:{line_of(MOVE_ABSOLUTE, 'CASE FB_status OF')} in" in section(text, "next")


def test_cli_debug_runs_commands_from_a_file_and_stdin(monkeypatch, tmp_path):
    commands = tmp_path / "cmds.txt"
    commands.write_text(f"break {small_line('total := total / divisor;')}\ncontinue\nprint total\n")
    monkeypatch.setattr(sys, "stdin", io.StringIO("print i\nquit\n"))
    code, out, err = cli(["debug", str(small_path()), "-x", str(commands), "--scan", "1ms"])
    assert code == 0, err
    assert "total = 7" in out and "i = 4" in out
    assert "t=T#0s" in out


def test_cli_debug_usage_and_compile_errors(monkeypatch):
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    code, out, err = cli(["debug", "nosuch.st"])
    assert code == 2 and "no such file" in err
    bad = write_st("PROGRAM P\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n", "bad_debug.st")
    code, out, err = cli(["debug", str(bad)])
    assert code == 1 and "'y' is not declared" in err
    code, out, err = cli(["debug", str(small_path()), "--robot", "nowhere"])
    assert code == 2 and "HOST:PORT" in err


def test_cli_debug_with_the_pnp_scenario_uses_the_lockstep_robot(monkeypatch):
    line = line_of(MOVE_ABSOLUTE, "TCP_Send_Size:=LEN(str_SendFrame);")
    monkeypatch.setattr(sys, "stdin", io.StringIO(
        f"break CBT_MoveAbsolute.st:{line}\ncontinue\nprint FB_step\nprint CBT.Connected\nquit\n"))
    code, out, err = cli(["debug", str(THESIS_MAIN), "--scan", "1ms", "--scenario", str(PNP_SCENARIO)])
    assert code == 0, err
    assert "robot: lockstep" in out
    assert "FB_step = 60" in out and "CBT.Connected = TRUE" in out
