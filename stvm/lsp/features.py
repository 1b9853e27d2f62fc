"""The language features, as plain functions of an `Index` (stvm/lsp/index.py) and the text the
editor holds: no protocol objects here beyond lsprotocol's result types, so each answer can be
tested and timed on its own.
"""

from __future__ import annotations

import re

from lsprotocol import types as lsp

from stvm.semantics import types as t
from stvm.lsp.index import ENUM, FIELD, GLOBAL, POU, PROP, TYPE, VAR, Index, Symbol, deref

KEYWORDS = (
    "IF THEN ELSIF ELSE END_IF CASE OF END_CASE FOR TO BY DO END_FOR WHILE END_WHILE REPEAT UNTIL "
    "END_REPEAT RETURN EXIT CONTINUE AND AND_THEN OR OR_ELSE XOR NOT MOD TRUE FALSE VAR VAR_INPUT "
    "VAR_OUTPUT VAR_IN_OUT VAR_TEMP VAR_GLOBAL VAR_EXTERNAL VAR_STAT VAR_INST END_VAR CONSTANT RETAIN "
    "PERSISTENT FUNCTION END_FUNCTION FUNCTION_BLOCK END_FUNCTION_BLOCK PROGRAM END_PROGRAM METHOD "
    "END_METHOD PROPERTY END_PROPERTY GET END_GET SET END_SET INTERFACE END_INTERFACE EXTENDS IMPLEMENTS "
    "THIS SUPER ABSTRACT FINAL PUBLIC PRIVATE PROTECTED INTERNAL TYPE END_TYPE STRUCT END_STRUCT UNION "
    "END_UNION ARRAY REF_TO POINTER REFERENCE NULL NAMESPACE END_NAMESPACE BOOL BYTE WORD DWORD LWORD "
    "SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL TIME LTIME DATE TIME_OF_DAY TOD DATE_AND_TIME "
    "DT STRING WSTRING").split()
_RESERVED = {k.lower() for k in KEYWORDS}
IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")

TOKEN_TYPES = ["namespace", "type", "class", "enum", "interface", "struct", "parameter", "variable",
               "property", "enumMember", "function", "method"]
TOKEN_MODIFIERS = ["declaration", "readonly", "defaultLibrary"]
_TOKEN_OF_KIND = {"VAR_INPUT": "parameter", "VAR_OUTPUT": "parameter", "VAR_IN_OUT": "parameter",
                  "VAR": "variable", "VAR_TEMP": "variable", "VAR_EXTERNAL": "variable", "VAR_GLOBAL": "variable",
                  "VAR_STAT": "variable", "VAR_INST": "variable", "FUNCTION": "function",
                  "FUNCTION_BLOCK": "class", "PROGRAM": "class", "INTERFACE": "interface", "METHOD": "method",
                  "PROPERTY": "property", "FIELD": "property", "STRUCT": "struct", "UNION": "struct",
                  "ALIAS": "type", "ENUM": "enum", "ENUMERATOR": "enumMember"}
_SYMBOL_KIND = {"FUNCTION": lsp.SymbolKind.Function, "FUNCTION_BLOCK": lsp.SymbolKind.Class,
                "PROGRAM": lsp.SymbolKind.Module, "INTERFACE": lsp.SymbolKind.Interface,
                "METHOD": lsp.SymbolKind.Method, "PROPERTY": lsp.SymbolKind.Property,
                "STRUCT": lsp.SymbolKind.Struct, "UNION": lsp.SymbolKind.Struct, "ALIAS": lsp.SymbolKind.TypeParameter,
                "ENUM": lsp.SymbolKind.Enum, "ENUMERATOR": lsp.SymbolKind.EnumMember, "FIELD": lsp.SymbolKind.Field,
                "VAR_GLOBAL": lsp.SymbolKind.Variable}
_COMPLETION_KIND = {"parameter": lsp.CompletionItemKind.Variable, "variable": lsp.CompletionItemKind.Variable,
                    "function": lsp.CompletionItemKind.Function, "class": lsp.CompletionItemKind.Class,
                    "interface": lsp.CompletionItemKind.Interface, "method": lsp.CompletionItemKind.Method,
                    "property": lsp.CompletionItemKind.Property, "struct": lsp.CompletionItemKind.Struct,
                    "type": lsp.CompletionItemKind.TypeParameter, "enum": lsp.CompletionItemKind.Enum,
                    "enumMember": lsp.CompletionItemKind.EnumMember}


# ---- text of types, signatures and comments ------------------------------------------------------


def type_text(ty: t.Type | None) -> str:
    if ty is None:
        return "?"
    if isinstance(ty, t.ArrayType):
        dims = "*" if ty.dims is None else ", ".join(f"{lo}..{hi}" for lo, hi in ty.dims)
        return f"ARRAY[{dims}] OF {type_text(ty.element)}"
    if isinstance(ty, t.RefType):
        word = {"REF_TO": "REF_TO", "POINTER": "POINTER TO", "REFERENCE": "REFERENCE TO"}.get(ty.flavour, "REF_TO")
        return f"{word} {type_text(ty.target)}"
    if isinstance(ty, t.StringType) and ty.name.upper() in ("STRING", "WSTRING") and ty.size != 1986 \
            and not isinstance(ty, t.WStringType):
        return f"STRING[{ty.size - 1}]"
    return str(ty)


def signature(pou) -> str:
    """`FUNCTION_BLOCK TON(IN : BOOL; PT : TIME) => (Q : BOOL; ET : TIME)`, `FUNCTION F(…) : T`."""
    ins = [f"{v.name} : {type_text(v.type)}" for v in pou.variables.values() if v.section == "VAR_INPUT"]
    io = [f"{v.name} : {type_text(v.type)}" for v in pou.variables.values() if v.section == "VAR_IN_OUT"]
    outs = [f"{v.name} : {type_text(v.type)}" for v in pou.variables.values() if v.section == "VAR_OUTPUT"]
    params = ins + [f"VAR_IN_OUT {p}" for p in io]
    name = pou.qualname.replace("\\", ".") if pou.kind != "METHOD" else pou.qualname
    text = f"{pou.kind} {name}({'; '.join(params)})"
    if pou.return_type is not None and not isinstance(pou.return_type, t.VoidType):
        text += f" : {type_text(pou.return_type)}"
    if outs:
        text += f" => ({'; '.join(outs)})"
    if pou.kind == "INTERFACE":
        text = f"INTERFACE {pou.name}"
    return text


_COMMENT_AFTER = re.compile(r"(?:\(\*(.*?)\*\)|//(.*)$)")


def doc_comment(text: str, line: int, col: int) -> str:
    """The comment of a declaration at (line, col): a comment after it on its line, else the
    block of comment lines right above it (pragma lines `{…}` between are skipped)."""
    lines = text.splitlines()
    if not 0 <= line < len(lines):
        return ""
    rest = lines[line][col:]
    m = _COMMENT_AFTER.search(rest)
    if m and ";" in rest[:m.start()] + ";":
        return (m.group(1) or m.group(2) or "").strip()
    out: list[str] = []
    i = line - 1
    while i >= 0 and lines[i].strip().startswith("{") and lines[i].strip().endswith("}"):
        i -= 1
    if i >= 0 and lines[i].rstrip().endswith("*)"):
        end = i
        while i >= 0 and "(*" not in lines[i]:
            i -= 1
        if i < 0:
            return ""
        block = "\n".join(lines[i:end + 1]).strip()
        if block.startswith("(*"):
            return _dedent(block[2:-2])
        return ""
    while i >= 0 and lines[i].strip().startswith("//"):
        out.insert(0, lines[i].strip()[2:].strip())
        i -= 1
    return "\n".join(out)


def _dedent(text: str) -> str:
    lines = [ln.rstrip() for ln in text.strip("\n").splitlines()]
    indents = [len(ln) - len(ln.lstrip()) for ln in lines[1:] if ln.strip()]
    cut = min(indents) if indents else 0
    return "\n".join([lines[0].strip()] + [ln[cut:] for ln in lines[1:]]).strip()


def describe(ix: Index, sym: Symbol) -> str:
    """The code line of a symbol's hover: its declaration in ST."""
    if sym.key[0] == POU and sym.pou is not None:
        return signature(sym.pou)
    if sym.key[0] == TYPE:
        ty = sym.type
        if isinstance(ty, t.EnumType):
            return f"TYPE {sym.name} : ({', '.join(f'{m} := {v}' for m, v in ty.members)})"
        if isinstance(ty, t.StructType):
            fields = "; ".join(f"{f} : {type_text(ft)}" for f, ft in ty.fields)
            return f"TYPE {sym.name} : {sym.kind} {fields}; END_{sym.kind}"
        return f"TYPE {sym.name}"
    if sym.key[0] == ENUM:
        return f"{sym.container}#{sym.name} = {sym.value}"
    if sym.key[0] == PROP:
        return f"PROPERTY {sym.container}.{sym.name} : {type_text(sym.type)}"
    if sym.key[0] == FIELD:
        return f"{sym.container}.{sym.name} : {type_text(sym.type)}"
    const = " CONSTANT" if sym.constant else ""
    init = ""
    if sym.variable is not None and sym.variable.init is not None and isinstance(sym.variable.init, (int, float, bool)):
        init = f" := {sym.variable.init}"
    where = f"{sym.container}." if sym.container else ""
    return f"({sym.kind}{const}) {where}{sym.name} : {type_text(sym.type)}{init}"


def hover_markdown(ix: Index, sym: Symbol) -> str:
    parts = [f"```iecst\n{describe(ix, sym)}\n```"]
    text = ix.texts.get(sym.file, "")
    doc = doc_comment(text, sym.line, sym.end_col) if sym.line >= 0 else ""
    if doc:
        parts.append(doc)
    where = "stvm standard library" if sym.stdlib else sym.file.rsplit("/", 1)[-1]
    if sym.line >= 0:
        parts.append(f"*declared in {where}, line {sym.line + 1}*")
    if sym.key[0] in (VAR, GLOBAL, FIELD, PROP):
        tsym = ix.type_symbol(sym.type)
        if tsym is not None and tsym.pou is not None and tsym.pou.kind in ("FUNCTION_BLOCK", "INTERFACE"):
            parts.append(f"`{signature(tsym.pou)}`")
    return "\n\n".join(parts)


# ---- positions -------------------------------------------------------------------------------


def rng(line: int, col: int, end: int) -> lsp.Range:
    return lsp.Range(lsp.Position(line, col), lsp.Position(line, end))


def symbol_at(ix: Index, file: str, line: int, col: int) -> tuple[Symbol, object] | None:
    occ = ix.at(file, line, col)
    if occ is None:
        return None
    sym = ix.symbols.get(occ.key)
    return (sym, occ) if sym is not None else None


# ---- completion ------------------------------------------------------------------------------

_CHAIN = re.compile(r"((?:[A-Za-z_]\w*\s*(?:\[[^\[\]]*\])?\s*\^?\s*\.\s*)+)(\w*)$")
_ENUM_PREFIX = re.compile(r"([A-Za-z_]\w*)#(\w*)$")


def scope_symbols(ix: Index, file: str, line: int) -> list[Symbol]:
    """Every variable visible at `line`: the POU's or method's own, its FB's (through the bases),
    then the globals."""
    out: list[Symbol] = []
    seen: set[str] = set()
    scope = ix.scope_at(file, line)
    if scope is not None:
        pous = [scope.pou] + (ix.lineage(scope.owner.key) if scope.owner is not None else ix.lineage(scope.pou.key)[1:])
        for pou in pous:
            for var in pou.variables.values():
                if var.key in seen:
                    continue
                sym = ix.symbols.get((VAR, pou.key, var.key))
                if sym is None:
                    for base in ix.lineage(pou.key):
                        sym = ix.symbols.get((VAR, base.key, var.key))
                        if sym is not None:
                            break
                if sym is not None:
                    seen.add(var.key)
                    out.append(sym)
    for sym in ix.symbols.values():
        if sym.key[0] == GLOBAL and sym.key[1] not in seen:
            out.append(sym)
    return out


def resolve_chain(ix: Index, file: str, line: int, chain: str) -> t.Type | None:
    """The type of `a.b[i].c` (the text before a `.` being completed), from the variables in
    scope at `line`."""
    parts = [p.strip() for p in chain.split(".")]
    scope = ix.scope_at(file, line)
    ty: t.Type | None = None
    for i, raw in enumerate(parts):
        indexed = "[" in raw
        name = re.sub(r"\[.*\]|\^", "", raw).strip()
        if not name:
            return None
        low = name.lower()
        if i == 0:
            if low in ("this", "super") and scope is not None:
                owner = scope.owner or scope.pou
                if low == "super":
                    owner = ix.pou_by_key.get((owner.base or "").lower())
                ty = t.FBType(owner.name, owner.qualname) if owner is not None else None
            else:
                match = next((s for s in scope_symbols(ix, file, line) if s.name.lower() == low), None)
                if match is not None:
                    ty = match.type
                else:
                    tkey = ix.type_names.get(low)
                    ty = ix.symbols[tkey].type if tkey and tkey in ix.symbols else None
        else:
            member = next((s for s in ix.members(ty, inside=True) if s.name.lower() == low), None)
            if member is None:
                return None
            ty = member.type if member.key[0] != POU else (member.pou.return_type if member.pou else None)
        ty = deref(ty)
        if indexed:
            while isinstance(ty, t.ArrayType):
                ty = deref(ty.element)
    return ty


def _item(sym: Symbol, sort: str = "1") -> lsp.CompletionItem:
    token = _TOKEN_OF_KIND.get(sym.kind, "variable")
    detail = type_text(sym.type) if sym.key[0] in (VAR, GLOBAL, FIELD, PROP) else sym.kind
    return lsp.CompletionItem(label=sym.name, kind=_COMPLETION_KIND.get(token, lsp.CompletionItemKind.Text),
                              detail=detail, sort_text=f"{sort}{sym.name.lower()}")


def call_snippet(name: str, pou) -> tuple[str, str]:
    """(label, snippet) of a call with every input pin named: `TON(IN := , PT := )`."""
    pins = [v.name for v in pou.variables.values() if v.section in ("VAR_INPUT", "VAR_IN_OUT")]
    label = f"{name}({', '.join(f'{p} := ' for p in pins)})".replace(":= ,", ":= ,").replace(" := )", " := )")
    body = ", ".join(f"{p} := ${{{i + 1}}}" for i, p in enumerate(pins))
    return label, f"{name}({body})$0"


def completion(ix: Index, file: str, line: int, col: int, line_text: str) -> list[lsp.CompletionItem]:
    before = line_text[:col]
    m = _ENUM_PREFIX.search(before)
    if m:
        tkey = ix.type_names.get(m.group(1).lower())
        tsym = ix.symbols.get(tkey) if tkey else None
        if tsym is not None and isinstance(tsym.type, t.EnumType):
            return [_item(ix.symbols[(ENUM, tkey[1], name.lower())])
                    for name, _ in tsym.type.members if (ENUM, tkey[1], name.lower()) in ix.symbols]
        return []
    m = _CHAIN.search(before)
    if m:
        ty = resolve_chain(ix, file, line, m.group(1).rstrip().rstrip("."))
        scope = ix.scope_at(file, line)
        own = scope.owner or scope.pou if scope is not None else None
        inside = own is not None and isinstance(deref(ty), t.FBType) and deref(ty).qualname.lower() in \
            {p.key for p in ix.lineage(own.key)}
        items = []
        for sym in ix.members(ty, inside=inside):
            items.append(_item(sym))
            if sym.key[0] == POU and sym.pou is not None and sym.pou.kind == "METHOD":
                label, snippet = call_snippet(sym.name, sym.pou)
                items.append(lsp.CompletionItem(label=label, kind=lsp.CompletionItemKind.Snippet, detail=signature(sym.pou),
                                                insert_text=snippet, insert_text_format=lsp.InsertTextFormat.Snippet,
                                                filter_text=sym.name, sort_text=f"2{sym.name.lower()}"))
        return items
    word = re.search(r"[A-Za-z_]\w*$", before)
    prefix = word.group(0).lower() if word else ""
    items: list[lsp.CompletionItem] = []
    for sym in scope_symbols(ix, file, line):
        if not sym.name.lower().startswith(prefix):
            continue
        items.append(_item(sym, "0" if sym.key[0] == VAR else "1"))
        tsym = ix.type_symbol(sym.type)
        if tsym is not None and tsym.pou is not None and tsym.pou.kind == "FUNCTION_BLOCK" \
                and not isinstance(sym.type, t.ArrayType):
            label, snippet = call_snippet(sym.name, tsym.pou)
            items.append(lsp.CompletionItem(label=label, kind=lsp.CompletionItemKind.Snippet,
                                            detail=signature(tsym.pou), insert_text=snippet,
                                            insert_text_format=lsp.InsertTextFormat.Snippet,
                                            filter_text=sym.name, sort_text=f"0{sym.name.lower()}~"))
    for low, item, stdlib in global_items(ix):
        # the stdlib's ~900 names only once a letter is typed: the list stays short, and the
        # answer is marked incomplete so the editor asks again as the word grows
        if low.startswith(prefix) and (prefix or not stdlib):
            items.append(item)
    return items


def global_items(ix: Index) -> list[tuple[str, lsp.CompletionItem, bool]]:
    """The POUs, types and keywords offered everywhere: (lower-case name, item, from the
    stdlib), built once per index."""
    cached = ix.cache.get("global_items")
    if cached is not None:
        return cached
    out: list[tuple[str, lsp.CompletionItem, bool]] = []
    for sym in ix.symbols.values():
        if sym.key[0] == POU and sym.pou is not None and sym.pou.kind != "METHOD":
            out.append((sym.name.lower(), _item(sym, "2"), sym.stdlib))
            if sym.pou.kind == "FUNCTION":
                label, snippet = call_snippet(sym.name, sym.pou)
                out.append((sym.name.lower(), lsp.CompletionItem(
                    label=label, kind=lsp.CompletionItemKind.Snippet, detail=signature(sym.pou), insert_text=snippet,
                    insert_text_format=lsp.InsertTextFormat.Snippet, filter_text=sym.name,
                    sort_text=f"2{sym.name.lower()}~"), sym.stdlib))
        elif sym.key[0] == TYPE:
            out.append((sym.name.lower(), _item(sym, "2"), sym.stdlib))
    for word in KEYWORDS:
        out.append((word.lower(), lsp.CompletionItem(label=word, kind=lsp.CompletionItemKind.Keyword,
                                                     sort_text=f"3{word.lower()}"), False))
    ix.cache["global_items"] = out
    return out


# ---- signature help --------------------------------------------------------------------------

_CALLEE = re.compile(r"((?:[A-Za-z_]\w*\s*(?:\[[^\[\]]*\])?\s*\.\s*)*)([A-Za-z_]\w*)\s*$")


def open_call(text: str, offset: int) -> tuple[int, int] | None:
    """(offset of the unclosed `(` before `offset`, offset where its argument list starts)."""
    depth = 0
    i = offset - 1
    limit = max(0, offset - 4000)
    while i >= limit:
        ch = text[i]
        if ch == ")":
            depth += 1
        elif ch == "(":
            if depth == 0:
                if i + 1 < len(text) and text[i + 1] == "*":   # a comment opener
                    i -= 1
                    continue
                return i, i + 1
            depth -= 1
        elif ch == ";":
            return None
        i -= 1
    return None


def callee_pou(ix: Index, file: str, line: int, before_paren: str):
    m = _CALLEE.search(before_paren)
    if not m:
        return None
    chain, name = m.group(1).rstrip().rstrip("."), m.group(2)
    low = name.lower()
    if chain:
        ty = resolve_chain(ix, file, line, chain)
        member = next((s for s in ix.members(ty, inside=True) if s.name.lower() == low), None)
        return member.pou if member is not None and member.key[0] == POU else None
    var = next((s for s in scope_symbols(ix, file, line) if s.name.lower() == low), None)
    if var is not None:
        tsym = ix.type_symbol(var.type)
        return tsym.pou if tsym is not None else None
    scope = ix.scope_at(file, line)
    if scope is not None:
        for pou in ix.lineage((scope.owner or scope.pou).key):
            if low in pou.methods:
                return pou.methods[low]
    key = ix.type_names.get(low)
    return ix.pou_by_key.get(key[1]) if key and key[0] == POU else None


def signature_help(ix: Index, file: str, line: int, text: str, offset: int) -> lsp.SignatureHelp | None:
    found = open_call(text, offset)
    if found is None:
        return None
    paren, start = found
    pou = callee_pou(ix, file, line, text[max(0, paren - 200):paren])
    if pou is None:
        return None
    params = [v for v in pou.variables.values() if v.section in ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT")]
    labels = [f"{v.name} {'=>' if v.section == 'VAR_OUTPUT' else ':='} {type_text(v.type)}" for v in params]
    label = f"{pou.name}({', '.join(labels)})"
    if pou.return_type is not None and not isinstance(pou.return_type, t.VoidType):
        label += f" : {type_text(pou.return_type)}"
    args = text[start:offset]
    depth = 0
    commas = 0
    current = 0
    for i, ch in enumerate(args):
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif ch == "," and depth == 0:
            commas += 1
            current = i + 1
    # the argument under the cursor, whole (the cursor may stand inside its pin name)
    segment = args[current:] + _rest_of_argument(text, offset)
    m = re.match(r"\s*(?:NOT\s+)?([A-Za-z_]\w*)\s*(?::=|=>)", segment, re.I)
    active = commas
    if m:
        names = [v.key for v in params]
        key = pou.aliases.get(m.group(1).lower(), m.group(1).lower())
        if key in names:
            active = names.index(key)
    offsets = []
    pos = len(pou.name) + 1
    for lab in labels:
        offsets.append((pos, pos + len(lab)))
        pos += len(lab) + 2
    sig = lsp.SignatureInformation(label=label, documentation=signature(pou),
                                   parameters=[lsp.ParameterInformation(label=o) for o in offsets])
    return lsp.SignatureHelp(signatures=[sig], active_signature=0,
                             active_parameter=min(active, max(len(params) - 1, 0)))


def _rest_of_argument(text: str, offset: int) -> str:
    depth = 0
    for i in range(offset, min(len(text), offset + 400)):
        ch = text[i]
        if ch in "([":
            depth += 1
        elif ch in ")]":
            if depth == 0:
                return text[offset:i]
            depth -= 1
        elif (ch == "," or ch == ";") and depth == 0:
            return text[offset:i]
    return text[offset:offset + 400]


def implementations(ix: Index, sym: Symbol) -> list[Symbol]:
    """The FBs implementing an interface, or their METHOD/PROPERTY for an interface's one
    (through EXTENDS of the FB and of the interface)."""
    if sym.key[0] == POU and sym.pou is not None and sym.pou.kind == "INTERFACE":
        itf, member = sym.pou.key, None
    elif sym.key[0] == POU and sym.pou is not None and sym.pou.kind == "METHOD":
        itf, member = sym.pou.owner, sym.pou.key.rsplit(".", 1)[-1]
    elif sym.key[0] == PROP:
        itf, member = sym.key[1], sym.key[2]
    else:
        return []
    owner = ix.pou_by_key.get(itf)
    if owner is None or owner.kind != "INTERFACE":
        return []
    out: list[Symbol] = []
    for pou in ix.pou_by_key.values():
        if pou.kind != "FUNCTION_BLOCK" or itf not in {p.key for p in ix.lineage(pou.key)[1:]}:
            continue
        if member is None:
            target = ix.symbols.get((POU, pou.key))
        elif member in pou.methods:
            target = ix.symbols.get((POU, pou.methods[member].key))
        else:
            target = ix.symbols.get((PROP, pou.key, member)) if member in pou.properties else None
        if target is not None:
            out.append(target)
    return out


# ---- rename ----------------------------------------------------------------------------------


def rename_problem(ix: Index, sym: Symbol, new_name: str) -> str | None:
    """Why `sym` cannot be renamed to `new_name` (None if it can)."""
    if sym.stdlib:
        return f"'{sym.name}' is declared in the stvm standard library: it cannot be renamed"
    if not IDENT.match(new_name) or "__" in new_name:
        return f"'{new_name}' is not an ST identifier"
    low = new_name.lower()
    if low in _RESERVED:
        return f"'{new_name}' is a keyword"
    if low == sym.name.lower():
        return None
    kind = sym.key[0]
    taken: list[str] = []
    if kind == VAR:
        pou = ix.pou_by_key.get(sym.key[1])
        scopes = [pou] if pou is not None else []
        if pou is not None and pou.owner:
            scopes += ix.lineage(pou.owner)
        elif pou is not None:
            scopes += ix.lineage(pou.key)[1:]
            # a derived FB's own variables clash with an inherited one
            for other in ix.pou_by_key.values():
                if other.kind == "FUNCTION_BLOCK" and pou.key in {p.key for p in ix.lineage(other.key)[1:]}:
                    scopes.append(other)
        for p in scopes:
            if low in p.variables or low in p.methods or low in p.properties:
                taken.append(p.name)
    elif kind == GLOBAL:
        if (GLOBAL, low) in ix.symbols or low in ix.type_names:
            taken.append("the global names")
    elif kind in (POU, TYPE):
        pou = sym.pou
        if pou is not None and pou.kind == "METHOD":
            for p in ix.lineage(pou.owner):
                if low in p.methods or low in p.variables or low in p.properties:
                    taken.append(p.name)
        elif low in ix.type_names or (GLOBAL, low) in ix.symbols:
            taken.append("the project's POUs, types and globals")
    elif kind == PROP:
        for p in ix.lineage(sym.key[1]):
            if low in p.methods or low in p.variables or low in p.properties:
                taken.append(p.name)
    elif kind in (FIELD, ENUM):
        if (kind, sym.key[1], low) in ix.symbols:
            taken.append(sym.container)
    if taken:
        return f"'{new_name}' is already declared in {taken[0]}"
    return None


def rename_family(ix: Index, sym: Symbol) -> list[Symbol]:
    """The symbols one rename changes together. An interface's METHOD or PROPERTY and its
    implementation in every FB that IMPLEMENTS the interface (directly, through a base FB or
    an interface it extends) are one name: renaming any of them renames all, else the FBs would
    no longer implement the interface (E068). Anything else is renamed alone."""
    members: list[Symbol] = []
    if sym.key[0] == POU and sym.pou is not None and sym.pou.kind == "METHOD":
        owner, name = ix.pou_by_key.get(sym.pou.owner), sym.pou.key.rsplit(".", 1)[-1]
    elif sym.key[0] == PROP:
        owner, name = ix.pou_by_key.get(sym.key[1]), sym.key[2]
    else:
        return [sym]
    if owner is None:
        return [sym]
    for pou in ix.lineage(owner.key):   # the owner itself if it is an interface, else its interfaces
        if pou.kind != "INTERFACE":
            continue
        if sym.key[0] == PROP:
            member = ix.symbols.get((PROP, pou.key, name)) if name in pou.properties else None
        else:
            member = ix.symbols.get((POU, pou.methods[name].key)) if name in pou.methods else None
        if member is not None:
            members.append(member)
    family = {sym.key: sym}
    for member in members:
        family.setdefault(member.key, member)
        for impl in implementations(ix, member):
            family.setdefault(impl.key, impl)
    return list(family.values())


def rename_all(ix: Index, sym: Symbol, new_name: str) -> dict[str, list[tuple[int, int, int]]] | str:
    """The edits that rename `sym` (and its family, `rename_family`) to `new_name` per file, or
    why it cannot be renamed (a clash in any FB of the family, the stdlib, a bad name)."""
    family = rename_family(ix, sym)
    for member in family:
        problem = rename_problem(ix, member, new_name)
        if problem:
            return problem
    out: dict[str, list[tuple[int, int, int]]] = {}
    for member in family:
        edits = rename_edits(ix, member)
        if isinstance(edits, str):
            return edits
        for file, spots in edits.items():
            have = out.setdefault(file, [])
            have += [spot for spot in spots if spot not in have]
    return out


def rename_edits(ix: Index, sym: Symbol) -> dict[str, list[tuple[int, int, int]]] | str:
    """(line, col, end) of every occurrence per file, or why one cannot be edited (its text is
    not the name: an XML entity, a macro)."""
    out: dict[str, list[tuple[int, int, int]]] = {}
    split: dict[str, list[str]] = {}
    for file, occ in ix.references(sym.key):
        lines = split.get(file)
        if lines is None:
            lines = split[file] = (ix.originals.get(file) or ix.texts.get(file, "")).splitlines()
        here = lines[occ.line][occ.col:occ.end] if occ.line < len(lines) else ""
        if here.lower() != sym.name.lower():
            return f"the name at {file}:{occ.line + 1}:{occ.col + 1} is not spelled '{sym.name}' in the source"
        out.setdefault(file, []).append((occ.line, occ.col, occ.end))
    return out


# ---- symbols, tokens, folds ------------------------------------------------------------------


def document_symbols(ix: Index, file: str) -> list[lsp.DocumentSymbol]:
    out: list[lsp.DocumentSymbol] = []
    by_container: dict[tuple, list[lsp.DocumentSymbol]] = {}
    own = [s for s in ix.symbols.values() if s.file == file and s.line >= 0]
    own.sort(key=lambda s: (s.line, s.col))
    ends = {sc.key: sc.end for sc in ix.scopes.get(file, ())}

    def make(sym: Symbol) -> lsp.DocumentSymbol:
        end_line = ends.get(sym.key[1], sym.line) if sym.key[0] == POU else sym.line
        full = lsp.Range(lsp.Position(sym.line, 0), lsp.Position(end_line, 10_000 if end_line > sym.line else sym.end_col))
        kind = _SYMBOL_KIND.get(sym.kind, lsp.SymbolKind.Variable)
        detail = type_text(sym.type) if sym.key[0] in (VAR, GLOBAL, FIELD, PROP) else sym.kind
        return lsp.DocumentSymbol(name=sym.name, kind=kind, range=full, selection_range=rng(sym.line, sym.col, sym.end_col),
                                  detail=detail, children=[])

    nodes = {}
    for sym in own:
        nodes[sym.key] = make(sym)
    for sym in own:
        node = nodes[sym.key]
        parent = None
        k = sym.key
        if k[0] == VAR:
            scope = ix.pou_by_key.get(k[1])
            if scope is not None and scope.key.rpartition(".")[2].startswith(("__get_", "__set_")):
                parent = nodes.get((PROP, scope.owner, scope.key.rpartition(".")[2][6:]))
            else:
                parent = nodes.get((POU, k[1]))
        elif k[0] == POU and sym.pou is not None and sym.pou.kind == "METHOD":
            parent = nodes.get((POU, sym.pou.owner))
        elif k[0] == PROP:
            parent = nodes.get((POU, k[1]))
        elif k[0] in (FIELD, ENUM):
            parent = nodes.get((TYPE, k[1]))
        if parent is not None:
            parent.children.append(node)
        else:
            out.append(node)
    del by_container
    return out


def workspace_symbols(indexes: list[Index], query: str, uri_of) -> list[lsp.WorkspaceSymbol]:
    q = query.lower()
    out: list[lsp.WorkspaceSymbol] = []
    seen: set[tuple] = set()
    for ix in indexes:
        for sym in ix.symbols.values():
            if sym.stdlib or sym.key[0] == VAR or sym.line < 0 or sym.file not in ix.files:
                continue
            if q and q not in sym.name.lower():
                continue
            ident = (sym.file, sym.line, sym.col)
            if ident in seen:
                continue
            seen.add(ident)
            out.append(lsp.WorkspaceSymbol(name=sym.name, kind=_SYMBOL_KIND.get(sym.kind, lsp.SymbolKind.Variable),
                                           location=lsp.Location(uri_of(sym.file), rng(sym.line, sym.col, sym.end_col)),
                                           container_name=sym.container or None))
            if len(out) >= 500:
                return out
    return out


def semantic_tokens(ix: Index, file: str) -> list[int]:
    data: list[int] = []
    prev_line = prev_col = 0
    last = (-1, -1)
    for occ in ix.by_file.get(file, ()):
        if (occ.line, occ.col) < last or (occ.line == last[0] and occ.col < last[1]):
            continue
        sym = ix.symbols.get(occ.key)
        if sym is None:
            continue
        token = TOKEN_TYPES.index(_TOKEN_OF_KIND.get(sym.kind, "variable"))
        mods = (1 if occ.decl else 0) | (2 if sym.constant else 0) | (4 if sym.stdlib else 0)
        dl = occ.line - prev_line
        dc = occ.col - prev_col if dl == 0 else occ.col
        data += [dl, dc, occ.end - occ.col, token, mods]
        prev_line, prev_col = occ.line, occ.col
        last = (occ.line, occ.end)
    return data


def folding_ranges(ix: Index, file: str) -> list[lsp.FoldingRange]:
    return [lsp.FoldingRange(start_line=a, end_line=b) for a, b in ix.folds.get(file, ())]
