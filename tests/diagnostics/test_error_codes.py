"""The error-code registry (stvm/diagnostics/codes.py): every example gets its code, every code
site uses a registered code, the docs page is generated from it, `stvm check --explain` prints it.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

from core_helpers import cli
from stvm.diagnostics import Diagnostic, render
from stvm.diagnostics.codes import CODES, explain
from stvm.project import check
from stvm.settings import DEFAULT_SETTINGS
from stvm.source import Span

ROOT = Path(__file__).resolve().parents[2]
CHECKED = [pytest.param(entry, id=code) for code, entry in CODES.items() if entry.checked]


def _diagnostics(tmp_path: Path, text: str, overrides: tuple[str, ...]) -> list[Diagnostic]:
    path = tmp_path / "example.st"
    path.write_text(text, encoding="utf-8")
    settings = DEFAULT_SETTINGS.with_overrides(list(overrides))
    _, diags, _ = check([path], settings=settings, use_cache=False)
    return diags


@pytest.mark.parametrize("entry", CHECKED)
def test_the_wrong_example_gets_its_code_and_the_right_one_checks_clean(entry, tmp_path):
    wrong = _diagnostics(tmp_path, entry.wrong, entry.settings)
    assert entry.code in {d.code for d in wrong}, [(d.code, d.message) for d in wrong]
    right = _diagnostics(tmp_path, entry.right, entry.settings)
    unexpected = [(d.code, d.message) for d in right if d.is_error or d.code == entry.code]
    assert not unexpected


def test_codes_are_well_formed_and_explained():
    for code, entry in CODES.items():
        assert re.fullmatch(r"[EW]\d{3}", code)
        assert entry.title and len(entry.explanation) > 60 and entry.wrong.strip() and entry.right.strip()
        assert entry.wrong != entry.right


# ---------------------------------------------------------------- every site has a registered code
# The modules whose diagnostics are the parser's, the checker's and the loader's.
SITES = [*sorted((ROOT / "stvm" / "semantics").glob("*.py")), ROOT / "stvm" / "syntax" / "parser.py",
         ROOT / "stvm" / "syntax" / "conditional.py", ROOT / "stvm" / "project.py", ROOT / "stvm" / "libraries.py",
         ROOT / "stvm" / "lsp" / "driver.py"]
# the helpers that forward a code they are given (their own parameter `code`)
FORWARDERS = {"error", "warning", "_error"}
CODE_LITERAL = re.compile(r"[EW]\d{3}")


def _code_argument(call: ast.Call, position: int) -> ast.expr | None:
    for keyword in call.keywords:
        if keyword.arg == "code":
            return keyword.value
    return call.args[position] if len(call.args) > position else None


def _diagnostic_calls(tree: ast.AST):
    """(call, code expression) of each Diagnostic.error/warning(...) and self.error/warning/_error(...)."""
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call) or not isinstance(node.func, ast.Attribute):
            continue
        func = node.func
        if isinstance(func.value, ast.Name) and func.value.id == "Diagnostic" and func.attr in ("error", "warning"):
            yield node, _code_argument(node, 2)
        elif func.attr in FORWARDERS and ast.unparse(func.value) in ("self", "self.c"):
            yield node, _code_argument(node, 2)


def test_every_diagnostic_site_passes_a_registered_code():
    missing, unknown, seen = [], [], 0
    for path in SITES:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        forwarding = {id(fn) for fn in ast.walk(tree) if isinstance(fn, ast.FunctionDef) and fn.name in FORWARDERS}
        inside_forwarder = {id(call) for fn in ast.walk(tree) if id(fn) in forwarding for call in ast.walk(fn)}
        for call, code in _diagnostic_calls(tree):
            seen += 1
            where = f"{path.relative_to(ROOT)}:{call.lineno}"
            if isinstance(code, ast.Constant) and isinstance(code.value, str):
                if code.value not in CODES:
                    unknown.append(f"{where}: {code.value}")
            elif isinstance(code, ast.Name) and code.id == "code" and id(call) in inside_forwarder:
                continue    # error(self, message, span, code) handing on its caller's code
            elif isinstance(code, ast.Attribute) and ast.unparse(code) == "exc.code":
                continue    # a SourceError's own code (E006, or E007 for vendor XML)
            else:
                missing.append(where)
    assert seen > 250      # the scan found the sites (a refactoring that renames them must update it)
    assert not missing, f"diagnostics without a code: {missing}"
    assert not unknown, f"codes not in stvm/diagnostics/codes.py: {unknown}"


def test_every_registered_code_is_used_somewhere():
    text = "".join(path.read_text(encoding="utf-8") for path in SITES)
    text += (ROOT / "stvm" / "source.py").read_text(encoding="utf-8")
    text += (ROOT / "stvm" / "syntax" / "vendor_xml.py").read_text(encoding="utf-8")
    unused = [code for code in CODES if f'"{code}"' not in text]
    assert not unused


def test_every_error_of_the_bad_program_corpus_has_a_code():
    """The diagnostics snapshots (tests/semantics/diagnostics/*.stderr) are the corpus of bad programs."""
    lines = [line for snap in sorted((ROOT / "tests" / "semantics" / "diagnostics").glob("*.stderr"))
             for line in snap.read_text(encoding="utf-8").splitlines()
             if re.match(r"^[^\s:][^:]*:\d+:\d+: (error|warning): ", line)]
    assert len(lines) > 50
    bad = [line for line in lines if not re.search(r" \[[EW]\d{3}\]$", line)]
    assert not bad


# ---------------------------------------------------------------- the output format
def test_the_code_ends_the_message_line_after_the_contract_prefix():
    d = Diagnostic.error("'y' is not declared", Span("a.st", 3, 5, 3, 6), "E031")
    text = render(d, {"a.st": "\n\n    y := 1;\n"})
    assert text.splitlines()[0] == "a.st:3:5: error: 'y' is not declared [E031]"
    assert text.splitlines()[2] == "        ^"
    # a message cut at the limit keeps its code
    long = render(Diagnostic.error("x" * 1000, Span("a.st", 1, 1, 1, 2), "E031"), {})
    assert long.splitlines()[0].endswith("… [E031]")
    # lint names its code in the severity word, not twice
    lint = render(Diagnostic.warning("never read", Span("a.st", 1, 1, 1, 2), "SA102"), {}, "warning[SA102]")
    assert lint.splitlines()[0] == "a.st:1:1: warning[SA102]: never read"


def test_check_prints_the_code(tmp_path):
    path = tmp_path / "a.st"
    path.write_text("PROGRAM Main\nVAR\n    x : INT;\nEND_VAR\ny := 1;\nEND_PROGRAM\n", encoding="utf-8")
    rc, out, err = cli(["check", str(path)])
    assert rc == 1
    assert f"{path}:5:1: error: 'y' is not declared [E031]\n" in err


# ---------------------------------------------------------------- --explain and the docs page
def test_explain_prints_the_entry():
    rc, out, err = cli(["check", "--explain", "e052"])
    assert rc == 0 and err == ""
    assert out == explain(CODES["E052"])
    assert out.startswith("E052 type mismatch (error)")
    assert "REAL_TO_INT(r)" in out and "Source: IEC 61131-3" in out


def test_explain_all_and_unknown_codes():
    rc, out, _ = cli(["check", "--explain", "ALL"])
    assert rc == 0 and all(f"{code} " in out for code in CODES)
    for unknown in ("E999", "SA102", ""):
        rc, out, err = cli(["check", "--explain", unknown]) if unknown else cli(["check"])
        assert rc == 2 and out == ""
        assert err.startswith("stvm: error: ") and "Traceback" not in err


def test_docs_page_is_generated_and_up_to_date():
    proc = subprocess.run([sys.executable, str(ROOT / "tools" / "gen_error_docs.py"), "--check"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    page = (ROOT / "docs" / "error_codes.md").read_text(encoding="utf-8")
    for code in CODES:
        assert f'<a id="{code.lower()}"></a>' in page
