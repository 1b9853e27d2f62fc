"""The project manifest (`stvm.toml`), read and checked at the edge.

    [project]
    files = ["Types.st", "Main.st"]     # the project's sources, in this folder (default: every *.st)
    encoding = "utf-8"                  # how the sources are encoded (default UTF-8)
    dialect = "sysmac"                  # iec, sysmac (default), codesys or twincat (README)
    defines = ["SIMULATION"]            # conditional compilation: {IF defined(SIMULATION)} (README)

    [sysmac]                            # Sysmac UNCERTAIN settings of the project (README)
    int_div_zero = "zero"

    [test]                              # a TcUnit test project (stvm test, pytest): docs/unit_tests.md
    library = "TcUnit"
    timeout = "120s"

    [demo]                              # makes `stvm run FILE` the demo (stvm/demo.py)
    title = "thesis PnP demo"
    scenario = "scenarios/pnp_demo.toml"
    step_variable = "PnP_Example_Instance.Prg_Step"
    cycle_from = 26
    cycle_to = 10
    status = ["Cobot.Connected"]        # rows of the live status
    errors = ["Connect_ErrorDescrip"]   # STRING variables shown in both views when not empty

Every problem is a `ManifestError` whose message names the file, the table and key, and what
is allowed; nothing in a manifest can end in a traceback or be silently misread (a string
where a list belongs is not read letter by letter).
"""

from __future__ import annotations

import codecs
import re
from pathlib import Path
from typing import Any

MANIFEST = "stvm.toml"

# a flag a manifest may declare for its demo (`[demo] cycles_flag`): long form, lower case
_FLAG = re.compile(r"--[a-z][a-z0-9]*(-[a-z0-9]+)*")


class ManifestError(ValueError):
    """A project manifest (`stvm.toml`) that cannot be used; the message names the file."""


def _string_list(value: Any) -> bool:
    return isinstance(value, list) and all(isinstance(v, str) for v in value)


def _integer(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


# table -> key -> (check, what is allowed); a table given as None takes any keys (checked elsewhere)
_SCHEMA: dict[str, dict[str, tuple[Any, str]] | None] = {
    "project": {
        "files": (_string_list, "a list of file names, e.g. files = [\"Main.st\"]"),
        "encoding": (lambda v: isinstance(v, str), "an encoding name, e.g. encoding = \"cp1252\""),
        "dialect": (lambda v: isinstance(v, str), "a dialect name, e.g. dialect = \"twincat\" (iec, sysmac, "
                                                  "codesys, twincat)"),
        "defines": (_string_list, "a list of defines for conditional compilation, e.g. defines = [\"SIMULATION\", "
                                  "\"AXES=2\"] (NAME or NAME=VALUE)"),
        "name": (lambda v: isinstance(v, str), "a string"),
        "description": (lambda v: isinstance(v, str), "a string"),
    },
    "sysmac": None,     # NAME = VALUE, checked by stvm.settings (names and allowed values)
    "hmi": None,        # the web HMI's pages, checked by stvm/hmi when it starts
    "limits": None,     # operator limits of variables, checked by stvm/frontend/limits.py
    "opcua": None,      # front ends and tools that read their own table
    "lint": None,
    "libraries": None,  # NAME = "folder or .plcproj", checked by stvm/libraries.py
    "files": {          # the folder SysFile/SysDir work in (stvm/stdlib/sys_file.py)
        "root": (lambda v: isinstance(v, str) and v != "", "a folder, relative to the manifest"),
    },
    "demo": {
        "scenario": (lambda v: isinstance(v, str), "a scenario file name, relative to the manifest"),
        "step_variable": (lambda v: isinstance(v, str), "a variable path, e.g. \"Main.step\""),
        "cycle_from": (_integer, "an integer (the step a cycle ends in)"),
        "cycle_to": (_integer, "an integer (the step a new cycle starts with)"),
        "status": (_string_list, "a list of variable paths"),
        "errors": (_string_list, "a list of STRING variable paths"),
        "title": (lambda v: isinstance(v, str), "a string (the demo's name in the status view)"),
        "description": (lambda v: isinstance(v, str), "a string"),
        "cycles": (lambda v: _integer(v) and v >= 0,
                   "a number of complete cycles after which the demo stops (0: no limit)"),
        "cycles_flag": (lambda v: isinstance(v, str) and _FLAG.fullmatch(v) is not None,
                        "a command-line flag, e.g. \"--pnp-cycles\", that sets `cycles` for a run"),
    },
    # a TcUnit test project (`stvm test`, the pytest plugin: docs/unit_tests.md)
    "test": {
        "library": (lambda v: isinstance(v, str) and v.isidentifier(),
                    "the name of the test framework library, e.g. library = \"TcUnit\""),
        "scan": (lambda v: isinstance(v, str), "the task period of the test run, e.g. scan = \"10ms\""),
        "timeout": (lambda v: isinstance(v, str), "virtual time the tests may take, e.g. timeout = \"120s\""),
    },
}


def read_manifest(path: Path) -> dict:
    """The checked contents of a `stvm.toml` (a plain dict, as TOML gives it)."""
    import tomllib   # lazy: start-up (a run without a manifest never parses TOML)
    from stvm.source import SourceError, read_limited   # lazy: start-up (as tomllib)
    try:
        data = tomllib.loads(read_limited(path, "project manifest").decode("utf-8"))
    except OSError as exc:
        raise ManifestError(f"{path}: cannot read the project manifest: {exc.strerror or exc}") from exc
    except SourceError as exc:
        raise ManifestError(f"{path}: {exc.message}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ManifestError(f"{path}: not valid TOML: {exc}") from exc
    except UnicodeDecodeError as exc:
        raise ManifestError(f"{path}: not valid TOML: the file is not UTF-8 ({exc.reason})") from exc
    return check_manifest(data, path)


def check_manifest(data: dict, path: Path | str) -> dict:
    unknown = sorted(set(data) - set(_SCHEMA))
    if unknown:
        raise ManifestError(f"{path}: unknown table or key {', '.join(unknown)}; known tables: "
                            f"{', '.join('[' + t + ']' for t in _SCHEMA)}")
    for table, keys in _SCHEMA.items():
        if table not in data:
            continue
        value = data[table]
        if not isinstance(value, dict):
            what = "a table of NAME = VALUE" if keys is None else "a table"
            raise ManifestError(f"{path}: [{table}] must be {what}, got {_kind(value)}")
        if keys is None:
            continue
        extra = sorted(set(value) - set(keys))
        if extra:
            raise ManifestError(f"{path}: [{table}]: unknown key(s) {', '.join(extra)}; known: {', '.join(keys)}")
        for key, (ok, allowed) in keys.items():
            if key in value and not ok(value[key]):
                raise ManifestError(f"{path}: [{table}] {key} must be {allowed}, got {_kind(value[key])}")
    project = data.get("project", {})
    if "encoding" in project:
        try:
            codecs.lookup(project["encoding"])
        except LookupError:
            raise ManifestError(f"{path}: [project] encoding: unknown encoding {project['encoding']!r}") from None
    for name in project.get("files", []):
        if not name.strip():
            raise ManifestError(f"{path}: [project] files: an empty file name")
    return data


def project_files(manifest: dict, folder: Path, manifest_path: Path) -> list[Path] | None:
    """The files `[project] files` lists (None when it lists none); a listed file that does not
    exist is an error naming the manifest."""
    listed = manifest.get("project", {}).get("files")
    if not listed:
        return None
    files = []
    for name in listed:
        file = folder / name
        if not file.is_file():
            what = "is a folder" if file.is_dir() else "does not exist"
            raise ManifestError(f"{manifest_path}: [project] files: {name!r} {what} ({file})")
        files.append(file)
    return files


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, (int, float)):
        return f"the number {value}"
    if isinstance(value, str):
        return f"the string {value[:60]!r}"
    if isinstance(value, list):
        return "a list" + (f" containing {_kind(next(v for v in value if not isinstance(v, str)))}"
                           if any(not isinstance(v, str) for v in value) else "")
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__
