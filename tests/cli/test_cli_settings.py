"""Sysmac settings through the `stvm` command line: `--sysmac NAME=VALUE` on check, run, trace and
debug, the `[sysmac]` table of `stvm.toml`, and a scenario's `[emulator] settings`. An unknown
name or value is a usage error (exit 2) that lists the allowed values; a good one changes the run."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from core_helpers import cli, write_files, write_st

ROOT = Path(__file__).resolve().parents[2]
PROGRAM = """
PROGRAM Main
VAR a : INT := 7; b : INT; q : INT := 5; END_VAR
q := a / b;
END_PROGRAM
"""
ALLOWED = "int_div_zero: 'zeroo' is not allowed; allowed: fault (default), zero"


def project(manifest: str | None, program: str = PROGRAM) -> Path:
    files = {"main.st": program}
    if manifest is not None:
        files["stvm.toml"] = manifest
    return write_files(files)[0]


@pytest.mark.parametrize("command", [
    ["check"], ["run", "--cycles", "1"], ["trace", "--cycles", "1", "-o", "OUT.jsonl"], ["debug"],
])
def test_every_command_rejects_a_bad_sysmac_value(command, tmp_path):
    path = write_st(PROGRAM)
    argv = [command[0], str(path), *[a.replace("OUT", str(tmp_path / "t")) for a in command[1:]]]
    rc, out, err = cli([*argv, "--sysmac", "int_div_zero=zeroo"])
    assert rc == 2 and ALLOWED in err and "Traceback" not in err, err


@pytest.mark.parametrize(("assignment", "message"), [
    ("int_div_zro=zero", "unknown Sysmac setting 'int_div_zro'; did you mean int_div_zero?"),
    ("int_div_zero", "--sysmac needs NAME=VALUE"),
    ("skt_send_max=-1", "skt_send_max: -1 is out of range; allowed: an integer 0..65535 (default 2000)"),
    ("skt_send_max=lots", "skt_send_max: 'lots' is not an integer"),
    ("skt_error_codes=1", "skt_error_codes is a table: set it in stvm.toml [sysmac.skt_error_codes]"),
])
def test_bad_names_and_numbers_are_usage_errors(assignment, message):
    rc, out, err = cli(["run", write_st(PROGRAM), "--cycles", "1", "--sysmac", assignment])
    assert rc == 2 and f"stvm: error: {message}" in err, err


def test_a_good_value_changes_the_run():
    path = write_st(PROGRAM)
    assert cli(["run", path, "--cycles", "1", "--no-cache"])[0] == 3              # the fault
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--sysmac", "int_div_zero=zero",
                        "--print", "Main.q"])
    assert (rc, out) == (0, "Main.q = 0\n"), err


def test_the_real_entry_point_rejects_a_bad_value():
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-m", "stvm", "run", str(write_st(PROGRAM)), "--cycles", "1",
                           "--sysmac", "int_div_zero=zeroo"], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 2 and ALLOWED in proc.stderr and "Traceback" not in proc.stderr


# ---- stvm.toml [sysmac] -----------------------------------------------------------------------------

def test_the_manifest_table_sets_the_project_and_the_command_line_wins():
    path = project('[sysmac]\nint_div_zero = "zero"\n')
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--print", "Main.q"])
    assert (rc, out) == (0, "Main.q = 0\n"), err
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache", "--sysmac", "int_div_zero=fault"])
    assert rc == 3 and "integer division by zero" in err


def test_the_manifest_table_reaches_the_python_api():
    import stvm
    path = project('[sysmac]\nint_div_zero = "zero"\n[sysmac.skt_error_codes]\ntimeout = 0x1234\n')
    settings = stvm.load([path], use_cache=False).settings
    assert settings.int_div_zero.value == "zero"
    assert settings.skt_error_codes["timeout"] == 0x1234 and settings.skt_error_codes["bad_handle"] == 0x2007


@pytest.mark.parametrize(("manifest", "message"), [
    ('[sysmac]\nint_div_zero = "zeroo"\n', "stvm.toml: [sysmac]: " + ALLOWED),
    ("[sysmac]\nskt_send_max = -1\n", "stvm.toml: [sysmac]: skt_send_max: -1 is out of range"),
    ('[sysmac]\nskt_send_max = "2000"\n', "skt_send_max: '2000' is not allowed; allowed: an integer 0..65535"),
    ("[sysmac]\nnope = 1\n", "stvm.toml: [sysmac]: unknown Sysmac setting 'nope'"),
    ("[sysmac.skt_error_codes]\ntimeout = -1\n", "skt_error_codes.timeout: -1 is not allowed"),
    ('sysmac = "lint"\n', "stvm.toml: [sysmac] must be a table of NAME = VALUE"),
    ("[sysmac\n", "stvm.toml: not valid TOML"),
])
@pytest.mark.parametrize("command", ["check", "run", "trace", "debug"])
def test_bad_manifest_values_are_usage_errors_naming_the_file(manifest, message, command, tmp_path):
    path = project(manifest)
    extra = {"run": ["--cycles", "1"], "trace": ["--cycles", "1", "-o", str(tmp_path / "t.jsonl")]}.get(command, [])
    rc, out, err = cli([command, path, *extra])
    assert rc == 2 and message in err and "Traceback" not in err, err


# ---- a scenario's [emulator] settings ------------------------------------------------------------------

@pytest.mark.parametrize("command", ["run", "trace"])
def test_bad_scenario_emulator_settings_are_usage_errors(command, tmp_path):
    scenario = tmp_path / "s.toml"
    scenario.write_text("[emulator]\nsettings = { time_scale = -1 }\n", encoding="utf-8")
    extra = ["--cycles", "1"] + (["-o", str(tmp_path / "t.jsonl")] if command == "trace" else [])
    rc, out, err = cli([command, write_st(PROGRAM.replace("q := a / b;", "")), *extra, "--scenario", scenario])
    assert rc == 2, err
    assert "[emulator] settings: time_scale: -1 is not allowed; allowed: a number > 0" in err
