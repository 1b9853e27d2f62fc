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
    is deterministic; a test's durations are virtual time)."""

    def call(self, inst, ctx) -> None:
        ticks = ctx.now_ns // 100
        inst.cpuCntLoDW = ticks & 0xFFFFFFFF
        inst.cpuCntHiDW = (ticks >> 32) & 0xFFFFFFFF


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
        self.set = lambda path, value: vm.set(f"TwinCAT_SystemInfoVarList.{path}", value)
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
