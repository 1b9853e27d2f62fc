"""Stage 2: index, resolve and type-check (`analyze`)."""

from stvm.semantics.checker import Analysis, analyze

__all__ = ["analyze", "Analysis"]
