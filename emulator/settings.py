"""Every behaviour the TM spec leaves open, as one named setting each.

The reference is `docs/tm_protocol.md`; section 11 lists the UNCERTAIN points and their
recommended defaults.  Each field below cites the section it settles.  The defaults answer as a
real robot would as far as the spec knows; a field that makes the emulator *more* lenient than the
default is always off by default, so nothing the default says a robot rejects is silently accepted.

Each field declares its allowed values once (a `Kind`: flag, bounded integer or number, text,
names, an Enum, a 6-joint vector).  Values are checked when an `EmulatorSettings` is built, from
Python, from ``tm-emulator --set NAME=VALUE`` (`parse_setting_assignment`) or from a scenario's
``[emulator] settings`` table (`EmulatorSettings.with_table`); a bad one raises `SettingError`
(a ValueError) whose message lists what is allowed.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field, fields, replace
from enum import Enum
from typing import Any, Mapping

# Choice: the kinematic model is a TM5-700 (spec §9 examples use its offsets: y = -122.3 is its
# d4).  Joint speed limits are the TM5-700 datasheet values in degrees per second.
TM5_700_MAX_JOINT_SPEED_DEG_S = (180.0, 180.0, 180.0, 225.0, 225.0, 225.0)
TM5_700_JOINT_LIMITS_DEG = ((-270.0, 270.0), (-180.0, 180.0), (-155.0, 155.0),
                            (-180.0, 180.0), (-180.0, 180.0), (-270.0, 270.0))
HOME_JOINTS_DEG = (0.0, 0.0, 90.0, 0.0, 90.0, 0.0)


class SettingError(ValueError):
    """A setting name or value that is not allowed; the message lists what is."""


class AfterExit(Enum):
    """§1.7: what the flow does after it leaves the Listen node."""
    REENTER = "reenter"    # loops back into the node after ``reenter_delay_ms``
    STAY = "stay"          # the project keeps running outside the node
    STOP = "stop"          # the project ends: all sockets closed, connections refused


# ---- kinds of values: each checks a Python/TOML value and parses command-line text -------------

class Kind:
    def allowed(self) -> str:
        raise NotImplementedError

    def coerce(self, name: str, value: Any) -> Any:
        """`value` checked (and normalised: lists become tuples); SettingError otherwise."""
        raise NotImplementedError

    def parse(self, name: str, text: str) -> Any:
        """A value typed on the command line."""
        return self.coerce(name, text)

    def _reject(self, name: str, value: Any) -> SettingError:
        return SettingError(f"{name}: {value!r} is not allowed; allowed: {self.allowed()}")


class Flag(Kind):
    TRUE, FALSE = ("1", "true", "yes", "on"), ("0", "false", "no", "off")

    def allowed(self) -> str:
        return "true, false"

    def coerce(self, name: str, value: Any) -> bool:
        if not isinstance(value, bool):
            raise self._reject(name, value)
        return value

    def parse(self, name: str, text: str) -> bool:
        if text.lower() in self.TRUE:
            return True
        if text.lower() in self.FALSE:
            return False
        raise self._reject(name, text)


@dataclass(frozen=True)
class Integer(Kind):
    lo: int
    hi: int

    def allowed(self) -> str:
        return f"an integer {self.lo}..{self.hi}"

    def coerce(self, name: str, value: Any) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or not self.lo <= value <= self.hi:
            raise self._reject(name, value)
        return value

    def parse(self, name: str, text: str) -> int:
        try:
            return self.coerce(name, int(text.replace("_", ""), 0))
        except ValueError:
            raise self._reject(name, text) from None


@dataclass(frozen=True)
class Number(Kind):
    lo: float
    hi: float
    open_low: bool = False     # lo itself excluded (a speed or scale of 0 is not physical)

    def allowed(self) -> str:
        return f"a number {'>' if self.open_low else '>='} {self.lo:g} and <= {self.hi:g}"

    def coerce(self, name: str, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self._reject(name, value)
        number = float(value)
        low_ok = number > self.lo if self.open_low else number >= self.lo
        if not (low_ok and number <= self.hi) or math.isnan(number):
            raise self._reject(name, value)
        return number

    def parse(self, name: str, text: str) -> float:
        try:
            return self.coerce(name, float(text))
        except ValueError:
            raise self._reject(name, text) from None


class Text(Kind):
    def allowed(self) -> str:
        return "any text without CR or LF"

    def coerce(self, name: str, value: Any) -> str:
        if not isinstance(value, str) or "\r" in value or "\n" in value:
            raise self._reject(name, value)
        return value


class Names(Kind):
    """A tuple of names (comma-separated on the command line, a list in TOML)."""

    def allowed(self) -> str:
        return "one or more names separated by commas (a list in TOML)"

    def coerce(self, name: str, value: Any) -> tuple[str, ...]:
        if isinstance(value, (list, tuple)) and value and all(isinstance(v, str) and v and "," not in v
                                                              for v in value):
            return tuple(value)
        raise self._reject(name, value)

    def parse(self, name: str, text: str) -> tuple[str, ...]:
        return self.coerce(name, [v.strip() for v in text.split(",") if v.strip()])


@dataclass(frozen=True)
class Choice(Kind):
    enum: type[Enum]

    def allowed(self) -> str:
        return ", ".join(str(member.value) for member in self.enum)

    def coerce(self, name: str, value: Any) -> Enum:
        if isinstance(value, self.enum):
            return value
        for member in self.enum:
            if isinstance(value, str) and value.lower() == member.value:
                return member
        raise self._reject(name, value)


@dataclass(frozen=True)
class Vector(Kind):
    """One number per joint (comma-separated on the command line, a list in TOML)."""

    count: int
    positive: bool = False

    def allowed(self) -> str:
        return f"{self.count} {'numbers > 0' if self.positive else 'numbers'} separated by commas"

    def coerce(self, name: str, value: Any) -> tuple[float, ...]:
        if not isinstance(value, (list, tuple)) or len(value) != self.count or any(
                isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
                or (self.positive and v <= 0) for v in value):
            raise self._reject(name, value)
        return tuple(float(v) for v in value)

    def parse(self, name: str, text: str) -> tuple[float, ...]:
        try:
            return self.coerce(name, [float(v) for v in text.split(",")])
        except ValueError:
            raise self._reject(name, text) from None


@dataclass(frozen=True)
class Ranges(Kind):
    """One (low, high) pair per joint, low < high (``lo:hi,lo:hi,...`` on the command line)."""

    count: int

    def allowed(self) -> str:
        return f"{self.count} pairs low:high (low < high) separated by commas"

    def coerce(self, name: str, value: Any) -> tuple[tuple[float, float], ...]:
        try:
            pairs = tuple((float(lo), float(hi)) for lo, hi in value)
        except (TypeError, ValueError):
            raise self._reject(name, value) from None
        if len(pairs) != self.count or any(not lo < hi for lo, hi in pairs) \
                or any(isinstance(v, bool) for pair in value for v in pair):
            raise self._reject(name, value)
        return pairs

    def parse(self, name: str, text: str) -> tuple[tuple[float, float], ...]:
        try:
            return self.coerce(name, [tuple(float(v) for v in pair.split(":")) for pair in text.split(",")])
        except ValueError:
            raise self._reject(name, text) from None


def setting(default: Any, spec: str, kind: Kind) -> Any:
    """Declare one setting: its default, the spec section it settles and its allowed values."""
    return field(default=default, metadata={"spec": spec, "kind": kind})


@dataclass(frozen=True)
class EmulatorSettings:
    """All switchable behaviour of the emulated robot (defaults = spec §11)."""

    # --- framing (spec §2, §2.1, §11 #8/#9) ---------------------------------------------------
    accept_lowercase_checksum: bool = setting(True, "§2 [C]", Flag())
    """§2: official TM drivers send lower-case hex and the robot accepts it [C]."""
    accept_one_digit_checksum: bool = setting(False, "§2, §11 #9", Flag())
    """§2/§11 #9 [U]: a one-digit checksum (what Sysmac BYTE_TO_STRING yields below 16#10) is a
    structure error, CPERR 01, by default."""
    accept_uppercase_length_prefix: bool = setting(True, "§2, §11 #9", Flag())
    """§2/§11 #9 [U]: ``0X``/``0B`` length prefixes accepted (expression constants are
    case-insensitive)."""
    max_data_length: int = setting(65536, "Choice (§2)", Integer(1, 2**31 - 1))
    """Choice (§2, not in the spec): a LENGTH above this is a structure error (CPERR 01) instead of
    waiting for that many bytes."""

    # --- listen node (spec §1) -----------------------------------------------------------------
    send_message: str = setting("Listen1", "§1.5", Text())
    """§1.5: the node's "Send message", data of the entry message ``$TMSCT,..,0,<msg>``."""
    entry_message_on_connect: bool = setting(False, "§1.5, §11 #1", Flag())
    """§1.5/§11 #1 [U]: a client connecting after entry does not get the entry message."""
    start_in_node: bool = setting(True, "Choice", Flag())
    """Choice: the project is running and the flow is in the Listen node at start-up."""
    enter_node_delay_ms: int = setting(0, "Choice", Integer(0, 86_400_000))
    """Choice: time from project start to entering the node."""
    connection_timeout_ms: int = setting(0, "§1.6", Integer(0, 86_400_000))
    """§1.6 node setting: no client within this time after entry -> Fail path (0 = none)."""
    data_timeout_ms: int = setting(0, "§1.6", Integer(0, 86_400_000))
    """§1.6 node setting: no packet within this time while in the node -> Fail path (0 = none)."""
    after_exit: AfterExit = setting(AfterExit.REENTER, "§1.7", Choice(AfterExit))
    """§1.7 flow after leaving the node: ``reenter`` (flow loops back to the node after
    ``reenter_delay_ms``), ``stay`` (project keeps running outside the node) or ``stop`` (project
    ends: all sockets closed, connections refused)."""
    reenter_delay_ms: int = setting(1000, "Choice (§1.7)", Integer(0, 86_400_000))
    """Choice: delay before the flow re-enters the node when ``after_exit == "reenter"``."""

    # --- replies and tags (spec §4, §5, §11) ---------------------------------------------------
    tag_notify_broadcast: bool = setting(False, "§5.3, §11 #2", Flag())
    """§5.3/§11 #2 [U]: tag notifications go to the connection that queued the tag."""
    tag_reply_echo_text: bool = setting(True, "§5.2, §11 #3", Flag())
    """§5.2/§11 #3 [U]: ``01`` replies echo the tag text of the request (``1`` stays ``1``);
    False = zero-pad to two digits."""
    notify_before_ok: bool = setting(True, "§5.3, §11 #4", Flag())
    """§5.3/§11 #4 [U]: for ``QueueTag(n,1)`` the ``TMSTA 01,nn,true`` precedes the ``OK``."""
    script_exit_ok_after_drain: bool = setting(True, "§4.6, §11 #5", Flag())
    """§4.6/§11 #5 [U]: the ``OK`` of a script with ``ScriptExit()`` comes after the motion queue
    drained; False = at once."""
    reject_invalid_args: bool = setting(True, "§7, §11 #6", Flag())
    """§7/§11 #6 [U]: runtime-invalid arguments (format string, ranges, tag > 15, unreachable
    target) answer ``ERROR;<line>``; False = ``OK`` and the function returns false."""
    tag_memory: int = setting(4, "§5.2, §11 #10", Integer(1, 1000))
    """§5.2/§11 #10 [M?/U]: how many distinct tags are remembered."""
    accept_tmflow2_formats: bool = setting(True, "§7, §10.2", Flag())
    """§7/§10.2: TMflow 2.x ``D`` speed formats (``CDP``, ``CDR``) are accepted (pytmrobot sends
    them)."""
    known_bases: tuple[str, ...] = setting(("RobotBase",), "§7", Names())
    """§7 ChangeBase("name"): names the robot knows; others make the function fail."""
    known_tcps: tuple[str, ...] = setting(("NOTOOL",), "§7", Names())
    """§7 ChangeTCP("name"): names the robot knows; others make the function fail."""

    # --- motion timing (spec §8, §11 #11) ------------------------------------------------------
    max_joint_speed_deg_s: tuple[float, ...] = setting(TM5_700_MAX_JOINT_SPEED_DEG_S, "§8, §11 #11", Vector(6, positive=True))
    """100 % PTP speed per joint."""
    max_tcp_speed_mm_s: float = setting(1100.0, "§8, §11 #11", Number(0.0, 1e6, open_low=True))
    """100 % Line/Circle speed for ``P`` speed formats; upper bound for ``A``/``D`` (mm/s)."""
    max_tcp_rot_speed_deg_s: float = setting(225.0, "§8, §11 #11", Number(0.0, 1e6, open_low=True))
    """Orientation speed at 100 % (Line: the slower of translation and rotation wins)."""
    joint_limits_deg: tuple[tuple[float, float], ...] = setting(TM5_700_JOINT_LIMITS_DEG, "Choice (§8)", Ranges(6))
    home_joints_deg: tuple[float, ...] = setting(HOME_JOINTS_DEG, "Choice (§8)", Vector(6))
    precise_settle_ms: int = setting(0, "§8, §11 #11", Integer(0, 86_400_000))
    """§8 [U]: extra settle time when precise positioning is on (``disablePrecise`` false)."""
    time_scale: float = setting(1.0, "Choice (§8)", Number(0.0, 1e6, open_low=True))
    """Multiplies every motion duration (e.g. 0.01 for fast tests)."""
    min_accel_ms: int = setting(1, "Choice (§8)", Integer(0, 86_400_000))
    """Choice: accel_ms below this is raised to it (a zero acceleration time is not physical)."""
    stop_applies_queued_frames: bool = setting(True, "Choice (§7, §8)", Flag())
    """Choice: a ChangeBase/ChangeTCP queued behind motions that StopAndClearBuffer drops still
    sets the base/tool of the motions after the stop (True, as the plan had it), or is dropped with
    them (False: the frames in effect where the robot stopped). The TM documents neither."""
    reject_zero_length_motion: bool = setting(False, "Choice (§7)", Flag())
    """Choice: a PTP/Line/Circle to the pose the robot is planned to be at is run as a motion of
    zero length that completes at once (False), or refused like an invalid argument (True:
    ``ERROR;<line>``). The TM documents neither."""

    def __post_init__(self) -> None:
        # every value is checked (lists become tuples, spellings Enum members) at construction
        for f in fields(self):
            try:
                value = f.metadata["kind"].coerce(f.name, getattr(self, f.name))
            except SettingError as exc:
                default = f.default.value if isinstance(f.default, Enum) else f.default
                raise SettingError(f"{exc} (default {default})") from None
            object.__setattr__(self, f.name, value)
        for joint, (angle, (lo, hi)) in enumerate(zip(self.home_joints_deg, self.joint_limits_deg), 1):
            if not lo <= angle <= hi:
                raise SettingError(f"home_joints_deg: joint {joint} at {angle:g} is outside "
                                   f"joint_limits_deg {lo:g}..{hi:g}")

    def with_(self, **changes: Any) -> "EmulatorSettings":
        """Return a copy with ``changes`` applied (unknown names raise SettingError)."""
        for name in changes:
            declaration(name)
        return replace(self, **changes)

    def with_table(self, table: Mapping[str, Any], where: str = "[emulator] settings") -> "EmulatorSettings":
        """Return a copy with a TOML table applied (a scenario's ``[emulator] settings``)."""
        try:
            return self.with_(**dict(table))
        except SettingError as exc:
            raise SettingError(f"{where}: {exc}") from None

    @classmethod
    def names(cls) -> list[str]:
        return [f.name for f in fields(cls)]


DEFAULT_SETTINGS = EmulatorSettings()


@dataclass(frozen=True)
class Declaration:
    """What one field declares: name, default, spec section, allowed values."""

    name: str
    default: Any
    spec: str
    kind: Kind

    def allowed(self) -> str:
        return self.kind.allowed()

    def parse(self, text: str) -> Any:
        """A value typed on the command line, checked; SettingError names the default."""
        try:
            return self.kind.parse(self.name, text)
        except SettingError as exc:
            default = self.default.value if isinstance(self.default, Enum) else self.default
            raise SettingError(f"{exc} (default {default})") from None


def declarations() -> list[Declaration]:
    """Every setting's declaration, in declaration order."""
    return [Declaration(f.name, f.default, f.metadata["spec"], f.metadata["kind"]) for f in fields(EmulatorSettings)]


def declaration(name: str) -> Declaration:
    """The declaration of setting `name`; SettingError (naming close matches) if there is none."""
    for declared in declarations():
        if declared.name == name:
            return declared
    close = difflib.get_close_matches(name, EmulatorSettings.names(), n=3)
    hint = f"; did you mean {' or '.join(close)}?" if close else ""
    raise SettingError(f"unknown emulator setting {name!r}{hint} (known: {', '.join(EmulatorSettings.names())})")


def parse_setting_assignment(text: str, base: EmulatorSettings) -> EmulatorSettings:
    """Apply ``name=value`` (CLI ``--set``) to ``base``; raises SettingError on bad input."""
    name, sep, raw = text.partition("=")
    name = name.strip()
    if not sep:
        raise SettingError(f"--set needs NAME=VALUE, got {text!r}")
    declared = declaration(name)
    return replace(base, **{name: declared.parse(raw.strip())})
