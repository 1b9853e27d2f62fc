"""Breakpoints compiled into the generated code, and a way to reach a running worker thread.

A debugger that traces every line (`sys.settrace`) makes a scan 5–30 times slower even when no
breakpoint is ever hit: on Python 3.11 a traced thread runs every instruction through the
interpreter's tracing path. So the engine runs untraced until something needs it (stepping, a
pause, the end of the session), and a breakpoint is a call written into the generated code at its
line:

* `BreakpointHooks.update(lines)` recompiles only the functions (POU bodies, METHODs) that gain or
  lose a breakpoint. Their source is the debug build's own generated text, parsed again as a
  Python syntax tree; at each breakpoint line a call `_dbg_bp(LINE)` is added as a statement before
  the statement that starts there, on the same line (so every line number, fault location and
  statement map stays valid). A WHILE test is a stop on every iteration, so there the call goes
  into the test (`_dbg_bp(LINE) or (test)`: the call returns None). The new code object replaces
  the live function's `__code__`: instances, classes and the module namespace stay as they are,
  calls from then on run the new code. A function without breakpoints gets its original code
  back. A line that cannot take a call (not the start of a statement in a POU body) is reported
  as `unhooked`: the engine traces its POU the slow way, as before.
* `ThreadKicker` makes a running worker thread install the engine's trace function at its next
  line (to pause it, end it, or arm frames that run code compiled before a breakpoint was set).
  `sys.settrace` only acts on the calling thread. On CPython 3.11 (and up to 3.13) the kicker
  gives the worker's thread state a C-level trace function through `_PyEval_SetTrace`, the call
  behind `threading.settrace_all_threads` in 3.12; it runs once in the worker, where it calls
  `sys.settrace` itself. Where that function is missing, `sys.monitoring` (PEP 669, Python ≥ 3.12)
  delivers a LINE event to the worker instead. With neither, `available` is False and the engine
  keeps its trace function installed while running (correct, but slow).

Nothing here sees ST text: the syntax tree is that of the generated module, and the only code
added is a call with an integer constant.
"""

from __future__ import annotations

import ast
import sys
import threading
from types import CodeType, FunctionType
from typing import Any, Callable

from stvm.runtime.vm import GENERATED_FILENAME

HOOK_NAME = "_dbg_bp"    # the generator writes no name with this prefix (its names: v_, P…, F…, _f, _r, …)

_NESTED = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)


class _Unit:
    """One top-level class or function of the generated module: its text and its functions."""

    def __init__(self, name: str, start: int, end: int, is_class: bool) -> None:
        self.name, self.start, self.end, self.is_class = name, start, end, is_class   # lines start..end-1 (1-based)
        self.functions: list[tuple[str, int, int]] | None = None   # (name, first line, last line)


class BreakpointHooks:
    """The live functions of one VM's generated module, with calls at breakpoint lines."""

    def __init__(self, source: str, namespace: dict[str, Any], hook: Callable[[int], None]) -> None:
        self._lines = source.splitlines(keepends=True)
        self._ns = namespace
        namespace[HOOK_NAME] = hook
        self._units = self._index_units()
        self._starts = [u.start for u in self._units]
        self._original: dict[tuple[str, str], CodeType] = {}        # (unit, function) → code as built
        self._current: dict[tuple[str, str], frozenset[int]] = {}   # hooked lines now compiled in
        self._variants: dict[tuple[str, str, frozenset[int]], tuple[CodeType, frozenset[int]]] = {}
        # every code object made here → the lines it calls the hook at (kept for frames still
        # running an older variant)
        self.hooked: dict[CodeType, frozenset[int]] = {}
        self.unhooked: frozenset[int] = frozenset()

    def _index_units(self) -> list[_Unit]:
        units: list[_Unit] = []
        for number, text in enumerate(self._lines, 1):
            if text.startswith(("class ", "def ")):
                name = text.split(None, 1)[1].split("(")[0].split(":")[0].strip()
                if units:
                    units[-1].end = number
                units.append(_Unit(name, number, len(self._lines) + 1, text.startswith("class ")))
        return units

    def _unit_of(self, line: int) -> _Unit | None:
        import bisect
        i = bisect.bisect_right(self._starts, line) - 1
        return self._units[i] if i >= 0 and line < self._units[i].end else None

    def _parse(self, unit: _Unit) -> ast.stmt:
        text = "".join(self._lines[unit.start - 1:unit.end - 1])
        tree = ast.parse(text, GENERATED_FILENAME)
        ast.increment_lineno(tree, unit.start - 1)
        return tree.body[0]

    def _function_of(self, unit: _Unit, line: int) -> str | None:
        if unit.functions is None:
            node = self._parse(unit)
            defs = node.body if unit.is_class else [node]
            unit.functions = [(d.name, d.lineno, d.end_lineno or d.lineno) for d in defs
                              if isinstance(d, ast.FunctionDef)]
        for name, first, last in unit.functions:
            if first <= line <= last:
                return name
        return None

    def _live(self, unit: _Unit, function: str) -> FunctionType | None:
        owner = self._ns.get(unit.name)
        if owner is None:
            return None
        target = vars(owner).get(function) if unit.is_class else owner
        return target if isinstance(target, FunctionType) else None

    def update(self, lines: set[int]) -> None:
        """Compile calls in at exactly `lines` (generated line numbers of statement starts)."""
        wanted: dict[tuple[str, str], set[int]] = {}
        unhooked: set[int] = set()
        for line in lines:
            unit = self._unit_of(line)
            function = self._function_of(unit, line) if unit is not None else None
            if function is None or self._live(unit, function) is None:
                unhooked.add(line)
                continue
            wanted.setdefault((unit.name, function), set()).add(line)
        for key in set(self._current) | set(wanted):
            want = frozenset(wanted.get(key, ()))
            if self._current.get(key, frozenset()) == want:
                continue
            unit = next(u for u in self._units if u.name == key[0])
            live = self._live(unit, key[1])
            assert live is not None
            if key not in self._original:
                self._original[key] = live.__code__
            if not want:
                live.__code__ = self._original[key]
                del self._current[key]
                continue
            variant = self._variants.get((*key, want))
            if variant is None:
                variant = self._variants[(*key, want)] = self._compile(unit, key[1], want, live)
            code, done = variant
            unhooked |= want - done
            live.__code__ = code
            self._current[key] = want
            self.hooked[code] = done
        self.unhooked = frozenset(unhooked)

    def _compile(self, unit: _Unit, function: str, lines: frozenset[int],
                 live: FunctionType) -> tuple[CodeType, frozenset[int]]:
        node = self._parse(unit)
        func = next(d for d in (node.body if unit.is_class else [node])
                    if isinstance(d, ast.FunctionDef) and d.name == function)
        done = frozenset(line for line in lines if _insert_hook(func.body, line))
        if unit.is_class:   # compiled inside a class of the same name: the same co_qualname
            assert isinstance(node, ast.ClassDef)
            node.body = [func]
            node.decorator_list = []
        module = ast.Module(body=[node], type_ignores=[])
        ast.fix_missing_locations(module)
        code = compile(module, GENERATED_FILENAME, "exec")
        found = _find_code(code, live.__code__.co_qualname)
        if found is None or found.co_freevars != live.__code__.co_freevars:
            return live.__code__, frozenset()
        return found, done


def _hook_call(line: int, col: int) -> ast.Call:
    return ast.Call(func=ast.Name(id=HOOK_NAME, ctx=ast.Load(), lineno=line, col_offset=col,
                                  end_lineno=line, end_col_offset=col + len(HOOK_NAME)),
                    args=[ast.Constant(value=line, lineno=line, col_offset=col, end_lineno=line,
                                       end_col_offset=col + 1)],
                    keywords=[], lineno=line, col_offset=col, end_lineno=line, end_col_offset=col + 1)


def _insert_hook(body: list[ast.stmt], line: int) -> bool:
    """Put a hook call at the statement starting at `line` in `body` (or a block nested in it,
    but not in a nested function). False when no statement starts there."""
    for index, stmt in enumerate(body):
        if stmt.lineno == line:
            col = stmt.col_offset
            if isinstance(stmt, ast.While) and not isinstance(stmt.test, ast.Constant):
                # the test runs on every iteration: the hook runs with it
                test = stmt.test
                stmt.test = ast.BoolOp(op=ast.Or(), values=[_hook_call(line, test.col_offset), test],
                                       lineno=test.lineno, col_offset=test.col_offset,
                                       end_lineno=test.end_lineno, end_col_offset=test.end_col_offset)
            else:
                body.insert(index, ast.Expr(value=_hook_call(line, col), lineno=line, col_offset=col,
                                            end_lineno=line, end_col_offset=col + 1))
            return True
        end = stmt.end_lineno or stmt.lineno
        if stmt.lineno < line <= end and not isinstance(stmt, _NESTED):
            for block in _blocks(stmt):
                if _insert_hook(block, line):
                    return True
            return False
    return False


def _blocks(stmt: ast.stmt) -> list[list[ast.stmt]]:
    out = []
    for name in ("body", "orelse", "finalbody"):
        block = getattr(stmt, name, None)
        if isinstance(block, list) and block and isinstance(block[0], ast.stmt):
            out.append(block)
    for handler in getattr(stmt, "handlers", ()) or ():
        out.append(handler.body)
    for case in getattr(stmt, "cases", ()) or ():
        out.append(case.body)
    return out


def _find_code(code: CodeType, qualname: str) -> CodeType | None:
    for const in code.co_consts:
        if isinstance(const, CodeType):
            if const.co_qualname == qualname:
                return const
            found = _find_code(const, qualname)
            if found is not None:
                return found
    return None


class ThreadKicker:
    """Runs `on_kick()` in a worker thread at its next line event (see the module text).

    Create it in the worker thread; `kick()` is called from any other thread."""

    def __init__(self, on_kick: Callable[[], None]) -> None:
        self._on_kick = on_kick
        self._thread_id = threading.get_ident()
        self._lock = threading.Lock()   # no kick once the worker closed it (its thread state goes)
        self._pending = False
        self._mode = ""
        self._tstate = None
        self._callback = None
        try:
            import ctypes
            api = ctypes.pythonapi
            set_trace = api._PyEval_SetTrace
        except (ImportError, AttributeError):
            set_trace = None
        if set_trace is not None:
            set_trace.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.py_object]
            set_trace.restype = ctypes.c_int
            api.PyThreadState_Get.restype = ctypes.c_void_p
            self._tstate = api.PyThreadState_Get()   # this (the worker) thread's state
            # int (*)(PyObject *obj, PyFrameObject *frame, int what, PyObject *arg); pointers
            # only (a `return` event during an exception passes a NULL arg)
            tracefunc = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                         ctypes.c_void_p)
            self._callback = tracefunc(self._c_trace)
            self._set_trace = set_trace
            self._callback_ptr = ctypes.cast(self._callback, ctypes.c_void_p)
            self._mode = "ctypes"
        elif hasattr(sys, "monitoring"):   # pragma: no cover - Python ≥ 3.12 without the C entry
            monitoring = sys.monitoring
            self._tool = monitoring.DEBUGGER_ID
            if monitoring.get_tool(self._tool) is None:
                monitoring.use_tool_id(self._tool, "stvm debug")
                monitoring.register_callback(self._tool, monitoring.events.LINE, self._monitor_line)
                self._mode = "monitoring"

    @property
    def available(self) -> bool:
        return bool(self._mode)

    def kick(self) -> None:
        with self._lock:
            if self._mode == "ctypes":
                self._set_trace(self._tstate, self._callback_ptr, None)
            elif self._mode == "monitoring":   # pragma: no cover - Python ≥ 3.12 without the C entry
                self._pending = True
                sys.monitoring.set_events(self._tool, sys.monitoring.events.LINE)

    def close(self) -> None:
        """(Worker thread, before it ends) no kick after this."""
        with self._lock:
            if self._mode == "monitoring":   # pragma: no cover
                sys.monitoring.set_events(self._tool, 0)
                sys.monitoring.register_callback(self._tool, sys.monitoring.events.LINE, None)
                sys.monitoring.free_tool_id(self._tool)
            self._mode = ""

    def _c_trace(self, obj: Any, frame: Any, what: int, arg: Any) -> int:
        # runs in the worker, as its C trace function; the engine's `sys.settrace` replaces it
        sys.settrace(None)
        try:
            self._on_kick()
        except BaseException:   # noqa: BLE001 - a C trace function must not leak an exception
            pass
        return 0

    def _monitor_line(self, code: CodeType, line: int) -> Any:   # pragma: no cover - Python ≥ 3.12
        if threading.get_ident() != self._thread_id or not self._pending:
            return None
        self._pending = False
        sys.monitoring.set_events(self._tool, 0)
        self._on_kick()
        return None
