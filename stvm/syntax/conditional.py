"""Conditional compilation (CODESYS / TwinCAT conditional pragmas), evaluated before parsing:

    {define X}  {define X 'value'}  {undefine X}
    {IF defined(X) AND NOT hasvalue(Y, '2')} … {ELSIF defined(Z)} … {ELSE} … {END_IF}

The code of the branches not taken and every directive are blanked out (each character but line
breaks becomes a space), so the kept code keeps its exact line and column. Defines come from the
settings (`stvm.toml` `[project] defines`, `--define NAME[=VALUE]`) and from `{define}` pragmas,
which hold from where they stand to the end of their file (CODESYS: to the end of the object; a
TwinCAT file is one object). Define names are case-sensitive, as CODESYS's; the directive words
(`IF`, `define`, `defined`, `AND` …) are not. Operators: `defined(NAME)`, `hasvalue(NAME,
'text')`, `NOT`, `AND`, `OR`, parentheses. The operators that ask the compiler about the program
(`defined(variable: x)`, `defined(pou: P)`, `defined(type: T)`, `hasattribute`, `hastype`,
`project_defined` …) are errors: stvm decides the branches before it knows the program.
Directives inside comments and string literals are not directives (the lexer's own rules).
"""

from __future__ import annotations

import re

from stvm.diagnostics import Diagnostic
from stvm.source import Span

# is there anything to do at all (a cheap test: most files have no directive)
_ANY_DIRECTIVE = re.compile(r"\{\s*(?:if|elsif|else|end_if|define|undefine)\b", re.I)

# what the lexer reads as one token that may hold a `{`: comments, strings, and pragmas themselves
# (st.lark COMMENT_ML, COMMENT_C, COMMENT_LINE, STRING_LITERAL, WSTRING_LITERAL, PRAGMA)
_SCAN = re.compile(r"""\(\*[\s\S]*?\*\)|/\*[\s\S]*?\*/|//[^\n]*|'(?:[^'$\n]|\$[\s\S])*'|"(?:[^"$\n]|\$[\s\S])*"|"""
                   r"""\{[^}]*\}""")

_DIRECTIVE = re.compile(r"\s*(if|elsif|else|end_if|define|undefine)\b(.*)\Z", re.I | re.S)
_DEFINE = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:'([^']*)')?\s*\Z", re.S)
_COND_TOKEN = re.compile(r"\s*(?:([A-Za-z_][A-Za-z0-9_]*)|('[^']*')|(\(|\)|,|:))")

_QUERIES = ("variable", "pou", "type", "task", "resource", "library")
_UNSUPPORTED = ("hasattribute", "hastype", "project_defined", "hasconstantvalue", "hasconstanttype")


def _blank(text: str) -> str:
    return re.sub(r"[^\r\n]", " ", text)


def _position(text: str, offset: int, line_starts: list[int]) -> tuple[int, int]:
    import bisect
    line = bisect.bisect_right(line_starts, offset)
    return line, offset - line_starts[line - 1] + 1


class _ConditionError(Exception):
    pass


class _Condition:
    """Recursive descent over the tokens of one `{IF …}` condition: OR < AND < NOT < primary."""

    def __init__(self, text: str, defines: dict[str, str]):
        self.tokens: list[str] = []
        self.defines = defines
        pos = 0
        text = text.rstrip()
        while pos < len(text):
            m = _COND_TOKEN.match(text, pos)
            if m is None or m.end() == pos:
                raise _ConditionError(f"unexpected {text[pos:].strip()[:20]!r} in the condition")
            self.tokens.append(m.group(0).strip())
            pos = m.end()
        self.i = 0

    def value(self) -> bool:
        if not self.tokens:
            raise _ConditionError("an empty condition")
        result = self._or()
        if self.i < len(self.tokens):
            raise _ConditionError(f"unexpected {self.tokens[self.i]!r} in the condition")
        return result

    def _peek(self) -> str:
        return self.tokens[self.i].upper() if self.i < len(self.tokens) else ""

    def _take(self, what: str | None = None) -> str:
        if self.i >= len(self.tokens):
            raise _ConditionError("the condition ends too early" + (f" (expected {what!r})" if what else ""))
        tok = self.tokens[self.i]
        if what is not None and tok.upper() != what:
            raise _ConditionError(f"expected {what!r} in the condition, got {tok!r}")
        self.i += 1
        return tok

    def _or(self) -> bool:
        result = self._and()
        while self._peek() == "OR":
            self._take()
            rhs = self._and()
            result = result or rhs
        return result

    def _and(self) -> bool:
        result = self._not()
        while self._peek() == "AND":
            self._take()
            rhs = self._not()
            result = result and rhs
        return result

    def _not(self) -> bool:
        if self._peek() == "NOT":
            self._take()
            return not self._not()
        return self._primary()

    def _name(self) -> str:
        tok = self._take()
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", tok):
            raise _ConditionError(f"expected a name in the condition, got {tok!r}")
        return tok

    def _primary(self) -> bool:
        word = self._peek()
        if word == "(":
            self._take()
            result = self._or()
            self._take(")")
            return result
        if word in ("TRUE", "FALSE"):
            self._take()
            return word == "TRUE"
        if word == "DEFINED":
            self._take()
            self._take("(")
            name = self._name()
            if self._peek() == ":":
                raise _ConditionError(f"`defined({name}: …)` asks about the program, which stvm does not "
                                      f"know before parsing: use a define (`{{define X}}`, --define X)")
            self._take(")")
            return name in self.defines
        if word == "HASVALUE":
            self._take()
            self._take("(")
            name = self._name()
            self._take(",")
            text = self._take()
            if not (text.startswith("'") and text.endswith("'")):
                raise _ConditionError(f"hasvalue needs a quoted value, got {text!r}")
            self._take(")")
            return self.defines.get(name) == text[1:-1]
        if word.lower() in _UNSUPPORTED:
            raise _ConditionError(f"{self.tokens[self.i]} asks about the program, which stvm does not know "
                                  f"before parsing (supported: defined(NAME), hasvalue(NAME, '…'), NOT, AND, OR)")
        if not word:
            raise _ConditionError("the condition ends too early")
        raise _ConditionError(f"unknown operand {self.tokens[self.i]!r} (supported: defined(NAME), "
                              f"hasvalue(NAME, '…'), NOT, AND, OR)")


def preprocess(text: str, file: str, defines: tuple[tuple[str, str], ...] = ()) -> tuple[str, list[Diagnostic]]:
    """The text with the branches not taken and the directives blanked out, and the errors
    (an unbalanced {IF}/{END_IF}, a malformed condition) as `FILE:LINE:COL: error:`."""
    if "{" not in text or _ANY_DIRECTIVE.search(text) is None:
        return text, []
    line_starts = [0] + [m.end() for m in re.finditer(r"\n", text)]
    diagnostics: list[Diagnostic] = []
    active = dict(defines)
    # one entry per open {IF}: (taken so far, this branch kept, parent kept, {IF} offset, seen {ELSE})
    stack: list[list] = []
    kept = True
    out: list[str] = []
    last = 0

    def span(start: int, end: int) -> Span:
        line, col = _position(text, start, line_starts)
        end_line, end_col = _position(text, max(start + 1, end), line_starts)   # end: exclusive
        return Span(file, line, col, end_line, end_col)

    def error(message: str, start: int, end: int) -> None:
        diagnostics.append(Diagnostic.error(message, span(start, end), "E005"))

    def condition(body: str, start: int, end: int) -> bool:
        try:
            return _Condition(body, active).value()
        except _ConditionError as exc:
            error(f"conditional compilation: {exc}", start, end)
            return False

    for m in _SCAN.finditer(text):
        token = m.group(0)
        if token[0] != "{":
            continue
        d = _DIRECTIVE.match(token, 1, len(token) - 1)
        if d is None:
            continue
        word, body = d.group(1).upper(), d.group(2)
        start, end = m.start(), m.end()
        # what stands before the directive: kept as it is, or blanked when in a branch not taken
        out.append(text[last:start] if kept else _blank(text[last:start]))
        out.append(_blank(token))
        last = end
        if word == "IF":
            parent = kept
            taken = parent and condition(body, start, end)
            stack.append([taken, taken, parent, start, False])
            kept = taken
        elif word in ("ELSIF", "ELSE", "END_IF"):
            if not stack:
                error(f"{{{word}}} without an open {{IF}}", start, end)
                continue
            frame = stack[-1]
            if word == "END_IF":
                if body.strip():
                    error("{END_IF} takes nothing after it", start, end)
                stack.pop()
                kept = frame[2]
                continue
            if frame[4]:
                error(f"{{{word}}} after the {{ELSE}} of this {{IF}}", start, end)
                kept = False
                continue
            if word == "ELSE":
                if body.strip():
                    error("{ELSE} takes no condition (an alternative with one is {ELSIF …})", start, end)
                frame[4] = True
                kept = frame[2] and not frame[0]
            else:
                kept = frame[2] and not frame[0] and condition(body, start, end)
            frame[0] = frame[0] or kept
        elif kept:   # define / undefine, only where the code is kept
            dm = _DEFINE.match(body)
            if dm is None:
                error(f"{{{d.group(1)}}} needs a name" + (" and an optional 'value'" if word == "DEFINE" else ""),
                      start, end)
            elif word == "DEFINE":
                active[dm.group(1)] = dm.group(2) or ""
            else:
                active.pop(dm.group(1), None)
    out.append(text[last:] if kept else _blank(text[last:]))
    for frame in stack:
        error("{IF} without its {END_IF}", frame[3], frame[3] + 3)
    return "".join(out), diagnostics
