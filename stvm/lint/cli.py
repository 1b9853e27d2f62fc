"""`stvm lint` (`stvm lsp` is stvm/lsp/cli.py).

    stvm lint FILE|DIR... [--select CODES] [--ignore CODES] [--format text|json|sarif]
              [--output F] [--sysmac NAME=VALUE]... [--dialect D] [--define N]... [--no-cache]
    stvm lint --explain SAnnn|ALL

Exit codes: 0 no findings, 1 findings (or compile errors), 2 usage error.
"""

from __future__ import annotations

import sys
from pathlib import Path

from stvm.cli_support import (EXIT_COMPILE, EXIT_OK, EXIT_USAGE, UsageError, add_project_options,  # noqa: F401
                              project_options, resolve_project, usage)

EXIT_CLEAN, EXIT_FINDINGS = EXIT_OK, EXIT_COMPILE


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
    add_project_options(lint)
    lint.set_defaults(func=cmd_lint)


def _options(args):
    """The driver's Options: each file is linted with its project's settings and these on top."""
    options = project_options(args)
    from stvm.settings import DEFAULT_SETTINGS   # lazy: start-up
    try:   # a bad --sysmac, --dialect or --define is a usage error before any file is read
        DEFAULT_SETTINGS.with_overrides(list(options.sysmac) + ([f"dialect={options.dialect}"]
                                                                 if options.dialect else [])) \
            .with_defines(list(options.defines))
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    return options


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
            return usage(str(exc))
        sys.stdout.write("\n".join(explain(r) for r in chosen))
        return EXIT_CLEAN
    if not args.files:
        return usage("lint needs FILE or DIR arguments (or --explain CODE)")
    try:
        spec = resolve_project(args)
    except UsageError as exc:
        return usage(str(exc))
    from stvm.lint.report import render_json, render_sarif, render_text   # lazy: start-up
    try:
        report = lint(args.files, spec, select=args.select, ignore=args.ignore, use_cache=not args.no_cache)
    except (SelectionError, ConfigError) as exc:
        return usage(str(exc))
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
            return usage(f"cannot write {args.output}: {exc.strerror or exc}")
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
