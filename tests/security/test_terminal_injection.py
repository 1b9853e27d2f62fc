"""Terminal injection through the live views (issue 34 item 6): a client's frame text carrying
escape sequences and rich markup is shown escaped, never acted on by the terminal."""

from __future__ import annotations

import io
import socket

from rich.console import Console

from emulator import start_server
from emulator.cli import _render
from emulator.framing import encode
from emulator.terminal_text import plain, printable
from stvm.demo import _frame_text


# set the window title, clear the screen, an OSC 8 link, a bidi override, rich markup
HOSTILE = ("\x1b]0;pwned\x07\x1b[2J\x1b[H\x1b]8;;http://evil.example/\x07click\x1b]8;;\x07"
           "\u202eevil\x9b31m[bold red]restyled[/bold red][link=http://evil.example]x[/link]")


def _shown(renderable) -> str:
    out = io.StringIO()
    Console(file=out, force_terminal=True, color_system="truecolor", width=400).print(renderable)
    return out.getvalue()


def _assert_inert(shown: str) -> None:
    assert "\x1b]" not in shown          # no OSC: no title, no hyperlink
    assert "\x1b[2J" not in shown and "\x1b[H" not in shown
    assert "\x07" not in shown and "\u202e" not in shown and "\x9b" not in shown
    assert "[bold red]restyled[/bold red]" in shown   # markup shown as text
    assert "\\x1b]0;pwned" in shown      # the escape made visible


def test_printable_escapes_every_control_character() -> None:
    assert printable("a\x1bb\x00c\x7fd\x85e\u2066f\tg") == "a\\x1bb\\x00c\\x7fd\\x85e\\u2066f\\x09g"
    assert printable("TMSCT,ok µ ü ⏎") == "TMSCT,ok µ ü ⏎"
    assert str(plain("[red]x[/red]")) == "[red]x[/red]"


def test_emulator_live_view_shows_a_hostile_frame_inert() -> None:
    srv = start_server(port=0)
    try:
        with socket.create_connection(("127.0.0.1", srv.port), timeout=5) as client:
            client.sendall(encode("TMSCT", f'1,var_s = "{HOSTILE}"'))
            assert client.recv(4096).startswith(b"$TMSCT")   # the answer: the frame was handled
        snap = srv.snapshot()
    finally:
        srv.stop()
    assert any("pwned" in text for _, _, text, _ in snap["recent_frames"])
    _assert_inert(_shown(_render(snap)))


def test_demo_status_shows_a_hostile_frame_inert() -> None:
    text = _frame_text((0.0, "tx", HOSTILE.encode("utf-8"), 1))
    shown = _shown(plain(text))
    assert "\x1b]" not in shown and "\x07" not in shown and "\x1b[2J" not in shown
    assert "\\x1b]0;pwned" in text
    full = _frame_text({"dir": "rx", "data": HOSTILE})
    assert "\x1b" not in full and "\u202e" not in full
