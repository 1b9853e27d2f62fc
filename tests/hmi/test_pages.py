"""Page files: every widget kind is read; every mistake is a FILE:LINE:COL error, never a traceback."""

from __future__ import annotations

import subprocess
import sys

import pytest

import stvm
from small_project import TEST_PAGE, write_project
from stvm.frontend import VariableBridge
from stvm.hmi import HmiLoadError, load_pages
from stvm.hmi.cli import page_files
from stvm.hmi.pages import WIDGET_KINDS


def load(tmp_path, page_text: str):
    main = write_project(tmp_path, page_text)
    project = stvm.load([str(main)])
    bridge = VariableBridge(project.start(scan="1ms"))
    files, start = page_files(project)
    return load_pages(files, bridge.type_of, start)


def errors(tmp_path, page_text: str) -> str:
    with pytest.raises(HmiLoadError) as exc:
        load(tmp_path, page_text)
    return exc.value.render()


def test_every_widget_kind_is_read(tmp_path):
    hmi = load(tmp_path, TEST_PAGE)
    page = hmi.pages["Test"]
    kinds = {w.kind for w in page.widgets()}
    assert kinds == set(WIDGET_KINDS)
    assert [p.id for p in page.popups] == ["Axis-X", "Axis-Y"]
    assert [w.var for w in page.popups[1].widgets] == ["Target.Y"]
    # only widgets that write make a variable writable; a lamp or a status does not
    assert set(hmi.writable) == {"Speed", "Gain", "M", "Pose", "Name", "Start", "Hold", "Target.X", "Target.Y"}
    assert hmi.writable["Speed"].min == 10 and hmi.writable["Speed"].max == 100
    assert hmi.writable["Pose"].options == (0, 1)
    assert hmi.presets["Pulse"].steps == ((("Hold", "FALSE"),), (("Hold", "TRUE"),))
    assert hmi.presets["Defaults"].steps[0] == (("Speed", "20"), ("Gain", "1.5"), ("Name", "'hello'"), ("M", "Run"))
    assert "Target.Z" in page.paths   # robot-view targets are published with their X, Y, Z
    assert hmi.start == "Main"


def replace(old: str, new: str) -> str:
    assert old in TEST_PAGE
    return TEST_PAGE.replace(old, new, 1)


def line_of(text: str, needle: str) -> int:
    return text.splitlines().index(needle) + 1


@pytest.mark.parametrize("old, new, needle, message", [
    ('var = "Speed"\nlabel = "Speed"', 'var = "Sped"\nlabel = "Speed"', 'var = "Sped"', "unknown variable path 'Sped'"),
    ('kind = "lamp"', 'kind = "lmap"', 'kind = "lmap"', "unknown widget kind 'lmap'"),
    ('min = 10\nmax = 100', 'min = 100\nmax = 10', "max = 10", "min 100 is greater than max 10"),
    ('var = "Lamp"', 'var = "Speed"', 'var = "Speed"', "wrong type: a lamp widget needs a BOOL variable, Speed is UINT"),
    ('kind = "text"\nvar = "Name"', 'kind = "text"\nvar = "Count"', 'var = "Count"', "a text widget needs a STRING"),
    ('unit = "%"', 'unit = "%"\nmaxx = 3', "maxx = 3", "unknown key 'maxx' in a numeric widget"),
    ('page = "Main"', 'page = "Mian"', 'page = "Mian"', "no page named 'Mian'"),
    ('preset = "Defaults"', 'preset = "Dfaults"', 'preset = "Dfaults"', "no preset named 'Dfaults'"),
    ("Speed = 20", "Speed = 200", "Speed = 200", "preset value 200 for Speed: 200 is above the maximum 100"),
    ('M = "Run"', 'M = "Walk"', 'M = "Walk"', "wrong type: Walk cannot be written to M (Mode)"),
    ('min = 10\n', 'min = "ten"\n', 'min = "ten"', "min must be a number"),
    ('min = 10\n', 'min = -1\n', "min = -1", "min -1 is outside UINT (0..65535)"),
    ('var = "Target.{n}"', 'var = "Target.{n}{n}"', 'var = "Target.{n}{n}"', "unknown variable path 'Target.XX' (popup instance X)"),
    ('var = "Lamp"', 'var = "Target"', 'var = "Target"', "Target is a Pt: map its elementary members"),
    ('targets = ["Target"]', 'targets = ["Speed"]', 'targets = ["Speed"]', "robot view target 'Speed' needs a member X"),
    ('instance = "X"', 'instance = "Q"', 'popup = "Axis"', "no popup 'Axis-Q' on this page"),
])
def test_mistakes_are_reported_at_their_line(tmp_path, old, new, needle, message):
    text = replace(old, new)
    report = errors(tmp_path, text)
    first = report.splitlines()[0]
    assert first.startswith(f"{tmp_path / 'hmi' / 'Test.toml'}:{line_of(text, needle)}:"), report
    assert message in first, report
    assert ": error: " in first and "Traceback" not in report


def test_toml_syntax_error_has_line_and_column(tmp_path):
    text = replace('label = "Running"', 'label = "Running')
    report = errors(tmp_path, text)
    line = line_of(text, 'label = "Running')
    assert report.startswith(f"{tmp_path / 'hmi' / 'Test.toml'}:{line}:")
    assert "TOML syntax" in report


def test_all_mistakes_of_a_file_are_reported_at_once(tmp_path):
    text = replace('kind = "lamp"', 'kind = "lmap"').replace('var = "Gain"', 'var = "Gian"')
    report = errors(tmp_path, text)
    assert report.count(": error: ") == 2


def test_duplicate_page_name(tmp_path):
    report = errors(tmp_path, TEST_PAGE.replace('name = "Test"', 'name = "Main"', 1))
    assert "page 'Main' is defined twice" in report


def run_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "stvm", *args], capture_output=True, text=True, timeout=120, cwd=cwd)


def test_cli_page_error_exits_1_with_location(tmp_path):
    main = write_project(tmp_path, replace('kind = "lamp"', 'kind = "lmap"'))
    result = run_cli("run", str(main), "--cycles", "5", "--hmi", "127.0.0.1:0")
    assert result.returncode == 1, result.stderr
    assert "Test.toml:" in result.stderr and "unknown widget kind 'lmap'" in result.stderr
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize("option, message", [("127.0.0.1:http", "--hmi needs [HOST:]PORT"),
                                             ("70000", "--hmi needs [HOST:]PORT")])
def test_cli_bad_hmi_option_exits_2(tmp_path, option, message):
    main = write_project(tmp_path)
    result = run_cli("run", str(main), "--cycles", "5", "--hmi", option)
    assert result.returncode == 2 and message in result.stderr, result.stderr


def test_cli_project_without_pages_exits_2(tmp_path):
    (tmp_path / "p.st").write_text("PROGRAM P\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n")
    result = run_cli("run", str(tmp_path / "p.st"), "--cycles", "5", "--hmi", "0")
    assert result.returncode == 2 and "no HMI pages" in result.stderr, result.stderr


def test_cli_port_in_use_exits_2(tmp_path):
    import socket
    main = write_project(tmp_path)
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        result = run_cli("run", str(main), "--cycles", "5", "--hmi", str(port))
    assert result.returncode == 2 and "cannot listen" in result.stderr, result.stderr


def test_cli_run_serves_and_exits_cleanly(tmp_path):
    main = write_project(tmp_path)
    result = run_cli("run", str(main), "--cycles", "200", "--hmi", "127.0.0.1:0", "--print", "Count")
    assert result.returncode == 0, result.stderr
    assert "HMI: http://127.0.0.1:" in result.stderr and "token" not in result.stderr
    assert "Count = 200" in result.stdout


@pytest.mark.parametrize("bound", ["nan", "inf", "-inf", "1e300"])
def test_non_finite_or_absurd_limits_are_errors_not_exit_70(tmp_path, bound):
    page = TEST_PAGE.replace("min = 10\nmax = 100", f"min = {bound}\nmax = 100", 1)
    assert f"min = {bound}" in page
    report = errors(tmp_path, page)
    assert "Test.toml:" in report and "min must be a finite number" in report
    result = run_cli("run", str(tmp_path / "main.st"), "--cycles", "5", "--hmi", "127.0.0.1:0")
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr and "a bug in stvm" not in result.stderr


def test_a_page_file_larger_than_the_limit_is_refused(tmp_path):
    from stvm.hmi.pages import MAX_PAGE_FILE_BYTES
    page = TEST_PAGE + "\n# " + "x" * MAX_PAGE_FILE_BYTES + "\n"
    report = errors(tmp_path, page)
    assert f"HMI page file larger than {MAX_PAGE_FILE_BYTES} bytes" in report
