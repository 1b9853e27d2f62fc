"""stvm/frontend/limits.py: one table of limits, units and read-only status for every front end."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import stvm
from stvm.frontend.limits import LimitTable, LimitsError

THESIS = Path(__file__).resolve().parents[2] / "st_src" / "PnP_Example.st"


@pytest.fixture(scope="module")
def thesis_table():
    project = stvm.load([str(THESIS)])
    vm = project.start(scan="1ms")
    yield LimitTable.for_project(project, vm)
    vm.close()


def test_the_chapter_5_ranges_come_from_the_limits_file(thesis_table):
    speed = thesis_table.limits_for("MoveAbs_Param.Speed")
    assert (speed.min, speed.max, speed.unit, speed.writable) == (0, 4500, "% | mm/s", True)
    assert thesis_table.check("MoveAbs_Param.Speed", 9000) == "9000 is above the maximum 4500 % | mm/s"
    assert thesis_table.check("MoveAbs_Param.Speed", 50) is None


def test_positions_have_a_range_and_non_finite_values_are_refused(thesis_table):
    x = thesis_table.limits_for("MoveAbs_Param.TargetPosition.X")
    assert (x.min, x.max, x.unit, x.decimals) == (-1000, 1000, "mm", 2)
    assert "above the maximum 1000 mm" in thesis_table.check("MoveAbs_Param.TargetPosition.X", 99999999.0)
    assert thesis_table.check("MoveAbs_Param.TargetPosition.X", math.nan) == "not a finite number"
    assert thesis_table.check("MoveAbs_Param.TargetPosition.X", math.inf) == "not a finite number"
    # an exact path wins over the pattern: a relative move may cross the work space
    assert thesis_table.limits_for("MoveRel_Param.TargetPosition.X").max == 2000
    # `[` in a path is an index, not a pattern's character class
    assert thesis_table.limits_for("PnP_MoveParameters[3].Speed").max == 4500


def test_outputs_and_status_are_read_only(thesis_table):
    for path in ("MoveRel_Busy", "MoveRel_Done", "Connect_Error", "MoveAbs_CmdID_Ack",
                 "Cobot.Connected", "Cobot.Socket.Handle", "PnP_Example_Instance.Prg_Step"):
        assert not thesis_table.limits_for(path).writable, path
        assert thesis_table.check(path, 1) == "read-only (an output or status)"
    for path in ("MoveRel_Execute", "Connect_AddressIP", "MoveAbs_Param.Speed"):
        assert thesis_table.limits_for(path).writable, path


def test_the_type_gives_enumerations_and_integer_ranges(thesis_table):
    assert thesis_table.limits_for("MoveRel_Param.MovementCommand").enum == ("Line", "PTP")
    port = thesis_table.limits_for("Connect_Dest_PortIP")
    assert (port.min, port.max) == (1, 32767)   # declared 1..65535, an INT holds 32767


def test_a_declared_range_never_widens_the_type():
    table = LimitTable({"x": {"min": -5, "max": 1e9}}, type_of=lambda p: stvm_uint())
    lim = table.limits_for("x")
    assert (lim.min, lim.max) == (0, 65535)


def stvm_uint():
    from stvm.semantics import types as t
    return t.UINT


def test_page_limits_merge_the_stricter_bound():
    class PageLimits:
        def __init__(self, lo, hi):
            self.min, self.max, self.options, self.by, self.unit = lo, hi, None, ("pgX: Speed",), "mm/s"
    table = LimitTable({"Speed": {"min": 0, "max": 4500}})
    table.merge_pages({"Speed": PageLimits(10, 5000)})
    lim = table.limits_for("speed")
    assert (lim.min, lim.max, lim.unit, lim.by) == (10, 4500, "mm/s", "pgX: Speed")


@pytest.mark.parametrize("entry, message", [
    ({"min": "0"}, "min must be a finite number"),
    ({"max": math.nan}, "max must be a finite number"),
    ({"min": 5, "max": 1}, "min 5 is greater than max 1"),
    ({"colour": "red"}, "unknown key(s) colour"),
    ({"decimals": 12}, "decimals must be an integer 0..9"),
    ({"writable": "no"}, "writable must be true or false"),
    ("fast", "the value is a table"),
])
def test_mistakes_in_a_limits_table_are_reported_with_their_key(entry, message):
    with pytest.raises(LimitsError) as err:
        LimitTable({"Main.Speed": entry}, where="limits.toml")
    assert message in str(err.value)
    assert "limits.toml 'Main.Speed'" in str(err.value)


def test_a_limits_table_in_the_manifest_is_read(tmp_path):
    (tmp_path / "main.st").write_text("PROGRAM Main VAR Speed : UINT; Out : BOOL; END_VAR Out := Speed > 5; END_PROGRAM\n")
    (tmp_path / "stvm.toml").write_text('[project]\nfiles = ["main.st"]\n\n[limits]\n'
                                        '"Main.Speed" = { min = 1, max = 90, unit = "mm/s", writable = true }\n')
    project = stvm.load([str(tmp_path / "main.st")])
    vm = project.start(scan="1ms")
    table = LimitTable.for_project(project, vm)
    lim = table.limits_for("main.speed")
    assert (lim.min, lim.max, lim.unit, lim.writable) == (1, 90, "mm/s", True)   # an exact entry opens a VAR
    assert not table.limits_for("Main.Out").writable                              # a program's VAR: status
    vm.close()


def test_status_names_are_read_only_in_any_project_and_the_switch_opens_them():
    from stvm.semantics import types as t
    table = LimitTable({}, type_of=lambda p: t.BOOL)
    for path in ("Connect_Busy", "Move_Done", "Move_Error", "Move_ErrorID", "Move_ErrorDescrip",
                 "Robot.Connected", "Robot.Socket.Handle", "Move_CmdID_Ack"):
        assert not table.limits_for(path).writable, path
    assert table.limits_for("Move_Execute").writable
    # a declared entry wins over the built-in names
    table.declare("Connect_Busy", {"writable": True})
    assert table.limits_for("Connect_Busy").writable
    opened = LimitTable({"@outputs": {"writable": True}}, type_of=lambda p: t.BOOL)
    assert opened.limits_for("Robot.Connected").writable
    with pytest.raises(LimitsError, match="only writable"):
        LimitTable({"@outputs": {"min": 1}})


def test_set_reads_the_limits_table(tmp_path):
    import subprocess
    import sys
    def run(assignment):
        return subprocess.run([sys.executable, "-m", "stvm", "run", str(THESIS), "--no-demo", "--cycles", "1",
                               "--set", assignment, "--print", assignment.split("=")[0]],
                              capture_output=True, text=True, timeout=120)
    refused = run("MoveAbs_Param.Speed=9000")
    assert refused.returncode == 2
    assert "--set MoveAbs_Param.Speed: 9000 is above the maximum 4500 % | mm/s" in refused.stderr
    assert "Traceback" not in refused.stderr
    far = run("MoveAbs_Param.TargetPosition.X=1e30")
    assert far.returncode == 2 and "1e+30 is above the maximum 1000 mm" in far.stderr
    ok = run("MoveAbs_Param.Speed=90")
    assert ok.returncode == 0 and "MoveAbs_Param.Speed = 90" in ok.stdout
