"""`stvm debug` at a real terminal: commands typed while the program runs are never lost.

Through a pipe the console read one line after the previous command had finished, so nothing
could be lost there; at a terminal the lines typed during a `continue` sat in the terminal's input
queue, and the Ctrl-C that followed made the terminal driver discard them. The console now reads
lines while the program runs (stvm/debug/console.py). This test drives `stvm debug` through a
pseudo-terminal as a person types. It waits for text, never for time."""

from __future__ import annotations

import os
import select
import signal
import sys
import time
from pathlib import Path

import pytest

pty = pytest.importorskip("pty")

ROOT = Path(__file__).resolve().parents[2]
PROGRAM = """PROGRAM Main
VAR
  n : DINT;
  m : DINT;
END_VAR
n := n + 1;
m := n * 2;
END_PROGRAM
"""


class Terminal:
    def __init__(self, argv: list[str]) -> None:
        env = dict(os.environ, PYTHONPATH=str(ROOT), NO_COLOR="1")
        self.pid, self.fd = pty.fork()
        if self.pid == 0:   # the child: stdin/stdout/stderr are the terminal
            try:
                os.chdir(ROOT)
                os.execvpe(argv[0], argv, env)
            finally:
                os._exit(127)
        self.text = ""
        self.seen = 0   # expect() looks after what an earlier expect() matched

    def send(self, data: str) -> None:
        os.write(self.fd, data.encode())

    def expect(self, wanted: str, timeout: float = 60.0) -> str:
        end = time.monotonic() + timeout
        while True:
            at = self.text.find(wanted, self.seen)
            if at >= 0:
                self.seen = at + len(wanted)
                return self.text
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError(f"{wanted!r} never came; the terminal showed:\n{self.text}")
            ready, _, _ = select.select([self.fd], [], [], min(left, 0.5))
            if ready:
                try:
                    chunk = os.read(self.fd, 65536)
                except OSError:   # the child has ended and the terminal closed
                    chunk = b""
                if not chunk:
                    raise AssertionError(f"{wanted!r} never came (end of output):\n{self.text}")
                self.text += chunk.decode("utf-8", "replace").replace("\r\n", "\n")

    def close(self) -> int:
        for _ in range(100):
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                os.close(self.fd)
                return os.waitstatus_to_exitcode(status)
            time.sleep(0.1)
        os.kill(self.pid, signal.SIGKILL)
        os.waitpid(self.pid, 0)
        os.close(self.fd)
        raise AssertionError(f"stvm debug did not end; the terminal showed:\n{self.text}")


@pytest.fixture
def terminal(tmp_path):
    source = tmp_path / "count.st"
    source.write_text(PROGRAM)
    term = Terminal([sys.executable, "-m", "stvm", "debug", str(source)])
    yield term
    try:
        os.kill(term.pid, signal.SIGKILL)
        os.waitpid(term.pid, 0)
        os.close(term.fd)
    except (ProcessLookupError, ChildProcessError, OSError):
        pass


def test_break_print_and_pause_typed_during_continue(terminal):
    terminal.expect("Type help.")
    terminal.expect("(stvm) ")
    terminal.send("continue\n")
    # typed while it runs: print waits for the stop, break is set at once and stops the program
    terminal.send("print n\n")
    terminal.expect("'print n' will run at the next stop")
    terminal.send("break 7\n")
    terminal.expect("Breakpoint 1 at ")
    terminal.expect("Breakpoint 1: ")
    terminal.expect("=>B    7  m := n * 2;")
    terminal.expect("(stvm) print n\nn = ")
    terminal.send("delete\n")
    terminal.expect("Deleted 1 breakpoint(s).")
    terminal.send("continue\n")
    terminal.send("print Main.m\n")
    terminal.expect("'print Main.m' will run at the next stop")
    terminal.send("pause\n")
    terminal.expect("Paused")
    terminal.expect("(stvm) print Main.m\nMain.m = ")
    terminal.send("quit\n")
    assert terminal.close() == 0


def test_lines_typed_before_ctrl_c_survive_the_interrupt(terminal):
    terminal.expect("(stvm) ")
    terminal.send("continue\n")
    terminal.send("print Main.n\n")
    terminal.send("watch Main.m\n")
    terminal.expect("'print Main.n' will run at the next stop")
    terminal.expect("watch 1: Main.m = <running>")
    # the INTR character flushes the terminal's input queue: the lines above are already read
    terminal.send("\x03")
    terminal.expect("Paused")
    terminal.expect("watch 1: Main.m = ")
    terminal.expect("(stvm) print Main.n\nMain.n = ")
    terminal.send("quit\n")
    assert terminal.close() == 0


def test_quit_while_running_ends_the_session(terminal):
    terminal.expect("(stvm) ")
    terminal.send("continue\n")
    terminal.send("print n\n")
    terminal.expect("will run at the next stop")
    terminal.send("quit\n")
    assert terminal.close() == 0
