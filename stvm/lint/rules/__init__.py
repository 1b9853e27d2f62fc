"""Every rule module; importing this package registers the rules (stvm.lint.registry)."""

from stvm.lint.rules import control, dataflow, protocol, ranges, resources  # noqa: F401
