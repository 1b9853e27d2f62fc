"""Vendor XML sources read as ST: TwinCAT 3 (`.TcPOU`, `.TcDUT`, `.TcGVL`, `.TcIO`) and PLCopen XML
(TC6 0201 `project` files, as CODESYS and TwinCAT export them).

The XML is parsed with defusedxml (a project file is untrusted input: no entity declarations, no
external references, so no "billion laughs" and no file disclosure through XXE), then turned into
ST text laid out on the XML's own lines: every character of a `<![CDATA[…]]>` or text body stands
at the line and column it has in the XML, and the glue stvm adds (`END_FUNCTION_BLOCK`,
`END_METHOD`, the declarations PLCopen spells as elements) is written into the columns the XML
markup occupies, at the tag it comes from. So the spans of the parsed tree already name the XML
file's lines and columns: diagnostics, faults, breakpoints and traces need no translation. Where
text cannot stand at its own column (an entity `&lt;` is four characters in the XML and one in the
ST; glue where the markup is too short), the `SourceMap` records the shift and `parse_text` maps
every span of the tree back (`VendorText.remap`).
"""

from __future__ import annotations

import bisect
import dataclasses
import html
import re
from pathlib import Path

from stvm.source import SourceError, Span, read_source

TWINCAT_SUFFIXES = (".tcpou", ".tcdut", ".tcgvl", ".tcio")
PLCOPEN_SUFFIX = ".xml"
PLCOPEN_NAMESPACE = "plcopen.org/xml/tc6"


def is_plcopen_file(path: Path) -> bool:
    """An `.xml` file whose start names the PLCopen TC6 namespace (for folder scans)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        return False
    return PLCOPEN_NAMESPACE.encode() in head


def folder_sources(folder: Path) -> list[Path]:
    """The vendor sources of a folder: its TwinCAT files (also in subfolders, as a TwinCAT PLC
    project keeps them under POUs/, DUTs/, GVLs/), those a `.plcproj` in it lists, and its PLCopen
    `.xml` projects."""
    found: dict[Path, None] = {}
    for proj in sorted(folder.glob("*.plcproj")):
        for item in plcproj_items(proj):
            found[item] = None
    for path in sorted(folder.rglob("*")):
        if path.suffix.lower() in TWINCAT_SUFFIXES and path.is_file():
            found[path] = None
    for path in sorted(folder.glob("*.xml")):
        if path.is_file() and is_plcopen_file(path):
            found[path] = None
    return list(found)


_COMPILE_ITEM = re.compile(r"""<Compile\s+Include\s*=\s*"([^"]+)\"""", re.I)


def plcproj_items(proj: Path) -> list[Path]:
    """The `.Tc*` sources a TwinCAT `.plcproj` (an MSBuild file) lists in `<Compile Include=…>`."""
    try:
        text = proj.read_text(encoding="utf-8-sig", errors="replace")
    except OSError:
        return []
    out = []
    for rel in _COMPILE_ITEM.findall(text):
        # an MSBuild attribute is XML text: `POUs\Time&amp;Date\X.TcPOU` names `Time&Date`
        path = proj.parent / html.unescape(rel).replace("\\", "/")
        if path.suffix.lower() in TWINCAT_SUFFIXES and path.is_file():
            out.append(path)
    return out


# ---- the source map ------------------------------------------------------------------------------


class SourceMap:
    """Where each character of the generated ST text comes from in the XML file. Identity (same
    line, same column) except on the ranges recorded: per ST line, sorted segments
    `(first_col, last_col, xml_line, delta, fixed)`: XML column = ST column + delta, or the
    constant `fixed` column for glue that has no spelling of its own in the XML."""

    def __init__(self) -> None:
        self.segments: dict[int, list[tuple[int, int, int, int, int]]] = {}

    def add(self, line: int, col: int, xml_line: int, xml_col: int, fixed: bool) -> None:
        if not fixed and line == xml_line and col == xml_col:
            return
        segs = self.segments.setdefault(line, [])
        delta = 0 if fixed else xml_col - col
        fixed_col = xml_col if fixed else 0
        if segs:
            first, last, l2, d2, f2 = segs[-1]
            if last == col - 1 and l2 == xml_line and d2 == delta and f2 == fixed_col:
                segs[-1] = (first, col, l2, d2, f2)
                return
        segs.append((col, col, xml_line, delta, fixed_col))

    def add_range(self, line: int, col: int, length: int, xml_line: int, xml_col: int) -> None:
        """ST columns col … col+length-1 of `line` stand at XML (xml_line, xml_col …)."""
        if line == xml_line and col == xml_col:
            return
        segs = self.segments.setdefault(line, [])
        delta = xml_col - col
        last = col + length - 1
        if segs:
            first, prev_last, l2, d2, f2 = segs[-1]
            if prev_last == col - 1 and l2 == xml_line and d2 == delta and not f2:
                segs[-1] = (first, last, l2, d2, 0)
                return
        segs.append((col, last, xml_line, delta, 0))

    @property
    def identity(self) -> bool:
        return not self.segments

    def position(self, line: int, col: int) -> tuple[int, int]:
        """The XML (line, column) of ST (line, column)."""
        segs = self.segments.get(line)
        if segs:
            i = bisect.bisect_right(segs, (col, 1 << 30)) - 1
            if i >= 0:
                first, last, xml_line, delta, fixed = segs[i]
                if first <= col <= last:
                    return xml_line, (fixed if fixed else col + delta)
        return line, col

    def span(self, span: Span) -> Span:
        if span.line <= 0:
            return span
        line, col = self.position(span.line, span.column)
        if span.end_column > 1:
            end_line, end_col = self.position(span.end_line, span.end_column - 1)
            end_col += 1
        else:
            end_line, end_col = self.position(span.end_line, span.end_column)
        if (end_line, end_col) < (line, col):
            end_line, end_col = line, col + 1
        return Span(span.file, line, col, end_line, end_col)


class VendorText(str):
    """The ST text of a vendor XML file (a `str`, so every reader of sources takes it as is), with
    the XML text it came from (`original`, for excerpts) and its `source_map`."""

    original: str
    source_map: SourceMap

    def __new__(cls, text: str, original: str, source_map: SourceMap) -> "VendorText":
        obj = super().__new__(cls, text)
        obj.original = original
        obj.source_map = source_map
        return obj

    def __reduce__(self):
        return (VendorText, (str(self), self.original, self.source_map))

    def remap(self, unit, diagnostics):
        """The parsed unit and diagnostics with every span moved to its place in the XML."""
        if self.source_map.identity:
            return unit, diagnostics
        mapper = _SpanMapper(self.source_map)
        return mapper.walk(unit), [dataclasses.replace(d, span=self.source_map.span(d.span)) for d in diagnostics]


class _SpanMapper:
    def __init__(self, smap: SourceMap) -> None:
        self.smap = smap
        self.memo: dict[int, object] = {}

    def walk(self, obj):
        if isinstance(obj, Span):
            return self.smap.span(obj)
        if isinstance(obj, (str, int, float, bool, bytes)) or obj is None:
            return obj
        key = id(obj)
        if key in self.memo:
            return self.memo[key]
        if isinstance(obj, tuple):
            out = tuple(self.walk(x) for x in obj)
        elif isinstance(obj, list):
            out = [self.walk(x) for x in obj]
        elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            values = {f.name: self.walk(getattr(obj, f.name)) for f in dataclasses.fields(obj) if f.init}
            out = type(obj)(**values)
        else:
            out = obj
        self.memo[key] = out
        return out


# ---- reading the XML -------------------------------------------------------------------------------


class _El:
    __slots__ = ("tag", "attrib", "start", "end", "children", "content_start")

    def __init__(self, tag: str, attrib: dict, start: int) -> None:
        self.tag = tag
        self.attrib = attrib
        self.start = start          # char offset of '<'
        self.end = start            # char offset of the end tag's '<' (or after '/>')
        self.content_start = start  # char offset after the start tag's '>'
        self.children: list[_El] = []

    def find(self, tag: str) -> "_El | None":
        for child in self.children:
            if child.tag == tag:
                return child
        return None

    def findall(self, tag: str) -> list["_El"]:
        return [c for c in self.children if c.tag == tag]


class _Builder:
    """Target of the defused parser: a light tree with the char offset of every tag."""

    def __init__(self, text: str) -> None:
        self.text = text
        self.stack: list[_El] = []
        self.root: _El | None = None
        self.expat = None
        # UTF-8 byte offset -> char offset: subtract the extra bytes of the non-ASCII chars before
        self._wide: list[int] = []     # byte offsets just after each non-ASCII char
        self._extra: list[int] = []    # cumulative extra bytes up to and including it
        if not text.isascii():
            pos = extra = 0
            for ch in text:
                width = len(ch.encode("utf-8", "surrogatepass"))
                pos += width
                if width > 1:
                    extra += width - 1
                    self._wide.append(pos)
                    self._extra.append(extra)

    def char_offset(self, byte_offset: int) -> int:
        if not self._wide:
            return byte_offset
        i = bisect.bisect_right(self._wide, byte_offset) - 1
        return byte_offset - (self._extra[i] if i >= 0 else 0)

    def start(self, tag: str, attrib: dict) -> None:
        offset = self.char_offset(self.expat.CurrentByteIndex)
        el = _El(tag.rpartition("}")[2], dict(attrib), offset)
        el.attrib = {k.rpartition("}")[2]: v for k, v in attrib.items()}
        el.content_start = el.end = _tag_end(self.text, offset) + 1
        if self.stack:
            self.stack[-1].children.append(el)
        elif self.root is None:
            self.root = el
        self.stack.append(el)

    def end(self, tag: str) -> None:
        el = self.stack.pop()
        offset = self.char_offset(self.expat.CurrentByteIndex)
        if self.text.startswith("</", offset):
            el.end = offset
        else:   # an empty-element tag `<x/>`: no content
            el.end = el.content_start

    def data(self, text: str) -> None:
        pass

    def close(self):
        return self.root


def _tag_end(text: str, start: int) -> int:
    """Offset of the '>' closing the tag that starts at `start` (quoted attribute values skipped)."""
    i = start
    quote = ""
    n = len(text)
    while i < n:
        ch = text[i]
        if quote:
            if ch == quote:
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch == ">":
            return i
        i += 1
    return n - 1


class _Lines:
    def __init__(self, text: str) -> None:
        self.starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def position(self, offset: int) -> tuple[int, int]:
        i = bisect.bisect_right(self.starts, offset) - 1
        return i + 1, offset - self.starts[i] + 1


def _xml_error(message: str, text: str, line: int, column: int) -> SourceError:
    return SourceError(message, line, column, text, "E007")


def _parse_xml(text: str) -> _Builder:
    from xml.etree.ElementTree import ParseError

    from defusedxml import DefusedXmlException
    from defusedxml.ElementTree import DefusedXMLParser

    builder = _Builder(text)
    parser = DefusedXMLParser(target=builder)
    builder.expat = parser.parser
    try:
        parser.feed(text)
        parser.close()
    except ParseError as exc:
        line, byte_col = exc.position
        raw = text.split("\n")[line - 1] if 0 < line <= text.count("\n") + 1 else ""
        col = len(raw.encode("utf-8")[:byte_col].decode("utf-8", errors="ignore")) + 1
        reason = str(exc).split(":", 1)[0]
        raise _xml_error(f"malformed XML: {reason}", text, line, col) from None
    except DefusedXmlException as exc:
        expat = parser.parser
        line = expat.CurrentLineNumber
        raise _xml_error(f"XML with entity declarations or external references is refused "
                         f"({type(exc).__name__}): stvm reads project files without them", text, line, 1) from None
    if builder.root is None:
        raise _xml_error("malformed XML: no element found", text, 1, 1)
    return builder


# ---- content of an element, with the position of every character ------------------------------------

_ENTITIES = {"lt": "<", "gt": ">", "amp": "&", "apos": "'", "quot": '"'}


_MARKUP = re.compile(r"[<&\r]")


def _verbatim(out: list[tuple[str, int]], text: str, start: int, end: int) -> None:
    """text[start:end] as runs of one line each (CR LF and a lone CR as LF)."""
    i = start
    while i < end:
        j = text.find("\n", i, end)
        stop = end if j < 0 else j
        if j >= 0 and stop > i and text[stop - 1] == "\r":
            stop -= 1                      # CR LF
        k = i
        while True:
            r = text.find("\r", k, stop)
            piece_end = stop if r < 0 else r
            if piece_end > k:
                out.append((text[k:piece_end], k))
            if r < 0:
                break
            out.append(("\n", r))          # a lone CR
            k = r + 1
        if j < 0:
            break
        out.append(("\n", j))
        i = j + 1


def _content(text: str, start: int, end: int) -> list[tuple[str, int]]:
    """The text of text[start:end] as XML reads it (CDATA verbatim, entities decoded, comments,
    processing instructions and nested tags dropped, CR LF as LF), as runs `(piece, offset)`:
    "\n", or a piece without line breaks whose characters stand from `offset` on in the XML
    (an entity is a one-character piece at its '&')."""
    out: list[tuple[str, int]] = []
    i = start
    while i < end:
        m = _MARKUP.search(text, i, end)
        if m is None:
            _verbatim(out, text, i, end)
            break
        k = m.start()
        if k > i:
            _verbatim(out, text, i, k)
        i = k
        ch = text[i]
        if ch == "<":
            if text.startswith("<![CDATA[", i):
                j = text.find("]]>", i + 9, end)
                j = end if j < 0 else j
                _verbatim(out, text, i + 9, j)
                i = j + 3
            elif text.startswith("<!--", i):
                j = text.find("-->", i + 4, end)
                i = end if j < 0 else j + 3
            elif text.startswith("<?", i):
                j = text.find("?>", i + 2, end)
                i = end if j < 0 else j + 2
            else:
                i = _tag_end(text, i) + 1
        elif ch == "&":
            j = text.find(";", i, end)
            name = text[i + 1:j] if j > 0 else ""
            if name.startswith("#x") or name.startswith("#X"):
                out.append((chr(int(name[2:], 16)), i))
            elif name.startswith("#"):
                out.append((chr(int(name[1:])), i))
            else:
                out.append((_ENTITIES.get(name, "?"), i))
            i = j + 1 if j > 0 else i + 1
        else:   # "\r"
            if not (i + 1 < end and text[i + 1] == "\n"):
                out.append(("\n", i))
            i += 1
    return out


# ---- the ST text, laid out on the XML's lines ----------------------------------------------------------


class _Out:
    def __init__(self, lines: _Lines) -> None:
        self.lines_of = lines
        self.rows: list[list[str]] = [[]]
        self.map = SourceMap()

    @property
    def line(self) -> int:
        return len(self.rows)

    @property
    def col(self) -> int:
        return len(self.rows[-1]) + 1

    def _last(self) -> str:
        row = self.rows[-1]
        return row[-1] if row else " "

    def _goto(self, line: int, col: int, tight: bool = False) -> bool:
        """Move to (line, col) by padding, if that is at or after the cursor (and, unless
        `tight`, leaves a blank after a previous token)."""
        if line < self.line or (line == self.line and col < self.col):
            return False
        if line == self.line and col == self.col and not tight and not self._last().isspace():
            return False
        while self.line < line:
            self.rows.append([])
        self.rows[-1].extend(" " * (col - self.col))
        return True

    def _write(self, ch: str, xml_line: int, xml_col: int, fixed: bool) -> None:
        self.map.add(self.line, self.col, xml_line, xml_col, fixed)
        self.rows[-1].append(ch)

    def glue(self, text: str, offset: int) -> None:
        """Text stvm adds (a keyword, a generated declaration) anchored at XML offset `offset`."""
        line, col = self.lines_of.position(offset)
        if self._goto(line, col):
            for ch in text:
                self._write(ch, line, self.col, False)
            return
        if not self._last().isspace():
            self._write(" ", line, col, True)
        for ch in text:
            self._write(ch, line, col, True)

    def value(self, text: str, offset: int) -> None:
        """Text spelled in the XML at `offset` (an attribute value), mapped character by character."""
        text = text.replace("\r", " ").replace("\n", " ")   # `&#10;` must not move the lines below
        line, col = self.lines_of.position(offset)
        if not self._goto(line, col):
            if not self._last().isspace():
                self._write(" ", line, col, True)
        for i, ch in enumerate(text):
            self._write(ch, line, col + i, False)

    def content(self, runs: list[tuple[str, int]]) -> None:
        """Decoded XML text: the first piece of each line at its own place when it can stand
        there, the others right after the one before (as XML concatenates them: an entity before
        a piece is longer in the XML than in the ST)."""
        at_start = True
        for piece, offset in runs:
            if piece == "\n":
                self.rows.append([])
                at_start = True
                continue
            line, col = self.lines_of.position(offset)
            if at_start and not self._goto(line, col) and not self._last().isspace():
                self._write(" ", line, col, True)
            at_start = False
            self.map.add_range(self.line, self.col, len(piece), line, col)
            self.rows[-1].extend(piece)

    def text(self) -> str:
        return "\n".join("".join(row) for row in self.rows) + "\n"


# ---- TwinCAT 3 -------------------------------------------------------------------------------------

_COMMENTS_AND_PRAGMAS = re.compile(r"\(\*[\s\S]*?\*\)|/\*[\s\S]*?\*/|//[^\n]*|\{[^}]*\}")
_POU_KEYWORD = re.compile(r"\b(FUNCTION_BLOCK|FUNCTION|PROGRAM|INTERFACE)\b", re.I)
_END_OF = {"FUNCTION_BLOCK": "END_FUNCTION_BLOCK", "FUNCTION": "END_FUNCTION", "PROGRAM": "END_PROGRAM",
           "INTERFACE": "END_INTERFACE"}


class _Reader:
    def __init__(self, text: str, builder: _Builder) -> None:
        self.text = text
        self.root = builder.root
        self.lines = _Lines(text)
        self.out = _Out(self.lines)

    def error(self, message: str, el: _El) -> SourceError:
        line, col = self.lines.position(el.start)
        return _xml_error(message, self.text, line, col)

    def name(self, el: _El, attr: str = "name") -> None:
        """The identifier in attribute `attr` of `el`, written at its place (a name that is not
        an ST identifier is an error there, never ST text)."""
        value = el.attrib.get(attr)
        if value is None:
            raise self.error(f"<{el.tag}> has no {attr}=\"…\"", el)
        if not _IDENT.match(value):
            line, col = self.lines.position(self.attr_offset(el, attr))
            raise _xml_error(f"{attr}={value[:40]!r} of <{el.tag}> is not an ST identifier", self.text, line, col)
        self.out.value(value, self.attr_offset(el, attr))

    def attr_offset(self, el: _El, name: str) -> int:
        """Offset of the value of attribute `name` in el's start tag (the tag itself if absent)."""
        tag = self.text[el.start:el.content_start]
        m = re.search(r"\b" + re.escape(name) + r"\s*=\s*([\"'])", tag)
        return el.start + m.end() if m else el.start

    def gvl_name(self, name: str, el: _El) -> None:
        """The name of a global variable list, as an attribute before its VAR_GLOBAL: its
        variables are then also `Name.var` (and only that with `qualified_only`)."""
        if _IDENT.match(name):
            self.out.glue(f"{{attribute 'gvl' := '{name}'}}", el.start + 1)

    def emit_content(self, el: _El | None) -> str:
        if el is None:
            return ""
        runs = _content(self.text, el.content_start, el.end)
        self.out.content(runs)
        return "".join(piece for piece, _ in runs)

    # -- TwinCAT
    def twincat(self) -> None:
        if self.root.tag != "TcPlcObject":
            raise self.error(f"not a TwinCAT source: the root element is <{self.root.tag}>, "
                             f"expected <TcPlcObject>", self.root)
        for obj in self.root.children:
            if obj.tag in ("POU", "Itf"):
                self.tc_pou(obj)
            elif obj.tag in ("DUT", "GVL"):
                if obj.tag == "GVL":
                    self.gvl_name(obj.attrib.get("Name", ""), obj)
                self.emit_content(obj.find("Declaration"))
            # other TwinCAT objects (tasks, visualisations, text lists …) hold no ST

    def st_body(self, el: _El, container: str, what: str) -> None:
        """The ST text of `el`'s body element (`Implementation` in TwinCAT, `body` in PLCopen);
        a body in another language (SFC, LD, FBD, IL) is an error at that element."""
        body = el.find(container)
        if body is None:
            return
        st = body.find("ST")
        if st is None:
            lang = body.children[0].tag if body.children else "no"
            raise self.error(f"{what} has a {lang} body; stvm reads Structured Text (<ST>) bodies only", body)
        self.emit_content(st)

    def tc_body(self, el: _El, what: str) -> None:
        self.st_body(el, "Implementation", what)

    def tc_pou(self, pou: _El) -> None:
        name = pou.attrib.get("Name", "?")
        decl = pou.find("Declaration")
        if decl is None:
            raise self.error(f"{pou.tag} '{name}' has no <Declaration>", pou)
        header = self.emit_content(decl)
        m = _POU_KEYWORD.search(_COMMENTS_AND_PRAGMAS.sub(" ", header))
        if m is None:
            raise self.error(f"the declaration of '{name}' names no FUNCTION_BLOCK, FUNCTION, PROGRAM or "
                             f"INTERFACE", decl)
        kind = m.group(1).upper()
        self.tc_body(pou, f"{pou.tag} '{name}'")
        for child in pou.children:
            if child.tag == "Method":
                self.emit_content(child.find("Declaration"))
                self.tc_body(child, f"method '{child.attrib.get('Name', '?')}'")
                self.out.glue("END_METHOD", child.end)
            elif child.tag == "Property":
                self.emit_content(child.find("Declaration"))
                for acc in child.children:
                    if acc.tag in ("Get", "Set"):
                        self.out.glue(acc.tag.upper(), acc.start + 1)
                        self.emit_content(acc.find("Declaration"))
                        self.tc_body(acc, f"property '{child.attrib.get('Name', '?')}' {acc.tag}")
                        self.out.glue("END_" + acc.tag.upper(), acc.end)
                self.out.glue("END_PROPERTY", child.end)
            elif child.tag == "Action":
                # an action is the POU's code under a name, called as `inst.A()`: a method with
                # no parameters and no variables of its own
                self.out.glue("METHOD", child.start + 1)
                self.name(child, "Name")
                self.tc_body(child, f"action '{child.attrib.get('Name', '?')}'")
                self.out.glue("END_METHOD", child.end)
        self.out.glue(_END_OF[kind], pou.end)

    # -- PLCopen
    def plcopen(self) -> None:
        if self.root.tag != "project":
            raise self.error(f"not a PLCopen XML project: the root element is <{self.root.tag}>, "
                             f"expected <project>", self.root)
        types = self.root.find("types")
        if types is not None:
            data_types = types.find("dataTypes")
            if data_types is not None and data_types.findall("dataType"):
                self.out.glue("TYPE", data_types.start + 1)
                for dt in data_types.findall("dataType"):
                    self.data_type(dt)
                self.out.glue("END_TYPE", data_types.end)
            pous = types.find("pous")
            for pou in pous.findall("pou") if pous is not None else []:
                self.plc_pou(pou)
        instances = self.root.find("instances")
        configurations = instances.find("configurations") if instances is not None else None
        for conf in configurations.findall("configuration") if configurations is not None else []:
            self.configuration(conf)
        for gvl in self._add_data(self.root, "globalvars", "globalVars"):   # CODESYS: after <instances>
            self.gvl_name(gvl.attrib.get("name", ""), gvl)
            self.attributes(gvl)
            self.var_list(gvl, "VAR_GLOBAL")

    def _add_data(self, el: _El, kind: str, tag: str) -> list[_El]:
        out = []
        add = el.find("addData")
        for data in add.findall("data") if add is not None else []:
            if data.attrib.get("name", "").lower().endswith("/" + kind):
                out += data.findall(tag)
        return out

    def attributes(self, el: _El) -> None:
        """CODESYS writes an object's attributes (`{attribute 'qualified_only'}`) into its
        `<addData>` as `<Attributes><Attribute Name=… Value=…/>`: as pragmas before it."""
        for attrs in self._add_data(el, "attributes", "Attributes"):
            for attr in attrs.findall("Attribute"):
                name, value = attr.attrib.get("Name", ""), attr.attrib.get("Value", "")
                if not _ATTRIBUTE_TEXT.match(name) or not _ATTRIBUTE_VALUE.match(value):
                    raise self.error(f"attribute {name[:40]!r} := {value[:40]!r} cannot be written as a pragma", attr)
                pragma = f"{{attribute '{name}' := '{value}'}}" if value else f"{{attribute '{name}'}}"
                self.out.glue(pragma, attr.start + 1)

    def data_type(self, dt: _El) -> None:
        self.attributes(dt)
        self.name(dt)
        base = dt.find("baseType")
        if base is None or not base.children:
            raise self.error(f"data type '{dt.attrib.get('name', '?')}' has no <baseType>", dt)
        self.out.glue(":", base.start)
        spec = base.children[0]
        if spec.tag == "struct":
            self.out.glue("STRUCT", spec.start + 1)
            for var in spec.findall("variable"):
                self.variable(var)
            self.out.glue("END_STRUCT", spec.end)
        elif spec.tag == "enum":
            self.out.glue("(", spec.start + 1)
            values = spec.find("values")
            for i, value in enumerate(values.findall("value") if values is not None else []):
                if i:
                    self.out.glue(",", value.start)
                self.name(value)
                if "value" in value.attrib:
                    self.out.glue(":=", self.attr_offset(value, "value") - 1)
                    self.out.value(value.attrib["value"], self.attr_offset(value, "value"))
            self.out.glue(")", spec.end)
            enum_base = spec.find("baseType")
            if enum_base is not None and enum_base.children:
                self.type_spec(enum_base.children[0])
        else:
            self.type_spec(spec)
        init = dt.find("initialValue")
        if init is not None:
            self.initial_value(init)
        self.out.glue(";", dt.end)

    def type_spec(self, spec: _El) -> None:
        tag = spec.tag
        if tag == "derived":
            self.name(spec)
        elif tag in ("string", "wstring"):
            self.out.glue(tag.upper(), spec.start + 1)
            if "length" in spec.attrib:
                self.out.glue("[", self.attr_offset(spec, "length") - 1)
                self.out.value(spec.attrib["length"], self.attr_offset(spec, "length"))
                self.out.glue("]", self.attr_offset(spec, "length") + len(spec.attrib["length"]))
        elif tag == "array":
            self.out.glue("ARRAY", spec.start + 1)
            for i, dim in enumerate(spec.findall("dimension")):
                self.out.glue("[" if i == 0 else ",", dim.start)
                self.out.value(dim.attrib.get("lower", "0"), self.attr_offset(dim, "lower"))
                self.out.glue("..", self.attr_offset(dim, "upper") - 1)
                self.out.value(dim.attrib.get("upper", "0"), self.attr_offset(dim, "upper"))
            base = spec.find("baseType")
            self.out.glue("]", base.start if base is not None else spec.end)
            self.out.glue("OF", base.start + 1 if base is not None else spec.end)
            if base is None or not base.children:
                raise self.error("an <array> needs a <baseType>", spec)
            self.type_spec(base.children[0])
        elif tag in ("subrangeSigned", "subrangeUnsigned"):
            base = spec.find("baseType")
            rng = spec.find("range")
            if base is None or not base.children or rng is None:
                raise self.error(f"a <{tag}> needs a <range> and a <baseType>", spec)
            self.type_spec(base.children[0])
            self.out.glue("(", rng.start)
            self.out.value(rng.attrib.get("lower", "0"), self.attr_offset(rng, "lower"))
            self.out.glue("..", self.attr_offset(rng, "upper") - 1)
            self.out.value(rng.attrib.get("upper", "0"), self.attr_offset(rng, "upper"))
            self.out.glue(")", rng.end)
        elif tag == "pointer":
            base = spec.find("baseType")
            if base is None or not base.children:
                raise self.error("a <pointer> needs a <baseType>", spec)
            self.out.glue("POINTER TO", spec.start + 1)
            self.type_spec(base.children[0])
        elif tag in ("struct", "enum"):
            raise self.error(f"an anonymous <{tag}> in a variable's type: declare it as a <dataType>", spec)
        else:
            # elementary types are spelled as elements: <INT/>, <BOOL/>, <TIME/>, <LREAL/> …
            self.out.value(tag, spec.start + 1)

    def initial_value(self, init: _El) -> None:
        self.out.glue(":=", init.start + 1)
        if not init.children:
            raise self.error("an empty <initialValue>", init)
        self.value_element(init.children[0])

    def value_element(self, val: _El) -> None:
        if val.tag == "simpleValue":
            self.out.value(val.attrib.get("value", ""), self.attr_offset(val, "value"))
        elif val.tag == "arrayValue":
            self.out.glue("[", val.start + 1)
            for i, item in enumerate(val.findall("value")):
                if i:
                    self.out.glue(",", item.start)
                inner = item.children[0] if item.children else None
                if "repetitionValue" in item.attrib:
                    self.out.value(item.attrib["repetitionValue"], self.attr_offset(item, "repetitionValue"))
                    self.out.glue("(", item.start + 1)
                    if inner is not None:
                        self.value_element(inner)
                    self.out.glue(")", item.end)
                elif inner is not None:
                    self.value_element(inner)
            self.out.glue("]", val.end)
        elif val.tag == "structValue":
            self.out.glue("(", val.start + 1)
            for i, item in enumerate(val.findall("value")):
                if i:
                    self.out.glue(",", item.start)
                self.name(item, "member")
                self.out.glue(":=", item.start + 1)
                if item.children:
                    self.value_element(item.children[0])
            self.out.glue(")", val.end)
        else:
            raise self.error(f"unknown initial value <{val.tag}>", val)

    def variable(self, var: _El) -> None:
        self.name(var)
        if "address" in var.attrib:
            self.out.glue("AT", self.attr_offset(var, "address") - 1)
            self.out.value(var.attrib["address"], self.attr_offset(var, "address"))
        typ = var.find("type")
        if typ is None or not typ.children:
            raise self.error(f"variable '{var.attrib.get('name', '?')}' has no <type>", var)
        self.out.glue(":", typ.start)
        self.type_spec(typ.children[0])
        init = var.find("initialValue")
        if init is not None:
            self.initial_value(init)
        self.out.glue(";", var.end)

    _VAR_LISTS = {"inputVars": "VAR_INPUT", "outputVars": "VAR_OUTPUT", "inOutVars": "VAR_IN_OUT",
                  "localVars": "VAR", "tempVars": "VAR_TEMP", "externalVars": "VAR_EXTERNAL",
                  "globalVars": "VAR_GLOBAL", "accessVars": "VAR_ACCESS"}

    def var_list(self, el: _El, keyword: str) -> None:
        self.out.glue(keyword, el.start + 1)
        for attr, qual in (("constant", "CONSTANT"), ("retain", "RETAIN"), ("nonretain", "NON_RETAIN"),
                           ("persistent", "PERSISTENT")):
            if el.attrib.get(attr, "").lower() in ("true", "1"):
                self.out.glue(qual, self.attr_offset(el, attr))
        for var in el.findall("variable"):
            self.variable(var)
        self.out.glue("END_VAR", el.end)

    def interface(self, iface: _El | None) -> None:
        if iface is None:
            return
        for child in iface.children:
            keyword = self._VAR_LISTS.get(child.tag)
            if keyword is not None:
                self.var_list(child, keyword)

    def plc_body(self, el: _El, what: str) -> None:
        self.st_body(el, "body", what)

    def plc_callable(self, el: _El, what: str) -> None:
        """A PLCopen pou or CODESYS method after its keyword: name, `: return type`, the var
        lists of its <interface>, its ST body."""
        self.name(el)
        iface = el.find("interface")
        ret = iface.find("returnType") if iface is not None else None
        if ret is not None and ret.children:
            self.out.glue(":", ret.start)
            self.type_spec(ret.children[0])
        self.interface(iface)
        self.plc_body(el, what)

    _POU_TYPES = {"function": "FUNCTION", "functionblock": "FUNCTION_BLOCK", "program": "PROGRAM"}

    def plc_pou(self, pou: _El) -> None:
        name = pou.attrib.get("name", "?")
        kind = self._POU_TYPES.get(pou.attrib.get("pouType", "").lower())
        if kind is None:
            raise self.error(f"pou '{name}' has pouType {pou.attrib.get('pouType')!r}; expected function, "
                             f"functionBlock or program", pou)
        self.out.glue(kind, pou.start + 1)
        self.plc_callable(pou, f"pou '{name}'")
        for method in self._add_data(pou, "method", "Method"):
            mname = method.attrib.get("name", "?")
            self.out.glue("METHOD", method.start + 1)
            self.plc_callable(method, f"method '{mname}'")
            self.out.glue("END_METHOD", method.end)
        for prop in self._add_data(pou, "property", "Property"):
            pname = prop.attrib.get("name", "?")
            self.out.glue("PROPERTY", prop.start + 1)
            self.name(prop)
            piface = prop.find("interface")
            pret = piface.find("returnType") if piface is not None else None
            if pret is None or not pret.children:
                raise self.error(f"property '{pname}' has no <returnType>", prop)
            self.out.glue(":", pret.start)
            self.type_spec(pret.children[0])
            for tag, word in (("GetAccessor", "GET"), ("SetAccessor", "SET")):
                acc = prop.find(tag)
                if acc is not None:
                    self.out.glue(word, acc.start + 1)
                    self.interface(acc.find("interface"))
                    self.plc_body(acc, f"property '{pname}' {word}")
                    self.out.glue("END_" + word, acc.end)
            self.out.glue("END_PROPERTY", prop.end)
        actions = pou.find("actions")
        for action in actions.findall("action") if actions is not None else []:
            self.out.glue("METHOD", action.start + 1)
            self.name(action)
            self.plc_body(action, f"action '{action.attrib.get('name', '?')}'")
            self.out.glue("END_METHOD", action.end)
        self.out.glue(_END_OF[kind], pou.end)

    def configuration(self, conf: _El) -> None:
        self.out.glue("CONFIGURATION", conf.start + 1)
        self.name(conf)
        for gv in conf.findall("globalVars"):
            self.var_list(gv, "VAR_GLOBAL")
        for res in conf.findall("resource"):
            self.out.glue("RESOURCE", res.start + 1)
            self.name(res)
            self.out.glue("ON PLC", res.content_start - 1)
            for gv in res.findall("globalVars"):
                self.var_list(gv, "VAR_GLOBAL")
            for task in res.findall("task"):
                self.out.glue("TASK", task.start + 1)
                self.name(task)
                params = [(k, task.attrib[k]) for k in ("interval", "single", "priority") if k in task.attrib]
                for i, (key, value) in enumerate(params):
                    self.out.glue("(" if i == 0 else ",", self.attr_offset(task, key) - len(key) - 2)
                    self.out.glue(key.upper() + " :=", self.attr_offset(task, key) - 1)
                    self.out.value(_task_value(key, value), self.attr_offset(task, key))
                if params:
                    self.out.glue(")", task.content_start - 1)
                self.out.glue(";", task.content_start - 1)
                for inst in task.findall("pouInstance"):
                    self.program_instance(inst, task.attrib.get("name"))
            for inst in res.findall("pouInstance"):
                self.program_instance(inst, None)
            self.out.glue("END_RESOURCE", res.end)
        self.out.glue("END_CONFIGURATION", conf.end)

    def program_instance(self, inst: _El, task: str | None) -> None:
        self.out.glue("PROGRAM", inst.start + 1)
        self.name(inst)
        if task:
            self.out.glue(f"WITH {task}", self.attr_offset(inst, "typeName") - len('typeName="'))
        self.out.glue(":", self.attr_offset(inst, "typeName") - 1)
        self.name(inst, "typeName")
        self.out.glue(";", inst.end)


_IDENT = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_ATTRIBUTE_TEXT = re.compile(r"^[A-Za-z_][A-Za-z0-9_.\-]*$")
_ATTRIBUTE_VALUE = re.compile(r"^[^'{}\r\n]*$")
_XSD_DURATION = re.compile(r"^P(?:(\d+)D)?(?:T(?:(\d+)H)?(?:(\d+)M)?(?:(\d+(?:\.\d+)?)S)?)?$", re.I)


def _task_value(key: str, value: str) -> str:
    """A task attribute as ST: PLCopen writes intervals as XML durations (`PT0.01S`) or IEC
    literals (`T#10ms`)."""
    if key != "interval":
        return value
    m = _XSD_DURATION.match(value.strip())
    if not m:
        return value
    days, hours, minutes, seconds = m.groups()
    ms = round((int(days or 0) * 86400 + int(hours or 0) * 3600 + int(minutes or 0) * 60
                + float(seconds or 0)) * 1000, 3)
    return f"T#{ms:g}ms"


# ---- entry points ----------------------------------------------------------------------------------

_XML_ENCODING = re.compile(rb"""^\s*<\?xml[^>]*\bencoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def read_vendor(path: Path, encoding: str = "utf-8") -> VendorText:
    """Read a vendor XML file as ST text (raises SourceError for a file that cannot be read as
    XML, with the line and column of the problem, and OSError)."""
    with open(path, "rb") as fh:
        head = fh.read(200)
    head = head[3:] if head.startswith(b"\xef\xbb\xbf") else head
    m = _XML_ENCODING.match(head)
    declared = m.group(1).decode("ascii") if m else encoding
    text = read_source(path, declared if declared.lower().replace("-", "") != "utf8" else "utf-8")
    return translate(text, str(path))


def unreadable(xml_text: str) -> VendorText:
    """A vendor file that is not usable XML: no ST at all, its XML kept for the excerpt."""
    return VendorText("", xml_text, SourceMap())


def translate(text: str, name: str) -> VendorText:
    """The ST text of the XML `text` of file `name` (TwinCAT by its extension or root element,
    else PLCopen)."""
    builder = _parse_xml(text)
    reader = _Reader(text, builder)
    if reader.root.tag == "TcPlcObject" or Path(name).suffix.lower() in TWINCAT_SUFFIXES:
        reader.twincat()
    else:
        reader.plcopen()
    return VendorText(reader.out.text(), text, reader.out.map)
