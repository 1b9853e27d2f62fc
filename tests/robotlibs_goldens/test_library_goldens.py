"""Golden traces of the robot libraries (st_src/<library>/scenarios/golden_*.toml ->
tests/golden/<library>_*.jsonl): each library's demo program on its normal path (one PnP cycle) and
its error paths (connection lost mid-motion, a command the robot refuses, a parameter out of range,
for V2 also a robot outside its Listen node). `pytest --update-goldens tests/robotlibs_goldens`
rewrites them after an intended change."""

from __future__ import annotations

from functools import lru_cache

import pytest

from robotlibs_helpers import REPO, ST_SRC
from stvm.trace import TraceSpec, read_trace

LIBRARIES = ("cbt_v2", "rockwell", "kuka", "schneider")
CASES = sorted((lib, p.stem.removeprefix("golden_")) for lib in LIBRARIES
               for p in (ST_SRC / lib / "scenarios").glob("golden_*.toml"))
GOLDEN = REPO / "tests" / "golden"


@lru_cache(maxsize=None)
def project(library: str):
    from stvm.project import load
    return load([ST_SRC / library])


def test_every_library_has_normal_and_error_goldens():
    for lib in LIBRARIES:
        names = {name for l, name in CASES if l == lib}
        assert "pnp_cycle" in names and "fault_drop" in names and "fault_rejected" in names
        assert any(n.startswith("param") for n in names)


@pytest.mark.parametrize(("library", "name"), CASES, ids=[f"{l}-{n}" for l, n in CASES])
def test_golden(library, name, golden_trace):
    spec = TraceSpec([ST_SRC / library], scenario=ST_SRC / library / "scenarios" / f"golden_{name}.toml")
    golden_trace.check(f"{library}_{name}", spec, project=project(library))


def final(trace, signal: str) -> str:
    return trace.value_at(trace.index_of(signal), trace.scans - 1)


def values(trace, signal: str) -> list[str]:
    return trace.series(trace.index_of(signal))[1]


def test_goldens_show_what_they_are_about():
    t = read_trace(GOLDEN / "cbt_v2_pnp_cycle.jsonl")
    assert final(t, "PnP_Cycles") == "1" and "TRUE" not in values(t, "PnP_MoveError")
    t = read_trace(GOLDEN / "cbt_v2_fault_drop.jsonl")
    assert final(t, "Connect_ErrorID") == "144" and final(t, "PnP_MoveErrorID") == "153"    # 16#90, 16#99
    assert final(t, "Cobot.WaitingReturn") == "FALSE"
    t = read_trace(GOLDEN / "cbt_v2_fault_rejected.jsonl")
    assert final(t, "PnP_MoveErrorDescrip") == "'Command rejected: ERROR;1'"
    t = read_trace(GOLDEN / "cbt_v2_not_in_node.jsonl")
    assert final(t, "Connect_ErrorID") == "112"                                             # 16#70
    t = read_trace(GOLDEN / "cbt_v2_param_range.jsonl")
    assert final(t, "PnP_MoveErrorID") == "38" and not any(f.data.startswith("$TMSCT") for f in t.frames)
    t = read_trace(GOLDEN / "rockwell_pnp_cycle.jsonl")
    assert final(t, "PnP_Example_Instance.Cycles") == "1"
    # 0 between the pick and the place path (nothing executes: issue 31 item 3)
    assert [v for v in values(t, "Robot.Sts.ActiveMoveID") if v != "0"][:6] == ["101", "102", "103", "104", "105", "106"]
    t = read_trace(GOLDEN / "rockwell_fault_drop.jsonl")
    assert final(t, "PnP_Example_Instance.Pick.Sts_ERR") == "1002" and final(t, "Robot.Sts.Faulted") == "TRUE"
    t = read_trace(GOLDEN / "rockwell_fault_rejected.jsonl")
    assert final(t, "PnP_Example_Instance.Pick.Sts_ERR") == "1044"
    t = read_trace(GOLDEN / "rockwell_param_first_move.jsonl")
    assert final(t, "PnP_Example_Instance.Pick.Sts_ERR") == "1013"
    t = read_trace(GOLDEN / "kuka_pnp_cycle.jsonl")
    assert final(t, "PnP_Example_Instance.Cycles") == "1"
    t = read_trace(GOLDEN / "kuka_fault_drop.jsonl")
    assert final(t, "PnP_Example_Instance.ErrorID") == "10153"
    t = read_trace(GOLDEN / "kuka_fault_rejected.jsonl")
    assert final(t, "PnP_Example_Instance.ErrorID") == "10128"
    t = read_trace(GOLDEN / "kuka_param_velocity.jsonl")
    assert final(t, "PnP_Example_Instance.ErrorID") == "510"
    t = read_trace(GOLDEN / "schneider_pnp_cycle.jsonl")
    assert final(t, "PnP_Example_Instance.Cycles") == "1"
    assert values(t, "Robot.udiCurrentSegmentId")[:9] == ["0", "1", "2", "3", "0", "4", "5", "6", "0"]
    t = read_trace(GOLDEN / "schneider_fault_drop.jsonl")
    assert final(t, "PnP_Example_Instance.ErrorDiagExt") == "ET_DiagExt#InterfaceInvalid"
    t = read_trace(GOLDEN / "schneider_fault_rejected.jsonl")
    assert final(t, "PnP_Example_Instance.ErrorDiagExt") == "ET_DiagExt#UnexpectedFeedback"
    assert final(t, "PnP_Example_Instance.ErrorSegment") == "2"
    t = read_trace(GOLDEN / "schneider_param_velocity.jsonl")
    assert final(t, "PnP_Example_Instance.ErrorDiagExt") == "ET_DiagExt#CommandRefused"
    assert not any("PTP" in f.data for f in t.frames)
