"""`stvm lsp`: the language server on stdio (docs/editor.md).

    stvm lsp [--sysmac NAME=VALUE]... [--dialect D] [--define NAME]...

Each open file's project is checked with the settings `stvm check` gives it (its stvm.toml, the
vendor files' dialect), then these options, then the client's `initializationOptions`
({"dialect": "codesys", "defines": ["SIM"], "sysmac": ["NAME=VALUE"]}). Exit code 2 on a usage
error (a bad setting, pygls missing).
"""

from __future__ import annotations

from stvm.cli_support import EXIT_OK, UsageError, add_project_options, project_options, usage


def register(subparsers) -> None:
    lsp = subparsers.add_parser(
        "lsp", help="language server on stdio (hover, definition, completion, rename, diagnostics …; docs/editor.md)")
    add_project_options(lsp)
    lsp.set_defaults(func=cmd_lsp)


def cmd_lsp(args) -> int:
    from stvm.settings import DEFAULT_SETTINGS   # lazy: start-up
    try:
        options = project_options(args)
        # a bad --sysmac, --dialect or --define is a usage error now, not per file later
        DEFAULT_SETTINGS.with_overrides(list(options.sysmac) + ([f"dialect={options.dialect}"] if options.dialect else [])) \
            .with_defines(list(options.defines))
    except (UsageError, ValueError) as exc:
        return usage(str(exc))
    try:
        from stvm.lsp.server import serve   # lazy: start-up (pygls)
    except ImportError as exc:
        return usage(f"the language server needs pygls: pip install 'stvm[lsp]' ({exc})")
    serve(options)
    return EXIT_OK
