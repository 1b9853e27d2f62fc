"""Source text: where a thing is (`Span`) and how an ST file is read (`read_source`).

The lowest stage of the pipeline (as RuSTy's `plc_source`): the parser, the diagnostics and the
project driver all need spans and file reading, so they live below all of them and import
nothing of stvm.
"""

from __future__ import annotations

import codecs
import dataclasses
from dataclasses import dataclass
from pathlib import Path


class _Slotted:
    __slots__ = ("x",)


_MEMBER = type(_Slotted.x)   # a slot's descriptor (types.MemberDescriptorType)


def fast_frozen_init(cls: type, stamp: tuple | None = None) -> type:
    """Give a frozen, slotted dataclass an `__init__` that stores each field through its slot.

    The generated frozen `__init__` calls `object.__setattr__(self, 'name', value)` per field,
    which looks the name up every time; the slot's own setter does the same store directly, at
    about half the cost. The parser makes a million nodes and spans for a 100,000-line input.
    Same signature, same defaults, same result (a class with default factories, `init=False`
    or keyword-only fields keeps its dataclass `__init__`; so does one with `__post_init__`).

    It also pickles (and copies) as its constructor arguments, unless it has its own `__reduce__`:
    the slotted dataclass's `__getstate__`/`__setstate__` run `fields()` and a Python loop per
    object, a third of a 100,000-line first load's cache write (the parsed unit) and most of
    reading it back.

    `stamp`, a (slot, source) pair, makes the `__init__` also store `source()` in that slot (the
    syntax nodes' ids: stvm/syntax/nodes.py); a class it leaves alone keeps its own `__init__`."""
    fields = dataclasses.fields(cls)
    if "__slots__" not in cls.__dict__ or hasattr(cls, "__post_init__") or any(
            not f.init or f.kw_only or f.default_factory is not dataclasses.MISSING for f in fields):
        return cls
    scope: dict = {}
    params, body = [], []
    for i, f in enumerate(fields):
        slot = next((k.__dict__[f.name] for k in cls.__mro__ if f.name in k.__dict__), None)
        if type(slot) is not _MEMBER:
            return cls
        scope[f"_set{i}"] = slot.__set__
        if f.default is dataclasses.MISSING:
            params.append(f.name)
        else:
            scope[f"_default{i}"] = f.default
            params.append(f"{f.name}=_default{i}")
        body.append(f"    _set{i}(self, {f.name})")
    if stamp is not None:
        scope["_stamp_set"], scope["_stamp_next"] = stamp[0].__set__, stamp[1]
        body.append("    _stamp_set(self, _stamp_next())")
    source = f"def __init__(self, {', '.join(params)}):\n" + "\n".join(body or ["    pass"]) + "\n"
    exec(source, scope)   # noqa: S102 (field names of our own classes, no outside text)
    init = scope["__init__"]
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    init.__doc__ = cls.__init__.__doc__
    cls.__init__ = init
    if "__reduce__" not in cls.__dict__:
        scope["_cls"] = cls
        args = "".join(f"self.{f.name}, " for f in fields)
        exec(f"def __reduce__(self):\n    return (_cls, ({args}))\n", scope)   # noqa: S102 (as above)
        reduce = scope["__reduce__"]
        reduce.__qualname__ = f"{cls.__qualname__}.__reduce__"
        cls.__reduce__ = reduce
    return cls


@fast_frozen_init
@dataclass(frozen=True, slots=True)
class Span:
    """A stretch of one source file: 1-based line and column of its first and last character."""
    file: str
    line: int
    column: int
    end_line: int
    end_column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"

    def __reduce__(self):
        # the fields as constructor arguments: pickled and unpickled as fast as the unslotted
        # class was (a slotted dataclass's own state methods run per field in Python)
        return (Span, (self.file, self.line, self.column, self.end_line, self.end_column))


NO_SPAN = Span("<builtin>", 0, 0, 0, 0)   # a declaration stvm itself made (builtins, defaults)


MAX_SOURCE_BYTES = 8 * 2**20
"""The largest source file stvm reads (8 MiB, about 300,000 lines of dense ST): a bigger
input is refused with a clear error instead of minutes of parsing and gigabytes of memory."""


MAX_SETTINGS_FILE_BYTES = 4 * 2**20
"""The largest scenario, manifest, debugger command or HMI page file read (4 MiB; such files are
a few KB): /dev/zero or a huge file given by mistake is refused instead of exhausting memory."""


def read_limited(path: Path | str, what: str, limit: int = MAX_SETTINGS_FILE_BYTES) -> bytes:
    """The bytes of a small input file (`what` names it in the error): raises SourceError when
    it holds more than `limit` bytes, OSError when it cannot be read."""
    with open(path, "rb") as fh:
        data = fh.read(limit + 1)   # bounded: /dev/zero must not exhaust memory
    if len(data) > limit:
        raise SourceError(f"the {what} is larger than {limit // 2**20} MiB, the most stvm reads from one")
    return data


class SourceError(Exception):
    """A file that is not ST source text: too large, binary, or not in its encoding.
    `line`/`column` locate the offending byte (0 when the whole file is the problem);
    `text` is what can be shown of it (decoded with replacement characters)."""

    def __init__(self, message: str, line: int = 0, column: int = 0, text: str = "", code: str = "E006") -> None:
        super().__init__(message)
        self.code = code   # stvm/diagnostics/codes.py: E006 unreadable file, E007 vendor XML
        self.message = message
        self.line = line
        self.column = column
        self.text = text


STDLIB_PREFIX = "<stdlib>/"
"""The name of every unit of stvm's own standard library begins with this."""


def is_stdlib_file(file: str) -> bool:
    """A unit of stvm's own standard library (`<stdlib>/…`), not the user's.

    A name beginning with `<` is one no user file can have: `read_source` refuses such a
    relative path (issue 34 item 7: a file named `<stdlib>x.st` was taken for the stdlib and
    given `{native}` and the stdlib's exemptions)."""
    return file.startswith(STDLIB_PREFIX)


def reserved_name_problem(path: Path | str) -> str | None:
    """Why `path` cannot name a user source file (None if it can): names beginning with `<`
    are stvm's own built-in texts (`<stdlib>/…`, `<builtin>`)."""
    name = str(path)
    if name.startswith("<"):
        return (f"the file name '{name}' begins with '<', which stvm keeps for its built-in sources "
                f"(<stdlib>/…); rename the file")
    return None


def _is_utf8(encoding: str) -> bool:
    return encoding.lower().replace("-", "").replace("_", "") == "utf8"


def read_source(path: Path, encoding: str = "utf-8") -> str:
    """The text of an ST file. Sources are UTF-8 (a BOM is skipped) unless the project manifest
    declares `encoding`; raises SourceError for an oversized, binary or mis-encoded file and
    OSError if it cannot be read."""
    problem = reserved_name_problem(path)
    if problem:
        raise SourceError(problem)
    try:
        codecs.lookup(encoding)
    except (LookupError, TypeError, ValueError):   # an XML file's own declaration, or stvm.toml's
        shown = str(encoding)[:40]
        raise SourceError(f"unknown text encoding {shown!r} (declared for this file; use e.g. utf-8 or cp1252)") from None
    with open(path, "rb") as fh:
        data = fh.read(MAX_SOURCE_BYTES + 1)   # bounded: /dev/zero must not exhaust memory
    if len(data) > MAX_SOURCE_BYTES:
        raise SourceError(f"file is larger than {MAX_SOURCE_BYTES // 2**20} MiB, the most stvm reads "
                          f"from one source file (split it into several files)")
    if data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SourceError("this file is UTF-16 text; ST sources are read as UTF-8 (save it as UTF-8)", 1, 1)
    nul = data.find(b"\0")
    if nul >= 0:
        line, column = _position(data, nul, encoding)
        raise SourceError(f"binary file (a NUL byte at line {line}, column {column}), not ST source text",
                          line, column)
    if data.startswith(b"\xef\xbb\xbf") and _is_utf8(encoding):
        data = data[3:]
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        line, column = _position(data, exc.start, encoding)
        bad = data[exc.start:exc.end].hex(" ").upper()
        hint = ("re-save the file as UTF-8, or declare its encoding in stvm.toml, e.g. "
                "[project] encoding = \"cp1252\"") if _is_utf8(encoding) else "check the encoding declared in stvm.toml"
        raise SourceError(f"invalid {'UTF-8' if _is_utf8(encoding) else encoding} byte {bad} ({hint})", line, column,
                          data.decode(encoding, errors="replace")) from None


def _position(data: bytes, offset: int, encoding: str) -> tuple[int, int]:
    """1-based line and column (in characters) of byte `offset`."""
    line_start = data.rfind(b"\n", 0, offset) + 1
    column = len(data[line_start:offset].decode(encoding, errors="replace")) + 1
    return data.count(b"\n", 0, offset) + 1, column
