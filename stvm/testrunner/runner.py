"""Run a TcUnit (or CfUnit) test project on the virtual clock and read back what TcUnit found.

The project is loaded by the driver (stvm/project.py) with its test framework as a library
(`--library TcUnit=DIR`, `[libraries]`); the framework itself is not changed and not imitated:
its PROGRAM calls `TcUnit.RUN()` every cycle, TcUnit runs the suites, records the results in
its own function blocks and logs them through ADSLOGSTR, one message per 10 ms (its
`FB_AdsLogStringMessageFifoQueue`). stvm only

* collects every ADSLOGSTR message (the run context's `ads_log` sink, stdlib/tc2_system.py) in
  the order TcUnit sends them;
* runs scan after scan until TcUnit's runner says every suite has finished
  (`GVL_TcUnit.TcUnitRunner.AllTestSuitesFinished`), its result logger has queued the final
  summary (`…TcUnitRunner.AdsTestResultLogger.PrintedFinalTestResults`) and its message queue
  is empty (`GVL_TcUnit.AdsMessageQueue.MemRingBuffer.nCount = 0`), or the time limit passes;
* reads each suite's tests from the suite instances (`FB_TestSuite.Tests[i]`, TcUnit's `FB_Test`:
  name, finished, skipped, failed, first assertion message, number of asserts, duration), the
  data TcUnit's `FB_TestResults` copies for its own report;
* attaches to each test the `FAILED TEST 'suite@test', EXP: …, ACT: …` messages TcUnit logged
  for it (`FB_AdsAssertMessageFormatter`).

The variable names above are TcUnit's, with the framework library's name in them: for a library
loaded as NAME the runner reads `GVL_NAME.NAMERunner…` (CfUnit: `GVL_CfUnit.CfUnitRunner`).
"""

from __future__ import annotations

import re
import shutil
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterator

from stvm.project import ProjectSpec, load, parse_duration

DEFAULT_TIMEOUT_NS = 120 * 1_000_000_000
DEFAULT_SCAN = "10ms"
FRAMEWORKS = ("TcUnit", "CfUnit")
JUNIT_FILE_NAME = "tcunit_xunit_testresults.xml"   # TcUnit's default file name (GVL_Param_TcUnit.xUnitFilePath)

# `FAILED TEST 'PRG_TEST.fbSuite@TestName', EXP: 1, ACT: 2, MSG: text` (FB_AdsAssertMessageFormatter)
FAILED_TEST = re.compile(r"FAILED TEST '(?P<suite>[^@']*)@(?P<test>.*?)'(?:, |$)")


class TestRunError(Exception):
    """A test project that cannot run: no framework library, not a TcUnit-shaped framework, no
    PROGRAM. The message is one line; the command exits 2."""


@dataclass
class TestCase:
    suite: str                 # the suite's instance path, as TcUnit names it (PRG_TEST.fbSuite)
    name: str                  # the test's name (TEST('name'), without a `disabled_` prefix)
    finished: bool
    skipped: bool
    failed: bool
    asserts: int
    duration_s: float          # virtual time, TcUnit's measure (100 ns counter)
    message: str               # the message of the first failed assertion (TcUnit keeps the first)
    failures: list[str] = field(default_factory=list)   # TcUnit's FAILED TEST lines for this test

    @property
    def id(self) -> str:
        return f"{self.suite}::{self.name}"

    @property
    def status(self) -> str:
        if self.failed:
            return "failed"
        if self.skipped:
            return "skipped"
        return "passed" if self.finished else "unfinished"


@dataclass
class SuiteResult:
    name: str
    path: str                  # the ST path stvm reads it by (Main.fbSuite)
    tests: list[TestCase]
    finished: bool
    duration_s: float


@dataclass
class TestRun:
    suites: list[SuiteResult]
    messages: list[tuple[str, str]]        # (error|warning|hint, text), in the order sent
    finished: bool                         # TcUnit finished and its log is drained
    scans: int
    virtual_ns: int
    wall_s: float
    timed_out: bool = False
    fault: object | None = None            # a RuntimeFault
    fault_test: str | None = None          # `suite::test` running when the fault happened
    junit_xml: bytes | None = None         # what TcUnit's FB_xUnitXmlPublisher wrote
    sources: dict = field(default_factory=dict)
    project_warnings: list = field(default_factory=list)

    @property
    def tests(self) -> list[TestCase]:
        return [t for s in self.suites for t in s.tests]

    def unfinished_suites(self) -> list[SuiteResult]:
        return [s for s in self.suites if not s.finished]


def framework_library(spec: ProjectSpec, wanted: str | None = None) -> str:
    """The name of the test framework library: `[test] library`, else the library named TcUnit or
    CfUnit among the project's (`--library`, `[libraries]`)."""
    from stvm.libraries import LibraryError, from_manifest   # lazy: start-up
    table = spec.manifest.get("test", {}) if isinstance(spec.manifest.get("test"), dict) else {}
    wanted = wanted or table.get("library")
    names = [name for name, _ in spec.libraries]
    try:
        names += [lib.name for lib in from_manifest(spec.manifest, spec.root, names)]
    except LibraryError:
        pass    # reported when the project loads
    if wanted:
        for name in names:
            if name.lower() == wanted.lower():
                return name
        raise TestRunError(f"the test framework library {wanted} is not loaded: give --library {wanted}=DIR "
                           f"(the folder of your copy of it) or add it to stvm.toml's [libraries]")
    for framework in FRAMEWORKS:
        for name in names:
            if name.lower() == framework.lower():
                return name
    raise TestRunError("no TcUnit library: give --library TcUnit=DIR (the folder of your copy of TcUnit, "
                       "e.g. its TcUnit/TcUnit folder with TcUnit.plcproj) or add it to stvm.toml's [libraries]")


def check_library_folders(spec: ProjectSpec) -> None:
    """Every library folder exists (a missing one is a TestRunError naming it, before loading)."""
    from stvm.libraries import LibraryError, from_manifest   # lazy: start-up
    given = [name for name, _ in spec.libraries]
    try:
        manifest_libs = [(lib.name, lib.path) for lib in from_manifest(spec.manifest, spec.root, given)]
    except LibraryError as exc:
        raise TestRunError(str(exc)) from None
    for name, folder in list(spec.libraries) + manifest_libs:
        if not Path(folder).exists():
            raise TestRunError(f"library {name}: no such folder or .plcproj: {folder}")


def with_junit(spec: ProjectSpec, library: str, file_name: str = JUNIT_FILE_NAME) -> ProjectSpec:
    """`spec` with the framework's xUnit publisher switched on and writing `file_name` (relative:
    into the folder the run's file FBs are confined to). TcUnit's library parameters
    `xUnitEnablePublish` and `xUnitFilePath` (GVL_Param_TcUnit)."""
    params = ((library, "xUnitEnablePublish", "TRUE"), (library, "xUnitFilePath", f"'{file_name}'"))
    return replace(spec, library_parameters=tuple(spec.library_parameters) + params)


def default_dialect(spec):
    """`spec` read in the twincat dialect when neither the command line nor the manifest names
    one and the project or a library is TwinCAT XML (TcUnit is): its platform functions
    (ADSLOGSTR, GETCPUCOUNTER, …) are TwinCAT's."""
    from stvm.libraries import Library, LibraryError, from_manifest, library_files   # lazy: start-up
    if spec.manifest.get("project", {}).get("dialect") or spec.dialect == "twincat":
        return spec
    tc = (".tcpou", ".tcgvl", ".tcdut", ".tcio", ".plcproj")
    try:
        libs = [Library(n, Path(f)) for n, f in spec.libraries] + from_manifest(spec.manifest, spec.root,
                                                                                [n for n, _ in spec.libraries])
        files = list(spec.files) + [f for lib in libs for f in library_files(lib)]
    except (LibraryError, OSError):
        return spec     # reported when the project loads
    if any(Path(f).suffix.lower() in tc for f in files) or any(Path(f).suffix.lower() == ".plcproj" for _, f in spec.libraries):
        return replace(spec, settings=spec.settings.with_overrides(["dialect=twincat"]))
    return spec


class _Paths:
    """The framework's variables the runner reads, resolved once (a global variable list's
    variable is reached as `GVL.x` or, when its list is not qualified, as `x`)."""

    def __init__(self, vm, library: str) -> None:
        self.vm = vm
        gvl = f"GVL_{library}"
        runner = self._find(f"{gvl}.{library}Runner", f"{library}Runner")
        queue = self._find(f"{gvl}.AdsMessageQueue", "AdsMessageQueue")
        if runner is None or queue is None:
            raise TestRunError(f"library {library} is not TcUnit-shaped: stvm reads {gvl}.{library}Runner and "
                               f"{gvl}.AdsMessageQueue (TcUnit's runner and message queue), which it does not declare")
        self.all_finished = vm.accessor(f"{runner}.AllTestSuitesFinished")
        self.printed_final = vm.accessor(f"{runner}.AdsTestResultLogger.PrintedFinalTestResults")
        self.queued = vm.accessor(f"{queue}.MemRingBuffer.nCount")
        self.current_test = self._find(f"{gvl}.CurrentTestNameBeingCalled", "CurrentTestNameBeingCalled")
        # TcUnit's pointer to the suite being called (MiniUnit has none)
        self.current_suite = self._find(f"{gvl}.CurrentTestSuiteBeingCalled^.InstancePath",
                                        "CurrentTestSuiteBeingCalled^.InstancePath")

    def _find(self, *candidates: str) -> str | None:
        """The first of `candidates` the program declares (a path through a pointer is only
        checked to name declared members: the pointer may still be NULL)."""
        from stvm.runtime.access import PathError, UnboundInOut   # lazy: start-up
        for path in candidates:
            try:
                self.vm.type_of(path)
                return path
            except UnboundInOut:   # a NULL pointer before the first scan (a PathError too): declared
                return path
            except PathError:
                continue
            except Exception:   # noqa: BLE001 - any other failure to follow a declared pointer
                return path
        return None

    def done(self) -> bool:
        return bool(self.all_finished.get()) and bool(self.printed_final.get()) and self.queued.get() == 0


def find_suites(vm, library: str) -> list[tuple[str, str]]:
    """(ST path, FB qualname) of every instance of an FB extending LIBRARY.FB_TestSuite: program
    variables, global variables, FB members and array elements, in declaration order."""
    from stvm.semantics import types as t   # lazy: start-up
    model = vm.model
    base_key = f"{library}\\fb_testsuite".lower()
    is_suite: dict[str, bool] = {}

    def suite_type(key: str) -> bool:
        if key not in is_suite:
            is_suite[key] = False    # a cycle ends here
            pou = model.pous.get(key)
            seen = 0
            while pou is not None and pou.base and seen < 64:
                if pou.base.lower() == base_key:
                    is_suite[key] = True
                    break
                pou, seen = model.pous.get(pou.base.lower()), seen + 1
        return is_suite[key]

    found: list[tuple[str, str]] = []
    lib_prefix = library.lower() + "\\"
    holds: dict[str, bool] = {}

    def may_hold(ty) -> bool:
        """Whether a value of `ty` is or contains a suite (so arrays of other blocks are not walked)."""
        while isinstance(ty, t.ArrayType):
            ty = ty.element
        if not isinstance(ty, t.FBType) or ty.is_program:
            return False
        key = ty.qualname.lower()
        if key not in holds:
            holds[key] = False    # a cycle ends here
            if suite_type(key):
                holds[key] = True
            elif not key.startswith(lib_prefix):     # the framework's own blocks hold no user suites
                pou = model.pous.get(key)
                holds[key] = any(may_hold(v.type) for v in (pou.variables.values() if pou else ())
                                 if v.section in ("VAR", "VAR_OUTPUT", "VAR_INPUT"))
        return holds[key]

    def visit(path: str, ty, depth: int) -> None:
        if depth > 8 or len(found) > 10_000 or not may_hold(ty):
            return
        if isinstance(ty, t.ArrayType) and ty.dims:
            if ty.length > 10_000:
                return
            for index in _indices(ty.dims):
                visit(f"{path}[{', '.join(map(str, index))}]", ty.element, depth + 1)
            return
        if not isinstance(ty, t.FBType) or ty.is_program:
            return
        key = ty.qualname.lower()
        if suite_type(key):
            found.append((path, ty.qualname))
            return
        if key.startswith(lib_prefix):     # the framework's own blocks hold no user suites
            return
        pou = model.pous.get(key)
        for var in (pou.variables.values() if pou else ()):
            if var.section in ("VAR", "VAR_OUTPUT", "VAR_INPUT"):
                visit(f"{path}.{var.name}", var.type, depth + 1)

    for name, _inst, qualname in vm.instances.values():
        pou = model.pous.get(qualname.lower())
        for var in (pou.variables.values() if pou else ()):
            if var.section in ("VAR", "VAR_OUTPUT", "VAR_INPUT", "VAR_STAT"):
                visit(f"{name}.{var.name}", var.type, 1)
    for var in model.globals.values():
        visit(var.name, var.type, 1)
    return found


def _indices(dims) -> Iterator[tuple[int, ...]]:
    if not dims:
        yield ()
        return
    (lo, hi), rest = dims[0], dims[1:]
    for i in range(lo, hi + 1):
        for tail in _indices(rest):
            yield (i,) + tail


def _text(value) -> str:
    return value.decode("latin-1") if isinstance(value, (bytes, bytearray)) else str(value)


def read_suite(vm, path: str, project_name: str) -> SuiteResult:
    """A suite's tests as its FB_TestSuite instance holds them (TcUnit's FB_Test members)."""
    get = vm.get
    name = _suite_name(_text(get(f"{path}.InstancePath")), project_name) or path
    count = int(get(f"{path}.NumberOfTests"))
    bound = vm.type_of(f"{path}.Tests").dims[0]
    tests = []
    for i in range(bound[0], min(bound[0] + count, bound[1] + 1)):
        at = f"{path}.Tests[{i}]"
        tests.append(TestCase(
            suite=name, name=_text(get(f"{at}.TestName")), finished=bool(get(f"{at}.TestIsFinished")),
            skipped=bool(get(f"{at}.TestIsSkipped")), failed=bool(get(f"{at}.TestIsFailed")),
            asserts=int(get(f"{at}.NumberOfAssertions")), duration_s=float(get(f"{at}.Duration")),
            message=_text(get(f"{at}.AssertionMessage"))))
    finished = count > 0 and all(tc.finished or tc.skipped for tc in tests)
    return SuiteResult(name, path, tests, finished, float(get(f"{path}.Duration")))


def _suite_name(instance_path: str, project_name: str) -> str:
    """TcUnit's name of a suite: its instance path without what comes before the project's
    name and the project's name (F_RemoveInstancePathAndProjectNameFromTestInstancePath)."""
    marker = project_name + "."
    for _ in range(2):
        at = instance_path.find(marker)
        if at >= 0:
            instance_path = instance_path[at + len(marker):]
    return instance_path


def severity(mask: int) -> str:
    from stvm.stdlib.tc2_system import severity as word   # lazy: start-up
    return word(mask)


def run_tests(spec: ProjectSpec, *, library: str | None = None, scan: str | int | None = None,
              timeout_ns: int | None = None, junit: bool = False,
              on_message: Callable[[str, str], None] | None = None, watchdog_s: float | None = 5.0) -> TestRun:
    """Load `spec` and run it until TcUnit has finished (see the module docstring). Raises
    LoadError (compile errors), TestRunError (not a test project). `on_message(severity, text)`
    sees each ADSLOGSTR message as it is sent."""
    from stvm.runtime.vm import RuntimeFault   # lazy: start-up
    from stvm.runtime.watchdog import Watchdog   # lazy: start-up
    library = framework_library(spec, library)
    check_library_folders(spec)
    table = spec.manifest.get("test", {}) if isinstance(spec.manifest.get("test"), dict) else {}
    scan = scan or table.get("scan") or DEFAULT_SCAN
    if timeout_ns is None:
        timeout_ns = parse_duration(table["timeout"]) if "timeout" in table else DEFAULT_TIMEOUT_NS
    files_dir = Path(tempfile.mkdtemp(prefix="stvm-test-files-")) if junit else None
    try:
        if junit:
            spec = with_junit(spec, library)
        project = load(spec)
        return _run(project, library, scan, timeout_ns, files_dir, on_message, watchdog_s, RuntimeFault, Watchdog)
    finally:
        if files_dir is not None:
            shutil.rmtree(files_dir, ignore_errors=True)


def _run(project, library, scan, timeout_ns, files_dir, on_message, watchdog_s, RuntimeFault, Watchdog) -> TestRun:
    from stvm.project import nothing_to_run   # lazy: start-up
    why = nothing_to_run(project)
    if why:
        raise TestRunError(why + f" (a test project's PROGRAM declares the suites and calls {library}.RUN())")
    messages: list[tuple[str, str]] = []

    def sink(mask: int, text: str) -> None:
        word = severity(mask)
        messages.append((word, text))
        if on_message is not None:
            on_message(word, text)

    if files_dir is not None:   # the SysFile functions' file root (stdlib/sys_file.py): a private folder
        project.files_root = str(files_dir)
    vm = project.start(scan=scan)
    vm.ctx.ads_log = sink
    paths = _Paths(vm, library)
    limit_scans = max(1, -(-timeout_ns // vm.base_ns))
    started = time.perf_counter()
    fault = fault_test = fault_suite = None
    try:
        with Watchdog(vm, watchdog_s) if watchdog_s else _null():
            vm.run(cycles=limit_scans, until=paths.done)
    except RuntimeFault as exc:
        fault = exc
        fault_test, fault_suite = _read_text(vm, paths.current_test), _read_text(vm, paths.current_suite)
    wall = time.perf_counter() - started
    finished = fault is None and paths.done()
    name = _project_name(project)
    suites = [read_suite(vm, path, name) for path, _ in find_suites(vm, library)]
    by_id = {tc.id: tc for s in suites for tc in s.tests}
    for word, text in messages:
        match = FAILED_TEST.match(text)
        if match:
            test = by_id.get(f"{match['suite']}::{match['test']}") or _by_suffix(by_id, match['suite'], match['test'])
            if test is not None:
                test.failures.append(text)
    if fault is not None and fault_test:
        suite = _suite_name(fault_suite, name) if fault_suite else None
        running = [s.name for s in suites if not s.finished]
        suite = suite or (running[0] if running else None)
        if suite:
            fault_test = f"{suite}::{fault_test}"
    junit_xml = None
    if files_dir is not None and finished:
        written = files_dir / JUNIT_FILE_NAME
        junit_xml = written.read_bytes() if written.is_file() else None
    return TestRun(suites, messages, finished, vm.scan_count, vm.now_ns, wall,
                   timed_out=fault is None and not finished, fault=fault, fault_test=fault_test,
                   junit_xml=junit_xml, sources=project.sources, project_warnings=list(project.warnings))


def _read_text(vm, path: str | None) -> str | None:
    """A STRING variable's text, or None (no such variable, or not readable after the fault)."""
    if path is None:
        return None
    try:
        return _text(vm.get(path)) or None
    except Exception:   # noqa: BLE001 - a pointer left invalid by the fault: the name is a nicety
        return None


def _by_suffix(by_id: dict, suite: str, test: str):
    """The test a FAILED TEST line names when TcUnit's suite name differs from stvm's by a prefix."""
    for key, tc in by_id.items():
        if tc.name == test and (tc.suite.endswith(suite) or suite.endswith(tc.suite)):
            return tc
    return None


def _project_name(project) -> str:
    manifest = project.manifest or {}
    root = project.root
    return str(manifest.get("project", {}).get("name") or (root.name if root is not None else "stvm"))


class _null:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
