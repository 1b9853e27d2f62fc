"""``tm-emulator`` / ``python -m emulator`` command line."""

from __future__ import annotations

import json
import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from emulator.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_cli_prints_port_and_logs_frames(tmp_path: Path) -> None:
    log = tmp_path / "frames.jsonl"
    proc = subprocess.Popen([sys.executable, "-m", "emulator", "--port", "0", "--log", str(log), "--quiet",
                             "--duration", "20"], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        match = re.fullmatch(r"tm-emulator listening on 127\.0\.0\.1:(\d+)\n", line)
        assert match, line
        with socket.create_connection(("127.0.0.1", int(match.group(1))), timeout=5) as sock:
            sock.sendall(b"$TMSTA,2,00,*41\r\n")
            assert sock.recv(100) == b"$TMSTA,15,00,true,Listen1,*79\r\n"
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and len(log.read_text().splitlines()) < 2:
            time.sleep(0.02)
        records = [json.loads(x) for x in log.read_text().splitlines()]
        assert [(r["dir"], r["data"]) for r in records] == [("rx", "$TMSTA,2,00,*41\r\n"),
                                                            ("tx", "$TMSTA,15,00,true,Listen1,*79\r\n")]
        assert all(isinstance(r["t"], float) for r in records)
    finally:
        proc.terminate()
        proc.wait(10)


def test_cli_rejects_unknown_fault(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--fault", "nonsense", "--port", "0"]) == 2
    assert "unknown fault" in capsys.readouterr().err


def test_cli_rejects_unknown_setting(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--set", "nope=1", "--port", "0"]) == 2


def test_cli_runs_with_faults_and_settings(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--port", "0", "--quiet", "--duration", "0.2", "--fault", "delay:5", "--fault", "busy",
                 "--set", "accept_one_digit_checksum=true", "--set", "known_bases=RobotBase,Base1"]) == 0
    out = capsys.readouterr().out
    assert "listening on 127.0.0.1:" in out and "reply_delay_ms=5" in out


@pytest.mark.parametrize("host", ["", "  "])
def test_cli_refuses_an_empty_host_instead_of_every_interface(host: str, capsys: pytest.CaptureFixture[str]) -> None:
    """`--host ''` (an unset shell variable) bound every interface silently (issue 34 item 8)."""
    with pytest.raises(SystemExit) as exit_info:
        main(["--host", host, "--port", "0", "--quiet", "--duration", "0"])
    assert exit_info.value.code == 2
    assert "needs an address to listen on" in capsys.readouterr().err


def test_cli_warns_when_listening_on_every_interface(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--host", "0.0.0.0", "--port", "0", "--quiet", "--duration", "0"]) == 0
    captured = capsys.readouterr()
    assert "listening on 0.0.0.0:" in captured.out
    assert "warning: listening on every network interface" in captured.err
