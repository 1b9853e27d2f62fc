"""Stage 1: ST text → syntax tree (`parse_files`, `parse_text`, `parse_expression`)."""

__all__ = ["parse_files", "parse_text", "parse_expression"]


def __getattr__(name):
    if name in __all__:
        # lazy: start-up (Lark loads with the parser; `import stvm.syntax.nodes` must not load it)
        from stvm.syntax import parser
        return getattr(parser, name)
    raise AttributeError(name)
