"""Beckhoff Tc2_System natives (declarations in tc2_system.st, loaded under `--dialect twincat`).

ADS log messages (ADSLOGSTR, ADSLOGDINT, ADSLOGLREAL). On TwinCAT they go to the ADS logger (the
error list of TwinCAT XAE, the Windows event log). Here each message is handed to the run's log
sink `ctx.ads_log(mask, text)` when the caller set one (`stvm test` collects them), else printed
on stdout as one line `error: …`, `warning: …` or `hint: …` after the message type in the mask
(error wins over warning over hint; a mask with none of the three prints `hint:`).
Choice (not documented by Beckhoff): only the first `%s` / `%d` / `%f` is replaced, as the
functions take one argument; the text is cut to 253 bytes, the length Beckhoff gives as the limit.

References (Beckhoff Information System, TwinCAT 3 PLC library Tc2_System):
- ADSLOGSTR   https://infosys.beckhoff.com/content/1031/tcplclib_tc2_system/31033611.html
- ADSLOGDINT  https://infosys.beckhoff.com/content/1033/tcplclib_tc2_system/31030539.html
- ADSLOGLREAL (same page family: ADSLOGDINT with an LREAL argument and `%f`)
- GETCPUCOUNTER, GETCURTASKINDEX (Tc2_System function blocks of the same library)
"""

from __future__ import annotations

import re
import sys

from stvm.lower.bind import st_names
from stvm.stdlib.registry import native_fb, native_function

HINT, WARN, ERROR = 0x01, 0x02, 0x04
MAX_MESSAGE_BYTES = 253


def severity(mask: int) -> str:
    """The word a message of control mask `mask` is printed with."""
    if mask & ERROR:
        return "error"
    if mask & WARN:
        return "warning"
    return "hint"


def _emit(ctx, mask: int, fmt: bytes, placeholder: bytes, arg: bytes) -> int:
    text = fmt.replace(placeholder, arg, 1)[:MAX_MESSAGE_BYTES].decode("latin-1")
    sink = getattr(ctx, "ads_log", None)
    if sink is not None:
        sink(mask, text)
    else:
        print(f"{severity(mask)}: {text}", file=sys.stdout)
    return 0


@native_function("ADSLOGSTR")
def adslogstr(ctx, mask: int, fmt: bytes, arg: bytes) -> int:
    return _emit(ctx, mask, fmt, b"%s", arg)


@native_function("ADSLOGDINT")
def adslogdint(ctx, mask: int, fmt: bytes, arg: int) -> int:
    return _emit(ctx, mask, fmt, b"%d", str(arg).encode())


@native_function("ADSLOGLREAL")
def adsloglreal(ctx, mask: int, fmt: bytes, arg: float) -> int:
    # C's printf %f: six decimals (TwinCAT formats the message with the C runtime)
    return _emit(ctx, mask, fmt, b"%f", f"{arg:f}".encode())


@native_fb("GETCPUCOUNTER")
@st_names("cpuCntLoDW", "cpuCntHiDW")
class CpuCounter:
    """The 64-bit counter in 100 ns ticks: the virtual clock at the start of the scan (so a run
    is deterministic; a test's durations are virtual time) plus BOOT_TICKS. A real CPU counter
    counts from the machine's start and is never 0 at the PLC's first scan; TcUnit takes a
    timestamp of 0 as "not started yet" (an empty suite started in scan 0 would never finish)."""

    BOOT_TICKS = 10_000_000    # choice: as if the machine started 1 s before the first scan

    def call(self, inst, ctx) -> None:
        ticks = ctx.now_ns // 100 + self.BOOT_TICKS
        inst.cpuCntLoDW = ticks & 0xFFFFFFFF
        inst.cpuCntHiDW = (ticks >> 32) & 0xFFFFFFFF


@native_function("GETCURTASKINDEXEX")
def get_cur_task_index_ex(ctx) -> int:
    """Tc2_System GETCURTASKINDEXEX: GETCURTASKINDEX as a function (the running task's index)."""
    indices = getattr(ctx, "task_indices", None) or {}
    return indices.get(ctx.task, 1)


@native_fb("GETCURTASKINDEX")
@st_names("index")
class CurrentTaskIndex:
    """TwinCAT numbers the tasks from 1; stvm runs one task's code at a time and reports the
    index of the task by its position in the configuration (1 when there is none)."""

    def call(self, inst, ctx) -> None:
        indices = getattr(ctx, "task_indices", None) or {}
        inst.index = indices.get(ctx.task, 1)


MAX_TASKS = 8   # the bound of _TaskInfo in tc2_system.st


class SystemInfo:
    """Fills TwinCAT_SystemInfoVarList before each scan (a VM scan-start hook): for every task
    due at this tick, CycleCount (cycles completed before this one) and FirstCycle; once, the
    static members (cycle time, priority, names). The project name is the manifest's
    `[project] name`, else the project folder's name."""

    def __init__(self, vm, project_name: str) -> None:
        self.vm = vm
        self.cycles = [0] * len(vm.tasks)
        self.index = {task.name: i + 1 for i, task in enumerate(vm.tasks[:MAX_TASKS])}
        self.set = lambda path, value: (vm.set(f"TwinCAT_SystemInfoVarList.{path}", value),
                                        vm.set(path, value))   # the bare `_TaskInfo[i]` too
        self.set("_AppInfo.TaskCnt", len(vm.tasks))
        self.set("_AppInfo.ProjectName", project_name.encode("latin-1", "replace")[:63])
        self.set("_AppInfo.AppName", b"Port_851")
        for task in vm.tasks[:MAX_TASKS]:
            at = f"_TaskInfo[{self.index[task.name]}]"
            self.set(f"{at}.CycleTime", task.interval_ns // 100)
            self.set(f"{at}.Priority", task.priority)
            self.set(f"{at}.TaskName", task.name.encode("latin-1", "replace")[:63])

    def __call__(self, vm) -> None:
        tick = vm.scan_count
        for i, task in enumerate(vm.tasks[:MAX_TASKS]):
            if tick % task.every:
                continue
            at = f"_TaskInfo[{i + 1}]"
            self.set(f"{at}.CycleCount", self.cycles[i] & 0xFFFFFFFF)
            self.set(f"{at}.FirstCycle", self.cycles[i] == 0)
            self.cycles[i] += 1


def install_system_info(vm, project) -> None:
    """Make `vm` keep TwinCAT_SystemInfoVarList current (twincat dialect only)."""
    manifest = getattr(project, "manifest", {}) or {}
    root = getattr(project, "root", None)
    name = manifest.get("project", {}).get("name") or (root.name if root is not None else "stvm")
    hook = SystemInfo(vm, str(name))
    vm.on_scan_start.append(hook)
    fill_instance_paths(vm, str(name))
    # GETCURTASKINDEX reads the index of the task whose code runs (ctx.task holds its name)
    vm.ctx.task_indices = hook.index


# Windows code page 1252 case pairs beyond ASCII (Tc2_Utilities F_ToLCase / F_ToUCase): Š Œ Ž Ÿ
# and the Latin-1 letters À..Þ except × (16#D7); ß and ÿ have no upper-case form in the code page
_UPPER = bytes(range(0x41, 0x5B)) + bytes([0x8A, 0x8C, 0x8E, 0x9F]) + bytes(
    b for b in range(0xC0, 0xDF) if b != 0xD7)
_LOWER = bytes(range(0x61, 0x7B)) + bytes([0x9A, 0x9C, 0x9E, 0xFF]) + bytes(
    b + 0x20 for b in range(0xC0, 0xDF) if b != 0xD7)
_TO_LOWER = bytes.maketrans(_UPPER, _LOWER)
_TO_UPPER = bytes.maketrans(_LOWER, _UPPER)


def _recase(text: bytes, table: bytes, upper: bool) -> bytes:
    """Choice: a STRING whose bytes are UTF-8 text with letters beyond ASCII (stvm reads UTF-8
    sources, so a literal 'Ä' is two bytes) is recased as that text, letter for letter where the
    letter keeps its length in bytes; any other STRING is code page 1252 bytes, as on TwinCAT."""
    if text.isascii():
        return text.translate(table)
    try:
        decoded = text.decode("utf-8")
    except UnicodeDecodeError:
        return text.translate(table)
    out = []
    for ch in decoded:
        other = ch.upper() if upper else ch.lower()
        out.append(other if len(other) == 1 and len(other.encode()) == len(ch.encode()) else ch)
    return "".join(out).encode("utf-8")


@native_function("F_ToLCase")
def f_to_lcase(ctx, text: bytes) -> bytes:
    return _recase(text, _TO_LOWER, upper=False)


@native_function("F_ToUCase")
def f_to_ucase(ctx, text: bytes) -> bytes:
    return _recase(text, _TO_UPPER, upper=True)


# ---- FB_FormatString (Tc2_Utilities) ------------------------------------------------------------
# E_ArgType values (Tc2_Utilities "E_ArgType")
_ARG_UNKNOWN, _ARG_REAL, _ARG_LREAL, _ARG_STRING = 0, 4, 5, 12
_ARG_SIGNED = {6: 8, 7: 16, 8: 32, 17: 64}                              # SINT INT DINT LARGE: bits
_ARG_UNSIGNED = {1: 8, 2: 16, 3: 32, 9: 8, 10: 16, 11: 32, 13: 1, 15: 64, 19: 64}   # ... BOOL ULARGE LWORD
_SPEC = re.compile(rb"%([-+ 0#]*)(\d*)(?:\.(\d*))?(.)", re.DOTALL)
FORMAT_ERROR = 1   # nErrId of a bad format or argument (Choice: Beckhoff does not list the codes)


class FormatError(Exception):
    pass


@st_names("eType", "nValue", "uValue", "fValue", "sValue")
def _arg_value(arg):
    """(kind, value) of a T_Arg: 'int' ((signed value, its type's bits)), 'uint', 'real', 'str'."""
    kind = arg.eType
    if kind in _ARG_SIGNED:
        return "int", (arg.nValue, _ARG_SIGNED[kind])
    if kind in _ARG_UNSIGNED:
        return "uint", arg.uValue
    if kind in (_ARG_REAL, _ARG_LREAL):
        return "real", arg.fValue
    if kind == _ARG_STRING:
        return "str", arg.sValue
    raise FormatError(f"argument type {kind}")


def format_args(fmt: bytes, args: list) -> bytes:
    """sFormat with each %-field replaced by the next argument (Tc2_Utilities "Format
    specification": %[flags][width][.precision]type, flags - + space 0 #, types d/D signed,
    u/U unsigned, b/B binary, o/O octal, x/X hex, c/C character, f/F fixed, e/E exponent, s/S
    string, %% a percent sign). FormatError on an unknown type or a missing/unsuitable argument."""
    out = bytearray()
    pos, next_arg = 0, 0
    for match in _SPEC.finditer(fmt):
        out += fmt[pos:match.start()]
        pos = match.end()
        flags, width, precision, kind = (match.group(1).decode(), match.group(2).decode(),
                                         match.group(3), match.group(4).decode("latin-1"))
        if kind == "%" and not flags and not width and precision is None:
            out += b"%"
            continue
        if next_arg >= len(args):
            raise FormatError("too few arguments")
        what, value = _arg_value(args[next_arg])
        next_arg += 1
        bits = 64
        if what == "int":
            value, bits = value
        prec = "" if precision is None else "." + (precision.decode() or "0")
        spec = "%" + flags + width + prec
        lower = kind.lower()
        if lower == "d":
            if what in ("real", "str"):
                raise FormatError("%d of a non-integer")
            text = (spec + "d") % value
        elif lower in ("u", "x", "o"):
            if what in ("real", "str"):
                raise FormatError(f"%{kind} of a non-integer")
            unsigned = value & ((1 << bits) - 1)   # a negative value as its type's bit pattern
            letter = {"u": "d", "x": "x", "o": "o"}[lower] if kind != "X" else "X"
            text = (spec + letter) % unsigned
        elif lower == "b":
            if what in ("real", "str"):
                raise FormatError("%b of a non-integer")
            digits = format(value & ((1 << bits) - 1), "b")
            text = digits.rjust(int(width or 0), "0" if "0" in flags else " ") if "-" not in flags \
                else digits.ljust(int(width or 0))
        elif lower == "c":
            if what in ("real", "str"):
                raise FormatError("%c of a non-integer")
            text = (spec.replace("0", "") + "c") % chr(value & 0xFF)
        elif lower in ("f", "e"):
            if what == "str":
                raise FormatError(f"%{kind} of a string")
            text = (spec + kind) % float(value)
        elif lower == "s":
            if what != "str":
                raise FormatError("%s of a number")
            text = (spec + "s") % value.decode("latin-1")
        else:
            raise FormatError(f"type field {kind!r}")
        out += text.encode("latin-1", "replace")
    out += fmt[pos:]
    return bytes(out[:255])


@native_fb("FB_FormatString")
@st_names("sFormat", "arg1", "arg2", "arg3", "arg4", "arg5", "arg6", "arg7", "arg8", "arg9", "arg10",
          "bError", "nErrId", "sOut", "eType", "nValue", "uValue", "fValue", "sValue")
class FormatString:
    """Formats in the same call, as Beckhoff's FB does; on an error sOut is empty."""

    def call(self, inst, ctx) -> None:
        args = [inst.arg1, inst.arg2, inst.arg3, inst.arg4, inst.arg5, inst.arg6, inst.arg7, inst.arg8,
                inst.arg9, inst.arg10]
        try:
            inst.sOut = format_args(inst.sFormat, args)
            inst.bError, inst.nErrId = False, 0
        except FormatError:
            inst.sOut, inst.bError, inst.nErrId = b"", True, FORMAT_ERROR


def fill_instance_paths(vm, project_name: str) -> None:
    """`{attribute 'instance-path'}` (Beckhoff Infosys, TwinCAT 3 PLC "Attribute 'instance-path'"):
    a STRING member of a function block so marked holds the path of each instance, which TwinCAT
    writes before the first cycle: the PLC project's name, then the instance's path
    (`TcUnitVerifier.PRG_TEST.PrimitiveTypes`; TcUnit strips the project name). Written once at
    start, for every FB instance the variable catalog lists (stvm/runtime/catalog.py)."""
    from stvm.runtime.catalog import Catalog   # lazy: twincat projects only
    pous = vm.model.pous
    marked: dict[str, list[str]] = {}

    def marked_members(qualname: str) -> list[str]:
        key = qualname.lower()
        if key not in marked:
            names, seen, info = [], set(), pous.get(key)
            while info is not None and info.qualname.lower() not in seen:    # the FB and its bases
                seen.add(info.qualname.lower())
                names += [v.name for v in info.variables.values() if getattr(v, "instance_path", False)]
                info = pous.get(info.base) if info.base else None
            marked[key] = names
        return marked[key]

    if not any(getattr(v, "instance_path", False) for info in pous.values() for v in info.variables.values()):
        return
    from stvm.semantics import types as t   # lazy: as above
    for node in Catalog(vm).walk():
        if isinstance(node.type, t.FBType) and not node.type.is_program:
            for name in marked_members(node.type.qualname):
                text = f"{project_name}.{node.path}".encode("latin-1", "replace")
                vm.set(f"{node.path}.{name}", text)


FILETIME_1970 = 116_444_736_000_000_000   # 100 ns intervals from 1601-01-01 to 1970-01-01


@native_function("F_GetSystemTime")
def f_get_system_time(ctx) -> int:
    """Tc2_System F_GetSystemTime: 100 ns intervals since 1601-01-01, from the virtual date and
    time (the run's start DT plus the virtual clock at the start of the scan), so it is the same
    on every run; in a real-time run, the host's clock (UTC)."""
    if ctx.realtime:
        import time   # lazy: only a real-time run reads the host clock
        return time.time_ns() // 100 + FILETIME_1970
    return (ctx.start_dt_ns + ctx.now_ns) // 100 + FILETIME_1970
