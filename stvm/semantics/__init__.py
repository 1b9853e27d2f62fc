"""Stage 2: index, resolve and type-check (`analyze`)."""

__all__ = ["analyze", "Analysis"]


def __getattr__(name):
    # lazy: start-up (the VM and the cached load need `stvm.semantics.types`, not the checker)
    if name in __all__:
        from stvm.semantics import checker   # lazy: start-up
        return getattr(checker, name)
    raise AttributeError(name)
