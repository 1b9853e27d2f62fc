"""The README's commands for the robot libraries: `stvm run st_src/<library> --scan 1ms` runs each
library's Pick-and-Place demo against the bundled emulator (stvm/demo.py, the folder's manifest)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("library", ["cbt_v2", "rockwell", "kuka", "schneider", "schneider/oo"])
def test_library_demo_runs_one_pnp_cycle(tmp_path, library):
    log = tmp_path / "frames.jsonl"
    result = subprocess.run(
        [sys.executable, "-m", "stvm", "run", f"st_src/{library}", "--scan", "1ms", "--pnp-cycles", "1",
         "--emulator-log", str(log), "--print", "PnP_Example_Instance.Prg_Step"],
        cwd=ROOT, capture_output=True, text=True, timeout=180)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    assert "PnP cycles completed: 1" in result.stderr
    assert "PnP_Example_Instance.Prg_Step = 10" in result.stdout
    frames = [json.loads(line) for line in log.read_text().splitlines()]
    sent = [f["data"] for f in frames if f["dir"] == "rx"]
    replies = [f["data"] for f in frames if f["dir"] == "tx"]
    assert sent[0] == "$TMSTA,2,00,*41\r\n"
    moves = [s for s in sent if 'PTP("CPP",' in s]
    assert len(moves) >= 6
    assert not any(r.startswith("$CPERR") for r in replies), replies
    assert not any(",ERROR" in r for r in replies), replies
