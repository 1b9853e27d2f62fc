"""The README's first command: the thesis PnP demo against the bundled emulator (stvm/demo.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_demo_runs_one_pnp_cycle_against_the_bundled_emulator(tmp_path):
    log = tmp_path / "frames.jsonl"
    result = subprocess.run(
        [sys.executable, "-m", "stvm", "run", "st_src/PnP_Example.st", "--scan", "1ms", "--pnp-cycles", "1",
         "--emulator-log", str(log), "--print", "PnP_Example_Instance.Prg_Step", "--print", "Cobot.Connected"],
        cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    assert "PnP cycles completed: 1" in result.stderr
    # the cycle ended going from step 26 back to 10, still connected
    assert "PnP_Example_Instance.Prg_Step = 10" in result.stdout
    assert "Cobot.Connected = TRUE" in result.stdout
    frames = [json.loads(line) for line in log.read_text().splitlines()]
    sent = [f["data"] for f in frames if f["dir"] == "rx"]
    # the status query of CBT_Connect, then the six segments with command IDs 2..7, in order
    assert sent[0] == "$TMSTA,2,00,*41\r\n"
    moves = [s for s in sent if s.startswith("$TMSCT")]
    assert [m.split(",")[2] for m in moves[:6]] == ["2", "3", "4", "5", "6", "7"]
    assert all('PTP("CPP",' in m for m in moves[:6])
    replies = [f["data"] for f in frames if f["dir"] == "tx"]
    assert not any(r.startswith("$CPERR") for r in replies), replies
    # every segment was acknowledged with OK and its queue tag reported done
    for cmd_id in range(2, 8):
        assert any(r.startswith(f"$TMSCT,4,{cmd_id},OK,") for r in replies)
        assert any(f",01,{cmd_id:02d},true," in r for r in replies)


def test_demo_reports_a_robot_that_cannot_be_reached(tmp_path):
    # --robot names a port where nothing listens: CBT_Connect must end in an error, not a crash
    result = subprocess.run(
        [sys.executable, "-m", "stvm", "run", "st_src/PnP_Example.st", "--scan", "1ms", "--robot", "127.0.0.1:9",
         "--duration", "300ms", "--print", "Connect_Error", "--print", "Cobot.Connected",
         "--print", "Program_Example_Instance.CBT_Connect_Instance.ErrorID"],
        cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    assert "Cobot.Connected = FALSE" in result.stdout
    assert "Connect_Error = TRUE" in result.stdout
    # thesis error code 16#20: the socket connection failed (Table 5.3.1.4)
    assert "Program_Example_Instance.CBT_Connect_Instance.ErrorID = 32" in result.stdout


def test_demo_status_line_shows_the_connection_error():
    # the line-a-second view (stdout not a terminal) names the error, not only Connected=FALSE
    result = subprocess.run(
        [sys.executable, "-m", "stvm", "run", "st_src/PnP_Example.st", "--scan", "1ms", "--robot", "127.0.0.1:9",
         "--virtual-clock", "--duration", "2500ms"],
        cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert any("Cobot.Connected=FALSE" in line and "Connect_ErrorDescrip='Connection Error'" in line
               for line in lines), result.stdout


def test_demo_table_rows_include_the_error_variables():
    import stvm
    from stvm.demo import Demo
    project = stvm.load([ROOT / "st_src" / "PnP_Example.st"])
    vm = project.start(scan="1ms")

    class Args:
        scenario = robot = emulator_log = pnp_cycles = None
    demo = Demo(project, vm, Args())
    demo.robot_address = ("127.0.0.1", 9)
    vm["Connect_ErrorDescrip"] = "Connection Error"
    rows = dict(demo.status_rows())
    assert rows["Connect_ErrorDescrip"] == "'Connection Error'"
    assert demo.error_rows() == [("Connect_ErrorDescrip", "'Connection Error'")]
