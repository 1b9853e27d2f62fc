"""The TM script built-ins: what each function of a ``$TMSCT`` script does (spec §7, §4.3, §5.4).

The parser (``script.py``) has already checked each call's name, argument count and argument
types; a built-in checks the argument *values* and acts.  A bad value raises :class:`ArgError`:
the function fails (spec §7 "runtime rejection"), which the robot turns into ``ERROR;<line>``
(``reject_invalid_args``) or a logged ``false``.

Two kinds, two tables:

* :data:`FUNCTIONS` -- ``fn_<name>(robot, args, ctx)`` takes the evaluated arguments and returns
  the function's value.  Motions are planned on ``ctx.plan`` and queued; in a dry run
  (``ctx.dry``, the up-front argument check) nothing is queued and no robot state changes.
* :data:`BLOCKING_STATEMENTS` -- ``st_<name>(robot, job, call, ctx)`` runs a whole statement that
  may block the script (spec §4.3): it returns ``"block"`` after setting ``job.wait``, ``"exit"``
  (§4.6: the statements after it do not run) or None.

A built-in sees the robot only through :class:`ScriptHost`; the state machine stays in
``robot.py``.
"""

from __future__ import annotations

import math
import struct
from collections import OrderedDict
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable, Protocol

import numpy as np

from . import detmath as dm
from . import script as sc
from .framing import encode
from .motion import (NS_PER_MS, Kinematics, Marker, MotionExecutor, PlanError, PlannedState, Planner,
                     matrix_to_pose, pose_to_matrix)
from .settings import EmulatorSettings

MAX_TAG = 15  # §7 QueueTag: tag 1-15


class ArgError(Exception):
    """A function call with invalid argument values: the function fails (spec §7)."""


@dataclass
class Wait:
    """What a blocked script waits for (spec §4.3)."""

    kind: str  # "tag" / "delay" / "waittag" / "drain"
    tag: int = 0
    until_ns: int | None = None


@dataclass
class ScriptJob:
    """One accepted ``$TMSCT`` packet: its script, how far it has run and what it waits for."""

    conn: int
    script_id: str
    parsed: sc.ParsedScript
    pc: int = 0
    wait: Wait | None = None
    forced_error: bool = False
    exiting: bool = False
    deferred: list[tuple[int, bytes]] = field(default_factory=list)  # notify_before_ok=False


@dataclass
class ScriptContext:
    """Evaluation context: the real session or a dry-run copy of it."""

    dry: bool
    conn: int
    variables: dict[str, list[Any]]  # name -> [type, is_array, value]
    plan: PlannedState
    line: int = 0
    errors: list[int] = field(default_factory=list)


class ScriptHost(Protocol):
    """The robot as the built-ins see it (``robot.Robot`` is the one implementation)."""

    settings: EmulatorSettings
    kin: Kinematics
    planner: Planner
    executor: MotionExecutor
    connections: list[int]
    tags: OrderedDict[int, str]  # tag -> "true"/"false", oldest first (§5.2)
    paused: bool
    now_ns: int
    io: dict[str, dict[str, list[int]]]  # module -> "DI"/"DO" -> channel values (io_read/io_write)

    def evaluate(self, expr: sc.Expr, ctx: ScriptContext) -> Any: ...
    def queue_motion(self, ctx: ScriptContext, item: Any) -> None: ...
    def stop_and_clear(self) -> None: ...
    def begin_exit(self) -> None: ...
    def reply(self, job: ScriptJob, status: str) -> None: ...
    def send(self, conn: int, data: bytes) -> None: ...
    def note(self, text: str) -> None: ...


# ---------------------------------------------------------------- argument values (§7)


def _flatten(args: list[Any]) -> list[Any]:
    flat: list[Any] = []
    for arg in args:
        if isinstance(arg, (list, tuple)):
            flat.extend(arg)
        else:
            flat.append(arg)
    return flat


def _num(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ArgError(f"{what} must be a number")
    return float(value)


def _boolean(value: Any, what: str) -> bool:
    if not isinstance(value, bool):
        raise ArgError(f"{what} must be true/false")
    return value


def _check_format(fmt: Any, allowed: set[str], settings: EmulatorSettings) -> str:
    if not isinstance(fmt, str):
        raise ArgError("format must be a string")
    allowed_now = set(allowed)
    if settings.accept_tmflow2_formats:
        allowed_now |= {f.replace("A", "D", 1) for f in allowed if len(f) == 3 and f[1] == "A"}
    if fmt not in allowed_now:
        raise ArgError(f"format {fmt!r} not valid here")
    return fmt


def _motion_values(args: list[Any], counts: tuple[int, ...]) -> list[Any]:
    flat = _flatten(args)
    if len(flat) not in counts:
        raise ArgError("wrong number of values (array length?)")
    return flat


def _speed(value: Any, is_pct: bool, settings: EmulatorSettings) -> float:
    speed = _num(value, "speed")
    # Choice (§7 [U]): percent in (0, 100], mm/s in (0, max_tcp_speed].
    limit = 100.0 if is_pct else settings.max_tcp_speed_mm_s
    if not 0.0 < speed <= limit:
        raise ArgError("speed out of range")
    return speed


def _accel(value: Any) -> float:
    accel = _num(value, "acceleration time")
    if accel < 0:
        raise ArgError("negative acceleration time")
    return accel


def _blend(value: Any, is_pct: bool) -> float:
    blend = _num(value, "blend")
    if blend < 0 or (is_pct and blend > 100):
        raise ArgError("blend out of range")
    return blend


def _pose6(values: list[Any]) -> np.ndarray:
    return np.array([_num(v, "coordinate") for v in values], dtype=float)


def fn_ptp(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``PTP(fmt, pose, speed%, accel_ms, blend%, disablePrecise[, config])`` (spec §7, timing §8).

    Point-to-point motion, queued: to joint angles (``"JPP"``) or to a Cartesian pose in the
    current base (``"CPP"``, the only format that takes the optional pose configuration).
    """
    v = _motion_values(args, (11, 14))
    fmt = _check_format(v[0], {"JPP", "CPP"}, robot.settings)
    target = _pose6(v[1:7])
    speed, accel, blend = _speed(v[7], True, robot.settings), _accel(v[8]), _blend(v[9], True)
    precise = not _boolean(v[10], "disablePrecise")
    if len(v) == 14:
        # §7: pose configuration only with "CPP": Config1 0/1, Config2 2/3, Config3 4/5.
        config = [_num(x, "pose") for x in v[11:14]]
        if fmt != "CPP" or config[0] not in (0, 1) or config[1] not in (2, 3) or config[2] not in (4, 5):
            raise ArgError("invalid pose configuration")
    try:
        if fmt == "JPP":
            joints = target
        else:
            joints = robot.planner.solve(ctx.plan, dm.matmul(ctx.plan.base, pose_to_matrix(target)))
        if robot.settings.reject_zero_length_motion and max(abs(float(a) - float(b))
                                                            for a, b in zip(joints, ctx.plan.joints)) < 1e-9:
            raise PlanError("zero-length motion")
        seg = robot.planner.joint_motion(ctx.plan, joints, speed, accel, blend, precise, f"PTP {fmt}")
    except PlanError as exc:
        raise ArgError(str(exc)) from None
    robot.queue_motion(ctx, seg)
    return True


def _line_like(robot: ScriptHost, ctx: ScriptContext, fmt: str, target_tcp: np.ndarray, v: list[Any],
               label: str) -> bool:
    speed_is_pct = fmt[1] == "P"
    blend_is_radius = fmt[2] == "R"
    speed = _speed(v[7], speed_is_pct, robot.settings)
    accel, blend = _accel(v[8]), _blend(v[9], not blend_is_radius)
    precise = not _boolean(v[10], "disablePrecise") if len(v) > 10 else False
    if robot.settings.reject_zero_length_motion and \
            float(dm.norm(target_tcp[:3, 3] - ctx.plan.tcp[:3, 3])) < 1e-9 and \
            float(dm.norm(target_tcp[:3, :3] - ctx.plan.tcp[:3, :3])) < 1e-9:
        raise ArgError("zero-length motion")
    try:
        seg = robot.planner.cart_motion(ctx.plan, target_tcp, speed, speed_is_pct, accel, blend,
                                        blend_is_radius, precise, label)
    except PlanError as exc:
        raise ArgError(str(exc)) from None
    robot.queue_motion(ctx, seg)
    return True


LINE_FORMATS = {"CPP", "CPR", "CAP", "CAR"}


def fn_line(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Line(fmt, pose, speed, accel_ms, blend, disablePrecise)`` (spec §7, timing §8).

    Straight Cartesian line to a pose in the current base, queued.  Format letters: 2nd P = speed
    in % of the maximum, A = mm/s; 3rd P = blend in %, R = blend radius in mm.
    """
    v = _motion_values(args, (11,))
    fmt = _check_format(v[0], LINE_FORMATS, robot.settings)
    return _line_like(robot, ctx, fmt, dm.matmul(ctx.plan.base, pose_to_matrix(_pose6(v[1:7]))), v, f"Line {fmt}")


def _relative_tcp(plan: PlannedState, frame: str, delta: np.ndarray) -> np.ndarray:
    """Target of a relative motion: ``C`` = in the current base, ``T`` = in the tool frame."""
    if frame == "T":
        return dm.matmul(plan.tcp, pose_to_matrix(delta))
    # Choice (§7 Move_*): base-relative adds the translation and the three angles.
    current = matrix_to_pose(dm.matmul(dm.rigid_inverse(plan.base), plan.tcp))
    return dm.matmul(plan.base, pose_to_matrix(current + delta))


def fn_move_ptp(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Move_PTP(fmt, delta, speed%, accel_ms, blend%, disablePrecise)`` (spec §7, timing §8).

    Relative point-to-point motion, queued: ``"CPP"`` in the current base, ``"TPP"`` in the tool
    frame, ``"JPP"`` added to the joint angles.
    """
    v = _motion_values(args, (11,))
    fmt = _check_format(v[0], {"CPP", "TPP", "JPP"}, robot.settings)
    delta = _pose6(v[1:7])
    speed, accel, blend = _speed(v[7], True, robot.settings), _accel(v[8]), _blend(v[9], True)
    precise = not _boolean(v[10], "disablePrecise")
    try:
        if fmt == "JPP":
            joints = ctx.plan.joints + delta
        else:
            joints = robot.planner.solve(ctx.plan, _relative_tcp(ctx.plan, fmt[0], delta))
        seg = robot.planner.joint_motion(ctx.plan, joints, speed, accel, blend, precise, f"Move_PTP {fmt}")
    except PlanError as exc:
        raise ArgError(str(exc)) from None
    robot.queue_motion(ctx, seg)
    return True


def fn_move_line(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Move_Line(fmt, delta, speed, accel_ms, blend, disablePrecise)`` (spec §7, timing §8).

    Relative straight line, queued: ``C..`` formats in the current base, ``T..`` in the tool frame;
    speed and blend letters as for ``Line``.
    """
    v = _motion_values(args, (11,))
    fmt = _check_format(v[0], LINE_FORMATS | {"TPP", "TPR", "TAP", "TAR"}, robot.settings)
    target = _relative_tcp(ctx.plan, fmt[0], _pose6(v[1:7]))
    return _line_like(robot, ctx, fmt, target, v, f"Move_Line {fmt}")


def fn_circle(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Circle(fmt, via, end, speed, accel_ms, blend%, arcAngle, disablePrecise)`` (spec §7, §8).

    Circular arc through ``via``, queued: arcAngle 0 goes to ``end``; otherwise the TCP keeps its
    orientation and sweeps that many degrees.
    """
    v = _motion_values(args, (18,))
    fmt = _check_format(v[0], {"CPP", "CAP"}, robot.settings)
    via = dm.matmul(ctx.plan.base, pose_to_matrix(_pose6(v[1:7])))
    end = dm.matmul(ctx.plan.base, pose_to_matrix(_pose6(v[7:13])))
    speed_is_pct = fmt[1] == "P"
    speed, accel, blend = _speed(v[13], speed_is_pct, robot.settings), _accel(v[14]), _blend(v[15], True)
    arc = _num(v[16], "arc angle")
    precise = not _boolean(v[17], "disablePrecise")
    try:
        seg = robot.planner.circle_motion(ctx.plan, via, end, arc, speed, speed_is_pct, accel, blend,
                                          precise, f"Circle {fmt}")
    except PlanError as exc:
        raise ArgError(str(exc)) from None
    robot.queue_motion(ctx, seg)
    return True


def _pline(robot: ScriptHost, args: list[Any], ctx: ScriptContext, relative: bool) -> bool:
    v = _motion_values(args, (10,))
    allowed = {"JAP", "CAP", "TAP"} if relative else {"JAP", "CAP"}
    fmt = _check_format(v[0], allowed, robot.settings)
    values = _pose6(v[1:7])
    speed, accel, blend = _speed(v[7], False, robot.settings), _accel(v[8]), _blend(v[9], True)
    try:
        if fmt[0] == "J":
            # Choice: PLine "JAP" moves in joint space at speed/max_tcp_speed of full joint speed.
            joints = ctx.plan.joints + values if relative else values
            pct = 100.0 * speed / robot.settings.max_tcp_speed_mm_s
            seg = robot.planner.joint_motion(ctx.plan, joints, pct, accel, blend, False, f"PLine {fmt}")
        else:
            target = _relative_tcp(ctx.plan, fmt[0], values) if relative else dm.matmul(ctx.plan.base, pose_to_matrix(values))
            seg = robot.planner.cart_motion(ctx.plan, target, speed, False, accel, blend, False, False,
                                            f"PLine {fmt}")
    except PlanError as exc:
        raise ArgError(str(exc)) from None
    robot.queue_motion(ctx, seg)
    return True


def fn_pline(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``PLine(fmt, pose, speed mm/s, accel_ms, blend%)`` (spec §7, used by techmanpy).

    Queued: ``"CAP"`` a Cartesian move to a pose in the current base, ``"JAP"`` a joint move.
    """
    return _pline(robot, args, ctx, relative=False)


def fn_move_pline(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Move_PLine(fmt, delta, speed mm/s, accel_ms, blend%)`` (spec §7, used by techmanpy).

    The relative form of ``PLine``; ``"TAP"`` moves in the tool frame.
    """
    return _pline(robot, args, ctx, relative=True)


def fn_change_base(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``ChangeBase("name")`` or ``ChangeBase(pose)`` (spec §7): the base of the following motions.

    Queued: it takes effect for motions planned after it (``ctx.plan``) and on the reported pose
    when the queue reaches it.
    """
    if len(args) == 1 and isinstance(args[0], str):
        if args[0] not in robot.settings.known_bases:
            raise ArgError(f"unknown base {args[0]!r}")
        name, base = args[0], np.eye(4)  # Choice: every named base is the robot base
    else:
        values = _flatten(args)
        if len(values) != 6:
            raise ArgError("ChangeBase needs 6 values")
        name, base = "custom", pose_to_matrix(_pose6(values))
    ctx.plan.base = base
    robot.queue_motion(ctx, Marker("base", (name, base)))
    return True


def fn_change_tcp(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``ChangeTCP("name" | pose[, weight[, inertia]])`` (spec §7): the tool of the following motions.

    Queued like ``ChangeBase``; the planned TCP moves with the tool although the joints do not.
    """
    if len(args) == 1 and isinstance(args[0], str):
        if args[0] not in robot.settings.known_tcps:
            raise ArgError(f"unknown TCP {args[0]!r}")
        name, tool = args[0], np.eye(4)
    else:
        values = _flatten(args)
        if len(values) not in (6, 7, 16):
            raise ArgError("ChangeTCP needs 6, 7 or 16 values")
        numbers = [_num(x, "TCP value") for x in values]
        if len(numbers) >= 7 and numbers[6] < 0:
            raise ArgError("negative TCP mass")
        name, tool = "custom", pose_to_matrix(numbers[:6])
    ctx.plan.tool = tool
    # The TCP moves with the tool even though the joints do not.
    ctx.plan.tcp = robot.kin.fk(ctx.plan.joints, tool)
    robot.queue_motion(ctx, Marker("tcp", (name, tool)))
    return True


def fn_change_load(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``ChangeLoad(kg)`` (spec §7): the payload, queued."""
    kg = _num(args[0], "load")
    if kg < 0:
        raise ArgError("negative load")
    robot.queue_motion(ctx, Marker("load", kg))
    return True


def _tag_number(value: Any) -> int:
    tag = _num(value, "tag")
    if tag != int(tag) or not 1 <= tag <= MAX_TAG:
        raise ArgError("tag outside 1-15")  # §7 QueueTag
    return int(tag)


def fn_queue_tag(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``QueueTag(tag[, wait])`` (spec §7, §5.2, §5.3): a marker in the motion queue.

    The tag (1-15) reads ``false`` until everything queued before it has finished, then ``true``
    with an unsolicited ``$TMSTA 01`` (see ``Robot._marker_reached``).  As a whole statement,
    ``wait`` = 1 also blocks the script (:func:`st_queue_tag`).
    """
    tag = _tag_number(args[0])
    if len(args) == 2 and _num(args[1], "wait") not in (0, 1):
        raise ArgError("wait must be 0 or 1")
    if not ctx.dry:
        # §5.2: re-queuing resets the tag to false; only the most recent tags are remembered.
        robot.tags.pop(tag, None)
        robot.tags[tag] = "false"
        while len(robot.tags) > robot.settings.tag_memory:
            robot.tags.popitem(last=False)
        robot.executor.enqueue(Marker("tag", tag, owner=ctx.conn))
    return True


def fn_wait_queue_tag(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> int:
    """``WaitQueueTag(tag[, timeout])`` inside an expression (spec §7).

    Returns 1 done, 0 not done, -1 no such tag.  Choice: inside an expression it checks once and
    never blocks; as a whole statement see :func:`st_wait_queue_tag`.
    """
    tag = int(_num(args[0], "tag"))
    if tag == 0:
        return 0
    state = robot.tags.get(tag)
    return -1 if state is None else (1 if state == "true" else 0)


def fn_stop_and_clear(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``StopAndClearBuffer()`` (spec §7, §8): stop now and drop every queued motion and marker.

    Instant.  The priority form ``StopAndClearBuffer(n)`` (§4.5) never reaches here: the robot
    runs it as soon as the packet arrives.
    """
    if args:
        # A non-literal or out-of-range priority argument is rejected by the parser; here only
        # the literal priority form can arrive, which the robot runs before buffering.
        raise ArgError("priority form inside a normal script")
    if not ctx.dry:
        robot.stop_and_clear()
    return True


def fn_pause(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Pause()`` (spec §7, §8): the motion decelerates and holds; scripts keep running.

    Instant; Pause while paused is OK with no effect.
    """
    if not ctx.dry and not robot.paused:  # §8: Pause while paused: OK, no effect
        robot.paused = True
        robot.note("paused")
    return True


def fn_resume(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Resume()`` (spec §7, §8): the interrupted motion is completed, then the queue continues.

    Instant; Resume while running is OK with no effect.
    """
    if not ctx.dry and robot.paused:
        robot.paused = False
        robot.note("resumed")
    return True


def fn_listen_send(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> int:
    """``ListenSend(subcmd, data)`` (spec §5.4): ``$TMSTA <subcmd>,<payload>`` to the script's connection.

    Returns 0, or -2 for a subcmd outside 90-99.
    """
    sub = _num(args[0], "subcmd")
    if sub != int(sub) or not 90 <= sub <= 99:
        return -2
    if not ctx.dry and ctx.conn in robot.connections:
        robot.send(ctx.conn, encode("TMSTA", f"{int(sub)},".encode("ascii") + _listen_payload(args[1])))
    return 0


def _listen_payload(value: Any) -> bytes:
    """Strings as text; numbers and arrays as little-endian binary (spec §5.4 [M?]): int32 for
    integers, float32 for floats (Choice)."""
    if isinstance(value, str):
        return value.encode("utf-8")
    if isinstance(value, bool):
        return bytes([1 if value else 0])
    if isinstance(value, (list, tuple)):
        return b"".join(_listen_payload(v) for v in value)
    if isinstance(value, int):
        return struct.pack("<i", value)
    return struct.pack("<f", float(value))


def format_value(value: Any) -> str:
    """GetString formatting.  Choice: up to 7 significant digits (float32 precision), no
    exponent for ordinary magnitudes, arrays as ``{a,b,c}``, bools as ``true``/``false``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "{" + ",".join(format_value(v) for v in value) + "}"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if value == 0:
            return "0"
        text = f"{value:.7g}"
        if "e" in text and 1e-4 <= abs(value) < 1e15:
            text = f"{value:.7f}".rstrip("0").rstrip(".")
        return text
    return str(value)


# ---------------------------------------------------------------- digital I/O objects

#: Digital channels per I/O module (TM5 control box: 16 DI / 16 DO; end module: 4 DI / 4 DO).
IO_CHANNELS = {"ControlBox": 16, "EndModule": 4}


def new_io() -> dict[str, dict[str, list[int]]]:
    """All digital inputs and outputs of a robot at project start: 0 (Low)."""
    return {module: {"DI": [0] * count, "DO": [0] * count} for module, count in IO_CHANNELS.items()}


def _io_module(module: Any) -> str:
    if not isinstance(module, str) or module not in IO_CHANNELS:
        raise ArgError(f"unknown IO module {module!r}")  # Choice: names are case-sensitive (manual 7.5)
    return module


def io_read(robot: ScriptHost, module: Any, member: str) -> list[int]:
    """``IO["<module>"].DI`` / ``.DO`` / ``.InstantDO`` read as a byte array (TM Expression Editor
    manual 7.5 IO, p.222-224: ``byte[] var_di = IO["ControlBox"].DI``); ``[n]`` picks a channel.
    ``InstantDO`` reads the same outputs as ``DO``."""
    name = _io_module(module)
    kind = "DI" if member.lower() == "di" else "DO"
    return list(robot.io[name][kind])


def io_write(robot: ScriptHost, ctx: ScriptContext, module: Any, member: str, channel: Any, value: Any) -> None:
    """``IO["<module>"].DO[n] = v`` / ``.InstantDO[n] = v`` (manual 7.5 IO, p.222-224).

    ``DO`` is a queued command: it goes into the motion queue and is written when the motions queued
    before it have finished (spec §8 "queued DO writes"; TMflow manual p.144 "IO value assignment
    ... placed in the queue and executed in order"). ``InstantDO`` is written when the script line
    runs. The value is 0 (Low) or 1 (High); anything else, or a channel outside the module, fails."""
    name = _io_module(module)
    index = _num(channel, "IO channel")
    if index != int(index) or not 0 <= index < IO_CHANNELS[name]:
        raise ArgError(f"IO channel outside 0-{IO_CHANNELS[name] - 1}")
    level = _num(value, "IO value")
    if level not in (0, 1):
        raise ArgError("IO value must be 0 or 1")
    if member.lower() == "do":
        robot.queue_motion(ctx, Marker("do", (name, int(index), int(level))))
    elif not ctx.dry:
        robot.io[name]["DO"][int(index)] = int(level)
        robot.note(f"IO[{name}].InstantDO[{int(index)}] = {int(level)}")


def apply_io_marker(robot: ScriptHost, marker: Marker) -> None:
    """A queued ``DO`` write reached in the motion queue (see :func:`io_write`)."""
    name, index, level = marker.value
    robot.io[name]["DO"][index] = level
    robot.note(f"IO[{name}].DO[{index}] = {level}")


def fn_get_string(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> str:
    """``GetString(value)`` (spec §7 subset): the value as text, see :func:`format_value`."""
    return format_value(args[0])


def fn_length(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> int:
    """``Length(value)``: bytes of a string (UTF-8) or elements of an array; a number fails."""
    value = args[0]
    if isinstance(value, str):
        return len(value.encode("utf-8"))
    if isinstance(value, (list, tuple)):
        return len(value)
    raise ArgError("Length of a number")


def fn_not_in_expression(robot: ScriptHost, args: list[Any], ctx: ScriptContext) -> bool:
    """``Sleep``/``ScriptExit`` used inside an expression: they block, so only a whole statement may
    call them (spec §4.3); the function fails.
    """
    raise ArgError("blocking function inside an expression")


FUNCTIONS: dict[str, Callable[[ScriptHost, list[Any], ScriptContext], Any]] = {
    "PTP": fn_ptp, "Line": fn_line, "Move_PTP": fn_move_ptp, "Move_Line": fn_move_line,
    "Circle": fn_circle, "PLine": fn_pline, "Move_PLine": fn_move_pline,
    "ChangeBase": fn_change_base, "ChangeTCP": fn_change_tcp, "ChangeLoad": fn_change_load,
    "QueueTag": fn_queue_tag, "WaitQueueTag": fn_wait_queue_tag,
    "StopAndClearBuffer": fn_stop_and_clear, "Pause": fn_pause, "Resume": fn_resume,
    "ScriptExit": fn_not_in_expression, "Sleep": fn_not_in_expression,
    "ListenSend": fn_listen_send, "GetString": fn_get_string, "Length": fn_length,
}


# ---------------------------------------------------------------- blocking statements (§4.3)


def st_queue_tag(robot: ScriptHost, job: ScriptJob, call: sc.Call, ctx: ScriptContext) -> str | None:
    """``QueueTag(tag, 1);`` as a statement (spec §7): queue the tag, then block until it is reached."""
    args = [robot.evaluate(a, ctx) for a in call.args]
    fn_queue_tag(robot, args, ctx)
    if len(args) == 2 and int(args[1]) == 1 and not ctx.dry:
        job.wait = Wait("tag", tag=_tag_number(args[0]))
        return "block"
    return None


def st_wait_queue_tag(robot: ScriptHost, job: ScriptJob, call: sc.Call, ctx: ScriptContext) -> str | None:
    """``WaitQueueTag(tag[, timeout]);`` as a statement (spec §7): block until the tag is reached.

    Timeout < 0 (or none) waits forever, 0 checks once, > 0 waits at most that many ms; tag 0 is
    no tag, i.e. a plain delay (forever without a timeout, until a priority command).
    """
    args = [robot.evaluate(a, ctx) for a in call.args]
    tag = int(_num(args[0], "tag"))
    timeout_ms = int(_num(args[1], "timeout")) if len(args) == 2 else -1
    if ctx.dry:
        return None
    until = None if timeout_ms < 0 else robot.now_ns + timeout_ms * NS_PER_MS
    if tag == 0:  # §7: tag 0 = no tag, a plain delay
        if until is None:
            job.wait = Wait("delay", until_ns=None)  # forever (until a priority command)
            return "block"
        job.wait = Wait("delay", until_ns=until)
        return "block"
    if timeout_ms == 0:
        return None
    job.wait = Wait("waittag", tag=tag, until_ns=until)
    return "block"


def st_sleep(robot: ScriptHost, job: ScriptJob, call: sc.Call, ctx: ScriptContext) -> str | None:
    """``Sleep(ms);`` (spec §7): block the script for ``ms`` milliseconds of robot time."""
    ms = _num(robot.evaluate(call.args[0], ctx), "time")
    if ms < 0:
        raise ArgError("negative sleep")
    if ctx.dry:
        return None
    # exact: the nanoseconds of the number the script wrote (a float's exact value), truncated
    job.wait = Wait("delay", until_ns=robot.now_ns + int(Fraction(ms) * NS_PER_MS))
    return "block"


def st_script_exit(robot: ScriptHost, job: ScriptJob, call: sc.Call, ctx: ScriptContext) -> str | None:
    """``ScriptExit();`` (normal form, spec §4.6): wait for the motion queue to drain, then leave via Pass.

    The node no longer accepts scripts meanwhile (``CPERR F1``, §4.4).  The OK comes after the
    drain, or at once with ``script_exit_ok_after_drain`` off (§11).
    """
    if ctx.dry:
        return "exit"
    robot.begin_exit()
    job.exiting = True
    job.wait = Wait("drain")
    if not robot.settings.script_exit_ok_after_drain:
        robot.reply(job, "OK")  # _finish_exit sends no second OK with this setting
    return "block"


BLOCKING_STATEMENTS: dict[str, Callable[[ScriptHost, ScriptJob, sc.Call, ScriptContext], str | None]] = {
    "QueueTag": st_queue_tag, "WaitQueueTag": st_wait_queue_tag, "Sleep": st_sleep,
    "ScriptExit": st_script_exit,
}
