"""The `stvm` command line (a contract): check/run, --print/--set/--cycles/--duration/--stats/--realtime,
exit codes 0 ok, 1 compile errors, 2 usage error, 3 runtime fault."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from core_helpers import cli, write_st

ROOT = Path(__file__).resolve().parents[2]

PROGRAM = """
TYPE Color : (Red, Green, Blue); Rec : STRUCT a : INT; b : STRING[8]; END_STRUCT; END_TYPE
FUNCTION_BLOCK Twice
VAR_INPUT i : INT; END_VAR
VAR_OUTPUT o : INT; END_VAR
o := i * 2;
END_FUNCTION_BLOCK
VAR_GLOBAL g : INT := 4; END_VAR
PROGRAM Main
VAR_EXTERNAL g : INT; END_VAR
VAR
  x : INT; first : INT; n : INT; r : REAL; l : LREAL; s : STRING; t : TIME; c : Color; rec : Rec;
  arr : ARRAY[1..3] OF INT; f : Twice; b : BOOL; u8 : USINT; m : ARRAY[1..2, 1..2] OF INT;
END_VAR
IF n = 0 THEN first := x; END_IF;
n := n + 1;
f(i := x + g);
END_PROGRAM
"""


@pytest.fixture(scope="module")
def prog() -> Path:
    return write_st(PROGRAM, "cli_main.st")


def run(prog, *args):
    return cli(["run", prog, "--no-cache", *args])


def test_check_ok_exit_0(prog):
    assert cli(["check", prog]) == (0, "", "")


def test_check_errors_exit_1(tmp_path):
    bad = tmp_path / "bad.st"
    bad.write_text("PROGRAM Main\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n")
    rc, out, err = cli(["check", bad])
    assert rc == 1 and out == ""
    assert err.startswith(f"{bad}:3:6: error: 'y' is not declared [E031]\n    x := y;\n         ^\n")
    assert err.endswith("1 error(s)\n")


def test_run_compile_errors_exit_1_and_nothing_runs(tmp_path):
    bad = tmp_path / "bad.st"
    bad.write_text("PROGRAM Main\nVAR x : INT; END_VAR\nx := 'a';\nEND_PROGRAM\n")
    rc, out, err = cli(["run", bad, "--cycles", "3", "--print", "Main.x", "--no-cache"])
    assert rc == 1 and out == "" and ": error:" in err


def test_print_formats(prog):
    rc, out, err = run(prog, "--cycles", "2", "--print", "Main.n", "--print", "Main.b", "--print", "Main.r",
                       "--print", "Main.s", "--print", "Main.t", "--print", "Main.c", "--print", "Main.rec",
                       "--print", "Main.arr", "--print", "Main.f.o", "--print", "Main.f", "--print", "g",
                       "--print", "Main.arr[2]", "--print", "Main.m", "--print", "Main.rec.b")
    assert (rc, err) == (0, "")
    assert out.splitlines() == [
        "Main.n = 2", "Main.b = FALSE", "Main.r = 0.0", "Main.s = ''", "Main.t = T#0s", "Main.c = Color#Red",
        "Main.rec = (a := 0, b := '')", "Main.arr = [0, 0, 0]", "Main.f.o = 8", "Main.f = (i := 4, o := 8)",
        "g = 4", "Main.arr[2] = 0", "Main.m = [[0, 0], [0, 0]]", "Main.rec.b = ''"]


def test_set_applies_before_the_first_scan(prog):
    rc, out, err = run(prog, "--cycles", "2", "--set", "Main.x=21", "--set", "g=100", "--set", "Main.r=1.25",
                       "--set", "Main.s='hi$L'", "--set", "Main.t=T#2s", "--set", "Main.c=Color#Blue",
                       "--set", "Main.rec.a=3", "--set", "Main.arr[2]=9", "--set", "Main.b=TRUE",
                       "--set", "Main.l=-1e300", "--set", "Main.u8=16#FF", "--set", "Main.m[2,1]=7",
                       "--print", "Main.first", "--print", "Main.f.o", "--print", "Main.r", "--print", "Main.s",
                       "--print", "Main.t", "--print", "Main.c", "--print", "Main.rec", "--print", "Main.arr",
                       "--print", "Main.b", "--print", "Main.l", "--print", "Main.u8", "--print", "Main.m")
    assert (rc, err) == (0, "")
    assert out.splitlines() == [
        "Main.first = 21", "Main.f.o = 242", "Main.r = 1.25", "Main.s = 'hi$L'", "Main.t = T#2s",
        "Main.c = Color#Blue", "Main.rec = (a := 3, b := '')", "Main.arr = [0, 9, 0]", "Main.b = TRUE",
        "Main.l = -1.0E+300", "Main.u8 = 255", "Main.m = [[0, 0], [7, 0]]"]


@pytest.mark.parametrize("value", ["Green", "Color#Green", "-5", "INT#7", "16#10", "2#11", "FALSE", "BOOL#0"])
def test_set_accepts_iec_literals(prog, value):
    var = {"Green": "Main.c", "Color#Green": "Main.c", "FALSE": "Main.b", "BOOL#0": "Main.b"}.get(value, "Main.x")
    rc, out, err = run(prog, "--cycles", "0", "--set", f"{var}={value}", "--print", var)
    assert rc == 0, err
    expected = {"Green": "Color#Green", "Color#Green": "Color#Green", "-5": "-5", "INT#7": "7", "16#10": "16",
                "2#11": "3", "FALSE": "FALSE", "BOOL#0": "FALSE"}[value]
    assert out == f"{var} = {expected}\n"


@pytest.mark.parametrize("args", [
    ["--set", "Main.b=2"],                        # a BOOL takes TRUE/FALSE, 0 or 1 (IEC 61131-3 table 5)
    ["--set", "Main.t=5"],                        # a TIME takes T#5ms, not 5 (ns)
    ["--set", "Main.s='open"],                    # an unterminated string
    ["--set", "Main.r=1e40"],                     # beyond REAL
    ["--set", "Main.x=70000"],                    # out of range
    ["--set", "Main.x=abc"],                      # not a literal
    ["--set", "Main.x"],                          # no '='
    ["--set", "=5"],
    ["--set", "Main.nope=1"],                     # unknown variable
    ["--set", "Main.c=Color#Pink"],
    ["--set", "Main.arr[7]=1"],
    ["--print", "Main.nope"],
    ["--print", "Nope.x"],
    ["--print", "Main"],
    ["--print", "Main.arr[0]"],
    ["--scan", "bogus"],
    ["--scan", "0ms"],
    ["--duration", "soon"],
    ["--cycles", "-1"],
    ["--cycles", "x"],
    ["--cycles", "1", "--duration", "1s"],
    ["--frobnicate"],
])
def test_usage_errors_exit_2(prog, args):
    rc, out, err = run(prog, *args)
    assert rc == 2, (rc, err)
    assert "Traceback" not in err and err.strip()


@pytest.mark.parametrize("args", [["--scan", ""], ["--duration", "T#"], ["--scan=T#"], ["--scan=-5ms"]])
def test_empty_duration_is_a_usage_error(prog, args):
    rc, out, err = run(prog, "--cycles", "1", *args)
    assert rc == 2 and "Traceback" not in err


@pytest.mark.parametrize("argv", [[], ["frob"], ["run"], ["check"], ["run", "/nonexistent/x.st"],
                                  ["check", "/nonexistent/x.st"]])
def test_usage_errors_without_a_program(argv):
    rc, out, err = cli(argv)
    assert rc == 2 and "Traceback" not in err


def test_duration_runs_ceil_of_duration_over_scan(prog):
    rc, out, _ = run(prog, "--scan", "10ms", "--duration", "25ms", "--print", "Main.n")
    assert (rc, out) == (0, "Main.n = 3\n")
    rc, out, _ = run(prog, "--scan", "1ms", "--duration", "T#1s", "--print", "Main.n")
    assert (rc, out) == (0, "Main.n = 1000\n")


def test_cycles_zero_prints_initial_values(prog):
    rc, out, _ = run(prog, "--cycles", "0", "--print", "Main.n", "--print", "g")
    assert (rc, out) == (0, "Main.n = 0\ng = 4\n")


def test_scan_period_drives_the_virtual_clock(tmp_path):
    path = tmp_path / "timer.st"
    path.write_text("PROGRAM Main\nVAR t : TON; q : BOOL; et : TIME; END_VAR\n"
                    "t(IN := TRUE, PT := T#1s); q := t.Q; et := t.ET;\nEND_PROGRAM\n")
    rc, out, _ = cli(["run", path, "--no-cache", "--scan", "100ms", "--cycles", "10", "--print", "Main.q",
                      "--print", "Main.et"])
    assert out == "Main.q = FALSE\nMain.et = T#900ms\n"
    rc, out, _ = cli(["run", path, "--no-cache", "--scan", "100ms", "--cycles", "11", "--print", "Main.q",
                      "--print", "Main.et"])
    assert out == "Main.q = TRUE\nMain.et = T#1s\n"


def test_stats(prog):
    rc, out, err = run(prog, "--cycles", "20", "--stats")
    assert rc == 0
    assert re.search(r"mean\s+[0-9.]+", out) and re.search(r"p50\s+[0-9.]+", out)
    assert re.search(r"p99\s+[0-9.]+", out) and re.search(r"max\s+[0-9.]+", out)


def test_realtime_sleeps_to_deadlines_and_reports_jitter(prog):
    start = time.perf_counter()
    rc, out, err = run(prog, "--cycles", "10", "--scan", "5ms", "--realtime", "--stats", "--print", "Main.n")
    elapsed = time.perf_counter() - start
    assert rc == 0
    assert "Main.n = 10" in out
    assert elapsed >= 0.045
    assert "overruns" in out and "jitter" in out


def test_multiple_files_and_a_folder(tmp_path):
    (tmp_path / "a.st").write_text("PROGRAM Main\nVAR p : Pt; END_VAR\np.x := Inc(p.x);\nEND_PROGRAM\n")
    (tmp_path / "b.st").write_text("TYPE Pt : STRUCT x : INT; END_STRUCT; END_TYPE\n"
                                   "FUNCTION Inc : INT VAR_INPUT v : INT; END_VAR Inc := v + 1; END_FUNCTION\n")
    for argv in ([tmp_path / "a.st", tmp_path / "b.st"], [tmp_path / "b.st", tmp_path / "a.st"], [tmp_path]):
        rc, out, err = cli(["run", *argv, "--cycles", "3", "--no-cache", "--print", "Main.p"])
        assert (rc, out) == (0, "Main.p = (x := 3)\n"), err


def test_runtime_fault_exit_3(tmp_path):
    path = tmp_path / "fault.st"
    path.write_text("PROGRAM Main\nVAR n, z : INT; arr : ARRAY[1..2] OF INT; END_VAR\nn := n + 1;\n"
                    "arr[n] := 10 / (3 - n);\nEND_PROGRAM\n")
    rc, out, err = cli(["run", path, "--cycles", "5", "--no-cache", "--print", "Main.n", "--print", "Main.arr"])
    assert rc == 3
    assert out == "Main.n = 3\nMain.arr = [5, 10]\n"
    assert re.match(rf"{re.escape(str(path))}:4:1: fault: .+ \(task \S+, scan \d+, t=T#20ms\)\n", err)
    assert "Traceback" not in err


def test_warnings_go_to_stderr_and_do_not_change_the_exit_code(tmp_path):
    path = tmp_path / "warn.st"
    path.write_text("PROGRAM Main\nVAR s : STRING[3] := 'abcdef'; END_VAR\nEND_PROGRAM\n")
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--print", "Main.s"])
    assert (rc, out) == (0, "Main.s = 'abc'\n")          # IEC (the default): STRING[3] holds 3
    assert f"{path}:2:" in err and ": warning:" in err
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--print", "Main.s", "--dialect", "sysmac"])
    assert (rc, out) == (0, "Main.s = 'ab'\n")           # Sysmac: 3 bytes with the NUL
    assert f"{path}:2:" in err and ": warning:" in err


def test_cached_run_gives_the_same_output(prog, tmp_path, monkeypatch):
    monkeypatch.setenv("STVM_CACHE_DIR", str(tmp_path / "cache"))
    first = cli(["run", prog, "--cycles", "3", "--print", "Main.f"])
    second = cli(["run", prog, "--cycles", "3", "--print", "Main.f"])
    assert first == second and first[0] == 0


# ---------------------------------------------------------------- a real process
def test_python_m_stvm_runs_until_ctrl_c_and_exits_cleanly(prog, tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    # warm the compile cache and measure how long a child takes to start on this machine now, so
    # Ctrl-C comes while the child is running, not loading, even on a loaded CI machine
    started = time.time()
    subprocess.run([sys.executable, "-m", "stvm", "run", str(prog), "--cycles", "1"], cwd=tmp_path,
                   env=env, capture_output=True, check=True, timeout=60)
    startup_s = time.time() - started
    proc = subprocess.Popen([sys.executable, "-m", "stvm", "run", str(prog), "--scan", "1ms", "--realtime",
                             "--print", "Main.first", "--set", "Main.x=5"],
                            cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(max(2.5, 3 * startup_s))
    deadline = time.time() + 20
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=max(1, deadline - time.time()))
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert out == "Main.first = 5\n"
    assert "Traceback" not in err


def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


def test_ctrl_c_during_load_exits_cleanly(prog, monkeypatch):
    """Ctrl-C before the first scan (here: inside the loader) is a clean exit, not a traceback."""
    import stvm.project
    monkeypatch.setattr(stvm.project, "load", _interrupt)
    rc, out, err = run(prog, "--print", "Main.n")
    assert "Traceback" not in err
    assert rc in (0, 130)


def test_ctrl_c_while_building_the_command_line_exits_cleanly(prog, monkeypatch):
    import stvm.cli
    monkeypatch.setattr(stvm.cli, "_register_extensions", _interrupt)
    rc, out, err = run(prog, "--print", "Main.n")
    assert "Traceback" not in err
    assert rc in (0, 130)


INOUT_PROGRAM = """
TYPE Conn : STRUCT sock : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK User
VAR_IN_OUT c : Conn; n : INT; END_VAR
c.sock := c.sock + 1; n := n + 10;
END_FUNCTION_BLOCK
PROGRAM Main
VAR c : Conn; u : User; k : INT; END_VAR
u(c := c, n := k);
END_PROGRAM
"""


def test_print_through_a_bound_in_out(tmp_path):
    path = write_st(INOUT_PROGRAM, "inout_print.st")
    rc, out, err = cli(["run", path, "--cycles", "2", "--no-cache", "--print", "Main.u.c.sock", "--print", "Main.u.c",
                        "--print", "Main.u.n"])
    assert (rc, out) == (0, "Main.u.c.sock = 2\nMain.u.c = (sock := 2)\nMain.u.n = 20\n"), err


@pytest.mark.parametrize("args", [
    pytest.param(["--cycles", "0", "--print", "Main.u.c.sock"], id="print_struct_member"),
    pytest.param(["--cycles", "0", "--print", "Main.u.n"], id="print_elementary"),
    pytest.param(["--cycles", "1", "--set", "Main.u.c.sock=5"], id="set_struct_member"),
    pytest.param(["--cycles", "1", "--set", "Main.u.n=5"], id="set_elementary"),
])
def test_path_through_an_unbound_in_out_is_a_usage_error(args):
    path = write_st(INOUT_PROGRAM, "inout_unbound.st")
    rc, out, err = cli(["run", path, "--no-cache", *args])
    assert "Traceback" not in err
    assert rc in (0, 2)


def test_a_folder_whose_manifest_lists_its_files(tmp_path):
    """`stvm run FOLDER`: a folder with an stvm.toml that lists [project] files runs those files,
    which may lie in another folder (a library the project builds on); without the list, every *.st
    of the folder."""
    lib = tmp_path / "lib"
    app = tmp_path / "app"
    lib.mkdir()
    app.mkdir()
    (lib / "inc.st").write_text("FUNCTION Inc : INT VAR_INPUT v : INT; END_VAR Inc := v + 1; END_FUNCTION\n")
    (app / "main.st").write_text("PROGRAM Main\nVAR n : INT; END_VAR\nn := Inc(n);\nEND_PROGRAM\n")
    (app / "unused.st").write_text("this is not ST and is not listed\n")
    (app / "stvm.toml").write_text('[project]\nfiles = ["../lib/inc.st", "main.st"]\n')
    rc, out, err = cli(["run", app, "--cycles", "4", "--no-cache", "--print", "Main.n"])
    assert (rc, out) == (0, "Main.n = 4\n"), err
