"""Every rule module; importing this package registers the rules (`@rule`, stvm.lint.findings)."""

from stvm.lint.rules import control, dataflow, protocol, ranges, resources  # noqa: F401
