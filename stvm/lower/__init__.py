"""Stage 3: checked project → Python source + line map (`lower_project`)."""

from stvm.lower.codegen import LineMap, LoweredProject, lower_project

__all__ = ["lower_project", "LoweredProject", "LineMap"]
