"""`stvm trace … -o path.svg|.png`: the robot's TCP path of a recorded lockstep run as a picture."""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from stvm.trace.tcp_path import TcpPathRecorder

ROOT = Path(__file__).resolve().parents[2]


def trace(*args):
    return subprocess.run([sys.executable, "-m", "stvm", "trace", str(ROOT / "st_src" / "PnP_Example.st"), *args],
                          capture_output=True, text=True, timeout=300)


def test_move_absolute_path_as_svg_and_png(tmp_path):
    scenario = str(ROOT / "st_src" / "scenarios" / "golden_moveabs_ok.toml")
    first, second = tmp_path / "a.svg", tmp_path / "b.svg"
    result = trace("--scenario", scenario, "-o", str(first), "-o", str(tmp_path / "a.png"), "-o", str(tmp_path / "t.jsonl"))
    assert result.returncode == 0, result.stderr
    svg = first.read_text()
    root = ET.fromstring(svg)               # well-formed SVG
    assert root.tag.endswith("svg")
    assert "top view (X-Y)" in svg and "front view (Y-Z)" in svg and "1 stop points" in svg
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "t.jsonl").exists()  # trace files and pictures in one run
    assert trace("--scenario", scenario, "-o", str(second)).returncode == 0
    assert second.read_text() == svg        # the same run draws the same file


def test_unknown_suffix_still_a_usage_error(tmp_path):
    result = trace("--scenario", str(ROOT / "st_src" / "scenarios" / "golden_moveabs_ok.toml"), "-o", str(tmp_path / "x.pdf"))
    assert result.returncode == 2 and ".svg" in result.stderr


def test_stops_are_distinct_points_where_a_motion_ended():
    recorder = TcpPathRecorder(transport=None)
    recorder.points = [(0, 0, 0, 0, False), (1, 1, 0, 0, True), (2, 2, 0, 0, False),     # stop at x=2
                       (3, 3, 0, 0, True), (4, 5, 0, 0, False), (5, 4, 0, 0, True),      # stop at x=5
                       (6, 2.5, 0, 0, False)]                                           # x=2 again
    assert recorder.stops() == [(2, 0, 0), (5, 0, 0)]
