"""TM Listen Node framing: pure encode/decode, checksum and CPERR codes (spec §2, §6).

No sockets, no clock.  :class:`ListenNodeFramer` turns a byte stream into frames and reports how
many bytes it used, so the caller keeps the rest for the next call (pymodbus style).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from .settings import DEFAULT_SETTINGS, EmulatorSettings

START = 0x24  # "$"
TRAILER_LEN = 6  # ",*HH\r\n" (spec §2)
# Choice (§2): a header or length token longer than these without its comma is a structure
# error; real headers are 5 bytes and a length is at most "0b" + 32 binary digits.
MAX_HEADER_TOKEN = 16
MAX_LENGTH_TOKEN = 40
HEX_DIGITS = b"0123456789abcdefABCDEF"
CLIENT_HEADERS = ("TMSCT", "TMSTA")  # §3: CPERR is robot -> client only


class Cperr(str, Enum):
    """CPERR codes (spec §6) as they appear on the wire."""

    PACKET = "01"     # structure: length, separators, trailer
    CHECKSUM = "02"
    HEADER = "03"
    DATA = "04"       # bad/missing ID, unknown SubCmd (raised by the robot layer)
    NOT_IN_NODE = "F1"


@dataclass(frozen=True)
class Frame:
    """One well-formed frame from a client.  ``data`` is the raw DATA bytes."""

    header: str
    data: bytes
    raw: bytes


@dataclass(frozen=True)
class FrameError:
    """A frame that the robot answers with ``$CPERR,2,<code>``."""

    code: Cperr
    raw: bytes
    reason: str


DecodeResult = tuple[int, "Frame | FrameError | None"]


def checksum(body: bytes) -> int:
    """XOR of ``body`` (= the bytes after ``$`` up to and including the comma before ``*``)."""
    value = 0
    for byte in body:
        value ^= byte
    return value


def encode(header: str, data: str | bytes) -> bytes:
    """Build ``$HEADER,LEN,DATA,*CS\\r\\n`` as the robot emits it: decimal LENGTH in bytes and an
    upper-case two-digit checksum (spec §2)."""
    data_bytes = data.encode("utf-8") if isinstance(data, str) else data
    body = header.encode("ascii") + b"," + str(len(data_bytes)).encode("ascii") + b"," + data_bytes + b","
    return b"$" + body + b"*" + f"{checksum(body):02X}".encode("ascii") + b"\r\n"


def encode_cperr(code: Cperr) -> bytes:
    """``$CPERR,2,<code>,*CS\\r\\n`` (spec §6)."""
    return encode("CPERR", code.value)


def parse_length(token: bytes, settings: EmulatorSettings = DEFAULT_SETTINGS) -> int | None:
    """LENGTH as decimal, ``0x`` hex or ``0b`` binary (spec §2); None if it is not a length."""
    try:
        text = token.decode("ascii")
    except UnicodeDecodeError:
        return None
    prefix = text[:2]
    prefixes_hex = ("0x", "0X") if settings.accept_uppercase_length_prefix else ("0x",)
    prefixes_bin = ("0b", "0B") if settings.accept_uppercase_length_prefix else ("0b",)
    digits = text[2:]
    if prefix in prefixes_hex:
        return int(digits, 16) if digits and all(c in "0123456789abcdefABCDEF" for c in digits) else None
    if prefix in prefixes_bin:
        return int(digits, 2) if digits and all(c in "01" for c in digits) else None
    # str.isdigit accepts non-ASCII digits; a length is ASCII only.  Rejects "-100", "+5", "".
    if text and all("0" <= c <= "9" for c in text):
        return int(text, 10)
    return None


class ListenNodeFramer:
    """TM Listen Node frame decoder.

    Layout::

        $ HEADER , LENGTH , DATA(LENGTH bytes) , * CS CS \\r \\n

    LENGTH is decimal, ``0x`` hex or ``0b`` binary and counts the bytes of DATA; DATA may contain
    ``,`` ``*`` ``$`` and CRLF, so framing is length-driven (spec §2).  CS is the XOR of the bytes
    between ``$`` and ``*`` as two hex digits.

    :meth:`decode` returns ``(bytes consumed, result)``:

    * ``(0, None)``: wait for more bytes (nothing usable yet);
    * ``(n, None)`` with ``n > 0``: ``n`` bytes of garbage before a ``$`` were skipped (spec §2 [U]
      default: skip silently) - call again with the rest;
    * ``(n, Frame)``: one good frame of ``n`` bytes;
    * ``(n, FrameError)``: one bad frame, answered with CPERR ``code``.  After a structure error
      (CPERR 01) only the ``$`` and the header/length text are consumed, up to the next ``$``,
      because the LENGTH it declared cannot be trusted (Choice, §2.1).

    Check order (spec §2.1/§11 #8): 01 structure -> 02 checksum -> 03 header.  Data errors (04) and
    F1 depend on the robot state and are decided by the robot layer.
    """

    def __init__(self, settings: EmulatorSettings = DEFAULT_SETTINGS) -> None:
        self.settings = settings

    def decode(self, buf: bytes) -> DecodeResult:
        """Return (bytes consumed, result); (0, None) means wait for more."""
        if not buf:
            return 0, None
        start = buf.find(b"$")
        if start < 0:
            return len(buf), None
        if start > 0:
            return start, None
        comma1 = buf.find(b",", 1, 1 + MAX_HEADER_TOKEN + 1)
        if comma1 < 0:
            if len(buf) > MAX_HEADER_TOKEN + 1:
                return self._structure_error(buf, "no comma after header")
            return 0, None
        comma2 = buf.find(b",", comma1 + 1, comma1 + 1 + MAX_LENGTH_TOKEN + 1)
        if comma2 < 0:
            if len(buf) > comma1 + 1 + MAX_LENGTH_TOKEN:
                return self._structure_error(buf, "no comma after length")
            return 0, None
        length = parse_length(buf[comma1 + 1:comma2], self.settings)
        if length is None:
            return self._structure_error(buf, "length is not a number")
        if length > self.settings.max_data_length:
            return self._structure_error(buf, f"length {length} above max_data_length")
        data_end = comma2 + 1 + length
        # One-digit checksums make the trailer one byte shorter; we need to see it to judge it.
        if len(buf) < data_end + TRAILER_LEN - 1:
            return 0, None
        trailer = buf[data_end:data_end + TRAILER_LEN]
        if trailer[:2] != b",*":
            return self._structure_error(buf, "no ',*' at the end of DATA")
        digits = trailer[2:4]
        if len(trailer) >= 5 and trailer[2:3] in _HEX_SINGLE and trailer[3:5] == b"\r\n":
            # ",*H\r\n": one hex digit (spec §2 [U], §11 #9).
            if not self.settings.accept_one_digit_checksum:
                return self._structure_error(buf, "one-digit checksum", end=data_end + 5)
            frame_end = data_end + 5
            digits = trailer[2:3]
        else:
            if len(buf) < data_end + TRAILER_LEN:
                return 0, None
            if trailer[4:6] != b"\r\n" or any(d not in HEX_DIGITS for d in digits):
                return self._structure_error(buf, "checksum is not two hex digits + CRLF")
            frame_end = data_end + TRAILER_LEN
        raw = bytes(buf[:frame_end])
        text = digits.decode("ascii")
        if not self.settings.accept_lowercase_checksum and text != text.upper():
            return frame_end, FrameError(Cperr.CHECKSUM, raw, "lower-case checksum")
        if int(text, 16) != checksum(buf[1:data_end + 1]):
            return frame_end, FrameError(Cperr.CHECKSUM, raw, "checksum mismatch")
        try:
            header = buf[1:comma1].decode("ascii")
        except UnicodeDecodeError:
            header = ""
        if header not in CLIENT_HEADERS:
            return frame_end, FrameError(Cperr.HEADER, raw, f"unknown header {buf[1:comma1]!r}")
        return frame_end, Frame(header, bytes(buf[comma2 + 1:data_end]), raw)

    @staticmethod
    def _structure_error(buf: bytes, reason: str, end: int | None = None) -> DecodeResult:
        """CPERR 01.  Resynchronise at the next ``$`` (or consume ``end`` bytes if the frame's
        extent is known), so every bad frame costs exactly one CPERR."""
        if end is None:
            nxt = buf.find(b"$", 1)
            end = nxt if nxt > 0 else len(buf)
        return end, FrameError(Cperr.PACKET, bytes(buf[:end]), reason)


_HEX_SINGLE = {bytes([c]) for c in HEX_DIGITS}


def decode_all(framer: ListenNodeFramer, buf: bytes) -> tuple[list[Frame | FrameError], bytes]:
    """Decode every complete frame in ``buf``; return the results and the unused tail."""
    results: list[Frame | FrameError] = []
    pos = 0
    view = bytes(buf)
    while pos < len(view):
        used, result = framer.decode(view[pos:])
        if used == 0:
            break
        pos += used
        if result is not None:
            results.append(result)
    return results, view[pos:]
