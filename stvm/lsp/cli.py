"""`stvm lsp`: the language server on stdio (docs/editor.md).

    stvm lsp [--sysmac NAME=VALUE]...

Each open file's project is checked with its own settings (stvm.toml, the vendor files'
dialect) plus these overrides. Exit code 2 on a usage error (a bad setting, pygls missing).
"""

from __future__ import annotations

import sys

EXIT_CLEAN, EXIT_USAGE = 0, 2


def register(subparsers) -> None:
    lsp = subparsers.add_parser(
        "lsp", help="language server on stdio (hover, definition, completion, rename, diagnostics …; docs/editor.md)")
    lsp.add_argument("--sysmac", action="append", metavar="NAME=VALUE", help="override a Sysmac UNCERTAIN setting")
    lsp.set_defaults(func=cmd_lsp)


def cmd_lsp(args) -> int:
    from stvm.settings import DEFAULT_SETTINGS   # lazy: start-up
    overrides = list(args.sysmac or [])
    try:
        DEFAULT_SETTINGS.with_overrides(overrides)    # a bad NAME=VALUE is a usage error now, not per file later
    except ValueError as exc:
        print(f"stvm: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        from stvm.lsp.server import serve   # lazy: start-up (pygls)
    except ImportError as exc:
        print(f"stvm: error: the language server needs pygls: pip install 'stvm[lsp]' ({exc})", file=sys.stderr)
        return EXIT_USAGE
    serve(overrides)
    return EXIT_CLEAN
