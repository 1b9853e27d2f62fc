"""Fault plans: ways to make the emulated robot misbehave on purpose (issue 5, design §Emulator).

A :class:`FaultPlan` is plain data.  The robot (``robot.py``) reads the robot-level faults (answer
ERROR, stay busy, tag ``false``, unsolicited frames, project stop); the connection core
(``core.py``) applies the byte-level ones (refuse, delay, corrupt checksum, split, drop).

Command line: ``--fault NAME[:ARG]``, repeatable; :func:`parse_fault` turns one into a plan change.

=================  ==========================================================================
``refuse[:N]``     refuse connections (the first N only; default: all)
``delay:MS``       hold every reply MS milliseconds before sending it
``drop[:MS]``      close a connection MS ms (default 0) after a motion starts moving
``corrupt[:N]``    corrupt the checksum of every Nth frame sent (default 1 = every frame)
``split[:N]``      send every frame in two writes, the first N bytes (default: half) first
``error[:N]``      answer every Nth TMSCT with ``ERROR;1`` instead of running it (default 1)
``busy``           motions never progress (the robot stays busy; tags never fire)
``tag_false``      tag notifications say ``false`` (the thesis code reads that as
                   "Motion failed", spec §5.3) and the status stays ``false``
``unsolicited:MS`` every MS ms send ``$TMSTA,..,90,unsolicited`` to every connection
``stop:MS``        stop the project MS ms after start (all sockets closed, refuse after)
=================  ==========================================================================
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace


@dataclass(frozen=True)
class FaultPlan:
    """Faults to inject; the default plan injects none."""

    refuse_connections: int = 0       # number of connection attempts to refuse; -1 = all
    reply_delay_ms: int = 0
    drop_after_motion_ms: int | None = None
    corrupt_checksum_every: int = 0   # 0 = never
    split_frames_at: int | None = None  # None = whole frames; 0 = half; N = first N bytes
    answer_error_every: int = 0       # 0 = never
    stay_busy: bool = False
    tag_false: bool = False
    unsolicited_every_ms: int = 0     # 0 = never
    stop_project_at_ms: int | None = None

    @property
    def active(self) -> bool:
        return self != FaultPlan()

    def describe(self) -> list[str]:
        default = FaultPlan()
        return [f"{f.name}={getattr(self, f.name)!r}" for f in fields(self)
                if getattr(self, f.name) != getattr(default, f.name)]


NO_FAULTS = FaultPlan()


def parse_fault(text: str, plan: FaultPlan = NO_FAULTS) -> FaultPlan:
    """Apply one ``NAME[:ARG]`` fault to ``plan``; raises ValueError for unknown names/args."""
    name, _, arg = text.strip().partition(":")
    name = name.lower().replace("-", "_")

    def number(default: int | None = None, minimum: int = 0) -> int:
        if arg == "":
            if default is None:
                raise ValueError(f"fault {name} needs an argument: {name}:N")
            return default
        try:
            value = int(arg)
        except ValueError:
            raise ValueError(f"fault {name}:{arg}: the argument must be a whole number") from None
        if value < minimum:
            raise ValueError(f"fault {name}:{arg}: the argument must be >= {minimum}")
        return value

    def no_argument() -> None:
        if arg:
            raise ValueError(f"fault {name} takes no argument, got {name}:{arg}")

    if name == "refuse":
        return replace(plan, refuse_connections=number(-1, minimum=1) if arg else -1)
    if name == "delay":
        return replace(plan, reply_delay_ms=number())
    if name == "drop":
        return replace(plan, drop_after_motion_ms=number(0))
    if name == "corrupt":
        return replace(plan, corrupt_checksum_every=number(1, minimum=1))
    if name == "split":
        return replace(plan, split_frames_at=number(0))
    if name == "error":
        return replace(plan, answer_error_every=number(1, minimum=1))
    if name == "busy":
        no_argument()
        return replace(plan, stay_busy=True)
    if name == "tag_false":
        no_argument()
        return replace(plan, tag_false=True)
    if name == "unsolicited":
        return replace(plan, unsolicited_every_ms=number(1000, minimum=1))
    if name == "stop":
        return replace(plan, stop_project_at_ms=number())
    raise ValueError(f"unknown fault {name!r} (refuse, delay, drop, corrupt, split, error, busy, "
                     "tag_false, unsolicited, stop)")


def parse_faults(texts: list[str] | tuple[str, ...] | None) -> FaultPlan:
    plan = NO_FAULTS
    for text in texts or ():
        plan = parse_fault(text, plan)
    return plan


def corrupt_checksum(frame: bytes) -> bytes:
    """Flip the checksum of an encoded frame (``...,*HH\\r\\n``) to a wrong value."""
    if len(frame) < 6 or frame[-5:-4] != b"*":
        return frame
    good = int(frame[-4:-2], 16)
    return frame[:-4] + f"{good ^ 0x5A:02X}".encode("ascii") + b"\r\n"
