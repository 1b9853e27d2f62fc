"""Shared helpers for the core's tests (syntax, semantics, lower, runtime, cli).

The common shapes:

    values = run_st(SOURCE, cycles=3, prints=["Main.x"])      # raw API values after 3 scans
    text = run_st(SOURCE, cycles=3, prints=["Main.x"], fmt=True)  # `--print` text
    rc, out, err = cli(["run", path, "--cycles", "1"])         # cli.main in-process, captured

`StCase` + `run_cases(cases)` compile many small PROGRAMs in ONE load and snapshot the
expected variables after each case's cycle count; a case that breaks the shared load or faults
is re-run alone, so one stvm bug never hides the others.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import io
import os
import re
import shutil
import tempfile
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import pytest

import stvm
from stvm.settings import SysmacSettings

_WORK = Path(tempfile.mkdtemp(prefix="stvm-core-tests-"))
atexit.register(shutil.rmtree, _WORK, ignore_errors=True)


# ---------------------------------------------------------------- files
def write_st(source: str, name: str | None = None, folder: Path | None = None) -> Path:
    """Write ST text to a fresh file (named by content hash unless `name` is given)."""
    digest = hashlib.sha1(source.encode("utf-8", "surrogatepass")).hexdigest()[:12]
    folder = folder or (_WORK / digest)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / (name or f"prog_{digest}.st")
    path.write_text(source, encoding="utf-8")
    return path


def write_files(files: Mapping[str, str]) -> list[Path]:
    """Write several files into one fresh folder; returns their paths in the given order."""
    digest = hashlib.sha1(repr(sorted(files.items())).encode()).hexdigest()[:12]
    folder = _WORK / f"multi_{digest}"
    return [write_st(text, name, folder) for name, text in files.items()]


def load_st(source: str | Mapping[str, str], **kwargs) -> "stvm.Project":
    paths = write_files(source) if isinstance(source, Mapping) else [write_st(source)]
    try:
        return stvm.load(paths, use_cache=kwargs.pop("use_cache", False), **kwargs)
    except stvm.LoadError as exc:
        exc.args = (exc.render(),)         # show the diagnostics in the test report
        raise


def start_st(source: str | Mapping[str, str], scan: str = "10ms", **kwargs):
    return load_st(source, **kwargs).start(scan=scan)


def run_st(source: str | Mapping[str, str], cycles: int = 1, prints: Sequence[str] = (),
           scan: str = "10ms", sets: Mapping[str, Any] | None = None, fmt: bool = False,
           **kwargs) -> dict[str, Any]:
    """Load, apply `sets`, run `cycles` scans, return {path: value} (formatted if `fmt`)."""
    vm = start_st(source, scan=scan, **kwargs)
    for path, value in (sets or {}).items():
        vm[path] = value
    vm.run(cycles=cycles)
    return {p: (vm.format(p) if fmt else vm[p]) for p in prints}


# ---------------------------------------------------------------- the CLI, in process
def cli(argv: Sequence[str | os.PathLike]) -> tuple[int, str, str]:
    """Run `stvm.cli.main(argv)` with captured stdout/stderr; (exit code, stdout, stderr).

    An exception escaping `main` is turned into a traceback on the captured stderr, exactly
    what a user would see, so tests can assert that none ever appears."""
    from stvm.cli import main
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in argv])
        except SystemExit as exc:
            rc = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        except BaseException:  # noqa: BLE001 - what the user would see
            traceback.print_exc(file=err)
            rc = 99
    return rc, out.getvalue(), err.getvalue()


def check_text(source: str, name: str = "case.st", dialect: str | None = None) -> tuple[int, str]:
    """`stvm check` on one file (written to a fresh folder); (exit code, stderr). Without
    `dialect`, the default one (iec: a file without a manifest)."""
    path = write_st(source, name)
    rc, _, err = cli(["check", path] + (["--dialect", dialect] if dialect else []))
    return rc, err


# Tests of Omron behaviour (name rules, BYTE_TO_STRING in hex, STRING[n] counting the NUL, …) run
# in the Sysmac dialect, as the thesis project does through its stvm.toml; the default is IEC.
SYSMAC = SysmacSettings(dialect="sysmac")


# ---------------------------------------------------------------- batched small programs
@dataclass
class StCase:
    """One small PROGRAM (`PROGRAM <name> … END_PROGRAM`, plus any TYPEs/POUs it needs).

    `expect` maps a variable path relative to the program (`x`, `fb.Q`, `arr[2]`) to a value:
    a `str` is compared with the `--print` text (`vm.format`), anything else with the raw API
    value (`vm[...]`)."""

    name: str
    source: str
    expect: Mapping[str, Any]
    cycles: int = 1
    xfail: str | None = None
    program: str | None = None       # defaults to the name after the first PROGRAM keyword
    extra: str = ""                  # shared declarations (types, FBs) that may appear once

    def prog(self) -> str:
        if self.program:
            return self.program
        m = re.search(r"^\s*PROGRAM\s+([A-Za-z_][A-Za-z0-9_]*)", self.source, re.I | re.M)
        assert m, f"case {self.name}: no PROGRAM"
        return m.group(1)


def case_params(cases: Iterable[StCase]):
    """pytest.param per case, with the strict xfail mark for known stvm bugs."""
    out = []
    for c in cases:
        marks = [pytest.mark.xfail(strict=True, reason=f"stvm bug: {c.xfail}")] if c.xfail else []
        out.append(pytest.param(c, id=c.name, marks=marks))
    return out


class CaseOutcome:
    def __init__(self, values: dict[str, Any] | None = None, error: str | None = None) -> None:
        self.values = values or {}
        self.error = error


def _snapshot(vm, case: StCase) -> dict[str, Any]:
    out = {}
    for rel, want in case.expect.items():
        path = f"{case.prog()}.{rel}"
        try:
            out[rel] = vm.format(path) if isinstance(want, str) else vm[path]
        except Exception as exc:  # noqa: BLE001 - reported per case
            out[rel] = f"<{type(exc).__name__}: {exc}>"
    return out


def _run_group(cases: list[StCase], settings: SysmacSettings | None = None) -> dict[str, CaseOutcome]:
    text = "\n".join(c.source for c in cases)
    project = load_st(text, settings=settings)
    vm = project.start(scan="10ms")
    results: dict[str, CaseOutcome] = {}
    done = 0
    for cycles in sorted({c.cycles for c in cases}):
        vm.run(cycles=cycles - done)
        done = cycles
        for c in cases:
            if c.cycles == cycles:
                results[c.name] = CaseOutcome(_snapshot(vm, c))
    return results


def run_cases(cases: Sequence[StCase], settings: SysmacSettings | None = None) -> dict[str, CaseOutcome]:
    """Run all cases in one load; on a load error or fault, run each case on its own. The cases
    are Sysmac code (STRING[n] counting the NUL, …) unless `settings` says otherwise."""
    settings = settings or SYSMAC
    names = [c.name for c in cases]
    assert len(names) == len(set(names)), "duplicate case names"
    progs = [c.prog().lower() for c in cases]
    assert len(progs) == len(set(progs)), "duplicate PROGRAM names across cases"
    try:
        return _run_group(list(cases), settings)
    except Exception:  # noqa: BLE001 - isolate the offender
        pass
    results = {}
    for c in cases:
        try:
            results.update(_run_group([c], settings))
        except stvm.LoadError as exc:
            results[c.name] = CaseOutcome(error="load error:\n" + exc.render())
        except Exception as exc:  # noqa: BLE001
            results[c.name] = CaseOutcome(error=f"{type(exc).__name__}: {exc}")
    return results


def assert_case(case: StCase, outcome: CaseOutcome) -> None:
    assert outcome.error is None, f"{case.name}: {outcome.error}"
    assert dict(outcome.values) == dict(case.expect), f"{case.name}: got {outcome.values}"


# ---------------------------------------------------------------- misc
NO_TRACEBACK = re.compile(r"Traceback \(most recent call last\)")


def assert_no_traceback(text: str) -> None:
    assert not NO_TRACEBACK.search(text), text
