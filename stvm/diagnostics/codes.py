"""The one registry of diagnostic codes of the parser, the checker and the loader.

Every `Diagnostic` those stages make carries one of these codes: `E…` for an error (the
program is not run), `W…` for a warning of the checker (it runs, and the message says what
stvm did). Lint findings have their own `SA…` codes (`stvm/lint/rules`). A code is stable: a
message may be reworded, its code stays; a retired code is never given to another mistake.

`stvm check --explain E031` prints an entry; `docs/error_codes.md` is generated from this
module (`python tools/gen_error_docs.py`, checked by `tests/diagnostics/test_error_codes.py`,
which also checks every example: `wrong` must give the code, `right` must check clean).

Numbering: E001–E009 reading and parsing, E010–E029 declarations and types, E030–E032
configuration, E033–E056 bodies (names, expressions, statements, calls, assignments),
E057–E073 namespaces and object-oriented features, E080–E089 loading a project.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass


@dataclass(frozen=True)
class ErrorCode:
    code: str
    title: str
    explanation: str
    wrong: str             # ST that gets this diagnostic (or a description, when `checked` is False)
    right: str             # the same intent written so that it checks clean
    source: str = ""       # the IEC 61131-3 clause or vendor manual the rule comes from
    settings: tuple[str, ...] = ()   # `--sysmac KEY=VALUE` overrides the example needs
    checked: bool = True   # the examples are ST a test checks (False: a file-level condition)

    @property
    def severity(self) -> str:
        return "warning" if self.code.startswith("W") else "error"


_PROGRAM = "PROGRAM Main\nVAR\n{decls}END_VAR\n{body}END_PROGRAM\n"


def _prog(decls: str, body: str) -> str:
    """A one-PROGRAM example: `decls` one declaration a line, `body` one statement a line."""
    indent = lambda text: "".join(f"    {line}\n" for line in text.splitlines())   # noqa: E731
    return _PROGRAM.format(decls=indent(decls), body=indent(body))


_CODES = [
    # ---------------------------------------------------------------- reading and parsing
    ErrorCode(
        "E001", "syntax error",
        "The text does not follow the Structured Text grammar at this point: a keyword, an operator "
        "or a `;` is missing or misplaced. The message names the token found and the tokens that "
        "could stand there. When the only thing missing is a `;` before the next statement, stvm "
        "reports it and goes on, so several missing `;` are reported at once.",
        _prog("x : INT;", "x := 1\nx := 2;"), _prog("x : INT;", "x := 1;\nx := 2;"),
        "IEC 61131-3 ed. 3, 7.3 (Structured Text: every statement ends with ';')"),
    ErrorCode(
        "E002", "unterminated string literal",
        "A quote opens a STRING ('…') or WSTRING (\"…\") literal that the line does not close. A "
        "quote inside a STRING literal is written `$'`, inside a WSTRING `$\"`.",
        _prog("s : STRING;", "s := 'it$'s;"), _prog("s : STRING;", "s := 'it$'s';"),
        "IEC 61131-3 ed. 3, 6.3.3 (character string literals, the `$` escapes)"),
    ErrorCode(
        "E003", "nesting too deep to parse",
        "Expressions or statements are nested more deeply than stvm's parser and checker handle "
        "(generated code with thousands of nested parentheses or IFs). Split the expression into "
        "intermediate variables or the statements into smaller POUs.",
        "x := ((((((((… 10,000 parentheses …))))))));", "t1 := a + b; t2 := t1 * c; x := t2 - d;",
        "stvm limit (reliability.md)", checked=False),
    ErrorCode(
        "E004", "nesting too deep to compile",
        "The program was checked, but the Python code stvm generates for it nests blocks or "
        "parentheses beyond what Python's compiler accepts (about 20 nested blocks, 200 nested "
        "parentheses). The message points at the ST statement; split it into smaller statements "
        "or POUs.",
        "IF a THEN IF b THEN … (25 nested IFs) … END_IF; END_IF;",
        "the inner IFs moved into a FUNCTION called from the outer ones",
        "stvm limit of its code generator", checked=False),
    ErrorCode(
        "E005", "conditional compilation directive",
        "A `{IF …}`, `{ELSIF …}`, `{ELSE}`, `{END_IF}`, `{define …}` or `{undefine …}` pragma is "
        "malformed: an `{END_IF}` without `{IF}`, an `{IF}` never closed, an `{ELSIF}` after "
        "`{ELSE}`, a condition that is not `defined(NAME)` combined with AND, OR, NOT and "
        "parentheses, or a `{define}` without a name.",
        _prog("x : INT;", "{IF defined(SIM)}\nx := 1;"),
        _prog("x : INT;", "{IF defined(SIM)}\nx := 1;\n{END_IF}"),
        "CODESYS / Beckhoff TwinCAT 3 help, 'Conditional pragmas'"),
    ErrorCode(
        "E006", "file cannot be read as source text",
        "The file is not text in the project's encoding (UTF-8 unless stvm.toml says `encoding`), "
        "is binary (it holds NUL bytes), is larger than stvm reads, or cannot be opened. The "
        "location is the first byte that could not be decoded.",
        "a .st file saved as UTF-16, or an .exe renamed to .st",
        "the file saved as UTF-8 (or `encoding = \"cp1252\"` in stvm.toml)",
        "stvm's reader (docs/security.md: input limits)", checked=False),
    ErrorCode(
        "E007", "vendor XML source not usable",
        "A TwinCAT (.TcPOU, .TcDUT, .TcGVL, .TcIO) or PLCopen XML file is well-formed XML but not "
        "one stvm can turn into ST: the root element is not the expected one, a POU has no "
        "<Declaration>, a body is not Structured Text (<ST>), a data type has no <baseType>, and so "
        "on. The message names the element.",
        "<TcPlcObject><POU Name=\"P\"><Implementation><LD/></Implementation></POU></TcPlcObject>",
        "the same POU with its body in <Implementation><ST>…</ST></Implementation>",
        "Beckhoff TwinCAT 3 PLC file formats; PLCopen TC6 XML", checked=False),
    ErrorCode(
        "E008", "malformed literal",
        "A numeric, duration, date or string literal cannot be read: digits outside the base "
        "(`8#9`), a doubled or trailing `_` separator, a REAL beyond LREAL's range, a duration or "
        "date field out of range, an unknown `$` escape in a string, or more digits than stvm "
        "reads.",
        _prog("x : INT;", "x := 1__0;"), _prog("x : INT;", "x := 1_0;"),
        "IEC 61131-3 ed. 3, 6.3 (literals)"),
    ErrorCode(
        "E009", "construct of another dialect",
        "The construct is valid in another dialect than the one the project is checked with: "
        "`S=`/`R=` assignments, `PERSISTENT`, an output pin left empty (`Q =>`) or a comma before "
        "`)` are CODESYS/TwinCAT syntax; under Sysmac with `double_quote_strings=error`, "
        "double-quoted text is refused. Either write it the portable way or choose the dialect "
        "with `--dialect` or `dialect = …` in stvm.toml.",
        _prog("x : BOOL;\nc : BOOL;", "x S= c;"), _prog("x : BOOL;\nc : BOOL;", "IF c THEN\n    x := TRUE;\nEND_IF;"),
        "CODESYS help, 'Assignment operators S= and R='; docs/dialects.md"),
    # ---------------------------------------------------------------- declarations and types
    ErrorCode(
        "E010", "duplicate declaration",
        "A name is declared twice where names must be unique: two POUs or types of the same name, "
        "two variables of one POU, a variable and a method of one FB, a variable that repeats one "
        "of the base FB, two enumerators, two fields of a STRUCT, two tasks or program "
        "instances, or a variable named like its own POU.",
        _prog("x : INT;\nx : REAL;", "x := 1;"), _prog("x : INT;\ny : REAL;", "x := 1;"),
        "IEC 61131-3 ed. 3, 6.5.2 (variable declaration: a name is declared once in its scope)"),
    ErrorCode(
        "E011", "invalid name",
        "The identifier is a reserved keyword of ST (IF, END_VAR, TIME, …) or breaks the naming "
        "rules of the dialect (for Sysmac: length, characters, a reserved prefix).",
        _prog("end_if : INT;", "end_if := 1;"), _prog("endIfCount : INT;", "endIfCount := 1;"),
        "IEC 61131-3 ed. 3, 6.1.2 (identifiers) and annex C (keywords); Omron Sysmac W501, variable names"),
    ErrorCode(
        "E012", "variable section not allowed here",
        "A VAR_… block stands where its kind is not allowed: VAR_GLOBAL inside a POU, any other "
        "section outside a POU, or VAR_INST outside a method of a FUNCTION_BLOCK.",
        "PROGRAM Main\nVAR_GLOBAL\n    g : INT;\nEND_VAR\nEND_PROGRAM\n",
        "VAR_GLOBAL\n    g : INT;\nEND_VAR\n\nPROGRAM Main\nVAR_EXTERNAL\n    g : INT;\nEND_VAR\nEND_PROGRAM\n",
        "IEC 61131-3 ed. 3, 6.5.2 (variable sections)"),
    ErrorCode(
        "E013", "initial value missing or not allowed",
        "A CONSTANT needs its value where it is declared; a VAR_IN_OUT refers to the caller's "
        "variable and cannot have one.",
        "PROGRAM Main\nVAR CONSTANT\n    N : INT;\nEND_VAR\nEND_PROGRAM\n",
        "PROGRAM Main\nVAR CONSTANT\n    N : INT := 10;\nEND_VAR\nEND_PROGRAM\n",
        "IEC 61131-3 ed. 3, 6.5.6 (CONSTANT), 6.5.2 (VAR_IN_OUT)"),
    ErrorCode(
        "E014", "return type missing or not allowed",
        "A FUNCTION declares the type of its result after its name; a FUNCTION_BLOCK or PROGRAM has "
        "none (it returns results through outputs).",
        "FUNCTION Twice\nVAR_INPUT\n    x : INT;\nEND_VAR\nTwice := 2 * x;\nEND_FUNCTION\n",
        "FUNCTION Twice : INT\nVAR_INPUT\n    x : INT;\nEND_VAR\nTwice := 2 * x;\nEND_FUNCTION\n",
        "IEC 61131-3 ed. 3, 6.6.2 (functions)"),
    ErrorCode(
        "E015", "type defined in terms of itself",
        "A TYPE's definition refers back to the type itself (directly or through other type "
        "names), so it has no size.",
        "TYPE A : B; END_TYPE\nTYPE B : A; END_TYPE\n", "TYPE A : INT; END_TYPE\nTYPE B : A; END_TYPE\n",
        "IEC 61131-3 ed. 3, 6.4.4 (user-defined data types)"),
    ErrorCode(
        "E016", "not an enumerator of the type",
        "A `Type#Name` literal or an enumeration's default names a value the enumeration does not "
        "declare.",
        "TYPE Color : (Red, Green); END_TYPE\n" + _prog("c : Color;", "c := Color#Blue;"),
        "TYPE Color : (Red, Green, Blue); END_TYPE\n" + _prog("c : Color;", "c := Color#Blue;"),
        "IEC 61131-3 ed. 3, 6.4.4.2 (enumerated data types)"),
    ErrorCode(
        "E017", "generic type outside a library",
        "ANY, ANY_NUM, ANY_INT and the other generic types describe the parameters of standard "
        "functions; user POUs declare concrete types.",
        "FUNCTION F : INT\nVAR_INPUT\n    x : ANY_INT;\nEND_VAR\nF := 0;\nEND_FUNCTION\n",
        "FUNCTION F : INT\nVAR_INPUT\n    x : DINT;\nEND_VAR\nF := 0;\nEND_FUNCTION\n",
        "IEC 61131-3 ed. 3, 6.4.3 (generic data types)"),
    ErrorCode(
        "E018", "unknown type",
        "The name after `:` is neither an elementary type nor a TYPE, FUNCTION_BLOCK, INTERFACE or "
        "library type stvm knows (a FUNCTION is not a type), or an enumeration prefix `X#` names "
        "something that is not an enumeration. Also: a UNION member whose type has no byte image.",
        _prog("t : TONN;", ""), _prog("t : TON;", ""),
        "IEC 61131-3 ed. 3, 6.4 (data types)"),
    ErrorCode(
        "E019", "invalid type specification",
        "The type is written with impossible parameters: STRING[n] outside the dialect's sizes, "
        "empty array bounds, a subrange that is empty or outside its base type, ARRAY[*] outside "
        "VAR_IN_OUT, a REFERENCE TO a reference.",
        _prog("a : ARRAY[10..1] OF INT;", ""), _prog("a : ARRAY[1..10] OF INT;", ""),
        "IEC 61131-3 ed. 3, 6.4.4 (arrays, subranges, strings)"),
    ErrorCode(
        "E020", "constant integer expected",
        "An array bound, STRING size or subrange bound must be known when the program is "
        "checked: a literal, a VAR_GLOBAL CONSTANT or an expression of those.",
        _prog("n : INT := 5;\na : ARRAY[1..n] OF INT;", ""),
        "VAR_GLOBAL CONSTANT\n    N : INT := 5;\nEND_VAR\n" + _prog("a : ARRAY[1..N] OF INT;", ""),
        "IEC 61131-3 ed. 3, 6.4.4.5 (arrays)"),
    ErrorCode(
        "E021", "enumerator needs its type",
        "A bare enumerator name is ambiguous when several enumerations declare it, or when the "
        "context gives no enumeration type; write it `Type#Name`.",
        "TYPE A : (Idle, Run); END_TYPE\nTYPE B : (Idle, Stop); END_TYPE\n" + _prog("x : INT;", "x := TO_INT(Idle);"),
        "TYPE A : (Idle, Run); END_TYPE\nTYPE B : (Idle, Stop); END_TYPE\n" + _prog("x : INT;", "x := TO_INT(A#Idle);"),
        "IEC 61131-3 ed. 3, 6.4.4.2 (typed enumerator literals)"),
    ErrorCode(
        "E022", "value out of range of its type",
        "A constant does not fit the type it is given or stored in (`INT#40000`, 300 into a USINT, "
        "a value outside a subrange). stvm never wraps a constant silently.",
        _prog("x : SINT;", "x := 200;"), _prog("x : INT;", "x := 200;"),
        "IEC 61131-3 ed. 3, 6.4.2 (ranges of the elementary types)"),
    ErrorCode(
        "E023", "invalid initial value",
        "The initial value does not suit the variable: not a constant expression, an array "
        "initialiser with more values than elements, a structure initialiser for a non-STRUCT, a "
        "WSTRING literal for a STRING, an initial value on a UNION member.",
        _prog("a : ARRAY[1..2] OF INT := [1, 2, 3];", ""), _prog("a : ARRAY[1..3] OF INT := [1, 2, 3];", ""),
        "IEC 61131-3 ed. 3, 6.5.3 (initial values)"),
    ErrorCode(
        "E024", "invalid member in an initialiser",
        "A structure or FB instance initialiser `(name := value, …)` names a member the type does "
        "not have, sets one twice, or sets an FB variable an instance initialiser may not set.",
        "TYPE P : STRUCT x : INT; END_STRUCT; END_TYPE\n" + _prog("p : P := (z := 1);", ""),
        "TYPE P : STRUCT x : INT; END_STRUCT; END_TYPE\n" + _prog("p : P := (x := 1);", ""),
        "IEC 61131-3 ed. 3, 6.5.3 (structure initialisation)"),
    ErrorCode(
        "E025", "native POU outside the standard library",
        "`{native}` marks the POUs of stvm's own standard library whose body is Python; user code "
        "cannot use it, and a native POU has no ST body.",
        "{native}\nFUNCTION F : INT\nF := 1;\nEND_FUNCTION\n", "FUNCTION F : INT\nF := 1;\nEND_FUNCTION\n",
        "stvm (docs/stdlib.md)"),
    ErrorCode(
        "E026", "type contains itself",
        "A STRUCT or FUNCTION_BLOCK holds an instance of itself (directly or through other "
        "members), so an instance would be infinitely large. Hold a REFERENCE TO or POINTER TO it "
        "instead.",
        "FUNCTION_BLOCK Node\nVAR\n    next : Node;\nEND_VAR\nEND_FUNCTION_BLOCK\n",
        "FUNCTION_BLOCK Node\nVAR\n    next : REF_TO Node;\nEND_VAR\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.4.4 and 6.6.3"),
    ErrorCode(
        "E027", "recursion",
        "A FUNCTION or METHOD calls itself, directly or through others. IEC 61131-3 forbids "
        "recursion; CODESYS and TwinCAT allow recursive methods, and stvm then warns (W002) "
        "instead. Write the recursion as a loop.",
        "FUNCTION Fact : DINT\nVAR_INPUT\n    n : DINT;\nEND_VAR\nIF n <= 1 THEN\n    Fact := 1;\nELSE\n"
        "    Fact := n * Fact(n - 1);\nEND_IF;\nEND_FUNCTION\n",
        "FUNCTION Fact : DINT\nVAR_INPUT\n    n : DINT;\nEND_VAR\nVAR\n    i : DINT;\nEND_VAR\nFact := 1;\n"
        "FOR i := 2 TO n DO\n    Fact := Fact * i;\nEND_FOR;\nEND_FUNCTION\n",
        "IEC 61131-3 ed. 3, 6.6.1 (POUs shall not be recursive)"),
    ErrorCode(
        "E028", "instances nested too deeply",
        "Function block instances hold instances that hold instances … more levels deep than "
        "stvm's limit; the message names the chain.",
        "FB1 holding an FB2 holding an FB3 … 100 levels deep", "a flatter design of fewer levels",
        "stvm limit (docs/reliability.md)", checked=False),
    ErrorCode(
        "E030", "configuration error",
        "The CONFIGURATION is malformed: more than one, a TASK without INTERVAL (event tasks are "
        "not supported) or with one that is not a positive TIME, a PROGRAM instance without "
        "`WITH` a declared task.",
        "PROGRAM Main\nEND_PROGRAM\nCONFIGURATION C\nRESOURCE R ON PLC\nTASK T(PRIORITY := 1);\n"
        "PROGRAM P WITH T : Main;\nEND_RESOURCE\nEND_CONFIGURATION\n",
        "PROGRAM Main\nEND_PROGRAM\nCONFIGURATION C\nRESOURCE R ON PLC\nTASK T(INTERVAL := T#10ms, PRIORITY := 1);\n"
        "PROGRAM P WITH T : Main;\nEND_RESOURCE\nEND_CONFIGURATION\n",
        "IEC 61131-3 ed. 3, 6.8 (configuration elements)"),
    ErrorCode(
        "E031", "not declared",
        "The name is not a variable of the POU, a global the POU can see, an enumerator or a "
        "constant of a library; or it is a POU used where a variable is expected.",
        _prog("x : INT;", "y := 1;"), _prog("x : INT;\ny : INT;", "y := 1;"),
        "IEC 61131-3 ed. 3, 6.5 (every variable is declared)"),
    ErrorCode(
        "E032", "unknown program type",
        "A PROGRAM instance of the CONFIGURATION names a type that is not a PROGRAM of the project.",
        "PROGRAM Main\nEND_PROGRAM\nCONFIGURATION C\nRESOURCE R ON PLC\nTASK T(INTERVAL := T#10ms, PRIORITY := 1);\n"
        "PROGRAM P WITH T : Mian;\nEND_RESOURCE\nEND_CONFIGURATION\n",
        "PROGRAM Main\nEND_PROGRAM\nCONFIGURATION C\nRESOURCE R ON PLC\nTASK T(INTERVAL := T#10ms, PRIORITY := 1);\n"
        "PROGRAM P WITH T : Main;\nEND_RESOURCE\nEND_CONFIGURATION\n",
        "IEC 61131-3 ed. 3, 6.8"),
    # ---------------------------------------------------------------- bodies
    ErrorCode(
        "E033", "VAR_EXTERNAL without its global",
        "A VAR_EXTERNAL declaration must repeat a VAR_GLOBAL of the same name and type.",
        "VAR_GLOBAL\n    g : INT;\nEND_VAR\nPROGRAM Main\nVAR_EXTERNAL\n    g : REAL;\nEND_VAR\nEND_PROGRAM\n",
        "VAR_GLOBAL\n    g : INT;\nEND_VAR\nPROGRAM Main\nVAR_EXTERNAL\n    g : INT;\nEND_VAR\nEND_PROGRAM\n",
        "IEC 61131-3 ed. 3, 6.5.2 (VAR_EXTERNAL)"),
    ErrorCode(
        "E034", "no such member",
        "`a.b`: the STRUCT, FB or interface has no member `b`, the value has no members at all, "
        "`b` is a method that must be called, or `b` is internal to the FB (from outside only its "
        "inputs and outputs are visible).",
        _prog("t : TON;", "t.Done := TRUE;"), _prog("t : TON;\nd : BOOL;", "d := t.Q;"),
        "IEC 61131-3 ed. 3, 6.6.3 (access to FB inputs and outputs)"),
    ErrorCode(
        "E035", "invalid bit access",
        "`x.n` (or `%X`, `%B`, `%W`, `%D` partial access) needs an integer or bit string, and a "
        "bit or part that exists in it.",
        _prog("w : BYTE;\nb : BOOL;", "b := w.8;"), _prog("w : BYTE;\nb : BOOL;", "b := w.7;"),
        "IEC 61131-3 ed. 3, 6.5.4 (partial access of ANY_BIT variables)"),
    ErrorCode(
        "E036", "invalid array index",
        "An index is applied to a value that is not an array, with the wrong number of indices, an "
        "index that is not an integer, or a constant index outside the bounds.",
        _prog("a : ARRAY[1..3] OF INT;", "a[4] := 0;"), _prog("a : ARRAY[1..3] OF INT;", "a[3] := 0;"),
        "IEC 61131-3 ed. 3, 6.5.2 and 7.3.2"),
    ErrorCode(
        "E037", "invalid dereference",
        "`^` dereferences a REF_TO or POINTER TO; it cannot be applied to another value, nor to "
        "NULL.",
        _prog("x : INT;\ny : INT;", "y := x^;"), _prog("x : INT;\nr : REF_TO INT;\ny : INT;", "r := REF(x);\ny := r^;"),
        "IEC 61131-3 ed. 3, 6.4.4.10 (references)"),
    ErrorCode(
        "E038", "unary operator on the wrong type",
        "NOT takes BOOL or a bit string; unary `-` and `+` take a number.",
        _prog("s : STRING;\nb : BOOL;", "b := NOT s;"), _prog("s : STRING;\nb : BOOL;", "b := NOT (s = '');"),
        "IEC 61131-3 ed. 3, 7.3.2 (operators of ST)"),
    ErrorCode(
        "E039", "operator on the wrong types",
        "A binary operator is applied to operands it does not take: arithmetic on BOOL or STRING, "
        "MOD on REAL, AND on numbers, a comparison of unrelated types.",
        _prog("b : BOOL;\nx : INT;", "x := b + 1;"), _prog("b : BOOL;\nx : INT;", "x := BOOL_TO_INT(b) + 1;"),
        "IEC 61131-3 ed. 3, 7.3.2 (operators of ST)"),
    ErrorCode(
        "E040", "statement without effect",
        "An expression stands alone as a statement, or an FB instance is named without "
        "parentheses. A statement assigns (`:=`) or calls (`name(…)`).",
        _prog("t : TON;", "t;"), _prog("t : TON;", "t();"),
        "IEC 61131-3 ed. 3, 7.3.3 (ST statements)"),
    ErrorCode(
        "E041", "condition is not BOOL",
        "The condition of IF, ELSIF, WHILE or REPEAT must be BOOL; an integer is not taken as "
        "true when it is not zero.",
        _prog("n : INT;", "IF n THEN\n    n := 0;\nEND_IF;"), _prog("n : INT;", "IF n <> 0 THEN\n    n := 0;\nEND_IF;"),
        "IEC 61131-3 ed. 3, 7.3.3.3 (selection statements)"),
    ErrorCode(
        "E042", "invalid CASE",
        "The CASE selector must be an integer or enumeration; each label a constant of its type, "
        "in range, and no value may appear twice.",
        _prog("n : INT;\nx : INT;", "CASE n OF\n    1: x := 1;\n    1: x := 2;\nEND_CASE;"),
        _prog("n : INT;\nx : INT;", "CASE n OF\n    1: x := 1;\n    2: x := 2;\nEND_CASE;"),
        "IEC 61131-3 ed. 3, 7.3.3.3 (CASE)"),
    ErrorCode(
        "E043", "invalid FOR loop",
        "The FOR variable must be an integer, and a constant step of 0 would never end the loop.",
        _prog("r : REAL;", "FOR r := 0 TO 10 DO\nEND_FOR;"), _prog("i : INT;", "FOR i := 0 TO 10 DO\nEND_FOR;"),
        "IEC 61131-3 ed. 3, 7.3.3.4 (FOR)"),
    ErrorCode(
        "E044", "EXIT or CONTINUE outside a loop",
        "EXIT and CONTINUE leave or restart the innermost FOR, WHILE or REPEAT; outside one they "
        "mean nothing.",
        _prog("x : INT;", "EXIT;"), _prog("i : INT;", "FOR i := 1 TO 3 DO\n    EXIT;\nEND_FOR;"),
        "IEC 61131-3 ed. 3, 7.3.3.4 (iteration statements)"),
    ErrorCode(
        "E045", "not callable",
        "What is called is not a FUNCTION, an FB instance or a method: an unknown function, a "
        "variable of an elementary type, an FB type instead of its instance, a PROGRAM (programs "
        "run from tasks), an FB call used as an expression, or a method the FB or interface does "
        "not have.",
        _prog("x : INT;", "x := Twice(2);"),
        "FUNCTION Twice : INT\nVAR_INPUT\n    v : INT;\nEND_VAR\nTwice := 2 * v;\nEND_FUNCTION\n"
        + _prog("x : INT;", "x := Twice(2);"),
        "IEC 61131-3 ed. 3, 6.6.1 and 7.3.3.2 (calls)"),
    ErrorCode(
        "E046", "result type of a call cannot be decided",
        "A standard function with generic parameters (MAX, SEL, MUX, ADD, …) is given arguments "
        "whose types have no common type, or whose result type the arguments do not decide.",
        _prog("s : STRING;\nx : INT;", "x := MAX(x, s);"), _prog("s : STRING;\nx : INT;", "x := MAX(x, STRING_TO_INT(s));"),
        "IEC 61131-3 ed. 3, 6.6.2.5 (standard functions, generic types)"),
    ErrorCode(
        "E047", "arguments written in the wrong form",
        "Formal (`IN := x`) and positional arguments are mixed, an FB is called with positional "
        "arguments, an argument is given twice, EN/ENO is bound on an FB call inside an "
        "expression, or SUPER^() is given arguments.",
        _prog("t : TON;\nb : BOOL;", "t(b, T#1s);"), _prog("t : TON;\nb : BOOL;", "t(IN := b, PT := T#1s);"),
        "IEC 61131-3 ed. 3, 6.6.1.7 (formal and non-formal calls)"),
    ErrorCode(
        "E048", "wrong number of arguments",
        "A positional call gives more or fewer arguments than the function takes, or a VAR_IN_OUT "
        "of the callee is left unbound (an in-out refers to the caller's variable and must be "
        "given).",
        _prog("x : INT;", "x := ABS(x, 2);"), _prog("x : INT;", "x := ABS(x);"),
        "IEC 61131-3 ed. 3, 6.6.1.7"),
    ErrorCode(
        "E049", "no such parameter",
        "A formal argument names an input, output or in-out the callee does not declare, or binds "
        "an output with `:=` (outputs are read with `=>`).",
        _prog("t : TON;", "t(IN := TRUE, TIME := T#1s);"), _prog("t : TON;", "t(IN := TRUE, PT := T#1s);"),
        "IEC 61131-3 ed. 3, 6.6.1.7"),
    ErrorCode(
        "E050", "cannot be assigned",
        "The left side of `:=` is not a variable that may be written: a constant (or a member of "
        "one), an enumerator, an FB instance, a call result, or another expression.",
        "PROGRAM Main\nVAR CONSTANT\n    N : INT := 3;\nEND_VAR\nN := 4;\nEND_PROGRAM\n",
        "PROGRAM Main\nVAR\n    N : INT := 3;\nEND_VAR\nN := 4;\nEND_PROGRAM\n",
        "IEC 61131-3 ed. 3, 6.5.6 (CONSTANT) and 7.3.3.1 (assignment)"),
    ErrorCode(
        "E051", "FB input or output written from outside",
        "`fb.IN := x` outside the FB: an FB's inputs are given in its call, and its outputs are "
        "written only by the FB itself.",
        _prog("t : TON;", "t.IN := TRUE;\nt();"), _prog("t : TON;", "t(IN := TRUE);"),
        "IEC 61131-3 ed. 3, 6.6.3 (FB inputs are set by the call)"),
    ErrorCode(
        "E052", "type mismatch",
        "A value is stored or passed where its type is not accepted: no implicit conversion "
        "exists (only the widening ones, e.g. INT to DINT or REAL to LREAL, are implicit), an FB "
        "does not implement the interface, a call without result is used as a value, an argument "
        "has the wrong type. The message names the conversion function to use.",
        _prog("r : REAL;\nx : INT;", "x := r;"), _prog("r : REAL;\nx : INT;", "x := REAL_TO_INT(r);"),
        "IEC 61131-3 ed. 3, 6.6.2.5.6 (implicit conversions); Omron Sysmac W501, data type conversion"),
    ErrorCode(
        "E053", "in-out needs a variable",
        "A VAR_IN_OUT is passed by reference: its argument must be a variable the callee may write, "
        "not an expression or a constant.",
        "FUNCTION_BLOCK Inc\nVAR_IN_OUT\n    v : INT;\nEND_VAR\nv := v + 1;\nEND_FUNCTION_BLOCK\n"
        + _prog("f : Inc;\nx : INT;", "f(v := x + 1);"),
        "FUNCTION_BLOCK Inc\nVAR_IN_OUT\n    v : INT;\nEND_VAR\nv := v + 1;\nEND_FUNCTION_BLOCK\n"
        + _prog("f : Inc;\nx : INT;", "f(v := x);"),
        "IEC 61131-3 ed. 3, 6.5.2 (VAR_IN_OUT)"),
    ErrorCode(
        "E054", "string does not fit (string_overflow=error)",
        "A constant string is longer than the STRING[n] it is stored in. By default stvm cuts it "
        "and warns (W001); with the Sysmac setting `string_overflow=error` it is an error.",
        _prog("s : STRING[3];", "s := 'abcdef';"), _prog("s : STRING[6];", "s := 'abcdef';"),
        "Omron Sysmac: string assignment truncation; docs/sysmac_behaviours.md",
        settings=("string_overflow=error",)),
    ErrorCode(
        "E055", "reference to something that is not a variable",
        "REF(), ADR() and REF= take a variable; an expression, a temporary value or a constant "
        "has no place a reference could point to.",
        _prog("x : INT;\nr : REF_TO INT;", "r := REF(x + 1);"), _prog("x : INT;\nr : REF_TO INT;", "r := REF(x);"),
        "IEC 61131-3 ed. 3, 6.4.4.10 (REF)"),
    ErrorCode(
        "E056", "REF= needs a REFERENCE TO",
        "`r REF= x` binds a REFERENCE TO variable; its left side must be one.",
        _prog("x : INT;\ny : INT;", "y REF= x;"), _prog("x : INT;\nr : REFERENCE TO INT;", "r REF= x;"),
        "CODESYS / TwinCAT help, 'REFERENCE TO'"),
    ErrorCode(
        "E057", "name needs its qualifier",
        "The global variable list or enumeration is `{attribute 'qualified_only'}`: its names are "
        "written with the list's or type's name (`GVL.x`, `Color.Red`). Also reported when a local "
        "variable hides the global a qualified name would reach.",
        "{attribute 'qualified_only'}\nVAR_GLOBAL\n    g : INT;\nEND_VAR\n" + _prog("x : INT;", "x := g;"),
        "{attribute 'qualified_only'}\nVAR_GLOBAL\n    g : INT;\nEND_VAR\n" + _prog("x : INT;", "x := GVL.g;"),
        "CODESYS / TwinCAT help, 'Attribute qualified_only'", checked=False),
    # ---------------------------------------------------------------- object orientation
    ErrorCode(
        "E060", "misplaced modifier",
        "ABSTRACT, FINAL and the access specifiers (PUBLIC, PRIVATE, PROTECTED, INTERNAL) apply to "
        "a FUNCTION_BLOCK, METHOD or PROPERTY; an FB cannot be ABSTRACT and FINAL at once, and a "
        "member has one access specifier.",
        "FUNCTION_BLOCK ABSTRACT FINAL F\nEND_FUNCTION_BLOCK\n", "FUNCTION_BLOCK ABSTRACT F\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.6.5 and 6.6.7 (ABSTRACT, FINAL, access specifiers)"),
    ErrorCode(
        "E061", "methods on a FUNCTION",
        "Methods and properties belong to a FUNCTION_BLOCK (or CLASS); a FUNCTION has none.",
        "FUNCTION F : INT\nF := 0;\nMETHOD M\nEND_METHOD\nEND_FUNCTION\n",
        "FUNCTION_BLOCK F\nMETHOD M\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.6.7 (methods of function blocks)", checked=False),
    ErrorCode(
        "E062", "property without accessor",
        "A PROPERTY is a pair of accessor methods: it declares a GET (to be read), a SET (to be "
        "written) or both; with neither there is nothing to call.",
        "FUNCTION_BLOCK F\nPROPERTY P : INT\nEND_PROPERTY\nEND_FUNCTION_BLOCK\n",
        "FUNCTION_BLOCK F\nVAR\n    v : INT;\nEND_VAR\nPROPERTY P : INT\nGET\n    P := v;\nEND_GET\nEND_PROPERTY\n"
        "END_FUNCTION_BLOCK\n",
        "CODESYS / TwinCAT help, 'Property'"),
    ErrorCode(
        "E063", "invalid special method or FB_init arguments",
        "FB_init, FB_reinit, FB_exit and `{attribute 'call_after_init'}` methods have the fixed "
        "parameters stvm calls them with; FB_init arguments in a declaration (`fb : F(1, 2)`) must "
        "match F's FB_init inputs and be constants; an interface or ABSTRACT method has no "
        "statements and declares only inputs, outputs and in-outs.",
        "FUNCTION_BLOCK F\nEND_FUNCTION_BLOCK\n" + _prog("f : F(1);", ""),
        "FUNCTION_BLOCK F\nEND_FUNCTION_BLOCK\n" + _prog("f : F;", ""),
        "CODESYS / TwinCAT help, 'FB_init, FB_reinit, FB_exit'"),
    ErrorCode(
        "E064", "invalid EXTENDS or IMPLEMENTS",
        "Only a FUNCTION_BLOCK or INTERFACE extends; an FB extends one base FB that is not FINAL; "
        "only an FB implements, and what it implements must be an INTERFACE.",
        "TYPE S : STRUCT x : INT; END_STRUCT; END_TYPE\nFUNCTION_BLOCK F IMPLEMENTS S\nEND_FUNCTION_BLOCK\n",
        "INTERFACE I\nEND_INTERFACE\nFUNCTION_BLOCK F IMPLEMENTS I\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.6.5 and 6.6.6 (EXTENDS, IMPLEMENTS)"),
    ErrorCode(
        "E065", "inheritance cycle",
        "An FB or interface extends itself through a chain of EXTENDS.",
        "FUNCTION_BLOCK A EXTENDS B\nEND_FUNCTION_BLOCK\nFUNCTION_BLOCK B EXTENDS A\nEND_FUNCTION_BLOCK\n",
        "FUNCTION_BLOCK A\nEND_FUNCTION_BLOCK\nFUNCTION_BLOCK B EXTENDS A\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.6.5"),
    ErrorCode(
        "E066", "FINAL method overridden",
        "A method declared FINAL in a base FB cannot be overridden in a derived one.",
        "FUNCTION_BLOCK A\nMETHOD FINAL M\nEND_METHOD\nEND_FUNCTION_BLOCK\n"
        "FUNCTION_BLOCK B EXTENDS A\nMETHOD M\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "FUNCTION_BLOCK A\nMETHOD M\nEND_METHOD\nEND_FUNCTION_BLOCK\n"
        "FUNCTION_BLOCK B EXTENDS A\nMETHOD M\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.6.5 (FINAL)"),
    ErrorCode(
        "E067", "signature does not match",
        "A method that overrides a base method or implements an interface method has the same "
        "parameters and result type, and is PUBLIC when it implements an interface; a property "
        "keeps its type.",
        "INTERFACE I\nMETHOD M : INT\nEND_METHOD\nEND_INTERFACE\nFUNCTION_BLOCK F IMPLEMENTS I\n"
        "METHOD M : BOOL\nM := TRUE;\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "INTERFACE I\nMETHOD M : INT\nEND_METHOD\nEND_INTERFACE\nFUNCTION_BLOCK F IMPLEMENTS I\n"
        "METHOD M : INT\nM := 1;\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.6.5 and 6.6.6"),
    ErrorCode(
        "E068", "implementation missing",
        "An FB that IMPLEMENTS an interface implements each of its methods and properties; a "
        "non-ABSTRACT FB implements every ABSTRACT method it inherits; an ABSTRACT method needs an "
        "ABSTRACT FB.",
        "INTERFACE I\nMETHOD M : INT\nEND_METHOD\nEND_INTERFACE\nFUNCTION_BLOCK F IMPLEMENTS I\nEND_FUNCTION_BLOCK\n",
        "INTERFACE I\nMETHOD M : INT\nEND_METHOD\nEND_INTERFACE\nFUNCTION_BLOCK F IMPLEMENTS I\n"
        "METHOD M : INT\nM := 1;\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "IEC 61131-3 ed. 3, 6.6.6 (interfaces)"),
    ErrorCode(
        "E069", "instance of an ABSTRACT FB",
        "An ABSTRACT function block is a base for others; declare an instance of a derived, "
        "complete FB instead.",
        "FUNCTION_BLOCK ABSTRACT A\nEND_FUNCTION_BLOCK\n" + _prog("a : A;", ""),
        "FUNCTION_BLOCK ABSTRACT A\nEND_FUNCTION_BLOCK\nFUNCTION_BLOCK B EXTENDS A\nEND_FUNCTION_BLOCK\n"
        + _prog("b : B;", ""),
        "IEC 61131-3 ed. 3, 6.6.5 (ABSTRACT)"),
    ErrorCode(
        "E070", "misused built-in (THIS, SUPER, SIZEOF, bounds)",
        "THIS and SUPER exist only in an FB and its methods (SUPER only when the FB extends one, "
        "and not for an ABSTRACT base method); SIZEOF takes one variable or type of a known size; "
        "LOWER_BOUND/UPPER_BOUND take an array and a constant dimension.",
        _prog("x : INT;\nn : DINT;", "n := UPPER_BOUND(x, 1);"),
        _prog("a : ARRAY[1..3] OF INT;\nn : DINT;", "n := UPPER_BOUND(a, 1);"),
        "IEC 61131-3 ed. 3, 6.6.5 (THIS, SUPER); 6.4.4.5 (LOWER_BOUND, UPPER_BOUND)"),
    ErrorCode(
        "E071", "member not accessible here",
        "A PRIVATE member is used outside its FB, a PROTECTED one outside its FB and those derived "
        "from it, an INTERNAL one outside its namespace.",
        "FUNCTION_BLOCK F\nMETHOD PRIVATE M\nEND_METHOD\nEND_FUNCTION_BLOCK\n" + _prog("f : F;", "f.M();"),
        "FUNCTION_BLOCK F\nMETHOD PUBLIC M\nEND_METHOD\nEND_FUNCTION_BLOCK\n" + _prog("f : F;", "f.M();"),
        "IEC 61131-3 ed. 3, 6.6.5 (access specifiers)"),
    ErrorCode(
        "E072", "property read without GET or written without SET",
        "A property with only a SET cannot be read, one with only a GET cannot be written.",
        "FUNCTION_BLOCK F\nVAR\n    v : INT;\nEND_VAR\nPROPERTY P : INT\nGET\n    P := v;\nEND_GET\nEND_PROPERTY\n"
        "END_FUNCTION_BLOCK\n" + _prog("f : F;", "f.P := 1;"),
        "FUNCTION_BLOCK F\nVAR\n    v : INT;\nEND_VAR\nPROPERTY P : INT\nGET\n    P := v;\nEND_GET\nEND_PROPERTY\n"
        "END_FUNCTION_BLOCK\n" + _prog("f : F;\nx : INT;", "x := f.P;"),
        "CODESYS / TwinCAT help, 'Property'"),
    ErrorCode(
        "E073", "write into a property's value",
        "A property's GET returns a copy: assigning a member or element of it (`fb.P.x := 1`) or "
        "passing it as an in-out or to REF() would change the copy only. Assign the whole "
        "property, or use a variable.",
        "TYPE S : STRUCT x : INT; END_STRUCT; END_TYPE\nFUNCTION_BLOCK F\nVAR\n    v : S;\nEND_VAR\n"
        "PROPERTY P : S\nGET\n    P := v;\nEND_GET\nSET\n    v := P;\nEND_SET\nEND_PROPERTY\nEND_FUNCTION_BLOCK\n"
        + _prog("f : F;", "f.P.x := 1;"),
        "TYPE S : STRUCT x : INT; END_STRUCT; END_TYPE\nFUNCTION_BLOCK F\nVAR\n    v : S;\nEND_VAR\n"
        "PROPERTY P : S\nGET\n    P := v;\nEND_GET\nSET\n    v := P;\nEND_SET\nEND_PROPERTY\nEND_FUNCTION_BLOCK\n"
        + _prog("f : F;\ns : S;", "s := f.P;\ns.x := 1;\nf.P := s;"),
        "CODESYS / TwinCAT help, 'Property'"),
    # ---------------------------------------------------------------- loading a project
    ErrorCode(
        "E080", "nothing to load",
        "A folder given to stvm holds no .st file (nor TwinCAT or PLCopen XML source) and no "
        "stvm.toml listing files, or a TwinCAT .plcproj lists no sources.",
        "stvm check empty_folder/", "stvm check folder_with_sources/",
        "stvm (docs/command_line.md)", checked=False),
    ErrorCode(
        "E081", "library cannot be used",
        "A library of `[libraries]` in stvm.toml or `--library NAME=FOLDER` is missing, is not a "
        "folder of sources, or clashes with another library's namespace.",
        "[libraries]\nTools = \"../no_such_folder\"", "[libraries]\nTools = \"../tools_lib\"",
        "stvm (docs/platform_libraries.md)", checked=False),
    # ---------------------------------------------------------------- warnings of the checker
    ErrorCode(
        "W001", "string truncated",
        "A constant string is longer than the STRING[n] or WSTRING[n] it is stored in; stvm keeps "
        "its first n bytes (code units), as the PLC does. Make the variable longer or the text "
        "shorter; `--sysmac string_overflow=error` makes this an error (E054).",
        _prog("s : STRING[3];", "s := 'abcdef';"), _prog("s : STRING[6];", "s := 'abcdef';"),
        "Omron Sysmac: string assignment truncation; docs/sysmac_behaviours.md"),
    ErrorCode(
        "W002", "recursive method call",
        "CODESYS and TwinCAT allow a method to call itself; a recursion that goes too deep ends "
        "the run with a stack fault. Under IEC and Sysmac this is an error (E027).",
        "FUNCTION_BLOCK F\nMETHOD M : INT\nVAR_INPUT\n    n : INT;\nEND_VAR\nIF n > 0 THEN\n    M := THIS^.M(n - 1);\n"
        "END_IF;\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "FUNCTION_BLOCK F\nMETHOD M : INT\nVAR_INPUT\n    n : INT;\nEND_VAR\nVAR\n    i : INT;\nEND_VAR\n"
        "FOR i := n TO 1 BY -1 DO\nEND_FOR;\nM := 0;\nEND_METHOD\nEND_FUNCTION_BLOCK\n",
        "CODESYS help, 'Method call' (recursion allowed); IEC 61131-3 ed. 3, 6.6.1",
        settings=("dialect=codesys",)),
    ErrorCode(
        "W003", "double-quoted text taken as STRING",
        "Under Sysmac, double-quoted text is accepted as a STRING literal (Sysmac has no WSTRING) "
        "with this warning (`double_quote_strings=accept_warn`, the default; `=error` refuses it, "
        "E009). Portable code writes STRING literals in single "
        "quotes.",
        _prog("s : STRING;", "s := \"abc\";"), _prog("s : STRING;", "s := 'abc';"),
        "Omron Sysmac W501 (string literals); docs/sysmac_behaviours.md",
        settings=("dialect=sysmac",)),
]

CODES: dict[str, ErrorCode] = {c.code: c for c in _CODES}
assert len(CODES) == len(_CODES), "a code is registered twice"


def lookup(code: str) -> ErrorCode | None:
    """The entry of `code` (any case), or None."""
    return CODES.get(code.strip().upper())


def explain(entry: ErrorCode) -> str:
    """`stvm check --explain E031`: the entry as plain text."""
    lines = [f"{entry.code} {entry.title} ({entry.severity})", "", textwrap.fill(entry.explanation, 100), "",
             "Example (reported):" if entry.checked else "Example (reported), described:", "",
             _indent(entry.wrong), "", "Instead:", "", _indent(entry.right)]
    if entry.settings:
        lines += ["", "(with " + ", ".join(f"--sysmac {s}" for s in entry.settings) + ")"]
    if entry.source:
        lines += ["", f"Source: {entry.source}"]
    return "\n".join(lines) + "\n"


def _indent(text: str) -> str:
    return "\n".join("    " + line if line else "" for line in text.splitlines())


def docs_page() -> str:
    """docs/error_codes.md, generated from this registry (tools/gen_error_docs.py writes it)."""
    out = ["# Error and warning codes", "",
           "<!-- Generated by tools/gen_error_docs.py from stvm/diagnostics/codes.py; do not edit by hand. -->", "",
           "Every diagnostic of the parser, the checker and the loader carries a stable code: `E…` for an",
           "error (the program is not run), `W…` for a warning (it runs, and the message says what stvm",
           "did). The code ends the message line, in brackets:", "",
           "```text", "a.st:3:5: error: 'y' is not declared [E031]", "    y := 1;", "    ^", "```", "",
           "The line keeps the `FILE:LINE:COL: error: message` form that editors and CI log parsers read",
           "(GCC and Clang append `[-Wname]` the same way), so a tool that matches `: error: ` still",
           "finds it. Lint findings are not errors of the language but advice, with their own `SA…` codes",
           "in the severity word (`warning[SA102]:`, as rustc and ruff print them; see [lint](lint.md)).",
           "In the editor (`stvm lsp`) the code is the diagnostic's `code`, and `codeDescription` links",
           "to its entry on this page.", "",
           "`stvm check --explain E031` prints an entry (`--explain ALL`: every entry). A code is stable:",
           "its message may be reworded, the code stays, and a retired code is never reused.",
           "Each example below is checked by the test suite (the wrong one must get its code, the right",
           "one must check clean), except the few marked as described.", "",
           "| code | title |", "|---|---|"]
    out += [f"| [{c.code}](#{c.code.lower()}) | {c.title} |" for c in _CODES]
    for c in _CODES:
        out += ["", f'<a id="{c.code.lower()}"></a>', "", f"## {c.code}: {c.title}", "",
                f"*{c.severity}*" + (f" · {c.source}" if c.source else ""), "", c.explanation, ""]
        lang = "st" if c.checked else "text"
        setting = (" (with " + ", ".join(f"`--sysmac {s}`" for s in c.settings) + ")") if c.settings else ""
        out += [("Reported" if c.checked else "Reported, for example") + setting + ":", "",
                f"```{lang}", c.wrong.rstrip("\n"), "```", "", "Instead:", "",
                f"```{lang}", c.right.rstrip("\n"), "```"]
    return "\n".join(out) + "\n"
