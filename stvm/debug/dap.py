"""`stvm dap`: a Debug Adapter Protocol server on stdin/stdout, on the same engine as the console.

Protocol (https://microsoft.github.io/debug-adapter-protocol/): `Content-Length` framed JSON.
Supported requests: initialize, launch, setBreakpoints (conditions), setExceptionBreakpoints,
configurationDone, threads (one per task), stackTrace, scopes (Locals, Inputs/Outputs, Globals;
between scans: Globals, Programs), variables (structs, arrays with paging, FB instances
expandable), source (library text), continue, next, stepIn, stepOut, pause, setVariable, evaluate
(hover, watch, repl; in the Debug Console also `force VAR := VALUE`, `unforce VAR|all`, `forces`,
`set VAR := VALUE`, `scan [N]`), exceptionInfo, terminate, disconnect. Events: initialized,
stopped (entry, breakpoint, step, pause, exception for a runtime fault), output, terminated,
exited.

Launch arguments (see docs/debugging.md): `program` (an ST file or a list), `cwd`, `scan`,
`scenario`, `robot` (lockstep | emulator | HOST:PORT), `set` (["NAME=VALUE"]), `sysmac`,
`dialect` and `define` (as the command line's --dialect and --define), `stopOnEntry`, `realtime`, `cycles` (end after N scans).
"""

from __future__ import annotations

import json
import os
import threading
from dataclasses import dataclass
from typing import Any, BinaryIO

from stvm.debug.engine import (BREAKPOINT, CONTINUE, ENTRY, FAULT, FAULTED, FINISH, NEXT, PAUSED,
                               SCAN, SCANNED, STEP, STEPPED, Engine, StopEvent)
from stvm.debug.scope import DebugError, is_scalar_ref
from stvm.diagnostics import printable
from stvm.lower.layout import VarSlot
from stvm.runtime.catalog import Catalog, call_slots, element_path
from stvm.semantics import types as t
from stvm.semantics.model import IN_OUT, INPUT, OUTPUT
from stvm.project import LoadError
from stvm.diagnostics import render
from stvm.debug.console import parse_assignment

_REASONS = {ENTRY: "entry", BREAKPOINT: "breakpoint", STEPPED: "step", PAUSED: "pause", SCANNED: "step",
            FAULT: "exception"}
_SCALARS = (t.BoolType, t.IntType, t.RealType, t.TimeType, t.StringType, t.EnumType)
_GLOBAL_FRAME = -1


class ProtocolError(Exception):
    pass


class FramingError(Exception):
    """The byte stream is not `Content-Length` framed: the session cannot go on."""


class BadMessage(Exception):
    """A well-framed message that is not a usable JSON object: it is reported and skipped."""


MAX_MESSAGE_BYTES = 16 * 2**20   # a DAP message (setBreakpoints of a huge file is far below)
MAX_HEADER_LINE = 8192
MAX_HANDLES = 100_000            # variablesReferences alive at one stop (see DapServer._handle)
MAX_BREAKPOINTS_PER_FILE = 1000  # a conditional one is compiled when set (~15 ms): 1,000 is ~15 s at most


def _int_arg(args: dict, name: str, default: int = 0) -> int:
    value = args.get(name)
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int):
        raise ProtocolError(f"argument {name!r} must be an integer, got {json.dumps(value)[:40]}")
    return value


def _str_arg(args: dict, name: str, default: str | None = None) -> str | None:
    value = args.get(name)
    if value is None:
        return default
    if not isinstance(value, str):
        raise ProtocolError(f"argument {name!r} must be a string, got {json.dumps(value)[:40]}")
    return value


def _str_list_arg(args: dict, name: str) -> list[str]:
    value = args.get(name)
    if value is None:
        return []
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ProtocolError(f"argument {name!r} must be a list of strings, got {json.dumps(value)[:40]}")
    return list(value)


def _dict_arg(args: dict, name: str) -> dict:
    value = args.get(name)
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ProtocolError(f"argument {name!r} must be an object, got {json.dumps(value)[:40]}")
    return value


@dataclass
class _Node:
    """What a variablesReference stands for: a scope of a frame, or an aggregate value."""

    kind: str                 # locals | io | globals | programs | value
    frame: int = 0            # frame index the paths are relative to (-1: global scope)
    value: Any = None
    type: t.Type | None = None
    path: str | None = None   # ST text of the value (None: not addressable)
    indices: tuple = ()       # array indices given so far (multi-dimensional arrays)


class DapServer:
    def __init__(self, rfile: BinaryIO, wfile: BinaryIO, log_path: str | None = None) -> None:
        self.rfile = rfile
        self.wfile = wfile
        self.log = open(log_path, "a", encoding="utf-8") if log_path else None
        self.seq = 0
        self.write_lock = threading.Lock()
        self.handles: dict[int, _Node] = {}
        self.handle_keys: dict[tuple, int] = {}   # scope or path → its reference (see _handle)
        self.handle_lock = threading.Lock()
        self.session = None
        self.engine: Engine | None = None
        self.launch_args: dict = {}
        self.pending_breakpoints: list[dict] = []
        self.sources: dict[int, str] = {}       # sourceReference → file name (library text)
        self.terminated_sent = False
        self.running = True

    # ================================================================ transport
    def read_message(self) -> dict | None:
        """The next message (a JSON object), or None at the end of the input. Raises
        FramingError when the header cannot be used (the stream cannot be resynchronised) and
        BadMessage for a well-framed body that is not a JSON object (the session goes on)."""
        length = None
        headers = 0
        while True:
            line = self.rfile.readline(MAX_HEADER_LINE + 1)
            if not line:
                return None
            if len(line) > MAX_HEADER_LINE:
                raise FramingError(f"header line longer than {MAX_HEADER_LINE} bytes")
            headers += 1
            if headers > 32:
                raise FramingError("more than 32 header lines without a blank line")
            line = line.strip()
            if not line:
                if length is not None:
                    break
                continue
            name, sep, value = line.decode("ascii", "replace").partition(":")
            if not sep:
                raise FramingError(f"malformed header {printable(line.decode('ascii', 'replace'), 80)!r} "
                                   f"(expected 'Content-Length: N')")
            if name.strip().lower() == "content-length":
                text = value.strip()
                if not text.isdigit():
                    raise FramingError(f"Content-Length must be a byte count, got {printable(text, 40)!r}")
                length = int(text)
                if length > MAX_MESSAGE_BYTES:
                    raise FramingError(f"Content-Length {length} is over the limit of {MAX_MESSAGE_BYTES} bytes")
        body = self.rfile.read(length)
        if len(body) < length:
            return None
        try:
            message = json.loads(body.decode("utf-8"))
        except UnicodeDecodeError as exc:
            raise BadMessage(f"message body is not UTF-8 ({exc.reason} at byte {exc.start})") from None
        except (ValueError, RecursionError) as exc:
            raise BadMessage(f"message body is not JSON ({printable(str(exc), 120)})") from None
        if not isinstance(message, dict):
            raise BadMessage(f"a message must be a JSON object, got {type(message).__name__}")
        self._log("<-", message)
        return message

    def send(self, message: dict) -> None:
        with self.write_lock:
            self.seq += 1
            message["seq"] = self.seq
            data = json.dumps(message).encode("utf-8")
            self._log("->", message)
            self.wfile.write(b"Content-Length: %d\r\n\r\n" % len(data) + data)
            self.wfile.flush()

    def _log(self, direction: str, message: dict) -> None:
        if self.log is not None:
            self.log.write(f"{direction} {json.dumps(message)}\n")
            self.log.flush()

    def respond(self, request: dict, body: dict | None = None, success: bool = True, message: str = "") -> None:
        response = {"type": "response", "request_seq": request.get("seq", 0), "command": request.get("command", ""),
                    "success": success}
        if message:
            response["message"] = message
        if body is not None or success:
            response["body"] = body or {}
        if not success:
            response["body"] = {"error": {"id": 1, "format": message, "showUser": True}}
        self.send(response)

    def event(self, name: str, body: dict | None = None) -> None:
        self.send({"type": "event", "event": name, "body": body or {}})

    def output(self, text: str, category: str = "console") -> None:
        self.event("output", {"category": category, "output": text if text.endswith("\n") else text + "\n"})

    # ================================================================ loop
    def serve(self) -> int:
        try:
            while self.running:
                try:
                    message = self.read_message()
                except BadMessage as exc:
                    self.output(f"stvm dap: ignored a message: {exc}", "stderr")
                    continue
                except FramingError as exc:
                    self.output(f"stvm dap: protocol error, ending the session: {exc}", "stderr")
                    import sys
                    print(f"stvm: error: dap: {exc}", file=sys.stderr)
                    return 2
                if message is None:
                    break
                if message.get("type") != "request":
                    continue
                self.dispatch(message)
        finally:
            self._close()
            if self.log is not None:
                self.log.close()
        return 0

    def dispatch(self, request: dict) -> None:
        command = request.get("command", "")
        seq = request.get("seq", 0)
        if not isinstance(command, str) or not isinstance(seq, int) or isinstance(seq, bool) \
                or not isinstance(request.get("arguments") or {}, dict):
            # answered under the request's own seq when it has one, so the client can match it
            self.respond({"seq": seq if isinstance(seq, int) and not isinstance(seq, bool) else 0,
                          "command": command if isinstance(command, str) else ""}, success=False,
                         message="a request needs \"command\" (a string), \"seq\" (an integer) and "
                                 "\"arguments\" (an object)")
            return
        handler = getattr(self, "on_" + command, None) if command.isidentifier() else None
        if handler is None:
            self.respond(request, success=False, message=f"unsupported request {command!r}")
            return
        try:
            body = handler(request.get("arguments") or {})
        except DebugError as exc:
            self.respond(request, success=False, message=str(exc))
            return
        except ProtocolError as exc:
            self.respond(request, success=False, message=str(exc))
            return
        except RecursionError:
            self.respond(request, success=False, message="the request is nested too deeply for stvm dap")
            return
        except Exception as exc:  # an adapter bug: answer, keep serving
            self.respond(request, success=False, message=f"internal error in stvm dap ({type(exc).__name__}: "
                                                         f"{printable(str(exc), 200)})")
            return
        self.respond(request, body)
        after = getattr(self, "after_" + command, None)
        if after is not None:
            after()

    def _close(self) -> None:
        if self.session is not None:
            session, self.session = self.session, None
            session.close()

    def _require_engine(self) -> Engine:
        if self.engine is None:
            raise ProtocolError("no program: send launch first")
        return self.engine

    # ================================================================ requests: setup
    def on_initialize(self, args: dict) -> dict:
        return {
            "supportsConfigurationDoneRequest": True,
            "supportsConditionalBreakpoints": True,
            "supportsEvaluateForHovers": True,
            "supportsSetVariable": True,
            "supportsTerminateRequest": True,
            "supportsExceptionInfoRequest": True,
            "supportsDelayedStackTraceLoading": False,
            "exceptionBreakpointFilters": [
                {"filter": "fault", "label": "Runtime faults (always stop, post-mortem)", "default": True},
            ],
        }

    def on_launch(self, args: dict) -> dict:
        from stvm.debug.session import SessionOptions, open_session   # lazy: start-up
        from stvm.scenario import ScenarioError   # lazy: start-up
        if self.session is not None:
            # one program per debug session (as the DAP spec has it): a second launch would start
            # a second VM and emulator and leak the first one's port and thread
            raise ProtocolError("a program is already launched in this debug session; "
                                "disconnect first (or start a new session)")
        program = args.get("program")
        if not program:
            raise ProtocolError("launch needs \"program\": an ST file (or a list of files)")
        files = program if isinstance(program, list) else [program]
        if not all(isinstance(f, str) and f for f in files):
            raise ProtocolError("launch \"program\" must be a file name (a string) or a list of file names")
        cwd = _str_arg(args, "cwd") or os.getcwd()
        for name in ("scenario", "robot", "dialect"):
            _str_arg(args, name)
        scan = args.get("scan")
        if scan is not None and not isinstance(scan, str):   # 5: 5 what? (was an internal error)
            raise ProtocolError("launch \"scan\" must be a duration in a string, such as \"1ms\"")
        cycles = args.get("cycles")
        if cycles is not None and (_int_arg(args, "cycles") < 0):
            raise ProtocolError("launch \"cycles\" must be >= 0")
        sets, sysmac = _str_list_arg(args, "set"), _str_list_arg(args, "sysmac")
        defines = _str_list_arg(args, "define")
        files = [f if os.path.isabs(f) else os.path.join(cwd, f) for f in files]
        for f in files:
            if not os.path.exists(f):
                raise ProtocolError(f"no such file: {f}")
        scenario = args.get("scenario")
        if scenario and not os.path.isabs(scenario):
            scenario = os.path.join(cwd, scenario)
        options = SessionOptions(files, scan=args.get("scan"), scenario=scenario,
                                 sets=sets, sysmac=sysmac, dialect=args.get("dialect"), defines=defines,
                                 robot=args.get("robot"), realtime=bool(args.get("realtime")),
                                 max_scans=args.get("cycles"))
        try:
            self.session = open_session(options)
        except LoadError as exc:
            self.output(exc.render(), "stderr")
            raise ProtocolError(f"the ST program has {sum(d.is_error for d in exc.diagnostics)} error(s); see the Debug Console")
        except (ValueError, KeyError, ScenarioError) as exc:
            raise ProtocolError(str(exc))
        self.engine = self.session.engine
        self.launch_args = args
        self.engine.listeners.append(self._on_engine_event)
        self.engine.output.append(lambda text: self.output(f"warning: {text}", "stderr"))
        for warning in self.session.build.project.warnings:
            self.output(render(warning, self.session.build.project.sources), "stderr")
        if self.session.robot != "none":
            port = f" on port {self.session.server.port}" if self.session.server is not None else ""
            self.output(f"stvm: robot {self.session.robot}{port}")
        for pending in self.pending_breakpoints:
            self.on_setBreakpoints(pending)
        return {}

    def after_launch(self) -> None:
        self.event("initialized")

    def on_setBreakpoints(self, args: dict) -> dict:
        source = _dict_arg(args, "source")
        path = _str_arg(source, "path") or _str_arg(source, "name") or ""
        specs = args.get("breakpoints")
        if specs is None:
            lines = args.get("lines") or []
            if not isinstance(lines, list):
                raise ProtocolError("argument 'lines' must be a list of line numbers")
            specs = [{"line": line} for line in lines]
        if not isinstance(specs, list) or not all(isinstance(spec, dict) for spec in specs):
            raise ProtocolError("argument 'breakpoints' must be a list of {\"line\": N} objects")
        if len(specs) > MAX_BREAKPOINTS_PER_FILE:
            raise ProtocolError(f"{len(specs)} breakpoints in one file: the limit is {MAX_BREAKPOINTS_PER_FILE}")
        for spec in specs:
            if _int_arg(spec, "line", -1) < 1:
                raise ProtocolError("each breakpoint needs \"line\": a line number >= 1")
            _str_arg(spec, "condition")
        if self.engine is None:
            self.pending_breakpoints.append(args)
            return {"breakpoints": [{"verified": False, "line": s.get("line"), "message": "not launched yet"} for s in specs]}
        results = self.engine.set_file_breakpoints(path, [(s["line"], s.get("condition")) for s in specs])
        out = []
        for spec, result in zip(specs, results):
            if isinstance(result, DebugError):
                out.append({"verified": False, "line": spec["line"], "message": str(result)})
            else:
                out.append({"verified": True, "id": result.id, "line": result.line, "source": self._source(result.file)})
        return {"breakpoints": out}

    def on_setExceptionBreakpoints(self, args: dict) -> dict:
        return {}   # runtime faults always stop: a faulted controller task cannot go on

    def on_configurationDone(self, args: dict) -> dict:
        engine = self._require_engine()
        if engine.state == "initial":
            stop = bool(self.launch_args.get("stopOnEntry", False)) and not self.launch_args.get("noDebug")
            if self.launch_args.get("noDebug"):
                engine.delete_breakpoint(None)
            engine.start(stop_on_entry=stop)
        return {}

    # ================================================================ requests: state
    def on_threads(self, args: dict) -> dict:
        if self.engine is None:
            return {"threads": []}
        return {"threads": [{"id": i + 1, "name": f"task {task.name}"} for i, task in enumerate(self.engine.vm.tasks)]}

    def _thread_of(self, event: StopEvent) -> int:
        for i, task in enumerate(self.engine.vm.tasks):
            if task.name == event.task:
                return i + 1
        return 1

    def on_stackTrace(self, args: dict) -> dict:
        engine = self._require_engine()
        event = engine.stop_event
        if event is None or not engine.stopped or args.get("threadId") != self._thread_of(event):
            return {"stackFrames": [], "totalFrames": 0}
        frames = []
        if event.between_scans:
            frames.append({"id": 1, "name": f"between scans (before scan {event.scan})", "line": 0, "column": 0,
                           "presentationHint": "label"})
        for frame in event.frames:
            span = frame.span
            frames.append({"id": frame.index + 1, "name": f"{frame.name} ({frame.pou.name})",
                           "source": self._source(span.file), "line": span.line, "column": span.column,
                           "endLine": span.end_line, "endColumn": span.end_column})
        start = _int_arg(args, "startFrame")
        levels = _int_arg(args, "levels")
        chosen = frames[start:start + levels] if levels else frames[start:]
        return {"stackFrames": chosen, "totalFrames": len(frames)}

    def _source(self, file: str) -> dict:
        path = self.session.build.absolute_path(file) if self.session else None
        if path is not None:
            return {"name": os.path.basename(file), "path": path}
        for ref, name in self.sources.items():
            if name == file:
                return {"name": file, "sourceReference": ref, "presentationHint": "deemphasize"}
        ref = len(self.sources) + 1
        self.sources[ref] = file
        return {"name": file, "sourceReference": ref, "presentationHint": "deemphasize"}

    def on_source(self, args: dict) -> dict:
        engine = self._require_engine()
        source = _dict_arg(args, "source")
        ref = _int_arg(args, "sourceReference") or _int_arg(source, "sourceReference")
        name = self.sources.get(ref) if ref else _str_arg(source, "path")
        text = engine.build.project.sources.get(name or "")
        if text is None:
            raise ProtocolError(f"no source {name!r}")
        return {"content": text, "mimeType": "text/x-structured-text"}

    def on_scopes(self, args: dict) -> dict:
        engine = self._require_engine()
        frame_index = _int_arg(args, "frameId", 1) - 1
        event = engine.stop_event
        if event is None or event.between_scans:
            return {"scopes": [self._scope("Globals", _Node("globals", _GLOBAL_FRAME)),
                               self._scope("Programs", _Node("programs", _GLOBAL_FRAME))]}
        if not 0 <= frame_index < len(engine.frames()):
            raise ProtocolError(f"no frame {frame_index + 1}")
        return {"scopes": [self._scope("Locals", _Node("locals", frame_index)),
                           self._scope("Inputs/Outputs", _Node("io", frame_index)),
                           self._scope("Globals", _Node("globals", frame_index), expensive=False)]}

    def _scope(self, name: str, node: _Node, expensive: bool = False) -> dict:
        return {"name": name, "variablesReference": self._handle(node), "expensive": expensive,
                "presentationHint": {"Locals": "locals", "Globals": "globals"}.get(name, "arguments")}

    def _handle(self, node: _Node) -> int:
        """The variablesReference of `node`, valid until the program runs again. A scope or an
        addressable value asked for again gets its first reference back: a client repeating
        `scopes` or `variables` on a stopped program would otherwise add handles without end
        (the soak measured 0.4 KB per `scopes`). At most MAX_HANDLES; past that a value is
        shown but cannot be expanded (0) until the next stop."""
        key = (node.kind, node.frame, node.path, node.indices) if node.kind != "value" or node.path else None
        with self.handle_lock:
            if key is not None:
                ref = self.handle_keys.get(key)
                if ref is not None and ref in self.handles:
                    return ref
            if len(self.handles) >= MAX_HANDLES:
                return 0
            ref = len(self.handles) + 1
            self.handles[ref] = node
            if key is not None:
                self.handle_keys[key] = ref
            return ref

    def on_variables(self, args: dict) -> dict:
        engine = self._require_engine()
        node = self.handles.get(_int_arg(args, "variablesReference"))
        if node is None:
            return {"variables": []}
        children = self._children(engine, node)
        start = max(0, _int_arg(args, "start"))
        count = max(0, _int_arg(args, "count"))
        if args.get("filter") == "named" and node.kind == "value" and isinstance(node.type, t.ArrayType):
            children = []
        if start or count:
            children = children[start:start + count] if count else children[start:]
        return {"variables": [self._variable(engine, name, value, ty, path, node.frame, indices)
                              for name, value, ty, path, indices in children]}

    def _children(self, engine: Engine, node: _Node) -> list[tuple[str, Any, t.Type, str | None, tuple]]:
        """(display name, value, type, ST path, array indices so far) of a node's children."""
        vm = engine.vm
        out: list[tuple[str, Any, t.Type, str | None, tuple]] = []
        if node.kind in ("locals", "io"):
            frame = engine.frames()[node.frame]
            scope, pou = frame.scope, frame.pou
            holder = scope.frame if pou.kind in ("FUNCTION", "METHOD") else scope.instance
            wanted = (INPUT, OUTPUT, IN_OUT) if node.kind == "io" else None
            for slot in call_slots(vm.layouts.pous[pou.key]):   # the frame's own variables
                if (wanted is None) == (slot.section in (INPUT, OUTPUT, IN_OUT)):
                    continue
                out.append((slot.name, _read(holder, slot), slot.type, slot.name, ()))
            if node.kind == "locals" and pou.kind in ("FUNCTION", "METHOD") and pou.return_type is not None:
                out.append((pou.name, scope.result, pou.return_type, None, ()))
            owner = engine.model.pous.get(pou.owner) if pou.kind == "METHOD" else None
            if node.kind == "locals" and owner is not None and scope.instance is not None:
                # a METHOD's instance, expandable like any FB instance
                out.append(("THIS", scope.instance, t.FBType(owner.name, owner.qualname, owner.kind == "PROGRAM"),
                            "THIS^", ()))
        elif node.kind in ("globals", "programs"):   # the roots of the one variable catalog
            kind = "global" if node.kind == "globals" else "program"
            for root in Catalog(vm).roots:
                if root.kind == kind:
                    out.append((root.name, root.read(), root.type, root.path, ()))
        elif node.kind == "value":
            out = _value_children(engine, node)
        return out

    def _variable(self, engine: Engine, name: str, value: Any, ty: t.Type, path: str | None, frame: int,
                  indices: tuple = ()) -> dict:
        item: dict[str, Any] = {"name": name, "type": ty.name, "variablesReference": 0}
        if path is not None and not indices:
            item["evaluateName"] = path
        if value is None and not isinstance(ty, _SCALARS):
            item["value"] = "<not bound>"
        elif isinstance(ty, _SCALARS) or ty is None:
            item["value"] = engine.format(value, ty) if value is not None else "<not bound>"
        else:
            item["value"] = _summary(ty)
            item["variablesReference"] = self._handle(_Node("value", frame, value, ty, path, indices))
            if isinstance(ty, t.ArrayType):
                item["indexedVariables"] = _array_length(value, ty)
        return item

    def on_setVariable(self, args: dict) -> dict:
        engine = self._require_engine()
        node = self.handles.get(_int_arg(args, "variablesReference"))
        if node is None:
            raise ProtocolError("unknown variablesReference")
        name = args.get("name", "")
        for child_name, _, ty, path, _ in self._children(engine, node):
            if child_name == name:
                if path is None:
                    raise DebugError(f"{name} cannot be set")
                text = engine.assign(path, str(args.get("value", "")), node.frame)
                return {"value": text, "type": ty.name, "variablesReference": 0}
        raise DebugError(f"no variable {name!r} here")

    def on_evaluate(self, args: dict) -> dict:
        engine = self._require_engine()
        expression = str(args.get("expression", "")).strip()
        frame = _int_arg(args, "frameId") - 1 if args.get("frameId") else 0
        if engine.stop_event is not None and engine.stop_event.between_scans:
            frame = _GLOBAL_FRAME
        if args.get("context") == "repl":
            handled = self._repl_command(engine, expression, frame)
            if handled is not None:
                return {"result": handled, "variablesReference": 0}
        value, ty = engine.evaluate(expression, frame)
        item = self._variable(engine, expression, value, ty, expression, frame)
        body = {"result": item["value"], "type": ty.name, "variablesReference": item["variablesReference"]}
        if "indexedVariables" in item:
            body["indexedVariables"] = item["indexedVariables"]
        return body

    def _repl_command(self, engine: Engine, text: str, frame: int) -> str | None:
        """Console commands typed in the Debug Console (None: an expression to evaluate)."""
        word, _, rest = text.partition(" ")
        word = word.lower()
        if word == "force" and rest:
            target, value = parse_assignment(rest, "force")
            forced = engine.force(target, value, frame)
            return f"forced {forced.key_display} := {engine.format(forced.value, forced.store.type)}"
        if word == "unforce" and rest:
            released = engine.unforce(None if rest.strip() == "all" else rest, frame)
            return "released " + (", ".join(f.key_display for f in released) or "nothing")
        if word in ("forces", "force") and not rest:
            return "\n".join(f"forced {f.describe()}" for f in engine.forces.values()) or "nothing is forced"
        if word == "set" and rest:
            target, value = parse_assignment(rest, "set")
            return f"{target} := {engine.assign(target, value, frame)}"
        if word == "scan":
            count = int(rest) if rest.strip().isdigit() else 1
            self._resume(SCAN, count)
            return f"running {count} scan(s)"
        if word == "where":
            return engine.where()
        return None

    # ================================================================ requests: execution
    def _resume(self, mode: str, count: int = 1) -> dict:
        engine = self._require_engine()
        if engine.state == FAULTED:
            self.output("stvm: the program stopped on a fault; ending the session")
            engine.terminate()
            return {"allThreadsContinued": True}
        if engine.state != "stopped":
            return {"allThreadsContinued": True}
        with self.handle_lock:
            self.handles.clear()
            self.handle_keys.clear()
        engine.resume(mode, count)
        return {"allThreadsContinued": True}

    def on_continue(self, args: dict) -> dict:
        return self._resume(CONTINUE)

    def on_next(self, args: dict) -> dict:
        return self._resume(NEXT)

    def on_stepIn(self, args: dict) -> dict:
        return self._resume(STEP)

    def on_stepOut(self, args: dict) -> dict:
        return self._resume(FINISH)

    def on_pause(self, args: dict) -> dict:
        self._require_engine().pause()
        return {}

    def on_exceptionInfo(self, args: dict) -> dict:
        engine = self._require_engine()
        fault = engine.fault
        if fault is None:
            raise ProtocolError("no fault")
        where = f"{fault.span.file}:{fault.span.line}:{fault.span.column}" if fault.span else "?"
        return {"exceptionId": "RuntimeFault", "description": fault.message, "breakMode": "always",
                "details": {"message": fault.message, "typeName": "RuntimeFault",
                            "stackTrace": f"{where} (task {fault.task}, scan {fault.scan})"}}

    def on_terminate(self, args: dict) -> dict:
        if self.engine is not None:
            self.engine.terminate()
        return {}

    def on_disconnect(self, args: dict) -> dict:
        self._close()
        return {}

    def after_disconnect(self) -> None:
        self.running = False

    # ================================================================ engine events (worker thread)
    def _on_engine_event(self, event: StopEvent | None) -> None:
        if event is None:
            if not self.terminated_sent:
                self.terminated_sent = True
                self.event("exited", {"exitCode": 3 if self.engine is not None and self.engine.fault else 0})
                self.event("terminated")
            return
        with self.handle_lock:
            self.handles.clear()
            self.handle_keys.clear()
        body: dict[str, Any] = {"reason": _REASONS.get(event.reason, "step"), "threadId": self._thread_of(event),
                                "allThreadsStopped": True, "description": event.describe().splitlines()[0]}
        if event.breakpoints:
            body["hitBreakpointIds"] = event.breakpoints
        if event.reason == FAULT:
            body["text"] = event.message
        elif event.message:
            body["text"] = event.message
            self.output(event.message, "stderr")
        self.event("stopped", body)


def _read(holder: Any, slot: VarSlot) -> Any:
    """The value of a POU variable on its instance/frame (through the reference of a scalar in-out)."""
    if holder is None:
        return None
    value = getattr(holder, slot.storage, None)
    if is_scalar_ref(slot):
        return value.get() if value is not None else None
    return value


def _summary(ty: t.Type) -> str:
    if isinstance(ty, t.ArrayType) and ty.dims:
        dims = ", ".join(f"{lo}..{hi}" for lo, hi in ty.dims)
        return f"ARRAY[{dims}] OF {ty.element.name}"
    return ty.name


def _open_as_fixed(ty: t.Type, value: Any) -> tuple[t.Type, Any]:
    """An ARRAY[*, *] parameter (an `OpenArray`) shown as the fixed array it was passed as."""
    if isinstance(ty, t.ArrayType) and ty.dims is None and ty.rank > 1:
        return t.ArrayType(ty.name, ty.element, tuple(value.bounds)), value.data
    return ty, value


def _array_length(value: Any, ty: t.ArrayType) -> int:
    ty, value = _open_as_fixed(ty, value)
    if ty.dims is None:
        return len(value)
    lo, hi = ty.dims[0]
    return hi - lo + 1


def _value_children(engine: Engine, node: _Node) -> list[tuple[str, Any, t.Type, str | None, tuple]]:
    ty, value, path = node.type, node.value, node.path
    ty, value = _open_as_fixed(ty, value)
    out: list[tuple[str, Any, t.Type, str | None, tuple]] = []
    if isinstance(ty, (t.StructType, t.FBType)):
        for slot in Catalog(engine.vm).members(ty):   # the catalog's members (its skip rules)
            out.append((slot.name, _read(value, slot), slot.type, f"{path}.{slot.name}" if path else None, ()))
    elif isinstance(ty, t.ArrayType):
        if ty.dims is None:
            for i in range(len(value)):
                out.append((f"[{i}]", value[i], ty.element, None, ()))
        else:
            lo, hi = ty.dims[0]
            rest = ty.dims[1:]
            child_type = t.ArrayType(ty.name, ty.element, tuple(rest)) if rest else ty.element
            for i in range(lo, hi + 1):
                indices = node.indices + (i,)
                child_path = None
                if path is not None and not rest:
                    child_path = element_path(path, indices)
                elif path is not None:
                    child_path = path
                out.append((f"[{i}]", value[i - lo], child_type, child_path, indices if rest else ()))
    return out


def serve(rfile: BinaryIO, wfile: BinaryIO, log_path: str | None = None) -> int:
    """Serve one DAP session on the given byte streams; returns the exit code."""
    return DapServer(rfile, wfile, log_path).serve()
