"""Every behaviour the TM spec leaves open, as one named setting each.

The reference is ``shared/spec/tm_protocol.md``; section 11 lists the UNCERTAIN points and their
recommended defaults.  Each field below cites the section it settles.  The defaults answer as a
real robot would as far as the spec knows; a field that makes the emulator *more* lenient than the
default is always off by default, so nothing the default says a robot rejects is silently accepted.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import Any

# Choice: the kinematic model is a TM5-700 (spec §9 examples use its offsets: y = -122.3 is its
# d4).  Joint speed limits are the TM5-700 datasheet values in degrees per second.
TM5_700_MAX_JOINT_SPEED_DEG_S = (180.0, 180.0, 180.0, 225.0, 225.0, 225.0)
TM5_700_JOINT_LIMITS_DEG = ((-270.0, 270.0), (-180.0, 180.0), (-155.0, 155.0),
                            (-180.0, 180.0), (-180.0, 180.0), (-270.0, 270.0))
HOME_JOINTS_DEG = (0.0, 0.0, 90.0, 0.0, 90.0, 0.0)


@dataclass(frozen=True)
class EmulatorSettings:
    """All switchable behaviour of the emulated robot (defaults = spec §11)."""

    # --- framing (spec §2, §2.1, §11 #8/#9) ---------------------------------------------------
    accept_lowercase_checksum: bool = True
    """§2: official TM drivers send lower-case hex and the robot accepts it [C]."""
    accept_one_digit_checksum: bool = False
    """§2/§11 #9 [U]: a one-digit checksum (what Sysmac BYTE_TO_STRING yields below 16#10) is a
    structure error, CPERR 01, by default."""
    accept_uppercase_length_prefix: bool = True
    """§2/§11 #9 [U]: ``0X``/``0B`` length prefixes accepted (expression constants are
    case-insensitive)."""
    max_data_length: int = 65536
    """Choice (§2, not in the spec): a LENGTH above this is a structure error (CPERR 01) instead of
    waiting for that many bytes."""

    # --- listen node (spec §1) -----------------------------------------------------------------
    send_message: str = "Listen1"
    """§1.5: the node's "Send message", data of the entry message ``$TMSCT,..,0,<msg>``."""
    entry_message_on_connect: bool = False
    """§1.5/§11 #1 [U]: a client connecting after entry does not get the entry message."""
    start_in_node: bool = True
    """Choice: the project is running and the flow is in the Listen node at start-up."""
    enter_node_delay_ms: int = 0
    """Choice: time from project start to entering the node."""
    connection_timeout_ms: int = 0
    """§1.6 node setting: no client within this time after entry -> Fail path (0 = none)."""
    data_timeout_ms: int = 0
    """§1.6 node setting: no packet within this time while in the node -> Fail path (0 = none)."""
    after_exit: str = "reenter"
    """§1.7 flow after leaving the node: ``reenter`` (flow loops back to the node after
    ``reenter_delay_ms``), ``stay`` (project keeps running outside the node) or ``stop`` (project
    ends: all sockets closed, connections refused)."""
    reenter_delay_ms: int = 1000
    """Choice: delay before the flow re-enters the node when ``after_exit == "reenter"``."""

    # --- replies and tags (spec §4, §5, §11) ---------------------------------------------------
    tag_notify_broadcast: bool = False
    """§5.3/§11 #2 [U]: tag notifications go to the connection that queued the tag."""
    tag_reply_echo_text: bool = True
    """§5.2/§11 #3 [U]: ``01`` replies echo the tag text of the request (``1`` stays ``1``);
    False = zero-pad to two digits."""
    notify_before_ok: bool = True
    """§5.3/§11 #4 [U]: for ``QueueTag(n,1)`` the ``TMSTA 01,nn,true`` precedes the ``OK``."""
    script_exit_ok_after_drain: bool = True
    """§4.6/§11 #5 [U]: the ``OK`` of a script with ``ScriptExit()`` comes after the motion queue
    drained; False = at once."""
    reject_invalid_args: bool = True
    """§7/§11 #6 [U]: runtime-invalid arguments (format string, ranges, tag > 15, unreachable
    target) answer ``ERROR;<line>``; False = ``OK`` and the function returns false."""
    tag_memory: int = 4
    """§5.2/§11 #10 [M?/U]: how many distinct tags are remembered."""
    accept_tmflow2_formats: bool = True
    """§7/§10.2: TMflow 2.x ``D`` speed formats (``CDP``, ``CDR``) are accepted (pytmrobot sends
    them)."""
    known_bases: tuple[str, ...] = ("RobotBase",)
    """§7 ChangeBase("name"): names the robot knows; others make the function fail."""
    known_tcps: tuple[str, ...] = ("NOTOOL",)
    """§7 ChangeTCP("name"): names the robot knows; others make the function fail."""

    # --- motion timing (spec §8, §11 #11) ------------------------------------------------------
    max_joint_speed_deg_s: tuple[float, ...] = TM5_700_MAX_JOINT_SPEED_DEG_S
    """100 % PTP speed per joint."""
    max_tcp_speed_mm_s: float = 1100.0
    """100 % Line/Circle speed for ``P`` speed formats; upper bound for ``A``/``D`` (mm/s)."""
    max_tcp_rot_speed_deg_s: float = 225.0
    """Orientation speed at 100 % (Line: the slower of translation and rotation wins)."""
    joint_limits_deg: tuple[tuple[float, float], ...] = TM5_700_JOINT_LIMITS_DEG
    home_joints_deg: tuple[float, ...] = HOME_JOINTS_DEG
    precise_settle_ms: int = 0
    """§8 [U]: extra settle time when precise positioning is on (``disablePrecise`` false)."""
    time_scale: float = 1.0
    """Multiplies every motion duration (e.g. 0.01 for fast tests)."""
    min_accel_ms: int = 1
    """Choice: accel_ms below this is raised to it (a zero acceleration time is not physical)."""

    def with_(self, **changes: Any) -> "EmulatorSettings":
        """Return a copy with ``changes`` applied (unknown names raise TypeError)."""
        return replace(self, **changes)

    @classmethod
    def names(cls) -> list[str]:
        return [f.name for f in fields(cls)]


DEFAULT_SETTINGS = EmulatorSettings()


def parse_setting_assignment(text: str, base: EmulatorSettings) -> EmulatorSettings:
    """Apply ``name=value`` (CLI ``--set``) to ``base``; raises ValueError on bad input."""
    name, sep, raw = text.partition("=")
    name = name.strip()
    if not sep or name not in EmulatorSettings.names():
        raise ValueError(f"unknown setting {name!r}; known: {', '.join(EmulatorSettings.names())}")
    current = getattr(base, name)
    value: Any
    if isinstance(current, bool):
        if raw.lower() in ("1", "true", "yes", "on"):
            value = True
        elif raw.lower() in ("0", "false", "no", "off"):
            value = False
        else:
            raise ValueError(f"{name} needs true/false, got {raw!r}")
    elif isinstance(current, int):
        value = int(raw)
    elif isinstance(current, float):
        value = float(raw)
    elif isinstance(current, str):
        value = raw
    elif isinstance(current, tuple) and all(isinstance(v, str) for v in current):
        value = tuple(v for v in raw.split(",") if v)
    else:
        raise ValueError(f"{name} cannot be set from the command line")
    return replace(base, **{name: value})
