"""Trace files by suffix: JSON lines and CSV read back exactly; VCD and WaveDrom are
deterministic and well-formed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from stvm.trace import TraceSpec, read_trace, run_trace, write_trace
from stvm.trace.golden import compare
from stvm.trace.model import escape_frame, unescape_frame
from stvm.trace.writers import TraceFormatError, to_csv, to_jsonl, to_vcd, to_wavedrom

ST = Path(__file__).parent / "st"
THESIS = Path(__file__).resolve().parents[2] / "st_src"


@pytest.fixture(scope="module")
def counter_trace():
    return run_trace(TraceSpec([ST / "counter.st"], cycles=12, watch=["Main.*"])).trace


@pytest.fixture(scope="module")
def robot_trace(thesis_project):
    spec = TraceSpec([THESIS / "PnP_Example.st"], scenario=THESIS / "scenarios" / "golden_moveabs_ok.toml")
    return run_trace(spec, thesis_project).trace


@pytest.mark.parametrize("suffix", [".jsonl", ".csv"])
def test_round_trip(tmp_path, robot_trace, suffix):
    path = write_trace(robot_trace, tmp_path / f"t{suffix}")[0]
    back = read_trace(path)
    assert compare(robot_trace, back) is None
    assert back.initial == robot_trace.initial and back.changes == robot_trace.changes
    assert [f.text() for f in back.frames] == [f.text() for f in robot_trace.frames]


def test_jsonl_layout(robot_trace):
    lines = [json.loads(line) for line in to_jsonl(robot_trace).splitlines()]
    assert lines[0]["format"] == "stvm-trace" and lines[0]["scans"] == robot_trace.scans
    assert lines[1]["scan"] == 0 and len(lines[1]["values"]) == len(robot_trace.signals)
    frames = [line for line in lines if "frame" in line]
    assert frames[0]["data"] == "$TMSTA,2,00,*41\r\n" and frames[0]["frame"] == "rx"
    scans = [line["scan"] for line in lines[1:]]
    assert scans == sorted(scans)


def test_csv_rows_are_change_points_with_full_state(counter_trace):
    rows = to_csv(counter_trace).splitlines()
    assert rows[0].startswith("scan,t_ns,Main.counter,Main.flag")
    assert len(rows) == 1 + 12           # the counter changes every scan
    assert rows[6].split(",")[3] == "TRUE"   # scan 5: flag


def test_vcd_is_deterministic_and_typed(robot_trace, counter_trace):
    text = to_vcd(robot_trace)
    assert text == to_vcd(robot_trace)
    assert "$date" not in text and "$timescale 1 ns $end" in text
    assert "$var wire 1" in text and "$var integer 16" in text and "$var string" in text
    assert "$scope module emulator $end" in text
    counter = to_vcd(counter_trace)
    assert "$var real 64" in counter
    from vcd.reader import TokenKind, tokenize
    import io
    kinds = {token.kind for token in tokenize(io.BytesIO(text.encode()))}
    assert TokenKind.CHANGE_TIME in kinds


def test_wavedrom_lanes(robot_trace):
    doc = to_wavedrom(robot_trace, max_columns=12)
    lanes = {lane["name"]: lane for lane in doc["signal"]}
    assert lanes["scan"]["data"][0] == "0"
    width = len(lanes["scan"]["wave"])
    assert width == 12 and all(len(lane["wave"]) == width for lane in doc["signal"])
    assert set(lanes["MoveAbs_Busy"]["wave"]) <= {"0", "1", "."}
    assert "robot rx" in lanes and "foot" in doc


def test_svg_with_wavedrom(tmp_path, robot_trace):
    written = write_trace(robot_trace, tmp_path / "w.json", svg=True, max_columns=20)
    assert written[1].suffix == ".svg" and written[1].read_text().lstrip().startswith("<?xml")


def test_frame_escapes_round_trip():
    data = "$TMSCT,9,2,ERROR;1,*04\r\n\x01"
    assert escape_frame(data) == "$$TMSCT,9,2,ERROR;1,*04$R$L$01"
    assert unescape_frame(escape_frame(data)) == data


def test_unknown_suffix_and_bad_files(tmp_path, counter_trace):
    with pytest.raises(TraceFormatError):
        write_trace(counter_trace, tmp_path / "x.txt")
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"format": "other"}\n')
    with pytest.raises(TraceFormatError, match="not a stvm trace"):
        read_trace(bad)
    with pytest.raises(TraceFormatError, match="golden traces are"):
        read_trace(tmp_path / "x.vcd")
