"""What every `stvm` sub-command shares: the exit codes, usage errors, the "no such file" check,
diagnostics on stderr, and the project options (`--sysmac`, `--dialect`, `--define`) that turn
a command line into the driver's `Options` (stvm/project.py).

Exit codes (a contract, the same for every command):

    0   ok (lint: no findings; trace: equal to the golden)
    1   compile errors (lint: findings or compile errors)
    2   usage error: a bad command line, a missing file, a manifest that cannot be used
    3   runtime fault
    4   trace: the run differs from the golden trace
    70  internal error (a bug in stvm, never the user's input)
    130 interrupted (Ctrl-C before a run started)

Every module registering a sub-command imports this one, so it imports nothing heavy: the
driver is imported when a command runs.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING, Iterable

from stvm.settings import Dialect

if TYPE_CHECKING:
    from stvm.project import Options, ProjectSpec

EXIT_OK = 0
EXIT_COMPILE = 1
EXIT_USAGE = 2
EXIT_FAULT = 3
EXIT_MISMATCH = 4
EXIT_INTERNAL = 70     # EX_SOFTWARE
EXIT_INTERRUPTED = 130

DIALECTS = tuple(d.value for d in Dialect)

SYSMAC_HELP = "override a Sysmac UNCERTAIN setting, NAME=VALUE (docs: Sysmac settings)"
DIALECT_HELP = "vendor dialect: name rules and vendor types (default: stvm.toml's [project] dialect)"
DEFINE_HELP = ("define NAME for conditional compilation ({IF defined(NAME)}, {IF hasvalue(NAME, 'VALUE')}), "
               "beside stvm.toml's [project] defines")


LIBRARY_HELP = ("load the folder or .plcproj DIR as library NAME, its POUs and types reachable as NAME.X "
                "(beside stvm.toml's [libraries])")


LIBRARY_PARAM_HELP = ("set parameter PARAM of library LIB (a constant of its parameter list, e.g. "
                      "TcUnit.xUnitEnablePublish=TRUE) to VALUE, an ST literal (beside stvm.toml's "
                      "[libraries.LIB] parameters)")


class UsageError(Exception):
    """A bad command line; printed as `stvm: error: message`, exit 2."""


def error(message: str, code: int = EXIT_USAGE) -> int:
    """Print `stvm: error: message` on stderr and return `code` (a command's `return usage(...)`)."""
    from stvm.diagnostics import printable   # lazy: start-up
    print(f"stvm: error: {printable(message)}", file=sys.stderr)
    return code


def usage(message: str) -> int:
    return error(message, EXIT_USAGE)


def require_files(files: Iterable[str | Path], what: str = "file") -> None:
    """Every path exists, else a UsageError `no such file: PATH`."""
    for f in files:
        if not Path(f).exists():
            raise UsageError(f"no such {what}: {f}")


def print_diagnostics(diags, sources) -> None:
    from stvm.diagnostics import render   # lazy: start-up
    for d in diags:
        sys.stderr.write(render(d, sources))


def compile_errors(diags, sources) -> int:
    """Print the diagnostics and the error count; EXIT_COMPILE."""
    print_diagnostics(diags, sources)
    print(f"{sum(d.is_error for d in diags)} error(s)", file=sys.stderr)
    return EXIT_COMPILE


def add_project_options(parser, defines: bool = True) -> None:
    """`--sysmac NAME=VALUE`, `--dialect NAME` and (with `defines`) `--define NAME[=VALUE]`:
    what a command line adds to the manifest's settings."""
    parser.add_argument("--sysmac", action="append", default=None, metavar="NAME=VALUE", help=SYSMAC_HELP)
    parser.add_argument("--dialect", choices=DIALECTS, help=DIALECT_HELP)
    if defines:
        parser.add_argument("--define", action="append", metavar="NAME[=VALUE]", help=DEFINE_HELP)
    parser.add_argument("--library", action="append", metavar="NAME=DIR", help=LIBRARY_HELP)
    parser.add_argument("--library-param", action="append", metavar="LIB.PARAM=VALUE", help=LIBRARY_PARAM_HELP)


def project_options(args) -> "Options":
    """The driver's `Options` from a parsed command line (the options it does not have are
    left at their defaults)."""
    from stvm.project import Options   # lazy: start-up
    given = vars(args)
    return Options(sysmac=tuple(given.get("sysmac") or ()), dialect=given.get("dialect"),
                   defines=tuple(given.get("define") or ()),
                   libraries=_libraries(given.get("library") or ()),
                   use_cache=not given.get("no_cache", False),
                   library_parameters=_library_parameters(given.get("library_param") or ()))


def _libraries(items) -> tuple[tuple[str, str], ...]:
    """`--library NAME=DIR` items as (name, folder) pairs."""
    pairs = []
    for item in items:
        if isinstance(item, tuple):
            pairs.append(item)
            continue
        name, sep, folder = str(item).partition("=")
        if not sep or not name.strip().isidentifier() or not folder.strip():
            raise UsageError(f"--library {item!r}: expected NAME=DIR (NAME an identifier, DIR a folder or a .plcproj)")
        pairs.append((name.strip(), folder.strip()))
    return tuple(pairs)


def _library_parameters(items) -> tuple[tuple[str, str, str], ...]:
    """`--library-param LIB.PARAM=VALUE` items as (library, parameter, ST text)."""
    if not items:
        return ()
    from stvm.libraries import LibraryError, parse_parameter_option   # lazy: start-up (rare option)
    out = []
    for item in items:
        if isinstance(item, tuple):
            out.append(item)
            continue
        try:
            out.append(parse_parameter_option(str(item)))
        except LibraryError as exc:
            raise UsageError(str(exc)) from None
    return tuple(out)


def resolve_project(args, files=None) -> "ProjectSpec":
    """The project the command line names (`args.files`, or `files`), resolved by the driver;
    a setting, dialect or manifest that cannot be used is a UsageError."""
    from stvm.project import resolve   # lazy: start-up
    paths = list(args.files if files is None else files)
    options = project_options(args)   # a malformed option is reported before a missing file
    require_files(paths)
    try:
        return resolve(paths, options)
    except ValueError as exc:   # SettingError, ManifestError: they name the file and the value
        raise UsageError(str(exc)) from exc
