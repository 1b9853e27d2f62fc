"""`stvm lint` (`stvm lsp` is stvm/lsp/cli.py).

    stvm lint FILE|DIR... [--select CODES] [--ignore CODES] [--format text|json|sarif]
              [--output F] [--sysmac NAME=VALUE]... [--no-cache]
    stvm lint --explain SAnnn|ALL

Exit codes: 0 no findings, 1 findings (or compile errors), 2 usage error.
"""

from __future__ import annotations

import sys
from pathlib import Path
from stvm.settings import DEFAULT_SETTINGS

EXIT_CLEAN, EXIT_FINDINGS, EXIT_USAGE = 0, 1, 2


def register(subparsers) -> None:
    lint = subparsers.add_parser(
        "lint", help="static analysis: find bugs the checker accepts (rule codes SAnnn)",
        description="Analyse ST files (a folder: its *.st; a file of a folder with stvm.toml: that project) "
                    "and report findings as FILE:LINE:COL: warning[SAnnn]: message. Exit 1 if there are "
                    "findings, 0 if none, 2 on a usage error.")
    lint.add_argument("files", nargs="*", help="ST files or folders")
    lint.add_argument("--select", action="append", metavar="CODES", default=[],
                      help="only these rules: codes, prefixes (SA2) or names, comma-separated; repeatable")
    lint.add_argument("--ignore", action="append", metavar="CODES", default=[],
                      help="skip these rules (same forms as --select); repeatable")
    lint.add_argument("--format", choices=("text", "json", "sarif"), default="text", help="output format (default text)")
    lint.add_argument("--output", "-o", metavar="FILE", help="write the report to FILE instead of stdout")
    lint.add_argument("--explain", metavar="CODE", help="print a rule's rationale and examples (ALL: every rule)")
    lint.add_argument("--no-cache", action="store_true", help="do not use the parse cache")
    lint.add_argument("--sysmac", action="append", metavar="NAME=VALUE", help="override a Sysmac UNCERTAIN setting")
    lint.set_defaults(func=cmd_lint)


def _usage(message: str) -> int:
    print(f"stvm: error: {message}", file=sys.stderr)
    return EXIT_USAGE


def _settings(args):
    settings = DEFAULT_SETTINGS
    dialect = _vendor_dialect(getattr(args, "files", None) or [])
    if dialect is not None:   # TwinCAT / PLCopen XML sources: their vendor's names and types
        settings = settings.with_overrides([f"dialect={dialect}"])
    return settings.with_overrides(getattr(args, "sysmac", None) or [])


def _vendor_dialect(files) -> str | None:
    from stvm.project import expand_paths, vendor_dialect   # lazy: start-up
    try:
        expanded, _, _ = expand_paths(files)
    except Exception:  # noqa: BLE001 - the lint run itself reports unusable paths
        return None
    return vendor_dialect(expanded)


def cmd_lint(args) -> int:
    # lazy: start-up (`stvm.cli` imports this module on every call to register `stvm lint`)
    from stvm.lint import lint
    from stvm.lint.config import ConfigError
    from stvm.lint.registry import SelectionError, select_rules
    from stvm.lint.report import explain   # lazy: start-up
    if args.explain:
        try:
            chosen = select_rules([args.explain])
        except SelectionError as exc:
            return _usage(str(exc))
        sys.stdout.write("\n".join(explain(r) for r in chosen))
        return EXIT_CLEAN
    if not args.files:
        return _usage("lint needs FILE or DIR arguments (or --explain CODE)")
    for f in args.files:
        if not Path(f).exists():
            return _usage(f"no such file: {f}")
    try:
        settings = _settings(args)
    except ValueError as exc:
        return _usage(str(exc))
    from stvm.lint.report import render_json, render_sarif, render_text   # lazy: start-up
    try:
        report = lint(args.files, settings, select=args.select, ignore=args.ignore, use_cache=not args.no_cache)
    except (SelectionError, ConfigError) as exc:
        return _usage(str(exc))
    if args.format == "json":
        text = render_json(report.findings, report.diagnostics, report.rules)
    elif args.format == "sarif":
        text = render_sarif(report.findings, report.diagnostics, base=Path.cwd())
    else:
        text = render_text(report.findings, report.diagnostics, report.sources)
    if args.output:
        try:
            Path(args.output).write_text(text, encoding="utf-8")
        except OSError as exc:
            return _usage(f"cannot write {args.output}: {exc.strerror or exc}")
    else:
        sys.stdout.write(text)
    errors = sum(d.is_error for d in report.diagnostics)
    if args.format == "text" or args.output:
        summary = f"{len(report.findings)} finding(s)"
        if report.suppressed:
            summary += f", {report.suppressed} suppressed"
        if errors:
            summary += f"; {errors} error(s): fix them to lint"
        print(summary, file=sys.stderr)
    return EXIT_FINDINGS if report.findings or errors else EXIT_CLEAN
