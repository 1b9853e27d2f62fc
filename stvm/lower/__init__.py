"""Stage 3: checked project → Python source + line map (`lower_project`)."""

from stvm.lower.product import LineMap, LoweredProject

__all__ = ["lower_project", "LoweredProject", "LineMap"]


def __getattr__(name):
    # lazy: start-up (a cached load unpickles a LoweredProject; the generator and the checker
    # behind it load only when something is lowered)
    if name == "lower_project":
        from stvm.lower.codegen import lower_project   # lazy: start-up
        return lower_project
    raise AttributeError(name)
