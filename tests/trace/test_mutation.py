"""A deliberately mutated FB is caught by the PnP golden, with a report that names the right
scan and variable (and the ST line that last wrote it)."""

from __future__ import annotations

import shutil

from trace_helpers import GOLDEN, SCENARIOS, THESIS
from stvm.trace import TraceSpec, compare, locate_writer, read_trace, render_report, run_trace

SUPERVISION = "Program_Example_Instance.CBT_Connect_Instance.FB_step"


def test_changed_constant_in_cbt_connect_is_caught(tmp_path):
    source = tmp_path / "st_src"
    shutil.copytree(THESIS, source, ignore=shutil.ignore_patterns("scenarios"))
    connect = source / "CBT_Connect.st"
    text = connect.read_text(encoding="utf-8")
    original = "Timer_1(In:=Timer_1_Enable, PT:=T#1000ms, Q=>Timer_1_Done);"
    assert text.count(original) == 1
    connect.write_text(text.replace(original, original.replace("T#1000ms", "T#1500ms")), encoding="utf-8")

    golden = read_trace(GOLDEN / "pnp_cycle.jsonl")
    # the golden's first supervision round: FB_step 90 -> 80 one period after connecting
    index = golden.index_of(SUPERVISION)
    scans, values = golden.series(index)
    first_round = next(s for s, v, prev in zip(scans[1:], values[1:], values) if (prev, v) == ("90", "80"))

    spec = TraceSpec([source / "PnP_Example.st"], scenario=SCENARIOS / "golden_pnp_cycle.toml", cycles=first_round + 50)
    run = run_trace(spec)
    divergence = compare(golden, run.trace)
    assert divergence is not None
    assert (divergence.scan, divergence.variable) == (first_round, SUPERVISION)
    assert (divergence.expected, divergence.actual) == ("80", "90")
    divergence.writer = locate_writer(spec, run.trace, divergence, run.project)
    report = render_report(divergence, golden, run.trace, context=3, golden_name="pnp_cycle.jsonl")
    assert f"first divergence at scan {first_round}" in report
    assert f"variable: {SUPERVISION}" in report
    # FB_step last became 90 in the connect sequence (step 80 -> 90), in the copied CBT_Connect.st
    assert divergence.writer is not None and divergence.writer.span is not None
    assert divergence.writer.span.file.endswith("CBT_Connect.st")
    assert "FB_step:=90" in divergence.writer.source_line.replace(" ", "")
    assert report.count("\n") >= 8  # header, 4 lines, context title, column header, 4 scans


def test_unchanged_copy_matches(tmp_path):
    source = tmp_path / "st_src"
    shutil.copytree(THESIS, source, ignore=shutil.ignore_patterns("scenarios"))
    spec = TraceSpec([source / "PnP_Example.st"], scenario=SCENARIOS / "golden_moveabs_ok.toml")
    assert compare(read_trace(GOLDEN / "moveabs_ok.jsonl"), run_trace(spec).trace) is None
