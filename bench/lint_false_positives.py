"""False positives of `stvm lint` on our own ST: the stdlib and the core test programs.

    python bench/lint_false_positives.py [--list]

The core test programs are the ST texts of the core test suites (string literals holding a
PROGRAM, FUNCTION_BLOCK or FUNCTION in tests/{syntax,semantics,lower,runtime,stdlib,cli,debug,
trace,frontend}/*.py, and tests/trace/st/*.st) that check without errors; each is linted on its
own. Every finding is counted as a false positive unless bench/lint_review.toml lists it as
reviewed true (code, a file pattern, the line's text, the reason). Prints one row per rule:
findings, reviewed true, false positives, and the number of programs and POUs looked at.
"""

from __future__ import annotations

import argparse
import ast
import fnmatch
import os
import sys
import tempfile
import tomllib
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from stvm.lint import lint, lint_analysis, select_rules  # noqa: E402
from stvm.project import check_project as load_for_lint  # noqa: E402 (the driver's parse + check)
from stvm.settings import DEFAULT_SETTINGS  # noqa: E402

SUITES = ("syntax", "semantics", "lower", "runtime", "stdlib", "cli", "debug", "trace", "frontend")
MARKERS = ("END_PROGRAM", "END_FUNCTION_BLOCK", "END_FUNCTION")


def harvest() -> list[tuple[str, str]]:
    """(origin, ST text) of every string literal in the core tests that holds a POU."""
    out = []
    for suite in SUITES:
        for path in sorted((ROOT / "tests" / suite).glob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                if isinstance(node, ast.Constant) and isinstance(node.value, str) \
                        and any(m in node.value.upper() for m in MARKERS) and "{" not in node.value:
                    out.append((f"{path.relative_to(ROOT)}:{node.lineno}", node.value))
    for path in sorted((ROOT / "tests" / "trace" / "st").glob("*.st")):
        out.append((str(path.relative_to(ROOT)), path.read_text(encoding="utf-8")))
    return out


def load_review() -> list[dict]:
    path = ROOT / "bench" / "lint_review.toml"
    if not path.exists():
        return []
    with path.open("rb") as fh:
        return tomllib.load(fh).get("true", [])


def reviewed(finding, origin: str, line_text: str, review: list[dict]) -> bool:
    for entry in review:
        if entry["code"] == finding.code and fnmatch.fnmatch(origin, entry["origin"]) \
                and entry["text"].strip() in line_text:
            return True
    return False


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--list", action="store_true", help="print every finding")
    args = parser.parse_args(argv)
    os.environ.setdefault("STVM_CACHE_DIR", tempfile.mkdtemp(prefix="stvm-lint-fp-"))
    review = load_review()
    rules = select_rules()
    total: Counter = Counter()
    true: Counter = Counter()
    pous = programs = skipped = 0
    rows = []

    # the stdlib's ST bodies
    loaded = load_for_lint([], DEFAULT_SETTINGS)
    from stvm.lint.context import ProjectContext
    pous += len(ProjectContext(loaded.analysis, DEFAULT_SETTINGS).pou_contexts(include_stdlib=True))
    for f in lint_analysis(loaded.analysis, DEFAULT_SETTINGS, rules, include_stdlib=True):
        text = loaded.sources[f.span.file].splitlines()[f.span.line - 1]
        rows.append(("stdlib", f, text))

    work = Path(tempfile.mkdtemp(prefix="stvm-lint-fp-src-"))
    for i, (origin, text) in enumerate(harvest()):
        path = work / f"p{i}" / "main.st"
        path.parent.mkdir()
        path.write_text(text, encoding="utf-8")
        report = lint([path])
        if report.has_errors:
            skipped += 1      # a deliberately wrong program (diagnostic tests), or a fragment
            continue
        programs += 1
        from stvm.lint.context import ProjectContext as _P  # noqa: F401
        pous += text.upper().count("END_PROGRAM") + text.upper().count("END_FUNCTION_BLOCK") \
            + text.upper().count("END_FUNCTION\n") + text.upper().rstrip().endswith("END_FUNCTION")
        for f in report.findings:
            rows.append((origin, f, text.splitlines()[f.span.line - 1]))

    for origin, f, line_text in rows:
        total[f.code] += 1
        ok = reviewed(f, origin, line_text, review)
        if ok:
            true[f.code] += 1
        if args.list:
            print(f"{'TRUE ' if ok else 'FP   '} {f.code} {origin} l.{f.span.line}: {line_text.strip()}  -- {f.message}")
    print(f"linted: the stdlib's ST bodies and {programs} core test programs ({pous} POUs; {skipped} "
          f"texts with check errors or fragments skipped)")
    print(f"{'rule':<8}{'name':<24}{'findings':>9}{'true':>6}{'false pos.':>11}")
    for r in rules:
        fp = total[r.code] - true[r.code]
        print(f"{r.code:<8}{r.name:<24}{total[r.code]:>9}{true[r.code]:>6}{fp:>11}")
    print(f"{'all':<32}{sum(total.values()):>9}{sum(true.values()):>6}{sum(total.values()) - sum(true.values()):>11}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
