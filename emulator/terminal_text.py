"""Text from the network, made safe to show on a terminal.

A client chooses the bytes of its frames; shown raw, an ESC or OSC sequence in them sets the
window title, clears the screen, restyles the view or plants an OSC 8 link, and ``[`` ... ``]`` is
rich markup. :func:`printable` replaces every control character (C0, DEL, C1, and the Unicode
bidirectional overrides that reorder what is shown) with a visible escape, ``\\x1b`` or
``\\u202e``; :func:`plain` wraps the result in a ``rich.text.Text`` so no markup is parsed.
"""

from __future__ import annotations

import re
from typing import Any

# C0 controls, DEL and C1 controls; the bidi embeddings/overrides/isolates (U+202A-U+202E,
# U+2066-U+2069) and the line/paragraph separators, which terminals may act on.
_UNSAFE = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029\u202a-\u202e\u2066-\u2069]")


def _escape(match: "re.Match[str]") -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def printable(text: str) -> str:
    """`text` with every control character replaced by a visible backslash escape."""
    return _UNSAFE.sub(_escape, text)


def plain(text: Any) -> Any:
    """A ``rich.text.Text`` of ``printable(str(text))``: shown as is, never read as markup."""
    from rich.text import Text   # lazy: rich is optional and only the live views need it
    return Text(printable(str(text)))
