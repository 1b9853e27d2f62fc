"""`stvm lsp`: a language server (LSP over stdio, pygls) publishing the checker's errors and
the lint findings of a `.st` file when the editor opens or saves it.

Each diagnostic carries `source` "stvm" (checker) or "stvm-lint", the rule code, and for lint
findings `codeDescription.href` = the rule's page (docs/lint.md#saNNN next to the project, or
the `stvm-rule:` URI the VS Code extension resolves with `stvm lint --explain`). The file is
linted together with its project (the folder's stvm.toml, as `stvm lint FILE`), so names from
other files resolve; the editor's unsaved text replaces the file's content. The project's
settings are `stvm check`'s (its stvm.toml, then `stvm lsp --sysmac/--dialect/--define`, then the
client's `initializationOptions`: {"dialect": "codesys", "defines": ["SIM"], "sysmac": ["NAME=VALUE"]}).
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import unquote, urlparse

from lsprotocol import types as lsp
from pygls.lsp.server import LanguageServer

from stvm.version import __version__
from stvm.lint import lint

SOURCE_CHECK, SOURCE_LINT = "stvm", "stvm-lint"


def _path_of(uri: str) -> Path | None:
    parsed = urlparse(uri)
    if parsed.scheme != "file":
        return None
    return Path(unquote(parsed.path))


def _range(span) -> lsp.Range:
    line = max(span.line - 1, 0)
    col = max(span.column - 1, 0)
    if span.end_line >= span.line and span.end_line > 0:
        end_line = span.end_line - 1
        end_col = max(span.end_column - 1, col + 1 if end_line == line else 0)
    else:
        end_line, end_col = line, col + 1
    return lsp.Range(lsp.Position(line, col), lsp.Position(end_line, end_col))


def rule_href(code: str, path: Path) -> str:
    """docs/lint.md#code of the repository that holds `path`, else a stvm-rule: URI."""
    for folder in [path.parent, *path.parents]:
        page = folder / "docs" / "lint.md"
        if page.exists():
            return page.as_uri() + f"#{code.lower()}"
    return f"stvm-rule:{code}"


def diagnostics_for(path: Path, text: str | None, settings) -> dict[str, list[lsp.Diagnostic]]:
    """Checker and lint diagnostics for `path` (and its project), grouped by file URI."""
    texts = {str(path): text} if text is not None else None
    report = lint([path], settings, texts=texts)
    out: dict[str, list[lsp.Diagnostic]] = {}

    def add(file: str, diag: lsp.Diagnostic) -> None:
        if file.startswith("<"):
            return
        out.setdefault(Path(file).resolve().as_uri(), []).append(diag)

    for d in report.diagnostics:
        severity = lsp.DiagnosticSeverity.Error if d.is_error else lsp.DiagnosticSeverity.Warning
        add(d.span.file, lsp.Diagnostic(_range(d.span), d.message, severity=severity, code=d.code or None,
                                        source=SOURCE_CHECK))
    for f in report.findings:
        add(f.span.file, lsp.Diagnostic(_range(f.span), f.message, severity=lsp.DiagnosticSeverity.Warning,
                                        code=f.code, source=SOURCE_LINT,
                                        code_description=lsp.CodeDescription(href=rule_href(f.code, path))))
    out.setdefault(path.resolve().as_uri(), [])
    return out


def with_initialization_options(settings, given):
    """`settings` (the driver's Options) with the client's initializationOptions on top:
    `dialect`, `defines` and `sysmac`; raises ValueError naming a bad one."""
    from dataclasses import replace   # lazy: start-up
    from stvm.cli_support import DIALECTS   # lazy: start-up
    from stvm.project import Options   # lazy: start-up
    if not given:
        return settings
    if not isinstance(given, dict) or not isinstance(settings, Options):
        raise ValueError("initializationOptions must be an object of dialect, defines, sysmac")
    dialect = given.get("dialect", settings.dialect)
    if dialect is not None and dialect not in DIALECTS:
        raise ValueError(f"initializationOptions dialect must be one of {', '.join(DIALECTS)}, got {dialect!r}")
    lists = {}
    for key in ("defines", "sysmac"):
        value = given.get(key, [])
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ValueError(f"initializationOptions {key} must be a list of strings")
        lists[key] = getattr(settings, key) + tuple(value)
    return replace(settings, dialect=dialect, **lists)


def build_server(settings) -> LanguageServer:
    server = LanguageServer("stvm", __version__, text_document_sync_kind=lsp.TextDocumentSyncKind.Full)
    published: set[str] = set()
    current = [settings]   # what every file is linted with, once the client has initialised

    @server.feature(lsp.INITIALIZE)
    def initialize(ls: LanguageServer, params: lsp.InitializeParams) -> None:
        try:
            current[0] = with_initialization_options(settings, params.initialization_options)
        except ValueError as exc:
            ls.window_log_message(lsp.LogMessageParams(lsp.MessageType.Error, f"stvm: {exc}"))

    def refresh(uri: str, text: str | None) -> None:
        path = _path_of(uri)
        if path is None or path.suffix.lower() != ".st":
            return
        try:
            by_uri = diagnostics_for(path, text, current[0])
        except Exception as exc:  # a bug in stvm must not kill the editor session
            server.window_log_message(lsp.LogMessageParams(lsp.MessageType.Error, f"stvm lint failed: {exc!r}"))
            return
        for stale in published - set(by_uri):
            server.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(stale, []))
        published.clear()
        for file_uri, diags in by_uri.items():
            published.add(file_uri)
            server.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(file_uri, diags))

    @server.feature(lsp.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: LanguageServer, params: lsp.DidOpenTextDocumentParams) -> None:
        refresh(params.text_document.uri, params.text_document.text)

    @server.feature(lsp.TEXT_DOCUMENT_DID_SAVE, lsp.SaveOptions(include_text=True))
    def did_save(ls: LanguageServer, params: lsp.DidSaveTextDocumentParams) -> None:
        text = params.text
        if text is None:
            doc = ls.workspace.get_text_document(params.text_document.uri)
            text = doc.source
        refresh(params.text_document.uri, text)

    @server.feature(lsp.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: LanguageServer, params: lsp.DidCloseTextDocumentParams) -> None:
        ls.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(params.text_document.uri, []))

    return server


def serve(settings) -> None:
    build_server(settings).start_io()
