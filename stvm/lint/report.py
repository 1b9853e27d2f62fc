"""Lint output: text (the checker's format), JSON (editors, scripts) and SARIF 2.1.0 (code
scanning). Findings render through the shared diagnostics renderer, so a lint warning looks
exactly like a checker diagnostic: `FILE:LINE:COL: warning[SA201]: message`, the line, a caret.
"""

from __future__ import annotations

import json
from pathlib import Path

from stvm.diagnostics import Diagnostic, render
from stvm.lint.findings import Finding, Rule
from stvm.lint.registry import all_rules
from stvm.version import __version__

SARIF_SCHEMA = "https://docs.oasis-open.org/sarif/sarif/v2.1.0/errata01/os/schemas/sarif-schema-2.1.0.json"
DOCS_PAGE = "docs/lint.md"
JSON_VERSION = 1


def rule_anchor(code: str) -> str:
    return code.lower()


def as_diagnostic(finding: Finding) -> Diagnostic:
    return Diagnostic.warning(finding.message, finding.span, finding.code)


def render_text(findings: list[Finding], diagnostics: list[Diagnostic], sources: dict[str, str]) -> str:
    out = [render(d, sources) for d in diagnostics]   # exactly as `stvm check` prints them
    out += [render(as_diagnostic(f), sources, f"warning[{f.code}]") for f in findings]
    return "".join(out)


def _location(span) -> dict:
    return {"file": span.file, "line": span.line, "column": span.column,
            "end_line": span.end_line, "end_column": span.end_column}


def render_json(findings: list[Finding], diagnostics: list[Diagnostic], rules: list[Rule] | None = None) -> str:
    """One JSON document: {"version", "findings": [...], "diagnostics": [...], "rules": {...}}.
    Each finding: code, name, severity "warning", message, file/line/column/end_line/end_column
    (1-based, end exclusive as the spans), doc (docs page anchor)."""
    by_code = {r.code: r for r in all_rules()}
    doc = {
        "version": JSON_VERSION,
        "findings": [
            {"code": f.code, "name": by_code[f.code].name, "severity": "warning", "message": f.message,
             **_location(f.span), "doc": f"{DOCS_PAGE}#{rule_anchor(f.code)}"}
            for f in findings
        ],
        "diagnostics": [
            {"code": d.code, "severity": d.severity.value, "message": d.message, **_location(d.span)}
            for d in diagnostics
        ],
        "rules": {r.code: {"name": r.name, "summary": r.summary} for r in (rules or all_rules())},
    }
    return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"


def _uri(file: str, base: Path | None) -> tuple[str, str | None]:
    """(uri, uriBaseId): relative to the repository root when possible (GitHub code scanning
    resolves relative URIs against the checkout), else an absolute file URI."""
    path = Path(file)
    if file.startswith("<"):
        return file.strip("<>").replace(">", ""), "STVM_STDLIB"
    if base is not None:
        try:
            return path.resolve().relative_to(base.resolve()).as_posix(), "%SRCROOT%"
        except ValueError:
            pass
    if not path.is_absolute():
        return path.as_posix(), "%SRCROOT%"
    return path.resolve().as_uri(), None


def render_sarif(findings: list[Finding], diagnostics: list[Diagnostic], base: Path | None = None,
                 version: str = "") -> str:
    rules = all_rules()
    index = {r.code: i for i, r in enumerate(rules)}
    driver = {
        "name": "stvm-lint",
        "version": version or __version__,
        "rules": [
            {
                "id": r.code,
                "name": "".join(word.capitalize() for word in r.name.split("-")),
                "shortDescription": {"text": r.summary},
                "fullDescription": {"text": " ".join(r.rationale.split())},
                "help": {"text": " ".join(r.rationale.split()),
                         "markdown": f"{r.rationale}\n\n```iecst\n{r.example}\n```\n\nInstead:\n\n```iecst\n{r.fixed}\n```"},
                "defaultConfiguration": {"level": "warning"},
                "properties": {"tags": [r.family.lower()]},
            }
            for r in rules
        ],
    }
    results = []
    for f in findings:
        uri, base_id = _uri(f.span.file, base)
        location = {"uri": uri}
        if base_id is not None:
            location["uriBaseId"] = base_id
        region = {"startLine": max(f.span.line, 1), "startColumn": max(f.span.column, 1)}
        if f.span.end_line >= f.span.line and f.span.end_line > 0:
            region["endLine"] = f.span.end_line
            if f.span.end_column > 0 and (f.span.end_line > f.span.line or f.span.end_column > f.span.column):
                region["endColumn"] = f.span.end_column
        results.append({
            "ruleId": f.code,
            "ruleIndex": index[f.code],
            "level": "warning",
            "message": {"text": f.message},
            "locations": [{"physicalLocation": {"artifactLocation": location, "region": region}}],
            "partialFingerprints": {"primaryLocationLineHash": _fingerprint(f)},
        })
    notifications = [
        {"level": "error" if d.is_error else "warning", "message": {"text": d.message},
         "locations": [{"physicalLocation": {"artifactLocation": {"uri": _uri(d.span.file, base)[0]},
                                             "region": {"startLine": max(d.span.line, 1)}}}]}
        for d in diagnostics
    ]
    run = {"tool": {"driver": driver}, "results": results, "columnKind": "unicodeCodePoints",
           "originalUriBaseIds": {"%SRCROOT%": {"uri": (base.resolve().as_uri() + "/") if base else "file:///"}}}
    if notifications:
        run["invocations"] = [{"executionSuccessful": not any(d.is_error for d in diagnostics),
                               "toolExecutionNotifications": notifications}]
    return json.dumps({"$schema": SARIF_SCHEMA, "version": "2.1.0", "runs": [run]}, indent=2,
                      ensure_ascii=False) + "\n"


def _fingerprint(f: Finding) -> str:
    import hashlib
    text = f"{f.code}\0{Path(f.span.file).name}\0{f.message}"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def explain(rule_: Rule) -> str:
    """`stvm lint --explain SAnnn`: the rule's page as plain text."""
    lines = [f"{rule_.code} {rule_.name}: {rule_.summary}", f"Family: {rule_.family}", "", rule_.rationale, "",
             "Example (reported):", "", _indent(rule_.example), "", "Instead:", "", _indent(rule_.fixed)]
    if rule_.thesis:
        lines += ["", f"In the thesis code: {' '.join(rule_.thesis.split())}"]
    lines += ["", f"Suppress one line with (* stvm: noqa {rule_.code} *), or list it under [lint] ignore "
                  f"in stvm.toml."]
    return "\n".join(lines) + "\n"


def _indent(text: str) -> str:
    return "\n".join("    " + line if line else "" for line in text.splitlines())


def docs_page() -> str:
    """docs/lint.md, generated from the registry (tools/gen_lint_docs.py writes it)."""
    rules = all_rules()
    out = ["# `stvm lint` rules", "",
           "<!-- Generated by tools/gen_lint_docs.py from stvm/lint/rules; do not edit by hand. -->", "",
           "`stvm lint FILE|DIR... [--select CODES] [--ignore CODES] [--format text|json|sarif] [--output F]`",
           "reports findings as `FILE:LINE:COL: warning[SAnnn]: message` with the source line and a caret,",
           "and exits 1 when there are findings, 0 when there are none, 2 on a usage error.",
           "`--select`/`--ignore` take codes (`SA201`), prefixes (`SA2`) or names (`index-out-of-bounds`).",
           "`stvm lint --explain SAnnn` prints a rule's page.", "",
           "Suppress a finding with `(* stvm: noqa SA201 *)` (or `// stvm: noqa SA201`) on its line, or",
           "project-wide in the `stvm.toml` next to the sources:", "",
           "```toml", "[lint]", 'ignore = ["SA304"]', "", "[lint.per-file-ignores]",
           '"Program_Example.st" = ["SA203"]', "```", "",
           "The analysis is data flow on each POU's control-flow graph, with the PLC scan as the outer",
           "loop: integer ranges and string lengths from declarations, subranges, assignments, loop bounds",
           "and the conditions on the path, and for step sequences (`CASE step OF`) a typestate analysis of",
           "what each step holds across scans. See README (\"Static analysis\") for the design and the",
           "measured false-positive counts.", "", "| code | name | summary |", "|---|---|---|"]
    for r in rules:
        out.append(f"| [{r.code}](#{rule_anchor(r.code)}) | {r.name} | {r.summary} |")
    family = None
    for r in rules:
        if r.family != family:
            family = r.family
            out += ["", f"## {family}"]
        out += ["", f'<a id="{rule_anchor(r.code)}"></a>', "", f"### {r.code} {r.name}", "", f"**{r.summary}.**", "",
                r.rationale, "", "Reported:", "", "```iecst", r.example, "```", "", "Instead:", "", "```iecst",
                r.fixed, "```"]
        if r.thesis:
            out += ["", f"In the thesis code: {' '.join(r.thesis.split())}"]
    return "\n".join(out) + "\n"
