"""`emulator/settings.py`: every setting declares its allowed values once, values from Python,
``tm-emulator --set`` and a scenario's ``[emulator] settings`` are checked against it, and the
meta-tests hold the emulator to the declarations:

* every setting is read somewhere in the emulator outside its declaration;
* every setting's alternative changes what a client of the robot observes: `PROBES` runs each
  probe (a client talking to the pure `Robot`) under the defaults and under `ALTERNATIVES[name]`;
  the two transcripts must differ;
* docs/emulator.md's settings table gives each setting's real default and allowed values.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from enum import Enum
from pathlib import Path
from typing import Any, Callable

import pytest

from emulator.cli import main
from emulator.framing import ListenNodeFramer, checksum, decode_all, encode
from emulator.robot import Robot, Send
from emulator.settings import (
    DEFAULT_SETTINGS, AfterExit, EmulatorSettings, SettingError, declarations, parse_setting_assignment,
)

ROOT = Path(__file__).resolve().parents[2]
MS = 1_000_000
S = 1_000_000_000
DECLARED = {d.name: d for d in declarations()}


# ---- a client of the pure robot -----------------------------------------------------------------

class Client:
    """Frames in, a transcript of everything the robot sends (and closes) out."""

    def __init__(self, settings: EmulatorSettings) -> None:
        self.robot = Robot(settings)
        self.framer = ListenNodeFramer(settings)
        self.t = 0
        self.log: list[Any] = []

    def _record(self, actions) -> None:
        for action in actions:
            self.log.append(action.data if isinstance(action, Send) else ("close", action.conn))

    def at(self, t_ns: int) -> "Client":
        self.t = t_ns
        self._record(self.robot.advance(t_ns))
        return self

    def connect(self, conn: int = 1) -> "Client":
        self._record(self.robot.connect(conn, self.t))
        return self

    def send(self, wire: bytes, conn: int = 1) -> "Client":
        for result in decode_all(self.framer, wire)[0]:
            self._record(self.robot.handle(conn, result, self.t))
        return self

    def sct(self, data: str, conn: int = 1) -> "Client":
        return self.send(encode("TMSCT", data), conn)

    def sta(self, data: str, conn: int = 1) -> "Client":
        return self.send(encode("TMSTA", data), conn)

    def tag_time(self, script: str, step_ns: int = 5 * MS, limit_ns: int = 60 * S) -> int:
        """When `QueueTag(1)` at the end of `script` is reached (ns after sending)."""
        start = self.t
        self.sct("1," + script + "\r\nQueueTag(1)")
        while self.t - start < limit_ns:
            if any(isinstance(x, bytes) and x.startswith(b"$TMSTA,10,01,01,true") for x in self.log):
                return self.t - start
            self.at(self.t + step_ns)
        return -1


def raw(body: str, cs: str | None = None) -> bytes:
    """`$body*CS\\r\\n` with the checksum as given (default: correct, two upper-case digits)."""
    data = body.encode()
    return b"$" + data + b"*" + (cs or f"{checksum(data):02X}").encode() + b"\r\n"


ONE_DIGIT_CHECKSUM = b"$TMSCT,4,aaa,,*8\r\n"      # checksum 16#08 written as Sysmac does, `8`
LOWER_CASE_CHECKSUM = b"$TMSTA,5,01,00,*6b\r\n"    # checksum 16#6B written `6b`


def client(settings: EmulatorSettings, connect: bool = True) -> Client:
    c = Client(settings)
    return c.connect() if connect else c


PTP_HOME_J6_90 = 'PTP("JPP",0,0,90,0,90,90,20,200,0,true)'        # J6 +90 deg at 20 %
LINE_X_100 = 'Line("CPP",517.5,-122.3,360.9,180,0,90,50,200,0,true)'  # 100 mm along X at 50 %
LINE_TURN = 'Line("CAP",417.5,-122.3,360.9,180,0,180,1000,200,0,true)'  # 90 deg about Z, 1000 mm/s
PROBES: dict[str, Callable[[EmulatorSettings], Any]] = {
    "accept_lowercase_checksum": lambda s: client(s).send(LOWER_CASE_CHECKSUM).log,
    "accept_one_digit_checksum": lambda s: client(s).send(ONE_DIGIT_CHECKSUM).log,
    "accept_uppercase_length_prefix": lambda s: client(s).send(raw("TMSTA,0X2,00,")).log,
    "max_data_length": lambda s: client(s).sct("1," + "x" * 20).log,
    "send_message": lambda s: client(s).sta("00").log,
    "entry_message_on_connect": lambda s: client(s, connect=False).at(10 * MS).connect().log,
    "start_in_node": lambda s: client(s).sta("00").log,
    "enter_node_delay_ms": lambda s: client(s).at(50 * MS).sta("00").log,
    "connection_timeout_ms": lambda s: client(s, connect=False).at(150 * MS).connect().sta("00").log,
    "data_timeout_ms": lambda s: client(s).at(150 * MS).sta("00").log,
    "after_exit": lambda s: client(s).sct("1,ScriptExit()").at(2 * S).connect(2).sta("00", conn=2).log,
    "reenter_delay_ms": lambda s: client(s).sct("1,ScriptExit()").at(200 * MS).sta("00").log,
    "tag_notify_broadcast": lambda s: client(s).connect(2).sct("1,QueueTag(1)").log,
    "tag_reply_echo_text": lambda s: client(s).sct("1,QueueTag(1)").sta("01,1").log,
    "notify_before_ok": lambda s: client(s).sct('1,' + PTP_HOME_J6_90).sct("2,QueueTag(1,1)").at(5 * S).log,
    "script_exit_ok_after_drain": lambda s: client(s).sct("1," + PTP_HOME_J6_90 + "\r\nScriptExit()").log,
    "reject_invalid_args": lambda s: client(s).sct('1,ChangeBase("NoSuchBase")').log,
    "tag_memory": lambda s: client(s).sct("1,QueueTag(1)\r\nQueueTag(2)").sta("01,01").log,
    "accept_tmflow2_formats": lambda s: client(s).sct('1,Line("CDP",417.5,-122.3,350,180,0,90,100,200,0,true)').log,
    "known_bases": lambda s: client(s).sct('1,ChangeBase("Fixture")').log,
    "known_tcps": lambda s: client(s).sct('1,ChangeTCP("Gripper")').log,
    "max_joint_speed_deg_s": lambda s: client(s).tag_time(PTP_HOME_J6_90),
    "max_tcp_speed_mm_s": lambda s: client(s).tag_time(LINE_X_100),
    "max_tcp_rot_speed_deg_s": lambda s: client(s).tag_time(LINE_TURN),
    "joint_limits_deg": lambda s: client(s).sct('1,PTP("JPP",100,0,90,0,90,0,20,200,0,true)').log,
    "home_joints_deg": lambda s: client(s).tag_time('PTP("JPP",0,0,90,0,90,0,20,200,0,true)'),
    "precise_settle_ms": lambda s: client(s).tag_time(PTP_HOME_J6_90.replace(",true)", ",false)")),
    "time_scale": lambda s: client(s).tag_time(PTP_HOME_J6_90),
    "min_accel_ms": lambda s: client(s).tag_time('PTP("JPP",0,0,90,0,90,1,100,0,0,true)'),
    # a base 100 mm up queued behind a motion, dropped by the stop: the next Line is longer when it applies
    "stop_applies_queued_frames": lambda s: client(s).sct("1," + PTP_HOME_J6_90 + "\r\nChangeBase(0,0,100,0,0,0)")
    .at(100 * MS).sct("2,StopAndClearBuffer()").at(200 * MS).tag_time(LINE_X_100),
    "reject_zero_length_motion": lambda s: client(s).sct('1,PTP("JPP",0,0,90,0,90,0,20,200,0,true)').log,
}

# the alternative each probe runs under (the defaults are the spec's; see emulator/settings.py)
ALTERNATIVES: dict[str, Any] = {
    "accept_lowercase_checksum": False,
    "accept_one_digit_checksum": True,
    "accept_uppercase_length_prefix": False,
    "max_data_length": 10,
    "send_message": "Cell2",
    "entry_message_on_connect": True,
    "start_in_node": False,
    "enter_node_delay_ms": 100,
    "connection_timeout_ms": 100,
    "data_timeout_ms": 100,
    "after_exit": [AfterExit.STAY, AfterExit.STOP],
    "reenter_delay_ms": 100,
    "tag_notify_broadcast": True,
    "tag_reply_echo_text": False,
    "notify_before_ok": False,
    "script_exit_ok_after_drain": False,
    "reject_invalid_args": False,
    "tag_memory": 1,
    "accept_tmflow2_formats": False,
    "known_bases": ("RobotBase", "Fixture"),
    "known_tcps": ("NOTOOL", "Gripper"),
    "max_joint_speed_deg_s": (90.0, 90.0, 90.0, 112.5, 112.5, 112.5),
    "max_tcp_speed_mm_s": 550.0,
    "max_tcp_rot_speed_deg_s": 45.0,
    "joint_limits_deg": ((-90.0, 90.0), (-180.0, 180.0), (-155.0, 155.0),
                         (-180.0, 180.0), (-180.0, 180.0), (-270.0, 270.0)),
    "home_joints_deg": (30.0, 0.0, 90.0, 0.0, 90.0, 0.0),
    "precise_settle_ms": 100,
    "time_scale": 0.5,
    "min_accel_ms": 500,
    "stop_applies_queued_frames": False,
    "reject_zero_length_motion": True,
}


def test_every_setting_has_a_probe_and_an_alternative():
    assert set(PROBES) == set(DECLARED) == set(ALTERNATIVES)


@pytest.mark.parametrize("name", list(DECLARED))
def test_each_alternative_changes_what_a_client_observes(name):
    alternatives = ALTERNATIVES[name] if isinstance(ALTERNATIVES[name], list) else [ALTERNATIVES[name]]
    baseline = PROBES[name](DEFAULT_SETTINGS)
    for alternative in alternatives:
        assert alternative != getattr(DEFAULT_SETTINGS, name)
        observed = PROBES[name](DEFAULT_SETTINGS.with_(**{name: alternative}))
        assert observed != baseline, (name, alternative, baseline)
    assert baseline != -1, (name, "the probe's tag was never reached under the defaults")


def test_every_setting_is_read_outside_its_declaration():
    reads: set[str] = set()
    for path in sorted((ROOT / "emulator").rglob("*.py")):
        if path.name == "settings.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Attribute) and node.attr in DECLARED:
                reads.add(node.attr)
    assert not set(DECLARED) - reads, sorted(set(DECLARED) - reads)


def test_enum_settings_are_compared_with_members():
    offenders = []
    for path in sorted((ROOT / "emulator").rglob("*.py")) + sorted((ROOT / "stvm").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Compare):
                sides = [node.left, *node.comparators]
                read = any(isinstance(x, ast.Attribute) and x.attr == "after_exit" for x in sides)
                if read and any(isinstance(x, ast.Constant) for x in sides):
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not offenders


# ---- declarations and validation ---------------------------------------------------------------

BAD = {
    "time_scale": ["-1", "0", "nan", "fast"],
    "max_tcp_speed_mm_s": ["0", "-5"],
    "tag_memory": ["0", "1.5"],
    "max_data_length": ["0", "-1"],
    "data_timeout_ms": ["-1"],
    "after_exit": ["bogus", ""],
    "accept_one_digit_checksum": ["maybe", "2"],
    "max_joint_speed_deg_s": ["1,2,3", "1,2,3,4,5,0", "a,b,c,d,e,f"],
    "joint_limits_deg": ["1:2", "10:5,0:1,0:1,0:1,0:1,0:1"],
    "home_joints_deg": ["0,0,90", "0,0,300,0,90,0"],
    "known_bases": [""],
    "send_message": ["a\r\nb"],
}


@pytest.mark.parametrize(("name", "text"), [(n, t) for n, texts in BAD.items() for t in texts])
def test_bad_values_are_rejected_with_the_allowed_ones(name, text):
    with pytest.raises(SettingError) as info:
        parse_setting_assignment(f"{name}={text}", DEFAULT_SETTINGS)
    message = str(info.value)
    assert message.startswith(f"{name}: ") or message.startswith("home_joints_deg: joint"), message
    if not message.startswith("home_joints_deg: joint"):
        assert f"allowed: {DECLARED[name].allowed()}" in message


@pytest.mark.parametrize("name", list(DECLARED))
def test_every_setting_parses_its_own_default_back(name):
    d = DECLARED[name]
    value = d.default
    text = value.value if isinstance(value, Enum) else (
        ",".join(f"{lo}:{hi}" for lo, hi in value) if name == "joint_limits_deg" else
        ",".join(str(v) for v in value) if isinstance(value, tuple) else str(value).lower()
        if isinstance(value, bool) else str(value))
    assert getattr(parse_setting_assignment(f"{name}={text}", DEFAULT_SETTINGS), name) == value
    assert d.spec and d.allowed()


def test_python_values_are_checked_at_construction():
    with pytest.raises(SettingError, match=r"time_scale: -0.5 is not allowed; allowed: a number > 0 .*\(default 1.0\)"):
        EmulatorSettings(time_scale=-0.5)
    with pytest.raises(SettingError, match="after_exit: 'later' is not allowed; allowed: reenter, stay, stop"):
        EmulatorSettings(after_exit="later")
    assert EmulatorSettings(after_exit="stay").after_exit is AfterExit.STAY
    assert EmulatorSettings(known_bases=["A", "B"]).known_bases == ("A", "B")   # lists become tuples
    with pytest.raises(SettingError, match="unknown emulator setting 'time_scal'; did you mean time_scale"):
        DEFAULT_SETTINGS.with_(time_scal=1.0)


def test_scenario_tables_are_checked_when_read():
    from stvm.scenario import ScenarioError, parse_scenario
    ok = parse_scenario({"emulator": {"settings": {"time_scale": 0.1, "known_tcps": ["NOTOOL", "G"]}}}, "s.toml")
    settings, _ = ok.emulator_plan()
    assert (settings.time_scale, settings.known_tcps) == (0.1, ("NOTOOL", "G"))
    for bad, message in [({"time_scale": -1}, r"s.toml: \[emulator\] settings: time_scale: -1 is not allowed"),
                         ({"tag_memory": 2.0}, "tag_memory: 2.0 is not allowed; allowed: an integer 1..1000"),
                         ({"after_exit": "later"}, "allowed: reenter, stay, stop"),
                         ({"nope": 1}, "unknown emulator setting 'nope'")]:
        with pytest.raises(ScenarioError, match=message):
            parse_scenario({"emulator": {"settings": bad}}, "s.toml")


# ---- the real tm-emulator entry point ------------------------------------------------------------

@pytest.mark.parametrize(("assignment", "message"), [
    ("time_scale=-1", "tm-emulator: error: time_scale: '-1' is not allowed; allowed: a number > 0 and <= 1e+06 (default 1.0)"),
    ("after_exit=bogus", "after_exit: 'bogus' is not allowed; allowed: reenter, stay, stop (default reenter)"),
    ("tim_scale=1", "unknown emulator setting 'tim_scale'; did you mean time_scale?"),
    ("time_scale", "--set needs NAME=VALUE"),
])
def test_cli_bad_settings_are_usage_errors(assignment, message, capsys):
    assert main(["--set", assignment, "--port", "0", "--quiet", "--duration", "0"]) == 2
    assert message in capsys.readouterr().err


def test_installed_cli_rejects_a_negative_time_scale():
    proc = subprocess.run([sys.executable, "-m", "emulator", "--set", "time_scale=-1", "--port", "0", "--quiet"],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2
    assert "time_scale: '-1' is not allowed; allowed: a number > 0" in proc.stderr
    assert "Traceback" not in proc.stderr


# ---- docs/emulator.md ---------------------------------------------------------------------------

def _doc_default(value: Any) -> str:
    """A default as the docs table spells it."""
    if isinstance(value, Enum):
        text = value.value
    elif isinstance(value, bool) or isinstance(value, int):
        text = str(value)
    elif isinstance(value, float):
        text = f"{value:g}"
    elif isinstance(value, str):
        text = f'"{value}"'
    elif value and isinstance(value[0], tuple):
        text = ",".join(f"{lo:g}:{hi:g}" for lo, hi in value)
    else:
        text = ",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in value)
    return f"`{text}`"


def test_docs_table_gives_every_default_and_allowed_values():
    lines = (ROOT / "docs" / "emulator.md").read_text(encoding="utf-8").splitlines()
    start = lines.index("| setting | default | allowed | spec | meaning |")
    rows = {}
    for line in lines[start + 2:]:
        if not line.startswith("| `"):
            break
        cells = [c.strip() for c in line.strip("|").split(" | ")]
        rows[cells[0].strip("`")] = cells
    assert set(rows) == set(DECLARED)
    for name, d in DECLARED.items():
        _, default, allowed, spec, meaning = rows[name]
        assert (default, allowed, spec) == (_doc_default(d.default), d.allowed(), d.spec), name
        assert meaning, name
