"""`stvm lsp`: the language server (LSP over stdio, pygls 2).

On open, change and save, the project of the document (its stvm.toml, else its folder:
stvm/lsp/driver.py) is checked with the editor's unsaved buffers; the checker's errors and the
lint findings are published for every file of the project (so an edit in one file updates its
dependents), and the position index (stvm/lsp/index.py) is rebuilt. After a change the
focused check's diagnostics come first, the full check, index and lint once typing pauses
(`edit_cycle`; docs/editor.md "Typing"). The requests
(hover, definition, references, completion, …) read the last index that was built from a
project without syntax errors, so they keep answering while a line is half typed.

Diagnostics carry `source` "stvm" (checker) or "stvm-lint", the code (E…/W… of
stvm/diagnostics/codes.py, SA… of lint), and `codeDescription.href` = the code's page
(docs/error_codes.md#eNNN or docs/lint.md#saNNN of the repository holding the file, or the
`stvm-error:`/`stvm-rule:` URI the VS Code extension resolves with `stvm check|lint --explain`).

Documents are published under the URI the client used for them (`file://host/share/a.st` keeps
its host, `file:///a/../b.st` stays as sent); other files under their resolved path's URI.
"""

from __future__ import annotations

import asyncio
import collections
import json
import os
import logging
import concurrent.futures
import functools
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote, urlparse

from lsprotocol import types as lsp
from pygls.exceptions import JsonRpcException, JsonRpcInternalError, JsonRpcInvalidParams
from pygls.lsp.server import LanguageServer
from pygls.protocol import LanguageServerProtocol

from stvm.heap import collector_paused
from stvm.lsp import features as f
from stvm.lsp import positions as pos
from stvm.lsp.driver import CheckResult, Driver, Stopwatch, is_source, project_identity, stdlib_path
from stvm.lsp.index import Index, build_index
from stvm.lsp.live import DEFAULT_ENDPOINT, LiveValues, format_value, instance_paths
from stvm.semantics import types as t
from stvm.source import is_stdlib_file
from stvm.version import __version__

SOURCE_CHECK, SOURCE_LINT = "stvm", "stvm-lint"
DEBOUNCE_SECONDS = 0.005
"""How long after an edit its check starts: just long enough that changes the client sent
together (a paste, a multi-cursor edit) are taken in one check. Keystrokes that arrive while a
check runs are not checked one by one: the edit cycle (`edit_cycle`) checks the latest text when
that check ends, and a result of older text is not published."""
SETTLE_SECONDS = 0.25
"""How long typing must pause after the focused check's diagnostics before the full check (and
the index, and lint) run: a keystroke during a full check would wait for it."""


def path_of(uri: str) -> Path | None:
    """The file a `file:` URI names; a host other than localhost is kept as a UNC path
    (`file://host/share/a.st` → //host/share/a.st)."""
    try:
        parsed = urlparse(uri)
    except ValueError:
        return None
    if parsed.scheme != "file":
        return None
    path = unquote(parsed.path)
    if parsed.netloc and parsed.netloc.lower() != "localhost":
        path = f"//{parsed.netloc}{path}"
    return Path(path)


def _norm(path: Path) -> str:
    return _resolved(str(path))


@functools.lru_cache(maxsize=4096)
def _resolved(name: str) -> str:
    # memoised: every diagnostic of every publish asks for its file's path, and resolving walks
    # the file system (a symlink changed during a session is not seen: a choice)
    try:
        return str(Path(name).resolve())
    except (OSError, RuntimeError):
        return name


def rule_href(code: str, path: Path, page_name: str = "lint.md") -> str:
    """docs/<page_name>#code of the repository that holds `path`, else a stvm-rule: URI."""
    page = _docs_page(str(path.parent), page_name)
    return page + f"#{code.lower()}" if page else f"stvm-rule:{code}"


@functools.lru_cache(maxsize=256)
def _docs_page(folder: str, page_name: str) -> str | None:
    """The URI of docs/<page_name> in `folder` or the nearest folder above it that has one
    (memoised per folder: a publish links ~1,400 findings of st_src/ to their rules)."""
    start = Path(folder)
    for up in [start, *start.parents]:
        page = up / "docs" / page_name
        try:
            if page.exists():
                return page.as_uri()
        except OSError:
            break
    return None


def error_href(code: str, path: Path) -> str:
    """docs/error_codes.md#e031 of the repository that holds `path`, else `stvm-error:E031`
    (what `stvm check --explain E031` prints)."""
    href = rule_href(code, path, "error_codes.md")
    return f"stvm-error:{code}" if href.startswith("stvm-rule:") else href


def _range(span) -> lsp.Range:
    line = max(span.line - 1, 0)
    col = max(span.column - 1, 0)
    if span.end_line >= span.line and span.end_line > 0:
        end_line = span.end_line - 1
        end_col = max(span.end_column - 1, col + 1 if end_line == line else 0)
    else:
        end_line, end_col = line, col + 1
    return lsp.Range(lsp.Position(line, col), lsp.Position(end_line, end_col))


def live_spots(ix: Index, file: str, first: int, last: int) -> list[tuple]:
    """(occurrence, stvm path, symbol) of each scalar program or global variable on lines
    first..last: what the running VM publishes (an FB's internals have no single path)."""
    instances = instance_paths(ix.model)
    out = []
    for occ in ix.by_file.get(file, ()):
        if occ.line < first or occ.line > last:
            continue
        sym = ix.symbols.get(occ.key)
        if sym is None or isinstance(sym.type, (t.StructType, t.ArrayType, t.FBType, t.InterfaceType)):
            continue
        if occ.key[0] == "global":
            out.append((occ, sym.name, sym))
        elif occ.key[0] == "var":
            pou = ix.pou_by_key.get(occ.key[1])
            if pou is not None and pou.kind == "PROGRAM":
                for instance in instances.get(pou.key, [])[:1]:
                    out.append((occ, f"{instance}.{sym.name}", sym))
    return out


class RequestFailed(JsonRpcException):
    """A request the server understood and refuses (LSP RequestFailed, -32803): the editor
    shows the message (a rename that would clash, a name of the stdlib)."""

    CODE = -32803


_DROPPED = object()

# JSON-RPC 2.0 error codes (section 5.1 of the specification)
PARSE_ERROR, INVALID_REQUEST, METHOD_NOT_FOUND, INVALID_PARAMS = -32700, -32600, -32601, -32602


class _Refused:
    """A message answered with a JSON-RPC error before any handler sees it."""

    def __init__(self, msg_id, code: int, message: str) -> None:
        self.msg_id, self.code, self.message = msg_id, code, message


def _valid_id(value) -> bool:
    return isinstance(value, (int, str)) and not isinstance(value, bool)


class GuardedProtocol(LanguageServerProtocol):
    """pygls, answering what is not a well-formed request as JSON-RPC 2.0 says, never with a
    traceback: a body that is not JSON gets Parse error (-32700, id null: `report_parse_error`);
    JSON that is not a request, notification or response (a number, an array, an object
    without `"jsonrpc": "2.0"` or with an id that is not a number or string) gets Invalid
    Request (-32600); an unknown method, Method not found (-32601); params that do not fit
    the method's schema, Invalid params (-32602), each with the request's id. A notification
    with bad params is ignored (logged to the client), as a notification has no answer."""

    def structure_message(self, data):
        # json.loads calls this for every object, innermost first: only a message is judged
        if not isinstance(data, dict) or "jsonrpc" not in data:
            return data
        msg_id = data.get("id") if _valid_id(data.get("id")) else None
        if data.get("jsonrpc") != "2.0":
            return _Refused(msg_id, INVALID_REQUEST, "not a JSON-RPC 2.0 message (\"jsonrpc\" must be \"2.0\")")
        if "id" in data and data["id"] is not None and msg_id is None:
            return _Refused(None, INVALID_REQUEST, "a request id is a number or a string")
        method = data.get("method")
        if "method" in data and not isinstance(method, str):
            return _Refused(msg_id, INVALID_REQUEST, "a method name is a string")
        if method is not None and "id" in data and method not in self.fm.builtin_features \
                and method not in self.fm.features:
            return _Refused(msg_id, METHOD_NOT_FOUND, f"unknown method {method[:80]!r}")
        try:
            return super().structure_message(data)
        except (JsonRpcInvalidParams, JsonRpcInternalError) as exc:
            if method is None:
                raise
            if msg_id is not None:
                return _Refused(msg_id, INVALID_PARAMS, f"invalid params for {method[:80]}: they do not match the LSP schema")
            self._server.window_log_message(lsp.LogMessageParams(
                lsp.MessageType.Warning, f"stvm: ignored {method[:80]} notification: invalid params ({type(exc).__name__})"))
            return _DROPPED

    def refuse(self, msg_id, code: int, message: str) -> None:
        # written as a plain object: pygls's response types drop an `"id": null`, which
        # JSON-RPC requires when the request's id could not be read
        self._send_data({"jsonrpc": "2.0", "id": msg_id, "error": {"code": code, "message": message}})

    def handle_message(self, message):
        if message is _DROPPED:
            return None
        if isinstance(message, _Refused):
            return self.refuse(message.msg_id, message.code, message.message)
        if not hasattr(message, "jsonrpc"):     # valid JSON, but no message
            msg_id = message.get("id") if isinstance(message, dict) and _valid_id(message.get("id")) else None
            return self.refuse(msg_id, INVALID_REQUEST, "not a JSON-RPC message (an object with \"jsonrpc\": \"2.0\")")
        return super().handle_message(message)


@dataclass
class ProjectState:
    result: CheckResult | None = None
    index: Index | None = None        # the last one built from a project that parsed
    published: frozenset = frozenset()
    lint: dict = field(default_factory=dict)        # file → its last lint findings
    indexed: object = None                          # the CheckResult `index` was built from
    full: CheckResult | None = None                 # the last full (not focused) check
    sent: dict = field(default_factory=dict)        # URI → the diagnostics last published for it
    converted: dict = field(default_factory=dict)   # id(diagnostic or finding) → (it, text, LSP form)
    generation: int = 0                             # edits seen (didChange)
    edited: float = 0.0                             # when the last edit arrived (perf_counter)
    edited_path: Path | None = None                 # the file it edited
    cycle: bool = False                             # an edit cycle (check, publish, …) is under way
    wake: object = None                             # asyncio.Event set by an edit while the cycle waits


class StvmLanguageServer(LanguageServer):
    def __init__(self, options=None) -> None:
        super().__init__("stvm", __version__, text_document_sync_kind=lsp.TextDocumentSyncKind.Incremental,
                         protocol_cls=GuardedProtocol)
        self.driver = Driver(options)
        self.projects: dict[tuple[str, ...], ProjectState] = {}
        self.project_of_file: dict[str, tuple[str, ...]] = {}
        self.client_uris: dict[str, str] = {}       # resolved path → the URI the client opened it as
        self.open_files: set[str] = set()
        self.stdlib_views: dict[str, str] = {}      # written stdlib file → its display name
        self.lock = threading.Lock()
        self.executor = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="stvm-check")
        self.timings: collections.deque = collections.deque(maxlen=1000)   # the last edits' (stvm.timings)
        self.problems: list[str] = []               # errors met off the event loop, logged on it
        self.live = LiveValues(DEFAULT_ENDPOINT)     # replaced at `initialize` (its options)
        self.refresh_hints = False

    def report_server_error(self, error: Exception, source) -> None:
        """pygls's reader hands a body it cannot decode here (ValueError: not JSON, not UTF-8):
        the client gets JSON-RPC's Parse error; any other error is logged to the client."""
        if isinstance(error, ValueError) and isinstance(self.protocol, GuardedProtocol) \
                and isinstance(error, (json.JSONDecodeError, UnicodeDecodeError)):
            self.protocol.refuse(None, PARSE_ERROR, f"parse error: the message body is not JSON ({str(error)[:80]})")
            return
        super().report_server_error(error, source)

    # ---- files and projects ------------------------------------------------------------------

    def uri_of(self, file: str) -> str:
        if file in self.client_uris:
            return self.client_uris[file]
        if is_stdlib_file(file):
            state = next((s for s in self.projects.values() if s.result and file in s.result.texts), None)
            if state is not None:
                path = stdlib_path(file, state.result.texts[file])
                self.stdlib_views[_norm(path)] = file
                return path.as_uri()
        return Path(file).as_uri()

    def buffers(self) -> dict[str, str]:
        out = {}
        for file in self.open_files:
            doc = self.workspace.get_text_document(self.client_uris[file])
            out[file] = doc.source
        return out

    def project_key(self, path: Path) -> tuple[str, ...]:
        return project_identity(path)

    def check_now(self, path: Path) -> ProjectState:
        """Check, lint and index the project of `path` (blocking) and publish its diagnostics."""
        state, by_uri = self.compute(path, self.buffers(), lint="all", fresh=True)
        self.publish(state, by_uri)     # in the project's order: the opened file is not waited for alone
        self.reindex(state)
        return state

    def compute(self, path: Path, buffers: dict[str, str], lint: str = "all",
                focus: bool = False, fresh: bool = False) -> tuple[ProjectState, dict]:
        """Check the project of `path` with `buffers` (any thread): the diagnostics per URI.
        `lint` "all" lints every file of the project, "none" none: the findings of the files
        not edited are kept from their last lint, the edited file's are dropped until
        `relint` (its lines may have moved). `focus`: a focused check of `path` when the driver
        can make one (stvm/lsp/driver.py), its result marked `focused`. `fresh`: the project's
        files and settings are read again from the disk (an open, a save)."""
        key = self.project_key(path)
        waited = time.perf_counter()
        with self.lock:
            waited = time.perf_counter() - waited
            if fresh:
                self.driver.forget()
            state = self.projects.setdefault(key, ProjectState())
            result = self.driver.check(path, buffers, focus, state.full)
            result.stages = {"lock wait": waited, **result.stages}
            if not result.focused:
                state.full = result
            state.result = result
            for file in result.files:
                self.project_of_file[file] = key
            watch = Stopwatch()
            if lint == "all":
                state.lint = self.lint_of(result, None)
            else:
                state.lint.pop(_norm(path), None)
            watch.lap("lint")
            by_uri = self.diagnostics_of(state, path)
            watch.lap("diagnostics to LSP objects")
            result.stages.update(watch.stages)
            return state, by_uri

    def relint(self, state: ProjectState, path: Path) -> dict | None:
        """Lint the edited file again (any thread); the diagnostics per URI, None if it cannot be."""
        with self.lock:
            result = state.result
            if result is None or result.analysis is None or result.focused:
                return None
            file = _norm(path)
            state.lint.update(self.lint_of(result, {file}))
            state.lint.setdefault(file, [])
            return self.diagnostics_of(state, path)

    def reindex(self, state: ProjectState) -> None:
        """Rebuild the position index from the last check (kept when that check had no analysis)."""
        result = state.result
        if result is not None and result.analysis is not None and state.indexed is not result \
                and not result.focused:    # a focused analysis lacks the other files' bodies
            # the collector paused, as for a check: the index's objects live until the next one,
            # and collections over the project's heap while building it cost a fifth of its time
            with collector_paused(age_survivors=True):
                state.index = build_index(result.analysis, result.texts, result.files, result.originals)
            state.indexed = result

    def lint_of(self, result: CheckResult, files: set[str] | None) -> dict[str, list]:
        out: dict[str, list] = {f: [] for f in (files if files is not None else result.files)}
        try:
            findings = self.driver.lint_findings(result, files)
        except Exception as exc:  # a lint rule's bug must not hide the checker's diagnostics
            self.problems.append(f"stvm lint failed: {exc!r}")
            return out
        for fnd in findings:
            out.setdefault(_norm(Path(fnd.span.file)), []).append(fnd)
        return out

    def diagnostics_of(self, state: ProjectState, path: Path) -> dict[str, list[lsp.Diagnostic]]:
        """The LSP diagnostics of every file of the project (checker's, then lint's), by URI.
        A diagnostic or finding carried over from the last check (a file whose bodies a focused
        check left out, a file not linted again) keeps the LSP form it was given, so a publish
        converts only what the check produced anew."""
        result = state.result
        uris = {file: self.uri_of(file) for file in result.files}
        out: dict[str, list[lsp.Diagnostic]] = {uri: [] for uri in uris.values()}
        encoding = self.encoding
        before, converted = state.converted, {}

        def add(item, make) -> None:
            file = item.span.file
            if file.startswith("<"):
                return
            text = result.originals.get(file) or result.texts.get(file)
            known = before.get(id(item))
            if known is not None and known[0] is item and known[1] == text:
                diag = known[2]
            else:
                diag = make(item)
                if encoding != pos.UTF32:
                    for p in (diag.range.start, diag.range.end):
                        p.character = pos.to_client(text, p.line, p.character, encoding)
            converted[id(item)] = (item, text, diag)
            uri = uris.get(file) or self.uri_of(_norm(Path(file)))
            out.setdefault(uri, []).append(diag)

        def checker(d) -> lsp.Diagnostic:
            severity = lsp.DiagnosticSeverity.Error if d.is_error else lsp.DiagnosticSeverity.Warning
            return lsp.Diagnostic(_range(d.span), d.message, severity=severity, code=d.code or None,
                                  source=SOURCE_CHECK, code_description=lsp.CodeDescription(
                                      href=error_href(d.code, path)) if d.code else None)

        def finding(fnd) -> lsp.Diagnostic:
            return lsp.Diagnostic(_range(fnd.span), fnd.message, severity=lsp.DiagnosticSeverity.Warning,
                                  code=fnd.code, source=SOURCE_LINT,
                                  code_description=lsp.CodeDescription(href=rule_href(fnd.code, path)))

        for d in result.diagnostics:
            add(d, checker)
        for findings in state.lint.values():
            for fnd in findings:
                add(fnd, finding)
        state.converted = converted
        return out

    def flush_problems(self) -> None:
        while self.problems:
            self.window_log_message(lsp.LogMessageParams(lsp.MessageType.Error, self.problems.pop(0)))

    def publish(self, state: ProjectState, by_uri: dict[str, list[lsp.Diagnostic]],
                first: str | None = None, changed_only: bool = False) -> None:
        """Publish the diagnostics of each URI: `first`'s before the others (the edited file's
        reach the editor before its dependents'), and with `changed_only` only those of the URIs
        whose diagnostics changed since their last publish (always `first`'s, which the editor
        waits for after an edit)."""
        for stale in state.published - set(by_uri):
            self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(stale, []))
            state.sent.pop(stale, None)
        state.published = frozenset(by_uri)
        order = sorted(by_uri, key=lambda uri: uri != first)
        for uri in order:
            diags = by_uri[uri]
            last = state.sent.get(uri)
            if changed_only and uri != first and last is not None and \
                    (len(last) == len(diags) and all(a is b for a, b in zip(last, diags)) or last == diags):
                continue
            state.sent[uri] = diags
            self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri, diags))

    def symbol_request(self, params):
        """(context, symbol at the request's position or None) of a positional request; (None,
        None) when the file has no context (what every positional feature starts with)."""
        ctx = self.context(params.text_document.uri)
        if ctx is None:
            return None, None
        return ctx, f.symbol_at(ctx[1], ctx[0], params.position.line, params.position.character)

    def context(self, uri: str) -> tuple[str, Index] | None:
        """(file name, index) for a request on `uri`, checking its project first if needed."""
        path = path_of(uri)
        if path is None:
            return None
        file = _norm(path)
        if file in self.stdlib_views:
            return None
        key = self.project_of_file.get(file)
        state = self.projects.get(key) if key else None
        if state is None:
            if not is_source(path) or not path.exists() and file not in self.open_files:
                return None
            state = self.check_now(path)
        if state.indexed is not state.result:
            self.reindex(state)
        if state.index is None:
            return None
        return file, state.index

    def text_of(self, uri: str) -> str:
        return self.workspace.get_text_document(uri).source

    @property
    def encoding(self) -> str:
        """The negotiated LSP position encoding (stvm/lsp/positions.py)."""
        chosen = getattr(self.workspace, "position_encoding", None) if self._workspace_ready() else None
        return str(getattr(chosen, "value", chosen) or pos.UTF16)

    def _workspace_ready(self) -> bool:
        try:
            return self.workspace is not None
        except RuntimeError:    # before `initialize` pygls has no workspace
            return False

    def text_for_positions(self, uri: str | None) -> str | None:
        """The text whose lines a position of `uri` counts in: the editor's buffer, else the
        checked text of the file (the original of a vendor XML file), else the file on disk."""
        if uri is None:
            return None
        path = path_of(uri)
        file = _norm(path) if path is not None else None
        if file is not None and file not in self.open_files:
            name = self.stdlib_views.get(file, file)
            for state in self.projects.values():
                result = state.result
                if result is not None and name in result.texts:
                    return result.originals.get(name) or result.texts[name]
        try:
            return self.workspace.get_text_document(uri).source
        except Exception:   # an unreadable file: columns stay as they are
            return None

    def to_client(self, value, uri: str | None):
        """`value` with its positions in the client's units (see positions.convert_out)."""
        encoding = self.encoding
        if encoding == pos.UTF32:
            return value
        memo: dict = {}

        def text_of(u):
            if u not in memo:
                memo[u] = self.text_for_positions(u)
            return memo[u]
        return pos.convert_out(value, text_of, uri, encoding)

    def from_client(self, params) -> None:
        """A positional request's `position` converted from the client's units to code points."""
        position = getattr(params, "position", None)
        document = getattr(params, "text_document", None)
        if position is None or document is None or self.encoding == pos.UTF32:
            return
        text = self.text_for_positions(document.uri)
        params.position = lsp.Position(position.line, pos.from_client(text, position.line, position.character,
                                                                       self.encoding))


def positioned(fn):
    """A request handler whose params arrive, and whose answer leaves, in the client's
    position encoding (the handler itself works in code points, as the index does)."""
    if asyncio.iscoroutinefunction(fn):
        @functools.wraps(fn)
        async def run_async(ls, params):
            ls.from_client(params)
            doc = getattr(params, "text_document", None)
            return ls.to_client(await fn(ls, params), doc.uri if doc else None)
        return run_async

    @functools.wraps(fn)
    def run(ls, params):
        ls.from_client(params)
        doc = getattr(params, "text_document", None)
        return ls.to_client(fn(ls, params), doc.uri if doc else None)
    return run


def with_initialization_options(options, given):
    """The driver's `Options` with the client's initializationOptions on top: `dialect`,
    `defines` and `sysmac` (what `stvm lsp --dialect/--define/--sysmac` give); raises ValueError
    naming a bad one."""
    from dataclasses import replace   # lazy: start-up
    from stvm.cli_support import DIALECTS   # lazy: start-up
    if not isinstance(given, dict):
        return options
    dialect = given.get("dialect", options.dialect)
    if dialect is not None and dialect not in DIALECTS:
        raise ValueError(f"initializationOptions dialect must be one of {', '.join(DIALECTS)}, got {dialect!r}")
    lists = {}
    for key in ("defines", "sysmac"):
        value = given.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ValueError(f"initializationOptions {key} must be a list of strings")
        lists[key] = getattr(options, key) + tuple(value)
    return replace(options, dialect=dialect, **lists)


def build_server(options=None) -> StvmLanguageServer:
    server = StvmLanguageServer(options)

    def relevant(uri: str) -> Path | None:
        path = path_of(uri)
        if path is None or not is_source(path) or _norm(path) in server.stdlib_views:
            return None
        return path

    def safely(fn, *args):
        try:
            return fn(*args)
        except Exception as exc:  # a bug in stvm must not kill the editor session
            server.problems.append(f"stvm: {exc!r}")
            return None

    def opened(uri: str) -> Path | None:
        path = relevant(uri)
        if path is not None:
            file = _norm(path)
            server.client_uris[file] = uri
            server.open_files.add(file)
        return path

    @server.feature(lsp.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: StvmLanguageServer, params: lsp.DidOpenTextDocumentParams) -> None:
        path = opened(params.text_document.uri)
        if path is None:
            return
        state = ls.projects.get(ls.project_key(path))
        file = _norm(path)
        if state is not None and state.result is not None and file in state.result.files \
                and state.result.originals.get(file) == params.text_document.text:
            # another file of a project already checked with this very text: its diagnostics
            # are out already, under the URI the client now uses
            ls.publish(state, ls.diagnostics_of(state, path))
        else:
            safely(ls.check_now, path)
        ls.flush_problems()

    @server.feature(lsp.TEXT_DOCUMENT_DID_SAVE, lsp.SaveOptions(include_text=True))
    def did_save(ls: StvmLanguageServer, params: lsp.DidSaveTextDocumentParams) -> None:
        path = opened(params.text_document.uri)
        if path is None:
            return
        if params.text is not None:
            doc = ls.workspace.get_text_document(params.text_document.uri)
            if doc.source != params.text:    # the client's saved text is the truth
                ls.workspace.put_text_document(lsp.TextDocumentItem(params.text_document.uri, doc.language_id or "structured-text",
                                                                    (doc.version or 0) + 1, params.text))
        safely(ls.check_now, path)
        ls.flush_problems()

    @server.feature(lsp.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: StvmLanguageServer, params: lsp.DidChangeTextDocumentParams) -> None:
        path = opened(params.text_document.uri)
        if path is None:
            return
        key = ls.project_key(path)
        state = ls.projects.setdefault(key, ProjectState())
        state.generation += 1
        state.edited = time.perf_counter()
        state.edited_path = path
        if state.wake is not None:
            state.wake.set()     # a cycle waiting for typing to pause: it starts again
        if not state.cycle:      # else the cycle under way sees the new generation and goes again
            state.cycle = True
            asyncio.get_running_loop().call_later(DEBOUNCE_SECONDS, lambda: asyncio.ensure_future(
                edit_cycle(ls, key, state, time.perf_counter())))

    async def edit_cycle(ls: StvmLanguageServer, key, state: ProjectState, fired: float) -> None:
        """After an edit: the focused check, published at once (the edited file's diagnostics
        first); then, once typing pauses, the full check (what a focused one cannot see:
        recursion through another file's body, and the analysis the index and lint need), the
        index and the edited file's lint findings. An edit arriving meanwhile starts it again
        from the focused check, with the new text: a result of older text is not published."""
        loop = asyncio.get_running_loop()

        def timed(path: Path, buffers: dict, focus: bool):
            entered = time.perf_counter()
            cpu = time.thread_time()
            out = safely(ls.compute, path, buffers, "none", focus)
            return out, time.thread_time() - cpu, entered, time.perf_counter()

        try:
            while True:
                generation, edited, path = state.generation, state.edited, state.edited_path
                buffers = ls.buffers()
                handed = time.perf_counter()
                done, cpu, entered, left = await loop.run_in_executor(ls.executor, timed, path, buffers, True)
                if state.generation != generation:
                    fired = time.perf_counter()
                    continue
                if done is None:
                    break
                back = time.perf_counter()
                first = ls.client_uris.get(_norm(path))
                done_state, by_uri = done
                ls.publish(done_state, by_uri, first, changed_only=True)   # on the event loop: the transport is not thread-safe
                published = time.perf_counter()
                ls.timings.append({"edit_to_publish": published - edited, "check_cpu": cpu,
                                   "focused": bool(done_state.result.focused),
                                   "stages": {"debounce (or a check of older text)": fired - edited,
                                              "buffers": handed - fired,
                                              "hand-over to the check thread": entered - handed,
                                              **done_state.result.stages,
                                              "hand-back to the event loop": back - left,
                                              "publish (serialise, write)": published - back}})
                del done, by_uri
                if done_state.result.focused:
                    state.wake = asyncio.Event()
                    try:
                        await asyncio.wait_for(state.wake.wait(), SETTLE_SECONDS)
                    except asyncio.TimeoutError:
                        pass
                    finally:
                        state.wake = None
                    if state.generation != generation:
                        fired = time.perf_counter()
                        continue
                    done, _, _, _ = await loop.run_in_executor(ls.executor, timed, path, buffers, False)
                    if state.generation != generation:
                        fired = time.perf_counter()
                        continue
                    if done is None:
                        break
                    ls.publish(done[0], done[1], first, changed_only=True)
                    del done
                # then the index (hover & co. see the edit) and the edited file's lint findings
                await loop.run_in_executor(ls.executor, lambda: safely(ls.reindex, state))
                if state.generation != generation:
                    fired = time.perf_counter()
                    continue
                linted = await loop.run_in_executor(ls.executor, lambda: safely(ls.relint, state, path))
                if state.generation != generation:
                    fired = time.perf_counter()
                    continue
                if linted is not None:
                    ls.publish(state, linted, first, changed_only=True)
                break
        finally:
            state.cycle = False
            ls.flush_problems()

    @server.feature(lsp.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: StvmLanguageServer, params: lsp.DidCloseTextDocumentParams) -> None:
        path = path_of(params.text_document.uri)
        if path is not None:
            ls.open_files.discard(_norm(path))
        ls.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(params.text_document.uri, []))
        for state in ls.projects.values():     # cleared: the next publish sends them again
            state.sent.pop(params.text_document.uri, None)

    @server.feature(lsp.TEXT_DOCUMENT_HOVER)
    @positioned
    def hover(ls: StvmLanguageServer, params: lsp.HoverParams) -> lsp.Hover | None:
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        if found is None:
            return None
        sym, occ = found
        return lsp.Hover(lsp.MarkupContent(lsp.MarkupKind.Markdown, f.hover_markdown(ctx[1], sym)),
                         f.rng(occ.line, occ.col, occ.end))

    def goto(ls: StvmLanguageServer, params) -> list[lsp.Location] | None:
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        if found is None or found[0].line < 0:
            return None
        sym = found[0]
        return [lsp.Location(ls.uri_of(sym.file), f.rng(sym.line, sym.col, sym.end_col))]

    @server.feature(lsp.TEXT_DOCUMENT_DEFINITION)
    @positioned
    def definition(ls: StvmLanguageServer, params: lsp.DefinitionParams):
        return goto(ls, params)

    @server.feature(lsp.TEXT_DOCUMENT_DECLARATION)
    @positioned
    def declaration(ls: StvmLanguageServer, params: lsp.DeclarationParams):
        return goto(ls, params)

    @server.feature(lsp.TEXT_DOCUMENT_TYPE_DEFINITION)
    @positioned
    def type_definition(ls: StvmLanguageServer, params: lsp.TypeDefinitionParams):
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        tsym = ctx[1].type_symbol(found[0].type) if found else None
        if tsym is None or tsym.line < 0:
            return None
        return [lsp.Location(ls.uri_of(tsym.file), f.rng(tsym.line, tsym.col, tsym.end_col))]

    @server.feature(lsp.TEXT_DOCUMENT_IMPLEMENTATION)
    @positioned
    def implementation(ls: StvmLanguageServer, params: lsp.ImplementationParams):
        """From an interface (or its method/property): the FBs implementing it (their method/property)."""
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        if found is None:
            return []
        return [lsp.Location(ls.uri_of(sym.file), f.rng(sym.line, sym.col, sym.end_col))
                for sym in f.implementations(ctx[1], found[0]) if sym.line >= 0]

    @server.feature(lsp.TEXT_DOCUMENT_REFERENCES)
    @positioned
    def references(ls: StvmLanguageServer, params: lsp.ReferenceParams) -> list[lsp.Location] | None:
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        if found is None:
            return []
        include = params.context.include_declaration
        return [lsp.Location(ls.uri_of(file), f.rng(o.line, o.col, o.end))
                for file, o in ctx[1].references(found[0].key) if include or not o.decl]

    @server.feature(lsp.TEXT_DOCUMENT_DOCUMENT_HIGHLIGHT)
    @positioned
    def highlight(ls: StvmLanguageServer, params: lsp.DocumentHighlightParams):
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        if found is None:
            return []
        return [lsp.DocumentHighlight(f.rng(o.line, o.col, o.end),
                                      lsp.DocumentHighlightKind.Write if o.decl else lsp.DocumentHighlightKind.Read)
                for file, o in ctx[1].references(found[0].key) if file == ctx[0]]

    @server.feature(lsp.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    @positioned
    def document_symbol(ls: StvmLanguageServer, params: lsp.DocumentSymbolParams):
        ctx = ls.context(params.text_document.uri)
        return f.document_symbols(ctx[1], ctx[0]) if ctx else None

    @server.feature(lsp.WORKSPACE_SYMBOL)
    @positioned
    def workspace_symbol(ls: StvmLanguageServer, params: lsp.WorkspaceSymbolParams):
        return f.workspace_symbols([s.index for s in ls.projects.values() if s.index is not None],
                                   params.query, ls.uri_of)

    @server.feature(lsp.TEXT_DOCUMENT_COMPLETION, lsp.CompletionOptions(trigger_characters=[".", "#"]))
    @positioned
    def completion(ls: StvmLanguageServer, params: lsp.CompletionParams):
        ctx = ls.context(params.text_document.uri)
        if ctx is None:
            return None
        doc = ls.workspace.get_text_document(params.text_document.uri)
        lines = doc.lines
        line_text = lines[params.position.line] if params.position.line < len(lines) else ""
        items = f.completion(ctx[1], ctx[0], params.position.line, params.position.character, line_text)
        return lsp.CompletionList(is_incomplete=True, items=items)

    @server.feature(lsp.TEXT_DOCUMENT_SIGNATURE_HELP, lsp.SignatureHelpOptions(trigger_characters=["(", ","]))
    def signature_help(ls: StvmLanguageServer, params: lsp.SignatureHelpParams):
        ctx = ls.context(params.text_document.uri)
        if ctx is None:
            return None
        doc = ls.workspace.get_text_document(params.text_document.uri)
        offset = doc.offset_at_position(params.position)
        return f.signature_help(ctx[1], ctx[0], params.position.line, doc.source, offset)

    @server.feature(lsp.TEXT_DOCUMENT_PREPARE_RENAME)
    @positioned
    def prepare_rename(ls: StvmLanguageServer, params: lsp.PrepareRenameParams):
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        if found is None:
            return None
        sym, occ = found
        if sym.stdlib:
            raise RequestFailed(f"'{sym.name}' is declared in the stvm standard library: it cannot be renamed")
        return lsp.PrepareRenamePlaceholder(f.rng(occ.line, occ.col, occ.end), sym.name)

    @server.feature(lsp.TEXT_DOCUMENT_RENAME, lsp.RenameOptions(prepare_provider=True))
    @positioned
    def rename(ls: StvmLanguageServer, params: lsp.RenameParams):
        ctx, found = ls.symbol_request(params)
        if ctx is None:
            return None
        if found is None:
            raise RequestFailed("nothing to rename here")
        edits = f.rename_all(ctx[1], found[0], params.new_name)
        if isinstance(edits, str):
            raise RequestFailed(edits)
        return lsp.WorkspaceEdit(changes={
            ls.uri_of(file): [lsp.TextEdit(f.rng(line, col, end), params.new_name) for line, col, end in spots]
            for file, spots in edits.items()})

    @server.feature(lsp.TEXT_DOCUMENT_SEMANTIC_TOKENS_FULL,
                    lsp.SemanticTokensLegend(token_types=f.TOKEN_TYPES, token_modifiers=f.TOKEN_MODIFIERS))
    def semantic_tokens(ls: StvmLanguageServer, params: lsp.SemanticTokensParams):
        ctx = ls.context(params.text_document.uri)
        if ctx is None:
            return lsp.SemanticTokens(data=[])
        return lsp.SemanticTokens(data=pos.semantic_tokens_out(f.semantic_tokens(ctx[1], ctx[0]),
                                                               ls.text_for_positions(params.text_document.uri),
                                                               ls.encoding))

    @server.feature(lsp.TEXT_DOCUMENT_FOLDING_RANGE)
    def folding(ls: StvmLanguageServer, params: lsp.FoldingRangeParams):
        ctx = ls.context(params.text_document.uri)
        return f.folding_ranges(ctx[1], ctx[0]) if ctx else []

    @server.feature(lsp.INITIALIZE)
    def initialize(ls: StvmLanguageServer, params: lsp.InitializeParams) -> None:
        options = params.initialization_options if isinstance(params.initialization_options, dict) else {}
        try:
            ls.driver.options = with_initialization_options(ls.driver.options, options)
        except ValueError as exc:
            ls.window_log_message(lsp.LogMessageParams(lsp.MessageType.Error, f"stvm: {exc}"))
        live = options.get("liveValues") if isinstance(options.get("liveValues"), dict) else {}
        endpoint = live.get("endpoint") if isinstance(live.get("endpoint"), str) else None
        ls.live = LiveValues(endpoint or os.environ.get("STVM_LIVE_ENDPOINT") or DEFAULT_ENDPOINT,
                             live.get("enable", True) is not False)
        caps = params.capabilities.workspace
        ls.refresh_hints = bool(caps and caps.inlay_hint and caps.inlay_hint.refresh_support)

    @server.feature(lsp.TEXT_DOCUMENT_INLAY_HINT)
    @positioned
    async def inlay_hint(ls: StvmLanguageServer, params: lsp.InlayHintParams):
        """Live values (stvm/lsp/live.py) beside the program and global variables in range."""
        ctx = ls.context(params.text_document.uri)
        if ctx is None or not ls.live.enabled:
            return []
        spots = live_spots(ctx[1], ctx[0], params.range.start.line, params.range.end.line)
        if not spots:
            return []
        paths = sorted({path for _, path, _ in spots})
        values = await ls.live.read(paths)
        if not values:
            return []

        async def changed() -> None:
            if ls.refresh_hints:
                ls.workspace_inlay_hint_refresh(None)

        ls.live.watch(list(values), changed)
        return [lsp.InlayHint(position=lsp.Position(occ.line, occ.end), label=f"= {format_value(values[path], sym.type)}",
                              padding_left=True, padding_right=True, tooltip=f"live value of {path} ({ls.live.endpoint})")
                for occ, path, sym in spots if path in values]

    @server.command("stvm.timings")
    def timings(ls: StvmLanguageServer, *args):
        """Per edit: seconds from the edit to its diagnostics and the CPU seconds of the check
        (bench/bench_lsp.py reads them: the CPU time does not depend on the machine's load)."""
        out = list(ls.timings)
        return out

    return server


def serve(options=None) -> None:
    """Serve on stdio; `options` are the driver's `Options` from `stvm lsp`'s command line."""
    # pygls logs every failed message with its traceback on stderr; the client is told instead
    # (a JSON-RPC error, window/logMessage)
    logging.getLogger("pygls").setLevel(logging.CRITICAL)
    build_server(options).start_io()
