"""Shared helpers for the lint tests: lint a piece of ST text in a temporary file."""

from __future__ import annotations

import tempfile
from pathlib import Path

from stvm.lint import lint

_WORK = Path(tempfile.mkdtemp(prefix="stvm-lint-tests-"))
_COUNT = [0]


def write_st(text: str, name: str | None = None) -> Path:
    _COUNT[0] += 1
    folder = _WORK / f"case{_COUNT[0]}"
    folder.mkdir()
    path = folder / (name or "main.st")
    path.write_text(text, encoding="utf-8")
    return path


def findings(text: str, select: str | list[str] | None = None, **kwargs):
    """The findings of linting `text` (asserting it checks without errors)."""
    path = write_st(text)
    report = lint([path], select=[select] if isinstance(select, str) else select, **kwargs)
    errors = [d for d in report.diagnostics if d.is_error]
    assert not errors, "\n".join(f"{d.span}: {d.message}" for d in errors)
    return report.findings


def codes(text: str, select: str | list[str] | None = None) -> list[str]:
    return [f.code for f in findings(text, select)]


def lines(text: str, code: str) -> list[int]:
    return [f.span.line for f in findings(text, code)]
