"""The language server behind `stvm lsp` (docs/editor.md).

    driver.py    the one module that calls the pipeline (stvm/project.py): a project's files,
                 settings and a check with the editor's unsaved buffers
    index.py     the position → symbol index built once per check from the syntax tree's spans
                 and the checker's resolution
    features.py  hover, definition, references, completion, signature help, rename, symbols,
                 semantic tokens and folding, as plain functions of an index
    server.py    the pygls server: documents, debounced re-checks, diagnostics, the requests
    live.py      live values of a running `stvm run`/`stvm debug` as inlay hints
"""

__all__ = ["serve", "build_server"]


def __getattr__(name):
    if name in __all__:
        from stvm.lsp import server   # lazy: start-up (pygls is imported only for `stvm lsp`)
        return getattr(server, name)
    raise AttributeError(name)
