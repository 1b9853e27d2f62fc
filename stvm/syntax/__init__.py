"""Stage 1: ST text → syntax tree (`parse_files`, `parse_text`, `parse_expression`)."""

__all__ = ["parse_files", "parse_text", "parse_expression"]


def __getattr__(name):
    # lazy: `stvm.syntax.nodes` is imported by diagnostics, which the parser itself imports
    if name in __all__:
        from stvm.syntax import parser
        return getattr(parser, name)
    raise AttributeError(name)
