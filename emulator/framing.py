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
    if type(data) is not str and type(data) is not bytes:  # bytearray, memoryview: not hashable
        return _encode(header, data)
    key = (header, data)
    frame = _ENCODED.get(key)
    if frame is None:
        frame = _encode(header, data)
        if len(data) <= _ENCODE_CACHE_MAX_DATA:  # replies repeat: "1,OK", "01,01,true", ...
            if len(_ENCODED) >= _ENCODE_CACHE_SIZE:
                _ENCODED.clear()
            _ENCODED[key] = frame
    return frame


def _encode(header: str, data: str | bytes) -> bytes:
    data_bytes = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    body = header.encode("ascii") + b"," + str(len(data_bytes)).encode("ascii") + b"," + data_bytes + b","
    return b"$" + body + b"*" + f"{checksum(body):02X}".encode("ascii") + b"\r\n"


# encode() is pure: frames of short DATA are remembered (bounded; cleared when full).
_ENCODED: dict[tuple[str, str | bytes], bytes] = {}
_ENCODE_CACHE_SIZE = 4096
_ENCODE_CACHE_MAX_DATA = 256


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
        # Once a frame's extent is known its result depends only on its bytes and the settings:
        # repeated frames (polling, the same script again) skip checksum, header and allocation.
        self._known: dict[bytes, Frame | FrameError] = {}

    def decode(self, buf: bytes, start: int = 0) -> DecodeResult:
        """Return (bytes consumed, result); (0, None) means wait for more.

        ``start``: decode ``buf[start:]`` without copying it (the count is relative to ``start``),
        so a caller holding several frames in one buffer walks through it without slicing."""
        size = len(buf) - start
        if size <= 0:
            return 0, None
        if buf[start] != START:
            found = buf.find(b"$", start)
            return (size if found < 0 else found - start), None
        comma1 = buf.find(b",", start + 1, start + MAX_HEADER_TOKEN + 2)
        if comma1 < 0:
            if size > MAX_HEADER_TOKEN + 1:
                return self._structure_error(buf, start, "no comma after header")
            return 0, None
        comma2 = buf.find(b",", comma1 + 1, comma1 + MAX_LENGTH_TOKEN + 2)
        if comma2 < 0:
            if len(buf) > comma1 + 1 + MAX_LENGTH_TOKEN:
                return self._structure_error(buf, start, "no comma after length")
            return 0, None
        token = buf[comma1 + 1:comma2]
        # Fast path: a plain decimal LENGTH (what every client sends) needs no further checks.
        length = int(token) if token.isdigit() else parse_length(token, self.settings)
        if length is None:
            return self._structure_error(buf, start, "length is not a number")
        if length > self.settings.max_data_length:
            return self._structure_error(buf, start, f"length {length} above max_data_length")
        data_end = comma2 + 1 + length
        frame_end = data_end + TRAILER_LEN
        if len(buf) >= frame_end and self._known and type(buf) is bytes:
            # A frame seen before (same bytes up to the end of a two-digit trailer) has the same
            # result: its header and LENGTH fix ``data_end``, so no other reading is possible.
            known = self._known.get(buf[start:frame_end])
            if known is not None:
                return frame_end - start, known
        # One-digit checksums make the trailer one byte shorter; we need to see it to judge it.
        if len(buf) < data_end + TRAILER_LEN - 1:
            return 0, None
        trailer = buf[data_end:data_end + TRAILER_LEN]
        if trailer[:2] != b",*":
            return self._structure_error(buf, start, "no ',*' at the end of DATA")
        digits = trailer[2:4]
        if len(trailer) >= 5 and trailer[2:3] in _HEX_SINGLE and trailer[3:5] == b"\r\n":
            # ",*H\r\n": one hex digit (spec §2 [U], §11 #9).
            if not self.settings.accept_one_digit_checksum:
                return self._structure_error(buf, start, "one-digit checksum", end=data_end + 5 - start)
            frame_end = data_end + 5
            digits = trailer[2:3]
        else:
            if len(buf) < data_end + TRAILER_LEN:
                return 0, None
            if trailer[4:6] != b"\r\n" or digits not in _HEX_PAIRS:
                return self._structure_error(buf, start, "checksum is not two hex digits + CRLF")
            frame_end = data_end + TRAILER_LEN
        used = frame_end - start
        raw = bytes(buf[start:frame_end])
        result = self._judge(buf, start, comma1, comma2, data_end, raw, digits)
        if used <= _KNOWN_MAX_FRAME:
            if len(self._known) >= _KNOWN_SIZE:
                self._known.clear()
            self._known[raw] = result
        return used, result

    def _judge(self, buf: bytes, start: int, comma1: int, comma2: int, data_end: int, raw: bytes,
               digits: bytes) -> Frame | FrameError:
        """Checksum (CPERR 02) and header (CPERR 03) of a frame whose structure is sound."""
        if not self.settings.accept_lowercase_checksum and digits != digits.upper():
            return FrameError(Cperr.CHECKSUM, raw, "lower-case checksum")
        if int(digits, 16) != checksum(buf[start + 1:data_end + 1]):
            return FrameError(Cperr.CHECKSUM, raw, "checksum mismatch")
        header_bytes = bytes(buf[start + 1:comma1])
        header = _CLIENT_HEADER_BYTES.get(header_bytes)
        if header is None:
            return FrameError(Cperr.HEADER, raw, f"unknown header {header_bytes!r}")
        return Frame(header, bytes(buf[comma2 + 1:data_end]), raw)

    @staticmethod
    def _structure_error(buf: bytes, start: int, reason: str, end: int | None = None) -> DecodeResult:
        """CPERR 01.  Resynchronise at the next ``$`` (or consume ``end`` bytes if the frame's
        extent is known), so every bad frame costs exactly one CPERR.  ``end`` is relative to
        ``start``."""
        if end is None:
            nxt = buf.find(b"$", start + 1)
            end = nxt - start if nxt > 0 else len(buf) - start
        return end, FrameError(Cperr.PACKET, bytes(buf[start:start + end]), reason)


_HEX_SINGLE = {bytes([c]) for c in HEX_DIGITS}
_HEX_PAIRS = {bytes([a, b]) for a in HEX_DIGITS for b in HEX_DIGITS}
_KNOWN_SIZE = 256  # frames remembered per framer (cleared when full)
_KNOWN_MAX_FRAME = 512  # only frames up to this many bytes
_CLIENT_HEADER_BYTES = {h.encode("ascii"): h for h in CLIENT_HEADERS}


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
