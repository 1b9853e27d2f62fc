"""`stvm debug`: the interactive console on the debug engine.

Reads one command per line from an input stream (a terminal, a file, or a test's StringIO) and
writes to an output stream; every stop prints where it is, the ST line and the watches. An empty
line repeats the last step/next/finish/scan/continue. Ctrl-C while the program runs pauses it.

On a terminal, lines are read while the program runs too (a reader thread): a person types
`break`, `print` or `pause` during a `continue`. Without it those lines sat unread in the
terminal's input queue, and the Ctrl-C that followed made the terminal driver flush that queue
(POSIX: the INTR character discards pending input unless NOFLSH), so they were lost. While the
program runs, `pause`, `quit`, `break`, `delete`, `watch`, `unwatch`, `info breakpoints|watch|force`
and `help` are done at once; every other command is queued and runs, in order, at the next stop.
From a file or a pipe (a script) lines are still read one at a time, each after the previous
command has finished, so a script's `break` never lands in the middle of its `continue`.
"""

from __future__ import annotations

import queue
import sys
import threading
from collections import deque
from typing import Callable, TextIO

from stvm.debug.engine import (CONTINUE, FAULTED, FINISH, NEXT, SCAN, STEP, TERMINATED, Engine,
                               StopEvent)
from stvm.debug.scope import DebugError
from stvm.runtime.catalog import ELEMENTARY_KINDS, Catalog
from stvm.syntax import parse_expression
from stvm.trace.signals import compile_pattern

HELP = """\
Commands (ST expressions in ST syntax, evaluated in the selected frame's scope):
  break FILE:LINE [if EXPR]   breakpoint on the first statement at or after LINE (b)
  break LINE [if EXPR]        ... in the current file;  break  lists breakpoints
  delete [N...]               delete breakpoints (all without N) (d)
  continue                    run to a breakpoint, a fault or Ctrl-C (c)
  pause                       while the program runs: stop it where it is (as Ctrl-C)
  step                        next ST statement, into FB and function calls (s)
  next                        next statement, over calls (n)
  finish                      run until the current FB/function returns; in a program: scan end
  scan [N]                    run N whole scans (default 1) and stop between scans
  print EXPR                  evaluate an ST expression (p), e.g. print fb.Q, print arr[3] + 1
  watch EXPR                  show EXPR at every stop;  watch  lists;  unwatch N|all
  set VAR := VALUE            assign once (ST assignment rules)
  force VAR := VALUE          hold VAR at VALUE at the start and end of every scan;  force  lists
  unforce VAR|all             release a forced variable
  where                       task, scan, virtual time and the call stack (bt)
  frame N / up / down         select a frame of the call stack for print/set/list
  list [FILE:]LINE            ST source around the current line or LINE (l)
  info breakpoints|watch|force
  info variables [PATTERN]    every variable (the variable catalog: globals, then the programs),
                              or those whose path matches PATTERN (the trace's globs: Main.*, **.Q)
  help, quit (q)"""

_ALIASES = {"b": "break", "d": "delete", "c": "continue", "cont": "continue", "s": "step", "n": "next",
            "fin": "finish", "p": "print", "bt": "where", "backtrace": "where", "l": "list", "q": "quit",
            "exit": "quit", "h": "help", "?": "help", "f": "frame", "w": "where"}
_REPEATABLE = {"step", "next", "finish", "scan", "continue"}
# done at once while the program runs (the engine takes them from another thread, as the DAP's
# setBreakpoints); every other command waits for the next stop
_WHILE_RUNNING = {"pause", "quit", "break", "delete", "watch", "unwatch", "info", "help"}
_INFO_WHILE_RUNNING = ("b", "w", "f")


class Console:
    def __init__(self, engine: Engine, stdin: TextIO | None = None, stdout: TextIO | None = None,
                 echo: bool | None = None, live: bool | None = None) -> None:
        self.engine = engine
        self.stdin = stdin or sys.stdin
        self.stdout = stdout or sys.stdout
        interactive = self.stdin.isatty()
        self.echo = (not interactive) if echo is None else echo
        # live: read lines while the program runs (a person at a terminal); see the module doc
        self.live = interactive if live is None else live
        self._lines: queue.Queue[str | None] = queue.Queue()   # live: lines read, None at the end
        self._reader: threading.Thread | None = None
        self._pending: deque[str] = deque()   # typed while running, to run at the next stop
        self._quit = False                    # quit typed while running
        self._write_lock = threading.Lock()
        self.watches: list[str] = []
        self.frame_index = 0
        self.list_line: tuple[str, int] | None = None
        self.last_command = ""
        engine.output.append(lambda message: self.write(f"warning: {message}"))

    # ---- output
    def write(self, text: str = "") -> None:
        with self._write_lock:
            self.stdout.write(text + "\n")
            self.stdout.flush()

    # ---- input
    def _read_lines(self) -> None:
        """The reader thread (live mode): every line as soon as it is typed."""
        try:
            while True:
                line = self.stdin.readline()
                if not line:
                    break
                self._lines.put(line.rstrip("\r\n"))
        except (OSError, ValueError):   # the terminal went away, or stdin was closed at exit
            pass
        self._lines.put(None)

    def _read_line(self) -> str | None:
        """The next command line; None at the end of the input."""
        if not self.live:
            line = self.stdin.readline()
            return line.rstrip("\n") if line else None
        if self._reader is None:
            self._reader = threading.Thread(target=self._read_lines, name="stvm-debug-input", daemon=True)
            self._reader.start()
        return self._lines.get()

    # ---- the loop
    def run(self, commands: list[str] | None = None) -> int:
        """Serve commands until `quit` or the end of the input; returns the exit code."""
        engine = self.engine
        if engine.state == "initial":
            engine.start(stop_on_entry=True)
            event = engine.wait_started()
            if event is not None:
                self.write(f"stvm debug: {len(engine.build.statements.stops)} statements in "
                           f"{len(engine.build.statements.st_lines)} file(s); stopped before scan 0. Type help.")
        try:
            for line in commands or []:
                if self.echo:
                    self.write(f"(stvm) {line}")
                if not self.execute(line):
                    return 0
            while True:
                if self._quit:
                    return 0
                if self._pending:   # typed while the program ran: run them now, in order
                    line = self._pending.popleft()
                    self.write(f"(stvm) {line}")
                    if not self.execute(line):
                        return 0
                    continue
                with self._write_lock:
                    self.stdout.write("(stvm) ")
                    self.stdout.flush()
                line = self._read_line()
                if line is None:
                    self.write()
                    return 0
                if self.echo:
                    self.write(line)
                if not self.execute(line):
                    return 0
        finally:
            engine.terminate()

    def execute(self, line: str) -> bool:
        """Run one command line; False when the session should end."""
        text = line.strip()
        if not text:
            if self.last_command.split(" ", 1)[0] not in _REPEATABLE:
                return True
            text = self.last_command
        if text.startswith("#"):
            return True
        word, _, rest = text.partition(" ")
        command = _ALIASES.get(word.lower(), word.lower())
        rest = rest.strip()
        handler: Callable[[str], bool | None] | None = getattr(self, "do_" + command, None)
        if handler is None:
            self.write(f"unknown command {word!r}; type help")
            return True
        self.last_command = f"{command} {rest}".strip()
        try:
            return handler(rest) is not False
        except DebugError as exc:
            self.write(f"error: {exc}")
            return True
        except Exception as exc:  # noqa: BLE001 - an stvm bug must not end the user's session
            self.write(f"internal error in stvm ({type(exc).__name__}: {exc})")
            return True

    # ---- execution control
    def _go(self, mode: str, count: int = 1) -> None:
        engine = self.engine
        if engine.state == TERMINATED:
            raise DebugError("the session has ended")
        serial = engine.resume(mode, count)
        event = None
        while True:
            try:
                event = engine.wait(serial, 0.05 if self.live else 0.2)
                if event is not None or engine.state in (TERMINATED,) or engine.serial > serial:
                    break
                if self.live and self._serve_while_running():
                    engine.terminate()
                    return
            except KeyboardInterrupt:   # Ctrl-C, wherever it lands while the program runs
                engine.pause()
        if event is None:
            self.write("The program has ended.")
            return
        self.frame_index = 0
        self.show_stop(event)

    def _serve_while_running(self) -> bool:
        """Live mode, while the program runs: handle the lines typed so far. True after quit
        (or the end of the input) typed while running."""
        while True:
            try:
                line = self._lines.get_nowait()
            except queue.Empty:
                return False
            if line is None:   # the end of the input (Ctrl-D): as quit
                self._quit = True
                return True
            text = line.strip()
            if not text or text.startswith("#"):
                continue   # an empty line does not repeat the continue that is running
            word, _, rest = text.partition(" ")
            command = _ALIASES.get(word.lower(), word.lower())
            at_once = command in _WHILE_RUNNING and (
                command != "info" or rest.strip().lower().startswith(_INFO_WHILE_RUNNING))
            if command == "quit":
                self._quit = True
                return True
            if at_once:
                self.execute(text)
            else:
                self._pending.append(text)
                self.write(f"(running: {text!r} will run at the next stop; type pause to stop now)")

    def do_pause(self, rest: str) -> None:
        if self.engine.state != "running":
            self.write("The program is not running.")
            return
        self.engine.pause()

    def show_stop(self, event: StopEvent) -> None:
        self.write(event.describe())
        if event.frames:
            span = event.frames[0].span
            self.list_line = (span.file, span.line)
            self.write(self._source_line(span.file, span.line, marker="=>"))
        for i, text in enumerate(self.watches, 1):
            self.write(f"  watch {i}: {text} = {self._value_or_error(text)}")
        if event.reason == "fault":
            self.write("Post-mortem: inspect with print/where/list; nothing more can run.")

    def do_continue(self, rest: str) -> None:
        self._go(CONTINUE)

    def do_step(self, rest: str) -> None:
        self._go(STEP)

    def do_next(self, rest: str) -> None:
        self._go(NEXT)

    def do_finish(self, rest: str) -> None:
        self._go(FINISH)

    def do_scan(self, rest: str) -> None:
        count = _count(rest, 1)
        if count < 1:
            raise DebugError(f"scan takes a number of scans >= 1, got {count}")
        self._go(SCAN, count)

    # ---- breakpoints
    def do_break(self, rest: str) -> None:
        if not rest:
            self.do_info("breakpoints")
            return
        location, _, condition = rest.partition(" if ")
        location = location.strip()
        file, sep, line_text = location.rpartition(":")
        if not sep:
            file, line_text = self._current_file(), location
        if not line_text.strip().isdigit():
            raise DebugError(f"break needs FILE:LINE, got {location!r}")
        bp = self.engine.add_breakpoint(file, int(line_text), condition.strip() or None)
        moved = f" (moved from line {bp.requested_line})" if bp.requested_line != bp.line else ""
        cond = f" if {bp.condition}" if bp.condition else ""
        self.write(f"Breakpoint {bp.id} at {bp.file}:{bp.line} in {bp.pou.name}{cond}{moved}")

    def do_delete(self, rest: str) -> None:
        if not rest:
            count = len(self.engine.breakpoints)
            self.engine.delete_breakpoint(None)
            self.write(f"Deleted {count} breakpoint(s).")
            return
        for word in rest.replace(",", " ").split():
            if not word.isdigit():
                raise DebugError(f"delete takes breakpoint numbers, got {word!r}")
            self.engine.delete_breakpoint(int(word))
            self.write(f"Deleted breakpoint {word}.")

    # ---- data
    def do_print(self, rest: str) -> None:
        if not rest:
            raise DebugError("print needs an expression")
        self.write(f"{rest} = {self.engine.evaluate_text(rest, self.frame_index)}")

    def do_watch(self, rest: str) -> None:
        if not rest:
            self.do_info("watch")
            return
        expr, diags = parse_expression(rest, "<watch>")
        if expr is None or any(d.is_error for d in diags):
            problem = next((d.message for d in diags if d.is_error), "not an expression")
            raise DebugError(f"watch needs an ST expression: {problem}")
        self.watches.append(rest)
        self.write(f"watch {len(self.watches)}: {rest} = {self._value_or_error(rest)}")

    def do_unwatch(self, rest: str) -> None:
        if rest in ("", "all"):
            self.watches.clear()
            self.write("Deleted all watches.")
            return
        if not rest.isdigit() or not 1 <= int(rest) <= len(self.watches):
            raise DebugError(f"no watch {rest!r}")
        removed = self.watches.pop(int(rest) - 1)
        self.write(f"Deleted watch {rest}: {removed}")

    def do_set(self, rest: str) -> None:
        target, value = parse_assignment(rest, "set")
        self.write(f"{target} := {self.engine.assign(target, value, self.frame_index)}")

    def do_force(self, rest: str) -> None:
        if not rest:
            self.do_info("force")
            return
        target, value = parse_assignment(rest, "force")
        forced = self.engine.force(target, value, self.frame_index)
        self.write(f"Forced {forced.key_display} := {self.engine.format(forced.value, forced.store.type)}")

    def do_unforce(self, rest: str) -> None:
        if not rest:
            raise DebugError("unforce needs a variable, or all")
        released = self.engine.unforce(None if rest == "all" else rest, self.frame_index)
        for forced in released:
            self.write(f"Released {forced.key_display}")
        if not released:
            self.write("Nothing was forced.")

    # ---- where am I
    def do_where(self, rest: str) -> None:
        text = self.engine.where()
        lines = text.splitlines()
        for i, line in enumerate(lines):
            if i and self.frame_index == i - 1 and len(lines) > 2:
                line = "=>" + line[2:]
            self.write(line)

    def do_frame(self, rest: str) -> None:
        frames = self.engine.frames()
        if not frames:
            raise DebugError("no frames: the program is between scans")
        index = _count(rest, self.frame_index) if rest else self.frame_index
        if not 0 <= index < len(frames):
            raise DebugError(f"no frame {index} (0..{len(frames) - 1})")
        self.frame_index = index
        frame = frames[index]
        self.list_line = (frame.span.file, frame.span.line)
        self.write(f"#{index} {frame.name} ({frame.pou.name}) at {frame.location}")
        self.write(self._source_line(frame.span.file, frame.span.line, marker="=>"))

    def do_up(self, rest: str) -> None:
        self.do_frame(str(self.frame_index + _count(rest, 1)))

    def do_down(self, rest: str) -> None:
        self.do_frame(str(self.frame_index - _count(rest, 1)))

    def do_list(self, rest: str) -> None:
        if rest:
            file, sep, line_text = rest.rpartition(":")
            if not sep:
                file = self._current_file()
                line_text = rest
            file = self.engine.build.span_file(file) or file
            if not line_text.strip().isdigit():
                raise DebugError(f"list needs [FILE:]LINE, got {rest!r}")
            center = int(line_text)
        elif self.list_line is not None:
            file, center = self.list_line
        else:
            raise DebugError("no current line; write list FILE:LINE")
        source = self.engine.build.project.sources.get(file)
        if source is None:
            raise DebugError(f"no source for {file!r}")
        lines = source.splitlines()
        current = self.engine.frames()[self.frame_index].span.line if self.engine.frames() else -1
        current_file = self.engine.frames()[self.frame_index].span.file if self.engine.frames() else ""
        first = max(1, center - 5)
        for number in range(first, min(len(lines), center + 5) + 1):
            marker = "=>" if (file == current_file and number == current) else "  "
            self.write(self._source_line(file, number, marker, lines))
        self.list_line = (file, center)

    def _current_file(self) -> str:
        """The file of the current line, else the project's only ST file."""
        if self.list_line is not None:
            return self.list_line[0]
        files = list(self.engine.build.statements.st_lines)
        if len(files) == 1:
            return files[0]
        raise DebugError("no current file; write FILE:LINE")

    def _source_line(self, file: str, number: int, marker: str = "  ", lines: list[str] | None = None) -> str:
        if lines is None:
            lines = self.engine.build.project.sources.get(file, "").splitlines()
        text = lines[number - 1] if 0 < number <= len(lines) else ""
        has_bp = any(bp.file == file and bp.line == number for bp in self.engine.breakpoints.values())
        return f"{marker}{'B' if has_bp else ' '}{number:5d}  {text.rstrip()}"

    def do_info(self, rest: str) -> None:
        what = rest.strip().lower()
        if what.startswith("b"):
            if not self.engine.breakpoints:
                self.write("No breakpoints.")
            for bp in self.engine.breakpoints.values():
                self.write(bp.describe())
        elif what.startswith("w"):
            if not self.watches:
                self.write("No watches.")
            for i, text in enumerate(self.watches, 1):
                self.write(f"watch {i}: {text} = {self._value_or_error(text)}")
        elif what.startswith("f"):
            if not self.engine.forces:
                self.write("Nothing is forced.")
            for forced in self.engine.forces.values():
                self.write(f"forced {forced.describe()}")
        elif what.startswith("v"):
            self.list_variables(rest.strip().partition(" ")[2].strip())
        else:
            raise DebugError("info breakpoints | watch | force | variables [PATTERN]")

    def list_variables(self, pattern: str = "") -> None:
        """`info variables`: the nodes of the one variable catalog (stvm/runtime/catalog.py), a
        leaf with its value; a PATTERN keeps the paths it matches (the trace's glob syntax)."""
        regex = compile_pattern(pattern) if pattern else None
        shown = 0
        for node in Catalog(self.engine.vm).walk():
            if regex is not None and not regex.fullmatch(node.path):
                continue
            shown += 1
            if node.type.kind in ELEMENTARY_KINDS:
                self.write(f"{node.path} : {node.type.name} = {self.engine.format(node.read(), node.type)}")
            else:
                self.write(f"{node.path} : {node.type.name}")
        if not shown:
            self.write(f"No variable matches {pattern!r}." if pattern else "No variables.")

    def do_help(self, rest: str) -> None:
        self.write(HELP)

    def do_quit(self, rest: str) -> bool:
        return False

    def _value_or_error(self, text: str) -> str:
        if self.engine.state not in ("stopped", FAULTED):
            return "<running>"
        try:
            return self.engine.evaluate_text(text, self.frame_index)
        except DebugError as exc:
            return "<not in this scope>" if "is not declared" in str(exc) else f"<{exc}>"


def _count(text: str, default: int) -> int:
    text = text.strip()
    if not text:
        return default
    if not text.lstrip("-").isdigit():
        raise DebugError(f"expected a number, got {text!r}")
    return int(text)


def parse_assignment(text: str, command: str) -> tuple[str, str]:
    """Split `VAR := VALUE` at the first `:=` outside quotes and parentheses."""
    depth = 0
    quote = ""
    for i, ch in enumerate(text):
        if quote:
            if ch == quote:
                quote = ""
        elif ch in "'\"":
            quote = ch
        elif ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif ch == ":" and depth == 0 and text[i + 1:i + 2] == "=":
            target, value = text[:i].strip(), text[i + 2:].strip()
            if target and value:
                return target, value
            break
    raise DebugError(f"{command} needs VAR := VALUE")

